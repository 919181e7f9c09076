// Refit: node boxes equal the boxes recomputed from the same topology, node by node (computed
// here independently: each node's primitive set gathered top-down, its box the union of theirs).
#include "bvh/refit.h"

#include <gtest/gtest.h>

#include "bvh/sah_builder.h"
#include "bvh/sah_cost.h"
#include "bvh/validate.h"
#include "test_util.h"

namespace ptc::bvh {
namespace {

// Box of every node as the union of the primitive boxes in its subtree's leaves.
std::vector<Box3f> boxes_from_topology(const Bvh& b, std::span<const Box3f> boxes) {
  std::vector<Box3f> out(b.nodes.size());
  for (std::uint32_t i = 0; i < b.nodes.size(); ++i) {
    std::vector<std::uint32_t> stack{i};
    while (!stack.empty()) {
      const std::uint32_t k = stack.back();
      stack.pop_back();
      const BvhNode& n = b.nodes[k];
      if (n.is_leaf()) {
        for (std::uint32_t j = 0; j < n.count; ++j) out[i].extend(boxes[b.prim_order[n.index + j]]);
      } else {
        stack.push_back(k + 1), stack.push_back(n.index);
      }
    }
  }
  return out;
}

TEST(Refit, EqualsBoxesRecomputedFromTheSameTopology) {
  const Mesh m = test::load_mesh("bunny00.off");
  const auto boxes = triangle_boxes(m.positions(), m.triangles());
  Bvh bvh = build_binned_sah({boxes, triangle_centroids(m.positions(), m.triangles()), {}}, {});
  const Mesh moved = test::deformed(m, 0.05);
  const auto new_boxes = triangle_boxes(moved.positions(), moved.triangles());
  const Bvh before = bvh;
  SahCostModel model;
  refit(bvh, new_boxes, {}, &model);
  const auto expect = boxes_from_topology(before, new_boxes);
  ASSERT_EQ(bvh.nodes.size(), expect.size());
  std::size_t changed = 0;
  for (std::size_t i = 0; i < expect.size(); ++i) {
    EXPECT_EQ(bvh.nodes[i].bounds, expect[i]) << "node " << i;
    EXPECT_EQ(bvh.nodes[i].index, before.nodes[i].index);
    EXPECT_EQ(bvh.nodes[i].count, before.nodes[i].count);
    changed += !(bvh.nodes[i].bounds == before.nodes[i].bounds);
  }
  EXPECT_GT(changed, expect.size() / 2);  // the deformation really moved the boxes
  // The refitted root is the rebuilt root: both are the union of all the new boxes.
  const Bvh rebuilt = build_binned_sah({new_boxes, triangle_centroids(moved.positions(), moved.triangles()), {}}, {});
  EXPECT_EQ(bvh.nodes[0].bounds, rebuilt.nodes[0].bounds);
  EXPECT_EQ(bvh.nodes[0].bounds, union_of(new_boxes));
  EXPECT_EQ(bvh.prim_order, before.prim_order);
  EXPECT_TRUE(validate(bvh, new_boxes).empty()) << test::joined(validate(bvh, new_boxes));
  // Refitting back to the old boxes restores the original tree exactly.
  refit(bvh, boxes, {}, &model);
  for (std::size_t i = 0; i < expect.size(); ++i) EXPECT_EQ(bvh.nodes[i].bounds, before.nodes[i].bounds);
  EXPECT_NEAR(bvh.cost, before.cost, 1e-12 * before.cost);  // same terms, summed in another order
}

TEST(Refit, EmptyAndSingle) {
  Bvh empty;
  refit(empty, {});
  EXPECT_TRUE(empty.nodes.empty());
  std::vector<Box3f> one{{{0, 0, 0}, {1, 1, 1}}};
  Bvh b = build_binned_sah({one, box_centers(one), {}}, {});
  one[0].hi = {2, 2, 2};
  refit(b, one);
  EXPECT_EQ(b.nodes[0].bounds, one[0]);
}

}  // namespace
}  // namespace ptc::bvh
