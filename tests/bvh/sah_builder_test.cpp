// Builders: degenerate inputs first, then random boxes and real meshes; every tree is checked by
// validate() (structure, containment, SAH cost recomputed independently).
#include "bvh/sah_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <limits>
#include <random>
#include <utility>
#include <string>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "bvh/binning.h"
#include "bvh/sah_cost.h"
#include "bvh/validate.h"
#include "test_util.h"
#include "toolkit/geometry/morton.h"

namespace ptc::bvh {
namespace {

using Builder = Bvh (*)(const BuildInput&, const BuildConfig&);

struct Named {
  const char* name;
  Builder fn;
};
const Named kBuilders[] = {{"sweep", &build_sweep_sah}, {"binned", &build_binned_sah}};

void expect_valid(const Bvh& bvh, std::span<const Box3f> boxes, const BuildConfig& cfg,
                  std::span<const std::uint32_t> weights = {}) {
  ValidateOptions opt;
  opt.weights = weights;
  opt.model = cfg.cost;
  const auto issues = validate(bvh, boxes, opt);
  EXPECT_TRUE(issues.empty()) << test::joined(issues);
  for (const BvhNode& n : bvh.nodes)
    if (n.is_leaf()) {
      EXPECT_LE(n.count, cfg.max_leaf_size);
    }
}

TEST(SahBuilder, EmptyInputGivesEmptyTree) {
  for (const Named& b : kBuilders) {
    const Bvh bvh = b.fn({}, {});
    EXPECT_TRUE(bvh.empty()) << b.name;
    EXPECT_TRUE(bvh.prim_order.empty());
    EXPECT_EQ(bvh.cost, 0.0);
    EXPECT_TRUE(validate(bvh, {}).empty());
  }
}

TEST(SahBuilder, OnePrimitiveIsOneLeaf) {
  const std::vector<Box3f> boxes{{{1, 2, 3}, {4, 5, 6}}};
  const auto c = box_centers(boxes);
  for (const Named& b : kBuilders) {
    const Bvh bvh = b.fn({boxes, c, {}}, {});
    ASSERT_EQ(bvh.nodes.size(), 1u) << b.name;
    EXPECT_EQ(bvh.nodes[0].count, 1u);
    EXPECT_EQ(bvh.nodes[0].bounds, boxes[0]);
    EXPECT_DOUBLE_EQ(bvh.cost, 1.0);  // one triangle test, A(leaf)/A(root) = 1
    expect_valid(bvh, boxes, {});
  }
}

TEST(SahBuilder, AllCentroidsEqualStillRespectsMaxLeafSize) {
  // 100 nested boxes around one centre: no plane separates them, so splits are object medians.
  std::vector<Box3f> boxes;
  for (int i = 0; i < 100; ++i) {
    const float e = 1.0f + 0.1f * static_cast<float>(i);
    boxes.push_back({{-e, -e, -e}, {e, e, e}});
  }
  const auto c = box_centers(boxes);
  BuildConfig cfg;
  cfg.max_leaf_size = 4;
  for (const Named& b : kBuilders) {
    const Bvh bvh = b.fn({boxes, c, {}}, cfg);
    SCOPED_TRACE(b.name);
    expect_valid(bvh, boxes, cfg);
  }
}

TEST(SahBuilder, ZeroSizeBoxes) {
  // Points (zero area everywhere: the 0/0 convention of sah_cost), all equal and all distinct.
  for (bool distinct : {false, true}) {
    std::vector<Box3f> boxes(37);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      const float x = distinct ? static_cast<float>(i) : 7.0f;
      boxes[i] = {{x, 2 * x, 3.0f}, {x, 2 * x, 3.0f}};
    }
    const auto c = box_centers(boxes);
    BuildConfig cfg;
    cfg.max_leaf_size = 3;
    for (const Named& b : kBuilders) {
      SCOPED_TRACE(std::string(b.name) + (distinct ? " distinct" : " equal"));
      const Bvh bvh = b.fn({boxes, c, {}}, cfg);
      expect_valid(bvh, boxes, cfg);
    }
  }
  // Flat boxes (zero volume, positive area): a plane of triangles.
  std::vector<Box3f> flat;
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 4; ++j)
      flat.push_back({{float(i), float(j), 0.0f}, {float(i) + 1, float(j) + 1, 0.0f}});
  const auto c = box_centers(flat);
  for (const Named& b : kBuilders) {
    SCOPED_TRACE(b.name);
    const Bvh bvh = b.fn({flat, c, {}}, {});
    expect_valid(bvh, flat, {});
  }
}

TEST(SahBuilder, RandomBoxesAreValidAndCostsAgree) {
  for (std::uint32_t seed = 1; seed <= 5; ++seed) {
    const auto boxes = test::random_boxes(50 + 300 * seed, seed);
    const auto c = box_centers(boxes);
    for (std::uint32_t leaf : {1u, 4u, 16u}) {
      BuildConfig cfg;
      cfg.max_leaf_size = leaf;
      for (const Named& b : kBuilders) {
        SCOPED_TRACE(std::string(b.name) + " seed " + std::to_string(seed) + " leaf " + std::to_string(leaf));
        const Bvh bvh = b.fn({boxes, c, {}}, cfg);
        expect_valid(bvh, boxes, cfg);
      }
    }
  }
}

