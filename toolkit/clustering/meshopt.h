// meshoptimizer's meshlet builder as a clustering baseline: meshopt_buildMeshlets of
// meshoptimizer 0.18 (Debian 12), greedy growth that prefers triangles adding no new vertex, then
// a distance score, jumping to the nearest unused triangle (kd-tree) when the meshlet has no
// neighbour left. Meshlets need not be edge-connected (the jump, and vertex-only adjacency), so
// split_disconnected restores the connectivity invariant of validate().
//
// Mapping of the configuration onto meshoptimizer 0.18's limits (its build aborts on an assert
// outside them, so they are checked here first):
// - max_vertices = config.max_count, must be in [3, 255] (0.18: "max_vertices <= 255 - not 256");
// - max_triangles = config.max_triangles, or 2 * max_count when 0; must then be in [4, 512] and is
//   rounded DOWN to a multiple of 4 (0.18 asserts max_triangles % 4 == 0 because meshlet index
//   data is 4-byte aligned). Rounding down keeps the requested limit a hard upper bound: a request
//   of 50 gives clusters of at most 48 triangles.
// Anything else throws std::invalid_argument naming the value and the range.
//
// Other choices:
// - cone_weight = 0: no cone-culling term; the clusters are for ray tracing, not backface culling.
// - Positions are converted to float after moving the mesh's box center to the origin and scaling
//   its largest extent to 1 (a similarity: meshoptimizer's score compares distances with a radius
//   derived from the mean triangle area, so it is scale-free up to rounding). This keeps far-away
//   (1e7 offset, 1e-3 features) and tiny (1e-30) meshes in float range and precision.
// - Triangle ids: meshlets store corners as local vertex indices, not input triangle ids. The
//   meshlet triangle (a, b, c) is mapped back through a map from the sorted vertex triple to the
//   ascending list of input triangles with that vertex set, taking the smallest one not yet taken
//   (duplicates with the same vertex set, in either orientation, are interchangeable: same vertices,
//   same edges). Measured on 0.18: degenerate triangles (repeated indices, zero area) and duplicate
//   triangles are all emitted. Any input triangle that is not emitted all the same (future versions
//   or pathological inputs) becomes a cluster of its own, so every triangle ends up in exactly one
//   cluster.
// - The empty mesh gives the empty clustering (0.18 asserts on an empty index buffer).
//
// What split_disconnected adds (measured, max_count 50 -> 50 vertices / 100 triangles): armadillo
// (52k triangles) 733 meshlets -> 898 clusters (+165, +23%); elephant (5.6k) 77 -> 93 (+16).
// Not invariant under rotation (the start corner and the kd-tree are axis-aligned).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

/// The limits passed to meshopt_buildMeshlets (see the file comment); they are also the limits
/// validate() can check on the result. Throws std::invalid_argument when out of range.
[[nodiscard]] ClusterLimits meshopt_limits(const ClusterConfig& config);

/// Per input triangle, the index of the meshlet holding it; triangles in no meshlet get labels
/// meshlet_count, meshlet_count + 1, ... in index order. meshlet m holds the vertex triples
/// meshlet_triangles[meshlet_offsets[m] .. meshlet_offsets[m + 1]). Throws std::logic_error when a
/// meshlet triangle is not an input triangle, or more meshlet triangles than input triangles share
/// a vertex set (that would be a meshoptimizer bug), and std::invalid_argument on bad offsets.
[[nodiscard]] std::vector<std::uint32_t> meshlet_labels(std::span<const Tri> triangles,
                                                        std::span<const std::uint32_t> meshlet_offsets,
                                                        std::span<const Tri> meshlet_triangles);

/// The meshlets as clusters, before split_disconnected (every triangle once, within the limits,
/// not necessarily connected). Only positions and triangles of `mesh` are used.
[[nodiscard]] Clustering meshopt_meshlets(const Mesh& mesh, const ClusterConfig& config);

/// meshopt_meshlets followed by split_disconnected: passes validate() with meshopt_limits(config).
/// Deterministic.
[[nodiscard]] Clustering meshopt_clusters(const Mesh& mesh, const ClusterConfig& config);

}  // namespace ptc
