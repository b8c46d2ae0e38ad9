// Which parts of a model an edited base mirrors (detail/mirrored_edit.h has the rule):
// reconstruction builds such parts mirrored, so that their detail is mirrored with the base.
#pragma once
#include <vector>

#include "pointscale/decomposition.h"

namespace pointscale {

// model   its base, supports and parts
// edited  #P by 3, the edited base in the model's coordinates (the stored base's frame)
// Returns #P flags, 1 for the points of a part the edit mirrors (all 0 when none).
// Throws std::invalid_argument for an edited base of another size, or a model without bands.
std::vector<unsigned char> mirrored_parts(const MultiscaleModel& model, const Points& edited);

}  // namespace pointscale