TEST(SahBuilder, SplitsOnlyWhenTheCostModelSaysSo) {
  // Two unit boxes 100 apart: splitting costs 1 + (1*6 + 1*6)/A(root) ~ 1.0x, a leaf costs 2.
  const std::vector<Box3f> boxes{{{0, 0, 0}, {1, 1, 1}}, {{100, 0, 0}, {101, 1, 1}}};
  const auto c = box_centers(boxes);
  for (const Named& b : kBuilders) {
    SCOPED_TRACE(b.name);
    EXPECT_EQ(b.fn({boxes, c, {}}, {}).nodes.size(), 3u);
    BuildConfig expensive;  // traversal 10: the leaf (cost 2) wins
    expensive.cost.traversal = 10.0;
    const Bvh leaf = b.fn({boxes, c, {}}, expensive);
    ASSERT_EQ(leaf.nodes.size(), 1u);
    EXPECT_DOUBLE_EQ(leaf.cost, 2.0);
    // ... unless the leaf is too heavy: weights 10 + 10 make the leaf cost 20.
    const std::vector<std::uint32_t> w{10, 10};
    const Bvh heavy = b.fn({boxes, c, w}, expensive);
    EXPECT_EQ(heavy.nodes.size(), 3u);
    expect_valid(heavy, boxes, expensive, w);
    // ... and never above max_leaf_size.
    expensive.max_leaf_size = 1;
    EXPECT_EQ(b.fn({boxes, c, {}}, expensive).nodes.size(), 3u);
  }
}

TEST(SahBuilder, CostMatchesAHandComputedTree) {
  // Three unit boxes on a line at x = 0, 2, 10; max leaf 1 forces a full binary tree.
  const std::vector<Box3f> boxes{{{0, 0, 0}, {1, 1, 1}}, {{2, 0, 0}, {3, 1, 1}}, {{10, 0, 0}, {11, 1, 1}}};
  const auto c = box_centers(boxes);
  BuildConfig cfg;
  cfg.max_leaf_size = 1;
  // Root [0,11]x[0,1]^2: A = 2(11 + 1 + 11) = 46; best split {0,2} | {10}: inner [0,3]: A = 14.
  // cost = (1*46 + 1*14 + 3 leaves * 6) / 46.
  const double expected = (46.0 + 14.0 + 18.0) / 46.0;
  for (const Named& b : kBuilders) {
    const Bvh bvh = b.fn({boxes, c, {}}, cfg);
    EXPECT_DOUBLE_EQ(bvh.cost, expected) << b.name;
    EXPECT_DOUBLE_EQ(sah_cost(bvh, boxes, {}, cfg.cost), expected) << b.name;
  }
  // The median split of small nodes (binned builder) splits the root {0} | {2, 10} instead:
  // inner [2,11]x[0,1]^2, A = 38; cost = (46 + 38 + 18) / 46.
  cfg.median_split_below = 4;
  const Bvh median = build_binned_sah({boxes, c, {}}, cfg);
  EXPECT_DOUBLE_EQ(median.cost, (46.0 + 38.0 + 18.0) / 46.0);
  EXPECT_DOUBLE_EQ(sah_cost(median, boxes, {}, cfg.cost), median.cost);
  expect_valid(median, boxes, cfg);
}

TEST(SahBuilder, RealMeshTrianglesAndClusters) {
  const Mesh m = test::load_mesh("armadillo.off");
  const auto boxes = triangle_boxes(m.positions(), m.triangles());
  const auto cent = triangle_centroids(m.positions(), m.triangles());
  for (const auto& b : boxes) ASSERT_FALSE(b.empty());
  BuildConfig cfg;
  const Bvh sweep = build_sweep_sah({boxes, cent, {}}, cfg);
  const Bvh binned = build_binned_sah({boxes, cent, {}}, cfg);
  expect_valid(sweep, boxes, cfg);
  expect_valid(binned, boxes, cfg);
  // Binning approximates the sweep: same quality within a few percent.
  EXPECT_LT(binned.cost, 1.10 * sweep.cost);
  EXPECT_GT(binned.cost, 0.90 * sweep.cost);

  // Clusters: Morton runs of 80 triangles, weight = triangles in the run.
  const auto order = morton_order(m.positions(), m.triangles());
  std::vector<std::uint32_t> offsets{0};
  while (offsets.back() < order.size()) offsets.push_back(std::min<std::uint32_t>(offsets.back() + 80, std::uint32_t(order.size())));
  std::vector<Box3f> cboxes(offsets.size() - 1);
  std::vector<std::uint32_t> weights(cboxes.size());
  for (std::size_t k = 0; k + 1 < offsets.size(); ++k) {
    for (std::uint32_t i = offsets[k]; i < offsets[k + 1]; ++i) cboxes[k].extend(boxes[order[i]]);
    weights[k] = offsets[k + 1] - offsets[k];
  }
  const auto cc = box_centers(cboxes);
  for (std::uint32_t leaf : {1u, 4u}) {
    BuildConfig ccfg;
    ccfg.max_leaf_size = leaf;
    for (const Named& b : kBuilders) {
      SCOPED_TRACE(b.name);
      const Bvh cb = b.fn({cboxes, cc, weights}, ccfg);
      expect_valid(cb, cboxes, ccfg, weights);
      if (leaf == 1) {
        EXPECT_EQ(stats(cb).leaves, cboxes.size());
      }
    }
  }
}

TEST(SahBuilder, Deterministic) {
  const auto boxes = test::random_boxes(5000, 42);
  const auto c = box_centers(boxes);
  for (const Named& b : kBuilders) {
    const Bvh x = b.fn({boxes, c, {}}, {}), y = b.fn({boxes, c, {}}, {});
    EXPECT_EQ(x.prim_order, y.prim_order) << b.name;
    ASSERT_EQ(x.nodes.size(), y.nodes.size());
    for (std::size_t i = 0; i < x.nodes.size(); ++i) {
      EXPECT_EQ(x.nodes[i].bounds, y.nodes[i].bounds);
      EXPECT_EQ(x.nodes[i].index, y.nodes[i].index);
      EXPECT_EQ(x.nodes[i].count, y.nodes[i].count);
    }
  }
}

