#include "pointscale/folds.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <stdexcept>
#include <type_traits>

#include "pointscale/edit_rotations.h"
#include "pointscale/parallel.h"
#include "pointscale/spatial_order.h"
#include "pointscale/validation.h"

namespace pointscale {

namespace {

// A reversal counts once its cosine is below -fold_rounding: a result and its reference built
// in different coordinates (centred or not) differ by rounding, about 1e-13 of an edge, and
// an edge or a plane at right angles must not flip between them.
constexpr double fold_rounding = 1e-9;

// A ring edge this much shorter than the ring's longest, in the base or in the input, is left
// out of both tests: points that coincide in the input (a mesh split along a seam, a scan's
// duplicates) have no order along it to keep, and their base positions differ by a rounding
// of how they were reached (1e-7 to 1e-5 of the spacing), which a result's rounding then turns
// either way. Blender's keys, in float32, round at about 1e-7 of the model.
constexpr double negligible_edge = 1e-4;

// Members of slot t's ring (bits m) whose edge from t is negligible_edge of the longest in x
// (#P by 3, by slot), among those skip leaves in.
std::uint16_t negligible_edges(const IndexList& rings, int ring_size, const Points& x, std::size_t t, std::uint16_t skip) {
  const Index* ring = rings.data() + t * static_cast<std::size_t>(ring_size);
  const Eigen::RowVector3d xi = x.row(static_cast<Eigen::Index>(t));
  double longest = 0.0;
  double length[16];
  for (int m = 1; m < ring_size; ++m) {
    length[m] = (x.row(ring[m]) - xi).squaredNorm();
    if (!((skip >> m) & 1u)) longest = std::max(longest, length[m]);
  }
  std::uint16_t bits = 0;
  for (int m = 1; m < ring_size; ++m)
    if (!((skip >> m) & 1u) && length[m] <= negligible_edge * negligible_edge * longest)
      bits |= static_cast<std::uint16_t>(1u << m);
  return bits;
}

// a . b < -fold_rounding |a| |b|, without the square roots.
inline bool reversed(const Vec3& a, const Vec3& b) {
  const double d = a.dot(b);
  return d < 0.0 && d * d > fold_rounding * fold_rounding * a.squaredNorm() * b.squaredNorm();
}

// An input edge within this sine of a right angle to its base edge has no clear order along it:
// the wall of a box handle stands at right angles to its base, and the edge from a top corner to
// the wall point below it turned from +0.3 to -0.9 degrees past the right angle under a bump of
// the base 0.5% of the model high, a fold nobody could see. With the input's reference such an
// edge folds only once its result turns past the right angle by as much again (a gain of -1 or
// 2 turns some 95 to 145 degrees from their base edges: folds).
constexpr double right_angle_margin = 0.05;  // sin(2.9 degrees)

// a . b within right_angle_margin |a| |b| of zero, without the square roots.
inline bool at_right_angle(const Vec3& a, const Vec3& b) {
  const double d = a.dot(b);
  return d * d <= right_angle_margin * right_angle_margin * a.squaredNorm() * b.squaredNorm();
}

// a . b < -right_angle_margin |a| |b|: past the right angle by the margin.
inline bool past_right_angle(const Vec3& a, const Vec3& b) {
  const double d = a.dot(b);
  return d < 0.0 && d * d > right_angle_margin * right_angle_margin * a.squaredNorm() * b.squaredNorm();
}

// Whether ring edge m (base db, result dr) fails the crossing test: never where the input exempts
// it, past the margin where the input holds it at right angles (right), else where reversed.
inline bool edge_folds(int m, std::uint16_t exempt, std::uint16_t right, const Vec3& dr, const Vec3& db) {
  if ((exempt >> m) & 1u) return false;
  return (right >> m) & 1u ? past_right_angle(dr, db) : reversed(dr, db);
}

// A ring's plane m0 x m1 is there only where it stands clear of rounding: its sine above
// plane_rounding. Where the ring lies on a line (three points along a CAD model's edge, the rest
// of the ring on the other side of a thin wall), the cross product is rounding's, of any
// direction: a rigid move of the whole model turned it over, and Prevent Folds then moved
// hundreds of points by 7% of the model.
constexpr double plane_rounding = 1e-6;
inline bool has_plane(const Vec3& m0, const Vec3& m1, const Vec3& normal) {
  return normal.squaredNorm() > plane_rounding * plane_rounding * m0.squaredNorm() * m1.squaredNorm();
}

// The plane test: the result's plane (m0 x m1) turned against the base's, nb (the stored
// base's rings with no plane are left out of the test: ring_on_a_line).
inline bool turned_over(const Vec3& m0, const Vec3& m1, const Vec3& nb) {
  const Vec3 nr = m0.cross(m1);
  return has_plane(m0, m1, nr) && reversed(nr, nb);
}

// Two tangents of the unit normal n with t1 x t2 = n, without a branch on its direction
// (Duff et al. 2017, "Building an orthonormal basis, revisited").
inline void tangents(const Vec3& n, Vec3& t1, Vec3& t2) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double b = n.x() * n.y() * a;
  t1 = Vec3(1.0 + sign * n.x() * n.x() * a, sign * b, -sign * n.x());
  t2 = Vec3(b, sign + n.y() * n.y() * a, -n.y());
}

// The rows of a #P by 3 array by slot: a copy already in slot order (order null), or the
// array itself in point order, read through the reference's order.
struct SlotRows {
  const double* rows;
  Eigen::Index stride;
  const Index* order;
  Vec3 operator()(Index s) const {
    const double* p = rows + stride * (order ? order[s] : s);
    return Vec3(p[0], p[1], p[2]);
  }
};

SlotRows by_point(const Eigen::Ref<const Points>& a, const FoldReference& ref) {
  return SlotRows{a.data(), a.outerStride(), ref.order.data()};
}

// a (in point order) copied into slot order: one pass of scattered reads, so that the tests
// after it read every ring from the cache.
Points in_slot_order(const Eigen::Ref<const Points>& a, const FoldReference& ref) {
  Points out(a.rows(), 3);
  parallel_for(static_cast<std::size_t>(a.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) out.row(static_cast<Eigen::Index>(t)) = a.row(ref.order[t]);
  }, {}, 16384);
  return out;
}

