#include "pointscale/edit_rotations.h"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

#include "pointscale/parallel.h"
#include "pointscale/plane_fit.h"
#include "pointscale/spatial_index.h"

namespace pointscale {

IndexList base_rings(const Points& base) {
  return knn_graph(SpatialIndex(base), ring_size_for(base.rows()));
}

IndexList base_feet(const Points& base, const Points& base_normals, const Points& finest) {
  const SpatialIndex index(base);
  IndexList feet(static_cast<std::size_t>(base.rows()));
  parallel_for(feet.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Eigen::Index row = static_cast<Eigen::Index>(i);
      const Vec3 q = finest.row(row).transpose();
      Index nearest = static_cast<Index>(i);
      double d2 = 0.0;
      if (index.knn(q.data(), 1, &nearest, &d2) < 1 || base_normals.row(nearest).dot(base_normals.row(row)) < 0.5)
        nearest = static_cast<Index>(i);
      feet[i] = nearest;
    }
  }, {}, 4096);
  return feet;
}

namespace {

enum class RingKind { unchanged, planar, curved, on_a_line };

using Ring = std::array<Vec3, base_ring_size>;

// The ring's points relative to its first (the point itself).
void ring_edges(const Points& p, const Index* ring, int m, Ring& e) {
  const Eigen::RowVector3d o = p.row(ring[0]);
  for (int j = 0; j < m; ++j) e[j] = (p.row(ring[j]) - o).transpose();
}

// The covariance of the ring about its mean.
Mat3 ring_covariance(const Ring& e, int m) {
  Vec3 mean = Vec3::Zero();
  for (int j = 0; j < m; ++j) mean += e[j];
  mean /= m;
  Mat3 c = Mat3::Zero();
  for (int j = 0; j < m; ++j) {
    const Vec3 d = e[j] - mean;
    c.noalias() += d * d.transpose();
  }
  return c;
}

// The rotation about unit axis u by the angle whose cosine and sine are c and s.
Mat3 about(const Vec3& u, double c, double s) {
  Mat3 k;
  k << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
  return c * Mat3::Identity() + s * k + (1.0 - c) * u * u.transpose();
}

// The least rotation taking unit a to unit b.
Mat3 least_turn(const Vec3& a, const Vec3& b) {
  const Vec3 v = a.cross(b);
  const double c = a.dot(b);
  if (c > -1.0 + 1e-12) {
    Mat3 k;
    k << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
    return Mat3::Identity() + k + (k * k) / (1.0 + c);
  }
  // Opposite: any half turn about an axis across a will do; the twist that follows fixes the rest.
  Vec3 axis = a.unitOrthogonal();
  return about(axis, -1.0, 0.0);
}

// The rotation best taking the ring's edges e0 onto e1 (Kabsch), for rings with no clear plane.
Mat3 best_rotation(const Ring& e0, const Ring& e1, int m) {
  Mat3 h = Mat3::Zero();
  for (int j = 1; j < m; ++j) h.noalias() += e0[j] * e1[j].transpose();
  const Eigen::JacobiSVD<Mat3> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 d = Mat3::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixV() * d * svd.matrixU().transpose();
}

// The two larger eigenvalues' smaller one, from the smallest (l0 = a' C a for its unit
// eigenvector a), the trace and the adjugate's quadratic form a' adj(C) a = l1 l2.
double middle_eigenvalue(const Mat3& c, const Vec3& a) {
  const double l0 = a.dot(c * a);
  const double sum = c.trace() - l0;
  double adj[6];
  detail::symmetric_adjugate(c, adj);
  Mat3 ad;
  ad << adj[0], adj[3], adj[4], adj[3], adj[1], adj[5], adj[4], adj[5], adj[2];
  const double product = std::max(0.0, a.dot(ad * a));
  const double disc = std::max(0.0, sum * sum - 4.0 * product);
  return 0.5 * (sum - std::sqrt(disc));
}

Mat3 ring_rotation(const Points& original, const Points& edited, const Index* ring, int m, const Mat3& cluster,
                   double tolerance, RingKind& kind) {
  Ring e0, e1;
  ring_edges(original, ring, m, e0);
  ring_edges(edited, ring, m, e1);
  // A ring that kept its shape to within rounding (a base handed back through another origin,
  // or the far side of a local edit) has not turned: exactly the identity.
  double moved = 0.0;
  for (int j = 1; j < m; ++j) moved = std::max(moved, (e1[j] - e0[j]).cwiseAbs().maxCoeff());
  if (!(moved > tolerance)) { kind = RingKind::unchanged; return Mat3::Identity(); }
  const Mat3 c0 = ring_covariance(e0, m), c1 = ring_covariance(e1, m);
  const double t0 = c0.trace(), t1 = c1.trace();
  const Vec3 a = t0 > 0.0 ? smallest_eigenvector(c0, t0) : Vec3::Zero();
  const Vec3 b_raw = t1 > 0.0 ? smallest_eigenvector(c1, t1) : Vec3::Zero();
  if (a.isZero() || b_raw.isZero()) { kind = RingKind::on_a_line; return cluster; }
  // A plane is clear when the ring spreads across it far more than off it.
  if (a.dot(c0 * a) > 0.25 * middle_eigenvalue(c0, a)) { kind = RingKind::curved; return best_rotation(e0, e1, m); }
  kind = RingKind::planar;
  const Vec3 b = b_raw.dot(cluster * a) < 0.0 ? Vec3(-b_raw) : b_raw;
  const Mat3 turn = least_turn(a, b);
  // The twist about b that best lines up the turned edges with the edited ones (2-D Procrustes
  // in the edited plane). Edges that did not move give a zero sine: no twist.
  double s = 0.0, c = 0.0;
  for (int j = 1; j < m; ++j) {
    const Vec3 u = turn * e0[j];
    const Vec3& v = e1[j];
    s += b.dot(u.cross(v));
    c += u.dot(v) - u.dot(b) * v.dot(b);
  }
  const double r = std::hypot(s, c);
  if (!(r > 0.0)) return turn;
  return about(b, c / r, s / r) * turn;
}

}  // namespace

std::vector<Mat3> edit_rotations(const Points& original, const Points& edited, const IndexList& rings,
                                 int ring_size, const std::vector<Mat3>& cluster_rotation, const IndexList& labels,
                                 EditRotationReport* report) {
  const std::size_t n = static_cast<std::size_t>(original.rows());
  std::vector<Mat3> rotation(n);
  std::atomic<std::size_t> counts[4] = {{0}, {0}, {0}, {0}};
  // Rounding of the base's coordinates, well below any edit an artist makes.
  const double tolerance = n > 0 ? 1e-12 * (original.colwise().maxCoeff() - original.colwise().minCoeff()).norm() : 0.0;
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    std::size_t local[4] = {0, 0, 0, 0};
    for (std::size_t i = b; i < e; ++i) {
      RingKind kind;
      rotation[i] = ring_rotation(original, edited, rings.data() + i * static_cast<std::size_t>(ring_size), ring_size,
                                  cluster_rotation[static_cast<std::size_t>(labels[i])], tolerance, kind);
      ++local[static_cast<int>(kind)];
    }
    for (int t = 0; t < 4; ++t) counts[t] += local[t];
  }, {}, 1024);
  if (report) {
    report->unchanged = counts[0];
    report->planar = counts[1];
    report->curved = counts[2];
    report->on_a_line = counts[3];
  }
  return rotation;
}

}  // namespace pointscale