// The per-frame form: one workspace and one output tree reused across builds of different
// inputs (sizes up and down, weights on and off) gives exactly the tree of a fresh build.
TEST(SahBuilder, WorkspaceReuseEqualsAFreshBuild) {
  const auto big = test::random_boxes(3000, 7), small = test::random_boxes(37, 8), mid = test::random_boxes(900, 9);
  std::vector<std::uint32_t> wmid(mid.size());
  for (std::size_t i = 0; i < wmid.size(); ++i) wmid[i] = 1 + static_cast<std::uint32_t>((i * 7919) % 60);
  const auto cbig = box_centers(big), csmall = box_centers(small), cmid = box_centers(mid);
  BuildWorkspace ws;
  Bvh out;
  struct Case {
    BuildInput in;
    std::uint32_t leaf;
  };
  const Case cases[] = {{{big, cbig, {}}, 8}, {{small, csmall, {}}, 1}, {{mid, cmid, wmid}, 1},
                        {{big, cbig, {}}, 1}, {{mid, cmid, wmid}, 4}, {{{}, {}, {}}, 1}, {{small, csmall, {}}, 8}};
  for (const Case& c : cases) {
    BuildConfig cfg;
    cfg.max_leaf_size = c.leaf;
    cfg.cost = {1.0, 0.3};
    build_binned_sah(c.in, cfg, out, ws);
    const Bvh fresh = build_binned_sah(c.in, cfg);
    ASSERT_EQ(out.nodes.size(), fresh.nodes.size());
    EXPECT_EQ(out.prim_order, fresh.prim_order);
    EXPECT_EQ(out.cost, fresh.cost);
    for (std::size_t i = 0; i < out.nodes.size(); ++i) {
      ASSERT_EQ(out.nodes[i].bounds, fresh.nodes[i].bounds) << i;
      ASSERT_EQ(out.nodes[i].index, fresh.nodes[i].index) << i;
      ASSERT_EQ(out.nodes[i].count, fresh.nodes[i].count) << i;
    }
    expect_valid(out, c.in.boxes, cfg, c.in.weights);
  }
}

// Single-primitive leaves (the cluster configuration) on hard inputs: duplicated boxes (no
// plane separates the centroids), a line of points (zero-area nodes), pairs and triples of
// boxes; every primitive must end in its own leaf and the cost must match sah_cost().
TEST(SahBuilder, SinglePrimitiveLeavesOnDegenerateInputs) {
  std::vector<std::vector<Box3f>> inputs;
  inputs.push_back(std::vector<Box3f>(40, Box3f{{1, 2, 3}, {2, 3, 4}}));  // all equal
  std::vector<Box3f> line;
  for (int i = 0; i < 50; ++i) line.push_back({{float(i), 0, 0}, {float(i), 0, 0}});  // points on a line
  inputs.push_back(line);
  inputs.push_back({{{0, 0, 0}, {1, 1, 1}}, {{5, 0, 0}, {6, 1, 1}}});
  inputs.push_back({{{0, 0, 0}, {1, 1, 1}}, {{5, 0, 0}, {6, 1, 1}}, {{2, 7, 0}, {3, 8, 1}}});
  inputs.push_back(test::random_boxes(17, 3));
  inputs.push_back(test::random_boxes(100, 4, 0.0f));  // points
  for (const auto& boxes : inputs) {
    const auto c = box_centers(boxes);
    BuildConfig cfg;
    cfg.max_leaf_size = 1;
    for (const Named& b : kBuilders) {
      SCOPED_TRACE(b.name);
      const Bvh bvh = b.fn({boxes, c, {}}, cfg);
      expect_valid(bvh, boxes, cfg);
      EXPECT_EQ(stats(bvh).leaves, boxes.size());
    }
  }
}

// Every tree the binned builder makes with its AVX2 binning loop equals, node for node, the tree
// of its SSE2 loop (the same bins by construction; on a CPU without AVX2 both runs take the
// SSE2 loop and the test still checks validity). Inputs: random boxes with weights, single-
// primitive leaves, duplicated boxes, points.
TEST(SahBuilder, Avx2AndSse2BinningGiveTheSameTree) {
  std::vector<std::vector<Box3f>> inputs{test::random_boxes(4000, 11), test::random_boxes(333, 12, 0.0f),
                                         std::vector<Box3f>(70, Box3f{{1, 2, 3}, {2, 3, 4}})};
  for (const auto& boxes : inputs) {
    const auto c = box_centers(boxes);
    std::vector<std::uint32_t> w(boxes.size());
    for (std::size_t i = 0; i < w.size(); ++i) w[i] = 1 + static_cast<std::uint32_t>((i * 31) % 50);
    for (std::uint32_t leaf : {1u, 4u}) {
      BuildConfig on, off;
      on.max_leaf_size = off.max_leaf_size = leaf;
      off.allow_avx2 = false;
      const Bvh a = build_binned_sah({boxes, c, w}, on), b = build_binned_sah({boxes, c, w}, off);
      SCOPED_TRACE("n " + std::to_string(boxes.size()) + " leaf " + std::to_string(leaf));
      expect_valid(a, boxes, on, w);
      expect_valid(b, boxes, off, w);
      EXPECT_EQ(a.prim_order, b.prim_order);
      EXPECT_EQ(a.cost, b.cost);
      ASSERT_EQ(a.nodes.size(), b.nodes.size());
      for (std::size_t i = 0; i < a.nodes.size(); ++i) {
        ASSERT_EQ(a.nodes[i].bounds, b.nodes[i].bounds) << i;
        ASSERT_EQ(a.nodes[i].index, b.nodes[i].index) << i;
        ASSERT_EQ(a.nodes[i].count, b.nodes[i].count) << i;
      }
    }
  }
}

// The object-median split of small nodes that must be split (median_split_below) against the
// exact sweep: valid with single-primitive leaves at every threshold, and an SAH cost close to
// the exact sweep's (within 3% on random weighted boxes; greedy builds give no exact ordering).
TEST(SahBuilder, MedianSplitOfSmallNodesIsValidAndClose) {
  const auto boxes = test::random_boxes(3000, 21);
  const auto c = box_centers(boxes);
  std::vector<std::uint32_t> w(boxes.size());
  for (std::size_t i = 0; i < w.size(); ++i) w[i] = 20 + static_cast<std::uint32_t>((i * 7) % 30);
  for (std::uint32_t median : {0u, 2u, 4u, 8u, 16u}) {
    BuildConfig cfg;
    cfg.max_leaf_size = 1;
    cfg.cost = {1.0, 0.3};
    cfg.median_split_below = median;
    const Bvh b = build_binned_sah({boxes, c, w}, cfg);
    SCOPED_TRACE("median below " + std::to_string(median));
    expect_valid(b, boxes, cfg, w);
    EXPECT_EQ(stats(b).leaves, boxes.size());
    BuildConfig exact = cfg;
    exact.median_split_below = 0;
    const Bvh e = build_binned_sah({boxes, c, w}, exact);
    if (median <= 8) {
      EXPECT_LT(b.cost, 1.03 * e.cost);
    }
    if (median < 2) {
      EXPECT_EQ(b.cost, e.cost);  // a node that must be split has >= 2 primitives: no effect
    }
  }
}