SlotRows by_slot(const Points& a) { return SlotRows{a.data(), 3, nullptr}; }

// A result and the base it was built on (null: the stored one), copied into slot order.
struct InSlotOrder {
  Points result, edited;
  SlotRows r, e;
  const SlotRows* e_rows;  // null for the stored base
  InSlotOrder(const Eigen::Ref<const Points>& result_, const Points* edited_, const FoldReference& ref)
      : result(in_slot_order(result_, ref)),
        edited(edited_ ? in_slot_order(*edited_, ref) : Points()),
        r(by_slot(result)),
        e(by_slot(edited)),
        e_rows(edited_ ? &e : nullptr) {}
  InSlotOrder(const InSlotOrder&) = delete;  // r and e point into the copies
  InSlotOrder& operator=(const InSlotOrder&) = delete;
};

// M_x0 x M_x1 at slot s (folds.h): the plane of x (#P by 3, by slot) over the ring's members
// that skip leaves in, with the stored base's tangent coordinates.
Vec3 ring_plane(const FoldReference& ref, std::uint16_t skip, const SlotRows& x, Index s) {
  const Index* ring = ref.rings.data() + static_cast<std::size_t>(s) * ref.ring_size;
  Vec3 t1, t2;
  tangents(ref.normals.row(s).transpose(), t1, t2);
  const Vec3 bi = ref.base.row(s).transpose(), xi = x(s);
  Vec3 m0 = Vec3::Zero(), m1 = Vec3::Zero();
  for (int m = 1; m < ref.ring_size; ++m) {
    if ((skip >> m) & 1u) continue;
    const Index j = ring[m];
    const Vec3 d0 = ref.base.row(j).transpose() - bi;
    const Vec3 dx = x(j) - xi;
    const double u0 = d0.dot(t1), u1 = d0.dot(t2);
    m0 += u0 * dx;
    m1 += u1 * dx;
  }
  return m0.cross(m1);
}

// Walks the ring of slot s over the members skip leaves in: visit(m, db, dr, u0, u1) for the
// edge from s to member m in the (edited) base (db) and in the result (dr), and the stored
// base edge's tangent coordinates u0, u1 (the weights of the ring's plane sums, folds.h).
template <class Visit>
inline void walk_ring_edges(const FoldReference& ref, std::uint16_t skip, const SlotRows* edited, const SlotRows& r,
                            Index s, Visit&& visit) {
  const Index* ring = ref.rings.data() + static_cast<std::size_t>(s) * ref.ring_size;
  Vec3 t1, t2;
  tangents(ref.normals.row(s).transpose(), t1, t2);
  const Vec3 bi = ref.base.row(s).transpose();
  const Vec3 ri = r(s);
  const Vec3 ei = edited ? (*edited)(s) : Vec3::Zero();
  for (int m = 1; m < ref.ring_size; ++m) {
    if ((skip >> m) & 1u) continue;
    const Index j = ring[m];
    const Vec3 d0 = ref.base.row(j).transpose() - bi;
    const Vec3 db = edited ? Vec3((*edited)(j) - ei) : d0;
    const Vec3 dr = r(j) - ri;
    visit(m, db, dr, d0.dot(t1), d0.dot(t2));
  }
}

