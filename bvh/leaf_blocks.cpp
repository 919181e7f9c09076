#include "bvh/leaf_blocks.h"

#include "bvh/box_simd.h"

#include <emmintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <limits>

namespace ptc::bvh {

namespace {

// The fills' chunks (fill_in_chunks).
constexpr std::size_t kBlocksPerTask = 8192;  // 1.2 MB of blocks
constexpr std::size_t kClustersPerTask = 1024;  // (fill_blocks_and_cluster_boxes) about 8k blocks

// The per-frame fills prefetch the first corner of the block this many blocks ahead: one
// prefetch a block took the one-thread fill at 832k from 2.46-2.54 to 2.31-2.42 ms (two a block
// or all twelve were slower; docs/tracing.md, "The fill's corner gathers").
constexpr std::size_t kPrefetchBlocks = 8;

inline void prefetch_corner(std::span<const std::uint32_t> corners, const float* fp, std::size_t b) {
  if (12 * (b + kPrefetchBlocks) < corners.size())
    _mm_prefetch(reinterpret_cast<const char*>(fp + 3 * std::size_t{corners[12 * (b + kPrefetchBlocks)]}), _MM_HINT_T0);
}

// One block from its corner vertex indices v[corner][lane]: corners gathered with one 16-byte
// load per vertex and transposed to SoA. When `box` is given it receives the block's exact
// float box (NaN lanes ignored: _mm_min_ps(x, acc) returns acc for a NaN x).
// The rows' min and max are also taken into acc_lo / acc_hi (x y z rows of four lanes) when given.
inline void fill_block_corners(const std::uint32_t (&v)[3][4], const float* fp, TriBlock& out, Box3f* box,
                               __m128* acc_lo = nullptr, __m128* acc_hi = nullptr) {
  __m128 lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = _mm_set1_ps(kInf), hi[a] = _mm_set1_ps(-kInf);
  for (int c = 0; c < 3; ++c) {
    __m128 r0 = _mm_loadu_ps(fp + 3 * std::size_t(v[c][0])), r1 = _mm_loadu_ps(fp + 3 * std::size_t(v[c][1]));
    __m128 r2 = _mm_loadu_ps(fp + 3 * std::size_t(v[c][2])), r3 = _mm_loadu_ps(fp + 3 * std::size_t(v[c][3]));
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);  // r0 = x of the 4 lanes, r1 = y, r2 = z
    // Streaming stores: the blocks (tens of MB) are written once per frame and not read back by
    // this pass, so they bypass the caches instead of evicting the vertex data being gathered.
    _mm_stream_ps(out.v[c][0], r0), _mm_stream_ps(out.v[c][1], r1), _mm_stream_ps(out.v[c][2], r2);
    if (box) {
      lo[0] = _mm_min_ps(r0, lo[0]), lo[1] = _mm_min_ps(r1, lo[1]), lo[2] = _mm_min_ps(r2, lo[2]);
      hi[0] = _mm_max_ps(r0, hi[0]), hi[1] = _mm_max_ps(r1, hi[1]), hi[2] = _mm_max_ps(r2, hi[2]);
    }
    if (acc_lo) {
      acc_lo[0] = _mm_min_ps(r0, acc_lo[0]), acc_lo[1] = _mm_min_ps(r1, acc_lo[1]), acc_lo[2] = _mm_min_ps(r2, acc_lo[2]);
      acc_hi[0] = _mm_max_ps(r0, acc_hi[0]), acc_hi[1] = _mm_max_ps(r1, acc_hi[1]), acc_hi[2] = _mm_max_ps(r2, acc_hi[2]);
    }
  }
  if (box) {
    for (int a = 0; a < 3; ++a) {
      __m128 l = lo[a], h = hi[a];
      l = _mm_min_ps(l, _mm_shuffle_ps(l, l, _MM_SHUFFLE(1, 0, 3, 2)));
      l = _mm_min_ps(l, _mm_shuffle_ps(l, l, _MM_SHUFFLE(2, 3, 0, 1)));
      h = _mm_max_ps(h, _mm_shuffle_ps(h, h, _MM_SHUFFLE(1, 0, 3, 2)));
      h = _mm_max_ps(h, _mm_shuffle_ps(h, h, _MM_SHUFFLE(2, 3, 0, 1)));
      box->lo[a] = _mm_cvtss_f32(l), box->hi[a] = _mm_cvtss_f32(h);
    }
  }
}

// One block from four triangle ids (kNoTriangle: padding, the sentinel's corners); its box as
// in fill_block_corners.
inline void fill_block(const std::uint32_t* ids, std::span<const Tri> tris, const float* fp, std::uint32_t sentinel,
                       TriBlock& out, Box3f* box = nullptr) {
  std::uint32_t v[3][4];
  for (int l = 0; l < 4; ++l) {
    if (ids[l] != kNoTriangle) {
      const Tri& t = tris[ids[l]];
      v[0][l] = t[0], v[1][l] = t[1], v[2][l] = t[2];
    } else {
      v[0][l] = v[1][l] = v[2][l] = sentinel;
    }
  }
  fill_block_corners(v, fp, out, box);
}

// Blocks [0, n), each by fill(b). Blocks are independent: chunks of them on the caller's threads
// (the same bytes at any count). Each chunk fences its own streaming stores, so they are visible
// once the loop returns.
template <class Fill>
void fill_in_chunks(std::size_t n, const Fill& fill) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kBlocksPerTask), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) fill(b);
    _mm_sfence();
  });
}

}  // namespace

