// Collapse to the 4-wide tree and its regrouping into 8-wide nodes: same leaves, boxes are
// unions; the tracer's flat data validates and its validator rejects corruption.
#include "bvh/wide_bvh.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

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

// The parallel collapse and regroup (2^16 binary / 2^14 4-wide nodes and more, more than one
// thread): the answer is the same call in an arena of one thread (the sequential walk), node for
// node (every byte), with the same depth, leaf count and bounds, at 2, 3 and 4 threads, through
// one kept workspace and output; the trees: random boxes in leaves of one and of eight, many
// duplicated boxes, and a skewed tree (boxes at exponentially growing distances: deep and
// unbalanced, so that the cut level holds subtrees of very different sizes).
TEST(WideBvh, ParallelCollapseAndRegroupAreTheSequentialOnes) {
  const auto random = test::random_boxes(150000, 4);
  std::vector<Box3f> dup(150000), skewed(100000);
  for (std::size_t i = 0; i < dup.size(); ++i) {
    const float x = static_cast<float>(i % 7);
    dup[i] = {{x, 0, 0}, {x + 0.5f, 1, 1}};
  }
  for (std::size_t i = 0; i < skewed.size(); ++i) {
    const float x = std::pow(1.0002f, static_cast<float>(i));
    skewed[i] = {{x, 0, 0}, {x * 1.0001f, 1, 1}};
  }
  struct Case {
    const char* name;
    const std::vector<Box3f>* boxes;
    std::uint32_t leaf;
  };
  const Case cases[] = {{"random, leaf 1", &random, 1}, {"random, leaf 8", &random, 8}, {"duplicated", &dup, 4},
                        {"skewed", &skewed, 1}};
  tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 4);
  WideWorkspace ws;
  WideBvh w;
  WideBvh8 w8;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    BuildConfig cfg;
    cfg.max_leaf_size = c.leaf;
    Bvh b;
    WideBvh seq;
    WideBvh8 seq8;
    tbb::task_arena(1).execute([&] {
      b = build_binned_sah({*c.boxes, box_centers(*c.boxes), {}}, cfg);
      collapse_to_wide(b, seq);
      regroup_to_8(seq, seq8);
    });
    ASSERT_GE(b.nodes.size(), std::size_t{1} << 16);
    ASSERT_GE(seq.nodes.size(), std::size_t{1} << 14);
    EXPECT_TRUE(validate_wide(seq, b).empty()) << test::joined(validate_wide(seq, b));
    for (int threads : {2, 3, 4}) {
      SCOPED_TRACE(std::to_string(threads) + " threads");
      tbb::task_arena(threads).execute([&] {
        collapse_to_wide(b, w, ws);
        regroup_to_8(w, w8, ws);
      });
      ASSERT_EQ(w.nodes.size(), seq.nodes.size());
      for (std::size_t i = 0; i < seq.nodes.size(); ++i)
        ASSERT_EQ(std::memcmp(&w.nodes[i], &seq.nodes[i], sizeof(WideNode)), 0) << "4-wide node " << i;
      EXPECT_EQ(w.root, seq.root);
      EXPECT_EQ(w.bounds, seq.bounds);
      EXPECT_EQ(w.depth, seq.depth);
      EXPECT_EQ(w.leaves, seq.leaves);
      ASSERT_EQ(w8.nodes.size(), seq8.nodes.size());
      for (std::size_t i = 0; i < seq8.nodes.size(); ++i)
        ASSERT_EQ(std::memcmp(&w8.nodes[i], &seq8.nodes[i], sizeof(WideNode8)), 0) << "8-wide node " << i;
      EXPECT_EQ(w8.root, seq8.root);
      EXPECT_EQ(w8.depth, seq8.depth);
    }
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
  SceneConfig linear = test::two_level_defaults();
  linear.cluster_leaf = ClusterLeaf::Linear;
  ClusterScene cs(m, view_of(runs), linear);
  ASSERT_TRUE(validate(cs.data(), m.triangle_count()).empty()) << test::joined(validate(cs.data(), m.triangle_count()));
  d = cs.data();
  bool corrupted = false;
  for (WideNode8& n : d.wide8.nodes)
    for (int k = 0; k < 8 && !corrupted; ++k)
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
  for (const WideNode8& n : cs4.data().wide8.nodes)
    for (int k = 0; k < 8; ++k) indirect += n.is_leaf(k) && (n.count[k] & kIndirectLeaf);
  EXPECT_GT(indirect, 0u);
  d = cs4.data();
  d.ranges[3] = d.ranges[4];
  EXPECT_FALSE(validate(d, m.triangle_count()).empty());
  // The tables format: each corruption of a group is found (validate's messages name it).
  SceneConfig tables = linear;
  tables.leaf_format = LeafFormatChoice::Tables;
  for (const SceneConfig& tc : {tables, [&] {
         SceneConfig t4 = many;
         t4.leaf_format = LeafFormatChoice::Tables;
         return t4;
       }()}) {
    ClusterScene ts(m, view_of(runs), tc);
    const TraceData& good = ts.data();
    ASSERT_TRUE(validate(good, m.triangle_count()).empty()) << test::joined(validate(good, m.triangle_count()));
    ASSERT_GT(good.tables.size(), 20u);
    std::size_t g = 0;  // a group of more than one triangle, not its cluster's last
    while (g < good.tables.size() && (good.tables[g].last || good.tables[g].count < 2)) ++g;
    ASSERT_LT(g, good.tables.size());
    const std::size_t S = kTableSlots;
    auto corrupt = [&](auto&& edit, const char* what) {
      TraceData d2 = good;
      edit(d2);
      EXPECT_FALSE(validate(d2, m.triangle_count()).empty()) << what;
    };
    corrupt([&](TraceData& x) { x.tables[g].v[1][x.tables[g].corner[0][0]] += 1.0f; }, "a corner out of its leaf box");
    corrupt([&](TraceData& x) { x.tables[g].last = 1; }, "a group marked last before its cluster's end");
    corrupt([&](TraceData& x) { x.tables[g].count -= 1; }, "a triangle dropped");
    corrupt([&](TraceData& x) { x.triangle_ids[S * g + 1] = x.triangle_ids[S * g]; }, "a triangle twice");
    ASSERT_NE(good.tables[g].slot_mask, ~0u) << "a group with an unused slot";
    const auto unused = static_cast<std::uint8_t>(__builtin_ctz(~good.tables[g].slot_mask));
    corrupt([&](TraceData& x) { x.tables[g].corner[2][0] = unused; }, "a corner on an unused slot");
    corrupt([&](TraceData& x) { x.tables[g].v[0][unused] = 0.0f; }, "an unused slot not NaN");
    corrupt([&](TraceData& x) { x.tables[g].slot_mask |= 1u << unused; }, "a slot marked in use beyond the vertex count");
    corrupt([&](TraceData& x) { x.tables[g].pair[0] ^= 3; }, "the first test's corners outside its chunks");
    corrupt([&](TraceData& x) { x.tables[g].pair[0] = 4; }, "a chunk pair code beyond 3");
    {  // A group of at most 16 vertices moved from chunks 0 and 1 to chunks 2 and 3, its tests'
       // pairs with it: consistent but for test 0, which the kernels read from chunks 0 and 1.
      std::size_t h = 0;
      while (h < good.tables.size() && good.tables[h].vertices > 16) ++h;
      ASSERT_LT(h, good.tables.size());
      TraceData d2 = good;
      TableGroup& t = d2.tables[h];
      for (int a = 0; a < 3; ++a)
        for (int q = 0; q < 16; ++q) t.v[a][q + 16] = t.v[a][q], t.v[a][q] = std::numeric_limits<float>::quiet_NaN();
      for (int c = 0; c < 3; ++c)
        for (int j = 0; j < kTableSlots; ++j) t.corner[c][j] = static_cast<std::uint8_t>(t.corner[c][j] + 16);
      t.slot_mask <<= 16;
      for (std::uint8_t& q : t.pair) q = 3;
      const std::string issues = test::joined(validate(d2, m.triangle_count()));
      EXPECT_NE(issues.find("test 0 not on chunks 0 and 1"), std::string::npos) << issues;
      EXPECT_EQ(issues.find("outside"), std::string::npos) << issues;
    }
    corrupt([&](TraceData& x) { x.triangle_ids.pop_back(); }, "ids not 32 a group");
    corrupt([&](TraceData& x) { x.blocks.resize(1); }, "blocks beside the tables");
  }
  // Block trees: valid (boxes contain, not equal, their children's), and refitted per frame.
  SceneConfig block_tree = test::two_level_defaults();
  block_tree.cluster_leaf = ClusterLeaf::BlockTree;
  ClusterScene bt(m, view_of(runs), block_tree);
  EXPECT_GT(bt.subtree_nodes(), ClusterScene(m, view_of(runs)).subtree_nodes());  // (the group trees count there too)
  EXPECT_TRUE(validate(bt.data(), m.triangle_count(), false).empty()) << test::joined(validate(bt.data(), m.triangle_count(), false));
  bt.update(test::deformed(m, 0.05).positions());
  EXPECT_TRUE(validate(bt.data(), m.triangle_count(), false).empty()) << test::joined(validate(bt.data(), m.triangle_count(), false));
  d = bt.data();
  d.wide8.nodes[0].bounds[1][0] = d.wide8.nodes[0].bounds[0][0];  // a block-tree box shrunk
  EXPECT_FALSE(validate(d, m.triangle_count(), false).empty());
}

