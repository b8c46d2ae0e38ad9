#include "pointscale/reconstruction.h"
#include "pointscale/validation.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "pointscale/parallel.h"
#include "pointscale/detail/ease_side_flips.h"
#include "pointscale/detail/level_normals.h"
#include "pointscale/detail/mirrored_edit.h"
#include "pointscale/detail/transported_rotations.h"
#include "pointscale/detail/reconstruct_levels.h"
#include "pointscale/detail/smooth_step.h"

namespace pointscale {

namespace {

struct HangFromFoot {
  Eigen::Index point;
  Vec3 base;   // the point's edited base position
  Vec3 foot;   // its foot's edited base position
  Vec3 shift;  // what hanging it from its foot rigidly would add
};

// What hanging point i from its foot f rigidly would add to it (HangFromFoot), or false where
// it stands on its own base position or nothing moved there.
inline bool foot_shift(Eigen::Index i, Index f, const Points& original, const Points& edited, const Mat3& turn,
                       HangFromFoot& hang) {
  if (f == static_cast<Index>(i)) return false;
  const Vec3 base = original.row(i).transpose(), base_edited = edited.row(i).transpose();
  const Vec3 foot = original.row(f).transpose(), foot_edited = edited.row(f).transpose();
  const Vec3 span = base - foot;
  const Vec3 shift = (foot_edited - foot) - (base_edited - base) + (turn * span - span);
  // Nothing moved here: the identity, exactly, so a local edit leaves the rest as it was.
  if (shift.x() == 0.0 && shift.y() == 0.0 && shift.z() == 0.0) return false;
  hang = {i, base_edited, foot_edited, shift};
  return true;
}

std::vector<HangFromFoot> hang_from_feet(const Points& original, const Points& edited, const IndexList& feet,
                                         const std::vector<Mat3>& rotation) {
  constexpr std::size_t chunk = 16384;
  std::vector<std::vector<HangFromFoot>> found((feet.size() + chunk - 1) / chunk);
  parallel_for(feet.size(), [&](std::size_t b, std::size_t e) {
    std::vector<HangFromFoot>& out = found[b / chunk];
    for (std::size_t ii = b; ii < e; ++ii) {
      const Index f = feet[ii];
      HangFromFoot hang;
      if (foot_shift(static_cast<Eigen::Index>(ii), f, original, edited, rotation[static_cast<std::size_t>(f)], hang))
        out.push_back(hang);
    }
  }, {}, chunk);
  std::vector<HangFromFoot> all;
  for (std::vector<HangFromFoot>& part : found) all.insert(all.end(), part.begin(), part.end());
  return all;
}

// Which way point h.point's offset from its edited base position goes, given its offset w
// there before the turn (any length; only its direction is used). Hanging it from its foot
// rigidly puts it at w + h.shift. A point well above its foot goes instead on the ray from its
// foot through there, at w's length: the base positions of a tall feature's points lie off to
// one side of its foot, and a steep edit stretches the base between the two by 1 / cos(slope),
// so offsets turned towards the hung points from those positions, keeping their lengths, slid
// sideways and the feature leaned; on the foot's ray only a point's height changes. The ray is
// followed fully only where it is a feature's axis (the hung point lies at least twice as far
// from the foot as the foot from the base position) and where it crosses the sphere of w's
// length squarely (it passes within half of w's length of the base position), and not at all
// where the point stands no farther from its foot than its base position does, or where the
// ray passes 0.8 of w's length away (near a tangent, where the crossing swings with the least
// change): between, the two directions are blended, so no point jumps.
inline Vec3 hung_direction(const HangFromFoot& h, const Vec3& w) {
  const Vec3 hung = w + h.shift;
  const Vec3 from_foot = h.base + hung - h.foot, foot = h.foot - h.base;
  const double reach = from_foot.norm(), length = w.norm(), hung_length = hung.norm();
  if (!(reach > 0.0) || !(hung_length > 0.0)) return hung;
  const Vec3 ray = from_foot / reach;
  const double along = foot.dot(ray), apart2 = std::max(0.0, foot.squaredNorm() - along * along);
  // Where the ray leaves the sphere of w's length, s along it from the foot. Where it also
  // enters the sphere ahead of the foot, that crossing is the nearer to the hung point only
  // where the point stands nearer its foot than its base position does: weight 0 below.
  const double s = -along + std::sqrt(std::max(0.0, length * length - apart2));
  // A crossing behind the foot, or at it, is no place on the feature's axis: the weight fades
  // out on the way there rather than dropping (the foot's span turned a quarter turn or more
  // against its own turn, as in a crumpled base).
  const double weight = smooth_step(reach / std::max(foot.norm(), 1e-300), 1.0, 2.0) *
                        (1.0 - smooth_step(std::sqrt(apart2) / length, 0.5, 0.8)) *
                        smooth_step(s / reach, 0.0, 0.5);
  if (!(weight > 0.0)) return hung;
  return (1.0 - weight) * (hung / hung_length) + weight * ((foot + s * ray) / length);
}

// Turns the point's offset from its base position to hung_direction, keeping its length, and
// every kept level and normal of it by the same turn.
inline void turn_towards_foot(const HangFromFoot& h, Points& p, Reconstruction* kept) {
  const Vec3 w = p.row(h.point).transpose() - h.base;
  if (!(w.norm() > 0.0)) return;
  const Vec3 v = hung_direction(h, w);
  if (!(v.norm() > 0.0)) return;
  const Mat3 q = Eigen::Quaterniond::FromTwoVectors(w, v).toRotationMatrix();
  p.row(h.point) = (h.base + q * w).transpose();
  if (!kept) return;
  for (std::size_t l = 1; l < kept->levels.size(); ++l) {
    Points& level = kept->levels[l];
    level.row(h.point) = (h.base + q * (level.row(h.point).transpose() - h.base)).transpose();
  }
  for (Points& n : kept->normals) n.row(h.point) = (q * n.row(h.point).transpose()).transpose();
}

// Turns each listed point's offset from its base position towards where hanging it from its
// foot puts it (turn_towards_foot, hung_direction). A steep edit stretches the base along its
// slope, and the base positions of a tall feature's top lie away from its foot: offsets hung
// from those positions would lean with the stretch.
void turn_towards_feet(const std::vector<HangFromFoot>& hang, Points& p, Reconstruction* kept) {
  parallel_for(hang.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t j = b; j < e; ++j) turn_towards_foot(hang[j], p, kept);
  }, {}, 4096);
}