// Huge and tiny coordinates (NaN-free): areas that overflow or underflow the builder's float
// arithmetic, and centroid extents that vanish next to the coordinates. Every builder and leaf
// size must still give a valid tree with the cost recomputed by sah_cost().
TEST(SahBuilder, HugeAndTinyCoordinates) {
  std::vector<std::pair<std::string, std::vector<Box3f>>> inputs;
  for (float scale : {1e-30f, 1e-20f, 1e18f, 1e30f}) {
    auto b = test::random_boxes(200, 31);
    for (Box3f& x : b)
      for (int a = 0; a < 3; ++a) x.lo[a] *= scale, x.hi[a] *= scale;
    inputs.push_back({"scale " + std::to_string(scale), b});
  }
  {  // tiny boxes far from the origin: centroids differ by a few ulps or not at all
    auto b = test::random_boxes(150, 32, 0.0f);
    for (Box3f& x : b)
      for (int a = 0; a < 3; ++a) {
        const float v = 1e7f + std::floor(x.lo[a] / 25.0f);  // 4 distinct values per axis
        x.lo[a] = v, x.hi[a] = std::nextafter(v, 2e7f);
      }
    inputs.push_back({"offset 1e7", b});
  }
  {  // one primitive and two primitives at extreme coordinates
    inputs.push_back({"one huge", {Box3f{{-3e38f, -3e38f, -3e38f}, {3e38f, 3e38f, 3e38f}}}});
    inputs.push_back({"two tiny", {Box3f{{1e-38f, 0, 0}, {2e-38f, 1e-38f, 1e-38f}},
                                   Box3f{{-2e-38f, 0, 0}, {-1e-38f, 1e-38f, 1e-38f}}}});
  }
  for (const auto& [name, boxes] : inputs) {
    const auto c = box_centers(boxes);
    for (std::uint32_t leaf : {1u, 4u}) {
      BuildConfig cfg;
      cfg.max_leaf_size = leaf;
      for (const Named& b : kBuilders) {
        SCOPED_TRACE(name + " " + b.name + " leaf " + std::to_string(leaf));
        const Bvh bvh = b.fn({boxes, c, {}}, cfg);
        expect_valid(bvh, boxes, cfg);
        if (leaf == 1) {
          EXPECT_EQ(stats(bvh).leaves, boxes.size());
        }
      }
    }
  }
}


// Two-level build (BuildInput::groups): valid trees whose leaves never mix groups; one primitive
// per group equals the plain build (same records), node for node; the reported cost equals the
// independent recomputation (validate); groups of a Morton order stay within a few percent of
// the plain build's SAH cost; bad offsets are refused.
TEST(SahBuilder, GroupedBuild) {
  const Mesh m = test::load_mesh("armadillo.off");
  const auto tboxes = triangle_boxes(m.positions(), m.triangles());
  const auto order = morton_order(m.positions(), m.triangles());
  // Clusters: Morton runs of 30 triangles (in Morton order: consecutive clusters are near).
  std::vector<std::uint32_t> offsets{0};
  while (offsets.back() < order.size())
    offsets.push_back(std::min<std::uint32_t>(offsets.back() + 30, std::uint32_t(order.size())));
  std::vector<Box3f> boxes(offsets.size() - 1);
  std::vector<std::uint32_t> weights(boxes.size());
  for (std::size_t k = 0; k + 1 < offsets.size(); ++k) {
    for (std::uint32_t i = offsets[k]; i < offsets[k + 1]; ++i) boxes[k].extend(tboxes[order[i]]);
    weights[k] = offsets[k + 1] - offsets[k];
  }
  const auto centers = box_centers(boxes);
  const auto n = static_cast<std::uint32_t>(boxes.size());
  BuildConfig cfg;
  cfg.max_leaf_size = 1;
  cfg.cost = {1.0, 0.3};
  const Bvh plain = build_binned_sah({boxes, centers, weights}, cfg);
  expect_valid(plain, boxes, cfg, weights);

  std::vector<std::uint32_t> singles(n + 1);
  std::iota(singles.begin(), singles.end(), 0u);
  const Bvh same = build_binned_sah({boxes, centers, weights, singles}, cfg);
  ASSERT_EQ(same.nodes.size(), plain.nodes.size());
  for (std::size_t i = 0; i < plain.nodes.size(); ++i) {  // (leaves may sit elsewhere in prim_order)
    ASSERT_EQ(same.nodes[i].bounds, plain.nodes[i].bounds) << i;
    ASSERT_EQ(same.nodes[i].count, plain.nodes[i].count) << i;
    if (plain.nodes[i].is_leaf()) {
      ASSERT_EQ(same.prim_order[same.nodes[i].index], plain.prim_order[plain.nodes[i].index]) << i;
    } else {
      ASSERT_EQ(same.nodes[i].index, plain.nodes[i].index) << i;
    }
  }
  EXPECT_DOUBLE_EQ(same.cost, plain.cost);

  for (std::uint32_t size : {2u, 7u, 16u, 64u}) {
    SCOPED_TRACE("group size " + std::to_string(size));
    std::vector<std::uint32_t> groups;
    for (std::uint32_t c = 0; c < n; c += size) groups.push_back(c);
    groups.push_back(n);
    for (std::uint32_t leaf : {1u, 4u}) {
      BuildConfig c2 = cfg;
      c2.max_leaf_size = leaf;
      const Bvh g = build_binned_sah({boxes, centers, weights, groups}, c2);
      expect_valid(g, boxes, c2, weights);
      // No leaf mixes two groups, and every group's primitives form one subtree: the node whose
      // range covers exactly the group exists (its primitives are contiguous in prim_order).
      std::vector<std::uint32_t> group_of(n);
      for (std::size_t k = 0; k + 1 < groups.size(); ++k)
        for (std::uint32_t i = groups[k]; i < groups[k + 1]; ++i) group_of[i] = static_cast<std::uint32_t>(k);
      for (const BvhNode& nd : g.nodes) {
        if (!nd.is_leaf()) continue;
        for (std::uint32_t i = nd.index; i < nd.index + nd.count; ++i)
          ASSERT_EQ(group_of[g.prim_order[i]], group_of[g.prim_order[nd.index]]) << "a leaf mixes groups";
      }
      for (std::size_t i = 1; i < n; ++i)  // each group contiguous in prim_order
        if (group_of[g.prim_order[i]] != group_of[g.prim_order[i - 1]]) {
          for (std::size_t j = i + 1; j < n; ++j) ASSERT_NE(group_of[g.prim_order[j]], group_of[g.prim_order[i - 1]]);
        }
      if (leaf == 1) {
        EXPECT_LT(g.cost, (size <= 16 ? 1.06 : 1.12) * plain.cost) << g.cost << " vs " << plain.cost;
      }
    }
  }
  std::vector<std::uint32_t> bad1{0, 5, 5, n}, bad2{0, 5}, bad3{1, n}, bad4{0, 9, 4, n};
  for (const auto* bad : {&bad1, &bad2, &bad3, &bad4})
    EXPECT_THROW((void)build_binned_sah({boxes, centers, weights, *bad}, cfg), std::invalid_argument);
}


