// Per-group vertex tables: the leaf format planned to replace the cluster scene's blocks
// (docs/tracing.md, "The vertex tables on this host"; step 1 of the plan there: the layout and
// the per-frame fill, not yet read by the tracer). Internal to bvh/.
//
// Each cluster's triangles are split into groups of at most 16 triangles that use at most 16
// distinct vertices. Per frame, a group's table holds its vertices in the trace frame as rows
// x[16] y[16] z[16] (192 bytes); its triangles' corners are fixed byte indices into the table
// (slots), written once per clustering. A kernel takes a row of 16 (or 8) triangles' corner
// coordinates with one permute of a table row by the slots. On the armadillo subdivided twice
// (832k triangles) the tables are 13.9 MB a frame and the slots 3.5 MB, against 31.6 MB of blocks.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "bvh/trace_data.h"

namespace ptc::bvh {

inline constexpr int kTableSlots = 16;

/// One group's vertices in the trace frame: v[axis][slot]. Unused slots hold the NaN sentinel.
struct alignas(64) VertexTable {
  VertexTable() {}  // NOLINT: uninitialised, as TriBlock (the fill writes every value)
  float v[3][kTableSlots];
};

/// The fixed part, made once per clustering (make_table_layout).
struct TableLayout {
  /// Cluster c's groups are [group_offsets[c], group_offsets[c + 1]); size clusters + 1.
  std::vector<std::uint32_t> group_offsets;
  /// 16 per group: the frame-position index of each slot (the sentinel for unused slots).
  AlignedVector<std::uint32_t> slot_vertices;
  /// 48 per group, [corner][lane]: the slot of corner c of the group's triangle l. Lanes at or
  /// beyond the group's triangle count point at an unused (NaN) slot when the group has one,
  /// else at slot 0: kernels mask them by the triangle count (lanes_in).
  AlignedVector<std::uint8_t> corner_slots;
  /// 16 per group: the mesh triangle id of each lane, kNoTriangle beyond the triangle count.
  AlignedVector<std::uint32_t> triangle_ids;
  /// Per group, 1..16.
  std::vector<std::uint8_t> triangle_count;

  [[nodiscard]] std::size_t group_count() const { return triangle_count.size(); }
  /// The live lanes of group g: bits 0 .. triangle_count[g] - 1.
  [[nodiscard]] std::uint32_t lanes_in(std::size_t g) const { return (1u << triangle_count[g]) - 1u; }
};

/// The groups of every cluster, from the scene's per-lane data: cluster c's triangles are the
/// used lanes of its blocks ranges[c] (lane_ids[4 b + l], kNoTriangle for padding), with corner
/// vertex indices corners[12 b + 4 k + l] (the frame-position indices fill_blocks_from_corners
/// reads); `sentinel` is the NaN vertex's index. Greedy, in each cluster's lane order: a group
/// takes, among the next 64 triangles of its cluster not yet placed, the one that adds the fewest
/// vertices it does not hold yet (the earliest on ties), until it has 16 triangles or none fits in
/// 16 vertices. Slots are numbered in the order the vertices were first taken. Deterministic (the
/// same layout at any thread count; clusters are independent). Throws std::invalid_argument when
/// the spans disagree in size.
[[nodiscard]] TableLayout make_table_layout(std::span<const LeafRange> ranges, std::span<const std::uint32_t> lane_ids,
                                            std::span<const std::uint32_t> corners, std::uint32_t sentinel);

/// Every group's table from the frame positions (x y z per vertex, with the sentinel and one more
/// element after the last vertex, as add_sentinel leaves them), in chunks of clusters on the
/// caller's threads, with streaming stores fenced per chunk. cluster_boxes[c] / centres[c]
/// (either null: neither written) receive the box of the cluster's vertices widened one unit in the last
/// place and its centre: bit for bit fill_blocks_and_cluster_boxes' boxes of the same clusters.
void fill_tables_and_cluster_boxes(const TableLayout& layout, const float* frame_pos, std::span<VertexTable> tables,
                                   Box3f* cluster_boxes, Vec3f* centres);

}  // namespace ptc::bvh
