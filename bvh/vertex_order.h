// Vertex orders for the per-frame cluster box update (once per clustering): the vertices
// renumbered in first-touch order over the clusters' vertex lists, so that a cluster's own
// vertices are contiguous (GroupVertexOrder, the gather mode of ClusterScene), and, for a mesh
// already renumbered that way (cluster_vertex_order), the runs of input vertices every cluster
// owns (GroupRuns), over which one fused pass converts the positions into the trace frame and
// computes the cluster boxes (frame_positions_and_boxes, SSE2 and AVX2). The boxes are those of
// box.h's point_group_boxes, bit for bit.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "bvh/box.h"

namespace ptc::bvh {

/// The vertex numbering a per-frame comparison runs on: Clusters = renumbered once with
/// cluster_vertex_order (every cluster's own vertices consecutive: the cluster path streams),
/// Input = the file's order (the cluster path gathers per frame).
enum class VertexOrder { Clusters, Input };
/// "clusters", "input".
[[nodiscard]] const char* to_string(VertexOrder o);
[[nodiscard]] std::optional<VertexOrder> parse_vertex_order(std::string_view s);


/// A vertex numbering for per-frame group boxes (once per clustering): vertices renumbered in
/// first-touch order over the groups' index lists, so that group g owns the contiguous new
/// indices [own_offsets[g], own_offsets[g+1]) (the vertices it touches first) and lists the
/// vertices it shares with earlier groups in shared[shared_offsets[g] .. shared_offsets[g+1])
/// (new indices, each once per group). Vertices no group references follow in their original
/// order, so every vertex has a new index: to_old[new] = old, to_new[old] = new.
struct GroupVertexOrder {
  std::vector<std::uint32_t> to_old, to_new;
  std::vector<std::uint32_t> own_offsets, shared_offsets, shared;
};
/// Throws std::invalid_argument when an index is >= vertex_count or offsets are not ascending
/// from 0 to indices.size().
[[nodiscard]] GroupVertexOrder first_touch_order(std::size_t vertex_count, std::span<const std::uint32_t> offsets,
                                                 std::span<const std::uint32_t> indices);

/// frame_positions in a new order: out[i] = to_frame(positions[to_old[i]], origin) (room for the
/// sentinel reserved as there).
void frame_positions(std::span<const Vec3> positions, std::span<const std::uint32_t> to_old, const FrameMap& origin,
                     AlignedVector<Vec3f>& out);

/// point_group_boxes(frame_pos_old, offsets, indices, out, centers), bit for bit (NaN-free
/// positions), from the positions in the order of `order` (frame_pos[new]): min/max over each
/// group's own contiguous range, then over its shared vertices. frame_pos may hold more entries
/// than vertices (sentinels): they are not read.
void point_group_boxes(std::span<const Vec3f> frame_pos, const GroupVertexOrder& order, AlignedVector<Box3f>& out,
                       AlignedVector<Vec3f>& centers);

/// The fused per-frame pass (no gather): possible when, in first-touch order over the groups,
/// every group's own vertices are consecutive INPUT indices (a mesh renumbered once by
/// cluster_vertex_order below). Group g owns input vertices [own_begin[g], own_begin[g] +
/// own_count[g]) and reads its shared vertices (owned by earlier groups) at the input indices
/// shared[shared_offsets[g] .. shared_offsets[g+1]); vertices no group lists form the ranges
/// gaps[i] = (begin, end).
struct GroupRuns {
  std::size_t vertex_count = 0;
  std::vector<std::uint32_t> own_begin, own_count, shared_offsets, shared;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> gaps;
};
/// The runs of `order` (first_touch_order's result), or nullopt when a group's own vertices are
/// not consecutive input indices.
[[nodiscard]] std::optional<GroupRuns> group_runs(const GroupVertexOrder& order);

/// A renumbering (to_old[new] = old) under which group_runs() succeeds: the first-touch order
/// over the groups, made stable within parts when part_offsets (ascending, from 0 to
/// vertex_count) are given: part p keeps the new indices [part_offsets[p], part_offsets[p+1]),
/// so that every part can renumber its own vertices (a scene of several meshes). A group that
/// spans parts may then lose the property (ClusterScene falls back to its gather). Throws
/// std::invalid_argument like first_touch_order, and for bad part offsets.
[[nodiscard]] std::vector<std::uint32_t> cluster_vertex_order(std::size_t vertex_count,
                                                              std::span<const std::uint32_t> offsets,
                                                              std::span<const std::uint32_t> indices,
                                                              std::span<const std::size_t> part_offsets = {});

/// out_pos[v] = to_frame(positions[v], frame) for every vertex v (out_pos.size() >= positions.size(),
/// else std::invalid_argument), in one streaming pass (AVX2 when allow_avx2 and the CPU has it,
/// writing with streaming stores, fenced; the same bits either way); a position that is not
/// finite in the trace frame throws std::invalid_argument (check_finite's message) after the pass.
void frame_positions_streamed(std::span<const Vec3> positions, const FrameMap& frame, std::span<Vec3f> out_pos,
                              bool allow_avx2 = true);

/// One pass per frame: out_pos[v] = to_frame(positions[v], origin) for every input vertex v
/// (positions.size() == runs.vertex_count <= out_pos.size(), else std::invalid_argument; entries
/// past it are not touched), and the boxes and
/// centres of point_group_boxes(out_pos, offsets, indices, boxes, centers), bit for bit
/// (NaN-free positions), computed while the group's own vertices are converted. A position that
/// is not finite in the trace frame throws std::invalid_argument (check_finite's message), after
/// the pass.
/// The own ranges are converted four vertices at a time with AVX2 when the CPU has it and
/// allow_avx2 is true (the SSE2 path gives the same bits; tests compare them). Chunks of groups
/// run on the caller's threads (oneTBB): the same outputs at any thread count.
void frame_positions_and_boxes(std::span<const Vec3> positions, const FrameMap& origin, const GroupRuns& runs,
                               std::span<Vec3f> out_pos, AlignedVector<Box3f>& boxes, AlignedVector<Vec3f>& centers,
                               bool allow_avx2 = true);

}  // namespace ptc::bvh
