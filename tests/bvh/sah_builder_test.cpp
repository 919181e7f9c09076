// Builders: degenerate inputs first, then random boxes and real meshes; every tree is checked by
// validate() (structure, containment, SAH cost recomputed independently).
#include "bvh/sah_builder.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

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

}  // namespace
}  // namespace ptc::bvh
