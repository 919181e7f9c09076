// The interface between the greedy clustering algorithms (growth.h, contraction.h) and the
// objectives that rank their merges (objectives/acc.h, objectives/naive.h, objectives/gwh01.h).
//
// A greedy step asks two separate questions about one candidate merge A + B (growth: A = the
// growing cluster, B = one untaken triangle; contraction: two adjacent clusters), kept apart as
// OpenMesh's decimater modules keep them (style.md point 3):
//   legal(ctx)                may this merge happen at all?   (hard limits; MaxCount for Naive/GWH01)
//   evaluate(a, b, ctx, p)    how good is the merged cluster? (a score: LARGER IS BETTER for all)
// Both read one MergeContext that the algorithm computes once per candidate (the union's vertex
// count via vertex stamps, its new and shared vertices, the boundary length that disappears).
// An objective carries a small mergeable Summary per cluster (sums, a box, a sphere, a quadric),
// so evaluating a candidate never walks the whole cluster except where that is the exact answer
// (each objective documents when).
//
// Lazy evaluation: below Precision::Exact an objective may return, instead of the exact score, a
// cheaper UPPER BOUND on it (Evaluation::exact = false). The algorithms only ever need the exact
// score of the best candidate, so they refine only candidates whose bound can still win (growth:
// best-first refinement over the candidates of one step, level by level; contraction: bound keys
// in the priority queue, replaced by exact keys when they reach the top). A valid bound never
// changes the result: the candidate chosen is the one with the best exact score.
//
// Stop rule: O::kMergeOnlyPositive = true (Acc) means "merge only while the best score is > 0";
// false (Naive, GWH01) means "merge while any legal candidate exists" -- the score then only
// orders the merges and the hard limit (plus, in contraction, a target cluster count) stops them.
//
// Ties: the algorithms break equal scores by ids (growth: lower triangle id; contraction: the
// pair of cluster ids, lexicographically), so the result is deterministic.
#pragma once

#include <concepts>
#include <cstdint>
#include <span>
#include <vector>

#include "toolkit/core/types.h"
#include "toolkit/geometry/triangle.h"
#include "toolkit/mesh/mesh.h"
#include "toolkit/mesh/topology.h"

namespace ptc {

/// Per-mesh data shared by every objective and algorithm, computed once per clustering run
/// (O(T + V)). Refers to the mesh's positions and triangles: the mesh must outlive it.
struct ClusterTables {
  const Mesh* mesh = nullptr;
  std::span<const Vec3> positions;
  std::span<const Tri> triangles;
  std::vector<double> area;    ///< Area_i (one side, L^2) per triangle; 0 for degenerate ones (triangle.h rule)
  std::vector<Vec3> normal;    ///< unit normal per triangle; the zero vector for degenerate ones
  EdgeMap edges;               ///< topology.h's edge map (collapsed sides are no edges); empty unless built with edges
  std::vector<double> edge_length;  ///< |p(v1) - p(v0)| per mesh edge (L); empty unless built with edges
  /// Distinct edge-neighbours of triangle t (triangles sharing a mesh edge with t, t excluded;
  /// on an edge of more than kMaxCliqueValence triangles only the previous and next in id
  /// order), ascending: neighbours[neighbour_offsets[t] .. neighbour_offsets[t + 1]). The dual
  /// graph's adjacency (topology.h build_dual_graph) without parallel edges.
  std::vector<std::uint32_t> neighbour_offsets;
  std::vector<std::uint32_t> neighbours;
  double mean_edge_length = 0;  ///< mean of edge_length over all mesh edges (L); 0 without edges (or lengths)
  bool with_edges = false;      ///< built with the edge map and edge lengths (see build)
  /// Built with the mesh sums (see build): AvgSA, the mean surface area of the triangles' minimal
  /// spheres (L^2; average_triangle_sphere_area's value, bit for bit), and the box of the
  /// triangles' centroids (morton_codes' grid box). 0 and an empty box otherwise.
  bool with_sums = false;
  double avg_sphere_area = 0;
  Box3 centroid_bounds;

  /// with_edges: build the edge map, edge_length and mean_edge_length (only objectives with
  /// kUsesBoundary or a length scale need them: GWH01; distinct_edges and the perimeter helpers
  /// below require them). Without, only the neighbour lists describe the topology (at 13M
  /// triangles the edge map costs 0.6 GB and a third of the tables' time).
  /// with_sums: AvgSA and the centroids' box too, in the same pass over the triangles as their
  /// areas and normals (each reads a triangle's three corners, which on a large mesh whose vertex
  /// numbers are far from its triangle order are cache misses; docs/scale.md, "Open (issue 15)").
  /// lean: without the per-triangle areas and normals (geometry_of makes them again, bit for bit)
  /// and without the neighbour lists (build_neighbours makes them for a caller that needs them
  /// once): 48 bytes a triangle less, for the contraction, which reads them rarely (areas and
  /// normals) or once (neighbours; docs/scale.md, "Contraction in one run: the memory").
  [[nodiscard]] static ClusterTables build(const Mesh& mesh, bool with_edges = true, bool with_sums = false,
                                           bool lean = false);
  bool lean = false;  ///< built lean: `area`, `normal` and the neighbour lists are empty

  /// Area_i and n_i of triangle t (`area[t]`, `normal[t]`, or made again when lean).
  [[nodiscard]] TriangleGeometry geometry_of(std::uint32_t t) const {
    if (!lean) return {area[t], normal[t]};
    const Tri& f = triangles[t];
    return triangle_geometry(positions[f[0]], positions[f[1]], positions[f[2]]);
  }