// The FoldKind bits of slot s (folds.h has the definitions). skip: ring members left out of
// both tests, and bit 0 the plane test on a ring with no plane; exempt: edges left out of the
// crossing test, and bit 0 the plane test. The stored base's plane is the reference's
// (base_planes); an edited base's is summed here.
inline std::uint8_t fold_kind(const FoldReference& ref, std::uint16_t skip, std::uint16_t exempt, const SlotRows* edited,
                              const SlotRows& r, Index s, std::uint16_t right = 0) {
  // The result's plane is summed in the same pass as the crossing test: ring_plane's sums,
  // without reading the ring twice.
  Vec3 mr0 = Vec3::Zero(), mr1 = Vec3::Zero();
  std::uint8_t kind = fold_none;
  walk_ring_edges(ref, skip, edited, r, s, [&](int m, const Vec3& db, const Vec3& dr, double u0, double u1) {
    if (edge_folds(m, exempt, right, dr, db)) kind |= fold_crossed;
    mr0 += u0 * dr;
    mr1 += u1 * dr;
  });
  const Vec3 nb = edited ? ring_plane(ref, skip, *edited, s) : Vec3(ref.base_planes.row(s).transpose());
  if (turned_over(mr0, mr1, nb) && !((exempt | skip) & 1u)) kind |= fold_turned;
  return kind;
}

// The smallest root in (0, 1) of a + b x + c x^2, which is positive at 0 and not at 1; 1 where
// rounding hides it.
double first_root(double a, double b, double c) {
  double lo = 0.0, hi = 1.0;
  // Bisection: the quadratic's closed form loses its digits where c is tiny against b, and
  // 40 halvings (1e-12) cost nothing next to the ring's sums, at the folds only.
  for (int k = 0; k < 40; ++k) {
    const double x = 0.5 * (lo + hi);
    if (a + x * (b + x * c) > 0.0) lo = x; else hi = x;
  }
  return lo > 0.0 ? lo : 1.0;
}

// The largest share mu of slot s's offsets, and of its ring members' (each from its own base
// position, all by the same share), at which the ring at s would no longer fold: the crossing
// test along an edge is linear in mu, the plane test quadratic. The limiter's first guess at
// how far a fold's gain must go: on its plateau the ring's members share the fold's limiter.
// Tests that do not fail at mu = 1 are left out (they hold on the whole way down, or dip
// below only in between: the rounds after catch those). 1 where nothing fails.
// An edge at right angles in the input (right) fails only past the margin, as in fold_kind, and
// its share is then the one that brings it back to the right angle itself.
double unfolding_share(const FoldReference& ref, std::uint16_t skip, std::uint16_t exempt, const SlotRows* edited,
                       const SlotRows& r, Index s, std::uint16_t right = 0) {
  Vec3 mr0 = Vec3::Zero(), mr1 = Vec3::Zero(), mb0 = Vec3::Zero(), mb1 = Vec3::Zero();
  double share = 1.0;
  walk_ring_edges(ref, skip, edited, r, s, [&](int m, const Vec3& db, const Vec3& dr, double u0, double u1) {
    if (edge_folds(m, exempt, right, dr, db)) {
      const double bb = db.squaredNorm();
      share = std::min(share, bb / (bb - dr.dot(db)));
    }
    mr0 += u0 * dr;
    mr1 += u1 * dr;
    mb0 += u0 * db;
    mb1 += u1 * db;
  });
  const Vec3 nb = mb0.cross(mb1);
  if (!((exempt | skip) & 1u) && turned_over(mr0, mr1, nb)) {
    const Vec3 d0 = mr0 - mb0, d1 = mr1 - mb1;
    share = std::min(share, first_root(nb.dot(nb), (d0.cross(mb1) + mb0.cross(d1)).dot(nb), d0.cross(d1).dot(nb)));
  }
  return share;
}

// Whether the stored base's ring at slot s spreads along one line only (its tangent spread
// across the line below on_a_line_spread of that along it): a strip of duplicated or collinear
// scan points. Such a ring has no plane to turn over; its plane test would read the rounding
// of a vanishing cross product and report folds that no limiter can undo (real scans have such
// strips).
bool ring_on_a_line(const FoldReference& ref, std::uint16_t skip, Index s) {
  constexpr double on_a_line_spread = 1e-3;  // eigenvalue ratio: a ring about 30 times longer than wide
  const Index* ring = ref.rings.data() + static_cast<std::size_t>(s) * ref.ring_size;
  Vec3 t1, t2;
  tangents(ref.normals.row(s).transpose(), t1, t2);
  const Vec3 bi = ref.base.row(s).transpose();
  double g00 = 0.0, g01 = 0.0, g11 = 0.0;
  for (int m = 1; m < ref.ring_size; ++m) {
    if ((skip >> m) & 1u) continue;
    const Vec3 d0 = ref.base.row(ring[m]).transpose() - bi;
    const double u0 = d0.dot(t1), u1 = d0.dot(t2);
    g00 += u0 * u0; g01 += u0 * u1; g11 += u1 * u1;
  }
  const double half = 0.5 * (g00 + g11), gap = std::sqrt(0.25 * (g00 - g11) * (g00 - g11) + g01 * g01);
  return !(half - gap > on_a_line_spread * (half + gap));
}

