#include "pointscale/edit_rotations.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "pointscale/connected_parts.h"
#include "pointscale/parallel.h"
#include "pointscale/detail/plane_fit.h"
#include "pointscale/detail/smooth_step.h"
#include "pointscale/spatial_index.h"

namespace pointscale {

IndexList base_rings(const Points& base, const IndexList& parts, int size) {
  const int width = ring_size_for(base.rows(), size);
  return parts.empty() ? knn_graph(SpatialIndex(base), width) : knn_within_parts(base, parts, width);
}

IndexList edit_rings(const Points& base, const IndexList& parts) {
  const std::size_t n = static_cast<std::size_t>(base.rows());
  const std::size_t width = static_cast<std::size_t>(ring_size_for(base.rows(), edit_ring_size));
  // One point per position (and part): the first of those that coincide stands for them all.
  std::vector<Index> sorted(n);
  for (std::size_t i = 0; i < n; ++i) sorted[i] = static_cast<Index>(i);
  auto part = [&](Index i) { return parts.empty() ? 0 : parts[static_cast<std::size_t>(i)]; };
  auto before = [&](Index a, Index b) {
    if (part(a) != part(b)) return part(a) < part(b);
    for (int c = 0; c < 3; ++c)
      if (base(a, c) != base(b, c)) return base(a, c) < base(b, c);
    return a < b;
  };
  std::sort(sorted.begin(), sorted.end(), before);
  std::vector<Index> first(n);  // the first point at each point's position
  for (std::size_t s = 0; s < n; ++s) {
    const Index i = sorted[s];
    const bool same = s > 0 && part(sorted[s - 1]) == part(i) &&
                      (base.row(sorted[s - 1]).array() == base.row(i).array()).all();
    first[static_cast<std::size_t>(i)] = same ? first[static_cast<std::size_t>(sorted[s - 1])] : i;
  }
  std::vector<Index> kept;  // the points that stand for their positions, in index order
  for (std::size_t i = 0; i < n; ++i)
    if (first[i] == static_cast<Index>(i)) kept.push_back(static_cast<Index>(i));
  if (kept.size() == n) return base_rings(base, parts, edit_ring_size);
  // Their rings (in index order, so that points at equal distances come as base_rings gives
  // them), read back for every point: its own position first, then the others'.
  Points positions(static_cast<Eigen::Index>(kept.size()), 3);
  IndexList kept_parts(parts.empty() ? 0 : kept.size());
  std::vector<Index> slot(n, -1);
  for (std::size_t k = 0; k < kept.size(); ++k) {
    positions.row(static_cast<Eigen::Index>(k)) = base.row(kept[k]);
    if (!parts.empty()) kept_parts[k] = parts[static_cast<std::size_t>(kept[k])];
    slot[static_cast<std::size_t>(kept[k])] = static_cast<Index>(k);
  }
  const IndexList few = base_rings(positions, kept_parts, edit_ring_size);
  const std::size_t few_width = static_cast<std::size_t>(ring_size_for(positions.rows(), edit_ring_size));
  IndexList rings(n * width);
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Index own = slot[static_cast<std::size_t>(first[i])];
      const Index* row = few.data() + static_cast<std::size_t>(own) * few_width;
      Index* ring = rings.data() + i * width;
      ring[0] = static_cast<Index>(i);
      std::size_t m = 1;
      for (std::size_t q = 1; q < few_width && m < width; ++q)
        if (row[q] != own) ring[m++] = kept[static_cast<std::size_t>(row[q])];
      for (; m < width; ++m) ring[m] = static_cast<Index>(i);  // fewer places than a ring: the point itself
    }
  }, {}, 4096);
  return rings;
}

namespace {

// Walks the rings downhill from start, step by step to the ring point that lowers cost the most
// among those allowed, until none does (at most 16 steps): on a smooth base that finds the best
// allowed point near start with no search of the whole base.
template <class Cost, class Allowed>
Index walk_rings(const IndexList& rings, std::size_t ring, Index start, double cost_here, Cost cost, Allowed allowed) {
  Index here = start;
  for (int step = 0; step < 16; ++step) {
    Index next = here;
    const Index* r = rings.data() + static_cast<std::size_t>(here) * ring;
    for (std::size_t j = 1; j < ring; ++j) {
      const Index c = r[j];
      const double d = cost(c);
      if (d < cost_here && allowed(c)) {
        cost_here = d;
        next = c;
      }
    }
    if (next == here) break;
    here = next;
  }
  return here;
}

}  // namespace

