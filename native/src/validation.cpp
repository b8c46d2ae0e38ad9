#include "pointscale/validation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "pointscale/parallel.h"

namespace pointscale {

namespace {

// printf into a string: the messages quote numbers as the Python package always has (%g).
std::string format(const char* f, ...) {
  char buffer[512];
  va_list args;
  va_start(args, f);
  std::vsnprintf(buffer, sizeof buffer, f, args);
  va_end(args);
  return buffer;
}

[[noreturn]] void fail(const std::string& message) { throw std::invalid_argument(message); }

// A number as Python's repr writes it, so that a message quotes what the caller typed: the
// fewest digits that read back as the same double, in fixed notation from 1e-4 to 1e16
// ("10000.0", "0.25"), else in exponent notation ("1e-07").
std::string number(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf");
  const double magnitude = std::abs(v);
  const bool fixed = v == 0.0 || (magnitude >= 1e-4 && magnitude < 1e16);
  for (int digits = 0; digits <= 17; ++digits) {
    const std::string s = format(fixed ? "%.*f" : "%.*e", digits, v);
    if (std::strtod(s.c_str(), nullptr) == v) return fixed && digits == 0 ? s + ".0" : s;
  }
  return format("%.17g", v);
}

void check_count(int value, const char* name, int minimum, int maximum) {
  if (value < minimum) fail(format("%s must be >= %d, got %d", name, minimum, value));
  if (value > maximum) fail(format("%s must be at most %d, got %d", name, maximum, value));
}

// A positive finite number, optionally bounded.
void check_positive(double value, const char* name, double maximum = INFINITY) {
  if (!(std::isfinite(value) && value > 0.0)) fail(format("%s must be > 0, got %s", name, number(value).c_str()));
  if (value > maximum) fail(format("%s must be at most %g, got %s", name, maximum, number(value).c_str()));
}

Vec3 column_min(const PointsRef& p) { return p.colwise().minCoeff().transpose(); }
Vec3 column_max(const PointsRef& p) { return p.colwise().maxCoeff().transpose(); }

double half_width(const PointsRef& p) { return (0.5 * (column_max(p) - column_min(p))).maxCoeff(); }

// The square roots of the covariance eigenvalues, largest first, in a frame scaled by a power
// of two so that the largest deviation from the mean is in [0.5, 1): sets of any size in the
// float range, 1e-320 to 1e300, are measured alike, their squares neither overflowing nor
// underflowing.
Vec3 scaled_spread(const PointsRef& p) {
  const Eigen::Index n = p.rows();
  const Vec3 mean = p.colwise().sum().transpose() / static_cast<double>(n);
  double w = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) w = std::max(w, (p.row(i).transpose() - mean).cwiseAbs().maxCoeff());
  int exponent = 0;
  if (w > 0.0) std::frexp(w, &exponent);
  Mat3 covariance = Mat3::Zero();
  for (Eigen::Index i = 0; i < n; ++i) {
    Vec3 c = p.row(i).transpose() - mean;
    for (int a = 0; a < 3; ++a) c[a] = std::ldexp(c[a], -exponent);
    covariance.noalias() += c * c.transpose();
  }
  covariance /= static_cast<double>(n);
  const Vec3 ev = Eigen::SelfAdjointEigenSolver<Mat3>(covariance, Eigen::EigenvaluesOnly).eigenvalues();
  return Vec3(ev[2], ev[1], ev[0]).cwiseMax(0.0).cwiseSqrt();
}

}  // namespace

void check_points(const PointsRef& points, const char* name, Eigen::Index min_count) {
  const Eigen::Index n = points.rows();
  if (n == 0) fail(format("%s is empty", name));
  if (n < min_count)
    fail(format("%s has %lld points; at least %lld are needed here", name, static_cast<long long>(n),
                static_cast<long long>(min_count)));
  if (!points.allFinite()) {
    long long bad = 0;
    for (Eigen::Index i = 0; i < n; ++i) bad += !points.row(i).allFinite();
    fail(format("%s contains NaN or infinite coordinates (%lld points)", name, bad));
  }
  const double largest = points.cwiseAbs().maxCoeff();
  if (largest > max_coordinate)
    fail(format("%s has a coordinate of %.3g; coordinates beyond +-%.0e are not supported", name, largest,
                max_coordinate));
}

