// Where a BVH's SAH cost comes from, primitive by primitive (issue 12: "the cluster's share of
// the cluster BVH's SAH cost"). With the cost of bvh/sah_cost.h,
//   cost = sum_inner traversal A(n) / A(root) + sum_leaves intersection W(l) A(l) / A(root),
// primitive p of leaf l carries its leaf term intersection w_p A(l) / A(root) and, for every inner
// node n above it, the part w_p / W(n) of traversal A(n) / A(root) (the node's cost split over
// its subtree in proportion to weight: a cluster of many triangles pays more of the nodes that
// lead to it). The contributions sum to sah_cost(); share = contribution / cost.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "bvh/bvh.h"

namespace ptc {

struct SahShares {
  std::vector<double> contribution;  ///< per primitive id, summing to `cost`
  std::vector<double> share;         ///< contribution / cost (0 when the cost is 0)
  double cost = 0;
};

/// Same preconditions as bvh::sah_cost (a valid tree over boxes.size() primitives; weights empty
/// or one per primitive). A(root) = 0 counts every area ratio as 1, as sah_cost does.
[[nodiscard]] SahShares sah_shares(const bvh::Bvh& bvh, std::span<const bvh::Box3f> boxes,
                                   std::span<const std::uint32_t> weights, const bvh::SahCostModel& model);

}  // namespace ptc
