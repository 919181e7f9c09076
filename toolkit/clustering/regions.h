// Clustering in regions: the parallel mode of growth and contraction (ClusterConfig::regions,
// `ptc cluster --regions N`; docs/clustering.md "Parallel clustering: regions").
//
//   order = morton_order(mesh)                        // the whole mesh's triangles, Z-order of centroids
//   region r = the triangles of ranks [r T / N, (r + 1) T / N) of that order, ascending by id
//   for every region, on any thread:                  // independent: nothing is shared but the input
//     sub-mesh = the region's triangles (ids ascending) and the vertices they use (ids ascending)
//     the one run's objective and method over the sub-mesh (cluster.h detail::run_objective),
//     with the whole mesh's AvgSA (Acc)
//   labels = every region's clusters, region by region (clustering_from_labels renames them)
//
// A cluster never crosses a region border: clusters at the borders are cut there (the quality
// cost, measured in docs/clustering.md). Every cluster is edge-connected (its region's
// adjacency is a part of the mesh's). The result depends on the mesh, the config and N, never
// on the thread count or the order in which regions finish: the same clusters bit for bit at
// 1, 2 or N threads (tested). Within a region the sub-mesh keeps the relative order of triangle
// and vertex ids, so the tie rules (lower id first) decide as they would on the mesh.
// Objectives: Acc and Naive (GWH01 needs the whole mesh's mean edge length). Memory: the
// tables and the algorithm's state of one region per thread at a time (each region's work is
// isolated, so a thread waiting in a nested parallel loop takes no other region), not of the
// whole mesh, plus two scratch arrays of the mesh's vertex count (8 bytes a vertex) per thread.
#pragma once

#include <cstdint>
#include <vector>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"

namespace ptc {

/// The region (0 .. regions - 1) of every triangle: Morton-order ranks cut into `regions` runs
/// of equal size (+-1). regions is capped at the triangle count; 0 and 1 give one region.
[[nodiscard]] std::vector<std::uint32_t> cluster_regions(const Mesh& mesh, std::uint32_t regions);

/// Growth or contraction (config.method), objective Acc or Naive, in config.regions regions,
/// the regions in parallel (oneTBB, under the caller's concurrency limit). avg_sa: the whole
/// mesh's AvgSA (Acc's size unit, > 0; cluster_mesh computes it; ignored by Naive). Throws
/// std::invalid_argument for a configuration check() refuses with regions. Progress: the
/// regions' fractions weighted by their triangles, monotonic, called on the caller's thread
/// only. Every region polls throw_if_cancelled() (toolkit/core/cancel.h) when it reports:
/// ptc::Interrupted.
[[nodiscard]] Clustering cluster_in_regions(const Mesh& mesh, const ClusterConfig& config, double avg_sa,
                                            const ProgressFn& progress = {});

}  // namespace ptc
