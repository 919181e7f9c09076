// A stand-in clustering for the BVH layer's tests and benchmarks: the triangles in Morton order
// of their centroids, cut into runs of `run` triangles (the last run may be shorter). Runs are
// spatially compact but not necessarily connected; they stand in for real clusters until the
// clustering algorithms (toolkit/clustering) are used, and stay as a baseline.
#pragma once

#include <cstdint>
#include <vector>

#include "bvh/trace_scene.h"

namespace ptc::bvh {

struct MortonRuns {
  std::vector<std::uint32_t> triangle_order, triangle_offsets, vertices, vertex_offsets;
  [[nodiscard]] ClusterView view() const { return view_of(*this); }
  [[nodiscard]] std::size_t cluster_count() const { return triangle_offsets.empty() ? 0 : triangle_offsets.size() - 1; }
};

/// run >= 1. Within a run, triangles keep the Morton order; vertex lists are the distinct
/// vertices of the run's triangles, ascending.
[[nodiscard]] MortonRuns morton_runs(const Mesh& mesh, std::uint32_t run);

}  // namespace ptc::bvh
