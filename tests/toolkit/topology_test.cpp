// Edge map, components and dual graph against brute-force answers, item by item.
#include "toolkit/mesh/topology.h"

#include <gtest/gtest.h>

#include <boost/graph/connected_components.hpp>

#include <algorithm>
#include <map>
#include <random>
#include <set>
#include <tuple>

namespace ptc {
namespace {

// Brute force: edge -> sorted triangle set, straight from the definition.
std::map<std::pair<std::uint32_t, std::uint32_t>, std::set<std::uint32_t>> brute_edges(const std::vector<Tri>& tris) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::set<std::uint32_t>> m;
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      auto a = tris[t][k], b = tris[t][(k + 1) % 3];
      if (a == b) continue;
      m[{std::min(a, b), std::max(a, b)}].insert(t);
    }
  return m;
}

void expect_matches_brute_force(const std::vector<Tri>& tris, std::size_t V) {
  const EdgeMap em = EdgeMap::build(tris, V);
  const auto bf = brute_edges(tris);
  ASSERT_EQ(em.edge_count(), bf.size());
  std::size_t e = 0;
  for (const auto& [key, ts] : bf) {
    EXPECT_EQ(em.edge(e).v0, key.first);
    EXPECT_EQ(em.edge(e).v1, key.second);
    auto got = em.triangles_of(e);
    EXPECT_EQ(std::vector<std::uint32_t>(got.begin(), got.end()), std::vector<std::uint32_t>(ts.begin(), ts.end()))
        << "edge " << key.first << "-" << key.second;
    EXPECT_EQ(em.find(key.first, key.second), e);
    EXPECT_EQ(em.find(key.second, key.first), e);
    ++e;
  }
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      auto a = tris[t][k], b = tris[t][(k + 1) % 3];
      const std::uint32_t se = em.side_edge(t, k);
      if (a == b) {
        EXPECT_EQ(se, kNoEdge);
      } else {
        ASSERT_NE(se, kNoEdge);
        EXPECT_EQ(em.edge(se), (Edge{std::min(a, b), std::max(a, b)}));
      }
    }
}

TEST(Topology, EmptyMesh) {
  const EdgeMap em = EdgeMap::build({}, 0);
  EXPECT_EQ(em.edge_count(), 0u);
  EXPECT_EQ(em.find(0, 1), kNoEdge);
  EXPECT_EQ(vertex_connected_components({}, 0).count, 0u);
  EXPECT_EQ(boost::num_vertices(build_dual_graph(em, 0)), 0u);
}