// Every leaf child (child, count, box) reached from the root of a 4- or 8-wide tree, sorted; and
// the check that each inner child's box is the union of its node's child boxes.
struct LeafChild {
  std::uint32_t child, count;
  float box[6];
  auto operator<=>(const LeafChild&) const = default;
};
template <int kWidth, class Nodes>
std::vector<LeafChild> leaf_children(const Nodes& nodes, std::uint32_t root, std::size_t& reached, bool& unions) {
  std::vector<LeafChild> out;
  std::vector<std::uint32_t> stack{root};
  reached = 0, unions = true;
  while (!stack.empty()) {
    const auto& n = nodes[stack.back()];
    stack.pop_back();
    ++reached;
    for (int k = 0; k < kWidth; ++k) {
      if (n.is_empty(k)) continue;
      const Box3f b = n.child_box(k);
      if (n.is_leaf(k)) {
        out.push_back({n.child[k], n.count[k], {b.lo[0], b.lo[1], b.lo[2], b.hi[0], b.hi[1], b.hi[2]}});
        continue;
      }
      Box3f u;
      for (int j = 0; j < kWidth; ++j) u.extend(nodes[n.child[k]].child_box(j));
      unions = unions && u == b;
      stack.push_back(n.child[k]);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The regrouping against its 4-wide source, child by child: the same leaf children (reference
// and box), inner boxes the unions of their children, every node reached once, no more nodes or
// levels than the 4-wide tree, and (a greedy that opens while children fit) no 8-wide node with
// an inner child whose children would have fitted beside its other children.
TEST(WideBvh8, RegroupKeepsLeavesAndBoxes) {
  const Mesh m = test::load_mesh("armadillo.off");
  const auto boxes = triangle_boxes(m.positions(), m.triangles());
  const auto cent = triangle_centroids(m.positions(), m.triangles());
  WideBvh8 w8;
  for (std::uint32_t leaf : {1u, 4u, 8u}) {
    BuildConfig cfg;
    cfg.max_leaf_size = leaf;
    const WideBvh w = collapse_to_wide(build_binned_sah({boxes, cent, {}}, cfg));
    regroup_to_8(w, w8);
    std::size_t r4 = 0, r8 = 0;
    bool u4 = false, u8 = false;
    const auto l4 = leaf_children<4>(w.nodes, w.root, r4, u4);
    const auto l8 = leaf_children<8>(w8.nodes, w8.root, r8, u8);
    EXPECT_EQ(l8, l4) << "leaf " << leaf;
    EXPECT_EQ(l8.size(), w.leaves);
    EXPECT_TRUE(u4 && u8);
    EXPECT_EQ(r8, w8.nodes.size());
    EXPECT_LT(w8.nodes.size(), w.nodes.size() * 3 / 5) << "leaf " << leaf;  // measured about 0.43-0.45
    EXPECT_LE(w8.depth, w.depth);
    EXPECT_GE(w8.depth, (2 * w.depth + 2) / 3);
    for (const WideNode8& n : w8.nodes) {
      int live = 0;
      for (int k = 0; k < 8; ++k) live += !n.is_empty(k);
      for (int k = 0; k < 8; ++k) {
        if (n.is_empty(k) || n.is_leaf(k)) continue;
        int inner_live = 0;
        for (int j = 0; j < 8; ++j) inner_live += !w8.nodes[n.child[k]].is_empty(j);
        // an 8-wide child made from one 4-wide node that would have fitted here
        if (inner_live <= 4) {
          EXPECT_GT(live - 1 + inner_live, 8);
        }
      }
    }
  }
}

TEST(WideBvh8, TinyTreesAndAKeptOutput) {
  WideBvh8 w8;
  regroup_to_8(WideBvh{}, w8);
  EXPECT_TRUE(w8.nodes.empty());
  // Eight leaves under a binary root: one 8-wide node holds all of them.
  const auto eight = test::random_boxes(8, 3);
  BuildConfig cfg;
  cfg.max_leaf_size = 1;
  const WideBvh w = collapse_to_wide(build_binned_sah({eight, box_centers(eight), {}}, cfg));
  ASSERT_GT(w.nodes.size(), 1u);
  regroup_to_8(w, w8);
  ASSERT_EQ(w8.nodes.size(), 1u);
  EXPECT_EQ(w8.depth, 1u);
  for (int k = 0; k < 8; ++k) EXPECT_TRUE(w8.nodes[0].is_leaf(k)) << k;
  // One leaf: one node with one leaf child, seven empty slots.
  const std::vector<Box3f> one{{{0, 0, 0}, {1, 1, 1}}};
  regroup_to_8(collapse_to_wide(build_binned_sah({one, box_centers(one), {}}, {})), w8);
  ASSERT_EQ(w8.nodes.size(), 1u);
  EXPECT_TRUE(w8.nodes[0].is_leaf(0));
  for (int k = 1; k < 8; ++k) EXPECT_TRUE(w8.nodes[0].is_empty(k) && w8.nodes[0].child_box(k).empty()) << k;
  // The same output again, after a larger tree: equal to a fresh regrouping.
  const Mesh m = test::load_mesh("bunny00.off");
  const WideBvh big = collapse_to_wide(
      build_binned_sah({triangle_boxes(m.positions(), m.triangles()), triangle_centroids(m.positions(), m.triangles()), {}}, {}));
  regroup_to_8(big, w8);
  regroup_to_8(w, w8);
  WideBvh8 fresh;
  regroup_to_8(w, fresh);
  ASSERT_EQ(w8.nodes.size(), fresh.nodes.size());
  EXPECT_EQ(std::memcmp(w8.nodes.data(), fresh.nodes.data(), sizeof(WideNode8) * fresh.nodes.size()), 0);
}

// The exact box of the used lanes' corners of blocks [first, first + n) into `box`; returns the
// triangles counted.
std::size_t block_corners_box(const TraceData& d, std::uint32_t first, std::uint32_t n, Box3f& box) {
  std::size_t tris = 0;
  for (std::uint32_t b = first; b < first + n; ++b)
    for (int l = 0; l < 4; ++l) {
      if (d.triangle_ids[4 * std::size_t{b} + l] == kNoTriangle) continue;
      ++tris;
      for (int c = 0; c < 3; ++c) box.extend(Vec3f{d.blocks[b].v[c][0][l], d.blocks[b].v[c][1][l], d.blocks[b].v[c][2][l]});
    }
  return tris;
}

// The same for table groups [first, first + n) (n 0: up to the first one marked last, a direct
// leaf), each triangle's corners read through its slots.
std::size_t group_corners_box(const TraceData& d, std::uint32_t first, std::uint32_t n, Box3f& box) {
  std::size_t tris = 0;
  for (std::uint32_t g = first; n == 0 || g < first + n; ++g) {
    const TableGroup& tg = d.tables[g];
    for (std::uint32_t j = 0; j < tg.count; ++j, ++tris)
      for (int c = 0; c < 3; ++c) {
        const int s = tg.corner[c][j];
        box.extend(Vec3f{tg.v[0][s], tg.v[1][s], tg.v[2][s]});
      }
    if (n == 0 && tg.last) break;
  }
  return tris;
}

// Walks the 8-wide tree of a scene: for every non-empty slot, the exact box of the
// corners under it (brute force over its leaves' blocks or table groups) against the slot's box, counting in
// `loose` the slots whose box is wider than that box widened by one unit in the last place on
// some face (or does not hold it). Returns the triangles reached.
std::size_t slot_boxes_are_tight(const TraceData& d, std::size_t& loose, std::size_t& slots) {
  auto widened_ok = [](const Box3f& got, const Box3f& exact) {
    for (int a = 0; a < 3; ++a) {
      if (!(got.lo[a] <= exact.lo[a] && got.hi[a] >= exact.hi[a])) return false;
      if (got.lo[a] < std::nextafter(exact.lo[a], -kInf) || got.hi[a] > std::nextafter(exact.hi[a], kInf)) return false;
    }
    return true;
  };
  std::size_t tris = 0;
  auto under = [&](auto& self, std::uint32_t node) -> Box3f {
    const WideNode8& n = d.wide8.nodes[node];
    Box3f all;
    for (int k = 0; k < 8; ++k) {
      if (n.is_empty(k)) continue;
      Box3f box;
      if (!n.is_leaf(k)) {
        box = self(self, n.child[k]);
      } else if (n.count[k] & kIndirectLeaf) {
        for (std::uint32_t r = n.child[k]; r < n.child[k] + (n.count[k] & ~kIndirectLeaf); ++r)
          tris += d.format == LeafFormat::Tables
                      ? group_corners_box(d, d.ranges[r].first_block, d.ranges[r].block_count, box)
                      : block_corners_box(d, d.ranges[r].first_block, d.ranges[r].block_count, box);
      } else {
        tris += d.format == LeafFormat::Tables ? group_corners_box(d, n.child[k], 0, box)
                                               : block_corners_box(d, n.child[k], (n.count[k] + 3) / 4, box);
      }
      ++slots;
      if (!widened_ok(n.child_box(k), box)) ++loose;
      all.extend(box);
    }
    return all;
  };
  loose = slots = 0;
  if (!d.wide8.nodes.empty()) under(under, d.wide8.root);
  return tris;
}

// The scenes' 8-wide trees: valid after updates (the cluster scene refits its fixed subtrees'
// 8-wide nodes every frame), every box tight around the corners under it, and the validator
// rejects an 8-wide tree that is missing or whose boxes do not hold its triangles.
TEST(WideBvh8, ScenesKeepTheirEightWideTreesValid) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Clustering runs = ptc::morton_runs(m, 24);
  std::vector<SceneConfig> configs(5, test::two_level_defaults());
  configs[0].leaf_format = configs[2].leaf_format = LeafFormatChoice::Blocks;
  configs[1].cluster_leaf = ClusterLeaf::BlockTree;
  configs[2].group_trees = GroupTrees::Rebuild;
  configs[3].leaf_format = configs[4].leaf_format = LeafFormatChoice::Tables;
  configs[4].group_trees = GroupTrees::Rebuild;
  for (std::size_t c = 0; c < configs.size(); ++c) {
    ClusterScene cs(m, view_of(runs), configs[c]);
    ASSERT_EQ(cs.data().format, c >= 3 ? LeafFormat::Tables : LeafFormat::Blocks) << "config " << c;
    const bool exact = configs[c].cluster_leaf == ClusterLeaf::Linear;
    for (double amount : {0.0, 0.05, 0.2}) {
      cs.update(test::deformed(m, amount).positions());
      const auto issues = validate(cs.data(), m.triangle_count(), exact);
      EXPECT_TRUE(issues.empty()) << "config " << c << " amount " << amount << ": " << test::joined(issues);
      EXPECT_TRUE(cs.data().wide.nodes.empty());  // (a cluster scene keeps its 4-wide tree to itself)
      // Every slot's box, recomputed from the corners of the blocks under it (the tracer's
      // floats): it must hold them (validate) and be no larger than their box widened by one
      // unit in the last place (the cluster boxes' widening) -- a fixed slot left at an earlier
      // frame's box is not (the boxes move with every deformation).
      std::size_t loose = 0, slots = 0;
      EXPECT_EQ(slot_boxes_are_tight(cs.data(), loose, slots), m.triangle_count());
      EXPECT_EQ(loose, 0u) << "config " << c << " amount " << amount << ": of " << slots << " slots";
      EXPECT_GT(slots, cs.subtree_nodes());
    }
    TraceData d = cs.data();
    d.wide8.nodes.clear();
    EXPECT_FALSE(validate(d, m.triangle_count(), exact).empty());
    d = cs.data();
    for (WideNode8& n : d.wide8.nodes)  // every leaf box of the 8-wide tree shrunk to a point
      for (int k = 0; k < 8; ++k)
        if (n.is_leaf(k)) n.set_child_box(k, Box3f{n.child_box(k).lo, n.child_box(k).lo});
    EXPECT_FALSE(validate(d, m.triangle_count(), false).empty());
  }
  TriangleScene ts(m);
  ts.update(test::deformed(m, 0.1).positions());
  EXPECT_TRUE(validate(ts.data(), m.triangle_count()).empty());
  EXPECT_FALSE(ts.data().wide8.nodes.empty());
}

}  // namespace
}  // namespace ptc::bvh
