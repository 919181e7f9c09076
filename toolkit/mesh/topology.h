// Connectivity of a fixed triangle array, computed once per topology: the edge -> triangles
// map, boundary and non-manifold edges, connected components and the dual graph.
//
// Policy for degenerate input (documented in docs/mesh_policy.md):
// - a triangle side whose two indices are equal (a "collapsed" side of a triangle with a
//   repeated index) is not an edge; it appears in no edge list and has kNoEdge as its edge id;
// - a triangle that uses the same undirected edge twice (indices a, b, a) lists it once;
// - an edge used by one triangle is a boundary edge, by two a manifold edge, by three or more a
//   non-manifold edge; in the dual graph every pair of triangles on an edge is adjacent when the
//   edge has at most kMaxCliqueValence triangles; beyond that (a "book" of thousands of pages,
//   which would give a quadratic number of dual edges) its triangles are linked as a path in
//   ascending id order, which keeps the same connected components in linear size.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <boost/graph/adjacency_list.hpp>

#include "toolkit/core/types.h"

namespace ptc {

/// An undirected mesh edge, v0 < v1.
struct Edge {
  std::uint32_t v0, v1;
  friend bool operator==(const Edge&, const Edge&) = default;
};

inline constexpr std::uint32_t kNoEdge = 0xffffffffu;

/// Non-manifold edges with up to this many triangles make a clique in the dual graph; more, a path.
inline constexpr std::size_t kMaxCliqueValence = 16;

/// The dual graph's pairs among the distinct triangles `ts` of one mesh edge (in the order
/// given): f(ts[i], ts[j]) for every i < j when there are at most kMaxCliqueValence of them, else
/// f(ts[i - 1], ts[i]) (a path). The one rule of build_dual_graph and ClusterTables' neighbours.
template <class F>
void for_each_dual_pair(std::span<const std::uint32_t> ts, F&& f) {
  if (ts.size() <= kMaxCliqueValence) {
    for (std::size_t i = 0; i < ts.size(); ++i)
      for (std::size_t j = i + 1; j < ts.size(); ++j) f(ts[i], ts[j]);
  } else {
    for (std::size_t i = 1; i < ts.size(); ++i) f(ts[i - 1], ts[i]);
  }
}

/// Every non-collapsed triangle side, bucketed by its smaller vertex and sorted within the
/// bucket by (larger vertex, slot), slot = 3 t + k for side k of triangle t (so by triangle too).
/// A run of equal `other` in a bucket is one mesh edge; its slots ascend. O(T + V); 8 bytes a
/// side. The one grouping of sides into edges that EdgeMap and ClusterTables' neighbour lists
/// share.
struct SortedSides {
  struct Side {
    std::uint32_t other, slot;
  };
  std::vector<std::uint32_t> first;  ///< vertex_count + 1: bucket of vertex v = sides[first[v] .. first[v + 1])
  std::vector<Side> sides;
  [[nodiscard]] static SortedSides build(std::span<const Tri> triangles, std::size_t vertex_count);
};

class EdgeMap {
 public:
  /// Builds the map in O(T + V) time (bucketed by the smaller vertex index).
  static EdgeMap build(std::span<const Tri> triangles, std::size_t vertex_count);

  [[nodiscard]] std::size_t edge_count() const { return edges_.size(); }
  [[nodiscard]] const Edge& edge(std::size_t e) const { return edges_[e]; }
  [[nodiscard]] std::span<const Edge> edges() const { return edges_; }
  /// Triangles incident to edge e, ascending, each once.
  [[nodiscard]] std::span<const std::uint32_t> triangles_of(std::size_t e) const {
    return {edge_tris_.data() + offsets_[e], edge_tris_.data() + offsets_[e + 1]};
  }
  [[nodiscard]] std::size_t valence(std::size_t e) const { return offsets_[e + 1] - offsets_[e]; }
  /// Edge id of side k of triangle t (side k joins corner k and corner (k+1)%3), or kNoEdge.
  [[nodiscard]] std::uint32_t side_edge(std::size_t t, int k) const { return side_edges_[3 * t + k]; }
  /// Edge id of {a, b}, or kNoEdge when no triangle uses it. O(log degree).
  [[nodiscard]] std::uint32_t find(std::uint32_t a, std::uint32_t b) const;

  [[nodiscard]] std::size_t boundary_edge_count() const;
  [[nodiscard]] std::size_t non_manifold_edge_count() const;

 private:
  std::vector<Edge> edges_;               // sorted by (v0, v1)
  std::vector<std::uint32_t> vertex_first_;  // edges of smaller vertex v: [vertex_first_[v], vertex_first_[v+1])
  std::vector<std::uint32_t> offsets_;    // edge_count + 1
  std::vector<std::uint32_t> edge_tris_;
  std::vector<std::uint32_t> side_edges_;  // 3 per triangle
};

/// Per-triangle component label (0..count-1, numbered in order of first triangle), where two
/// triangles are connected when they share a vertex.
struct Components {
  std::vector<std::uint32_t> label;
  std::uint32_t count = 0;
};
[[nodiscard]] Components vertex_connected_components(std::span<const Tri> triangles, std::size_t vertex_count);
/// Same, but triangles are connected only through shared edges (the dual graph's components).
[[nodiscard]] Components edge_connected_components(const EdgeMap& edges, std::size_t triangle_count);

/// Dual graph: a vertex per triangle (vertex index = triangle index), an edge per pair of
/// triangles sharing a mesh edge (but see kMaxCliqueValence); the edge property is the shared
/// mesh edge's id. A pair of triangles sharing two edges (possible on degenerate input) gets one
/// dual edge per shared edge.
struct DualEdgeProperty {
  std::uint32_t mesh_edge = kNoEdge;
};
using DualGraph = boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS, boost::no_property,
                                        DualEdgeProperty>;
[[nodiscard]] DualGraph build_dual_graph(const EdgeMap& edges, std::size_t triangle_count);

}  // namespace ptc
