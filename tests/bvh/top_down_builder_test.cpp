// The top-down skeleton both SAH builders share, through a toy builder whose decisions the test
// controls (split cost, early leaf, forced splits; the split is the object median in the
// current order): the tree equals, node for node, the one a plain recursion with the same
// decisions builds (the independent answer), is valid, and reports the SAH cost sah_cost()
// recomputes; the early-leaf and forced-split hooks are honoured.
#include "bvh/top_down_builder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <vector>

#include "bvh/sah_cost.h"
#include "bvh/validate.h"
#include "test_util.h"

namespace ptc::bvh {
namespace {

// The decisions of the toy builder, as functions of a node's range [begin, end).
struct Rules {
  std::function<double(std::uint32_t, std::uint32_t)> split_cost = [](std::uint32_t, std::uint32_t) { return 0.0; };
  std::function<bool(std::uint32_t, std::uint32_t)> leaf_by_bound = [](std::uint32_t, std::uint32_t) { return false; };
  std::function<bool(std::uint32_t, std::uint32_t)> must_split = [](std::uint32_t, std::uint32_t) { return false; };
};

class ToyBuilder {
 public:
  struct Extra {};
  using Task = TopDownTask<Extra>;
  struct Split {
    double cost;
    double weight;
  };
  ToyBuilder(std::span<const Box3f> boxes, std::span<const std::uint32_t> weights, const Rules& rules)
      : boxes_(boxes), weights_(weights), rules_(rules) {}

  Box3f open(Task& t) {
    ++opened;
    Box3f b;
    for (std::uint32_t i = t.begin; i < t.end; ++i) b.extend(boxes_[i]);
    return b;
  }
  bool single_primitive(const Task& t) const { return t.size() == 1; }
  bool must_split(const Task& t) const { return rules_.must_split(t.begin, t.end); }
  bool leaf_by_bound(const Task& t, double) const { return rules_.leaf_by_bound(t.begin, t.end); }
  double leaf_weight(const Task& t) const { return weight(t); }
  Split find_split(const Task& t, double, bool) {
    ++searched;
    return {rules_.split_cost(t.begin, t.end), weight(t)};
  }
  TopDownChildren<Extra> apply(const Task& t, const Split&) { return {t.size() / 2}; }

  int opened = 0, searched = 0;

 private:
  double weight(const Task& t) const {
    double w = 0.0;
    for (std::uint32_t i = t.begin; i < t.end; ++i) w += weights_.empty() ? 1.0 : weights_[i];
    return w;
  }
  std::span<const Box3f> boxes_;
  std::span<const std::uint32_t> weights_;
  const Rules& rules_;
};

// The same decisions as a recursion: node, then the first subtree, then the second.
struct Reference {
  std::span<const Box3f> boxes;
  std::span<const std::uint32_t> weights;
  const Rules& rules;
  const BuildConfig& cfg;
  std::vector<BvhNode> nodes;

