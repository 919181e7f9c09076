// What the tracer reads (TraceData): a BVH (built 4-wide, walked as its 8-wide regrouping) whose
// leaves refer to SIMD blocks of four triangles, the same layout for triangle and cluster scenes,
// and its self-check validate().
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bvh/aligned.h"
#include "bvh/box.h"
#include "bvh/wide_bvh.h"

namespace ptc::bvh {

/// Four triangles in structure-of-arrays form: v[corner][axis][lane], 144 bytes. Unused lanes
/// hold NaN corners, which every comparison of the kernel rejects.
struct alignas(16) TriBlock {
  /// Uninitialised: the fills write every value (padding lanes too), and zeroing a scene's
  /// blocks first (520 MB at 13.3M triangles) was a pass over memory of its own.
  TriBlock() {}  // NOLINT: not = default, which would zero the blocks in resize()
  float v[3][3][4];
};

/// Triangles in consecutive blocks [first_block, first_block + block_count) holding
/// triangle_count triangles (padding lanes may be in any block).
struct LeafRange {
  std::uint32_t first_block = 0;
  std::uint32_t block_count = 0;
  std::uint32_t triangle_count = 0;
};

/// Slots of a TableGroup: vertices and triangles.
inline constexpr int kTableSlots = 32;
/// Tests of eight triangles in a TableGroup (the AVX-512VL kernel's unit).
inline constexpr int kTableTests = kTableSlots / 8;

/// The chunks of slots a TableGroup's test of eight reads (TableGroup::pair): the even chunk
/// [0, 8) or [16, 24) and the odd chunk [8, 16) or [24, 32), as first slots.
[[nodiscard]] constexpr int table_even_chunk(std::uint8_t pair) { return pair & 1 ? 16 : 0; }
[[nodiscard]] constexpr int table_odd_chunk(std::uint8_t pair) { return pair & 2 ? 24 : 8; }

/// Up to 32 triangles of one cluster on up to 32 distinct vertices, 512 bytes (the "tables" leaf
/// format, LeafFormat::Tables): the vertices in the trace frame as rows v[axis][slot], written
/// every frame, and each triangle's corners as byte slots into them, fixed per clustering. A
/// kernel takes a row of 8 or 16 triangles' corner coordinates with one permute of a table row
/// by the slots (`vpermt2ps`), where blocks take two loads a row for four triangles. The slots
/// come in four chunks of eight; the corners of each test of eight triangles (triangles
/// 8j .. 8j + 7) lie in one even and one odd chunk, `pair[j]`, so that the AVX-512VL kernel
/// permutes two 256-bit pieces of a row (the slot's bit 3 picks the piece: even chunk or odd)
/// instead of the whole 512-bit row. Test 0 always reads chunks 0 and 1 (`pair[0]` is 0, which
/// loses nothing: the chunks' labels are symmetric), so a kernel starts its loads without
/// reading the pair codes. A group of at most 16 vertices uses slots 0 .. vertices - 1;
/// in a larger one each chunk's slots in use come first in the chunk. Unused slots hold NaN;
/// triangles at or beyond `count` point at an unused slot when there is one, else at slot 0
/// (kernels mask them by `count`).
struct alignas(64) TableGroup {
  /// Uninitialised, as TriBlock (the layout writes the fixed part, the fills the rows).
  TableGroup() {}  // NOLINT: not = default
  float v[3][kTableSlots];
  std::uint8_t corner[3][kTableSlots];
  std::uint32_t count;     ///< triangles, 1 .. kTableSlots
  std::uint32_t last;      ///< 1 on the last group of its cluster, else 0
  std::uint32_t vertices;  ///< slots in use, 1 .. kTableSlots
  std::uint32_t slot_mask;           ///< bit s: slot s in use
  std::uint8_t pair[kTableTests];    ///< per test of eight: bit 0, the even chunk is [16, 24); bit 1, the odd one [24, 32)
  std::uint32_t unused[3];
};
static_assert(sizeof(TableGroup) == 512);

/// How a scene's leaves hold their triangles: SIMD blocks of four (TriBlock, 36 bytes a
/// triangle, every scene) or per-group vertex tables (TableGroup, a cluster scene's linear leaves:
/// 512 bytes a group, 27-30 bytes a triangle with the bench's clusters of 17-19 triangles).
enum class LeafFormat : std::uint8_t { Blocks, Tables };

/// Marker of "no triangle" (padding lanes, misses).
inline constexpr std::uint32_t kNoTriangle = 0xffffffffu;

/// Flag in WideNode::count of a leaf child that refers to several ranges (see TraceData).
inline constexpr std::uint32_t kIndirectLeaf = 0x80000000u;

/// The flat data of a scene, as traversal sees it. Traversal starts at wide8.root. A leaf child
/// of a wide node is either
///   direct   (count < kIndirectLeaf): `count` triangles packed in the ceil(count / 4) blocks
///            starting at block `child` (padding only in the last block);
///   indirect (count & kIndirectLeaf): the ranges ranges[child .. child + (count & ~kIndirectLeaf)).
/// Triangle scenes have direct leaves only; cluster scenes direct leaves for single clusters (or
/// single blocks) and indirect ones for leaves of several clusters.
/// With LeafFormat::Tables (cluster scenes with linear leaves) `blocks` is empty and a leaf
/// refers to whole clusters' table groups instead: a direct leaf to the groups from `child` up
/// to the first one marked `last`, `count` being their triangles; a LeafRange reads as first
/// group, group count and triangle count; triangle_ids holds kTableSlots ids per group (slot i:
/// the group's triangle i, kNoTriangle at or beyond its count).
struct TraceData {
  /// The 4-wide tree a TriangleScene builds and collapses; empty for a ClusterScene, which makes
  /// its 8-wide nodes without one per frame (its fixed subtrees are refitted in `wide8`, its top
  /// collapsed straight into it).
  WideBvh wide;
  /// The 4-wide tree regrouped into 8-wide nodes (regroup_to_8), with the same leaf children
  /// (a ClusterScene makes the same nodes without storing the 4-wide tree): what the tracer
  /// walks (single rays and packets). The scenes make it with every update.
  WideBvh8 wide8;
  std::vector<LeafRange> ranges;
  AlignedVector<TriBlock> blocks;
  AlignedVector<std::uint32_t> triangle_ids;  ///< 4 per block (kTableSlots per group): mesh triangle id or kNoTriangle
  LeafFormat format = LeafFormat::Blocks;
  AlignedVector<TableGroup> tables;  ///< LeafFormat::Tables: the groups, cluster by cluster
  Vec3 origin = Vec3::Zero();                 ///< the trace frame's origin (box.h, FrameMap)
  double scale = 1.0;                         ///< the trace frame's scale, a power of two (FrameMap)