// The same, with the edges that fold as bits (bit 0 for the plane): what the input exempts.
// right: receives the edges the input holds at right angles to the base (right_angle_margin).
std::uint16_t folding_bits(const FoldReference& ref, std::uint16_t skip, const SlotRows& r, Index s,
                           std::uint16_t& right) {
  const Index* ring = ref.rings.data() + static_cast<std::size_t>(s) * ref.ring_size;
  std::uint16_t bits = fold_kind(ref, skip, 0, nullptr, r, s) & fold_turned ? 1u : 0u;
  const Vec3 bi = ref.base.row(s).transpose(), ri = r(s);
  right = 0;
  for (int m = 1; m < ref.ring_size; ++m) {
    if ((skip >> m) & 1u) continue;
    const Vec3 d0 = ref.base.row(ring[m]).transpose() - bi;
    const Vec3 dr = r(ring[m]) - ri;
    if (reversed(dr, d0)) bits |= static_cast<std::uint16_t>(1u << m);
    else if (at_right_angle(dr, d0)) right |= static_cast<std::uint16_t>(1u << m);
  }
  return bits;
}

}  // namespace

FoldReference fold_reference(const MultiscaleModel& model, const Points* input, const Points* base,
                             const Points* base_normals) {
  validate(model);
  if (input) check_rows(input->rows(), model.base.rows(), "input");
  if ((base == nullptr) != (base_normals == nullptr))
    throw std::invalid_argument("a fold reference's base and base normals are given together");
  if (base) {
    check_rows(base->rows(), model.base.rows(), "base");
    check_rows(base_normals->rows(), model.base.rows(), "base normals");
    check_points(*base, "base");
    check_points(*base_normals, "base normals");
  }
  const Points& stored = base ? *base : model.base;
  const Points& stored_normals = base ? *base_normals : model.base_normals;
  static_assert(base_ring_size <= 16, "ring bits are 16 wide");
  const std::size_t n = static_cast<std::size_t>(stored.rows());
  FoldReference ref;
  ref.order = morton_order(stored);
  ref.slot.resize(n);
  for (std::size_t t = 0; t < n; ++t) ref.slot[static_cast<std::size_t>(ref.order[t])] = static_cast<Index>(t);
  ref.ring_size = ring_size_for(stored.rows());
  const std::size_t width = static_cast<std::size_t>(ref.ring_size);
  {
    const IndexList rings = base_rings(stored, model.parts);
    ref.rings.resize(rings.size());
    parallel_for(n, [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) {
        const Index* ring = rings.data() + static_cast<std::size_t>(ref.order[t]) * width;
        for (std::size_t m = 0; m < width; ++m) ref.rings[t * width + m] = ref.slot[static_cast<std::size_t>(ring[m])];
      }
    }, {}, 16384);
  }
  ref.base = in_slot_order(stored, ref);
  ref.normals = in_slot_order(stored_normals, ref);
  ref.other_sheet.assign(n, 0);
  ref.base_planes.resize(static_cast<Eigen::Index>(n), 3);
  Points input_by_slot;
  if (input) {
    ref.exempt.assign(n, 0);
    ref.right_angles.assign(n, 0);
    input_by_slot = in_slot_order(*input, ref);
  }
  const SlotRows in = by_slot(input_by_slot);
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t t = b; t < e; ++t) {
      const Index* ring = ref.rings.data() + t * width;
      const Eigen::Index row = static_cast<Eigen::Index>(t);
      std::uint16_t skip = 0;
      for (std::size_t m = 1; m < width; ++m)
        if (ring[m] == ring[0] || ref.normals.row(ring[m]).dot(ref.normals.row(row)) <= 0.0)
          skip |= static_cast<std::uint16_t>(1u << m);
      skip |= negligible_edges(ref.rings, ref.ring_size, ref.base, t, skip);
      if (input) skip |= negligible_edges(ref.rings, ref.ring_size, input_by_slot, t, skip);
      if (ring_on_a_line(ref, skip, static_cast<Index>(t))) skip |= 1u;
      ref.other_sheet[t] = skip;
      ref.base_planes.row(static_cast<Eigen::Index>(t)) = ring_plane(ref, skip, by_slot(ref.base), static_cast<Index>(t)).transpose();
      if (input) ref.exempt[t] = folding_bits(ref, skip, in, static_cast<Index>(t), ref.right_angles[t]);
    }
  }, {}, 4096);
  // The rings reversed, by a counting sort over the members.
  ref.in_offsets.assign(n + 1, 0);
  for (std::size_t t = 0; t < n; ++t)
    for (std::size_t m = 1; m < width; ++m) ++ref.in_offsets[static_cast<std::size_t>(ref.rings[t * width + m]) + 1];
  for (std::size_t j = 0; j < n; ++j) ref.in_offsets[j + 1] += ref.in_offsets[j];
  ref.in_rings.resize(static_cast<std::size_t>(ref.in_offsets[n]));
  std::vector<Index> fill(ref.in_offsets.begin(), ref.in_offsets.end() - 1);
  for (std::size_t t = 0; t < n; ++t)
    for (std::size_t m = 1; m < width; ++m)
      ref.in_rings[static_cast<std::size_t>(fill[static_cast<std::size_t>(ref.rings[t * width + m])]++)] = static_cast<Index>(t);
  // Each list by point index, so that the limiter's means add up in the same order whatever the slots.
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t s = b; s < e; ++s)
      std::sort(ref.in_rings.begin() + ref.in_offsets[s], ref.in_rings.begin() + ref.in_offsets[s + 1],
                [&](Index x, Index y) { return ref.order[static_cast<std::size_t>(x)] < ref.order[static_cast<std::size_t>(y)]; });
  }, {}, 16384);
  return ref;
}

