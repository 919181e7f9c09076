// The SAH cost of a finished tree, recomputed from scratch (independent of any builder): the
// oracle the builders' reported cost is checked against, and the "SAH" column of reports.
#pragma once

#include <cstdint>
#include <limits>
#include <span>

#include "bvh/bvh.h"

namespace ptc::bvh {

/// cost = sum over inner nodes n of traversal * A(n) / A(root)
///      + sum over leaves l of intersection * W(l) * A(l) / A(root),
/// A(n) = surface area of the union of the primitive boxes below n (recomputed from `boxes`,
/// not read from the nodes), W(l) = sum of the weights of l's primitives (weights empty: 1 each).
/// When A(root) = 0 (every box a point or a segment) each ratio A(n) / A(root) is taken as 1.
/// Equals the recursive form at SahCostModel. Empty tree: 0. Precondition: the tree's
/// structure is valid (see validate()); boxes.size() = primitive count.
[[nodiscard]] double sah_cost(const Bvh& bvh, std::span<const Box3f> boxes, std::span<const std::uint32_t> weights,
                              const SahCostModel& model);

/// The SAH cost of a wide tree as its nodes hold it (boxes read from the nodes, unlike
/// sah_cost): traversal * (A(root) + sum of the inner slots' A) + intersection * (sum of the
/// leaf slots' count * A), over A(root), `root` the box of the whole tree. What a refitted tree
/// is compared with the tree it had right after its build (SceneConfig::refit_growth). An empty
/// tree: 0. A(root) = 0 (no ratio to take): NaN, which no comparison passes, so a tree built
/// over such a frame is never kept (counting each ratio as 1, as sah_cost does, would let
/// every later refit pass, since no area ratio exceeds 1).
template <class Nodes>
[[nodiscard]] double wide_sah_cost(const Nodes& nodes, const Box3f& root, const SahCostModel& model) {
  if (nodes.empty()) return 0.0;
  const double ar = root.surface_area();
  if (!(ar > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  double inner = ar, leaf = 0.0;
  for (const auto& n : nodes)
    for (int k = 0; k < n.kWidth; ++k) {
      if (n.is_empty(k)) continue;
      const double a = n.child_box(k).surface_area();
      if (n.is_leaf(k)) leaf += n.count[k] * a;
      else inner += a;
    }
  return (model.traversal * inner + model.intersection * leaf) / ar;
}

}  // namespace ptc::bvh