void check_normals(const Points* normals, const PointsRef& points, const char* name, const char* points_name) {
  if (!normals) return;
  if (normals->rows() != points.rows())
    fail(format("%s must have the shape of %s (%lld, 3), got (%lld, 3)", name, points_name,
                static_cast<long long>(points.rows()), static_cast<long long>(normals->rows())));
  check_points(*normals, name);
  // A zero normal faces neither way, and orientation follows the sign of a dot product with
  // it: half of such points would come out turned inward, with nothing to say so.
  Eigen::Index zero = 0, first = -1;
  for (Eigen::Index i = 0; i < normals->rows(); ++i) {
    if (normals->row(i).squaredNorm() > 0.0) continue;
    if (first < 0) first = i;
    ++zero;
  }
  if (zero > 0)
    fail(format("%s: %lld of them are zero (the first at point %lld); a zero normal faces neither way. Give "
                "oriented normals, or none to estimate them", name, static_cast<long long>(zero),
                static_cast<long long>(first)));
}

double check_extent(const PointsRef& points, const char* name, bool minimum) {
  const double w = half_width(points);
  if (w > max_extent)
    fail(format("%s span %.3g; sets wider than %.0e are not supported (scale them down first)", name, 2 * w,
                2 * max_extent));
  if (minimum && 0.0 < w && w < min_extent)
    fail(format("%s span only %.3g; sets narrower than %.0e are not supported (scale them up first)", name, 2 * w,
                2 * min_extent));
  return w;
}

void check_near(const PointsRef& points, const Vec3& centre, const char* name, const char* other) {
  const double far = std::max((column_min(points) - centre).cwiseAbs().maxCoeff(),
                              (column_max(points) - centre).cwiseAbs().maxCoeff());
  if (far > max_extent)
    fail(format("%s reach %.3g from the centre of %s; more than %.0e is not supported", name, far, other,
                max_extent));
}

void check_surface(const PointsRef& points, const char* name, bool allow_planar) {
  if (half_width(points) == 0.0) fail(format("all %s are identical: they define no surface", name));
  const Vec3 spread = scaled_spread(points);  // judged by shape, whatever the size
  if (spread[0] == 0.0) fail(format("all %s are identical: they define no surface", name));
  // Rounding leaves eigenvalues near 1e-16 of the largest, so spreads below 1e-6 count as zero.
  // Parts far apart or a stray point far away look the same to this test: say so, since such
  // a set is not a line to the eye.
  if (spread[1] <= 1e-6 * spread[0])
    fail(format("%s are collinear, or nearly so: across their longest axis they spread less than 1e-6 as far as "
                "along it, so they define no surface and no normals. A few points far from the rest (outliers), "
                "or parts far apart, do this too: remove the outliers, or process the parts apart", name));
  if (!allow_planar && spread[2] <= 1e-6 * spread[0])
    fail(format("%s all lie in one plane: there is no detail to separate from a base "
                "(use project() to work with planar data)", name));
  check_extent(points, name);
}

Vec3 bounding_box_centre(const PointsRef& points) { return 0.5 * (column_min(points) + column_max(points)); }

void check_threads(int threads) {
  if (threads < 0 || threads > max_threads)
    fail(format("threads must be in [0, %d] (0: all cores), got %d", max_threads, threads));
}

void check_neighbors(int neighbors, int minimum, const char* name) {
  check_count(neighbors, name, minimum, max_neighbors);
}

void check_normal_estimation(const PointsRef& points, int k) {
  check_neighbors(k);
  check_points(points, "points", k);
  check_surface(points, "points", true);
}

void check_near_support(const IndexList& near, Eigen::Index points, Eigen::Index support) {
  if (static_cast<Eigen::Index>(near.size()) != points)
    fail(format("near must be (%lld,): one index into onto per point, got %lld entries", static_cast<long long>(points),
                static_cast<long long>(near.size())));
  if (near.empty()) return;
  const auto [lo, hi] = std::minmax_element(near.begin(), near.end());
  if (*lo < 0 || *hi >= support)
    fail(format("near must index onto: each in [0, %lld], got [%d, %d]", static_cast<long long>(support - 1), *lo, *hi));
}

void check_rays(const PointsRef& origins, const PointsRef& directions) {
  check_points(origins, "origins");
  if (directions.rows() != origins.rows())
    fail(format("directions must have the shape of origins (%lld, 3), got (%lld, 3)",
                static_cast<long long>(origins.rows()), static_cast<long long>(directions.rows())));
  check_points(directions, "directions");
  if (((directions.rowwise().norm().array() - 1.0).abs() >= 1e-6).any()) fail("directions must be unit vectors");
}

