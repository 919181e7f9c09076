#include "bvh/refit.h"

#include "bvh/sah_cost.h"

namespace ptc::bvh {

void refit(Bvh& bvh, std::span<const Box3f> boxes, std::span<const std::uint32_t> weights, const SahCostModel* model) {
  for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
    BvhNode& nd = bvh.nodes[i];
    Box3f b;
    if (nd.is_leaf()) {
      for (std::uint32_t k = nd.index; k < nd.index + nd.count; ++k) b.extend(boxes[bvh.prim_order[k]]);
    } else {
      b = bvh.nodes[i + 1].bounds;
      b.extend(bvh.nodes[nd.index].bounds);
    }
    nd.bounds = b;
  }
  if (model) bvh.cost = sah_cost(bvh, boxes, weights, *model);
}

}  // namespace ptc::bvh
