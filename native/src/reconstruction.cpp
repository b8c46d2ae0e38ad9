#include "pointscale/reconstruction.h"
#include "pointscale/validation.h"

#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "pointscale/parallel.h"
#include "pointscale/detail/level_normals.h"
#include "pointscale/detail/transported_rotations.h"
#include "pointscale/detail/reconstruct_levels.h"

namespace pointscale {

namespace {

struct HangFromFoot {
  Eigen::Index point;
  Vec3 base;   // the point's edited base position
  Vec3 shift;  // what hanging it from its foot rigidly would add
};

std::vector<HangFromFoot> hang_from_feet(const Points& original, const Points& edited, const IndexList& feet,
                                         const std::vector<Mat3>& rotation) {
  constexpr std::size_t chunk = 16384;
  std::vector<std::vector<HangFromFoot>> found((feet.size() + chunk - 1) / chunk);
  parallel_for(feet.size(), [&](std::size_t b, std::size_t e) {
    std::vector<HangFromFoot>& out = found[b / chunk];
    for (std::size_t ii = b; ii < e; ++ii) {
      const Index f = feet[ii];
      if (f == static_cast<Index>(ii)) continue;
      const Eigen::Index i = static_cast<Eigen::Index>(ii);
      const Vec3 base = original.row(i).transpose(), base_edited = edited.row(i).transpose();
      const Vec3 foot = original.row(f).transpose(), foot_edited = edited.row(f).transpose();
      const Mat3& turn = rotation[static_cast<std::size_t>(f)];
      const Vec3 span = base - foot;
      const Vec3 shift = (foot_edited - foot) - (base_edited - base) + (turn * span - span);
      // Nothing moved here: the identity, exactly, so a local edit leaves the rest as it was.
      if (shift.x() == 0.0 && shift.y() == 0.0 && shift.z() == 0.0) continue;
      out.push_back({i, base_edited, shift});
    }
  }, {}, chunk);
  std::vector<HangFromFoot> all;
  for (std::vector<HangFromFoot>& part : found) all.insert(all.end(), part.begin(), part.end());
  return all;
}

// Turns each listed point's offset from its base position towards where hanging it from its
// foot puts it, keeping its length, and every kept level and normal of it by the same turn.
// A steep edit stretches the base along its slope, and the base positions of a tall feature's
// top lie away from its foot: offsets hung from those positions would lean with the stretch.
void turn_towards_feet(const std::vector<HangFromFoot>& hang, Points& p, Reconstruction* kept) {
  parallel_for(hang.size(), [&](std::size_t b, std::size_t e) {
    for (std::size_t j = b; j < e; ++j) {
      const HangFromFoot& h = hang[j];
      const Vec3 w = p.row(h.point).transpose() - h.base;
      const Vec3 v = w + h.shift;
      if (!(w.norm() > 0.0) || !(v.norm() > 0.0)) continue;
      const Mat3 q = Eigen::Quaterniond::FromTwoVectors(w, v).toRotationMatrix();
      p.row(h.point) = (h.base + q * w).transpose();
      if (!kept) continue;
      for (std::size_t l = 1; l < kept->levels.size(); ++l) {
        Points& level = kept->levels[l];
        level.row(h.point) = (h.base + q * (level.row(h.point).transpose() - h.base)).transpose();
      }
      for (Points& n : kept->normals) n.row(h.point) = (q * n.row(h.point).transpose()).transpose();
    }
  }, {}, 4096);
}

}  // namespace

EditRotationReport reconstruct_levels_in_place(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points& p,
                                               bool edited, Reconstruction* kept, int upto,
                                               const ProgressStage& all, ReconstructionWorkspace& ws,
                                               bool keep_normals) {
  const int k = model.bands();
  if (upto < 0 || upto > k) upto = k;
  const bool per_point = gains.cols() > 1;
  EditRotationReport report;
  // An edited base: each point's turn, and the levels of the stored base built beside the
  // edited ones. Their normals, turned, are the edited levels' normals; with nothing edited
  // every turn is exactly the identity and the result is bit for bit the unedited one.
  const bool turned = edited && upto > 0;
  if (turned) {
    const std::vector<Mat3> clusters = transported_rotations(model.base, p, model.support[0]);
    edit_rotations(model.base, p, ws.edit->rings, ws.edit->ring_size, clusters, model.support[0].labels,
                   &ws.edit->planes, ws.rotation, &report);
  }
  // Points whose detail stands on a foot other than their own base position: how far the edit
  // moves the foot, less how far it moves their own base position, less the turn of the span
  // between the two. Hanging the point from its foot rigidly would add exactly that.
  std::vector<HangFromFoot> hang;
  if (turned) hang = hang_from_feet(model.base, p, ws.edit->feet, ws.rotation);
  Points& fitted = turned ? ws.unedited : p;  // the level each level's normals are fitted to
  // Normals fitted once for these gains are reused (they do not depend on the edit): kept
  // between calls by a Reconstructor, or handed over by the unedited pass before this one.
  // An unedited pass asked for its normals (keep_normals) leaves them in the same place.
  // At unit gains they may also come shared, found once for the model (KeptEdit).
  const bool cache = (turned && ws.kept) || (!edited && keep_normals);
  const bool unit_gains = gains.cols() == 1 && (gains.array() == 1.0).all();
  const std::vector<Points>* shared = turned && unit_gains && ws.unit_normals ? ws.unit_normals.get() : nullptr;
  const bool cached = shared || (turned && ws.unedited_normals.size() >= static_cast<std::size_t>(upto) &&
                                 ws.unedited_gains.rows() == gains.rows() && ws.unedited_gains.cols() == gains.cols() &&
                                 (ws.unedited_gains.array() == gains.array()).all());
  const std::vector<Points>& cached_normals = shared ? *shared : ws.unedited_normals;
  if (turned && !cached) ws.unedited = model.base;
  if (cache && !cached) {
    ws.unedited_gains.resize(0, 0);  // valid again only once every level is in
    ws.unedited_normals.resize(static_cast<std::size_t>(k));
  }
  if (turned && !cached && !ws.kept) std::vector<Points>().swap(ws.unedited_normals);  // other gains: of no use
  if (kept) kept->levels.push_back(p);
  // Level l's normals orient level l + 1's. They are computed into whichever of two buffers
  // the level before does not hold, so each level reuses the storage of the one before it.
  // The stored base's normals are the stored ones, bit for bit (decompose made them with the
  // same function and oriented them), so level 0 reads them in place.
  const Points* previous = &model.base_normals;
  for (int l = 0; l < upto; ++l) {
    const LevelSupport& s = model.support[l];
    const ProgressStage stage = all.sub(double(l) / upto, double(l + 1) / upto);
    const Points* normals = previous;
    if (l > 0 && cached) {
      normals = &cached_normals[static_cast<std::size_t>(l)];
    } else if (l > 0) {
      Points& into = cache ? ws.unedited_normals[static_cast<std::size_t>(l)]
                           : previous == &ws.normals[0] ? ws.normals[1] : ws.normals[0];
      const LabelGroups* groups = static_cast<std::size_t>(l) < ws.groups.size() ? &ws.groups[l] : nullptr;
      level_normals(fitted, s, *previous, stage, into, groups, ws.kept ? &ws.centroids : nullptr);
      normals = &into;
    }
    const Points& nrm = *normals;
    Points applied;
    if (kept && turned) applied.resize(p.rows(), 3);
    parallel_for(static_cast<std::size_t>(p.rows()), [&](std::size_t b, std::size_t e) {
      for (std::size_t ii = b; ii < e; ++ii) {
        const Eigen::Index i = static_cast<Eigen::Index>(ii);
        const double g = per_point ? gains(l, i) : gains(l, 0);
        const double offset = g * model.details(l, i);
        if (turned) {
          const Mat3& turn = ws.rotation[static_cast<std::size_t>(ws.edit->feet[ii])];
          const Eigen::RowVector3d n = (turn * nrm.row(i).transpose()).transpose();
          p.row(i) += offset * n;
          if (!cached) ws.unedited.row(i) += offset * nrm.row(i);
          if (kept) applied.row(i) = n;
        } else {
          p.row(i) += offset * nrm.row(i);
        }
      }
    }, {}, 4096);
    if (kept) { kept->levels.push_back(p); kept->normals.push_back(turned ? std::move(applied) : nrm); }
    previous = normals;
    stage.report(1.0);
  }
  if (!hang.empty()) turn_towards_feet(hang, p, kept);
  if (cache && !cached && upto == k) ws.unedited_gains = gains;
  if (turned) Points().swap(ws.unedited);  // only fitting the normals needs it
  return report;
}

EditSupport edit_support(const Points& base, const IndexList& parts, const Points& base_normals, const Points& finest) {
  EditSupport edit;
  edit.rings = base_rings(base, parts, edit_ring_size);
  edit.ring_size = ring_size_for(base.rows(), edit_ring_size);
  edit.planes = ring_planes(base, edit.rings, edit.ring_size);
  edit.feet = base_feet(base, base_normals, finest, edit.rings, edit.ring_size);
  return edit;
}

KeptEdit find_kept_edit(const MultiscaleModel& model, const ProgressStage& progress, bool with_unit_normals) {
  // The feet need the unedited finest level. The pass that makes it fits the stored base's
  // level normals at unit gains, which are the ones an edited pass fits at those gains.
  ReconstructionWorkspace workspace;
  const Eigen::MatrixXd ones = Eigen::MatrixXd::Ones(model.bands(), 1);
  Points finest = model.base;
  reconstruct_levels_in_place(model, ones, finest, false, nullptr, -1, progress.sub(0.0, 0.5), workspace,
                              with_unit_normals);
  KeptEdit kept;
  kept.support = std::make_shared<const EditSupport>(edit_support(model.base, model.parts, model.base_normals, finest));
  if (with_unit_normals)
    kept.unit_normals = std::make_shared<const std::vector<Points>>(std::move(workspace.unedited_normals));
  progress.report(1.0);
  return kept;
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
      // Without a memo, the normals at unit gains are of use to this call only at those gains
      // (at others they cost memory).
      const bool unit_gains = gains.cols() == 1 && (gains.array() == 1.0).all();
      kept = std::make_shared<const KeptEdit>(find_kept_edit(model, all.sub(0.0, 2.0 / 3.0), memo || unit_gains));
      if (memo) memo->keep(kept);
      found_here = true;
    }
    workspace.edit = kept->support;
    workspace.unit_normals = kept->unit_normals;
  }
  Reconstruction out;
  const ProgressStage rest = all.sub(found_here ? 2.0 / 3.0 : 0.0, 1.0);
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
  return reconstruct_levels(model, gains, model.base, false, keep_levels, upto, progress, nullptr);
}

Reconstruction reconstruct_from_base(const MultiscaleModel& model, const Eigen::MatrixXd& gains, Points base,
                                     bool keep_levels, int upto, const ProgressCallback* progress, EditMemo* memo) {
  check_gains(gains, model.bands(), model.base.rows());
  check_base(base, model.base.rows(), Vec3::Zero());
  return reconstruct_levels(model, gains, std::move(base), true, keep_levels, upto, progress, memo);
}

}  // namespace pointscale
