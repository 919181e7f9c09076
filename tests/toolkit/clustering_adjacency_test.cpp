// Adjacency by positions (cluster.h ClusterAdjacency): a triangle soup clusters exactly like the
// connected mesh it came from. The independent answer is the connected mesh itself, clustered
// with its own edges: its vertices are numbered in the order in which the soup's weld numbers
// them (first use in triangle order), so both runs see the same mesh and must give the same
// partition, triangle for triangle, for every method.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"
#include "test_meshes.h"

namespace ptc {
namespace {

using namespace test_meshes;

std::vector<std::uint32_t> labels_of(const Clustering& c) { return c.cluster_of_triangle(); }

ClusterConfig config(ClusterMethod m, ObjectiveKind o, std::uint32_t size, ClusterAdjacency a) {
  ClusterConfig c;
  c.method = m;
  c.objective = o;
  c.max_count = size;
  c.max_size = size;
  c.adjacency = a;
  return c;
}

TEST(ClusterAdjacency, SoupDetection) {
  const Mesh g = grid(3, 2);
  EXPECT_FALSE(is_triangle_soup(g));
  EXPECT_TRUE(is_triangle_soup(soup_of(g)));
  EXPECT_FALSE(is_triangle_soup(Mesh()));                    // empty
  EXPECT_FALSE(is_triangle_soup(Mesh({{0, 1, 2}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)})));  // one triangle
  // One shared vertex among otherwise separate triangles: not a soup.
  EXPECT_FALSE(is_triangle_soup(Mesh({{0, 1, 2}, {2, 3, 4}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0),
                                                               Vec3(1, 1, 0), Vec3(2, 1, 0)})));
  EXPECT_EQ(resolve_adjacency(g, ClusterAdjacency::Auto), ClusterAdjacency::Edges);
  EXPECT_EQ(resolve_adjacency(soup_of(g), ClusterAdjacency::Auto), ClusterAdjacency::Positions);
  EXPECT_EQ(resolve_adjacency(soup_of(g), ClusterAdjacency::Edges), ClusterAdjacency::Edges);
  EXPECT_EQ(resolve_adjacency(g, ClusterAdjacency::Positions), ClusterAdjacency::Positions);
  for (ClusterAdjacency a : {ClusterAdjacency::Auto, ClusterAdjacency::Edges, ClusterAdjacency::Positions})
    EXPECT_EQ(parse_cluster_adjacency(to_string(a)), a);
  EXPECT_EQ(parse_cluster_adjacency("Positions"), ClusterAdjacency::Positions);
  EXPECT_FALSE(parse_cluster_adjacency("vertices"));
}

TEST(ClusterAdjacency, WeldedTrianglesAreTheConnectedMesh) {
  // The adjacency of a soup is the connected mesh, each corner named by the soup's first vertex
  // at its position: soup vertex 3 t + k for the first corner (t, k) using that mesh vertex.
  for (const Mesh& m : {grid(4, 3), icosahedron(), sphere_patch(6, 5), load("armadillo.off")}) {
    const Mesh soup = soup_of(m);
    std::vector<std::uint32_t> first(m.vertex_count(), 0xffffffffu);
    for (std::uint32_t t = 0; t < m.triangle_count(); ++t)
      for (int k = 0; k < 3; ++k)
        if (first[m.triangles()[t][k]] == 0xffffffffu) first[m.triangles()[t][k]] = 3 * t + k;
    const std::vector<Tri> w = adjacency_triangles(soup, ClusterAdjacency::Auto);
    ASSERT_EQ(w.size(), m.triangle_count());
    for (std::size_t t = 0; t < w.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(w[t][k], first[m.triangles()[t][k]]) << "triangle " << t;
        ASSERT_EQ(soup.positions()[w[t][k]], m.positions()[m.triangles()[t][k]]);  // indexes the soup's own positions
      }
    // Edges: the mesh's own triangles.
    const std::vector<Tri> e = adjacency_triangles(soup, ClusterAdjacency::Edges);
    ASSERT_EQ(e.size(), soup.triangle_count());
    for (std::size_t t = 0; t < e.size(); ++t) ASSERT_EQ(e[t], soup.triangles()[t]);
  }
}

