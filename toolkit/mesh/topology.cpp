#include "toolkit/mesh/topology.h"

#include <algorithm>
#include <numeric>

namespace ptc {

SortedSides SortedSides::build(std::span<const Tri> triangles, std::size_t vertex_count) {
  SortedSides r;
  const std::size_t T = triangles.size();
  // Counting sort by the smaller vertex, in slot order.
  r.first.assign(vertex_count + 1, 0);
  for (const Tri& f : triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = f[k], b = f[(k + 1) % 3];
      if (a != b) ++r.first[std::min(a, b) + 1];
    }
  std::partial_sum(r.first.begin(), r.first.end(), r.first.begin());
  r.sides.resize(r.first.back());
  {
    std::vector<std::uint32_t> fill(r.first.begin(), r.first.end() - 1);
    for (std::size_t t = 0; t < T; ++t)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = triangles[t][k], b = triangles[t][(k + 1) % 3];
        if (a != b) r.sides[fill[std::min(a, b)]++] = {std::max(a, b), static_cast<std::uint32_t>(3 * t + k)};
      }
  }
  // Within a bucket by (other, slot); a vertex has a handful of sides: insertion sort.
  const auto before = [](const Side& x, const Side& y) { return x.other != y.other ? x.other < y.other : x.slot < y.slot; };
  for (std::size_t v = 0; v < vertex_count; ++v) {
    Side* lo = r.sides.data() + r.first[v];
    Side* const hi = r.sides.data() + r.first[v + 1];
    if (hi - lo <= 16) {
      for (Side* it = lo + (lo != hi); it < hi; ++it)
        for (Side* j = it; j != lo && before(*j, *(j - 1)); --j) std::swap(*j, *(j - 1));
    } else {
      std::sort(lo, hi, before);
    }
  }
  return r;
}

EdgeMap EdgeMap::build(std::span<const Tri> triangles, std::size_t vertex_count) {
  EdgeMap m;
  m.side_edges_.assign(3 * triangles.size(), kNoEdge);
  const SortedSides ss = SortedSides::build(triangles, vertex_count);
  // Equal "other" values in a bucket form one edge. Every list is at most one entry per side:
  // reserved once (untouched capacity costs no memory).
  m.vertex_first_.assign(vertex_count + 1, 0);
  m.edges_.reserve(ss.sides.size());
  m.edge_tris_.reserve(ss.sides.size());
  m.offsets_.reserve(ss.sides.size() + 1);
  m.offsets_.push_back(0);
  for (std::size_t v = 0; v < vertex_count; ++v) {
    m.vertex_first_[v] = static_cast<std::uint32_t>(m.edges_.size());
    auto it = ss.sides.begin() + ss.first[v];
    const auto last = ss.sides.begin() + ss.first[v + 1];
    while (it != last) {
      const std::uint32_t other = it->other;
      const auto e = static_cast<std::uint32_t>(m.edges_.size());
      m.edges_.push_back({static_cast<std::uint32_t>(v), other});
      std::uint32_t last_tri = kNoEdge;
      for (; it != last && it->other == other; ++it) {
        m.side_edges_[it->slot] = e;
        const std::uint32_t tri = it->slot / 3;
        if (tri != last_tri) m.edge_tris_.push_back(tri);  // a, b, a lists its edge once
        last_tri = tri;
      }
      m.offsets_.push_back(static_cast<std::uint32_t>(m.edge_tris_.size()));
    }
  }
  m.vertex_first_[vertex_count] = static_cast<std::uint32_t>(m.edges_.size());
  return m;
}

std::uint32_t EdgeMap::find(std::uint32_t a, std::uint32_t b) const {
  if (a == b) return kNoEdge;
  if (a > b) std::swap(a, b);
  if (a + 1 >= vertex_first_.size()) return kNoEdge;
  auto first = edges_.begin() + vertex_first_[a], last = edges_.begin() + vertex_first_[a + 1];
  auto it = std::lower_bound(first, last, b, [](const Edge& e, std::uint32_t x) { return e.v1 < x; });
  return (it != last && it->v1 == b) ? static_cast<std::uint32_t>(it - edges_.begin()) : kNoEdge;
}

std::size_t EdgeMap::boundary_edge_count() const {
  std::size_t n = 0;
  for (std::size_t e = 0; e < edge_count(); ++e) n += valence(e) == 1;
  return n;
}

std::size_t EdgeMap::non_manifold_edge_count() const {
  std::size_t n = 0;
  for (std::size_t e = 0; e < edge_count(); ++e) n += valence(e) > 2;
  return n;
}

namespace {
struct UnionFind {
  std::vector<std::uint32_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

Components label_by_root(std::size_t triangle_count, auto root_of) {
  Components c;
  c.label.assign(triangle_count, 0);
  std::vector<std::uint32_t> seen;  // root -> label+1
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const std::uint32_t r = root_of(t);
    if (r >= seen.size()) seen.resize(r + 1, 0);
    if (seen[r] == 0) seen[r] = ++c.count;
    c.label[t] = seen[r] - 1;
  }
  return c;
}
}  // namespace

Components vertex_connected_components(std::span<const Tri> triangles, std::size_t vertex_count) {
  UnionFind uf(vertex_count);
  for (const Tri& f : triangles) {
    uf.unite(f[0], f[1]);
    uf.unite(f[1], f[2]);
  }
  return label_by_root(triangles.size(), [&](std::size_t t) { return uf.find(triangles[t][0]); });
}

Components edge_connected_components(const EdgeMap& edges, std::size_t triangle_count) {
  UnionFind uf(triangle_count);
  for (std::size_t e = 0; e < edges.edge_count(); ++e) {
    auto ts = edges.triangles_of(e);
    for (std::size_t i = 1; i < ts.size(); ++i) uf.unite(ts[0], ts[i]);
  }
  return label_by_root(triangle_count, [&](std::size_t t) { return uf.find(static_cast<std::uint32_t>(t)); });
}

DualGraph build_dual_graph(const EdgeMap& edges, std::size_t triangle_count) {
  DualGraph g(triangle_count);
  for (std::size_t e = 0; e < edges.edge_count(); ++e) {
    auto ts = edges.triangles_of(e);
    const DualEdgeProperty prop{static_cast<std::uint32_t>(e)};
    for_each_dual_pair(ts, [&](std::uint32_t a, std::uint32_t b) { boost::add_edge(a, b, prop, g); });
  }
  return g;
}

}  // namespace ptc