IndexList base_feet(const Points& base, const Points& base_normals, const Points& finest, const IndexList& rings,
                     int ring_size) {
  IndexList feet(static_cast<std::size_t>(base.rows()));
  const std::size_t ring = static_cast<std::size_t>(ring_size);
  parallel_for(feet.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      const Eigen::Index row = static_cast<Eigen::Index>(i);
      const Eigen::RowVector3d q = finest.row(row), n = base_normals.row(row);
      const Eigen::RowVector3d offset = q - base.row(row);
      // The foot is sought within a quarter of the offset of a centre that stays at the point's
      // own base position unless q has drifted sideways from it by more than that (offset less
      // its part along the normal). A tall feature's points drift on the way down through the
      // levels, each its own way; searched for around their base positions, the feet of those
      // that drifted far lie off to one side of the feature, which then leans with the lift's
      // turn under them. Around the centre moved just far enough that the point right below q
      // is within reach, the feet lie under the feature. Points that drifted less keep the
      // search as it was.
      const Eigen::RowVector3d drift = offset - offset.dot(n) * n;
      const double reach2 = 0.0625 * offset.squaredNorm();  // a quarter of the offset, squared
      const double drift_norm = drift.norm(), beyond = drift_norm - std::sqrt(reach2);
      const Eigen::RowVector3d centre = beyond > 0.0 ? Eigen::RowVector3d(base.row(row) + (beyond / drift_norm) * drift)
                                                     : Eigen::RowVector3d(base.row(row));
      auto same_side = [&](Index c) { return base_normals.row(c).dot(n) >= 0.5; };
      // A moved centre: first to the base point nearest it, if that is within reach (else the
      // walk starts from the point's own base position, as before); then downhill towards the
      // line through q along n, within reach of the centre.
      Index start = static_cast<Index>(i);
      if (beyond > 0.0) {
        const Index nearest = walk_rings(rings, ring, start, beyond * beyond,
                                         [&](Index c) { return (centre - base.row(c)).squaredNorm(); }, same_side);
        if ((base.row(nearest) - centre).squaredNorm() <= reach2) start = nearest;
      }
      // Downhill in the distance from the line through q along the base normal: the foot lies
      // right below q. The nearest base point in space is pulled towards whatever of the base
      // rises nearest to q, such as the crown of a bump under a tall feature, and a feature
      // whose points stand on one side of their feet fans out unevenly under a curved edit.
      auto off_line = [&](Index c) {
        const Eigen::RowVector3d d = q - base.row(c);
        return (d - d.dot(n) * n).squaredNorm();
      };
      feet[i] = walk_rings(rings, ring, start, off_line(start), off_line,
                           [&](Index c) { return (base.row(c) - centre).squaredNorm() <= reach2 && same_side(c); });
    }
  }, {}, 4096);
  return feet;
}

