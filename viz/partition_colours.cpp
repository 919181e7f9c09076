#include "viz/partition_colours.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <tuple>

#include "toolkit/mesh/topology.h"

namespace ptc::viz {
namespace {

constexpr std::array<Rgb8, 12> kPalette = {{
    {31, 119, 180},   // blue
    {255, 127, 14},   // orange
    {44, 160, 44},    // green
    {214, 39, 40},    // red
    {148, 103, 189},  // purple
    {140, 86, 75},    // brown
    {227, 119, 194},  // pink
    {188, 189, 34},   // olive
    {23, 190, 207},   // cyan
    {174, 199, 232},  // light blue
    {152, 223, 138},  // light green
    {255, 187, 120},  // light orange
}};

std::vector<std::uint32_t> cluster_of(const Mesh& mesh, const Clustering& c) {
  if (c.triangle_count() != mesh.triangle_count())
    throw std::invalid_argument("clustering covers " + std::to_string(c.triangle_count()) + " triangles, the mesh has " +
                                std::to_string(mesh.triangle_count()));
  std::vector<std::uint32_t> of = c.cluster_of_triangle();
  for (std::uint32_t k : of)
    if (k >= c.cluster_count()) throw std::invalid_argument("clustering does not cover every triangle once");
  return of;
}

ClusterGraph graph_of(const EdgeMap& edges, const std::vector<std::uint32_t>& of, std::size_t n) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  std::vector<std::uint32_t> ks;
  for (std::size_t e = 0; e < edges.edge_count(); ++e) {
    const auto tris = edges.triangles_of(e);
    if (tris.size() < 2) continue;
    ks.clear();
    for (std::uint32_t t : tris) ks.push_back(of[t]);
    std::sort(ks.begin(), ks.end());
    ks.erase(std::unique(ks.begin(), ks.end()), ks.end());
    for (std::size_t i = 0; i < ks.size(); ++i)
      for (std::size_t j = i + 1; j < ks.size(); ++j) pairs.emplace_back(ks[i], ks[j]), pairs.emplace_back(ks[j], ks[i]);
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  ClusterGraph g;
  g.offsets.assign(n + 1, 0);
  for (const auto& [a, b] : pairs) ++g.offsets[a + 1];
  for (std::size_t c = 0; c < n; ++c) g.offsets[c + 1] += g.offsets[c];
  g.adjacency.reserve(pairs.size());
  for (const auto& p : pairs) g.adjacency.push_back(p.second);
  return g;
}

std::vector<std::array<std::uint32_t, 2>> borders_of(const EdgeMap& edges, const std::vector<std::uint32_t>& of) {
  std::vector<std::array<std::uint32_t, 2>> out;
  for (std::size_t e = 0; e < edges.edge_count(); ++e) {
    const auto tris = edges.triangles_of(e);
    bool border = false;
    for (std::uint32_t t : tris) border = border || of[t] != of[tris[0]];
    if (border) out.push_back({edges.edge(e).v0, edges.edge(e).v1});
  }
  return out;
}

}  // namespace

ClusterGraph cluster_graph(const Mesh& mesh, const Clustering& clustering) { return partition_topology(mesh, clustering).graph; }

std::vector<std::array<std::uint32_t, 2>> border_edges(const Mesh& mesh, const Clustering& clustering) {
  return partition_topology(mesh, clustering).borders;
}

PartitionTopology partition_topology(const Mesh& mesh, const Clustering& clustering) {
  const std::vector<std::uint32_t> of = cluster_of(mesh, clustering);
  const EdgeMap edges = EdgeMap::build(mesh.triangles(), mesh.vertex_count());
  return {graph_of(edges, of, clustering.cluster_count()), borders_of(edges, of)};
}

std::vector<std::uint32_t> dsatur_colouring(const ClusterGraph& g) {
  const std::size_t n = g.size();
  constexpr std::uint32_t kNone = 0xffffffffu;
  std::vector<std::uint32_t> colour(n, kNone);
  std::vector<std::vector<std::uint32_t>> seen(n);  // distinct neighbour colours, ascending
  std::vector<std::uint32_t> free_degree(n);
  for (std::size_t v = 0; v < n; ++v) free_degree[v] = static_cast<std::uint32_t>(g.neighbours(v).size());
  // Ordered by (saturation desc, uncoloured degree desc, id asc): the first element is next.
  using Key = std::tuple<std::int64_t, std::int64_t, std::uint32_t>;
  const auto key = [&](std::size_t v) {
    return Key{-static_cast<std::int64_t>(seen[v].size()), -static_cast<std::int64_t>(free_degree[v]), static_cast<std::uint32_t>(v)};
  };
  std::set<Key> queue;
  for (std::size_t v = 0; v < n; ++v) queue.insert(key(v));
  while (!queue.empty()) {
    const std::uint32_t v = std::get<2>(*queue.begin());
    queue.erase(queue.begin());
    std::uint32_t c = 0;
    for (std::uint32_t s : seen[v]) {  // smallest colour not among the (sorted) neighbour colours
      if (s != c) break;
      ++c;
    }
    colour[v] = c;
    for (std::uint32_t w : g.neighbours(v)) {
      if (colour[w] != kNone) continue;
      queue.erase(key(w));
      auto it = std::lower_bound(seen[w].begin(), seen[w].end(), c);
      if (it == seen[w].end() || *it != c) seen[w].insert(it, c);
      --free_degree[w];
      queue.insert(key(w));
    }
  }
  return colour;
}

std::span<const Rgb8> qualitative_palette() { return kPalette; }

Rgb8 palette_colour(std::uint32_t index) {
  if (index < kPalette.size()) return kPalette[index];
  // HSV -> RGB with the hue stepped by the golden angle.
  const double h = std::fmod(static_cast<double>(index - kPalette.size()) * 137.50776405, 360.0) / 60.0, s = 0.65, v = 0.9;
  const double c = v * s, x = c * (1 - std::abs(std::fmod(h, 2.0) - 1)), m = v - c;
  double r = 0, gg = 0, b = 0;
  switch (static_cast<int>(h) % 6) {
    case 0: r = c, gg = x; break;
    case 1: r = x, gg = c; break;
    case 2: gg = c, b = x; break;
    case 3: gg = x, b = c; break;
    case 4: r = x, b = c; break;
    default: r = c, b = x; break;
  }
  return {to_u8(r + m), to_u8(gg + m), to_u8(b + m)};
}

}  // namespace ptc::viz
