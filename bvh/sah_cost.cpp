#include "bvh/sah_cost.h"

#include <algorithm>
#include <vector>

namespace ptc::bvh {

namespace {

// Box and weight of the subtree at `node`, recomputed from the primitive boxes; adds the
// subtree's terms to the two sums. Recursion depth = tree depth.
struct Walk {
  const Bvh& bvh;
  std::span<const Box3f> boxes;
  std::span<const std::uint32_t> weights;
  const SahCostModel& m;
  double area_sum = 0.0, count_sum = 0.0;

  Box3f visit(std::uint32_t node) {
    const BvhNode& nd = bvh.nodes[node];
    Box3f box;
    if (nd.is_leaf()) {
      double w = 0.0;
      for (std::uint32_t i = nd.index; i < nd.index + nd.count; ++i) {
        const std::uint32_t p = bvh.prim_order[i];
        box.extend(boxes[p]);
        w += weights.empty() ? 1.0 : static_cast<double>(weights[p]);
      }
      area_sum += m.intersection * w * box.surface_area();
      count_sum += m.intersection * w;
      return box;
    }
    box = visit(node + 1);
    box.extend(visit(nd.index));
    area_sum += m.traversal * box.surface_area();
    count_sum += m.traversal;
    return box;
  }
};

}  // namespace

double sah_cost(const Bvh& bvh, std::span<const Box3f> boxes, std::span<const std::uint32_t> weights,
                const SahCostModel& model) {
  if (bvh.nodes.empty()) return 0.0;
  Walk w{bvh, boxes, weights, model};
  const Box3f root = w.visit(0);
  const double a = root.surface_area();
  return a > 0.0 ? w.area_sum / a : w.count_sum;
}

}  // namespace ptc::bvh