namespace {

// The FoldKind of every point, by point, from rows already in slot order (edited: null for the
// stored base). Returns the number of points that fold.
std::size_t folds_everywhere(const FoldReference& ref, const SlotRows* edited, const SlotRows& r,
                             std::vector<std::uint8_t>& kind) {
  const std::size_t n = ref.order.size();
  kind.assign(n, fold_none);
  const bool exempting = !ref.exempt.empty();
  parallel_for(n, [&](std::size_t b, std::size_t end) {
    for (std::size_t t = b; t < end; ++t)
      kind[static_cast<std::size_t>(ref.order[t])] =
          fold_kind(ref, ref.other_sheet[t], exempting ? ref.exempt[t] : 0, edited, r, static_cast<Index>(t),
                    exempting ? ref.right_angles[t] : 0);
  }, {}, 4096);
  return n - static_cast<std::size_t>(std::count(kind.begin(), kind.end(), std::uint8_t(fold_none)));
}

}  // namespace

std::size_t find_folds(const MultiscaleModel& model, const FoldReference& ref, const Points* edited,
                       Eigen::Ref<const Points> result, std::vector<std::uint8_t>& kind) {
  check_folds_input(model, ref, edited, result);
  const InSlotOrder rows(result, edited, ref);
  return folds_everywhere(ref, rows.e_rows, rows.r, kind);
}

namespace {

// find_folds_at on checked input, at slots: kind stays by point.
void folds_at(const FoldReference& ref, const SlotRows* edited, const SlotRows& r, const IndexList& slots,
              std::vector<std::uint8_t>& kind) {
  const bool exempting = !ref.exempt.empty();
  parallel_for(slots.size(), [&](std::size_t b, std::size_t end) {
    for (std::size_t k = b; k < end; ++k) {
      const std::size_t s = static_cast<std::size_t>(slots[k]);
      kind[static_cast<std::size_t>(ref.order[s])] =
          fold_kind(ref, ref.other_sheet[s], exempting ? ref.exempt[s] : 0, edited, r, static_cast<Index>(s),
                    exempting ? ref.right_angles[s] : 0);
    }
  }, {}, 1024);
}

}  // namespace

void find_folds_at(const MultiscaleModel& model, const FoldReference& ref, const Points* edited,
                   Eigen::Ref<const Points> result, const IndexList& points, std::vector<std::uint8_t>& kind) {
  check_folds_input(model, ref, edited, result);
  if (kind.size() != static_cast<std::size_t>(result.rows())) throw std::invalid_argument("kind must have #P entries");
  IndexList slots(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Index i = points[k];
    if (i < 0 || i >= result.rows()) throw std::invalid_argument("points to test must be indices of points");
    slots[k] = ref.slot[static_cast<std::size_t>(i)];
  }
  const SlotRows r = by_point(result, ref);
  SlotRows e{nullptr, 3, nullptr};
  if (edited) e = by_point(*edited, ref);
  folds_at(ref, edited ? &e : nullptr, r, slots, kind);
}

// n values, all zero, in pages the system zeroes as they are first touched: prevention touches
// only the rings near folds, so the rest of a large model's layers cost nothing.
template <class T>
class ZeroedArray {
  static_assert(std::is_trivial<T>::value, "all-zero bytes must be the value zero");