void check_decimation(const PointsRef& points, long long target, double max_variation) {
  check_points(points);
  if (target < 1) fail(format("target must be >= 1, got %lld", target));
  if (target > points.rows())
    fail(format("target (%lld) exceeds the number of points (%lld)", target, static_cast<long long>(points.rows())));
  check_positive(max_variation, "max_variation");
  check_extent(points, "points", false);
}

void check_kernel(double kernel, const char* name) {
  if (!(kernel >= min_kernel && kernel <= max_kernel))
    fail(format("%s must be in [%g, %g] (a multiple of the local spacing), got %s", name, min_kernel, max_kernel,
                number(kernel).c_str()));
}

void check_stable_diffusion(double lambda, double mu, long long iterations, const char* name) {
  // The largest factor by which one iteration (a lambda step, then a mu step when mu is not 0)
  // scales a frequency k of the umbrella Laplacian, over k in [0, 2]: max |(1 - lambda k)(1 - mu k)|.
  const auto f = [&](double k) { return std::abs((1.0 - lambda * k) * (1.0 - mu * k)); };
  double growth = std::max(f(0.0), f(2.0));
  if (mu != 0.0) {
    const double k_star = (lambda + mu) / (2.0 * lambda * mu);
    if (0.0 <= k_star && k_star <= 2.0) growth = std::max(growth, f(k_star));
  }
  if (growth > 1.0 && static_cast<double>(iterations) * std::log(growth) > std::log(max_diffusion_growth)) {
    const long long most = static_cast<long long>(std::log(max_diffusion_growth) / std::log(growth));
    fail(format("lam=%g, mu=%g amplify some frequencies %.6g times per iteration, so %s=%lld would inflate the "
                "shape; at most %lld iterations are stable (use fewer, or mu closer to -lam)",
                lambda, mu, growth, name, iterations, most));
  }
}

void validate(const MlsOptions& options) {
  check_count(options.neighbors, "neighbors", 3, max_neighbors);
  check_positive(options.tolerance, "tolerance");
  check_count(options.max_iterations, "max_iterations", 1, max_iterations);
  if (!(options.sheet >= 1e-3 && options.sheet <= 1.0))
    fail(format("sheet must be in [0.001, 1] (a fraction of the kernel width), got %s", number(options.sheet).c_str()));
}

void validate(const DiffusionOptions& options, const char* prefix) {
  const double lambda = options.lambda, mu = options.mu;
  if (!(lambda >= 1e-3 && lambda <= 1.0))
    fail(format("lam must be in [0.001, 1] for a stable explicit step, got %s", number(lambda).c_str()));
  check_count(options.neighbors, (std::string(prefix) + "neighbors").c_str(), 3, max_neighbors);
  // mu = 0 is plain Laplacian smoothing; otherwise Taubin's inflating step, below -lambda.
  if (mu != 0.0 && !(mu < -lambda && mu >= -1e3))
    fail(format("mu must be below -lam = %s (Taubin's inflating step) and at least -1000, or 0, got %s",
                number(-lambda).c_str(), number(mu).c_str()));
  const std::string iterations = std::string(prefix) + "iterations";
  check_count(options.iterations, iterations.c_str(), 1, max_diffusion_iterations);
  check_stable_diffusion(lambda, mu, options.iterations, iterations.c_str());
}

void validate(const DecomposeOptions& options) {
  if (options.levels < 2) fail(format("levels must be at least 2 (a base and one band), got %d", options.levels));
  if (options.levels > max_levels) fail(format("levels must be at most %d, got %d", max_levels, options.levels));
  if (!(options.decimation > 0.0 && options.decimation < 1.0))
    fail(format("decimation must be in (0, 1), got %s", number(options.decimation).c_str()));
  check_kernel(options.kernel);
  check_count(options.mls.neighbors, "neighbors", 4, max_neighbors);  // a level's support takes 4
  validate(options.mls);
  check_positive(options.max_variation, "max_variation");
  if (options.consistency_iterations < 0)
    fail(format("consistency_iterations must be >= 0, got %d", options.consistency_iterations));
  if (options.diffusion) validate(*options.diffusion, "diffusion_");
}