// The binned build runs in parallel from 2^15 items at the root when its arena has more than one
// thread: the tree is cut into fragments built at once and spliced in pre-order. The answer to
// compare with is the same build in an arena of one thread (the sequential code path), node for
// node (bounds, index, count), the primitive order and the cost's bits, at 2, 3 and 4 threads, on
// hard inputs: duplicated centroids (object-median splits), points, huge offsets at a tiny
// scale, weights, single-primitive leaves and a two-level build; one workspace goes through
// every case and thread count. A NaN far into a large input is refused by the parallel record
// pass, naming the primitive.
TEST(SahBuilder, ParallelBuildIsTheSequentialTree) {
  constexpr std::size_t kN = 70000;
  std::mt19937 rng(11);
  const auto random = test::random_boxes(kN, 21);
  std::vector<Box3f> dup(kN), points(kN), far(kN);
  std::uniform_int_distribution<int> pick(0, 5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (std::size_t i = 0; i < kN; ++i) {
    const float x = static_cast<float>(pick(rng));  // six distinct positions, many copies each
    dup[i] = {{x, 0.0f, 0.0f}, {x + 1.0f, 1.0f, 1.0f}};
    const Vec3f p{u(rng), u(rng), i % 3 == 0 ? 0.5f : u(rng)};
    points[i] = {p, p};  // zero-size boxes
    for (int a = 0; a < 3; ++a) {
      far[i].lo[a] = 1e30f + 1e24f * random[i].lo[a];
      far[i].hi[a] = 1e30f + 1e24f * random[i].hi[a];
    }
  }
  std::vector<std::uint32_t> weights(kN);
  for (std::size_t i = 0; i < kN; ++i) weights[i] = 1 + static_cast<std::uint32_t>((i * 7919) % 60);
  std::vector<std::uint32_t> groups{0};  // 35,000 groups of one to three primitives
  while (groups.back() < kN)
    groups.push_back(std::min<std::uint32_t>(groups.back() + 1 + static_cast<std::uint32_t>(groups.size() % 3), kN));
  ASSERT_GE(groups.size() - 1, 1u << 15);
  const auto crandom = box_centers(random), cdup = box_centers(dup), cpoints = box_centers(points), cfar = box_centers(far);
  struct Case {
    const char* name;
    BuildInput in;
    std::uint32_t leaf;
  };
  const Case cases[] = {{"random", {random, crandom, {}}, 4},     {"duplicated", {dup, cdup, {}}, 4},
                        {"points", {points, cpoints, {}}, 8},     {"far and tiny", {far, cfar, {}}, 4},
                        {"weighted", {random, crandom, weights}, 1}, {"grouped", {random, crandom, weights, groups}, 1},
                        {"random, leaf 1", {random, crandom, {}}, 1}};
  tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 4);  // (above this machine's cores)
  BuildWorkspace ws;
  Bvh out;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    BuildConfig cfg;
    cfg.max_leaf_size = c.leaf;
    cfg.cost = {1.0, 0.3};
    Bvh seq;
    tbb::task_arena(1).execute([&] { seq = build_binned_sah(c.in, cfg); });
    expect_valid(seq, c.in.boxes, cfg, c.in.weights);
    for (int threads : {2, 3, 4}) {
      SCOPED_TRACE(std::to_string(threads) + " threads");
      tbb::task_arena(threads).execute([&] { build_binned_sah(c.in, cfg, out, ws); });
      ASSERT_EQ(out.nodes.size(), seq.nodes.size());
      for (std::size_t i = 0; i < seq.nodes.size(); ++i) {
        ASSERT_EQ(out.nodes[i].bounds, seq.nodes[i].bounds) << i;
        ASSERT_EQ(out.nodes[i].index, seq.nodes[i].index) << i;
        ASSERT_EQ(out.nodes[i].count, seq.nodes[i].count) << i;
      }
      EXPECT_EQ(out.prim_order, seq.prim_order);
      EXPECT_EQ(std::bit_cast<std::uint64_t>(out.cost), std::bit_cast<std::uint64_t>(seq.cost)) << out.cost << " vs " << seq.cost;
    }
  }
  {  // an arena wider than the process's limit (ptc --threads 2 under a wider arena): its thread
     // slots run past the limit; the build still gives the sequential tree
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    BuildConfig cfg;
    cfg.max_leaf_size = 4;
    const Bvh seq = build_binned_sah({random, crandom, {}}, cfg);  // (compared above with one thread's)
    for (int round = 0; round < 3; ++round) {
      tbb::task_arena(4).execute([&] { build_binned_sah({random, crandom, {}}, cfg, out, ws); });
      ASSERT_EQ(out.nodes.size(), seq.nodes.size());
      for (std::size_t i = 0; i < seq.nodes.size(); ++i) ASSERT_EQ(out.nodes[i].index, seq.nodes[i].index) << i;
      EXPECT_EQ(out.prim_order, seq.prim_order);
    }
  }
  auto bad = random;
  bad[61234].hi[1] = std::nanf("");
  tbb::task_arena(2).execute([&] {
    try {
      (void)build_binned_sah({bad, crandom, {}}, {});
      ADD_FAILURE() << "accepted NaN";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("primitive 61234"), std::string::npos) << e.what();
    }
  });
}

