#include "toolkit/clustering/objectives.h"

#include <algorithm>

#include "toolkit/geometry/triangle.h"

namespace ptc {

ClusterTables ClusterTables::build(const Mesh& mesh, bool edge_lengths) {
  ClusterTables t;
  t.mesh = &mesh;
  t.positions = mesh.positions();
  t.triangles = mesh.triangles();
  const std::size_t T = t.triangles.size();
  t.area.resize(T);
  t.normal.resize(T);
  for (std::size_t i = 0; i < T; ++i) {
    const Tri& f = t.triangles[i];
    const TriangleGeometry g = triangle_geometry(t.positions[f[0]], t.positions[f[1]], t.positions[f[2]]);
    t.area[i] = g.area;
    t.normal[i] = g.normal;
  }
  t.edges = EdgeMap::build(t.triangles, mesh.vertex_count());
  if (edge_lengths) {
    const std::size_t E = t.edges.edge_count();
    t.edge_length.resize(E);
    double sum = 0;
    for (std::size_t e = 0; e < E; ++e) {
      const Edge& ed = t.edges.edge(e);
      t.edge_length[e] = safe_norm(t.positions[ed.v1] - t.positions[ed.v0]);  // as gwh_terms measures it
      sum += t.edge_length[e];
    }
    t.mean_edge_length = E > 0 ? sum / static_cast<double>(E) : 0.0;
  }

  t.neighbour_offsets.assign(T + 1, 0);
  t.neighbours.reserve(3 * T);
  for (std::size_t i = 0; i < T; ++i) {
    const std::size_t first = t.neighbours.size();
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t e = t.edges.side_edge(i, k);
      if (e == kNoEdge) continue;
      for (std::uint32_t u : t.edges.triangles_of(e))
        if (u != i) t.neighbours.push_back(u);
    }
    // A handful of entries (3 on a manifold mesh): insertion sort, then drop repeats.
    auto* b = t.neighbours.data() + first;
    const std::size_t n = t.neighbours.size() - first;
    for (std::size_t k = 1; k < n; ++k)
      for (std::size_t j = k; j > 0 && b[j] < b[j - 1]; --j) std::swap(b[j], b[j - 1]);
    t.neighbours.resize(first + static_cast<std::size_t>(std::unique(b, b + n) - b));
    t.neighbour_offsets[i + 1] = static_cast<std::uint32_t>(t.neighbours.size());
  }
  return t;
}

int ClusterTables::distinct_vertices(std::uint32_t t, std::uint32_t out[3]) const {
  Tri f = triangles[t];
  std::sort(f.begin(), f.end());
  int n = 0;
  for (int k = 0; k < 3; ++k)
    if (n == 0 || out[n - 1] != f[k]) out[n++] = f[k];
  return n;
}

int ClusterTables::distinct_edges(std::uint32_t t, std::uint32_t out[3]) const {
  int n = 0;
  for (int k = 0; k < 3; ++k) {
    const std::uint32_t e = edges.side_edge(t, k);
    if (e == kNoEdge || std::find(out, out + n, e) != out + n) continue;
    out[n++] = e;
  }
  return n;
}

double ClusterTables::triangle_perimeter(std::uint32_t t) const {
  std::uint32_t es[3];
  const int n = distinct_edges(t, es);
  double p = 0;
  for (int i = 0; i < n; ++i) p += edge_length[es[i]];
  return p;
}

}  // namespace ptc
