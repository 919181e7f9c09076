#include "bvh/morton_runs.h"

#include <algorithm>

#include "toolkit/geometry/morton.h"

namespace ptc::bvh {

MortonRuns morton_runs(const Mesh& mesh, std::uint32_t run) {
  MortonRuns r;
  r.triangle_order = morton_order(mesh.positions(), mesh.triangles());
  const auto n = static_cast<std::uint32_t>(r.triangle_order.size());
  r.triangle_offsets.push_back(0);
  r.vertex_offsets.push_back(0);
  std::vector<std::uint32_t> vs;
  for (std::uint32_t b = 0; b < n; b += run) {
    const std::uint32_t e = std::min(n, b + run);
    vs.clear();
    for (std::uint32_t i = b; i < e; ++i)
      for (std::uint32_t v : mesh.triangle(r.triangle_order[i])) vs.push_back(v);
    std::sort(vs.begin(), vs.end());
    vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
    r.vertices.insert(r.vertices.end(), vs.begin(), vs.end());
    r.triangle_offsets.push_back(e);
    r.vertex_offsets.push_back(static_cast<std::uint32_t>(r.vertices.size()));
  }
  return r;
}

}  // namespace ptc::bvh