TEST(ClusterAdjacency, SoupClustersLikeItsConnectedMesh) {
  const Mesh arm = load("armadillo.off");
  struct Run {
    ClusterMethod m;
    ObjectiveKind o;
  };
  const Run runs[] = {{ClusterMethod::Growth, ObjectiveKind::Acc},      {ClusterMethod::Contraction, ObjectiveKind::Acc},
                      {ClusterMethod::Growth, ObjectiveKind::Naive},    {ClusterMethod::Contraction, ObjectiveKind::Gwh01},
                      {ClusterMethod::SahSplit, ObjectiveKind::Acc},    {ClusterMethod::Meshopt, ObjectiveKind::Acc}};
  for (const Mesh& m : {grid(12, 9), sphere_patch(10, 8), arm}) {
    const Mesh ref = by_first_use(m);
    const Mesh soup = soup_of(m);
    for (const Run& r : runs) {
      const std::string what = std::string(to_string(r.m)) + "/" + std::string(to_string(r.o)) + " on " +
                               std::to_string(m.triangle_count()) + " triangles";
      const Clustering want = cluster_mesh(ref, config(r.m, r.o, 24, ClusterAdjacency::Edges));
      const Clustering got = cluster_mesh(soup, config(r.m, r.o, 24, ClusterAdjacency::Auto));
      EXPECT_EQ(labels_of(got), labels_of(want)) << what;
      ASSERT_GT(want.cluster_count(), 0u);
      EXPECT_LT(got.cluster_count(), soup.triangle_count() / 4) << what;  // real clusters, not singletons
      // The vertex lists are the soup's own vertices (3 per triangle, each in one cluster).
      std::size_t listed = 0;
      for (std::size_t k = 0; k < got.cluster_count(); ++k) listed += got.vertices_of(k).size();
      EXPECT_EQ(listed, soup.vertex_count()) << what;
      // Valid by the adjacency it grew over (connectivity, vertex limit in welded vertices), not by
      // the soup's own edges.
      ClusterLimits lim;
      if (r.o != ObjectiveKind::Acc || r.m == ClusterMethod::SahSplit || r.m == ClusterMethod::Meshopt)
        lim.max_vertices = 24;
      const std::vector<Tri> adj = adjacency_triangles(soup, ClusterAdjacency::Positions);
      const auto issues = validate(got, soup.triangles(), lim, 20, adj);
      EXPECT_TRUE(issues.empty()) << what << ": " << joined(issues);
      const auto by_edges = validate(got, soup.triangles(), {}, 20);
      EXPECT_FALSE(by_edges.empty()) << what;
      EXPECT_NE(joined(by_edges).find("not edge-connected"), std::string::npos) << what;
    }
  }
}

TEST(ClusterAdjacency, EdgesOnASoupGiveSingletons) {
  const Mesh soup = soup_of(sphere_patch(8, 6));
  const Clustering c =
      cluster_mesh(soup, config(ClusterMethod::Growth, ObjectiveKind::Acc, 30, ClusterAdjacency::Edges));
  EXPECT_EQ(c.cluster_count(), soup.triangle_count());
}

