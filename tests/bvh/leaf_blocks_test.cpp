// The leaf blocks the scenes refill every frame, lane by lane against the frame positions they
// were gathered from: padding lanes hold the NaN sentinel and kNoTriangle, used lanes the
// triangle's corners, and the per-block boxes equal a scalar min/max over the used lanes.
#include "bvh/leaf_blocks.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <string>
#include <random>
#include <vector>

#include "test_util.h"

namespace ptc::bvh {
namespace {

using test::random_frame_positions;

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
  // (and both encodings of the loop: allow_avx2 false is the SSE2 one)
  for (const auto& [threads, avx2] : {std::pair{1, true}, {2, true}, {4, true}, {1, false}, {2, false}}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    AlignedVector<TriBlock> blocks(nb);
    AlignedVector<Box3f> boxes(nb);
    fill_blocks_from_corners(corners, fp[0].data(), blocks, boxes.data(), avx2);
    const std::string what = "threads " + std::to_string(threads) + (avx2 ? "" : " sse2");
    for (std::size_t b = 0; b < nb; ++b) {
      Box3f want;
      ASSERT_TRUE(block_matches(corners, fp, V, blocks[b], b, want)) << what;
      ASSERT_EQ(boxes[b], want) << what << " block " << b;
    }
  }
}

// The fill cluster by cluster (ClusterScene's update on one thread): the same blocks and block
// boxes as fill_blocks_from_corners, and per cluster the box of its corners widened one ulp
// outwards and its centre, against a brute-force box of the corners read back (padding lanes
// ignored); clusters of one block, of padded blocks, of many blocks, with +-0, huge and tiny
// coordinates; several chunks of clusters, at 1, 2 and 4 threads, in both encodings of the loop.
TEST(LeafBlocks, ClusterBoxesFromTheFillAreTheCornersBoxes) {
  const std::uint32_t V = 3000;
  AlignedVector<Vec3f> fp = random_frame_positions(V, 17);
  fp[0] = {0.0f, -0.0f, 0.0f}, fp[1] = {-0.0f, 0.0f, -0.0f};
  fp[2] = {3e38f, -3e38f, 1e-38f}, fp[3] = {-1e-45f, 1e-45f, 2e38f};
  add_sentinel(fp);
  std::mt19937 g(19);
  std::vector<LeafRange> ranges;
  std::uint32_t nb = 0;
  while (ranges.size() < 1024 * 3 + 5) {  // several chunks of clusters
    const auto count = static_cast<std::uint32_t>(1 + g() % 60);
    ranges.push_back({nb, blocks_for(count), count});
    nb += blocks_for(count);
  }
  std::vector<std::uint32_t> corners(12 * std::size_t{nb});
  for (const LeafRange& r : ranges) {
    const auto lo = static_cast<std::uint32_t>(g() % (V - 64));  // a cluster's vertices are near each other
    for (std::uint32_t i = 0; i < 4 * r.block_count; ++i) {
      const std::size_t b = r.first_block + i / 4, l = i % 4;
      for (int c = 0; c < 3; ++c) corners[12 * b + 4 * c + l] = i < r.triangle_count ? lo + g() % 64 : V;
    }
  }
  AlignedVector<TriBlock> want_blocks(nb);
  AlignedVector<Box3f> want_block_boxes(nb);
  fill_blocks_from_corners(corners, fp[0].data(), want_blocks, want_block_boxes.data());
  for (int threads : {1, 2, 4}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    for (const auto& [with_block_boxes, avx2] : {std::pair{true, true}, {false, true}, {true, false}}) {
      AlignedVector<TriBlock> blocks(nb);
      AlignedVector<Box3f> block_boxes(with_block_boxes ? nb : 0), boxes(ranges.size());
      AlignedVector<Vec3f> centres(ranges.size());
      fill_blocks_and_cluster_boxes(corners, fp[0].data(), blocks, with_block_boxes ? block_boxes.data() : nullptr,
                                    ranges, boxes.data(), centres.data(), avx2);
      const std::string what = "threads " + std::to_string(threads) + (with_block_boxes ? " with" : " without") +
                               " block boxes" + (avx2 ? "" : " sse2");
      for (std::uint32_t b = 0; b < nb; ++b) {
        ASSERT_EQ(std::memcmp(&blocks[b], &want_blocks[b], sizeof(TriBlock)), 0) << what << " block " << b;
        if (with_block_boxes) {
          ASSERT_EQ(block_boxes[b], want_block_boxes[b]) << what << " block " << b;
        }
      }
      for (std::size_t c = 0; c < ranges.size(); ++c) {
        std::vector<std::uint32_t> vs;
        const LeafRange& r = ranges[c];
        for (std::uint32_t i = 0; i < r.triangle_count; ++i)
          for (int k = 0; k < 3; ++k) vs.push_back(corners[12 * (r.first_block + i / 4) + 4 * k + i % 4]);
        Box3f want;
        for (std::uint32_t v : vs) want.extend(fp[v]);
        for (int a = 0; a < 3; ++a) want.lo[a] = next_below(want.lo[a]), want.hi[a] = next_above(want.hi[a]);
        ASSERT_EQ(boxes[c], want) << what << " cluster " << c;
        ASSERT_EQ(centres[c], want.center()) << what << " cluster " << c;
      }
    }
  }
}

}  // namespace
}  // namespace ptc::bvh