  [[nodiscard]] std::uint32_t triangle_count() const { return static_cast<std::uint32_t>(triangles.size()); }
  /// Not when lean.
  [[nodiscard]] std::span<const std::uint32_t> neighbours_of(std::uint32_t t) const {
    return {neighbours.data() + neighbour_offsets[t], neighbours.data() + neighbour_offsets[t + 1]};
  }
  /// The distinct vertex ids of triangle t, ascending (1 to 3 of them); returns the count.
  int distinct_vertices(std::uint32_t t, std::uint32_t out[3]) const;
  /// The distinct mesh edges of triangle t (0 to 3; a triangle (a, b, a) has one); returns the
  /// count. Requires the edge map (built with edges).
  int distinct_edges(std::uint32_t t, std::uint32_t out[3]) const;
  /// Sum of the lengths of t's distinct edges: the perimeter of the one-triangle cluster {t}
  /// (gwh01.h's boundary rule). Requires edge lengths.
  [[nodiscard]] double triangle_perimeter(std::uint32_t t) const;
};

/// The tables' neighbour lists of `triangles` (ClusterTables::neighbour_offsets and neighbours).
void build_neighbours(std::span<const Tri> triangles, std::size_t vertex_count, std::vector<std::uint32_t>& offsets,
                      std::vector<std::uint32_t>& out);

/// Everything an objective may ask about one candidate merge A + B, computed once by the
/// algorithm. Vertex lists are distinct vertex ids, ascending.
struct MergeContext {
  std::span<const std::uint32_t> a_triangles;  ///< members of A (any order, fixed per cluster)
  std::span<const std::uint32_t> b_triangles;  ///< members of B
  std::span<const std::uint32_t> a_vertices;   ///< V(A)
  std::span<const std::uint32_t> added;        ///< V(B) \ V(A): what the merge adds to A
  std::span<const std::uint32_t> shared;       ///< V(A) n V(B)
  std::uint32_t vertex_count = 0;              ///< |V(A u B)| = |V(A)| + |added| (VertexCount of the merged cluster)
  /// P(A) + P(B) - P(A u B) >= 0 (L): the boundary length the merge removes (computed only for
  /// objectives with kUsesBoundary = true; 0 otherwise), with the boundary
  /// rule of gwh01.h (an edge is boundary when exactly one triangle of the cluster uses it). Per
  /// mesh edge used by both clusters, n_A and n_B triangles of it in A and B: length times
  /// ([n_A == 1] + [n_B == 1]); for a manifold edge between A and B that is 2 x length.
  double boundary_removed = 0;
};

/// How exact evaluate() must be (see the file comment).
/// Growth's levels, cheapest first, then the contraction's middle level; each may return the
/// exact score instead of a bound when that is as cheap. An objective without a bound at some
/// level returns what the next level returns (without any bound: the exact score).
enum class Precision {
  UpperBoundAllowed,  ///< an upper bound, O(1)
  RefinedBound,       ///< a tighter upper bound, one O(|V(A)|) pass (still far below the exact cost)
  TightBound,         ///< a tighter one still, a few O(|V(A)|) passes
  Exact,              ///< the exact score
  /// Outside growth's ladder: an upper bound for any pair from three passes over V(A u B), never
  /// computing the exact score where that needs more than UpperBoundAllowed's shortcuts (the
  /// contraction's middle level; objectives without it evaluate exactly).
  SupportBound,
};

/// What an objective's evaluate() returns at least (each objective adds what its merge() reuses,
/// e.g. Acc's sphere of the union).
struct ScoreBase {
  double score = 0;   ///< exact score, or an upper bound on it when exact = false; never NaN
  bool exact = true;
};

template <class O>
concept ClusterObjective = requires(O& o, const typename O::Summary& s, const MergeContext& ctx,
                                    const typename O::Evaluation& ev, std::uint32_t t) {
  { o.single(t) } -> std::same_as<typename O::Summary>;           ///< summary of the cluster {t}
  { o.legal(ctx) } -> std::same_as<bool>;                         ///< hard limits only
  { o.evaluate(s, s, ctx, Precision::Exact) } -> std::same_as<typename O::Evaluation>;
  { o.merge(s, s, ctx, ev) } -> std::same_as<typename O::Summary>;  ///< summary of A u B; ev from evaluate(.., Exact)
  requires std::derived_from<typename O::Evaluation, ScoreBase>;
  { O::kMergeOnlyPositive } -> std::convertible_to<bool>;
  { O::kUsesBoundary } -> std::convertible_to<bool>;  ///< reads MergeContext::boundary_removed
};

/// One merge performed by an algorithm, for tests and reports.
/// Growth: `into` = the cluster's index (labels), `from` = the triangle added.
/// Contraction: `into` = the surviving cluster id (the smaller of the two; a cluster's id is its
/// smallest triangle id), `from` = the absorbed cluster's id.
/// `score` = the exact score of the merged cluster (for Acc: Acc(A u B)).
struct MergeRecord {
  std::uint32_t into = 0;
  std::uint32_t from = 0;
  double score = 0;
};

/// What growth and contraction return: one cluster label per triangle (growth: cluster index in
/// creation order; contraction: the cluster's smallest triangle id) and, on request, the merges
/// in the order they happened. clustering_from_labels turns the labels into a Clustering.
struct ClusterRun {
  std::vector<std::uint32_t> labels;
  std::vector<MergeRecord> merges;
  std::uint64_t exact_evaluations = 0;  ///< evaluate(.., Exact) calls (work counter for the benchmark)
  std::uint64_t bound_evaluations = 0;  ///< evaluate(.., UpperBoundAllowed) calls that returned a bound
};

}  // namespace ptc
