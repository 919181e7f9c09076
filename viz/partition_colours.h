// Colours for a partition: the cluster adjacency graph (two clusters are adjacent when a mesh
// edge has triangles of both, non-manifold edges included) coloured with DSatur (Brélaz 1979), so
// that clusters sharing an edge never share a colour, over a fixed qualitative palette of 12
// colours (distinct hues, so a lit surface still shows which one it is). A graph that needs more
// colours than the palette holds (possible only for non-planar adjacency, e.g. a "book" of many
// clusters on one edge) gets further colours spread over the hue circle; the count is reported.
// No VTK here.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "render/images.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"

namespace ptc::viz {

/// Cluster adjacency: neighbours of cluster c are adjacency[offsets[c] .. offsets[c + 1]),
/// ascending, each once, never c itself.
struct ClusterGraph {
  std::vector<std::uint32_t> offsets{0}, adjacency;
  [[nodiscard]] std::size_t size() const { return offsets.size() - 1; }
  [[nodiscard]] std::span<const std::uint32_t> neighbours(std::size_t c) const {
    return {adjacency.data() + offsets[c], adjacency.data() + offsets[c + 1]};
  }
};

/// The graph of `clustering` on `mesh` (the clustering must cover the mesh's triangles;
/// std::invalid_argument otherwise).
[[nodiscard]] ClusterGraph cluster_graph(const Mesh& mesh, const Clustering& clustering);

/// The graph and the border edges at once (one edge map of the mesh for both).
struct PartitionTopology {
  ClusterGraph graph;
  std::vector<std::array<std::uint32_t, 2>> borders;
};
[[nodiscard]] PartitionTopology partition_topology(const Mesh& mesh, const Clustering& clustering);

/// DSatur: repeatedly colours the uncoloured vertex with the most distinct colours among its
/// neighbours (ties: more uncoloured neighbours, then the smaller id) with the smallest colour
/// none of its neighbours has. Deterministic. Returns one colour index per vertex.
[[nodiscard]] std::vector<std::uint32_t> dsatur_colouring(const ClusterGraph& g);

/// The qualitative palette (12 colours: Tableau's ten without its grey, plus two light tints).
[[nodiscard]] std::span<const Rgb8> qualitative_palette();
/// Colour `index` of the palette; beyond the palette, golden-angle hues (s = 0.65, v = 0.9).
[[nodiscard]] Rgb8 palette_colour(std::uint32_t index);

/// Mesh edges on a border between two clusters (a mesh edge whose triangles are not all in one
/// cluster), as pairs of vertex ids.
[[nodiscard]] std::vector<std::array<std::uint32_t, 2>> border_edges(const Mesh& mesh, const Clustering& clustering);

}  // namespace ptc::viz
