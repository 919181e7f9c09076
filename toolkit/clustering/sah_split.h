// Top-down SAH split into clusters of bounded size: the modern baseline behind today's
// ray-tracing cluster builders (hardware cluster acceleration structures take clusters of at most
// 64 triangles / 64 vertices) and meshoptimizer's "spatial" meshlet builder (v0.23+,
// meshopt_buildMeshletsSpatial: SAH split with a fill penalty). Not the paper's method: it
// ignores connectivity while splitting and restores it afterwards (split_disconnected).
//
// Algorithm (one node = a set of triangles; the root holds all of them):
//
//   stack = [root]
//   while stack not empty:
//     node = pop
//     if |node| <= max_triangles and distinct_vertices(node) <= max_vertices: emit leaf; continue
//     for each axis with centroid extent > 0:
//       put the triangles into `bins` equal bins over the node's centroid bounds
//       sweep bins left->right and right->left: box, triangle count, distinct vertex count
//       for each plane between two bins with triangles on both sides: cost (below)
//     if no plane: sort the node by triangle id and split at the median (all centroids equal)
//     else split at the cheapest plane (ties: lower axis, lower plane); push right, push left
//   labels = leaf index per triangle; clusters = split_disconnected(clustering_from_labels(labels))
//
// Split cost (SAH over the children's boxes of the whole triangles, plus a fill term):
//   cost = A_L n_L + A_R n_R + fill_weight (A_L rest_L + A_R rest_R)
// with A = surface area of a child's box, n = its triangle count and rest = the room left empty in
// the leaves the child will at least need, in triangles:
//   leaves = max(ceil(n / max_triangles), ceil(v / max_vertices))      (v: its distinct vertices)
//   f      = max(n / max_triangles, v / max_vertices)                  (fill in leaf units)
//   rest   = (leaves - f) * n / f
// For a triangle-bound child this is meshoptimizer's rest = leaves * max_triangles - n; for a
// vertex-bound child (the usual case: a disc-like patch of n triangles has about n/2 + O(sqrt n)
// vertices, so with max_triangles = 2 max_vertices the vertex limit binds first) the empty vertex
// slots are converted into triangles at the child's own triangles-per-vertex ratio. Why: the plain
// SAH cost halves nodes wherever the geometry suggests and leaves many half-empty clusters (e.g.
// 120 triangles with limit 100 -> 60 + 60; 250 -> 125 + 125 -> four leaves of ~62); the fill term
// prefers planes whose sides are multiples of a leaf, so the number of clusters approaches the
// lower bound max(T / max_triangles, V / max_vertices) while the SAH term keeps them compact. It
// is weighted by area so that it trades against the SAH term in the same unit.
// A node whose box has zero area (all triangles on a line or a point) uses A = 1 for both children
// (pure count cost), so the fill term still steers the split there.
//
// Connectivity: a leaf is a box-bounded set of triangles, not a connected patch (two sides of a
// thin part, nearby components, a fully collapsed triangle). split_disconnected then cuts every
// leaf into its edge-connected pieces; pieces are subsets of leaves, so the limits still hold and
// every invariant of validate() is restored. What this adds (measured, max_count 50 = 50 vertices
// / 100 triangles): armadillo (52k triangles) 962 leaves -> 1098 clusters (+136, +14%); elephant
// (5.6k) 102 -> 138 (+36). Without the fill term (fill_weight 0): armadillo 1074 -> 1150 (+76),
// so the fill term trades a few more pieces for 10% fewer leaves and still ends with fewer clusters.
//
// Not invariant under rotation (axis-aligned planes); translation changes only rounding.
// Cost O(T log(T / max_triangles)) for balanced splits (armadillo 0.05 s, 832k triangles 2 s);
// sequential (deterministic by construction); no recursion (explicit stack), so degenerate inputs
// cannot overflow the stack.
#pragma once

#include <cstdint>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

/// Tuning of the SAH split (defaults are the ones measured in the report).
struct SahSplitOptions {
  /// Bins per axis for the binned SAH; in [2, 1024]. 32 is the usual compromise of binned builders
  /// (Wald 2007 uses 16-32): a finer grid changes the cost by a few percent at most.
  std::uint32_t bins = 32;
  /// Weight of the fill term; >= 0 (0 = plain SAH). 0.5 after meshoptimizer's recommended
  /// fill_weight for meshopt_buildMeshletsSpatial.
  double fill_weight = 0.5;
};

/// The hard limits the SAH split works under: max_vertices = config.max_count, max_triangles =
/// config.max_triangles, or 2 * max_count when that is 0 (saturating at 2^32 - 1). Throws
/// std::invalid_argument when max_count < 3 (a triangle could not be placed).
[[nodiscard]] ClusterLimits sah_split_limits(const ClusterConfig& config);

/// The SAH tree's leaves as clusters, before split_disconnected: every triangle in exactly one
/// cluster and every cluster within the limits, but a cluster need not be edge-connected (two
/// sides of a thin part, nearby components). For measuring what split_disconnected adds.
/// Limits: sah_split_limits(config). Throws std::invalid_argument when those throw or the
/// options are out of range. Empty mesh: empty clustering. Only the positions and
/// triangles of `mesh` are used; the other fields of `config` are ignored.
[[nodiscard]] Clustering sah_split_leaves(const Mesh& mesh, const ClusterConfig& config,
                                          const SahSplitOptions& options = {});

/// sah_split_leaves followed by split_disconnected: passes validate() with the limits above.
/// Deterministic (bit-identical output for identical input).
[[nodiscard]] Clustering sah_split_clusters(const Mesh& mesh, const ClusterConfig& config,
                                            const SahSplitOptions& options = {});

}  // namespace ptc
