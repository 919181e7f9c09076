#include "toolkit/clustering/morton_runs.h"

#include <algorithm>
#include <random>
#include <stdexcept>

#include "toolkit/geometry/morton.h"

namespace ptc {

Clustering morton_runs(const Mesh& mesh, const MortonRunsConfig& cfg) {
  if (cfg.min_run < 1 || cfg.max_run < cfg.min_run)
    throw std::invalid_argument("morton_runs: need 1 <= min_run <= max_run");
  const std::vector<std::uint32_t> order = morton_order(mesh.positions(), mesh.triangles());
  std::mt19937_64 rng(cfg.seed);
  std::uniform_int_distribution<std::size_t> len(cfg.min_run, cfg.max_run);
  Clustering c;
  c.triangle_order.reserve(order.size());
  std::vector<std::uint32_t> vs;
  for (std::size_t first = 0; first < order.size();) {
    const std::size_t last = std::min(order.size(), first + len(rng));
    const auto begin = c.triangle_order.end() - c.triangle_order.begin();
    c.triangle_order.insert(c.triangle_order.end(), order.begin() + std::ptrdiff_t(first), order.begin() + std::ptrdiff_t(last));
    std::sort(c.triangle_order.begin() + begin, c.triangle_order.end());
    vs.clear();
    for (std::size_t i = first; i < last; ++i)
      for (std::uint32_t v : mesh.triangle(order[i])) vs.push_back(v);
    std::sort(vs.begin(), vs.end());
    vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
    c.vertices.insert(c.vertices.end(), vs.begin(), vs.end());
    c.triangle_offsets.push_back(static_cast<std::uint32_t>(c.triangle_order.size()));
    c.vertex_offsets.push_back(static_cast<std::uint32_t>(c.vertices.size()));
    first = last;
  }
  return c;
}

}  // namespace ptc
