// Partition colours: the cluster graph against a brute force over triangle pairs, DSatur's
// colouring checked edge by edge (and optimal where the optimum is known), on hard cases
// (non-manifold books, complete graphs, an empty mesh) and on a real clustering of a real mesh.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "toolkit/clustering/cluster.h"
#include "toolkit/io/mesh_io.h"
#include "viz/partition_colours.h"

namespace ptc::viz {
namespace {

// Brute force: clusters a != b are adjacent when two triangles of theirs share two vertex ids.
std::set<std::pair<std::uint32_t, std::uint32_t>> brute_adjacency(const Mesh& m, const std::vector<std::uint32_t>& label) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> adj;
  for (std::uint32_t s = 0; s < m.triangle_count(); ++s)
    for (std::uint32_t t = s + 1; t < m.triangle_count(); ++t) {
      if (label[s] == label[t]) continue;
      int shared = 0;
      std::set<std::uint32_t> a(m.triangle(s).begin(), m.triangle(s).end());
      for (std::uint32_t v : std::set<std::uint32_t>(m.triangle(t).begin(), m.triangle(t).end())) shared += static_cast<int>(a.count(v));
      if (shared >= 2) adj.insert({std::min(label[s], label[t]), std::max(label[s], label[t])});
    }
  return adj;
}

std::set<std::pair<std::uint32_t, std::uint32_t>> graph_pairs(const ClusterGraph& g) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> out;
  for (std::uint32_t c = 0; c < g.size(); ++c)
    for (std::uint32_t d : g.neighbours(c)) {
      EXPECT_NE(c, d);
      if (c < d) out.insert({c, d});
      else EXPECT_TRUE(std::count(g.neighbours(d).begin(), g.neighbours(d).end(), c)) << "symmetric";
    }
  return out;
}

void expect_proper(const ClusterGraph& g, const std::vector<std::uint32_t>& colour) {
  ASSERT_EQ(colour.size(), g.size());
  for (std::uint32_t c = 0; c < g.size(); ++c)
    for (std::uint32_t d : g.neighbours(c)) EXPECT_NE(colour[c], colour[d]) << "clusters " << c << " and " << d;
}

ClusterGraph graph_of(std::size_t n, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges) {
  std::vector<std::set<std::uint32_t>> adj(n);
  for (auto [a, b] : edges) adj[a].insert(b), adj[b].insert(a);
  ClusterGraph g;
  g.offsets.assign(1, 0);
  for (const auto& s : adj) {
    g.adjacency.insert(g.adjacency.end(), s.begin(), s.end());
    g.offsets.push_back(static_cast<std::uint32_t>(g.adjacency.size()));
  }
  return g;
}

std::uint32_t colours_used(const std::vector<std::uint32_t>& c) {
  return c.empty() ? 0 : *std::max_element(c.begin(), c.end()) + 1;
}

Mesh strip_grid(int n) {
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) p.emplace_back(x, y, 0);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const auto id = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
      t.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      t.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  return Mesh(std::move(t), std::move(p));
}

TEST(PartitionColours, GraphMatchesBruteForceOnAGridWithRandomLabels) {
  const Mesh m = strip_grid(7);
  std::mt19937 rng(5);
  std::vector<std::uint32_t> label(m.triangle_count());
  for (auto& l : label) l = static_cast<std::uint32_t>(rng() % 9);  // clusters need not be connected for the graph
  const Clustering c = clustering_from_labels(label, m.triangles());
  // clustering_from_labels renumbers; map the brute force through the same numbering.
  const std::vector<std::uint32_t> of = c.cluster_of_triangle();
  EXPECT_EQ(graph_pairs(cluster_graph(m, c)), brute_adjacency(m, of));
}

TEST(PartitionColours, NonManifoldBookMakesEveryClusterOnTheEdgeAdjacent) {
  // Five triangles on the edge (0, 1), each its own cluster: K5 (5 colours), plus one on the side.
  std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}};
  std::vector<Tri> t;
  for (int k = 0; k < 5; ++k) {
    p.emplace_back(0.5, std::cos(k * 1.2), std::sin(k * 1.2));
    t.push_back({0, 1, static_cast<std::uint32_t>(2 + k)});
  }
  p.emplace_back(2, 2, 0);
  t.push_back({1, 2, 7});  // shares edge (1, 2) with triangle 0
  const Mesh m(std::move(t), std::move(p));
  std::vector<std::uint32_t> label{0, 1, 2, 3, 4, 5};
  const Clustering c = clustering_from_labels(label, m.triangles());
  const ClusterGraph g = cluster_graph(m, c);
  EXPECT_EQ(graph_pairs(g), brute_adjacency(m, c.cluster_of_triangle()));
  const auto colour = dsatur_colouring(g);
  expect_proper(g, colour);
  EXPECT_EQ(colours_used(colour), 5u);
  const auto borders = border_edges(m, c);
  EXPECT_EQ(borders.size(), 2u);  // (0, 1) and (1, 2)
}

