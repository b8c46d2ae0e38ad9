#include "pointscale/morph.h"
#include "pointscale/validation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>
#include <stdexcept>

#include "pointscale/parallel.h"
#include "pointscale/detail/plane_fit.h"
#include "pointscale/sample_spacing.h"
#include "pointscale/detail/base_normals.h"
#include "pointscale/detail/project_from_afar.h"
#include "pointscale/detail/knn_weights.h"
#include "pointscale/detail/sheet_matching.h"

namespace pointscale {

Eigen::VectorXd knn_interpolate(const Points& from, const Eigen::VectorXd& values, const Points& to, int k) {
  check_points(from, "from");
  check_points(to, "to");
  if (values.size() != from.rows()) throw std::invalid_argument("values must hold one value per point of from");
  check_neighbors(k, 1, "k");
  const SpatialIndex index(from);
  k = std::min<int>(k, index.size());
  Eigen::VectorXd out(to.rows());
  parallel_for(static_cast<std::size_t>(to.rows()), [&](std::size_t b, std::size_t e) {
    std::vector<Index> idx(k);
    std::vector<double> d2(k), ih2(k), w(k);
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const int found = knn_gaussian_weights(index, to.row(i).data(), k, idx.data(), d2.data(), ih2.data(), w.data());
      double sum = 0.0, wsum = 0.0;
      for (int j = 0; j < found; ++j) { sum += w[j] * values(idx[j]); wsum += w[j]; }
      out(i) = sum / wsum;
    }
  }, {}, 512);
  return out;
}

namespace {

// Projects x onto the base; returns the foot points, oriented normals and signed offsets.
struct Projection {
  Points foot, normals;
  Eigen::VectorXd detail;
};

Projection project_onto_base(const Points& x, const SpatialIndex& base, const Eigen::VectorXd& h,
                             const Points& base_normals, const MlsOptions& mls, const ProgressStage& stage,
                             MorphModel& report) {
  MlsResult r = project_from_afar(x, base, h, mls, stage);
  report.not_converged += r.not_converged;
  report.degenerate += r.degenerate;
  Projection p;
  const Points ref = nearest_normals(r.positions, base, base_normals);
  p.normals = std::move(r.normals);
  p.detail.resize(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    // A degenerate projection has no normal: fall back to the nearest base sample's.
    if (!(p.normals.row(i).squaredNorm() > 0.5)) p.normals.row(i) = ref.row(i);
    if (p.normals.row(i).dot(ref.row(i)) < 0.0) p.normals.row(i) *= -1.0;
    p.detail(i) = (x.row(i) - r.positions.row(i)).dot(p.normals.row(i));
    // Slide the foot within its tangent plane onto x's normal line (a tolerance-sized move),
    // so foot + detail * normal gives x back exactly.
    r.positions.row(i) = x.row(i) - p.detail(i) * p.normals.row(i);
  }
  p.foot = std::move(r.positions);
  return p;
}

}  // namespace

MorphModel morph(const Points& a, const Points& b, const Points& base, const Points* base_normals,
                 const MorphOptions& options, const ProgressCallback* progress) {
  validate(options);
  check_points(a, "points_a");
  check_points(b, "points_b");
  check_points(base, "base_points", min_coarse_points);
  check_surface(base, "base_points", true);
  const Vec3 centre = bounding_box_centre(base);
  check_near(a, centre, "points_a", "base_points");
  check_near(b, centre, "points_b", "base_points");
  check_normals(base_normals, base, "base_normals", "base_points");
  const ProgressStage all{progress, 0.0, 1.0};
  const SpatialIndex base_index(base);
  const Eigen::VectorXd h = options.kernel * local_spacing(base_index, 6);
  const Points oriented = base_normals ? *base_normals : oriented_normals(base_index);
  MorphModel out;
  Projection pa = project_onto_base(a, base_index, h, oriented, options.mls, all.sub(0.0, 0.45), out);
  Projection pb = project_onto_base(b, base_index, h, oriented, options.mls, all.sub(0.45, 0.9), out);
  out.detail_b = offsets_on_matching_sheets(pb.foot, pb.detail, pa.foot, pa.detail, options.interpolation_neighbors,
                                            all.sub(0.9, 1.0));
  out.base = std::move(pa.foot);
  out.normals = std::move(pa.normals);
  out.detail_a = std::move(pa.detail);
  all.report(1.0);
  return out;
}

}  // namespace pointscale