TEST(Topology, ClosedTetrahedron) {
  std::vector<Tri> t{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  expect_matches_brute_force(t, 4);
  const EdgeMap em = EdgeMap::build(t, 4);
  EXPECT_EQ(em.edge_count(), 6u);
  EXPECT_EQ(em.boundary_edge_count(), 0u);
  EXPECT_EQ(em.non_manifold_edge_count(), 0u);
  const DualGraph g = build_dual_graph(em, 4);
  EXPECT_EQ(boost::num_edges(g), 6u);
  for (std::size_t v = 0; v < 4; ++v) EXPECT_EQ(boost::out_degree(v, g), 3u);
}

TEST(Topology, NonManifoldFanOfThreeAndDegenerates) {
  // Three triangles on edge (0,1); a repeated-index triangle (0,0,2); a triangle using edge
  // (1,2) twice (1,2,1); an isolated vertex 9.
  std::vector<Tri> t{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {0, 0, 2}, {1, 2, 1}};
  expect_matches_brute_force(t, 10);
  const EdgeMap em = EdgeMap::build(t, 10);
  const auto e01 = em.find(0, 1);
  ASSERT_NE(e01, kNoEdge);
  EXPECT_EQ(em.valence(e01), 3u);
  EXPECT_EQ(em.non_manifold_edge_count(), 1u);
  const auto e12 = em.find(1, 2);
  // (1,2,1) lists edge (1,2) once.
  auto ts = em.triangles_of(e12);
  EXPECT_EQ(std::vector<std::uint32_t>(ts.begin(), ts.end()), (std::vector<std::uint32_t>{0, 4}));
  // Dual graph: every pair on the fan of three is adjacent.
  const DualGraph g = build_dual_graph(em, t.size());
  EXPECT_TRUE(boost::edge(0, 1, g).second);
  EXPECT_TRUE(boost::edge(0, 2, g).second);
  EXPECT_TRUE(boost::edge(1, 2, g).second);
  EXPECT_EQ(g[boost::edge(1, 2, g).first].mesh_edge, e01);
}

// SortedSides against brute force: every non-collapsed side once, in the bucket of its smaller
// vertex, ordered by (larger vertex, slot); on degenerate triangles, a fan, a book of 20 pages
// (beyond insertion sort's 16 in a bucket) and random triangles.
TEST(Topology, SortedSidesAreEverySideInOrder) {
  std::vector<Tri> t{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {0, 0, 2}, {1, 2, 1}, {5, 5, 5}};
  for (std::uint32_t k = 0; k < 20; ++k) t.push_back({k % 2 ? 7u : 6u, k % 2 ? 6u : 7u, 8 + k});
  std::mt19937 rng(5);
  for (int k = 0; k < 200; ++k) {
    std::uniform_int_distribution<std::uint32_t> v(0, 40);
    t.push_back({v(rng), v(rng), v(rng)});
  }
  const std::size_t V = 41;
  const SortedSides ss = SortedSides::build(t, V);
  std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>> want;  // (smaller, larger, slot)
  for (std::uint32_t i = 0; i < t.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[i][k], b = t[i][(k + 1) % 3];
      if (a != b) want.emplace_back(std::min(a, b), std::max(a, b), 3 * i + static_cast<std::uint32_t>(k));
    }
  std::sort(want.begin(), want.end());
  ASSERT_EQ(ss.first.size(), V + 1);
  ASSERT_EQ(ss.sides.size(), want.size());
  std::size_t i = 0;
  for (std::uint32_t v = 0; v < V; ++v)
    for (std::uint32_t j = ss.first[v]; j < ss.first[v + 1]; ++j, ++i) {
      EXPECT_EQ(std::get<0>(want[i]), v) << "side " << i;
      EXPECT_EQ(std::get<1>(want[i]), ss.sides[j].other) << "side " << i;
      EXPECT_EQ(std::get<2>(want[i]), ss.sides[j].slot) << "side " << i;
    }
  EXPECT_EQ(i, want.size());
  expect_matches_brute_force(t, V);
}

TEST(Topology, HugeBookIsLinearInTheDualGraph) {
  // 5000 pages on edge (0, 1): a clique would have 12.5M dual edges; the path has 4999 and the
  // same single component.
  const std::uint32_t pages = 5000;
  std::vector<Tri> t;
  for (std::uint32_t i = 0; i < pages; ++i) t.push_back({0, 1, 2 + i});
  const EdgeMap em = EdgeMap::build(t, pages + 2);
  EXPECT_EQ(em.valence(em.find(0, 1)), pages);
  const DualGraph g = build_dual_graph(em, t.size());
  EXPECT_EQ(boost::num_edges(g), pages - 1u);
  EXPECT_EQ(edge_connected_components(em, t.size()).count, 1u);
  std::vector<int> comp(t.size());
  EXPECT_EQ(boost::connected_components(g, comp.data()), 1);
}

TEST(Topology, ComponentsByVertexAndByEdge) {
  // Two triangles touching only at vertex 2 (a bow tie) and a separate triangle.
  std::vector<Tri> t{{0, 1, 2}, {2, 3, 4}, {5, 6, 7}};
  const auto vc = vertex_connected_components(t, 8);
  EXPECT_EQ(vc.count, 2u);
  EXPECT_EQ(vc.label, (std::vector<std::uint32_t>{0, 0, 1}));
  const auto ec = edge_connected_components(EdgeMap::build(t, 8), 3);
  EXPECT_EQ(ec.count, 3u);
  EXPECT_EQ(ec.label, (std::vector<std::uint32_t>{0, 1, 2}));
}

TEST(Topology, RandomSoupsMatchBruteForce) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const auto V = static_cast<std::uint32_t>(1 + rng() % 12);
    std::vector<Tri> t(rng() % 40);
    auto r = [&] { return static_cast<std::uint32_t>(rng() % V); };
    for (auto& f : t) f = {r(), r(), r()};
    expect_matches_brute_force(t, V);
    // Components through the dual graph agree with Boost's connected_components.
    const EdgeMap em = EdgeMap::build(t, V);
    const DualGraph g = build_dual_graph(em, t.size());
    std::vector<int> comp(t.size());
    const int n = t.empty() ? 0 : boost::connected_components(g, comp.data());
    const auto ours = edge_connected_components(em, t.size());
    EXPECT_EQ(static_cast<std::uint32_t>(n), ours.count);
    for (std::size_t i = 0; i < t.size(); ++i)
      for (std::size_t j = 0; j < t.size(); ++j) EXPECT_EQ(comp[i] == comp[j], ours.label[i] == ours.label[j]);
  }
}

}  // namespace
}  // namespace ptc