// Band l's offset at point i: its gain (per band, k by 1, or per point, k by #P) times its detail.
inline double band_offset(const MultiscaleModel& model, const Eigen::MatrixXd& gains, int l, Eigen::Index i) {
  return (gains.cols() > 1 ? gains(l, i) : gains(l, 0)) * model.details(l, i);
}

// Adds level l's band along the stored base's level normals nrm to each point's detail
// (ReconstructionWorkspace::detail), and to the level `unedited` builds when not null.
void add_level_detail(const MultiscaleModel& model, const Eigen::MatrixXd& gains, int l, const Points& nrm,
                      Points& detail, Points* unedited) {
  parallel_for(static_cast<std::size_t>(detail.rows()), [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const double offset = band_offset(model, gains, l, i);
      detail.row(i) += offset * nrm.row(i);
      if (unedited) unedited->row(i) += offset * nrm.row(i);
    }
  }, {}, 4096);
}

// Whether a and b are the same gains (k by 1 or k by #P), bit for bit; an empty a never is.
bool same_gains(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.size() > 0 && a.rows() == b.rows() && a.cols() == b.cols() && (a.array() == b.array()).all();
}

bool same_bits(const Mat3& a, const Mat3& b) { return std::memcmp(a.data(), b.data(), sizeof(Mat3)) == 0; }

// Whether the edit left the ring of a point's foot as it was (its turn is exactly the identity).
inline bool not_turned(const Mat3& turn) {
  static const Mat3 identity = Mat3::Identity();
  return same_bits(turn, identity);
}

// Point i of an edited pass, before its hang from its foot, from the edited base position it
// holds: its detail turned by the edit at its foot (every level's normal at a point turns by
// that same turn, so turning the levels' sum is turning each band, to rounding). Where the
// edit did not turn it, its bands are added one by one along the levels' normals (normals[l],
// l < upto), as the unedited pass adds them: a local edit leaves the rest bit for bit as it was.
inline void edited_point(const MultiscaleModel& model, const Eigen::MatrixXd& gains,
                         const std::vector<const Points*>& normals, const Points& detail, const Mat3& turn,
                         Eigen::Index i, Points& p) {
  if (!not_turned(turn)) {
    p.row(i) += (turn * detail.row(i).transpose()).transpose();
    return;
  }
  for (std::size_t l = 0; l < normals.size(); ++l)
    p.row(i) += band_offset(model, gains, static_cast<int>(l), i) * normals[l]->row(i);
}

