#include "toolkit/mesh/mesh_report.h"

#include <algorithm>
#include <numeric>

#include "toolkit/geometry/triangle.h"

namespace ptc {

namespace {

// Coordinates compared with -0.0 == +0.0 (the only two distinct doubles that compare equal).
Vec3 canonical(const Vec3& p) { return Vec3(p.x() + 0.0, p.y() + 0.0, p.z() + 0.0); }

std::size_t count_duplicate_vertices(std::span<const Vec3> pos) {
  std::vector<std::uint32_t> order(pos.size());
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](std::uint32_t a, std::uint32_t b) {
    const Vec3 p = canonical(pos[a]), q = canonical(pos[b]);
    if (p.x() != q.x()) return p.x() < q.x();
    if (p.y() != q.y()) return p.y() < q.y();
    return p.z() < q.z();
  };
  std::sort(order.begin(), order.end(), less);
  std::size_t dup = 0;
  for (std::size_t i = 1; i < order.size(); ++i) dup += !less(order[i - 1], order[i]);
  return dup;
}

std::size_t count_duplicate_triangles(std::span<const Tri> tris) {
  std::vector<Tri> sorted(tris.begin(), tris.end());
  for (Tri& f : sorted) std::sort(f.begin(), f.end());
  std::sort(sorted.begin(), sorted.end());
  std::size_t dup = 0;
  for (std::size_t i = 1; i < sorted.size(); ++i) dup += sorted[i] == sorted[i - 1];
  return dup;
}

// A vertex is non-manifold when its incident triangles split into two or more groups that are
// not connected through edges incident to that vertex (two fans touching at a point). The
// endpoints of a non-manifold edge are not counted for that reason alone (all the edge's
// triangles are linked through it); they are counted when their fans split as well.
// Cost: O(sum over vertices of incident triangles * log), each edge through v visited once.
std::size_t count_non_manifold_vertices(const Mesh& mesh, const EdgeMap& edges) {
  const auto tris = mesh.triangles();
  const std::size_t V = mesh.vertex_count();
  auto distinct_corner = [](const Tri& f, int k) {
    return k == 0 || (f[k] != f[0] && (k == 1 || f[k] != f[1]));
  };
  // vertex -> incident triangles (CSR, ascending)
  std::vector<std::uint32_t> first(V + 1, 0);
  for (const Tri& f : tris)
    for (int k = 0; k < 3; ++k)
      if (distinct_corner(f, k)) ++first[f[k] + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<std::uint32_t> inc(first.back());
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::size_t t = 0; t < tris.size(); ++t)
      for (int k = 0; k < 3; ++k)
        if (distinct_corner(tris[t], k)) inc[fill[tris[t][k]]++] = static_cast<std::uint32_t>(t);
  }
  std::size_t count = 0;
  std::vector<std::uint32_t> parent;
  for (std::size_t v = 0; v < V; ++v) {
    const std::size_t n = first[v + 1] - first[v];
    if (n < 2) continue;
    const std::uint32_t* ts = inc.data() + first[v];
    auto local = [&](std::uint32_t t) { return static_cast<std::uint32_t>(std::lower_bound(ts, ts + n, t) - ts); };
    parent.resize(n);
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](std::uint32_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    std::size_t groups = n;
    for (std::size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t e = edges.side_edge(ts[i], k);
        if (e == kNoEdge) continue;
        const Edge& ed = edges.edge(e);
        const auto et = edges.triangles_of(e);
        // Visit each edge through v once: from its first triangle.
        if ((ed.v0 != v && ed.v1 != v) || et.front() != ts[i]) continue;
        const std::uint32_t a = find(static_cast<std::uint32_t>(i));
        for (std::size_t j = 1; j < et.size(); ++j) {
          const std::uint32_t b = find(local(et[j]));
          if (a != b) {
            parent[b] = a;
            --groups;
          }
        }
      }
    count += groups > 1;
  }
  return count;
}

}  // namespace

MeshReport analyze_mesh(const Mesh& mesh, const EdgeMap& edges) {
  MeshReport r;
  const auto tris = mesh.triangles();
  const auto pos = mesh.positions();
  r.vertices = mesh.vertex_count();
  r.triangles = tris.size();

  std::vector<char> used(r.vertices, 0);
  std::vector<double> areas(tris.size());
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const Tri& f = tris[t];
    for (auto v : f) used[v] = 1;
    const Vec3 &a = pos[f[0]], &b = pos[f[1]], &c = pos[f[2]];
    const TriangleGeometry g = triangle_geometry(a, b, c);
    areas[t] = g.area;
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2])
      ++r.repeated_index_triangles;
    else if (collinear_exact(a, b, c))
      ++r.zero_area_triangles;
    else if (g.normal == Vec3::Zero())  // the sine test (scale-free); not area == 0, which a right
      ++r.near_degenerate_triangles;    // triangle of 1e-170 units also has (its area underflows)
  }
  for (std::size_t v = 0; v < r.vertices; ++v) {
    if (used[v])
      r.bounds.extend(pos[v]);
    else
      ++r.unreferenced_vertices;
  }
  long double total = 0;
  for (double a : areas) total += a;
  r.total_area = static_cast<double>(total);
  r.triangle_area = summarize(areas);

  std::vector<double> lengths(edges.edge_count());
  for (std::size_t e = 0; e < edges.edge_count(); ++e)
    lengths[e] = safe_distance(pos[edges.edge(e).v0], pos[edges.edge(e).v1]);  // (inf, not NaN, beyond the range)
  r.edge_length = summarize(lengths);

  r.duplicate_vertices = count_duplicate_vertices(pos);
  r.duplicate_triangles = count_duplicate_triangles(tris);
  r.edges = edges.edge_count();
  r.boundary_edges = edges.boundary_edge_count();
  r.non_manifold_edges = edges.non_manifold_edge_count();
  r.non_manifold_vertices = count_non_manifold_vertices(mesh, edges);
  r.components = vertex_connected_components(tris, r.vertices).count;
  r.edge_components = edge_connected_components(edges, tris.size()).count;
  return r;
}

MeshReport analyze_mesh(const Mesh& mesh) {
  return analyze_mesh(mesh, EdgeMap::build(mesh.triangles(), mesh.vertex_count()));
}

}  // namespace ptc