  [[nodiscard]] FrameMap frame() const { return {origin, scale}; }
};

/// How full a scene's leaves are (ptc bench reports it for the cluster BVH): the format, its
/// units (blocks, or table groups), the triangles in them, the groups' vertex slots in use (0
/// for blocks), and the lanes their tests take: 4 a block, and a group's triangles in runs of 8
/// (the AVX-512VL test).
struct LeafShape {
  LeafFormat format = LeafFormat::Blocks;
  std::size_t units = 0, triangles = 0, vertices = 0, lanes = 0;
};
[[nodiscard]] LeafShape leaf_shape(const TraceData& d);

/// Bytes of a clustering's linear leaves in either format, as LeafFormatChoice::Auto estimates
/// them before any layout (estimate_leaf_bytes, leaf_tables.h): blocks exactly (144 bytes per
/// four triangles of a cluster, rounded up), tables at their least (512 bytes per group, a
/// cluster taking at least ceil(max(triangles, distinct vertices) / 32) groups; the layout may
/// need more).
struct LeafBytes {
  std::uint64_t blocks = 0, tables = 0;
};

/// Checks of the flat data (tests call it on every scene), of `wide` (when not empty) and of
/// `wide8` alike (`wide8` present whenever `wide` is): every node reachable from the root exactly once (a
/// tree) and none deeper than the tree's `depth`, every leaf child's ranges inside `ranges` and
/// blocks inside `blocks`,
/// every mesh triangle id 0 .. triangle_count-1 in exactly one used lane (padding lanes:
/// kNoTriangle and NaN corners), every inner child box containing its node's child boxes
/// (equal to their union when `exact_unions`), every leaf child box containing its triangles'
/// float corners. One line per violation (empty = valid).
[[nodiscard]] std::vector<std::string> validate(const TraceData& data, std::size_t triangle_count,
                                                bool exact_unions = true);

}  // namespace ptc::bvh