// NaN in a box or a centroid (a NaN position upstream): both builders refuse it, naming the
// primitive, instead of building a broken tree (ranks by a NaN centroid are not an order).
TEST(SahBuilder, NanBoxesAndCentroidsAreRefused) {
  const auto boxes = test::random_boxes(43, 3);
  const auto c = box_centers(boxes);
  BuildConfig cfg;
  cfg.max_leaf_size = 1;
  for (int what = 0; what < 3; ++what) {
    auto b2 = boxes;
    auto c2 = c;
    const float nan = std::nanf("");
    if (what == 0) b2[17].lo[1] = nan;
    if (what == 1) b2[17].hi[2] = nan;
    if (what == 2) c2[17][0] = nan;
    for (const Named& b : kBuilders) {
      try {
        (void)b.fn({b2, c2, {}}, cfg);
        ADD_FAILURE() << b.name << " accepted NaN (" << what << ")";
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("primitive 17"), std::string::npos) << e.what();
      }
    }
    std::vector<std::uint32_t> groups{0, 20, 43};
    EXPECT_THROW((void)build_binned_sah({b2, c2, {}, groups}, cfg), std::invalid_argument);
  }
}

// BuildConfig::area_weights: four unit boxes at the corners of a 4 x 6 rectangle in x and z.
// The plain SAH cuts across z (children of area 18 against 26 across x); weights (0.01, 0.01, 1),
// rays along z, price the children across x at 2(1 + 0.06 + 0.06) = 2.24 and across z at
// 2(4 + 0.01 + 0.04) = 8.1, so both builders cut across x. Bvh::cost is the plain SAH cost of
// the tree either way (by hand: (68 + 18 + 18 + 4 * 6) / 68 and (68 + 26 + 26 + 24) / 68).
TEST(SahBuilder, AreaWeightsChooseTheSplitsAndTheCostStaysPlain) {
  const std::vector<Box3f> boxes{{{0, 0, 0}, {1, 1, 1}}, {{0, 0, 5}, {1, 1, 6}}, {{3, 0, 0}, {4, 1, 1}}, {{3, 0, 5}, {4, 1, 6}}};
  const auto c = box_centers(boxes);
  for (const Named& b : kBuilders)
    for (const bool longest : {true, false}) {  // (binned: the small node swept along one axis, or all three)
    SCOPED_TRACE(std::string(b.name) + (longest ? " longest axis" : " all axes"));
    BuildConfig cfg;
    cfg.max_leaf_size = 1;
    cfg.small_nodes_longest_axis = longest;
    const Bvh plain = b.fn({boxes, c, {}}, cfg);
    cfg.area_weights = {0.01f, 0.01f, 1.0f};
    const Bvh along_z = b.fn({boxes, c, {}}, cfg);
    // (rays from a point far along z see the same: BuildConfig::area_eye, which replaces the weights)
    BuildConfig eye_cfg = cfg;
    eye_cfg.area_weights = {1.0f, 1.0f, 1.0f};
    eye_cfg.area_eye = Vec3f{2.0f, 0.5f, 1e4f};
    const Bvh from_far = b.fn({boxes, c, {}}, eye_cfg);
    EXPECT_EQ(from_far.prim_order, along_z.prim_order);
    EXPECT_EQ(from_far.cost, along_z.cost);
    for (const Bvh* t : {&plain, &along_z, &from_far}) {
      expect_valid(*t, boxes, cfg);
      ASSERT_EQ(t->nodes.size(), 7u);
      EXPECT_DOUBLE_EQ(sah_cost(*t, boxes, {}, cfg.cost), t->cost);
    }
    EXPECT_DOUBLE_EQ(plain.cost, 128.0 / 68.0);
    EXPECT_DOUBLE_EQ(along_z.cost, 144.0 / 68.0);
    // The root's first child holds prim_order[0, 2): {0, 2} (across z) or {0, 1} (across x).
    auto first_pair = [](const Bvh& t) {
    return std::make_pair(std::min(t.prim_order[0], t.prim_order[1]), std::max(t.prim_order[0], t.prim_order[1]));
  };
    EXPECT_EQ(first_pair(plain), std::make_pair(0u, 2u));
    EXPECT_EQ(first_pair(along_z), std::make_pair(0u, 1u));
    EXPECT_EQ(plain.nodes[1].bounds, (Box3f{{0, 0, 0}, {4, 1, 1}}));
    EXPECT_EQ(along_z.nodes[1].bounds, (Box3f{{0, 0, 0}, {1, 1, 6}}));
    }
}