// An editing session's edited call with the gains of its last one (whose level normals it
// reads) and a base that changed at few points since then: only what those changes reach is
// done again, and the rest is the last result, so the points are bit for bit what the whole
// pass gives. A ring is measured again where one of its points moved or its level-0 cluster
// turned otherwise; a point is rebuilt where it, its foot, or its foot's turn changed (nothing
// else enters its bands or its hang). Returns false, having changed nothing, where more than a
// quarter of the base moved (or of every 64th point, which is seen first): the whole pass is
// then as quick.
// edited: the edited base; the rebuilt points are written over the last result (the others
// are the last result already), and the workspace's detail is that of these gains.
bool rebuild_since_last_edit(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points& edited,
                             const std::vector<Mat3>& clusters, const std::vector<const Points*>& normals,
                             ReconstructionWorkspace& ws, EditRotationReport& report) {
  LastEdit& last = ws.last;
  Points& p = last.result;
  const Eigen::Index n = edited.rows();
  const std::size_t count = static_cast<std::size_t>(n);
  auto moved_since = [&](Eigen::Index r) {
    const double a[3] = {edited(r, 0), edited(r, 1), edited(r, 2)}, was[3] = {last.base(r, 0), last.base(r, 1), last.base(r, 2)};
    return std::memcmp(a, was, sizeof a) != 0;
  };
  // A base moved everywhere (a deform, a lattice) is told by a sample, before the whole diff.
  constexpr Eigen::Index sample_step = 64;
  Eigen::Index sampled = 0, sampled_moved = 0;
  for (Eigen::Index r = 0; r < n; r += sample_step, ++sampled) sampled_moved += moved_since(r) ? 1 : 0;
  if (sampled_moved > sampled / 4) return false;
  std::vector<unsigned char> moved(count, 0);
  std::atomic<std::size_t> how_many{0};
  parallel_for(count, [&](std::size_t b, std::size_t e) {
    std::size_t local = 0;
    for (std::size_t i = b; i < e; ++i) {
      if (moved_since(static_cast<Eigen::Index>(i))) { moved[i] = 1; ++local; }
    }
    how_many += local;
  }, {}, 16384);
  if (how_many.load() > count / 4) return false;
  const EditSupport& edit = *ws.edit;
  const IndexList& labels = model.support[0].labels;
  std::vector<unsigned char> cluster_turned(clusters.size(), 0);
  for (std::size_t c = 0; c < clusters.size(); ++c) cluster_turned[c] = !same_bits(clusters[c], last.clusters[c]);
  // The rings to measure again.
  const std::size_t ring = static_cast<std::size_t>(edit.ring_size);
  constexpr std::size_t chunk = 16384;
  std::vector<IndexList> found((count + chunk - 1) / chunk);
  parallel_for(count, [&](std::size_t b, std::size_t e) {
    IndexList& out = found[b / chunk];
    for (std::size_t j = b; j < e; ++j) {
      bool dirty = cluster_turned[static_cast<std::size_t>(labels[j])] != 0;
      const Index* r = edit.rings.data() + j * ring;
      for (std::size_t m = 0; m < ring && !dirty; ++m) dirty = moved[static_cast<std::size_t>(r[m])] != 0;
      if (dirty) out.push_back(static_cast<Index>(j));
    }
  }, {}, chunk);
  IndexList which;
  for (IndexList& part : found) which.insert(which.end(), part.begin(), part.end());
  std::vector<unsigned char> turned_again(count, 0);
  edit_rotations_of(which, model.base, edited, edit.rings, edit.ring_size, clusters, labels, edit.planes, ws.rotation,
                    last.kinds, turned_again);
  // The points to rebuild.
  parallel_for(count, [&](std::size_t b, std::size_t e) {
    for (std::size_t ii = b; ii < e; ++ii) {
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const std::size_t f = static_cast<std::size_t>(edit.feet[ii]);
      if (!moved[ii] && !moved[f] && !turned_again[f]) continue;
      const Mat3& turn = ws.rotation[f];
      p.row(i) = edited.row(i);
      edited_point(model, gains, normals, ws.detail, turn, i, p);
      HangFromFoot hang;
      if (foot_shift(i, static_cast<Index>(f), model.base, edited, turn, hang)) turn_towards_foot(hang, p, nullptr);
    }
  }, {}, 4096);
  report = count_ring_kinds(last.kinds);
  return true;
}

}  // namespace

