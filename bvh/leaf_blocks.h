// Filling the SIMD triangle blocks of a scene's leaves (TriBlock, trace_data.h) from the frame
// positions, every frame. Internal to bvh/ (the two scenes). Padding lanes read a sentinel
// vertex of NaN corners (add_sentinel), which every comparison of the kernel rejects. Blocks are
// written with streaming stores: fence_blocks() after fill_leaf_blocks, before the blocks are
// traced (fill_blocks_from_corners fences its own).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "bvh/trace_data.h"

namespace ptc::bvh {

/// Blocks of four lanes for `triangles` triangles.
[[nodiscard]] constexpr std::uint32_t blocks_for(std::uint32_t triangles) { return (triangles + 3) / 4; }

/// Appends the sentinel vertex (NaN, at index V = frame_pos.size() before the call, for padding
/// lanes) and one more element, so that a 16-byte load at any vertex stays inside the array.
void add_sentinel(AlignedVector<Vec3f>& frame_pos);

/// The blocks of one leaf of triangles `ids` (mesh triangle ids): lane_ids[0 .. 4 *
/// blocks_for(n)) receives the ids padded with kNoTriangle, blocks[0 .. blocks_for(n)) their
/// corners gathered from frame_pos (x y z per vertex; `sentinel` = the sentinel's index).
void fill_leaf_blocks(std::span<const std::uint32_t> ids, std::span<const Tri> triangles, const float* frame_pos,
                      std::uint32_t sentinel, std::uint32_t* lane_ids, std::span<TriBlock> blocks);

/// Every block b from its corner vertex indices corners[12 b + 4 c + l] (corner c of lane l;
/// the sentinel's index for padding lanes), gathered from frame_pos. boxes: null, or one entry
/// per block receiving the block's exact float box (padding lanes ignored). Runs in chunks on
/// the caller's threads (oneTBB), each fencing its own streaming stores; the same bytes at any
/// thread count. The loop runs in its VEX (AVX2) encoding when allow_avx2 and the CPU has AVX2:
/// the same instructions, hence the same bytes (a test compares them).
void fill_blocks_from_corners(std::span<const std::uint32_t> corners, const float* frame_pos, std::span<TriBlock> blocks,
                              Box3f* boxes, bool allow_avx2 = true);

/// fill_blocks_from_corners, cluster by cluster: cluster c's blocks are ranges[c] (consecutive,
/// first_block .. + block_count), and cluster_boxes[c] / centres[c] receive the box of all its
/// blocks' corners widened one unit in the last place and its centre: bit for bit
/// point_group_boxes over the clusters' corner vertices (padding lanes ignored). block_boxes:
/// null or one entry per block, as in fill_blocks_from_corners. Chunks of clusters run on the
/// caller's threads; the same bytes at any count. allow_avx2 as in fill_blocks_from_corners.
void fill_blocks_and_cluster_boxes(std::span<const std::uint32_t> corners, const float* frame_pos,
                                   std::span<TriBlock> blocks, Box3f* block_boxes, std::span<const LeafRange> ranges,
                                   Box3f* cluster_boxes, Vec3f* centres, bool allow_avx2 = true);

/// The same blocks and boxes from the lanes' triangle ids (lane_ids[4 b + l], kNoTriangle for
/// padding) and the triangles' corners, for a scene filled once (no corner indices kept).
void fill_blocks_from_lanes(std::span<const std::uint32_t> lane_ids, std::span<const Tri> triangles,
                            const float* frame_pos, std::uint32_t sentinel, std::span<TriBlock> blocks, Box3f* boxes);

/// Makes the streaming stores of the fills visible before the blocks are traced.
void fence_blocks();

}  // namespace ptc::bvh