// The same four corners, each a stack of five unit boxes along y (20 boxes: the binned builder
// bins the root, on all three axes). Sums of child area times count: plain, across z 2 * 58 * 10
// against across x 2 * 82 * 10 (and every cut across y dearer); with weights (0.01, 0.01, 1),
// across x 2 * (2 * 5.36) * 10 against across z 2 * (2 * 20.09) * 10, a cut across y at k
// boxes up at least 2 * 280.9 (k = 1). And the binned builder's float half areas with the
// weights are Box3f::weighted_area's halves.
TEST(SahBuilder, AreaWeightsChooseTheBinnedRootSplit) {
  std::vector<Box3f> boxes;
  for (const float x : {0.0f, 3.0f})
    for (const float z : {0.0f, 5.0f})
      for (int k = 0; k < 5; ++k) boxes.push_back({{x, float(k), z}, {x + 1, float(k + 1), z + 1}});
  const auto c = box_centers(boxes);
  for (const Named& b : kBuilders) {
    SCOPED_TRACE(b.name);
    BuildConfig cfg;
    cfg.max_leaf_size = 1;
    const Bvh plain = b.fn({boxes, c, {}}, cfg);
    cfg.area_weights = {0.01f, 0.01f, 1.0f};
    const Bvh along_z = b.fn({boxes, c, {}}, cfg);
    for (const Bvh* t : {&plain, &along_z}) {
      expect_valid(*t, boxes, cfg);
      EXPECT_NEAR(sah_cost(*t, boxes, {}, cfg.cost), t->cost, 1e-12 * t->cost);
    }
    EXPECT_EQ(plain.nodes[1].bounds, (Box3f{{0, 0, 0}, {4, 5, 1}}));
    EXPECT_EQ(along_z.nodes[1].bounds, (Box3f{{0, 0, 0}, {1, 5, 6}}));
    EXPECT_LT(plain.cost, along_z.cost);  // (the plain SAH's own tree is the cheaper under it)
  }
  const Box3f box{{-1.5f, 0.25f, 2.0f}, {2.0f, 1.0f, 7.5f}};
  for (const std::array<float, 3> w : {std::array<float, 3>{1, 1, 1}, std::array<float, 3>{0.05f, 0.7f, 1.9f}}) {
    const __m128 lo = _mm_setr_ps(box.lo[0], box.lo[1], box.lo[2], 0), hi = _mm_setr_ps(box.hi[0], box.hi[1], box.hi[2], 0);
    const double half = binned::half_area(lo, hi, binned::area_weights_of(w));
    EXPECT_NEAR(2.0 * half, box.weighted_area(w), 1e-6 * box.weighted_area(w));
  }
  EXPECT_EQ(box.weighted_area({1, 1, 1}), box.surface_area());
  EXPECT_DOUBLE_EQ(box.weighted_area({0.05f, 0.7f, 1.9f}), 2.0 * (double(1.9f) * 3.5 * 0.75 + double(0.05f) * 0.75 * 5.5 +
                                                                   double(0.7f) * 5.5 * 3.5));
}

// Box3f::area_from is about twice the solid angle the box shows the point (plus kEyeAreaIsotropic
// of its area over D^2): counted by brute force, the share of 8 million directions spread evenly
// from the point (Fibonacci) that meet the box's slabs, times 4 pi. The binned builder's float
// half_area_from is half of it. A box around the point, or a point box at it, stays finite.
TEST(SahBuilder, AreaFromAPointIsItsSolidAngle) {
  const Vec3f eye{0.5f, -1.0f, 2.0f};
  const Box3f boxes[] = {{{10.0f, 3.0f, -1.0f}, {11.5f, 4.0f, 1.0f}}, {{-2.0f, -16.0f, 1.0f}, {0.0f, -14.5f, 4.0f}}};
  const int n = 8000000;
  for (const Box3f& box : boxes) {
    std::size_t hits = 0;
    for (int i = 0; i < n; ++i) {
      const double z = 1.0 - (2.0 * i + 1.0) / n, r = std::sqrt(1.0 - z * z), phi = i * M_PI * (3.0 - std::sqrt(5.0));
      const double d[3] = {r * std::cos(phi), r * std::sin(phi), z};
      double t0 = 0.0, t1 = 1e300;
      for (int a = 0; a < 3; ++a) {
        const double ta = (box.lo[a] - eye[a]) / d[a], tb = (box.hi[a] - eye[a]) / d[a];
        t0 = std::max(t0, std::min(ta, tb)), t1 = std::min(t1, std::max(ta, tb));
      }
      hits += t0 <= t1 ? 1 : 0;
    }
    const double omega = 4.0 * M_PI * static_cast<double>(hits) / n;
    // (the isotropic share: the faces' areas sum over D^2, v to the centre, D = |v| here)
    double x = double(box.hi[0]) - box.lo[0], y = double(box.hi[1]) - box.lo[1], zz = double(box.hi[2]) - box.lo[2], d2 = 0.0;
    for (int a = 0; a < 3; ++a) d2 += std::pow(0.5 * (double(box.lo[a]) + box.hi[a]) - eye[a], 2.0);
    const double iso = kEyeAreaIsotropic * (x * y + y * zz + zz * x) / d2;
    EXPECT_NEAR(box.area_from(eye) / 2.0 - iso, omega, 0.04 * omega);
    const __m128 lo = _mm_setr_ps(box.lo[0], box.lo[1], box.lo[2], 0), hi = _mm_setr_ps(box.hi[0], box.hi[1], box.hi[2], 0);
    EXPECT_NEAR(binned::half_area_from(lo, hi, _mm_setr_ps(eye[0], eye[1], eye[2], 0)), box.area_from(eye) / 2.0,
                1e-5 * box.area_from(eye));
  }
  // By hand: box (1,2,3)-(2,4,4) from the origin: v = (1.5, 3, 3.5), D^2 = 23.5, faces xy 2,
  // yz 2, zx 1, seen 3.5*2 + 1.5*2 + 3*1 = 13, all 5. A box around the origin, (-1,-1,-1)-(1,1,3):
  // v = (0, 0, 1), D^2 = max(1, 6) = 6 (half the diagonal), faces 4, 8, 8, seen 4, all 20.
  const Vec3f o{0.0f, 0.0f, 0.0f};
  EXPECT_NEAR((Box3f{{1, 2, 3}, {2, 4, 4}}.area_from(o)), 2.0 * (13.0 / std::sqrt(23.5) + 5.0 / 64.0) / 23.5, 1e-14);
  const Box3f around{{-1, -1, -1}, {1, 1, 3}};
  EXPECT_NEAR(around.area_from(o), 2.0 * (4.0 / std::sqrt(6.0) + 20.0 / 64.0) / 6.0, 1e-14);
  EXPECT_EQ((Box3f{eye, eye}.area_from(eye)), 0.0);
  EXPECT_EQ(Box3f{}.area_from(eye), 0.0);
  // A point that is not finite is refused by both builders, naming the axis.
  const auto rb = test::random_boxes(30, 4);
  const auto rc = box_centers(rb);
  for (const Named& b : kBuilders) {
    BuildConfig cfg;
    cfg.area_eye = Vec3f{0.0f, std::nanf(""), 0.0f};
    try {
      (void)b.fn({rb, rc, {}}, cfg);
      ADD_FAILURE() << b.name << " took a NaN point";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("axis y"), std::string::npos) << e.what();
    }
  }
}

