// Morton runs: the triangles in Morton order of their centroids (toolkit/geometry/morton.h), cut
// into consecutive runs. A baseline clustering, spatially compact but not necessarily connected
// (validate() with connectivity may fail on it): the BVH layer's tests and benchmarks use it as
// a stand-in for real clusters, and the sphere report (analysis/metrics/sphere_accuracy.h) takes
// its point sets from it.
#pragma once

#include <cstdint>

#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

struct MortonRunsConfig {
  std::uint32_t min_run = 64;  ///< fewest triangles per run (>= 1); the last run may be shorter
  std::uint32_t max_run = 64;  ///< most triangles per run (>= min_run); min_run = max_run: fixed length
  std::uint64_t seed = 1;      ///< run lengths: uniform in [min_run, max_run], std::mt19937_64(seed)
};

/// Cluster k is the k-th run of the Morton order (clusters in that order); triangles and
/// vertices ascending within a cluster, as in every Clustering. std::invalid_argument for
/// min_run < 1 or max_run < min_run; an empty mesh gives no cluster.
[[nodiscard]] Clustering morton_runs(const Mesh& mesh, const MortonRunsConfig& config);

/// Runs of a fixed length `run` (>= 1).
[[nodiscard]] inline Clustering morton_runs(const Mesh& mesh, std::uint32_t run) {
  return morton_runs(mesh, MortonRunsConfig{run, run, 1});
}

}  // namespace ptc
