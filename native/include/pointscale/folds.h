// Folds: where a reconstruction turns the surface over itself (the paper's future work, Sec. 9).
// Scaled-up detail, or a strong edit of the base, can push a point's offset past its
// neighbours' (a face's nose and ears become spikes when the finer bands are doubled). The base is the
// parameter domain of the detail, so a fold is where the map from the base to the result
// stops being one to one: seen on each point's ring (edit_rotations.h), the base's one-ring.
#pragma once
#include <cstdint>
#include <vector>

#include "pointscale/decomposition.h"

namespace pointscale {

// Why a point folds, as bits (a point may have both).
enum FoldKind : std::uint8_t {
  fold_none = 0,
  fold_turned = 1,   // its ring's plane in the result faces against the base's there
  fold_crossed = 2,  // along an edge (i, j) of its ring, j comes before i in the result
};

// What a result's folds are measured against, per point: which ring members to leave out,
// as bits m = 1..ring_size - 1 of the ring's columns, and bit 0 for the ring's plane; and
// what the tests and the limiter walk the rings with. Everything per point is kept in a
// spatial order ("slots": slot t holds point order[t]) and the rings name slots, so that a
// ring's members lie close together in memory: a test then reads its neighbours from the
// cache instead of from all over a large model.
struct FoldReference {
  IndexList order;                         // #P: the point in each slot (morton_order of the base)
  IndexList slot;                          // #P: the slot of each point (order inverted)
  IndexList rings;                         // #P by ring_size, by slot: each slot's ring (base_rings) as slots,
                                           // itself first
  int ring_size = 0;
  Points base, normals;                    // #P by 3, by slot: the stored base and its normals
  Points base_planes;                      // #P by 3, by slot: the stored base's ring plane, M_b0 x M_b1 of
                                           // find_folds with the stored base (no edit), as find_folds sums it
  std::vector<std::uint16_t> other_sheet;  // #P, by slot: members whose stored base normal faces away (n_i . n_j <= 0),
                                           // or whose edge is under 1e-4 of the ring's longest in the base or the input,
                                           // and bit 0 where the stored ring lies on a line (no plane test)
  std::vector<std::uint16_t> exempt;       // #P, by slot: edges (bit m) and planes (bit 0) that already fold in
                                           // the input, or empty: every fold counts
  std::vector<std::uint16_t> right_angles; // #P, by slot, beside exempt: edges the input holds within 3 degrees of
                                           // right angles to their base edges, which fold only once their result
                                           // turns 3 degrees past the right angle
  std::vector<Index> in_offsets;           // #P + 1, and
  IndexList in_rings;                      // the slots whose rings hold each slot (the rings reversed): slot s
                                           // is in the rings of in_rings[in_offsets[s] .. in_offsets[s+1])
};

// The reference of a model. input: #P by 3, its unedited reconstruction (the input), whose
// own folds over the base are then not counted in results; or nullptr, and every fold over
// the base counts. base, base_normals: #P by 3 each, the base (in the model's coordinates)
// and its normals to measure against instead of the model's, or both nullptr: a mirrored
// model's whole base made exactly symmetric, so that a point and its reflection take the same
// tests and limiter (std::invalid_argument when only one is given or their rows differ).
FoldReference fold_reference(const MultiscaleModel& model, const Points* input, const Points* base = nullptr,
                             const Points* base_normals = nullptr);

// The folds of a result, point by point. For point i and the members j of its ring that lie
// on the same side of the base as i (stored base normals agreeing, n_i . n_j > 0; a ring
// reaching across a thin part would otherwise compare two sheets):
//  - crossed: (r_j - r_i) . (b_j - b_i) < 0, the order of i and j along the edge reverses
//    between the (edited) base b and the result r: their offsets cross;
//  - turned: the ring's plane in the result, oriented by the stored base's tangent plane at i,
//    faces against the (edited) base's ring plane: (M_r0 x M_r1) . (M_b0 x M_b1) < 0, where
//    M_x = sum_j (x_j - x_i) u_j^T and u_j are the tangent coordinates of the stored base's
//    edge (i, j). M_x (sum u u^T)^-1 is the least-squares Jacobian of the map from the
//    stored base to x on the ring; the inverse only scales the cross product by a positive
//    number, so the sign is read without it.
// An edge under 1e-4 of its ring's longest, in the stored base or in the input, takes neither
// test: points that coincide in the input (a mesh split along a seam, a scan's duplicates) have
// no order along it, and their base positions differ only by rounding, which a result's own
// rounding turns either way.
// A ring that spreads along one line only (a strip of duplicated or collinear scan points, its
// tangent spread across the line under 1e-3 of that along it) has no plane: it takes only the
// crossing test. Nor does a ring whose plane in the result has a sine under 1e-6 (M_r0 and
// M_r1 nearly parallel: the points of a CAD edge's ring left on one side of a thin wall), whose
// cross product is rounding's, of any direction.
// Both are sign tests, a reversal counting once its cosine is below -1e-9 (a result and its
// reference built in different coordinates differ by rounding, and an edge at right angles
// must not flip between them). Where the result is the base itself each edge gives
// |b_j - b_i|^2 >= 0 and each plane its own square, so nothing folds. The input itself can
// fold over its base (box walls standing on a concave foot; a scan's overhangs, nose and ears,
// over a base smoothed over three levels), and a reference built from it leaves those edges and planes out: what is counted is what a
// filter or an edit adds, and an unedited reconstruction has no folds at all.
//
// model   its base (the parameter domain) and base_normals; the rings are the reference's
// ref     fold_reference(model, ...)
// edited  #P by 3 the base the result was built on, in the result's coordinates, or nullptr
//         for the stored one (only differences of positions are used, so the stored base's
//         centring does not matter)
// result  #P by 3
// kind    receives #P FoldKind bits
// Returns the number of points that fold. Throws std::invalid_argument for what
// check_folds_input (validation.h) refuses; limit_folds also for options out of range.
std::size_t find_folds(const MultiscaleModel& model, const FoldReference& ref, const Points* edited,
                       Eigen::Ref<const Points> result, std::vector<std::uint8_t>& kind);

// The same at the listed points only; the other entries of kind (#P) are left as they are.
void find_folds_at(const MultiscaleModel& model, const FoldReference& ref, const Points* edited,
                   Eigen::Ref<const Points> result, const IndexList& points, std::vector<std::uint8_t>& kind);

struct FoldLimitOptions {
  int max_rounds = 40;   // detect, lower the limiter, detect again: at most this many times
  int smoothing = 2;     // the limiter's reach: this many steps of widening, then as many of averaging,
                         // over the rings (in both directions)
  double step = 0.5;     // each round a point still folds keeps this share of the gain it had left
};

struct FoldLimitReport {
  std::vector<std::uint8_t> before;  // #P FoldKind of the result as reconstructed
  std::vector<std::uint8_t> after;   // #P FoldKind of the limited result
  std::vector<double> limiter;       // #P lambda in [0, 1], or empty when nothing folded (all 1)
  std::size_t folded_before = 0, folded_after = 0;
  std::size_t changed = 0;           // points whose limiter is below 1 (the only ones moved)
  int rounds = 0;                    // rounds of lowering run
  bool capped = false;               // max_rounds was reached with folds left
};

// Prevents folds by limiting the gain point by point: result_i becomes
// b_i + lambda_i (result_i - b_i), every band's gain scaled by lambda_i along the level normals
// the reconstruction used (refitting them for the lowered gains would move every point within
// a kernel width of a fold, at every level). Each round, every point that folds gets a
// strength w: 1 - step the first time, and halfway (by step) closer to 1 each round it still
// folds, or at once what its ring asks for, whichever is more. Its ring asks for 1 - 0.8 mu
// lambda_now: mu is the largest share of the ring's present offsets from their base positions
// (the point's and its members', all scaled alike, as on the limiter's plateau) at which none
// of its tests fails (each crossing edge's test is linear in mu, the plane test quadratic).
// So a fold far over takes one round, not ten. The limiter is lambda = 1 - A^s D^s w, where D takes the largest w over a point and
// the two-way ring neighbours (ring members and the points whose rings hold it) and A their
// mean, each applied s = smoothing times: D^s keeps w on a plateau s steps wide around each
// fold, and A^s ramps it down to 0 over s more steps, so the limiter reaches w at the fold
// itself and falls smoothly to 1, exactly 1 beyond 2s ring steps from it. A point that folds in
// a third round (after its ring's own ask and a round more), or with its own gain all but gone
// (the strength of the step's tenth round), gives its strength to its ring's members too (the
// averaging leaves them a share of their gain, which keeps a fold on a ring with hardly any
// plane); they then count as folds of that strength, so around it the limiter reaches one ring
// step further, and a member that folds as well hands it on in turn (at once when it holds the
// strength of the step's tenth round, else in its own third round of folding; the folds are
// visited in point order each round, so the strengths handed on are the same on any number of
// threads). Points farther than that from every fold are not written to: they keep their
// result bit for bit.
//
// edited  as for find_folds, in the result's coordinates; origin: the stored base's offset
//         from them (the result's coordinates = the model's + origin), used when edited is null
// result  #P by 3, changed in place
FoldLimitReport limit_folds(const MultiscaleModel& model, const FoldReference& ref, const Points* edited, const Vec3& origin,
                            Eigen::Ref<Points> result, const FoldLimitOptions& options = {});

}  // namespace pointscale