void add_sentinel(AlignedVector<Vec3f>& fp) {
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  fp.push_back({nan, nan, nan});
  fp.push_back({0.0f, 0.0f, 0.0f});
}

void fill_leaf_blocks(std::span<const std::uint32_t> ids, std::span<const Tri> tris, const float* fp,
                      std::uint32_t sentinel, std::uint32_t* lane_ids, std::span<TriBlock> blocks) {
  const auto n = static_cast<std::uint32_t>(ids.size());
  for (std::uint32_t i = 0; i < 4 * blocks_for(n); ++i) lane_ids[i] = i < n ? ids[i] : kNoTriangle;
  for (std::uint32_t j = 0; j < blocks_for(n); ++j) fill_block(lane_ids + 4 * j, tris, fp, sentinel, blocks[j]);
}

namespace {

// The two per-frame fills from corner indices, each over its own chunk ([b0, b1) blocks, or
// [c0, c1) clusters), compiled twice: SSE2 (the x86-64 baseline) and the same instructions in
// their VEX forms (three operands: none of the register copies of the two-operand forms), picked
// at run time. The same bytes either way (a test compares them).
[[gnu::always_inline]] inline void corner_blocks(const std::uint32_t* corners, std::size_t ncorners, const float* fp,
                                                 TriBlock* blocks, Box3f* boxes, std::size_t b0, std::size_t b1) {
  const std::span<const std::uint32_t> cs(corners, ncorners);
  for (std::size_t b = b0; b < b1; ++b) {
    prefetch_corner(cs, fp, b);
    fill_block_corners(*reinterpret_cast<const std::uint32_t(*)[3][4]>(corners + 12 * b), fp, blocks[b],
                       boxes ? boxes + b : nullptr);
  }
}
[[gnu::always_inline]] inline void corner_clusters(const std::uint32_t* corners, std::size_t ncorners, const float* fp,
                                                   TriBlock* blocks, Box3f* block_boxes, const LeafRange* ranges,
                                                   Box3f* cluster_boxes, Vec3f* centres, std::size_t c0, std::size_t c1) {
  const std::span<const std::uint32_t> cs(corners, ncorners);
  for (std::size_t c = c0; c < c1; ++c) {
    __m128 lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = _mm_set1_ps(kInf), hi[a] = _mm_set1_ps(-kInf);
    const LeafRange lr = ranges[c];
    for (std::size_t b = lr.first_block; b < std::size_t{lr.first_block} + lr.block_count; ++b) {
      prefetch_corner(cs, fp, b);
      fill_block_corners(*reinterpret_cast<const std::uint32_t(*)[3][4]>(corners + 12 * b), fp, blocks[b],
                         block_boxes ? block_boxes + b : nullptr, lo, hi);
    }
    simd::fold_rows_store_widened(lo, hi, cluster_boxes[c], centres[c]);  // the four lanes' rows into one box
  }
}

using CornerBlocksFn = void (*)(const std::uint32_t*, std::size_t, const float*, TriBlock*, Box3f*, std::size_t,
                                std::size_t);
using CornerClustersFn = void (*)(const std::uint32_t*, std::size_t, const float*, TriBlock*, Box3f*, const LeafRange*,
                                  Box3f*, Vec3f*, std::size_t, std::size_t);
void corner_blocks_sse2(const std::uint32_t* corners, std::size_t n, const float* fp, TriBlock* blocks, Box3f* boxes,
                        std::size_t b0, std::size_t b1) {
  corner_blocks(corners, n, fp, blocks, boxes, b0, b1);
}
__attribute__((target("avx2"))) void corner_blocks_avx2(const std::uint32_t* corners, std::size_t n, const float* fp,
                                                        TriBlock* blocks, Box3f* boxes, std::size_t b0, std::size_t b1) {
  corner_blocks(corners, n, fp, blocks, boxes, b0, b1);
}
void corner_clusters_sse2(const std::uint32_t* corners, std::size_t n, const float* fp, TriBlock* blocks,
                          Box3f* block_boxes, const LeafRange* ranges, Box3f* cluster_boxes, Vec3f* centres,
                          std::size_t c0, std::size_t c1) {
  corner_clusters(corners, n, fp, blocks, block_boxes, ranges, cluster_boxes, centres, c0, c1);
}
__attribute__((target("avx2"))) void corner_clusters_avx2(const std::uint32_t* corners, std::size_t n, const float* fp,
                                                          TriBlock* blocks, Box3f* block_boxes, const LeafRange* ranges,
                                                          Box3f* cluster_boxes, Vec3f* centres, std::size_t c0,
                                                          std::size_t c1) {
  corner_clusters(corners, n, fp, blocks, block_boxes, ranges, cluster_boxes, centres, c0, c1);
}

}  // namespace