// A point beyond 2^20 root diagonals is moved in along its direction (with_near_area_eye): points at
// 2^40 and 2^100 straight up build the same tree, a valid one, in both builders (at 2^100 the
// float solid angles would overflow: every box would price 0).
TEST(SahBuilder, AFarPointIsMovedIn) {
  const auto boxes = test::random_boxes(3000, 17);
  const auto c = box_centers(boxes);
  for (const Named& b : kBuilders) {
    SCOPED_TRACE(b.name);
    BuildConfig cfg;
    cfg.area_eye = Vec3f{0.0f, 0.0f, std::ldexp(1.0f, 40)};
    const Bvh near = b.fn({boxes, c, {}}, cfg);
    cfg.area_eye = Vec3f{0.0f, 0.0f, std::ldexp(1.0f, 100)};
    const Bvh far = b.fn({boxes, c, {}}, cfg);
    expect_valid(far, boxes, cfg);
    EXPECT_EQ(near.prim_order, far.prim_order);
    EXPECT_EQ(near.nodes.size(), far.nodes.size());
    EXPECT_EQ(near.cost, far.cost);
  }
}

// Weights of any scale: only their ratios count (the builders divide by the largest), so
// (s, s, 3s) builds the tree of (1, 1, 3) for s = 2^120 (whose products with areas and counts
// would pass the float range) and 2^-120 (whose would fall into subnormals).
TEST(SahBuilder, AreaWeightsOfAnyScale) {
  const auto boxes = test::random_boxes(5000, 9);
  const auto c = box_centers(boxes);
  BuildConfig cfg;
  cfg.area_weights = {1.0f, 1.0f, 3.0f};
  const Bvh want = build_binned_sah({boxes, c, {}}, cfg);
  for (const float s : {std::ldexp(1.0f, 120), std::ldexp(1.0f, -120)}) {
    cfg.area_weights = {s, s, 3.0f * s};
    const Bvh got = build_binned_sah({boxes, c, {}}, cfg);
    EXPECT_EQ(got.prim_order, want.prim_order) << s;
    EXPECT_EQ(got.nodes.size(), want.nodes.size()) << s;
    EXPECT_EQ(got.cost, want.cost) << s;
  }
}

// Only the weights' ratios matter: doubling all three (exact in float) gives the plain tree bit
// for bit, as (1, 1, 1) given explicitly does; uneven weights give another valid tree, the same
// at one and two threads, whose cost stays the plain SAH cost recomputed independently.
TEST(SahBuilder, AreaWeightsAreScaleFreeAndDeterministic) {
  const auto boxes = test::random_boxes(60000, 5);
  const auto c = box_centers(boxes);
  auto same = [](const Bvh& a, const Bvh& b) {
    if (a.prim_order != b.prim_order || a.nodes.size() != b.nodes.size() || a.cost != b.cost) return false;
    for (std::size_t i = 0; i < a.nodes.size(); ++i)
      if (!(a.nodes[i].bounds == b.nodes[i].bounds) || a.nodes[i].index != b.nodes[i].index ||
          a.nodes[i].count != b.nodes[i].count)
        return false;
    return true;
  };
  for (const Named& b : kBuilders) {
    SCOPED_TRACE(b.name);
    const auto& sub = b.fn == &build_sweep_sah ? std::span<const Box3f>(boxes).first(3000) : std::span<const Box3f>(boxes);
    const auto sc = std::span<const Vec3f>(c).first(sub.size());
    BuildConfig cfg;
    const Bvh plain = b.fn({sub, sc, {}}, cfg);
    cfg.area_weights = {1.0f, 1.0f, 1.0f};
    EXPECT_TRUE(same(plain, b.fn({sub, sc, {}}, cfg)));
    cfg.area_weights = {2.0f, 2.0f, 2.0f};
    EXPECT_TRUE(same(plain, b.fn({sub, sc, {}}, cfg)));
    cfg.area_weights = {0.1f, 0.6f, 1.7f};
    const Bvh uneven = b.fn({sub, sc, {}}, cfg);
    expect_valid(uneven, sub, cfg);
    EXPECT_FALSE(same(plain, uneven));
    EXPECT_NEAR(sah_cost(uneven, sub, {}, cfg.cost), uneven.cost, 1e-12 * uneven.cost);  // (summed in another order)
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    EXPECT_TRUE(same(uneven, b.fn({sub, sc, {}}, cfg)));
  }
}

TEST(SahBuilder, BadAreaWeightsAreRefused) {
  const auto boxes = test::random_boxes(40, 8);
  const auto c = box_centers(boxes);
  const float bad[] = {0.0f, -1.0f, std::nanf(""), std::numeric_limits<float>::infinity()};
  for (int a = 0; a < 3; ++a)
    for (const float v : bad)
      for (const Named& b : kBuilders) {
        BuildConfig cfg;
        cfg.area_weights[a] = v;
        try {
          (void)b.fn({boxes, c, {}}, cfg);
          ADD_FAILURE() << b.name << " took area weight " << v << " on axis " << a;
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find(std::string("axis ") + "xyz"[a]), std::string::npos) << e.what();
        }
      }
}

}  // namespace
}  // namespace ptc::bvh
