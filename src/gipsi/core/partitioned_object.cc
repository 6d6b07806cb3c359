/// @file
/// SplitAlike: whether two split objects can be coupled part to part.

#include "gipsi/core/partitioned_object.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "gipsi/core/sim_object.h"

namespace gipsi {

bool SplitAlike(const SimObject& a, const SimObject& b) {
  const auto* pa = dynamic_cast<const PartitionedObject*>(&a);
  const auto* pb = dynamic_cast<const PartitionedObject*>(&b);
  // Whether an object is split is decided alike on every process (by its type and the
  // scene), so this answer needs no agreement.
  if (pa == nullptr || pb == nullptr) return false;
  const Points& xa = pa->local_part().domain().nodes;
  const Points& xb = pb->local_part().domain().nodes;
  const std::span<const int> na = pa->whole_nodes_of_part(), nb = pb->whole_nodes_of_part();
  const std::span<const int> ta = pa->whole_tets_of_part(), tb = pb->whole_tets_of_part();
  const bool alike = pa->num_owned_nodes() == pb->num_owned_nodes() && std::ranges::equal(na, nb) &&
                     std::ranges::equal(ta, tb) && xa.cols() == xb.cols() && xa == xb;
  double verdict[1] = {alike ? 1.0 : 0.0};
  pa->CombineAcross(verdict, PartitionedObject::Combine::kMin);
  return verdict[0] == 1.0;
}

std::optional<NonFiniteItem> FirstNonFinite(const Eigen::Ref<const Eigen::MatrixXd>& values,
                                            FieldLocation location,
                                            const PartitionedObject* split) {
  std::optional<NonFiniteItem> first;
  for (Index i = 0; i < values.cols() && !first; ++i)
    for (Index k = 0; k < values.rows(); ++k)
      if (!std::isfinite(values(k, i))) {
        first = NonFiniteItem{i, values(k, i)};
        break;
      }
  if (split == nullptr) return first;
  double agreed[1] = {std::numeric_limits<double>::infinity()};
  if (first) {
    const std::span<const int> whole = location == FieldLocation::kNode
                                           ? split->whole_nodes_of_part()
                                           : split->whole_tets_of_part();
    agreed[0] = whole[static_cast<std::size_t>(first->item)];
  }
  split->CombineAcross(agreed, PartitionedObject::Combine::kMin);
  if (!std::isfinite(agreed[0])) return std::nullopt;
  return NonFiniteItem{static_cast<Index>(agreed[0]), std::numeric_limits<double>::quiet_NaN()};
}

}  // namespace gipsi
