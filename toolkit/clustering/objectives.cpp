#include "toolkit/clustering/objectives.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <span>
#include <stdexcept>

#include "toolkit/core/isa.h"
#include "toolkit/geometry/sphere.h"
#include "toolkit/geometry/triangle.h"

namespace ptc {

/// The distinct edge-neighbours of every triangle, ascending (ClusterTables::neighbours), without
/// an edge map: a run of equal pairs in topology.h's SortedSides is one mesh edge, and its
/// distinct triangles are neighbours as in the dual graph (topology.h build_dual_graph): every pair
/// up to kMaxCliqueValence triangles on the edge, beyond that a path in triangle order (the same
/// components in linear size; every pair at any valence was quadratic: 100,000 copies of one
/// triangle made 3 10^10 entries and overflowed the 32-bit offsets). 8 bytes a side and the lists themselves, against the edge map's ~45 bytes a
/// triangle. When every edge has at most two triangles, one pass over the edges into three slots
/// a triangle; otherwise two: count each triangle's entries, then write them.
void build_neighbours(std::span<const Tri> triangles, std::size_t vertex_count, std::vector<std::uint32_t>& offsets,
                      std::vector<std::uint32_t>& out) {
  const std::size_t T = triangles.size();
  using Side = SortedSides::Side;
  const SortedSides ss = SortedSides::build(triangles, vertex_count);
  auto for_each_edge = [&](auto&& on_edge) {
    for (std::size_t v = 0; v < vertex_count; ++v) {
      const Side* lo = ss.sides.data() + ss.first[v];
      const Side* const hi = ss.sides.data() + ss.first[v + 1];
      for (const Side* e = lo; lo != hi; lo = e) {
        while (e != hi && e->other == lo->other) ++e;
        on_edge(lo, e);
      }
    }
  };
  // A side's triangle, and whether it is the first side of its triangle in the run (a triangle
  // (a, b, a) lists one edge twice).
  auto tri = [](const Side* s) { return s->slot / 3; };
  auto first_of_its_triangle = [&](const Side* lo, const Side* s) { return s == lo || tri(s) != tri(s - 1); };
  // Every edge with at most two triangles (a manifold mesh, with or without border): a triangle
  // has at most one neighbour per side, so its list is written into three slots of its own, in
  // one pass over the edges, and compacted below. An edge with three or more triangles: the
  // general count-and-fill below instead.
  {
    out.assign(3 * T, 0);
    std::vector<std::uint8_t> count(T, 0);
    bool manifold = true;
    for_each_edge([&](const Side* lo, const Side* hi) {
      const Side* second = nullptr;  // the run's second distinct triangle, if any
      for (const Side* s = lo + 1; s != hi; ++s)
        if (first_of_its_triangle(lo, s)) {
          if (second) manifold = false;
          second = s;
        }
      if (!second || !manifold) return;
      const std::uint32_t a = tri(lo), b = tri(second);
      out[3 * std::size_t{a} + count[a]++] = b;  // one side of a and of b per run: at most 3 each
      out[3 * std::size_t{b} + count[b]++] = a;
    });
    if (manifold) {
      offsets.resize(T + 1);
      std::size_t w = 0;
      for (std::size_t t = 0; t < T; ++t) {
        std::uint32_t b[3] = {out[3 * t], out[3 * t + 1], out[3 * t + 2]};
        const int n = count[t];
        if (n > 1 && b[1] < b[0]) std::swap(b[0], b[1]);
        if (n > 2) {
          if (b[2] < b[1]) std::swap(b[1], b[2]);
          if (b[1] < b[0]) std::swap(b[0], b[1]);
        }
        offsets[t] = static_cast<std::uint32_t>(w);
        for (int k = 0; k < n; ++k)  // two triangles sharing two edges meet twice: once in the list
          if (k == 0 || b[k] != b[k - 1]) out[w++] = b[k];
      }
      offsets[T] = static_cast<std::uint32_t>(w);
      out.resize(w);
      return;
    }
  }
  // Each edge's distinct triangles, ascending (a run's slots ascend), linked by the dual graph's
  // rule (for_each_dual_pair).
  std::vector<std::uint32_t> run;
  auto distinct_of = [&](const Side* lo, const Side* hi) {
    run.clear();
    for (const Side* s = lo; s != hi; ++s)
      if (first_of_its_triangle(lo, s)) run.push_back(tri(s));
  };
  std::vector<std::uint64_t> count(T + 1, 0);
  for_each_edge([&](const Side* lo, const Side* hi) {
    distinct_of(lo, hi);
    for_each_dual_pair(run, [&](std::uint32_t a, std::uint32_t b) {
      ++count[a + 1];
      ++count[b + 1];
    });
  });
  for (std::size_t t = 0; t < T; ++t) count[t + 1] += count[t];
  if (count[T] > std::numeric_limits<std::uint32_t>::max())  // (at most 45 a triangle: beyond 95M triangles)
    throw std::length_error("build_neighbours: more than 2^32 neighbour entries");
  offsets.assign(count.begin(), count.end());
  std::vector<std::uint64_t>().swap(count);
  out.resize(offsets[T]);
  {
    std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for_each_edge([&](const Side* lo, const Side* hi) {
      distinct_of(lo, hi);
      for_each_dual_pair(run, [&](std::uint32_t a, std::uint32_t b) {
        out[fill[a]++] = b;
        out[fill[b]++] = a;
      });
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

namespace {

// Triangles [begin, end) of the tables' pass: area and normal, and with the sums the sum of their
// minimal spheres' areas (in order) and their centroids' box. A function of its own so that it has
// instruction-set clones (toolkit/core/isa.h).
PTC_ISA_CLONES
void tables_chunk(ClusterTables& t, std::size_t begin, std::size_t end, bool with_sums, double* sum_out,
                  Box3* box_out) {
  double sum = 0.0;
  Box3 box;
  for (std::size_t i = begin; i < end; ++i) {
    if (i + kCornerPrefetchAhead < end) prefetch_corners(t.positions.data(), t.triangles[i + kCornerPrefetchAhead]);
    const Tri& f = t.triangles[i];
    const Vec3 &p0 = t.positions[f[0]], &p1 = t.positions[f[1]], &p2 = t.positions[f[2]];
    if (!t.lean) {
      const TriangleGeometry g = triangle_geometry(p0, p1, p2);
      t.area[i] = g.area;
      t.normal[i] = g.normal;
    }
    if (with_sums) {
      sum += triangle_sphere_area(p0, p1, p2);
      box.extend(triangle_centroid(p0, p1, p2));
    }
  }
  if (with_sums) *sum_out = sum, *box_out = box;
}

}  // namespace

ClusterTables ClusterTables::build(const Mesh& mesh, bool with_edges, bool with_sums, bool lean) {
  ClusterTables t;
  t.mesh = &mesh;
  t.positions = mesh.positions();
  t.triangles = mesh.triangles();
  t.lean = lean;
  const std::size_t T = t.triangles.size();
  if (!lean) {
    t.area.resize(T);
    t.normal.resize(T);
  }
  // Per triangle: area and normal, and with the sums its minimal sphere's area and its centroid.
  // In average_triangle_sphere_area's fixed chunks (each summed in order, then the chunks' sums in
  // order), so AvgSA is its value bit for bit; chunks run on the caller's threads.
  constexpr std::size_t chunk = kAvgSaChunk;
  const std::size_t chunks = (T + chunk - 1) / chunk;
  std::vector<double> sums(with_sums ? chunks : 0);
  std::vector<Box3> boxes(with_sums ? chunks : 0);
  if (!lean || with_sums) tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    tables_chunk(t, c * chunk, std::min(T, (c + 1) * chunk), with_sums, with_sums ? &sums[c] : nullptr,
                 with_sums ? &boxes[c] : nullptr);
  });
  if (with_sums && T > 0) {
    double sum = 0.0;
    for (const double s : sums) sum += s;
    t.avg_sphere_area = sum / static_cast<double>(T);
    for (const Box3& b : boxes) t.centroid_bounds.extend(b);
  }
  t.with_sums = with_sums;
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
  if (!lean) build_neighbours(t.triangles, mesh.vertex_count(), t.neighbour_offsets, t.neighbours);
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
