// Iterative contraction of the dual graph (after Garland, Willmott, Heckbert 2001; docs/method.md
// "Clustering algorithms"): every triangle starts as a cluster; a global priority queue contracts
// the BEST dual edge first, i.e. the adjacent pair whose merged cluster scores highest. (The
// seminar write-up says "the edge with the lowest Acc"; that contradicts its own stop rule "until
// no edge is positive" and GWH01, which contracts the lowest COST; Acc is a gain, so the highest
// is contracted -- method.md.)
//
// Graph: the cluster graph is a Boost.Graph boost::adjacency_list (vecS, vecS, directedS) whose
// vertex c is the cluster with id c. It starts as the dual graph (a vertex per triangle, an arc
// pair per two triangles on a mesh edge, including every pair on a non-manifold edge; parallel
// dual edges -- triangles sharing two edges -- become one pair), built from ClusterTables' CSR
// adjacency, which clustering_objectives_test checks pair-for-pair against topology.h's
// build_dual_graph. Each merge mutates it with Boost's own operations: remove_edge (lo -> hi,
// x -> hi), add_edge (lo <-> x for hi's other neighbours), clear_out_edges(hi); the neighbours
// whose entries are refreshed are read with out_edges(lo). Objectives that measure the boundary
// (GWH01) carry an edge property: 2 x the length of the manifold mesh edges the two clusters
// share, summed on merge. Why directedS with arc pairs, not undirectedS: an undirected
// adjacency_list also keeps a global std::list of edges (a node allocation per edge, and
// clear_vertex walks it), which the contraction never needs. Cost of Boost against the
// previous hand-written sorted adjacency lists, measured alternately in one session on the 832k
// mesh at MaxCount = MaxSize = 50 (same clusters, same work counters; CPU s): Acc 6.3/6.7 ->
// 7.6/8.3, GWH01 6.8/6.5 -> 7.5/8.1, i.e. +10..25%, mostly remove_edge's linear erase and vector
// growth; still inside the 10 s target (docs/clustering.md).
// The order of out_edges does not matter: the queue's order is a strict order on (score, pair).
// A cluster's id is its smallest triangle id, so a merge keeps the smaller id.
//
// Priority queue: a max-heap of entries (score, exact?, pair (lo, hi), version stamps of
// lo and hi) with LAZY DELETION: merging a cluster increments its version and kills the other,
// which makes every entry that mentions either STALE; stale entries are dropped when popped and
// purged in one O(n) pass whenever the heap holds 1.5x the live pairs (memory stays O(live pairs)).
// A live pair has at most one current entry. Entries may carry an UPPER BOUND instead of the
// exact score (objectives.h, "Lazy evaluation"); such an entry is evaluated exactly when it
// reaches the top and re-inserted (its evaluation kept in a small direct-mapped cache, so that it
// is not computed twice when it comes back). Order: higher score first, equal scores by the
// smaller pair (lo, then hi) -- deterministic and independent of the heap's internals (a 4-ary
// heap, keys apart from the stamps).
//
//   for each dual edge (a, b): push entry(a, b)            // entry(): see below
//   while heap not empty and clusters > target_clusters:
//     e = pop max
//     if a or b is dead, or a version differs: continue    // stale (lazy deletion)
//     ctx = MergeContext(a, b)                             // vertex stamps: |V(a u b)|, added, shared
//     if !objective.legal(ctx): continue                   // re-check legality after each pop
//     if !e.exact:                                         // the key was an upper bound
//       s = objective.evaluate(a, b, ctx, Exact)
//       if kMergeOnlyPositive and s <= 0: continue         // re-entered if a or b changes
//       if (s, pair) ranks below the heap's top: push exact entry; continue
//     else s = cached or objective.evaluate(a, b, ctx, Exact)  // what merge() reuses (same value)
//     merge b into a (the smaller id survives): summaries, members, vertex lists, adjacency;
//       version[a]++, b dead
//     for each neighbour x of a: push entry(a, x)
//   entry(a, x): ctx; if legal, e = evaluate(a, x, ctx, UpperBoundAllowed);
//                push unless (kMergeOnlyPositive and e.score <= 0)
//
// Why the result equals the eager greedy rule ("contract the pair with the best exact score,
// ties by pair"): every live legal pair q has a current entry with key k_q >= its exact score
// v_q; when an exact entry (v_p, p) is contracted it ranks at or above the top, so
// (v_q, q) <= (k_q, q) <= (v_p, p) for all q. Illegal pairs stay illegal (clusters only grow), and
// with kMergeOnlyPositive a pair whose bound is <= 0 cannot win until one of its clusters changes,
// which re-evaluates it.
//
// Stop: Acc -- no positive edge left; Naive -- no legal edge left (every merge would exceed
// MaxCount); GWH01 -- target_clusters reached or no legal edge left. target_clusters applies to
// every objective.
// Cost: O(E log E) heap operations plus O(|V(a)| + |V(x)|) per evaluated pair (vertex stamps) and
// O(|a| + |b|) per merge (vertex lists); memory O(T + V).
#pragma once

#include <cstdint>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/objectives.h"
#include "toolkit/clustering/objectives/acc.h"
#include "toolkit/clustering/objectives/gwh01.h"
#include "toolkit/clustering/objectives/naive.h"

namespace ptc {

struct ContractionOptions {
  std::uint32_t target_clusters = 0;  ///< stop when this many clusters remain (0 = no target)
  bool record_merges = false;         ///< fill ClusterRun::merges
  /// A pair popped with the O(1) bound as its key gets Precision::SupportBound before its exact
  /// evaluation (docs/scale.md, "Contraction time on one thread"). The same merges either way;
  /// false: the exact evaluation at once (the reference in the tests).
  bool support_level = true;
  /// Purge the queue's stale entries as soon as it holds 8 more entries than live pairs (instead
  /// of 1.25x the live pairs, with 1024 of slack), and hand back every page past 8 more: the same
  /// merges, with the purges and the page release run thousands of times (for the tests).
  bool purge_often = false;
};

/// Contracts the dual graph. Labels are the clusters' smallest triangle ids. Deterministic.
/// Empty mesh: empty labels. Progress: merges done / triangles (the final count is not known).
/// At most 2^30 - 1 triangles (the queue's push-time stamps), else std::invalid_argument.
template <ClusterObjective O>
[[nodiscard]] ClusterRun contract_clusters(const ClusterTables& tables, O& objective,
                                           const ContractionOptions& options = {}, const ProgressFn& progress = {});

extern template ClusterRun contract_clusters<AccObjective>(const ClusterTables&, AccObjective&,
                                                           const ContractionOptions&, const ProgressFn&);
extern template ClusterRun contract_clusters<NaiveObjective>(const ClusterTables&, NaiveObjective&,
                                                             const ContractionOptions&, const ProgressFn&);
extern template ClusterRun contract_clusters<Gwh01Objective>(const ClusterTables&, Gwh01Objective&,
                                                             const ContractionOptions&, const ProgressFn&);

}  // namespace ptc