EditRotationReport reconstruct_levels_in_place(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points& p,
                                               bool edited, Reconstruction* kept, int upto,
                                               const ProgressStage& all, ReconstructionWorkspace& ws,
                                               bool keep_normals) {
  const int k = model.bands();
  if (upto < 0 || upto > k) upto = k;
  EditRotationReport report;
  // An edited base: each point's turn, and the levels of the stored base built beside the
  // edited ones. Their normals, turned, are the edited levels' normals; with nothing edited
  // every turn is exactly the identity and the result is bit for bit the unedited one.
  const bool turned = edited && upto > 0;
  // The parts the edit mirrors are built mirrored once more, a proper edit of the stored base,
  // and mirrored back on the way out (mirrored_edit.h); their clusters' turns are then found again.
  std::vector<Mat3> clusters;
  std::vector<unsigned char> mirrored;
  if (turned) {
    std::vector<signed char> orientation;
    clusters = transported_rotations(model.base, p, model.support[0], &orientation);
    mirrored = mirrored_points(model.base, p, model.support, model.parts, orientation);
    if (!mirrored.empty()) {
      reflect_rows(p, mirrored);
      clusters = transported_rotations(model.base, p, model.support[0]);
    }
  }
  Points& fitted = turned ? ws.unedited : p;  // the level each level's normals are fitted to
  // Normals fitted once for these gains are reused (they do not depend on the edit): kept
  // between calls by a Reconstructor, or handed over by the unedited pass before this one.
  // An unedited pass asked for its normals (keep_normals) leaves them in the same place.
  // At unit gains they may also come shared, found once for the model (KeptEdit).
  const bool cache = (turned && ws.kept) || (!edited && keep_normals);
  const bool unit_gains = all_unit(gains);
  const std::vector<Points>* shared = turned && unit_gains && ws.unit_normals ? ws.unit_normals.get() : nullptr;
  const std::vector<Points>* orient = unit_gains ? nullptr : ws.unit_reference.get();
  const bool cached = shared || (turned && ws.unedited_normals.size() >= static_cast<std::size_t>(upto) &&
                                 ws.unedited_gains.rows() == gains.rows() && ws.unedited_gains.cols() == gains.cols() &&
                                 (ws.unedited_gains.array() == gains.array()).all());
  const std::vector<Points>& cached_normals = shared ? *shared : ws.unedited_normals;
  // An editing session remembers its last edited call (LastEdit), valid again only once this
  // one is done: a call that fails or is cancelled on the way leaves none behind.
  const bool remember = turned && ws.kept && !kept && upto == k;
  // Each point's detail before the edit's turn (ReconstructionWorkspace::detail): summed up
  // front where every level's normals are at hand, and kept between calls by a Reconstructor
  // for its gains; else summed as the levels are built. The same sums in the same order
  // either way, so every path gives the same points.
  const bool summed_first = turned && cached && !kept;  // the level loop then adds no band
  const bool detail_kept = remember && cached && ws.detail.rows() == p.rows() && same_gains(ws.detail_gains, gains);
  const bool detail_first = summed_first && !detail_kept;
  std::vector<const Points*> levels_normals;  // where they are all at hand: normals[l], l < upto
  if (turned && cached) {
    levels_normals.push_back(&model.base_normals);
    for (int l = 1; l < upto; ++l) levels_normals.push_back(&cached_normals[static_cast<std::size_t>(l)]);
  }
  if (turned && !detail_kept) {
    ws.detail_gains.resize(0, 0);  // valid again only once every level is in
    ws.detail.setZero(p.rows(), 3);
  }
  if (detail_first) {
    for (int l = 0; l < upto; ++l) add_level_detail(model, gains, l, *levels_normals[static_cast<std::size_t>(l)], ws.detail, nullptr);
    if (remember) ws.detail_gains = gains;
  }
  const bool since_last = remember && cached && ws.last.valid && ws.last.base.rows() == p.rows() &&
                          same_gains(ws.last.gains, gains);
  if (remember) {
    if (since_last) {
      const ProgressStage stage = all.sub(0.0, 1.0);
      stage.report(0.0);  // a callback may cancel here too
      bool rebuilt = false;
      try {
        rebuilt = rebuild_since_last_edit(model, gains, p, clusters, levels_normals, ws, report);
      } catch (...) {
        ws.last.valid = false;  // its result, turns and kinds may be half updated
        throw;
      }
      if (rebuilt) {
        ws.last.base = p;  // copied into the storage it has
        p = ws.last.result;
        ws.last.clusters = std::move(clusters);
        reflect_rows(p, mirrored);
        stage.report(1.0);
        return report;
      }
    }
    ws.last.valid = false;
    ws.last.base = p;  // the edited base this call was given, into the storage the last one had
  }
  if (turned) {
    edit_rotations(model.base, p, ws.edit->rings, ws.edit->ring_size, clusters, model.support[0].labels,
                   &ws.edit->planes, ws.rotation, &report, remember ? &ws.last.kinds : nullptr);
  }
  // Points whose detail stands on a foot other than their own base position: how far the edit
  // moves the foot, less how far it moves their own base position, less the turn of the span
  // between the two. Hanging the point from its foot rigidly would add exactly that.
  std::vector<HangFromFoot> hang;
  if (turned) hang = hang_from_feet(model.base, p, ws.edit->feet, ws.rotation);
  if (turned && !cached) ws.unedited = model.base;
  if (cache && !cached) {
    ws.unedited_gains.resize(0, 0);  // valid again only once every level is in
    ws.unedited_normals.resize(static_cast<std::size_t>(k));
  }
  if (turned && !cached && !ws.kept) std::vector<Points>().swap(ws.unedited_normals);  // other gains: of no use
  if (kept) kept->levels.push_back(p);
  // Each edited point's turn at its foot (read once per point below).
  auto turn_of = [&](std::size_t i) -> const Mat3& { return ws.rotation[static_cast<std::size_t>(ws.edit->feet[i])]; };
  // Level l's normals orient level l + 1's. They are computed into whichever of two buffers
  // the level before does not hold, so each level reuses the storage of the one before it.
  // The stored base's normals are the stored ones, bit for bit (decompose made them with the
  // same function and oriented them), so level 0 reads them in place.
  const Points* previous = &model.base_normals;
  for (int l = 0; l < upto; ++l) {
    const LevelSupport& s = model.support[l];
    const ProgressStage stage = all.sub(double(l) / upto, double(l + 1) / upto);
    if (summed_first) {
      stage.report(1.0);
      continue;
    }
    const Points* normals = previous;
    if (l > 0 && cached) {
      normals = &cached_normals[static_cast<std::size_t>(l)];
    } else if (l > 0) {
      Points& into = cache ? ws.unedited_normals[static_cast<std::size_t>(l)]
                           : previous == &ws.normals[0] ? ws.normals[1] : ws.normals[0];
      const LabelGroups* groups = static_cast<std::size_t>(l) < ws.groups.size() ? &ws.groups[l] : nullptr;
      // The side of the unit gains' normal and the level's below together: near unit gains the
      // first decides, where the level's below stands at right angles to it; near gain 0, where
      // the level is fitted to nearly the level below's shape, the second. At unit gains the
      // side is the one the level below gives, bit for bit (the two agree there).
      const std::size_t at = static_cast<std::size_t>(l);
      const bool both = orient && at < orient->size() && (*orient)[at].rows() == fitted.rows();
      if (both) ws.reference = (*orient)[at] + *previous;
      level_normals(fitted, s, both ? ws.reference : *previous, stage, into, groups,
                    ws.kept ? &ws.centroids : nullptr);
      if (both) ease_side_flips(into, ws.reference);
      normals = &into;
    }
    const Points& nrm = *normals;
    if (turned) {
      // The detail, and the bands of the points the edit did not turn, one by one (edited_point).
      add_level_detail(model, gains, l, nrm, ws.detail, cached ? nullptr : &ws.unedited);
      parallel_for(static_cast<std::size_t>(p.rows()), [&](std::size_t b, std::size_t e) {
        for (std::size_t ii = b; ii < e; ++ii) {
          if (!not_turned(turn_of(ii))) continue;
          const Eigen::Index i = static_cast<Eigen::Index>(ii);
          p.row(i) += band_offset(model, gains, l, i) * nrm.row(i);
        }
      }, {}, 4096);
      if (kept) {  // this level, and its normals as the edit turns them
        Points level(p.rows(), 3), applied(p.rows(), 3);
        parallel_for(static_cast<std::size_t>(p.rows()), [&](std::size_t b, std::size_t e) {
          for (std::size_t ii = b; ii < e; ++ii) {
            const Eigen::Index i = static_cast<Eigen::Index>(ii);
            const Mat3& turn = turn_of(ii);
            level.row(i) = not_turned(turn) ? Eigen::RowVector3d(p.row(i))
                                            : Eigen::RowVector3d(p.row(i) + (turn * ws.detail.row(i).transpose()).transpose());
            applied.row(i) = (turn * nrm.row(i).transpose()).transpose();
          }
        }, {}, 4096);
        kept->levels.push_back(std::move(level));
        kept->normals.push_back(std::move(applied));
      }
    } else {
      parallel_for(static_cast<std::size_t>(p.rows()), [&](std::size_t b, std::size_t e) {
        for (std::size_t ii = b; ii < e; ++ii) {
          const Eigen::Index i = static_cast<Eigen::Index>(ii);
          p.row(i) += band_offset(model, gains, l, i) * nrm.row(i);
        }
      }, {}, 4096);
      if (kept) { kept->levels.push_back(p); kept->normals.push_back(nrm); }
    }
    previous = normals;
    stage.report(1.0);
  }
  if (turned && !cached && remember) ws.detail_gains = gains;  // summed as the levels were built
  if (turned) {
    // The turned points (their rows still hold their edited base positions), and, where the
    // loop above added no band, the points not turned too.
    parallel_for(static_cast<std::size_t>(p.rows()), [&](std::size_t b, std::size_t e) {
      for (std::size_t ii = b; ii < e; ++ii) {
        const Mat3& turn = turn_of(ii);
        if (!summed_first && not_turned(turn)) continue;
        edited_point(model, gains, levels_normals, ws.detail, turn, static_cast<Eigen::Index>(ii), p);
      }
    }, {}, 4096);
  }
  if (!hang.empty()) turn_towards_feet(hang, p, kept);
  if (cache && !cached && upto == k) ws.unedited_gains = gains;
  if (remember) {
    ws.last.result = p;
    ws.last.valid = true;
    ws.last.gains = gains;
    ws.last.clusters = std::move(clusters);
  }
  if (turned) Points().swap(ws.unedited);  // only fitting the normals needs it
  reflect_rows(p, mirrored);
  if (kept && !mirrored.empty()) {
    for (Points& level : kept->levels) reflect_rows(level, mirrored);
    for (Points& n : kept->normals) reflect_rows(n, mirrored);
  }
  return report;
}

