// Morton (Z-order) sort of triangles by their centroids: cuts a mesh into spatially compact runs
// ("Morton-ordered runs of 64-128 triangles"), e.g. as start order for clustering or as a
// per-triangle baseline. Pure functions; deterministic for a given input.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "toolkit/core/types.h"

namespace ptc {

/// Bits per axis of the Morton code (3 x 21 = 63 bits).
inline constexpr int kMortonBits = 21;

/// Interleaves the low 21 bits of x, y, z: bit i of x goes to bit 3i+2 of the code, of y to
/// 3i+1, of z to 3i (x is the most significant axis). Higher input bits are ignored.
[[nodiscard]] std::uint64_t morton_encode(std::uint32_t x, std::uint32_t y, std::uint32_t z);

/// How centroids are quantised in their bounding box [lo, hi] (extent E_a = hi_a - lo_a):
/// - Cube (default): one scale for all axes, s = 2^21 / max_a E_a, so grid cells are cubes and
///   runs stay compact on long, thin meshes;
/// - PerAxis: s_a = 2^21 / E_a per axis (the box is stretched to a cube first).
/// In both, an axis with E_a = 0 (flat along that axis, or all centroids equal) gets cell 0 (s_a = 0).
enum class MortonGrid { Cube, PerAxis };

/// Morton code of every triangle's centroid c = (p0 + p1 + p2) / 3:
///   cell_a = min(2^21 - 1, floor((c_a - lo_a) * s_a)),  code = morton_encode(cell_x, cell_y, cell_z),
/// with lo, s as described at MortonGrid. Positions must be finite. Throws std::invalid_argument
/// when a triangle refers to a position out of range. Empty input: empty result.
/// centroid_bounds: the box of the centroids when the caller has it already (ClusterTables'
/// with_sums; it must be that box, and every index in range): one pass over the triangles
/// instead of two.
[[nodiscard]] std::vector<std::uint64_t> morton_codes(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                                      MortonGrid grid = MortonGrid::Cube,
                                                      const Box3* centroid_bounds = nullptr);

/// Triangle ids 0..T-1 sorted by (morton code, id): ties keep index order, so the order is
/// deterministic. Same preconditions as morton_codes. O(T log T).
[[nodiscard]] std::vector<std::uint32_t> morton_order(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                                      MortonGrid grid = MortonGrid::Cube,
                                                      const Box3* centroid_bounds = nullptr);

}  // namespace ptc