namespace {

enum class RingKind { unchanged, planar, curved, on_a_line };

using Ring = std::array<Vec3, edit_ring_size>;

// A ring's points are held in a Ring.
void check_ring_size(int ring_size) {
  if (ring_size < 1 || ring_size > edit_ring_size)
    throw std::invalid_argument("ring_size must be 1.." + std::to_string(edit_ring_size) + ", got " + std::to_string(ring_size));
}

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

// The unedited ring's plane: its normal, whether it has a clear plane at all, and for a clear
// plane the two vectors planar_rotation weighs the edited ring by (RingPlane).
RingKind ring_plane(const Ring& e0, int m, Vec3& normal, Vec3& w1, Vec3& w2) {
  const Mat3 c0 = ring_covariance(e0, m);
  const double t0 = c0.trace();
  normal = t0 > 0.0 ? smallest_eigenvector(c0, t0) : Vec3::Zero();
  w1 = w2 = Vec3::Zero();
  if (normal.isZero()) return RingKind::on_a_line;
  // A plane is clear when the ring spreads across it far more than off it.
  if (normal.dot(c0 * normal) > 0.25 * middle_eigenvalue(c0, normal)) return RingKind::curved;
  // The ring's coordinates u in its plane (axes t1, t2), about their mean, and their Gram
  // matrix G. The least-squares map taking them to the edited ring has columns
  // sum e1 u^T G^-1 = sum e1 (d . w), with d a point's edge less the mean and w1, w2 the
  // columns of [t1 t2] G^-1: they depend on the unedited ring alone.
  const Vec3 t1 = normal.unitOrthogonal(), t2 = normal.cross(t1);
  Vec3 m0 = Vec3::Zero();
  for (int j = 0; j < m; ++j) m0 += e0[j];
  m0 /= m;
  double g00 = 0.0, g01 = 0.0, g11 = 0.0;
  for (int j = 0; j < m; ++j) {
    const Vec3 d0 = e0[j] - m0;
    const double u0 = d0.dot(t1), u1 = d0.dot(t2);
    g00 += u0 * u0; g01 += u0 * u1; g11 += u1 * u1;
  }
  const double det = g00 * g11 - g01 * g01;
  if (!(det > 1e-12 * (g00 + g11) * (g00 + g11))) return RingKind::on_a_line;  // collapsed to a line
  w1 = (g11 * t1 - g01 * t2) / det;
  w2 = (g00 * t2 - g01 * t1) / det;
  return RingKind::planar;
}

// The rotation of a ring with a clear plane: the linear map that best takes the unedited ring
// onto the edited one within its plane (least squares over the ring's points about their
// means), then the rotation nearest to it (2-D polar decomposition). A rigid turn of the ring
// gives that turn exactly, since the unedited plane normal is uncorrelated with the ring's
// spread across it; stretching the ring within its plane turns nothing.
// c1, c2: the edited images of the plane's axes t1, t2 (sum e1 (d . w), RingPlane); a: the
// unedited plane's unit normal. Returns false where the ring folded over or collapsed.
// A ring whose plane turned more than 75 degrees from its cluster's turn is on its way to
// turning over (a shear of the base so strong that the ring's plane swings round, as in the
// blend zone of a part turned rigidly): its turn goes over to its cluster's, smoothly, so that
// no point's detail jumps where the ring gives up its own (a finned torus's fins jumped 10% of
// the model, turning 90 degrees, at a base change of 1e-13).
constexpr double giving_up_turn = 0.26;  // cos(75 degrees)
// A ring whose map keeps its shape (the images of the plane's axes of one length and at right
// angles, as a rigid turn or an isometric bend of the base leaves them) has not turned over,
// however far it turned from its cluster (a level-0 cluster spans far more than a hinge: a part
// folded 85 degrees or more about one took its cluster's turn, and detail standing on it leaned
// 30-90 degrees). It keeps its own turn, fully from conformal_trusted on, not at all below
// conformal_doubted (a shear that swings a ring's plane round squeezes it flat), and only where
// its turn is less than 150 degrees from its cluster's, giving way to it by 170: two turns half a
// circle apart have no one way between them, and the way taken would jump.
constexpr double conformal_doubted = 0.5, conformal_trusted = 0.8;  // smaller over larger singular value
constexpr double far_apart = 0.0872, farther_apart = 0.2588;  // cos(85 degrees), cos(75 degrees): half the turns
bool planar_rotation(const Vec3& c1, const Vec3& c2, const Vec3& a, const Mat3& cluster, Mat3& rotation) {
  Vec3 b = c1.cross(c2);
  const double bn = b.norm(), c1n = c1.norm();
  if (!(bn > 0.0) || !(c1n > 0.0)) return false;
  b /= bn;
  const double agreement = b.dot(cluster * a);
  const Vec3 t1 = a.unitOrthogonal(), t2 = a.cross(t1);
  const Vec3 f1 = c1 / c1n, f2 = b.cross(f1);
  double cs = c1n + c2.dot(f2), sn = -c2.dot(f1);
  const double r = std::sqrt(cs * cs + sn * sn);
  if (!(r > 0.0)) return false;
  cs /= r;
  sn /= r;
  const Vec3 r1 = cs * f1 + sn * f2, r2 = cs * f2 - sn * f1;
  rotation = r1 * t1.transpose() + r2 * t2.transpose() + b * a.transpose();
  if (agreement >= giving_up_turn) return true;
  double weight = smooth_step(agreement, 0.0, giving_up_turn);
  const double g11 = c1.squaredNorm(), g22 = c2.squaredNorm(), g12 = c1.dot(c2);
  const double half = 0.5 * (g11 + g22), gap = std::sqrt(0.25 * (g11 - g22) * (g11 - g22) + g12 * g12);
  const double conformal = std::sqrt(std::max(0.0, half - gap) / (half + gap));
  const double trust = smooth_step(conformal, conformal_doubted, conformal_trusted);
  const Eigen::Quaterniond from(cluster), to(rotation);
  if (trust > 0.0) {
    const double near = smooth_step(std::abs(from.dot(to)), far_apart, farther_apart);
    weight = std::max(weight, trust * near);
  }
  if (!(weight > 0.0)) return false;  // the ring turned over: no rotation describes it
  if (weight < 1.0) rotation = from.slerp(weight, to).toRotationMatrix();
  return true;
}

// A ring's edges e0 (unedited) and e1 (edited), relative to its first point, in one pass over
// the ring: how far it changed shape (the largest coordinate of e1 - e0), and, for a clear
// plane, the edited images c1, c2 of the plane's axes. The weights (e0 - mean e0) . w sum to
// zero over the ring, so c = sum e1 (e0 . w) - (mean e0 . w) sum e1.
double planar_images(const Points& original, const Points& edited, const Index* ring, int m, const Vec3& w1,
                     const Vec3& w2, Vec3& c1, Vec3& c2) {
  const double* o = original.data() + 3 * static_cast<std::size_t>(ring[0]);
  const double* q = edited.data() + 3 * static_cast<std::size_t>(ring[0]);
  double moved = 0.0;
  Vec3 sum0 = Vec3::Zero(), sum1 = Vec3::Zero(), a1 = Vec3::Zero(), a2 = Vec3::Zero();
  for (int j = 1; j < m; ++j) {  // the first edge is zero
    const double* oj = original.data() + 3 * static_cast<std::size_t>(ring[j]);
    const double* qj = edited.data() + 3 * static_cast<std::size_t>(ring[j]);
    const Vec3 e0(oj[0] - o[0], oj[1] - o[1], oj[2] - o[2]);
    const Vec3 e1(qj[0] - q[0], qj[1] - q[1], qj[2] - q[2]);
    moved = std::max(moved, (e1 - e0).cwiseAbs().maxCoeff());
    sum0 += e0;
    sum1 += e1;
    a1 += e0.dot(w1) * e1;
    a2 += e0.dot(w2) * e1;
  }
  const Vec3 m0 = sum0 / m;
  c1 = a1 - m0.dot(w1) * sum1;
  c2 = a2 - m0.dot(w2) * sum1;
  return moved;
}

// The rotation at ring i, and how it was measured (kind).
Mat3 ring_rotation(const Points& original, const Points& edited, const Index* ring, int m, const Mat3& cluster,
                   double tolerance, const EditRingPlanes& planes, std::size_t i, RingKind& kind) {
  kind = static_cast<RingKind>(planes.kind[i]);
  if (kind == RingKind::planar) {
    Vec3 c1, c2;
    const double moved = planar_images(original, edited, ring, m, planes.in_plane[i][0], planes.in_plane[i][1], c1, c2);
    // A ring that kept its shape to within rounding (a base handed back through another
    // origin, or the far side of a local edit) has not turned: exactly the identity.
    if (!(moved > tolerance)) { kind = RingKind::unchanged; return Mat3::Identity(); }
    Mat3 rotation;
    if (planar_rotation(c1, c2, planes.normals[i], cluster, rotation)) return rotation;
    kind = RingKind::on_a_line;
    return cluster;
  }
  Ring e0, e1;
  ring_edges(original, ring, m, e0);
  ring_edges(edited, ring, m, e1);
  double moved = 0.0;
  for (int j = 1; j < m; ++j) moved = std::max(moved, (e1[j] - e0[j]).cwiseAbs().maxCoeff());
  if (!(moved > tolerance)) { kind = RingKind::unchanged; return Mat3::Identity(); }
  if (kind == RingKind::curved) return best_rotation(e0, e1, m);
  return cluster;  // on a line
}

}  // namespace

