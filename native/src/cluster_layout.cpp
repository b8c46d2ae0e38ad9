#include "pointscale/detail/cluster_layout.h"

namespace pointscale {

LabelGroups cluster_layout(const IndexList& labels, Index clusters, const Index* visit) {
  return group_by_label(labels.data(), labels.size(), clusters, visit);
}

}  // namespace pointscale