EditSupport edit_support(const Points& base, const IndexList& parts, const Points& base_normals, const Points& finest) {
  EditSupport edit;
  edit.rings = edit_rings(base, parts);
  edit.ring_size = ring_size_for(base.rows(), edit_ring_size);
  edit.planes = ring_planes(base, edit.rings, edit.ring_size);
  edit.feet = base_feet(base, base_normals, finest, edit.rings, edit.ring_size);
  return edit;
}

bool all_unit(const Eigen::MatrixXd& gains) { return (gains.array() == 1.0).all(); }

Points unit_pass(const MultiscaleModel& model, const ProgressStage& progress, ReconstructionWorkspace& workspace) {
  const Eigen::MatrixXd ones = Eigen::MatrixXd::Ones(model.bands(), 1);
  Points finest = model.base;
  reconstruct_levels_in_place(model, ones, finest, false, nullptr, -1, progress, workspace, true);
  return finest;
}

std::shared_ptr<const std::vector<Points>> unit_level_normals(const MultiscaleModel& model,
                                                              const ProgressStage& progress) {
  ReconstructionWorkspace workspace;
  unit_pass(model, progress, workspace);
  return std::make_shared<const std::vector<Points>>(std::move(workspace.unedited_normals));
}

KeptEdit find_kept_edit(const MultiscaleModel& model, const ProgressStage& progress) {
  // The feet need the unedited finest level. The pass that makes it fits the stored base's
  // level normals at unit gains, which are the ones an edited pass fits at those gains.
  ReconstructionWorkspace workspace;
  const Points finest = unit_pass(model, progress.sub(0.0, 0.5), workspace);
  KeptEdit kept;
  kept.support = std::make_shared<const EditSupport>(edit_support(model.base, model.parts, model.base_normals, finest));
  kept.unit_normals = std::make_shared<const std::vector<Points>>(std::move(workspace.unedited_normals));
  progress.report(1.0);
  return kept;
}