void fill_blocks_from_corners(std::span<const std::uint32_t> corners, const float* fp, std::span<TriBlock> blocks,
                              Box3f* boxes, bool allow_avx2) {
  const CornerBlocksFn fill = allow_avx2 && simd::cpu_has_avx2() ? &corner_blocks_avx2 : &corner_blocks_sse2;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), kBlocksPerTask),
                    [&](const tbb::blocked_range<std::size_t>& r) {
    fill(corners.data(), corners.size(), fp, blocks.data(), boxes, r.begin(), r.end());
    _mm_sfence();
  });
}

void fill_blocks_and_cluster_boxes(std::span<const std::uint32_t> corners, const float* fp, std::span<TriBlock> blocks,
                                   Box3f* block_boxes, std::span<const LeafRange> ranges, Box3f* cluster_boxes,
                                   Vec3f* centres, bool allow_avx2) {
  const CornerClustersFn fill = allow_avx2 && simd::cpu_has_avx2() ? &corner_clusters_avx2 : &corner_clusters_sse2;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ranges.size(), kClustersPerTask),
                    [&](const tbb::blocked_range<std::size_t>& r) {
    fill(corners.data(), corners.size(), fp, blocks.data(), block_boxes, ranges.data(), cluster_boxes, centres,
         r.begin(), r.end());
    _mm_sfence();
  });
}

void fill_blocks_from_lanes(std::span<const std::uint32_t> lane_ids, std::span<const Tri> tris, const float* fp,
                            std::uint32_t sentinel, std::span<TriBlock> blocks, Box3f* boxes) {
  fill_in_chunks(blocks.size(), [&](std::size_t b) {
    fill_block(lane_ids.data() + 4 * b, tris, fp, sentinel, blocks[b], boxes ? boxes + b : nullptr);
  });
}

void fence_blocks() { _mm_sfence(); }

}  // namespace ptc::bvh
