// The SAH cost of a finished tree, recomputed from scratch (independent of any builder): the
// oracle the builders' reported cost is checked against, and the "SAH" column of reports.
#pragma once

#include <cstdint>
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

}  // namespace ptc::bvh