std::shared_ptr<const std::vector<Points>> EditMemo::unit_reference() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return unit_reference_;
}

void EditMemo::keep_unit_reference(std::shared_ptr<const std::vector<Points>> found) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!unit_reference_) unit_reference_ = std::move(found);
}

std::shared_ptr<const KeptEdit> EditMemo::get() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return kept_;
}

void EditMemo::keep(std::shared_ptr<const KeptEdit> found) {
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!kept_) kept_ = std::move(found);
}

namespace {

Reconstruction reconstruct_levels(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points p, bool edited,
                                  bool keep_levels, int upto, const ProgressCallback* progress, EditMemo* memo) {
  const ProgressStage all{progress, 0.0, 1.0};
  // A base handed back unchanged turns no detail: the unedited path gives the same points bit
  // for bit, without finding the edit support.
  if (edited && p.rows() == model.base.rows() && p == model.base) edited = false;
  ReconstructionWorkspace workspace;
  // An edit turns detail only where there is detail to turn. Finding what it needs costs about
  // two passes over the levels (the unedited one and the edit support): two thirds of the
  // progress, where a memo does not have it yet.
  const bool turns = edited && upto != 0 && model.bands() > 0;
  bool found_here = false;
  if (turns) {
    std::shared_ptr<const KeptEdit> kept = memo ? memo->get() : nullptr;
    // A memo found for another model would be read out of its bounds (a model of the same
    // size cannot be told apart: reconstruction.h).
    if (kept && kept->support->feet.size() != static_cast<std::size_t>(model.base.rows()))
      throw std::invalid_argument("this EditMemo was found for a model of " +
                                  std::to_string(kept->support->feet.size()) + " points, not this one's " +
                                  std::to_string(model.base.rows()));
    if (!kept) {
      // The normals at unit gains: read at those gains, and orienting every other gains'.
      kept = std::make_shared<const KeptEdit>(find_kept_edit(model, all.sub(0.0, 2.0 / 3.0)));
      if (memo) memo->keep(kept);
      found_here = true;
    }
    workspace.edit = kept->support;
    workspace.unit_normals = kept->unit_normals;
  }
  double done = found_here ? 2.0 / 3.0 : 0.0;
  // Gains other than 1 orient each level's normals by those at unit gains
  // (ReconstructionWorkspace::unit_reference): found by one more unedited pass, unless kept.
  if (!all_unit(gains) && model.bands() > 1 && upto != 0) {
    std::shared_ptr<const std::vector<Points>> reference = workspace.unit_normals;
    if (!reference && memo) reference = memo->unit_reference();
    if (!reference) {
      reference = unit_level_normals(model, all.sub(done, (done + 1.0) / 2.0));
      done = (done + 1.0) / 2.0;
    }
    if (memo) memo->keep_unit_reference(reference);
    workspace.unit_reference = std::move(reference);
  }
  Reconstruction out;
  const ProgressStage rest = all.sub(done, 1.0);
  out.edit = reconstruct_levels_in_place(model, gains, p, edited, keep_levels ? &out : nullptr, upto, rest,
                                         workspace);
  out.positions = std::move(p);
  return out;
}

}  // namespace

Reconstruction reconstruct(const MultiscaleModel& model, const Eigen::MatrixXd& gains, const Points* base,
                           bool keep_levels, int upto, const ProgressCallback* progress, EditMemo* memo) {
  if (base) return reconstruct_from_base(model, gains, *base, keep_levels, upto, progress, memo);
  check_gains(gains, model.bands(), model.base.rows());
  return reconstruct_levels(model, gains, model.base, false, keep_levels, upto, progress, memo);
}

Reconstruction reconstruct_from_base(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points base,
                                     bool keep_levels, int upto, const ProgressCallback* progress, EditMemo* memo) {
  check_gains(gains, model.bands(), model.base.rows());
  check_base(base, model.base.rows(), Vec3::Zero());
  return reconstruct_levels(model, gains, std::move(base), true, keep_levels, upto, progress, memo);
}

}  // namespace pointscale