namespace {

// Rounding of the base's coordinates, well below any edit an artist makes.
double edit_tolerance(const Points& original) {
  return original.rows() > 0 ? 1e-12 * (original.colwise().maxCoeff() - original.colwise().minCoeff()).norm() : 0.0;
}

}  // namespace

EditRingPlanes ring_planes(const Points& original, const IndexList& rings, int ring_size) {
  check_ring_size(ring_size);
  const std::size_t n = static_cast<std::size_t>(original.rows());
  EditRingPlanes planes;
  planes.normals.resize(n);
  planes.kind.resize(n);
  planes.in_plane.resize(n);
  planes.tolerance = edit_tolerance(original);
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    Ring e0;
    for (std::size_t i = b; i < e; ++i) {
      ring_edges(original, rings.data() + i * static_cast<std::size_t>(ring_size), ring_size, e0);
      planes.kind[i] = static_cast<unsigned char>(
          ring_plane(e0, ring_size, planes.normals[i], planes.in_plane[i][0], planes.in_plane[i][1]));
    }
  }, {}, 1024);
  return planes;
}

std::vector<Mat3> edit_rotations(const Points& original, const Points& edited, const IndexList& rings,
                                 int ring_size, const std::vector<Mat3>& cluster_rotation, const IndexList& labels,
                                 const EditRingPlanes* planes, EditRotationReport* report) {
  std::vector<Mat3> rotation;
  edit_rotations(original, edited, rings, ring_size, cluster_rotation, labels, planes, rotation, report);
  return rotation;
}

