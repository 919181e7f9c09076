// The SAH-split baseline (toolkit/clustering/sah_split.h). Independent answers: validate() is
// itself checked against brute force (clustering_result_test); here each result is also checked
// item by item against the input (every triangle once, limits recounted by hand), hard inputs
// first, then the real meshes, determinism and the effect of the fill term.
#include "toolkit/clustering/sah_split.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "toolkit/io/mesh_io.h"
#include "test_meshes.h"

namespace ptc {
namespace {

using Ids = std::vector<std::uint32_t>;
using namespace test_meshes;  // grid, concat, expect_partition_within_limits, joined

ClusterConfig config(std::uint32_t max_count, std::uint32_t max_triangles = 0) {
  ClusterConfig c;
  c.method = ClusterMethod::SahSplit;
  c.max_count = max_count;
  c.max_triangles = max_triangles;
  return c;
}

// The full contract: leaves partition the mesh within the limits; clusters additionally pass
// validate(); clusters are the edge-connected pieces of the leaves; two runs are bit-identical.
void expect_contract(const Mesh& m, const ClusterConfig& cfg, const SahSplitOptions& opt = {}) {
  const ClusterLimits lim = sah_split_limits(cfg);
  const Clustering leaves = sah_split_leaves(m, cfg, opt);
  expect_partition_within_limits(leaves, m, lim);
  const Clustering c = sah_split_clusters(m, cfg, opt);
  expect_partition_within_limits(c, m, lim);
  const auto issues = validate(c, m.triangles(), lim);
  EXPECT_TRUE(issues.empty()) << joined(issues);
  // Every cluster lies inside one leaf, and there are at least as many clusters as leaves.
  const Ids leaf_of = leaves.cluster_of_triangle();
  for (std::size_t k = 0; k < c.cluster_count(); ++k)
    for (auto t : c.triangles_of(k)) EXPECT_EQ(leaf_of[t], leaf_of[c.triangles_of(k)[0]]);
  EXPECT_GE(c.cluster_count(), leaves.cluster_count());
  const Clustering again = sah_split_clusters(m, cfg, opt);
  EXPECT_EQ(again.triangle_order, c.triangle_order);
  EXPECT_EQ(again.triangle_offsets, c.triangle_offsets);
  EXPECT_EQ(again.vertices, c.vertices);
  EXPECT_EQ(again.vertex_offsets, c.vertex_offsets);
}

TEST(SahSplit, LimitsAndBadConfigurations) {
  EXPECT_THROW((void)sah_split_limits(config(2)), std::invalid_argument);
  EXPECT_THROW((void)sah_split_limits(config(0)), std::invalid_argument);
  EXPECT_EQ(sah_split_limits(config(50)).max_vertices, 50u);
  EXPECT_EQ(sah_split_limits(config(50)).max_triangles, 100u);
  EXPECT_EQ(sah_split_limits(config(64, 64)).max_triangles, 64u);
  EXPECT_EQ(sah_split_limits(config(0xffffffffu)).max_triangles, 0xffffffffu);  // saturates
  const Mesh m = grid(2, 2);
  EXPECT_THROW((void)sah_split_clusters(m, config(2)), std::invalid_argument);
  EXPECT_THROW((void)sah_split_clusters(m, config(50), {1, 0.5}), std::invalid_argument);
  EXPECT_THROW((void)sah_split_clusters(m, config(50), {2000, 0.5}), std::invalid_argument);
  EXPECT_THROW((void)sah_split_clusters(m, config(50), {32, -1}), std::invalid_argument);
  EXPECT_THROW((void)sah_split_clusters(m, config(50), {32, std::nan("")}), std::invalid_argument);
}

TEST(SahSplit, EmptyMesh) {
  const Clustering c = sah_split_clusters(Mesh(), config(50));
  EXPECT_EQ(c.cluster_count(), 0u);
  EXPECT_TRUE(c.triangle_order.empty());
  EXPECT_EQ(c.vertex_offsets, Ids{0});
}

TEST(SahSplit, SingleTriangle) {
  const Mesh m({{0, 1, 2}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
  const Clustering c = sah_split_clusters(m, config(3, 1));
  ASSERT_EQ(c.cluster_count(), 1u);
  EXPECT_EQ(c.triangle_order, Ids{0});
  EXPECT_EQ(c.vertices, (Ids{0, 1, 2}));
  expect_contract(m, config(3, 1));
}

TEST(SahSplit, SmallestLimitsGiveOneTrianglePerCluster) {
  const Mesh m = grid(4, 3);
  const Clustering c = sah_split_clusters(m, config(3, 1));
  EXPECT_EQ(c.cluster_count(), m.triangle_count());
  expect_contract(m, config(3, 1));
  expect_contract(m, config(4));
}

TEST(SahSplit, AllCentroidsEqualFallsBackToIndexMedian) {
  // 1000 copies of one triangle (and reversed copies): every centroid equal, every box equal.
  std::vector<Tri> t;
  for (int i = 0; i < 1000; ++i) t.push_back(i % 2 ? Tri{0, 1, 2} : Tri{0, 2, 1});
  const Mesh m(std::move(t), {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
  expect_contract(m, config(50));
  // Index-order medians: 1000 -> 500 -> 250 -> 125 -> 62 + 63, so 16 leaves of consecutive ids.
  const Clustering c = sah_split_leaves(m, config(50));
  ASSERT_EQ(c.cluster_count(), 16u);
  for (std::size_t k = 0; k < c.cluster_count(); ++k) {
    const auto ts = c.triangles_of(k);
    EXPECT_EQ(ts.back() - ts.front() + 1, ts.size()) << "cluster " << k;
  }
}

TEST(SahSplit, AllPositionsEqualAndCollinearMeshes) {
  // Zero-area boxes everywhere: the count-only cost path.
  Mesh g = grid(12, 12);
  std::vector<Vec3> same(g.vertex_count(), Vec3(3, -2, 7));
  expect_contract(g.with_positions(same), config(10));
  std::vector<Vec3> line;
  for (std::size_t v = 0; v < g.vertex_count(); ++v) line.emplace_back(double(v % 13), 0, 0);
  expect_contract(g.with_positions(line), config(10));
}

TEST(SahSplit, ManyTinyComponents) {
  // 600 separate triangles on a 3D lattice: every cluster must end up a single triangle.
  const Mesh m = triangle_lattice(600);
  expect_contract(m, config(50));
  EXPECT_EQ(sah_split_clusters(m, config(50)).cluster_count(), 600u);
  EXPECT_LT(sah_split_leaves(m, config(50)).cluster_count(), 600u);  // leaves mix components
}

TEST(SahSplit, NonManifoldFan) {
  // 300 triangles on the single edge 0-1, apexes on a circle: all edge-connected, 302 vertices.
  const Mesh m = edge_fan(300);
  expect_contract(m, config(50));
  expect_contract(m, config(3));
}

TEST(SahSplit, DegenerateAndDuplicateTriangles) {
  Mesh g = grid(10, 10);
  std::vector<Tri> t(g.triangles().begin(), g.triangles().end());
  const auto n = static_cast<std::uint32_t>(t.size());
  for (std::uint32_t i = 0; i < n; i += 3) t.push_back({t[i][0], t[i][2], t[i][1]});  // reversed duplicates
  for (std::uint32_t i = 0; i < n; i += 7) t.push_back(t[i]);                         // duplicates
  for (std::uint32_t v = 0; v < 121; v += 5) t.push_back({v, v, v});                 // collapsed
  for (std::uint32_t v = 0; v + 1 < 121; v += 4) t.push_back({v, v + 1, v});          // repeated index
  t.push_back({0, 1, 2});                                                              // collinear
  const Mesh m(std::move(t), std::vector<Vec3>(g.positions().begin(), g.positions().end()));
  expect_contract(m, config(50));
  expect_contract(m, config(8, 5));
  // A collapsed triangle has no edge, so it is always a cluster of its own.
  const Clustering c = sah_split_clusters(m, config(50));
  const Ids of = c.cluster_of_triangle();
  for (std::size_t tt = 0; tt < m.triangle_count(); ++tt) {
    const Tri& f = m.triangle(tt);
    if (f[0] == f[1] && f[1] == f[2]) {
      EXPECT_EQ(c.triangles_of(of[tt]).size(), 1u) << "triangle " << tt;
    }
  }
}

TEST(SahSplit, FarApartPatchesWithinLimitsAreTheClusters) {
  // Two 4x4 grids (32 triangles, 25 vertices each) 1000 units apart; limits fit one grid: the
  // first split must separate them and no further split is allowed.
  const Mesh m = concat(grid(4, 4), grid(4, 4, 1000.0));
  const Clustering c = sah_split_clusters(m, config(25, 32));
  ASSERT_EQ(c.cluster_count(), 2u);
  Ids first(32), second(32);
  std::iota(first.begin(), first.end(), 0u);
  std::iota(second.begin(), second.end(), 32u);
  EXPECT_EQ(Ids(c.triangles_of(0).begin(), c.triangles_of(0).end()), first);
  EXPECT_EQ(Ids(c.triangles_of(1).begin(), c.triangles_of(1).end()), second);
}

TEST(SahSplit, FarOffsetAndTinyScale) {
  const Mesh g = grid(20, 20);
  std::vector<Vec3> far, tiny;
  for (const Vec3& p : g.positions()) {
    far.push_back(Vec3(1e7, -1e7, 1e7) + 1e-3 * p);
    tiny.push_back(1e-30 * p);
  }
  expect_contract(g.with_positions(far), config(20));
  expect_contract(g.with_positions(tiny), config(20));
  // Scaling by a power of two is exact in every step: bit-identical clusters.
  std::vector<Vec3> scaled;
  for (const Vec3& p : g.positions()) scaled.push_back(std::ldexp(1.0, -90) * p);
  const Clustering a = sah_split_clusters(g, config(20));
  const Clustering b = sah_split_clusters(g.with_positions(scaled), config(20));
  EXPECT_EQ(a.triangle_order, b.triangle_order);
  EXPECT_EQ(a.triangle_offsets, b.triangle_offsets);
}

class SahSplitRealMesh : public ::testing::TestWithParam<std::string> {};

TEST_P(SahSplitRealMesh, ValidWithLimitsAndDeterministic) {
  const Mesh m = read_mesh(std::string(PTC_TEST_DATA) + "/meshes/" + GetParam()).mesh;
  expect_contract(m, config(50));      // 50 vertices / 100 triangles
  expect_contract(m, config(64, 64));  // the hardware cluster default
  expect_contract(m, config(50), {16, 0.0});
}

TEST_P(SahSplitRealMesh, FillTermGivesFewerLeaves) {
  // The point of the fill term (header): fewer, fuller leaves than the plain SAH cost.
  const Mesh m = read_mesh(std::string(PTC_TEST_DATA) + "/meshes/" + GetParam()).mesh;
  const std::size_t plain = sah_split_leaves(m, config(50), {32, 0.0}).cluster_count();
  const std::size_t filled = sah_split_leaves(m, config(50), {32, 0.5}).cluster_count();
  EXPECT_LT(filled, plain);
}

INSTANTIATE_TEST_SUITE_P(Cgal, SahSplitRealMesh, ::testing::Values("elephant.off", "armadillo.off"),
                         [](const auto& param_info) { return param_info.param.substr(0, param_info.param.find('.')); });

}  // namespace
}  // namespace ptc
