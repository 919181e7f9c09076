// Iterative growth (Garanzha 2009; docs/method.md "Clustering algorithms"): clusters are grown
// one at a time from a start triangle by the best adjacent untaken triangle.
//
//   label[t] = none for every t
//   while s = next_start(rule) exists:                 // rule: index / Morton / fewest free neighbours
//     k = {s}; frontier = untaken triangles sharing an EDGE with s
//     loop:
//       queue = {}                                     // best-first refinement of bounds
//       for d in frontier:                             // every candidate, every step (k changed)
//         ctx = MergeContext(k, {d})                   // O(1): d's vertices against k's stamps,
//                                                      //       d's edges against k's labels
//         if objective.legal(ctx): queue.push(evaluate(k, {d}, ctx, UpperBoundAllowed), d)
//       loop:
//         (key, d) = queue.pop_max()                   // keys bound the exact scores from above
//         if kMergeOnlyPositive and key <= 0: best = none; break
//         if key is exact: best = d; break             // nothing else can beat it
//         queue.push(evaluate(k, {d}, ctx, next level), d)   // UpperBound -> Refined -> Tight -> Exact
//       if best = none: close k; break
//       k = k + best (objective.merge); update stamps, labels; frontier += best's untaken
//       edge-neighbours, -= best
//   queue order: higher key first; equal keys -> lower triangle id (deterministic; an exact key
//   on top ranks at or above every other candidate's exact score).
//
// Start rules (ClusterConfig::start): IndexOrder = the lowest untaken triangle id; SpatialOrder =
// the next untaken triangle in Morton order of the centroids (morton.h, cube grid); FewestFree =
// the untaken triangle with the fewest untaken edge-neighbours, ties by Morton order (a bucket
// heap with lazy deletion: stale entries, whose count changed or whose triangle was taken, are
// skipped when popped).
// Morton order is not rotation invariant, so only IndexOrder growth gives the same clusters for
// a rotated mesh (up to rounding ties); translations and uniform scalings keep all three rules.
//
// Cost: O(sum over steps of the frontier size) candidate evaluations at the cheapest level
// (O(1) each; Naive and GWH01 are exact there, GWH01 with a 3x3 eigen-solve) plus a few
// refinements per step (Acc: one pass over the cluster's vertices for the diameter bound, three
// for the three-point sphere, rarely a CGAL sphere); memory O(T + V). Measured (bench/
// clustering_bench.cpp, Acc, armadillo subdivided to 832k triangles, one thread, CPU time):
// 0.83 s, 1.49 s, 1.96 s at MaxCount = MaxSize = 10, 50, 100 (docs/clustering.md).
// Every cluster is edge-connected by construction; a triangle without edge-neighbours (or one
// whose neighbours are all taken) is a cluster of its own.
#pragma once

#include <cstdint>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/objectives.h"
#include "toolkit/clustering/objectives/acc.h"
#include "toolkit/clustering/objectives/gwh01.h"
#include "toolkit/clustering/objectives/naive.h"

namespace ptc {

struct GrowthOptions {
  StartRule start = StartRule::SpatialOrder;  ///< how the next cluster's first triangle is picked
  bool record_merges = false;                 ///< fill ClusterRun::merges (T records at most)
  /// Acc: the O(1) level of the candidates that add one vertex through AccObjective's
  /// growth_prepare / growth_key (the same keys as evaluate(), faster). False sends every
  /// candidate through evaluate(): for the test that both give the same run, bit for bit.
  bool objective_fast_level = true;
};

/// Grows clusters over the whole mesh. `objective` is a per-run workspace (not shared between
/// threads). Deterministic. Empty mesh: empty labels. Progress: fraction of triangles taken.
template <ClusterObjective O>
[[nodiscard]] ClusterRun grow_clusters(const ClusterTables& tables, O& objective, const GrowthOptions& options = {},
                                       const ProgressFn& progress = {});

extern template ClusterRun grow_clusters<AccObjective>(const ClusterTables&, AccObjective&, const GrowthOptions&,
                                                       const ProgressFn&);
extern template ClusterRun grow_clusters<NaiveObjective>(const ClusterTables&, NaiveObjective&, const GrowthOptions&,
                                                         const ProgressFn&);
extern template ClusterRun grow_clusters<Gwh01Objective>(const ClusterTables&, Gwh01Objective&,
                                                         const GrowthOptions&, const ProgressFn&);

}  // namespace ptc
