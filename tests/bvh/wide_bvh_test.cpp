// Collapse to the 4-wide tree: same leaves, boxes are unions; the tracer's flat data validates
// and its validator rejects corruption.
#include "bvh/wide_bvh.h"

#include <gtest/gtest.h>

#include <cstring>

#include "toolkit/clustering/morton_runs.h"
#include "bvh/sah_builder.h"
#include "bvh/trace_scene.h"
#include "test_util.h"

namespace ptc::bvh {
namespace {

TEST(WideBvh, CollapseKeepsLeavesAndBoxes) {
  const Mesh m = test::load_mesh("armadillo.off");
  const auto boxes = triangle_boxes(m.positions(), m.triangles());
  const auto cent = triangle_centroids(m.positions(), m.triangles());
  for (std::uint32_t leaf : {1u, 4u, 8u}) {
    BuildConfig cfg;
    cfg.max_leaf_size = leaf;
    const Bvh b = build_binned_sah({boxes, cent, {}}, cfg);
    const WideBvh w = collapse_to_wide(b);
    EXPECT_TRUE(validate_wide(w, b).empty()) << test::joined(validate_wide(w, b));
    EXPECT_EQ(w.leaves, stats(b).leaves);
    EXPECT_LT(w.nodes.size(), stats(b).inner / 2);  // ~1/3 of the binary inner nodes
    EXPECT_EQ(w.bounds, b.nodes[0].bounds);
  }
}

TEST(WideBvh, TinyTrees) {
  EXPECT_TRUE(collapse_to_wide(Bvh{}).nodes.empty());
  const std::vector<Box3f> one{{{0, 0, 0}, {1, 1, 1}}};
  const Bvh b1 = build_binned_sah({one, box_centers(one), {}}, {});
  const WideBvh w1 = collapse_to_wide(b1);
  ASSERT_EQ(w1.nodes.size(), 1u);
  EXPECT_TRUE(w1.nodes[0].is_leaf(0));
  EXPECT_TRUE(w1.nodes[0].is_empty(1));
  EXPECT_TRUE(validate_wide(w1, b1).empty());
  const auto three = test::random_boxes(3, 1);
  BuildConfig cfg;
  cfg.max_leaf_size = 1;
  const Bvh b3 = build_binned_sah({three, box_centers(three), {}}, cfg);
  const WideBvh w3 = collapse_to_wide(b3);
  EXPECT_EQ(w3.nodes.size(), 1u);  // three leaves pulled into the root
  EXPECT_TRUE(validate_wide(w3, b3).empty());
}

// A per-frame collapse reuses one output: after a large tree, a smaller one, a single leaf and
// an empty tree, each result equals a fresh collapse field by field (no stale nodes or counts).
TEST(WideBvh, CollapseIntoAKeptOutputEqualsAFreshOne) {
  const Mesh m = test::load_mesh("armadillo.off");
  const auto boxes = triangle_boxes(m.positions(), m.triangles());
  const auto cent = triangle_centroids(m.positions(), m.triangles());
  const std::vector<Box3f> few(boxes.begin(), boxes.begin() + 37), one(boxes.begin(), boxes.begin() + 1);
  std::vector<Bvh> trees{build_binned_sah({boxes, cent, {}}, {}),
                         build_binned_sah({few, box_centers(few), {}}, {}),
                         build_binned_sah({one, box_centers(one), {}}, {}), Bvh{},
                         build_binned_sah({few, box_centers(few), {}}, {})};
  WideBvh kept;
  for (std::size_t t = 0; t < trees.size(); ++t) {
    collapse_to_wide(trees[t], kept);
    const WideBvh fresh = collapse_to_wide(trees[t]);
    ASSERT_EQ(kept.nodes.size(), fresh.nodes.size()) << "tree " << t;
    for (std::size_t i = 0; i < fresh.nodes.size(); ++i)
      ASSERT_EQ(std::memcmp(&kept.nodes[i], &fresh.nodes[i], sizeof(WideNode)), 0) << "tree " << t << " node " << i;
    EXPECT_EQ(kept.root, fresh.root);
    EXPECT_EQ(kept.bounds, fresh.bounds) << "tree " << t;
    EXPECT_EQ(kept.depth, fresh.depth);
    EXPECT_EQ(kept.leaves, fresh.leaves);
    if (!trees[t].nodes.empty()) {
      EXPECT_TRUE(validate_wide(kept, trees[t]).empty());
    }
  }
}

TEST(WideBvh, ValidatorsRejectCorruption) {
  const Mesh m = test::load_mesh("bunny00.off");
  const auto boxes = triangle_boxes(m.positions(), m.triangles());
  const Bvh b = build_binned_sah({boxes, triangle_centroids(m.positions(), m.triangles()), {}}, {});
  WideBvh w = collapse_to_wide(b);
  w.nodes[1].bounds[0][0] -= 1.0f;
  EXPECT_FALSE(validate_wide(w, b).empty());

  TriangleScene s(m);
  ASSERT_TRUE(validate(s.data(), m.triangle_count()).empty());
  TraceData d = s.data();
  d.triangle_ids[5] = d.triangle_ids[4];
  EXPECT_FALSE(validate(d, m.triangle_count()).empty());
  d = s.data();
  d.blocks[10].v[1][2][1] += 1.0f;  // a corner moved out of its leaf box
  EXPECT_FALSE(validate(d, m.triangle_count()).empty());
  d = s.data();
  for (WideNode& n : d.wide.nodes)
    for (int k = 0; k < 4; ++k)
      if (n.is_leaf(k)) n.count[k] = 0, n.child[k] = 0;  // leaves dropped
  EXPECT_FALSE(validate(d, m.triangle_count()).empty());

  const Clustering runs = ptc::morton_runs(m, 80);
  SceneConfig linear = cluster_scene_defaults();
  linear.cluster_leaf = ClusterLeaf::Linear;
  ClusterScene cs(m, view_of(runs), linear);
  ASSERT_TRUE(validate(cs.data(), m.triangle_count()).empty()) << test::joined(validate(cs.data(), m.triangle_count()));
  d = cs.data();
  bool corrupted = false;
  for (WideNode& n : d.wide.nodes)
    for (int k = 0; k < 4 && !corrupted; ++k)
      if (n.is_leaf(k) && !(n.count[k] & kIndirectLeaf)) n.count[k] -= 1, corrupted = true;  // drops a triangle
  ASSERT_TRUE(corrupted);
  EXPECT_FALSE(validate(d, m.triangle_count()).empty());
  // Leaves of several clusters use the range table (indirect leaves).
  SceneConfig many = linear;
  many.build.max_leaf_size = 4;
  many.build.cost.traversal = 1000.0;  // leaves as large as allowed
  ClusterScene cs4(m, view_of(runs), many);
  ASSERT_TRUE(validate(cs4.data(), m.triangle_count()).empty());
  std::size_t indirect = 0;
  for (const WideNode& n : cs4.data().wide.nodes)
    for (int k = 0; k < 4; ++k) indirect += n.is_leaf(k) && (n.count[k] & kIndirectLeaf);
  EXPECT_GT(indirect, 0u);
  d = cs4.data();
  d.ranges[3] = d.ranges[4];
  EXPECT_FALSE(validate(d, m.triangle_count()).empty());
  // Block trees: valid (boxes contain, not equal, their children's), and refitted per frame.
  SceneConfig block_tree = cluster_scene_defaults();
  block_tree.cluster_leaf = ClusterLeaf::BlockTree;
  ClusterScene bt(m, view_of(runs), block_tree);
  EXPECT_GT(bt.subtree_nodes(), ClusterScene(m, view_of(runs)).subtree_nodes());  // (the group trees count there too)
  EXPECT_TRUE(validate(bt.data(), m.triangle_count(), false).empty()) << test::joined(validate(bt.data(), m.triangle_count(), false));
  bt.update(test::deformed(m, 0.05).positions());
  EXPECT_TRUE(validate(bt.data(), m.triangle_count(), false).empty()) << test::joined(validate(bt.data(), m.triangle_count(), false));
  d = bt.data();
  d.wide.nodes[0].bounds[1][0] = d.wide.nodes[0].bounds[0][0];  // a block-tree box shrunk
  EXPECT_FALSE(validate(d, m.triangle_count(), false).empty());
}

}  // namespace
}  // namespace ptc::bvh
