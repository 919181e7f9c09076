// The per-group vertex tables of LeafFormat::Tables (TableGroup, trace_data.h): each cluster's
// triangles in groups of at most 32 triangles on at most 32 distinct vertices, laid out once per
// clustering, and the per-frame fill of the groups' vertex rows. Internal to bvh/ (the cluster
// scene). On the armadillo subdivided twice clustered at MaxCount 32 (832k triangles, clusters of
// 17 triangles on average) the 49.2k groups are 25.2 MB, of which the fill writes at most 18.9 MB
// a frame (half the rows of a group of at most 16 vertices), against about 33 MB of blocks.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "bvh/trace_data.h"

namespace ptc::bvh {

/// What the fill needs, made once per clustering (make_table_layout).
struct TableLayout {
  /// Cluster c's groups are [group_offsets[c], group_offsets[c + 1]); size clusters + 1.
  std::vector<std::uint32_t> group_offsets;
  /// kTableSlots per group: the frame-position index of each vertex slot (the NaN sentinel's
  /// index for unused slots).
  AlignedVector<std::uint32_t> slot_vertices;
  /// Per group, 1 when it uses slots 16-31 (chunks 2 or 3), 0 when only 0-15: the fill then writes
  /// only the first half of each row and reads only the first half of the group's slot_vertices.
  std::vector<std::uint8_t> wide;
  /// The NaN sentinel's index (make_table_layout's `sentinel`).
  std::uint32_t sentinel = 0;

  [[nodiscard]] std::size_t group_count() const { return slot_vertices.size() / kTableSlots; }
};

/// The groups of every cluster, from the block layout: cluster c's triangles are the used lanes
/// of its blocks ranges[c] (lane_ids[4 b + l], kNoTriangle for padding) in lane order, with
/// corner vertex indices corners[12 b + 4 k + l] (frame-position indices, as
/// fill_blocks_from_corners reads them); `sentinel` is the NaN vertex's index. A group must fit
/// its chunks (TableGroup): at most 32 triangles on at most 32 vertices, and the vertices of each
/// test of eight in one even and one odd chunk of eight slots. A cluster that fits is one group
/// in lane order. Otherwise greedy, in lane order: a group takes, among the next 64 triangles of
/// its cluster not yet placed, the one that adds the fewest vertices it does not hold yet (the
/// earliest on ties), until it has 32 triangles or none fits in 32 vertices; then the triangles
/// it took last go back, one at a time, until its tests fit their chunks. A group of at most 16
/// vertices numbers its slots in the order the vertices were first taken; a larger one takes
/// the first combination of chunk pairs that admits its vertices (chunk_fit in leaf_tables.cpp),
/// each chunk's vertices in that order from the chunk's first slot. Writes the groups' fixed
/// parts (corner slots, count, last, vertices, slot mask, chunk pairs; the rows NaN) into
/// `groups` and their triangle ids (kTableSlots a group) into `ids`. Deterministic: the same
/// layout at any thread count. Throws std::invalid_argument when the spans disagree in size. A
/// triangle soup (no shared vertices) gets groups of five triangles: eight would need 24 slots.
[[nodiscard]] TableLayout make_table_layout(std::span<const LeafRange> ranges, std::span<const std::uint32_t> lane_ids,
                                            std::span<const std::uint32_t> corners, std::uint32_t sentinel,
                                            AlignedVector<TableGroup>& groups, AlignedVector<std::uint32_t>& ids);

/// LeafBytes (trace_data.h) of clusters: cluster c has triangles [tri_offsets[c], tri_offsets[c + 1]) and vertices [vertex_offsets[c],
/// vertex_offsets[c + 1]) (its distinct vertices); both lists of offsets have clusters + 1
/// entries (std::invalid_argument otherwise, or when they decrease).
[[nodiscard]] LeafBytes estimate_leaf_bytes(std::span<const std::uint32_t> tri_offsets,
                                            std::span<const std::uint32_t> vertex_offsets);
/// Whether Auto picks the tables for these bytes: at most kAutoTablesMaxShare (scene_config.h)
/// of the blocks' (and some triangles at all).
[[nodiscard]] bool tables_suit(const LeafBytes& b);

/// Every group's vertex rows from the frame positions (x y z per vertex, with the sentinel and
/// one more element after the last vertex, as add_sentinel leaves them; a group of at most 16
/// vertices has only the rows' first halves written, the rest keeping the layout's NaN), in chunks of clusters
/// on the caller's threads, with streaming stores fenced per chunk; the same bytes at any thread
/// count. cluster_boxes[c] / centres[c] (either null: neither written) receive the box of the
/// cluster's vertices widened one unit in the last place and its centre: bit for bit
/// fill_blocks_and_cluster_boxes' boxes of the same clusters (the same vertices, and min and max
/// do not depend on their order). The loop runs in its VEX (AVX2) encoding when allow_avx2 and the
/// CPU has AVX2: the same instructions, hence the same bytes (a test compares them).
void fill_tables(const TableLayout& layout, const float* frame_pos, std::span<TableGroup> groups, Box3f* cluster_boxes,
                 Vec3f* centres, bool allow_avx2 = true);

}  // namespace ptc::bvh
