// The checks of the core's public entry points: each throws std::invalid_argument (ValueError
// in Python) with a message that names the parameter and says what is wrong. Every entry point
// calls them before any work, so a C++ caller gets the same checks as the Python package, and
// each check exists here once; the package calls the same functions (through _core) where it
// must check an input before it centres it.
#pragma once
#include "pointscale/decomposition.h"
#include "pointscale/diffusion.h"
#include "pointscale/encoding.h"
#include "pointscale/folds.h"
#include "pointscale/mls_projection.h"
#include "pointscale/morph.h"
#include "pointscale/ray_shooting.h"
#include "pointscale/types.h"

namespace pointscale {

// Supported inputs. The plane fits square covariances, which makes fourth powers of the local
// spacing; in double precision those stay in range for spacings between about 1e-76 and 1e76
// (a sphere at 1e78 gives NaN). The limits keep a wide margin: every coordinate within
// +-max_coordinate, and a surface spans at most max_extent and at least min_extent about its
// bounding-box centre (half the largest side of its bounding box).
constexpr double max_coordinate = 1e150;
constexpr double max_extent = 1e50;
constexpr double min_extent = 1e-50;
constexpr int max_threads = 1024;
constexpr int max_levels = 64;
constexpr int max_neighbors = 1024;
constexpr int max_iterations = 1000;              // MLS and ray iterations per point
constexpr int max_diffusion_iterations = 10000;   // diffusion steps in one call
constexpr double max_diffusion_growth = 4.0;      // the most a diffusion may amplify any frequency, in total
constexpr double min_kernel = 1e-3, max_kernel = 1e3;  // kernel widths, as multiples of the local spacing
constexpr double max_gain = 1e6;                  // band gains
// The coarsest level keeps decimation^(levels-1) of the points; fewer than this carry no surface.
constexpr int min_coarse_points = 8;

using PointsRef = Eigen::Ref<const Points>;

// points     #P by 3: at least min_count rows (and at least 1), finite, within +-max_coordinate
// name       the parameter's name, for the message
void check_points(const PointsRef& points, const char* name = "points", Eigen::Index min_count = 1);

// normals    #P by 3 or nullptr (nothing to check): the rows of `points`, checked as points
void check_normals(const Points* normals, const PointsRef& points, const char* name = "normals",
                   const char* points_name = "points");

// Refuses a set wider than max_extent about its centre or, with minimum, narrower than
// min_extent but not a single point. Returns the half width. points #P by 3, finite.
double check_extent(const PointsRef& points, const char* name = "points", bool minimum = true);

// Refuses points (#P by 3) farther than max_extent, along an axis, from `centre`, the
// bounding-box centre of the set named `other`.
void check_near(const PointsRef& points, const Vec3& centre, const char* name, const char* other);

// Refuses a set (#P by 3, finite) that spans no surface: all identical, collinear or, unless
// allowed, planar; then a set outside the supported size (check_extent). The shape is judged in
// a frame scaled to the set, so a set is judged by its shape, whatever its size.
void check_surface(const PointsRef& points, const char* name = "points", bool allow_planar = false);

// The bounding-box centre of points (#P by 3, at least one row).
Vec3 bounding_box_centre(const PointsRef& points);

// threads  0 (all cores) to max_threads
void check_threads(int threads);

// neighbors  minimum to max_neighbors points per fit
void check_neighbors(int neighbors, int minimum = 3, const char* name = "neighbors");

// The input of normal estimation: k (check_neighbors) and at least k points that span a
// surface (planar allowed). points #P by 3.
void check_normal_estimation(const PointsRef& points, int k);

// near  #X indices of a support point near each of the #X points (MlsOptions::near_support),
//       each in [0, #S)
void check_near_support(const IndexList& near, Eigen::Index points, Eigen::Index support);

// origins     #R by 3 (check_points)
// directions  #R by 3 unit vectors
void check_rays(const PointsRef& origins, const PointsRef& directions);

// The input of cluster_decimate: points #P by 3 (finite, within max_extent), target in
// [1, #P], max_variation > 0.
void check_decimation(const PointsRef& points, long long target, double max_variation);

// A kernel width as a multiple of the local spacing, in [min_kernel, max_kernel].
void check_kernel(double kernel, const char* name = "kernel");

// Refuses a diffusion whose iterations would amplify some frequency of the umbrella Laplacian
// more than max_diffusion_growth times in total: Taubin's lambda|mu pair lifts the frequencies
// near k* = (lambda + mu) / (2 lambda mu) slightly above 1, and many steps inflate the shape or
// give NaN. name: what the iterations are called in the message.
void check_stable_diffusion(double lambda, double mu, long long iterations, const char* name = "iterations");

// The option structs. prefix names the diffusion's neighbours and iterations as decompose's
// callers know them ("diffusion_").
void validate(const MlsOptions& options);
void validate(const DiffusionOptions& options, const char* prefix = "");
void validate(const DecomposeOptions& options);
void validate(const EncodeOptions& options);
void validate(const MorphOptions& options);
void validate(const RayOptions& options);

// The fewest input points that leave min_coarse_points at decompose's coarsest level; throws
// when that would be more than 2^31. what: the caller's name, for the message.
Eigen::Index points_needed(const DecomposeOptions& options, const char* what = "decompose");

// The points, input normals and options of decompose and decompose_rayshoot (what: its name).
void check_decompose_input(const PointsRef& points, const Points* input_normals, const DecomposeOptions& options,
                           const char* what = "decompose");

// gains  k by 1 (per band) or k by #P (per point) of a model of `bands` bands and #P points,
//        finite and within +-max_gain
void check_gains(const Eigen::MatrixXd& gains, int bands, Eigen::Index points);

// base    an edited P^0: #P rows (the model's points), finite, within max_extent of `centre`,
//         where the model's own base is centred (zero in the model's coordinates)
void check_base(const PointsRef& base, Eigen::Index points, const Vec3& centre);

// rows  the rows of an array that holds one row per point of the decomposition (#P); name
//       says which
void check_rows(Eigen::Index rows, Eigen::Index points, const char* name);

// What the fold functions (folds.h) take: ref made for this model (fold_reference), result
// #P by 3 and finite (named "points", as the package calls it), edited #P by 3 or nullptr.
void check_folds_input(const MultiscaleModel& model, const FoldReference& ref, const Points* edited,
                       const PointsRef& result);
void validate(const FoldLimitOptions& options);

// knn_within_parts's input: parts #P labels in [0, #P), k >= 1.
void check_parts(const IndexList& parts, Eigen::Index points, int k);

// A model's structure: k >= 1 bands over #P >= 1 points, every index in range, every value
// finite and each cluster's anchor one of its members, so that reconstruction reads nothing out
// of bounds. A model that decompose made passes; a saved one is checked when loaded.
void validate(const MultiscaleModel& model);

}  // namespace pointscale