TEST(ClusterAdjacency, PositionsJoinASeam) {
  // Two grids side by side whose touching column of vertices is duplicated (a texture seam):
  // by edges no cluster crosses the seam (x = 6); by positions some do, and both validate.
  const Mesh m = concat(grid(6, 6), grid(6, 6, 6.0));
  ASSERT_FALSE(is_triangle_soup(m));
  auto crosses = [&](const Clustering& c) {
    std::size_t n = 0;
    for (std::size_t k = 0; k < c.cluster_count(); ++k) {
      bool left = false, right = false;
      for (std::uint32_t t : c.triangles_of(k)) (t < 72 ? left : right) = true;
      n += left && right;
    }
    return n;
  };
  const ClusterConfig e = config(ClusterMethod::Growth, ObjectiveKind::Acc, 40, ClusterAdjacency::Auto);
  const Clustering by_edges = cluster_mesh(m, e);
  EXPECT_EQ(crosses(by_edges), 0u);
  EXPECT_TRUE(validate(by_edges, m.triangles()).empty());
  ClusterConfig p = e;
  p.adjacency = ClusterAdjacency::Positions;
  const Clustering by_pos = cluster_mesh(m, p);
  EXPECT_GT(crosses(by_pos), 0u);
  EXPECT_TRUE(validate(by_pos, m.triangles(), {}, 20, adjacency_triangles(m, ClusterAdjacency::Positions)).empty());
  EXPECT_FALSE(validate(by_pos, m.triangles()).empty());
}

TEST(ClusterAdjacency, HardCases) {
  // NaN corners weld with nothing; -0.0 welds with +0.0; a duplicated triangle shares all sides.
  Mesh s = soup_of(grid(3, 3));
  std::vector<Vec3> p(s.positions().begin(), s.positions().end());
  for (Vec3& q : p)
    if (q.x() == 0) q.x() = -0.0;  // the soup's left column written as -0.0 in every triangle ...
  p[0].x() = 0.0;                  // ... but one (+0.0): still the same position
  p[4] = Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0);  // triangle 1's second corner
  s = s.with_positions(p);
  const std::vector<Tri> w = adjacency_triangles(s, ClusterAdjacency::Positions);
  // Triangle 0's first corner (+0.0) and every soup corner at (-0.0, 0, 0) are one vertex.
  for (std::size_t t = 0; t < w.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (p[3 * t + k] == Vec3(0, 0, 0)) {
        EXPECT_EQ(w[t][k], 0u) << "triangle " << t;
      }
  for (std::size_t t = 0; t < w.size(); ++t)
    for (int k = 0; k < 3; ++k)
      if (t * 3 + k != 4) {
        EXPECT_NE(w[t][k], w[1][1]) << "NaN corner welded to triangle " << t;
      }
  const Clustering c = cluster_mesh(s, config(ClusterMethod::Growth, ObjectiveKind::Acc, 20, ClusterAdjacency::Auto));
  EXPECT_TRUE(validate(c, s.triangles(), {}, 20, w).empty());
  // A soup of two identical triangles: one cluster by positions.
  const Mesh twin({{0, 1, 2}, {3, 4, 5}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 0), Vec3(1, 0, 0),
                                           Vec3(0, 1, 0)});
  const Clustering tc =
      cluster_mesh(twin, config(ClusterMethod::Contraction, ObjectiveKind::Acc, 20, ClusterAdjacency::Auto));
  EXPECT_EQ(tc.cluster_count(), 1u);
  // A soup whose triangles touch nowhere stays one triangle per cluster.
  Mesh apart = soup_of(grid(4, 1));
  std::vector<Vec3> q(apart.positions().begin(), apart.positions().end());
  for (std::size_t i = 0; i < q.size(); ++i) q[i] += Vec3(10.0 * double(i / 3), 0, 0);
  apart = apart.with_positions(q);
  EXPECT_EQ(cluster_mesh(apart, config(ClusterMethod::Growth, ObjectiveKind::Acc, 20, ClusterAdjacency::Auto))
                .cluster_count(),
            apart.triangle_count());
  // A wrong-sized adjacency is a message, not a crash.
  const auto bad = validate(c, s.triangles(), {}, 20, std::vector<Tri>(3, Tri{0, 1, 2}));
  ASSERT_EQ(bad.size(), 1u);
  EXPECT_NE(bad[0].find("adjacency"), std::string::npos);
}

}  // namespace
}  // namespace ptc