 public:
  explicit ZeroedArray(std::size_t n) : data_(static_cast<T*>(std::calloc(n > 0 ? n : 1, sizeof(T)))) {
    if (!data_) throw std::bad_alloc();
  }
  ~ZeroedArray() { std::free(data_); }
  ZeroedArray(ZeroedArray&& other) noexcept : data_(other.data_) { other.data_ = nullptr; }
  ZeroedArray(const ZeroedArray&) = delete;
  ZeroedArray& operator=(const ZeroedArray&) = delete;
  ZeroedArray& operator=(ZeroedArray&&) = delete;
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

 private:
  T* data_;
};

// Which slots are on a list being built, so that each goes on it once; marked by any number of
// threads at once. A list is built from the neighbourhoods of the slots before it, which on a
// large model reach a hundred thousand slots in a round, so every thread builds a share.
class SlotMarks {
 public:
  explicit SlotMarks(std::size_t n) : taken_(n) {}  // all clear
  // Marks slot s, and says whether this call marked it (false: it already was).
  bool claim(Index s) {
    std::atomic<std::uint8_t>& t = taken_[static_cast<std::size_t>(s)];
    return t.load(std::memory_order_relaxed) == 0 && t.exchange(1, std::memory_order_relaxed) == 0;
  }
  bool taken(Index s) const { return taken_[static_cast<std::size_t>(s)].load(std::memory_order_relaxed) != 0; }
  // Clears the marks of the slots listed (the list that was built).
  void clear(const IndexList& list) {
    parallel_for(list.size(), [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) taken_[static_cast<std::size_t>(list[t])].store(0, std::memory_order_relaxed);
    }, {}, 16384);
  }

 private:
  std::vector<std::atomic<std::uint8_t>> taken_;
};

// Calls visit(chunk's list, slot) for the slots from[begin..) on any number of threads, then
// appends the chunks' lists to into in chunk order (into may be from: it grows after the reading).
template <class Visit>
void append_in_parallel(const IndexList& from, std::size_t begin, IndexList& into, Visit&& visit) {
  constexpr std::size_t chunk = 1024;
  const std::size_t count = from.size() - begin;
  std::vector<IndexList> found((count + chunk - 1) / chunk);
  parallel_for(count, [&](std::size_t b, std::size_t e) {
    IndexList& out = found[b / chunk];
    for (std::size_t t = b; t < e; ++t) visit(out, from[begin + t]);
  }, {}, chunk);
  for (const IndexList& f : found) into.insert(into.end(), f.begin(), f.end());
}

// Appends to list the neighbours of list[begin..) not marked yet, marking them.
template <class EachNeighbour>
void claim_neighbours(IndexList& list, std::size_t begin, SlotMarks& marks, EachNeighbour&& each_neighbour) {
  append_in_parallel(list, begin, list, [&](IndexList& out, Index s) {
    each_neighbour(s, [&](Index q) {
      if (marks.claim(q)) out.push_back(q);
    });
  });
}

// The slots whose folds may have changed: those of `dirty` that moved, and the slots whose rings hold
// one (no other slot's ring moved), into check (empty, marks clear), marked.
void claim_moved(const IndexList& dirty, const ZeroedArray<std::uint8_t>& moved, SlotMarks& marks,
                 const FoldReference& ref, IndexList& check) {
  append_in_parallel(dirty, 0, check, [&](IndexList& out, Index s) {
    const std::size_t us = static_cast<std::size_t>(s);
    if (!moved[us]) return;
    if (marks.claim(s)) out.push_back(s);
    for (Index k = ref.in_offsets[us]; k < ref.in_offsets[us + 1]; ++k) {
      const Index q = ref.in_rings[static_cast<std::size_t>(k)];
      if (marks.claim(q)) out.push_back(q);
    }
  });
}

// The round of folding (its strength rising each time) in which a point's ring first takes its
// strength too, or the strength at which it does, whichever comes first: rounds at the step
// alone (1/2, 3/4, ...) reach that strength in their tenth.
constexpr int hand_on_round = 3;
constexpr int stubborn_rounds = 10;
// The share of a fold's gain the limiter leaves it, of what unfolding_share says would just do.
constexpr double unfolding_margin = 0.8;

