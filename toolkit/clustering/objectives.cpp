#include "toolkit/clustering/objectives.h"

#include <algorithm>
#include <span>

#include "toolkit/geometry/triangle.h"

namespace ptc {

namespace {

/// The distinct edge-neighbours of every triangle, ascending (ClusterTables::neighbours), without
/// an edge map: the sides are bucketed by their smaller vertex (counting sort, in triangle order)
/// and sorted by the larger one within a bucket; a run of equal pairs is one mesh edge, and its
/// distinct triangles are pairwise neighbours (every pair, at any valence: the dual graph without
/// parallel edges). 8 bytes a side and the lists themselves, against the edge map's ~45 bytes a
/// triangle and a 12-byte side table.
void build_neighbours(std::span<const Tri> triangles, std::size_t vertex_count, std::vector<std::uint32_t>& offsets,
                      std::vector<std::uint32_t>& out) {
  const std::size_t T = triangles.size();
  std::vector<std::uint32_t> first(vertex_count + 1, 0);
  for (const Tri& f : triangles)
    for (int k = 0; k < 3; ++k)
      if (f[k] != f[(k + 1) % 3]) ++first[std::min(f[k], f[(k + 1) % 3]) + 1];
  for (std::size_t v = 0; v < vertex_count; ++v) first[v + 1] += first[v];
  struct Side {
    std::uint32_t other, tri;
  };
  std::vector<Side> sides(first.back());
  {
    std::vector<std::uint32_t> fill(first.begin(), first.end() - 1);
    for (std::size_t t = 0; t < T; ++t)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = triangles[t][k], b = triangles[t][(k + 1) % 3];
        if (a != b) sides[fill[std::min(a, b)]++] = {std::max(a, b), static_cast<std::uint32_t>(t)};
      }
  }
  const auto before = [](const Side& x, const Side& y) { return x.other != y.other ? x.other < y.other : x.tri < y.tri; };
  // Pass 1: sort each bucket, and count each triangle's entries (one per other triangle of each
  // of its edges); pass 2 writes them.
  offsets.assign(T + 1, 0);
  auto for_each_edge = [&](auto&& on_edge) {
    for (std::size_t v = 0; v < vertex_count; ++v) {
      Side* lo = sides.data() + first[v];
      Side* const hi = sides.data() + first[v + 1];
      for (Side* e = lo; lo != hi; lo = e) {
        while (e != hi && e->other == lo->other) ++e;
        on_edge(lo, e);
      }
    }
  };
  for (std::size_t v = 0; v < vertex_count; ++v) {
    Side* lo = sides.data() + first[v];
    Side* const hi = sides.data() + first[v + 1];
    if (hi - lo <= 16) {  // a vertex has a handful of sides: insertion sort
      for (Side* it = lo + (lo != hi); it < hi; ++it)
        for (Side* j = it; j != lo && before(*j, *(j - 1)); --j) std::swap(*j, *(j - 1));
    } else {
      std::sort(lo, hi, before);
    }
  }
  // A triangle (a, b, a) lists one edge twice in a run: count distinct triangles per run.
  auto distinct = [](const Side* lo, const Side* hi) {
    std::size_t m = 0;
    for (const Side* s = lo; s != hi; ++s) m += s == lo || s->tri != (s - 1)->tri;
    return m;
  };
  for_each_edge([&](const Side* lo, const Side* hi) {
    const std::size_t m = distinct(lo, hi);
    for (const Side* s = lo; s != hi; ++s)
      if (s == lo || s->tri != (s - 1)->tri) offsets[s->tri + 1] += static_cast<std::uint32_t>(m - 1);
  });
  for (std::size_t t = 0; t < T; ++t) offsets[t + 1] += offsets[t];
  out.resize(offsets[T]);
  {
    std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for_each_edge([&](const Side* lo, const Side* hi) {
      for (const Side* s = lo; s != hi; ++s) {
        if (s != lo && s->tri == (s - 1)->tri) continue;
        for (const Side* u = lo; u != hi; ++u)
          if (u->tri != s->tri && (u == lo || u->tri != (u - 1)->tri)) out[fill[s->tri]++] = u->tri;
      }
    });
  }
  // Ascending and distinct per triangle (two triangles sharing two edges meet twice), compacted
  // in place: the write position never passes the read position.
  std::size_t w = 0;
  for (std::size_t t = 0; t < T; ++t) {
    std::uint32_t* b = out.data() + offsets[t];
    const std::size_t n = offsets[t + 1] - offsets[t];
    for (std::size_t k = 1; k < n; ++k)
      for (std::size_t j = k; j > 0 && b[j] < b[j - 1]; --j) std::swap(b[j], b[j - 1]);
    offsets[t] = static_cast<std::uint32_t>(w);
    for (std::size_t k = 0; k < n; ++k)
      if (k == 0 || b[k] != b[k - 1]) out[w++] = b[k];
  }
  offsets[T] = static_cast<std::uint32_t>(w);
  out.resize(w);
}

}  // namespace

ClusterTables ClusterTables::build(const Mesh& mesh, bool with_edges) {
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
  t.with_edges = with_edges;
  if (with_edges) {
    t.edges = EdgeMap::build(t.triangles, mesh.vertex_count());
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
  build_neighbours(t.triangles, mesh.vertex_count(), t.neighbour_offsets, t.neighbours);
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
