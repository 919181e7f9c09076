// The result of every clustering algorithm: a permutation of the triangles in which each cluster
// is a contiguous range, plus each cluster's distinct vertices (flat arrays with offsets, as
// meshoptimizer's meshlets). Computed once per topology and reused by every frame; the BVH layer
// sees a cluster only as "a contiguous range of triangle indices".
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "toolkit/core/types.h"
#include "toolkit/mesh/topology.h"

namespace ptc {

struct Clustering {
  /// Triangle ids (of the input mesh) grouped by cluster: cluster c holds
  /// triangle_order[triangle_offsets[c] .. triangle_offsets[c + 1]), ascending within a cluster.
  std::vector<std::uint32_t> triangle_order;
  std::vector<std::uint32_t> triangle_offsets{0};  ///< cluster_count + 1 entries
  /// Distinct vertex ids of cluster c: vertices[vertex_offsets[c] .. vertex_offsets[c + 1]), ascending.
  std::vector<std::uint32_t> vertices;
  std::vector<std::uint32_t> vertex_offsets{0};  ///< cluster_count + 1 entries

  [[nodiscard]] std::size_t cluster_count() const { return triangle_offsets.size() - 1; }
  [[nodiscard]] std::size_t triangle_count() const { return triangle_order.size(); }
  [[nodiscard]] std::span<const std::uint32_t> triangles_of(std::size_t c) const {
    return {triangle_order.data() + triangle_offsets[c], triangle_order.data() + triangle_offsets[c + 1]};
  }
  [[nodiscard]] std::span<const std::uint32_t> vertices_of(std::size_t c) const {
    return {vertices.data() + vertex_offsets[c], vertices.data() + vertex_offsets[c + 1]};
  }
  /// Per input triangle (ids 0 .. triangle_count-1), the id of its cluster. On an invalid
  /// clustering (see validate) it does not fail: a triangle in no cluster gets kNoCluster, one in
  /// several clusters the last of them, ids out of range and ranges past the end are ignored.
  [[nodiscard]] std::vector<std::uint32_t> cluster_of_triangle() const;
};

/// "No cluster" marker of Clustering::cluster_of_triangle.
inline constexpr std::uint32_t kNoCluster = 0xffffffffu;

/// Builds a Clustering from one label per triangle (any 32-bit values). Clusters are numbered
/// densely in the order of their smallest triangle id; triangles and vertices ascending within a
/// cluster. Deterministic: equal labelings (up to renaming) give bit-identical results.
/// Throws std::invalid_argument unless labels.size() == triangles.size(). O(T log T).
[[nodiscard]] Clustering clustering_from_labels(std::span<const std::uint32_t> labels, std::span<const Tri> triangles);

/// Hard limits a clustering was made under; 0 means "no limit".
struct ClusterLimits {
  std::uint32_t max_triangles = 0;
  std::uint32_t max_vertices = 0;
};

/// Checks the invariants; returns one line per violation (empty = valid), at most `max_issues`:
/// - triangle_order is a permutation of 0 .. triangle_count-1 (every triangle in exactly one cluster);
/// - offsets are consistent, no cluster is empty;
/// - triangles are ascending within a cluster (the order documented at Clustering);
/// - each cluster's vertex list is exactly the distinct vertices of its triangles, ascending;
/// - every cluster is connected through shared edges (the dual graph restricted to the cluster);
///   a triangle without edges (all three indices equal) is therefore only valid alone;
/// - the limits hold (vertices counted as the distinct vertices of the cluster's triangles).
/// `triangles` is the mesh's triangle array (its size is the triangle count); two triangles
/// share an edge when they have a side with the same two distinct vertex ids (topology.h). The clustering itself may be garbage (ids out of range, offsets that
/// decrease or run past the end, mismatched sizes): every such defect gives a message naming the
/// cluster or triangle, never a crash. When the triangle offsets are unusable the per-cluster
/// checks are skipped (their ranges mean nothing) and only the structural messages are returned.
/// Cost O(T log T) and O(T) memory (no edge map); the clusters are checked in parallel, with the
/// same messages at any thread count.
/// `adjacency`: when not empty, the triangles whose shared sides define connectivity and whose
/// distinct vertices the vertex limit counts (cluster.h adjacency_triangles: a clustering made
/// with adjacency by positions); the vertex lists are still those of `triangles`. Its size must
/// be the triangle count (a message otherwise).
[[nodiscard]] std::vector<std::string> validate(const Clustering& c, std::span<const Tri> triangles,
                                                const ClusterLimits& limits = {}, std::size_t max_issues = 20,
                                                std::span<const Tri> adjacency = {});

/// Splits every cluster that is not connected through shared edges into its edge-connected
/// pieces (used after baselines that do not guarantee connectivity, such as meshoptimizer's
/// meshlets and the SAH split). Pieces are numbered as clustering_from_labels numbers them.
/// Restores the connectivity invariant of validate() and keeps all others (a piece of a cluster
/// within the limits is within them too). Precondition: every triangle of `triangles` is in
/// exactly one cluster of `c` with consistent offsets (std::invalid_argument otherwise); the
/// vertex lists of `c` are not read. O(T log T).
[[nodiscard]] Clustering split_disconnected(const Clustering& c, std::span<const Tri> triangles);

/// The clustering of a mesh whose vertices were renumbered (to_new[old] = new, e.g.
/// inverse_permutation of the renumbering): vertex lists renamed and sorted ascending again;
/// triangles and clusters unchanged. Throws std::invalid_argument for a vertex id outside to_new
/// (or bad vertex offsets), before anything changes. The second form renames `c`'s own lists (no
/// copy: at 13.3M triangles the clustering is 100 MB).
[[nodiscard]] Clustering renumber_vertices(const Clustering& c, std::span<const std::uint32_t> to_new);
[[nodiscard]] Clustering renumber_vertices(Clustering&& c, std::span<const std::uint32_t> to_new);

}  // namespace ptc