void edit_rotations(const Points& original, const Points& edited, const IndexList& rings, int ring_size,
                    const std::vector<Mat3>& cluster_rotation, const IndexList& labels, const EditRingPlanes* planes,
                    std::vector<Mat3>& rotation, EditRotationReport* report, std::vector<unsigned char>* kinds) {
  check_ring_size(ring_size);
  const std::size_t n = static_cast<std::size_t>(original.rows());
  rotation.resize(n);
  if (kinds) kinds->resize(n);
  std::atomic<std::size_t> counts[4] = {{0}, {0}, {0}, {0}};
  EditRingPlanes found;
  if (!planes) {
    found = ring_planes(original, rings, ring_size);
    planes = &found;
  }
  const double tolerance = planes->tolerance;
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    std::size_t local[4] = {0, 0, 0, 0};
    for (std::size_t i = b; i < e; ++i) {
      RingKind kind;
      rotation[i] = ring_rotation(original, edited, rings.data() + i * static_cast<std::size_t>(ring_size), ring_size,
                                  cluster_rotation[static_cast<std::size_t>(labels[i])], tolerance, *planes, i, kind);
      ++local[static_cast<int>(kind)];
      if (kinds) (*kinds)[i] = static_cast<unsigned char>(kind);
    }
    for (int t = 0; t < 4; ++t) counts[t] += local[t];
  }, {}, 1024);
  if (report) {
    report->unchanged = counts[0];
    report->planar = counts[1];
    report->curved = counts[2];
    report->on_a_line = counts[3];
  }
}

void edit_rotations_of(const IndexList& which, const Points& original, const Points& edited, const IndexList& rings,
                       int ring_size, const std::vector<Mat3>& cluster_rotation, const IndexList& labels,
                       const EditRingPlanes& planes, std::vector<Mat3>& rotation, std::vector<unsigned char>& kinds,
                       std::vector<unsigned char>& turned_again) {
  check_ring_size(ring_size);
  const std::size_t n = static_cast<std::size_t>(original.rows());
  if (rotation.size() != n || kinds.size() != n || turned_again.size() != n)
    throw std::invalid_argument("edit_rotations_of needs rotation, kinds and turned_again sized #P");
  const double tolerance = planes.tolerance;
  parallel_for(which.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      const std::size_t i = static_cast<std::size_t>(which[t]);
      RingKind kind;
      const Mat3 turn = ring_rotation(original, edited, rings.data() + i * static_cast<std::size_t>(ring_size), ring_size,
                                      cluster_rotation[static_cast<std::size_t>(labels[i])], tolerance, planes, i, kind);
      if (std::memcmp(turn.data(), rotation[i].data(), sizeof(Mat3)) != 0) {
        rotation[i] = turn;
        turned_again[i] = 1;
      }
      kinds[i] = static_cast<unsigned char>(kind);
    }
  }, {}, 1024);
}

EditRotationReport count_ring_kinds(const std::vector<unsigned char>& kinds) {
  std::size_t counts[4] = {0, 0, 0, 0};
  for (unsigned char k : kinds) ++counts[k & 3];
  EditRotationReport report;
  report.unchanged = counts[0];
  report.planar = counts[1];
  report.curved = counts[2];
  report.on_a_line = counts[3];
  return report;
}

}  // namespace pointscale