  void build(std::uint32_t begin, std::uint32_t end) {
    const auto idx = static_cast<std::uint32_t>(nodes.size());
    BvhNode& n = nodes.emplace_back();
    for (std::uint32_t i = begin; i < end; ++i) n.bounds.extend(boxes[i]);
    double w = 0.0;
    for (std::uint32_t i = begin; i < end; ++i) w += weights.empty() ? 1.0 : weights[i];
    const std::uint32_t size = end - begin;
    const bool must = size > cfg.max_leaf_size || rules.must_split(begin, end);
    const bool leaf = size == 1 || (!must && (rules.leaf_by_bound(begin, end) ||
                                               cfg.cost.intersection * w <= rules.split_cost(begin, end)));
    if (leaf) {
      nodes[idx].index = begin, nodes[idx].count = size;
      return;
    }
    build(begin, begin + size / 2);
    nodes[idx].index = static_cast<std::uint32_t>(nodes.size());
    build(begin + size / 2, end);
  }
};

struct Built {
  Bvh bvh;
  int opened = 0, searched = 0;
};

Built build(std::span<const Box3f> boxes, std::span<const std::uint32_t> weights, const Rules& rules,
            const BuildConfig& cfg) {
  Built r;
  const auto n = static_cast<std::uint32_t>(boxes.size());
  r.bvh.prim_order.resize(n);
  std::iota(r.bvh.prim_order.begin(), r.bvh.prim_order.end(), 0u);  // the toy builder reorders nothing
  ToyBuilder b(boxes, weights, rules);
  std::vector<ToyBuilder::Task> stack;
  build_top_down(b, cfg, {{}, 0, n}, stack, r.bvh);
  r.opened = b.opened, r.searched = b.searched;
  return r;
}

void expect_same_as_reference(std::span<const Box3f> boxes, std::span<const std::uint32_t> weights,
                              const Rules& rules, const BuildConfig& cfg) {
  const Built got = build(boxes, weights, rules, cfg);
  Reference ref{boxes, weights, rules, cfg, {}};
  ref.build(0, static_cast<std::uint32_t>(boxes.size()));
  ASSERT_EQ(got.bvh.nodes.size(), ref.nodes.size());
  for (std::size_t i = 0; i < ref.nodes.size(); ++i) {
    EXPECT_EQ(got.bvh.nodes[i].bounds, ref.nodes[i].bounds) << i;
    EXPECT_EQ(got.bvh.nodes[i].index, ref.nodes[i].index) << i;
    EXPECT_EQ(got.bvh.nodes[i].count, ref.nodes[i].count) << i;
  }
  EXPECT_EQ(got.opened, static_cast<int>(ref.nodes.size()));  // every node opened once
  ValidateOptions opt;
  opt.weights = weights;
  opt.model = cfg.cost;
  const auto issues = validate(got.bvh, boxes, opt);  // (includes the cost against sah_cost())
  EXPECT_TRUE(issues.empty()) << test::joined(issues);
}

TEST(TopDownBuilder, OnePrimitiveIsOneLeafWithoutSearch) {
  const std::vector<Box3f> boxes{{{0, 0, 0}, {1, 2, 3}}};
  const Built b = build(boxes, {}, Rules{}, BuildConfig{});
  ASSERT_EQ(b.bvh.nodes.size(), 1u);
  EXPECT_EQ(b.bvh.nodes[0].count, 1u);
  EXPECT_EQ(b.searched, 0);
  EXPECT_DOUBLE_EQ(b.bvh.cost, 1.0);
}

TEST(TopDownBuilder, CheapSplitsGoDownToSinglePrimitives) {
  const std::vector<Box3f> boxes = test::random_boxes(37, 3);
  BuildConfig cfg;
  cfg.max_leaf_size = 8;
  expect_same_as_reference(boxes, {}, Rules{}, cfg);  // split cost 0 < every leaf cost
  const Built b = build(boxes, {}, Rules{}, cfg);
  for (const BvhNode& n : b.bvh.nodes)
    if (n.is_leaf()) {
      EXPECT_EQ(n.count, 1u);
    }
}

TEST(TopDownBuilder, NoSplitBelowMaxLeafSizeWhenNoneIsCheaper) {
  const std::vector<Box3f> boxes = test::random_boxes(100, 4);
  Rules never;
  never.split_cost = [](std::uint32_t, std::uint32_t) { return std::numeric_limits<double>::infinity(); };
  for (std::uint32_t leaf : {1u, 3u, 8u, 100u}) {
    BuildConfig cfg;
    cfg.max_leaf_size = leaf;
    SCOPED_TRACE(leaf);
    expect_same_as_reference(boxes, {}, never, cfg);
    const Built b = build(boxes, {}, never, cfg);
    for (const BvhNode& n : b.bvh.nodes)  // leaves only where the size allows; inner nodes above it
      if (n.is_leaf()) {
        EXPECT_LE(n.count, leaf);
      }
    if (leaf == 100) {
      EXPECT_EQ(b.bvh.nodes.size(), 1u);
    }
  }
}

TEST(TopDownBuilder, LeafDecisionWeighsTheLeafCostAgainstTheSplit) {
  // Weighted primitives, split cost = 2.5 everywhere: a node becomes a leaf iff
  // intersection * W(P) <= 2.5 (within max_leaf_size).
  const std::vector<Box3f> boxes = test::random_boxes(64, 5);
  std::vector<std::uint32_t> w(boxes.size());
  for (std::size_t i = 0; i < w.size(); ++i) w[i] = 1 + static_cast<std::uint32_t>(i % 3);
  Rules r;
  r.split_cost = [](std::uint32_t, std::uint32_t) { return 2.5; };
  BuildConfig cfg;
  cfg.max_leaf_size = 16;
  cfg.cost = {1.0, 0.5};
  expect_same_as_reference(boxes, w, r, cfg);
  const Built b = build(boxes, w, r, cfg);
  for (const BvhNode& n : b.bvh.nodes) {
    double wt = 0.0;
    for (std::uint32_t i = 0; i < (n.is_leaf() ? n.count : 0); ++i) wt += w[n.index + i];
    if (n.is_leaf() && n.count > 1) {
      EXPECT_LE(0.5 * wt, 2.5);
    }
  }
}

TEST(TopDownBuilder, EarlyLeafSkipsTheSearchAndForcedSplitsOverrideIt) {
  const std::vector<Box3f> boxes = test::random_boxes(50, 6);
  BuildConfig cfg;
  cfg.max_leaf_size = 50;
  Rules early;
  early.leaf_by_bound = [](std::uint32_t, std::uint32_t) { return true; };
  const Built b = build(boxes, {}, early, cfg);
  EXPECT_EQ(b.bvh.nodes.size(), 1u);
  EXPECT_EQ(b.searched, 0);
  // A builder's forced split (the binned builder's group ranges) wins over the early leaf and
  // over max_leaf_size: ranges of more than 5 items are always split.
  Rules forced = early;
  forced.must_split = [](std::uint32_t begin, std::uint32_t end) { return end - begin > 5; };
  expect_same_as_reference(boxes, {}, forced, cfg);
  const Built f = build(boxes, {}, forced, cfg);
  for (const BvhNode& n : f.bvh.nodes)
    if (n.is_leaf()) {
      EXPECT_LE(n.count, 5u);
    }
}

TEST(TopDownBuilder, MixedDecisionsOnDegenerateBoxes) {
  // Points and repeated boxes (zero-area nodes: the cost falls back to counts), decisions that
  // depend on the range.
  std::vector<Box3f> boxes(41, Box3f{{1, 1, 1}, {1, 1, 1}});
  for (std::size_t i = 0; i < boxes.size(); i += 3) boxes[i] = {{0, 0, 0}, {2, 2, 2}};
  Rules r;
  r.split_cost = [](std::uint32_t begin, std::uint32_t end) { return (begin % 2) ? 0.0 : 1.0 + 0.1 * (end - begin); };
  r.leaf_by_bound = [](std::uint32_t begin, std::uint32_t end) { return end - begin == 3 && begin % 4 == 0; };
  for (std::uint32_t leaf : {1u, 2u, 4u, 7u}) {
    BuildConfig cfg;
    cfg.max_leaf_size = leaf;
    SCOPED_TRACE(leaf);
    expect_same_as_reference(boxes, {}, r, cfg);
  }
  std::vector<Box3f> points(9, Box3f{{3, 3, 3}, {3, 3, 3}});
  expect_same_as_reference(points, {}, Rules{}, BuildConfig{});
}

}  // namespace
}  // namespace ptc::bvh
