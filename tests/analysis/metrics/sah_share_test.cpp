// Per-primitive shares of a BVH's SAH cost (analysis/metrics/sah_share.h): they add up to the
// cost bvh::sah_cost recomputes independently, and follow the weights and the leaf areas.
#include <gtest/gtest.h>

#include <random>

#include "analysis/metrics/sah_share.h"
#include "bvh/sah_builder.h"
#include "bvh/sah_cost.h"

namespace ptc {
namespace {

using bvh::Box3f;

std::vector<Box3f> random_boxes(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-10.0f, 10.0f), s(0.01f, 1.0f);
  std::vector<Box3f> b(n);
  for (auto& x : b) {
    const bvh::Vec3f c{u(rng), u(rng), u(rng)};
    const float h = s(rng);
    x.extend(bvh::Vec3f{c[0] - h, c[1] - h, c[2] - h});
    x.extend(bvh::Vec3f{c[0] + h, c[1] + 2 * h, c[2] + h});
  }
  return b;
}

TEST(SahShares, SumToTheTreesCostForEveryBuild) {
  for (std::size_t n : {1u, 2u, 7u, 300u}) {
    const auto boxes = random_boxes(n, n);
    std::vector<bvh::Vec3f> centroids;
    for (const auto& b : boxes) centroids.push_back(b.center());
    std::vector<std::uint32_t> weights(n);
    for (std::size_t i = 0; i < n; ++i) weights[i] = 1 + std::uint32_t(i % 9);
    bvh::BuildConfig cfg;
    cfg.cost = {1.0, 0.3};
    cfg.max_leaf_size = 4;
    for (bool weighted : {false, true}) {
      const std::span<const std::uint32_t> w = weighted ? std::span<const std::uint32_t>(weights) : std::span<const std::uint32_t>{};
      const bvh::Bvh t = bvh::build_binned_sah({boxes, centroids, w}, cfg);
      const SahShares s = sah_shares(t, boxes, w, cfg.cost);
      const double oracle = bvh::sah_cost(t, boxes, w, cfg.cost);
      EXPECT_NEAR(s.cost, oracle, 1e-9 * oracle) << n;
      double sum = 0, csum = 0;
      for (std::size_t p = 0; p < n; ++p) {
        EXPECT_GT(s.contribution[p], 0.0) << p;
        sum += s.share[p], csum += s.contribution[p];
      }
      EXPECT_NEAR(sum, 1.0, 1e-12) << n;
      EXPECT_NEAR(csum, oracle, 1e-9 * oracle) << n;
    }
  }
}

TEST(SahShares, OneLeafSplitsByWeightAndEmptyTreesAreEmpty) {
  const auto boxes = random_boxes(3, 5);
  bvh::Bvh t;
  bvh::BvhNode leaf;
  for (const auto& b : boxes) leaf.bounds.extend(b);
  leaf.index = 0, leaf.count = 3;
  t.nodes = {leaf};
  t.prim_order = {0, 1, 2};
  const std::vector<std::uint32_t> w{1, 2, 5};
  const SahShares s = sah_shares(t, boxes, w, {1.0, 0.5});
  EXPECT_NEAR(s.share[0], 1.0 / 8, 1e-15);
  EXPECT_NEAR(s.share[1], 2.0 / 8, 1e-15);
  EXPECT_NEAR(s.share[2], 5.0 / 8, 1e-15);
  EXPECT_NEAR(s.cost, 0.5 * 8, 1e-12);  // intersection * W, A(leaf) = A(root)
  EXPECT_EQ(sah_shares(bvh::Bvh{}, {}, {}, {}).cost, 0.0);
}

}  // namespace
}  // namespace ptc