void validate(const EncodeOptions& options) {
  check_kernel(options.kernel);
  check_count(options.mls.neighbors, "neighbors", 4, max_neighbors);
  validate(options.mls);
  check_positive(options.max_variation, "max_variation");
  if (options.consistency_iterations < 0)
    fail(format("consistency_iterations must be >= 0, got %d", options.consistency_iterations));
}

void validate(const MorphOptions& options) {
  check_kernel(options.kernel);
  check_count(options.mls.neighbors, "neighbors", 4, max_neighbors);
  validate(options.mls);
  check_count(options.interpolation_neighbors, "interpolation_neighbors", 1, max_neighbors);
}

void validate(const RayOptions& options) {
  check_count(options.neighbors, "neighbors", 3, max_neighbors);
  check_positive(options.tolerance, "tolerance");
  check_count(options.max_iterations, "max_iterations", 1, max_iterations);
  // A limit of 0 would make every hit a miss; no limit is infinity (the default).
  if (!(options.max_distance > 0.0))
    fail(format("max_distance must be > 0 (infinity: no limit), got %s", number(options.max_distance).c_str()));
  if (!(options.min_cosine >= 0.0 && options.min_cosine < 1.0))
    fail(format("min_cosine must be in [0, 1), got %s", number(options.min_cosine).c_str()));
}

Eigen::Index points_needed(const DecomposeOptions& options, const char* what) {
  const double fraction = std::pow(options.decimation, options.levels - 1);
  if (fraction * std::ldexp(1.0, 31) < min_coarse_points)
    fail(format("%s with levels=%d and decimation=%s would need more than 2^31 points (the coarsest level keeps "
                "decimation**(levels-1) of them and needs %d); use fewer levels or a larger decimation",
                what, options.levels, number(options.decimation).c_str(), min_coarse_points));
  return static_cast<Eigen::Index>(std::ceil(min_coarse_points / fraction));
}

void check_decompose_input(const PointsRef& points, const Points* input_normals, const DecomposeOptions& options,
                           const char* what) {
  validate(options);
  const Eigen::Index need = points_needed(options, what);
  check_points(points);
  if (points.rows() < need)
    fail(format("%s needs at least %lld points for levels=%d and decimation=%s (the coarsest level keeps "
                "decimation**(levels-1) of them and needs %d); got %lld",
                what, static_cast<long long>(need), options.levels, number(options.decimation).c_str(),
                min_coarse_points, static_cast<long long>(points.rows())));
  check_surface(points);
  check_normals(input_normals, points);
  if (options.thin_sheets && !input_normals) fail("thin_sheets needs the input normals, which tell the sides apart");
}

void check_gains(const Eigen::MatrixXd& gains, int bands, Eigen::Index points) {
  if (bands < 1) fail("the model has no bands");
  if (gains.rows() != bands || (gains.cols() != 1 && gains.cols() != points))
    fail(format("gains must have shape (%d,) per band or (%d, %lld) per point, got %lld by %lld", bands, bands,
                static_cast<long long>(points), static_cast<long long>(gains.rows()),
                static_cast<long long>(gains.cols())));
  if (!gains.allFinite()) fail("gains contain NaN or infinite values");
  const double largest = gains.size() ? gains.cwiseAbs().maxCoeff() : 0.0;
  if (largest > max_gain) fail(format("gains must be within +-%.0e, got %.17g", max_gain, largest));
}

void check_rows(Eigen::Index rows, Eigen::Index points, const char* name) {
  if (rows != points)
    fail(format("%s must have the decomposition's %lld points, got %lld", name, static_cast<long long>(points),
                static_cast<long long>(rows)));
}

