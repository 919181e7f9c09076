#include "analysis/metrics/meshlet_stats.h"

#include <numeric>
#include <unordered_map>

namespace ptc {
namespace {

std::uint32_t root(std::vector<std::uint32_t>& parent, std::uint32_t x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];  // path halving
  return x;
}

}  // namespace

std::vector<MeshletShape> meshlet_shapes(const Clustering& c, std::span<const Tri> triangles, std::size_t vertex_count,
                                         std::uint32_t max_vertices) {
  // How many clusters hold each vertex.
  std::vector<std::uint32_t> owners(vertex_count, 0);
  for (std::size_t k = 0; k < c.cluster_count(); ++k)
    for (std::uint32_t v : c.vertices_of(k)) ++owners[v];
  std::vector<MeshletShape> out(c.cluster_count());
  std::unordered_map<std::uint32_t, std::uint32_t> local;
  std::vector<std::uint32_t> parent;
  for (std::size_t k = 0; k < c.cluster_count(); ++k) {
    MeshletShape& s = out[k];
    const auto vs = c.vertices_of(k);
    local.clear();
    for (std::uint32_t v : vs) {
      local.emplace(v, static_cast<std::uint32_t>(local.size()));
      s.boundary_vertices += owners[v] > 1;
    }
    parent.resize(local.size());
    std::iota(parent.begin(), parent.end(), 0u);
    for (std::uint32_t t : c.triangles_of(k))
      for (int e = 0; e < 3; ++e) {
        const std::uint32_t a = root(parent, local.at(triangles[t][e])), b = root(parent, local.at(triangles[t][(e + 1) % 3]));
        if (a != b) parent[a] = b;
      }
    for (std::uint32_t i = 0; i < parent.size(); ++i) s.components += root(parent, i) == i;
    s.not_full = vs.size() < max_vertices;
  }
  return out;
}

MeshletReport meshlet_report(const Clustering& c, const std::vector<MeshletShape>& shapes) {
  MeshletReport r;
  r.clusters = c.cluster_count();
  if (r.clusters == 0) return r;
  for (std::size_t k = 0; k < r.clusters; ++k) {
    r.avg_vertices += double(c.vertices_of(k).size());
    r.avg_triangles += double(c.triangles_of(k).size());
    r.avg_boundary += shapes[k].boundary_vertices;
    r.avg_connected += shapes[k].components;
    r.not_full += shapes[k].not_full;
  }
  const double n = double(r.clusters);
  r.avg_vertices /= n, r.avg_triangles /= n, r.avg_boundary /= n, r.avg_connected /= n;
  return r;
}

}  // namespace ptc
