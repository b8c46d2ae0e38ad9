// The step policy shared by the two offset aligners, make_offsets_normal (decompose) and
// align_offsets (encode_onto): each anchor moves by a damped step towards its foot on the fine
// point's normal line, halving the step while its move grows (a swing) and regaining it while
// the move shrinks. The two differ in how far they let the step fall and how fast it comes
// back; each keeps its own numbers, so their results are unchanged.
#pragma once
#include <algorithm>

namespace pointscale {

struct DampingPolicy {
  double swing = 1.0;          // a move above swing x the last one counts as a swing
  double floor = 1.0 / 64.0;   // the step never falls below this fraction
  double regain = 1.5;         // factor by which the step grows back
  // true: any move that is no swing regains the step; false: only a move smaller than the last.
  bool regain_unless_swing = true;
};

// The next damping of one anchor. full: its move now; last: its move before; cap: the largest
// damping it may regain (1, or a Newton step).
inline double next_damping(const DampingPolicy& policy, double damping, double full, double last, double cap) {
  if (full > policy.swing * last) return std::max(damping * 0.5, policy.floor);
  if (policy.regain_unless_swing || full < last) return std::min(cap, damping * policy.regain);
  return damping;
}

}  // namespace pointscale
