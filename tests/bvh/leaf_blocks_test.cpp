// The leaf blocks the scenes refill every frame, lane by lane against the frame positions they
// were gathered from: padding lanes hold the NaN sentinel and kNoTriangle, used lanes the
// triangle's corners, and the per-block boxes equal a scalar min/max over the used lanes.
#include "bvh/leaf_blocks.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <random>
#include <vector>

namespace ptc::bvh {
namespace {

AlignedVector<Vec3f> random_frame_positions(std::size_t n, std::uint32_t seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<float> U(-10.0f, 10.0f);
  AlignedVector<Vec3f> fp(n);
  for (Vec3f& p : fp) p = {U(g), U(g), U(g)};
  return fp;
}

TEST(LeafBlocks, SentinelIsNanAndPadded) {
  AlignedVector<Vec3f> fp = random_frame_positions(5, 1);
  add_sentinel(fp);
  ASSERT_EQ(fp.size(), 7u);
  for (int a = 0; a < 3; ++a) EXPECT_TRUE(std::isnan(fp[5][a]));
  EXPECT_EQ(blocks_for(0), 0u);
  EXPECT_EQ(blocks_for(1), 1u);
  EXPECT_EQ(blocks_for(4), 1u);
  EXPECT_EQ(blocks_for(5), 2u);
}

TEST(LeafBlocks, LeafLanesHoldTheTrianglesCorners) {
  const std::uint32_t V = 40;
  AlignedVector<Vec3f> fp = random_frame_positions(V, 2);
  add_sentinel(fp);
  std::mt19937 g(3);
  std::vector<Tri> tris(30);
  for (Tri& t : tris) t = {static_cast<std::uint32_t>(g() % V), static_cast<std::uint32_t>(g() % V),
                           static_cast<std::uint32_t>(g() % V)};
  for (std::uint32_t n : {1u, 3u, 4u, 5u, 8u, 9u}) {
    std::vector<std::uint32_t> ids(n);
    for (std::uint32_t& id : ids) id = static_cast<std::uint32_t>(g() % tris.size());
    const std::uint32_t nb = blocks_for(n);
    std::vector<std::uint32_t> lanes(4 * nb, 12345u);
    AlignedVector<TriBlock> blocks(nb);
    fill_leaf_blocks(ids, tris, fp[0].data(), V, lanes.data(), blocks);
    fence_blocks();
    for (std::uint32_t l = 0; l < 4 * nb; ++l) {
      const TriBlock& b = blocks[l / 4];
      if (l >= n) {
        EXPECT_EQ(lanes[l], kNoTriangle);
        for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isnan(b.v[c][0][l % 4])) << "padding lane " << l;
        continue;
      }
      EXPECT_EQ(lanes[l], ids[l]);
      for (int c = 0; c < 3; ++c)
        for (int a = 0; a < 3; ++a) EXPECT_EQ(b.v[c][a][l % 4], fp[tris[ids[l]][c]][a]) << l;
    }
  }
}

// Block b's lanes against its corners read back from fp (index V, the sentinel: NaN lanes);
// `box` receives the box of its real corners.
::testing::AssertionResult block_matches(const std::vector<std::uint32_t>& corners, const AlignedVector<Vec3f>& fp,
                                         std::uint32_t V, const TriBlock& block, std::size_t b, Box3f& box) {
  box = Box3f{};
  for (int l = 0; l < 4; ++l)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = corners[12 * b + 4 * c + l];
      for (int a = 0; a < 3; ++a) {
        const float x = block.v[c][a][l];
        if (v == V ? !std::isnan(x) : x != fp[v][a])
          return ::testing::AssertionFailure() << "block " << b << " lane " << l << " corner " << c << " axis " << a;
      }
      if (v != V) box.extend(fp[v]);
    }
  return ::testing::AssertionSuccess();
}

TEST(LeafBlocks, CornerFillGivesExactBlockBoxes) {
  const std::uint32_t V = 64;
  AlignedVector<Vec3f> fp = random_frame_positions(V, 4);
  add_sentinel(fp);
  std::mt19937 g(5);
  const std::size_t nb = 9;
  std::vector<std::uint32_t> corners(12 * nb);
  for (std::size_t b = 0; b < nb; ++b)
    for (int l = 0; l < 4; ++l) {
      const bool pad = l >= 1 + static_cast<int>(b % 4);  // block b uses 1 + b % 4 lanes
      for (int c = 0; c < 3; ++c) corners[12 * b + 4 * c + l] = pad ? V : static_cast<std::uint32_t>(g() % V);
    }
  AlignedVector<TriBlock> blocks(nb);
  AlignedVector<Box3f> boxes(nb);
  fill_blocks_from_corners(corners, fp[0].data(), blocks, boxes.data());
  AlignedVector<TriBlock> again(nb);
  fill_blocks_from_corners(corners, fp[0].data(), again, nullptr);  // no boxes: the same blocks
  for (std::size_t b = 0; b < nb; ++b) {
    Box3f want, want_again;
    ASSERT_TRUE(block_matches(corners, fp, V, blocks[b], b, want));
    ASSERT_TRUE(block_matches(corners, fp, V, again[b], b, want_again));
    EXPECT_EQ(boxes[b], want) << b;
  }
}

// The fill runs in chunks of blocks on the caller's threads: with several chunks, at 1, 2 and 4
// threads, every block and box equals the one-block-at-a-time answer (corners read back).
TEST(LeafBlocks, CornerFillIsTheSameAtAnyThreadCount) {
  const std::uint32_t V = 5000;
  AlignedVector<Vec3f> fp = random_frame_positions(V, 11);
  add_sentinel(fp);
  std::mt19937 g(13);
  const std::size_t nb = 8192 * 5 + 77;  // several chunks and a short last one
  std::vector<std::uint32_t> corners(12 * nb);
  for (std::size_t b = 0; b < nb; ++b)
    for (int l = 0; l < 4; ++l) {
      const bool pad = b % 7 == 0 && l == 3;
      for (int c = 0; c < 3; ++c) corners[12 * b + 4 * c + l] = pad ? V : static_cast<std::uint32_t>(g() % V);
    }
  for (int threads : {1, 2, 4}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    AlignedVector<TriBlock> blocks(nb);
    AlignedVector<Box3f> boxes(nb);
    fill_blocks_from_corners(corners, fp[0].data(), blocks, boxes.data());
    for (std::size_t b = 0; b < nb; ++b) {
      Box3f want;
      ASSERT_TRUE(block_matches(corners, fp, V, blocks[b], b, want)) << "threads " << threads;
      ASSERT_EQ(boxes[b], want) << "threads " << threads << " block " << b;
    }
  }
}

}  // namespace
}  // namespace ptc::bvh
