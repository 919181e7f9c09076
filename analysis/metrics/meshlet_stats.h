// meshoptimizer's cluster statistics with its definitions (its demo's meshlet report, read from
// meshoptimizer's source), so that ptc's clusterings can be compared with that library's numbers:
//   boundary vertices: the cluster's vertices that also belong to another cluster;
//   connected: the number of components of the cluster's vertices joined by its triangles'
//              edges (vertex connectivity: two triangles sharing only a corner are connected);
//   not full: the cluster has fewer than `max_vertices` vertices (meshoptimizer's default,
//              non-uniform mode).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "toolkit/clustering/clustering.h"
#include "toolkit/core/types.h"

namespace ptc {

struct MeshletShape {
  std::uint32_t boundary_vertices = 0;
  std::uint32_t components = 0;
  bool not_full = false;
};

/// Per cluster. `vertex_count` = the mesh's vertex count (vertex ids of the clustering are below).
[[nodiscard]] std::vector<MeshletShape> meshlet_shapes(const Clustering& c, std::span<const Tri> triangles,
                                                       std::size_t vertex_count, std::uint32_t max_vertices);

struct MeshletReport {
  std::size_t clusters = 0, not_full = 0;
  double avg_vertices = 0, avg_triangles = 0, avg_boundary = 0, avg_connected = 0;
};
/// meshoptimizer's averages over the clusters (0 for none).
[[nodiscard]] MeshletReport meshlet_report(const Clustering& c, const std::vector<MeshletShape>& shapes);

}  // namespace ptc
