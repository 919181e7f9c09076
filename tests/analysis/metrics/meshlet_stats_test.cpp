// meshoptimizer's cluster statistics (analysis/metrics/meshlet_stats.h) on hand-made clusters and
// against a second method (sets and breadth-first search) on Morton runs of a real mesh.
#include <gtest/gtest.h>

#include <queue>
#include <set>

#include "analysis/metrics/meshlet_stats.h"
#include "toolkit/clustering/morton_runs.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

TEST(MeshletStats, HandMadeClusters) {
  // Triangles 0, 1 share edge (1, 2); triangle 2 touches triangle 1 at vertex 3 only; triangle 3
  // is far away.
  const std::vector<Tri> tris{{0, 1, 2}, {1, 3, 2}, {3, 4, 5}, {6, 7, 8}};
  const Clustering c = clustering_from_labels(std::vector<std::uint32_t>{0, 1, 1, 2}, tris);
  // Cluster 2 = triangle 3 alone; and a cluster {0, 3} of two disjoint triangles:
  const Clustering d = clustering_from_labels(std::vector<std::uint32_t>{0, 1, 1, 0}, tris);
  const auto s = meshlet_shapes(c, tris, 9, 4);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].boundary_vertices, 2u);  // vertices 1 and 2 are also in cluster 1
  EXPECT_EQ(s[1].boundary_vertices, 2u);
  EXPECT_EQ(s[2].boundary_vertices, 0u);
  EXPECT_EQ(s[1].components, 1u);  // joined at vertex 3: one component (vertex connectivity)
  EXPECT_EQ(s[0].components, 1u);
  EXPECT_TRUE(s[0].not_full);      // 3 < 4 vertices
  EXPECT_FALSE(s[1].not_full);     // 5 vertices
  const auto t = meshlet_shapes(d, tris, 9, 4);
  EXPECT_EQ(t[0].components, 2u);  // {0, 1, 2} and {6, 7, 8}
  const MeshletReport r = meshlet_report(c, s);
  EXPECT_EQ(r.clusters, 3u);
  EXPECT_DOUBLE_EQ(r.avg_vertices, (3.0 + 5.0 + 3.0) / 3);
  EXPECT_DOUBLE_EQ(r.avg_triangles, 4.0 / 3);
  EXPECT_DOUBLE_EQ(r.avg_boundary, 4.0 / 3);
  EXPECT_DOUBLE_EQ(r.avg_connected, 1.0);
  EXPECT_EQ(r.not_full, 2u);
  EXPECT_EQ(meshlet_report(Clustering{}, {}).avg_vertices, 0.0);
}

TEST(MeshletStats, AgreeWithSetsAndBreadthFirstSearch) {
  const Mesh m = read_mesh(std::string(PTC_TEST_DATA) + "/meshes/elephant.off").mesh;
  const Clustering c = morton_runs(m, MortonRunsConfig{20, 90, 3});  // compact, not always connected
  const auto s = meshlet_shapes(c, m.triangles(), m.vertex_count(), 64);
  std::vector<std::set<std::uint32_t>> sets(c.cluster_count());
  for (std::size_t k = 0; k < c.cluster_count(); ++k)
    for (std::uint32_t t : c.triangles_of(k))
      for (std::uint32_t v : m.triangle(t)) sets[k].insert(v);
  std::size_t disconnected = 0;
  for (std::size_t k = 0; k < c.cluster_count(); ++k) {
    std::uint32_t boundary = 0;
    for (std::uint32_t v : sets[k]) {
      bool other = false;
      for (std::size_t j = 0; j < sets.size() && !other; ++j) other = j != k && sets[j].count(v);
      boundary += other;
    }
    EXPECT_EQ(s[k].boundary_vertices, boundary) << k;
    // Components by breadth-first search over the cluster's triangles sharing a vertex.
    const auto tris = c.triangles_of(k);
    std::vector<bool> seen(tris.size(), false);
    std::uint32_t comps = 0;
    for (std::size_t i = 0; i < tris.size(); ++i) {
      if (seen[i]) continue;
      ++comps;
      std::queue<std::size_t> q;
      q.push(i);
      seen[i] = true;
      while (!q.empty()) {
        const std::size_t a = q.front();
        q.pop();
        for (std::size_t b = 0; b < tris.size(); ++b) {
          if (seen[b]) continue;
          bool share = false;
          for (std::uint32_t u : m.triangle(tris[a]))
            for (std::uint32_t w : m.triangle(tris[b])) share |= u == w;
          if (share) seen[b] = true, q.push(b);
        }
      }
    }
    EXPECT_EQ(s[k].components, comps) << k;
    disconnected += comps > 1;
    EXPECT_EQ(s[k].not_full, sets[k].size() < 64) << k;
  }
  EXPECT_GT(disconnected, 0u);  // Morton runs are not always connected: the test sees both cases
}

}  // namespace
}  // namespace ptc