TEST(PartitionColours, DSaturIsOptimalWhereTheOptimumIsKnown) {
  // Complete graphs need n colours; bipartite graphs 2 (DSatur is exact on them); cycles 2 or 3.
  for (std::size_t n : {1u, 2u, 5u, 13u, 20u}) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> e;
    for (std::uint32_t a = 0; a < n; ++a)
      for (std::uint32_t b = a + 1; b < n; ++b) e.emplace_back(a, b);
    const ClusterGraph g = graph_of(n, e);
    const auto c = dsatur_colouring(g);
    expect_proper(g, c);
    EXPECT_EQ(colours_used(c), n);
  }
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const auto l = static_cast<std::uint32_t>(1 + rng() % 15), r = static_cast<std::uint32_t>(1 + rng() % 15);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> e;
    for (std::uint32_t a = 0; a < l; ++a)
      for (std::uint32_t b = 0; b < r; ++b)
        if (rng() % 3 == 0) e.emplace_back(a, l + b);
    const ClusterGraph g = graph_of(l + r, e);
    const auto c = dsatur_colouring(g);
    expect_proper(g, c);
    EXPECT_LE(colours_used(c), e.empty() ? 1u : 2u) << "trial " << trial;
  }
  for (std::uint32_t n : {4u, 7u}) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> e;
    for (std::uint32_t a = 0; a < n; ++a) e.emplace_back(a, (a + 1) % n);
    const auto c = dsatur_colouring(graph_of(n, e));
    EXPECT_EQ(colours_used(c), n % 2 ? 3u : 2u);
  }
  EXPECT_TRUE(dsatur_colouring(ClusterGraph{}).empty());
}

TEST(PartitionColours, RandomGraphsAreColouredProperly) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 30; ++trial) {
    const auto n = static_cast<std::uint32_t>(1 + rng() % 60);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> e;
    for (std::uint32_t a = 0; a < n; ++a)
      for (std::uint32_t b = a + 1; b < n; ++b)
        if (rng() % 5 == 0) e.emplace_back(a, b);
    const ClusterGraph g = graph_of(n, e);
    const auto c = dsatur_colouring(g);
    expect_proper(g, c);
    std::size_t max_degree = 0;
    for (std::uint32_t v = 0; v < n; ++v) max_degree = std::max(max_degree, g.neighbours(v).size());
    EXPECT_LE(colours_used(c), max_degree + 1);  // greedy's bound
  }
}

TEST(PartitionColours, ARealClusteringNeedsFewColoursAndNoNeighboursShareOne) {
  const Mesh m = read_mesh(std::string(PTC_TEST_DATA) + "/meshes/bunny00.off").mesh;
  ClusterConfig cfg;
  cfg.method = ClusterMethod::Growth;
  const Clustering c = cluster_mesh(m, cfg);
  ASSERT_GT(c.cluster_count(), 100u);
  const ClusterGraph g = cluster_graph(m, c);
  std::size_t edges = 0;
  for (std::uint32_t v = 0; v < g.size(); ++v) edges += g.neighbours(v).size();
  EXPECT_GT(edges, 2 * c.cluster_count());
  const auto colour = dsatur_colouring(g);
  expect_proper(g, colour);
  EXPECT_LE(colours_used(colour), qualitative_palette().size()) << "a surface partition fits the palette";
  // Every border edge joins triangles of two clusters, and every adjacency has a border edge.
  const auto borders = border_edges(m, c);
  EXPECT_GE(borders.size(), edges / 2);
}

TEST(PartitionColours, PaletteColoursAreDistinctAlsoBeyondTwelve) {
  std::set<Rgb8> seen;
  for (std::uint32_t i = 0; i < 40; ++i) EXPECT_TRUE(seen.insert(palette_colour(i)).second) << i;
  for (std::uint32_t i = 0; i < 12; ++i) EXPECT_EQ(palette_colour(i), qualitative_palette()[i]);
  // Distinct hues: no two palette colours are multiples of each other (a lit surface keeps them apart).
  for (std::uint32_t i = 0; i < 12; ++i)
    for (std::uint32_t j = i + 1; j < 12; ++j) {
      const Rgb8 a = palette_colour(i), b = palette_colour(j);
      const double sa = a[0] + a[1] + a[2], sb = b[0] + b[1] + b[2];
      double d = 0;
      for (int k = 0; k < 3; ++k) d += std::abs(a[k] / sa - b[k] / sb);
      EXPECT_GT(d, 0.06) << i << " " << j;
    }
}

TEST(PartitionColours, EmptyMeshAndMismatchedClustering) {
  const Mesh empty;
  const Clustering none = clustering_from_labels(std::vector<std::uint32_t>{}, empty.triangles());
  EXPECT_EQ(cluster_graph(empty, none).size(), 0u);
  EXPECT_TRUE(border_edges(empty, none).empty());
  const Mesh m = strip_grid(2);
  EXPECT_THROW((void)cluster_graph(m, none), std::invalid_argument);
}

}  // namespace
}  // namespace ptc::viz