FoldLimitReport limit_folds(const MultiscaleModel& model, const FoldReference& ref, const Points* edited,
                            const Vec3& origin, Eigen::Ref<Points> result, const FoldLimitOptions& options) {
  check_folds_input(model, ref, edited, result);
  validate(options);
  FoldLimitReport out;
  const std::size_t n = static_cast<std::size_t>(model.base.rows());
  const std::size_t width = static_cast<std::size_t>(ref.ring_size);
  // Everything below is kept by slot, as the reference is, so that a ring and its neighbours
  // are read from the cache; the result is written back by point at the end.
  InSlotOrder rows(result, edited, ref);
  Points& r_by_slot = rows.result;  // limited in place, written back by point at the end
  const SlotRows& r = rows.r;
  const SlotRows* e_rows = rows.e_rows;
  out.folded_before = folds_everywhere(ref, e_rows, r, out.before);
  out.after = out.before;
  out.folded_after = out.folded_before;
  if (out.folded_before == 0) return out;

  // The two-way ring neighbours of slot s (its ring's members, and the slots whose rings hold
  // it): a symmetric neighbourhood, so that widening and averaging spread alike in every direction.
  auto each_neighbour = [&](Index s, auto&& visit) {
    const std::size_t us = static_cast<std::size_t>(s);
    const Index* ring = ref.rings.data() + us * width;
    for (std::size_t m = 1; m < width; ++m) visit(ring[m]);
    for (Index k = ref.in_offsets[us]; k < ref.in_offsets[us + 1]; ++k) visit(ref.in_rings[static_cast<std::size_t>(k)]);
  };
  // Where the limiter pulls a slot's point: its base, in the result's coordinates.
  auto base_at = [&](Index s) -> Eigen::RowVector3d {
    return edited ? Eigen::RowVector3d(rows.edited.row(s)) : Eigen::RowVector3d(ref.base.row(s) + origin.transpose());
  };
  // The limiter's layers, by slot: the strengths, `smoothing` widenings of them, then as many
  // averagings; the last is 1 - lambda. A layer at a point reads the layer below at the point and its
  // neighbours only, so when strengths change, each layer changes only within one more ring
  // step of where the layer below changed: a round recomputes just that, and late rounds,
  // with few folds left, cost little.
  const int passes = 2 * options.smoothing;
  const bool exempting = !ref.exempt.empty();
  std::vector<ZeroedArray<double>> layer;
  for (int k = 0; k <= passes; ++k) layer.emplace_back(n);
  ZeroedArray<double>& strength = layer.front();
  SlotMarks marks(n);  // the slots on the list being built (cleared when it is done)
  IndexList dirty, check, folds;  // slots
  ZeroedArray<std::uint8_t> moved(n);
  for (std::size_t i = 0; i < n; ++i)
    if (out.before[i] != fold_none) folds.push_back(ref.slot[i]);

  // A point that still folds after its ring's own guess (unfolding_share) and a round more, or
  // once its own gain is all but gone, folds because of its ring: the averaging leaves each ring
  // member a share of its gain (about 1% on a sharp CAD edge), and on a ring with hardly any
  // plane that share keeps the fold. From its hand_on_round-th round of folding on, or once its
  // strength reaches that of the step's tenth round, such a point hands its strength on to its
  // ring's members, which then limit like folds of their own (and hand it on in turn if they
  // fold too: at once when it is the stubborn strength, else in their own hand_on_round-th
  // round of folding).
  double stubborn = 0.0;  // the strength the step alone gives in a point's stubborn_rounds-th round of folding
  for (int k = 0; k < stubborn_rounds; ++k) stubborn = 1.0 - options.step * (1.0 - stubborn);
  ZeroedArray<std::uint8_t> times_folded(n);  // rounds each slot has folded in, up to 255
  while (!folds.empty() && out.rounds < options.max_rounds) {
    ++out.rounds;
    // In point order, whatever order the tests found them in: a stubborn fold hands on the
    // strength it holds when its turn comes, which a fold before it may have raised.
    std::sort(folds.begin(), folds.end(), [&](Index x, Index y) {
      return ref.order[static_cast<std::size_t>(x)] < ref.order[static_cast<std::size_t>(y)];
    });
    // Each fold's strength rises by the step, or at once as far as its ring says it must
    // (unfolding_share, with a margin: the ring's members keep a little more of their gain
    // than the fold itself), whichever is more: a fold far over takes one round, not ten.
    const ZeroedArray<double>& lowered_now = layer.back();  // 1 - lambda, as the last round left it
    std::vector<double> guess(folds.size());
    parallel_for(folds.size(), [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) {
        const std::size_t f = static_cast<std::size_t>(folds[k]);
        const double share = unfolding_share(ref, ref.other_sheet[f], exempting ? ref.exempt[f] : 0, e_rows, r,
                                             folds[k], exempting ? ref.right_angles[f] : 0);
        guess[k] = 1.0 - unfolding_margin * share * (1.0 - lowered_now[f]);
      }
    }, {}, 256);
    for (std::size_t k = 0; k < folds.size(); ++k) {
      double& w = strength[static_cast<std::size_t>(folds[k])];
      w = std::max(1.0 - options.step * (1.0 - w), guess[k]);
      std::uint8_t& c = times_folded[static_cast<std::size_t>(folds[k])];
      if (c < 255) ++c;
    }
    // Each layer again where the one below changed, and one ring step around it: the largest
    // (widening) or the mean (averaging) of each point and its neighbours, the mean adding up
    // in the neighbours' order, so that it is the same sum wherever it is recomputed.
    dirty.clear();  // each slot once: with smoothing 0 dirty is written to as it is
    for (Index f : folds)
      if (marks.claim(f)) dirty.push_back(f);
    for (Index f : folds) {
      const double w = strength[static_cast<std::size_t>(f)];
      if (w < stubborn && times_folded[static_cast<std::size_t>(f)] < hand_on_round) continue;
      const Index* ring = ref.rings.data() + static_cast<std::size_t>(f) * width;
      for (std::size_t m = 1; m < width; ++m) {
        const Index j = ring[m];
        double& wj = strength[static_cast<std::size_t>(j)];
        if (wj < w) {
          wj = w;
          if (marks.claim(j)) dirty.push_back(j);
        }
      }
    }
    // A layer changes where the one below changed and at their neighbours: each pass adds to
    // dirty the neighbours of the slots the pass before added (its frontier), the others'
    // neighbours being on it already.
    std::size_t frontier = 0;  // where the frontier starts in dirty: all of it on the first pass
    for (int k = 1; k <= passes; ++k) {
      const bool largest = k <= options.smoothing;
      const std::size_t taken = dirty.size();
      claim_neighbours(dirty, frontier, marks, each_neighbour);
      frontier = taken;
      const ZeroedArray<double>& below = layer[static_cast<std::size_t>(k - 1)];
      ZeroedArray<double>& into = layer[static_cast<std::size_t>(k)];
      parallel_for(dirty.size(), [&](std::size_t b, std::size_t e) {
        for (std::size_t t = b; t < e; ++t) {
          const Index j = dirty[t];
          double v = below[static_cast<std::size_t>(j)];
          int count = 1;
          each_neighbour(j, [&](Index q) {
            const double f = below[static_cast<std::size_t>(q)];
            v = largest ? std::max(v, f) : v + f;
            ++count;
          });
          into[static_cast<std::size_t>(j)] = largest ? v : v / count;
        }
      }, {}, 512);
    }
    marks.clear(dirty);
    // The points whose limiter may have changed, from their reconstructed rows (the result
    // keeps them until the end).
    const ZeroedArray<double>& field = layer.back();
    parallel_for(dirty.size(), [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) {
        const Index s = dirty[t];
        const std::size_t us = static_cast<std::size_t>(s);
        const double lambda = 1.0 - field[us];
        const Eigen::RowVector3d original = result.row(ref.order[us]);
        const Eigen::RowVector3d base = base_at(s);
        const Eigen::RowVector3d now = lambda == 1.0 ? original : Eigen::RowVector3d(base + lambda * (original - base));
        moved[us] = (now.array() != r_by_slot.row(s).array()).any() ? 1 : 0;
        r_by_slot.row(s) = now;
      }
    }, {}, 4096);
    // Test again every point that moved or whose ring holds one that moved: no other point's
    // folds can have changed.
    check.clear();
    claim_moved(dirty, moved, marks, ref, check);
    folds_at(ref, e_rows, r, check, out.after);
    // Folds left: among the tested points, and the folds of this round that were not tested
    // (their limiter and their rings did not move: one stronger fold beside them sets it).
    for (Index f : folds)
      if (!marks.taken(f)) check.push_back(f);
    folds.clear();
    for (Index s : check)
      if (out.after[static_cast<std::size_t>(ref.order[static_cast<std::size_t>(s)])] != fold_none) folds.push_back(s);
    marks.clear(check);
  }
  // Back to point order: the limited rows (the others are as reconstructed), and the limiter.
  out.limiter.resize(n);
  const ZeroedArray<double>& field = layer.back();
  parallel_for(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t s = b; s < e; ++s) {
      const Index i = ref.order[s];
      const double lambda = 1.0 - field[s];
      out.limiter[static_cast<std::size_t>(i)] = lambda;
      if (lambda < 1.0) result.row(i) = r_by_slot.row(static_cast<Eigen::Index>(s));
    }
  }, {}, 16384);
  out.folded_after = n - static_cast<std::size_t>(std::count(out.after.begin(), out.after.end(), std::uint8_t(fold_none)));
  out.capped = out.folded_after > 0;
  out.changed = static_cast<std::size_t>(std::count_if(out.limiter.begin(), out.limiter.end(), [](double l) { return l < 1.0; }));
  return out;
}

}  // namespace pointscale