void check_base(const PointsRef& base, Eigen::Index points, const Vec3& centre) {
  check_rows(base.rows(), points, "base");
  // An editing session checks a base on every call: one pass over it on every thread finds
  // what the three checks below need, and they run (and say what is wrong) only if it fails.
  const std::size_t n = static_cast<std::size_t>(base.rows()), chunk = 16384;
  const std::size_t chunks = (n + chunk - 1) / chunk;
  std::vector<Vec3> lo(chunks), hi(chunks);
  std::vector<unsigned char> finite(chunks, 1);
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    const std::size_t c = b / chunk;
    Vec3 l = Vec3::Constant(INFINITY), h = Vec3::Constant(-INFINITY);
    bool ok = true;
    for (std::size_t i = b; i < e; ++i)
      for (int a = 0; a < 3; ++a) {
        const double v = base(static_cast<Eigen::Index>(i), a);
        ok = ok && std::isfinite(v);
        l[a] = std::min(l[a], v);
        h[a] = std::max(h[a], v);
      }
    lo[c] = l;
    hi[c] = h;
    finite[c] = ok ? 1 : 0;
  }, {}, chunk);
  Vec3 l = Vec3::Constant(INFINITY), h = Vec3::Constant(-INFINITY);
  bool ok = n > 0;
  for (std::size_t c = 0; c < chunks; ++c) {
    ok = ok && finite[c];
    l = l.cwiseMin(lo[c]);
    h = h.cwiseMax(hi[c]);
  }
  const double largest = std::max(l.cwiseAbs().maxCoeff(), h.cwiseAbs().maxCoeff());
  const double far = std::max((l - centre).cwiseAbs().maxCoeff(), (h - centre).cwiseAbs().maxCoeff());
  if (!(ok && largest <= max_coordinate && far <= max_extent)) {
    check_points(base, "base");
    check_near(base, centre, "base", "the decomposition");
  }
  // A base must still span a surface (a plane will do: a flattened base is an edit): one that
  // collapsed to a point or a line has no normals to turn the detail by, and its folds and
  // result would be read off rounding. The spread about the box's centre, scaled to it, on
  // every thread; where it looks degenerate, check_surface decides and says why.
  const Vec3 mid = 0.5 * (l + h);
  const double half = 0.5 * (h - l).maxCoeff();
  int exponent = 0;
  if (half > 0.0) std::frexp(half, &exponent);
  std::vector<Mat3> moments(chunks, Mat3::Zero());
  std::vector<Vec3> sums(chunks, Vec3::Zero());
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    Mat3 m = Mat3::Zero();
    Vec3 sum = Vec3::Zero();
    for (std::size_t i = b; i < e; ++i) {
      Vec3 c = base.row(static_cast<Eigen::Index>(i)).transpose() - mid;
      for (int a = 0; a < 3; ++a) c[a] = std::ldexp(c[a], -exponent);
      sum += c;
      m.noalias() += c * c.transpose();
    }
    moments[b / chunk] = m;
    sums[b / chunk] = sum;
  }, {}, chunk);
  Mat3 m = Mat3::Zero();
  Vec3 sum = Vec3::Zero();
  for (std::size_t c = 0; c < chunks; ++c) {
    m += moments[c];
    sum += sums[c];
  }
  const Vec3 mean = sum / static_cast<double>(n);
  const Mat3 covariance = m / static_cast<double>(n) - mean * mean.transpose();
  const Vec3 ev = Eigen::SelfAdjointEigenSolver<Mat3>(covariance, Eigen::EigenvaluesOnly).eigenvalues();
  const double widest = std::sqrt(std::max(ev[2], 0.0)), middle = std::sqrt(std::max(ev[1], 0.0));
  if (half < min_extent || !(middle > 1e-5 * widest)) check_surface(base, "the base's points", true);
}

void check_folds_input(const MultiscaleModel& model, const FoldReference& ref, const Points* edited,
                       const PointsRef& result) {
  const Eigen::Index n = model.base.rows();
  const std::size_t un = static_cast<std::size_t>(n);
  if (ref.other_sheet.size() != un || ref.order.size() != un || ref.slot.size() != un ||
      (!ref.exempt.empty() && ref.exempt.size() != un) ||
      (!ref.right_angles.empty() && ref.right_angles.size() != un) || ref.rings.size() != un * static_cast<std::size_t>(ref.ring_size) ||
      ref.base_planes.rows() != n)
    fail("the fold reference was made for another model");
  check_rows(result.rows(), n, "points");
  check_points(result, "points");
  if (edited) {
    check_rows(edited->rows(), n, "base");
    check_points(*edited, "base");
  }
}

void validate(const FoldLimitOptions& options) {
  check_count(options.max_rounds, "max_rounds", 0, 1000);
  check_count(options.smoothing, "smoothing", 0, 64);
  if (!(options.step > 0.0 && options.step < 1.0)) fail(format("step must be in (0, 1), got %s", number(options.step).c_str()));
}

void check_parts(const IndexList& parts, Eigen::Index points, int k) {
  if (k < 1) fail(format("k must be at least 1, got %d", k));
  if (static_cast<Eigen::Index>(parts.size()) != points) fail("parts must be (n,): one label per point");
  for (Index v : parts)
    if (v < 0 || v >= points) fail("part label out of range");
}

}  // namespace pointscale
