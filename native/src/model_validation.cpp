// validate(const MultiscaleModel&) (validation.h): the structure a model must have for
// reconstruction to read nothing out of bounds and give nothing but finite points. A model
// that decompose made has it; one rebuilt from saved arrays may not.
#include <stdexcept>
#include <string>

#include "pointscale/validation.h"

namespace pointscale {

namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("not a valid decomposition: " + what);
}

// Every index in [0, count).
bool in_range(const IndexList& indices, Eigen::Index count) {
  for (Index v : indices)
    if (v < 0 || v >= count) return false;
  return true;
}

void validate_level(const LevelSupport& sup, Eigen::Index n, int l) {
  const std::string s = std::to_string(l);
  const auto clusters = static_cast<std::size_t>(sup.clusters);
  require(sup.clusters >= 1 && sup.neighbors >= 1, "level " + s + " has no clusters or no neighbours");
  require(sup.neighborhoods.size() == clusters * static_cast<std::size_t>(sup.neighbors),
          "level " + s + " has neighbourhoods of another size than clusters by neighbours");
  require(static_cast<std::size_t>(sup.h.size()) == clusters, "level " + s + " has one kernel width per cluster");
  require(sup.h.allFinite() && (sup.h.array() > 0.0).all(), "kernel widths must be finite and > 0 at level " + s);
  require(sup.anchors.size() == clusters, "anchors must be (clusters,) at level " + s);
  require(in_range(sup.anchors, n), "anchor out of range at level " + s);
  require(sup.frames.size() == 2 * clusters, "frames must be (clusters, 2) at level " + s);
  require(in_range(sup.frames, sup.clusters), "frame out of range at level " + s);
  require(sup.labels.size() == static_cast<std::size_t>(n), "labels must be (k, n)");
  require(in_range(sup.labels, sup.clusters), "label out of range at level " + s);
  require(in_range(sup.neighborhoods, sup.clusters), "neighbourhood out of range at level " + s);
  // Each cluster's anchor is one of its members, so no cluster is empty.
  for (Index c = 0; c < sup.clusters; ++c)
    require(sup.labels[static_cast<std::size_t>(sup.anchors[static_cast<std::size_t>(c)])] == c,
            "the anchor of cluster " + std::to_string(c) + " is not in that cluster at level " + s);
  require(sup.local.rows() == n, "local coordinates must be (n, 3) at level " + s);
  require(sup.local.allFinite(), "local coordinates hold NaN or infinite values at level " + s);
}

}  // namespace

void validate(const MultiscaleModel& m) {
  const Eigen::Index n = m.base.rows();
  require(n >= 1, "base has no points");
  require(m.base.allFinite(), "base holds NaN or infinite values");
  require(m.details.cols() == n, "details must be (k, n)");
  require(m.details.rows() >= 1, "details has no bands (at least 1 is needed)");
  require(m.details.rows() <= 1024, "details has more than 1024 bands");
  require(m.details.allFinite(), "details holds NaN or infinite values");
  require(m.base_normals.rows() == n, "base_normals must have the " + std::to_string(n) + " rows of base, got " +
                                          std::to_string(m.base_normals.rows()));
  require(m.base_normals.allFinite(), "base_normals holds NaN or infinite values");
  require(m.support.size() == static_cast<std::size_t>(m.bands()), "the model has one support per band");
  for (int l = 0; l < m.bands(); ++l) validate_level(m.support[static_cast<std::size_t>(l)], n, l);
  require(m.parts.empty() || m.parts.size() == static_cast<std::size_t>(n), "parts must be (n,)");
  require(in_range(m.parts, n), "part label out of range");
}

}  // namespace pointscale
