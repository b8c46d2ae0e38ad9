// Which anchors the level aligner moves next, under AlignPolicy::wake_list (align_level.h).
#pragma once
#include <algorithm>
#include <numeric>
#include <vector>

#include "pointscale/level_support.h"

namespace pointscale {

// The anchors to move next (AlignPolicy::wake_list): only anchors that moved, or whose
// neighbours moved, can move again. Flagged in `active` and listed in `woken`, so that an
// iteration costs in proportion to them.
class WakeList {
 public:
  explicit WakeList(Index clusters) : active_(static_cast<std::size_t>(clusters), 0) { wake_all(); }

  void wake_all() {
    woken_.resize(active_.size());
    std::iota(woken_.begin(), woken_.end(), 0);
    std::fill(active_.begin(), active_.end(), 1);
  }

  // Lists the woken anchors that are not frozen, in order, into todo; once none is left, every
  // anchor that is not frozen, for one sweep that confirms they have settled. Returns whether
  // this is that sweep.
  bool next(const std::vector<unsigned char>& frozen, std::vector<Index>& todo) {
    std::sort(woken_.begin(), woken_.end());
    todo.clear();
    for (const Index c : woken_) if (!frozen[c]) todo.push_back(c);
    const bool sweep = todo.empty();
    if (sweep)
      for (Index c = 0; c < static_cast<Index>(active_.size()); ++c) if (!frozen[c]) todo.push_back(c);
    return sweep;
  }

  void clear() {
    for (const Index c : woken_) active_[c] = 0;
    woken_.clear();
  }

  // Wakes cluster c's neighbourhood (itself included).
  void wake_neighbourhood(const LevelSupport& support, Index c) {
    const int k = support.neighbors;
    const Index* nb = support.neighborhoods.data() + static_cast<std::size_t>(c) * k;
    for (int j = 0; j < k; ++j)
      if (!active_[nb[j]]) { active_[nb[j]] = 1; woken_.push_back(nb[j]); }
  }

  const std::vector<Index>& woken() const { return woken_; }

 private:
  std::vector<unsigned char> active_;
  std::vector<Index> woken_;
};

}  // namespace pointscale
