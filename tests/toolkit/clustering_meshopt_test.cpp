// The meshoptimizer baseline (toolkit/clustering/meshopt.h): the mapping of the limits, the mapping
// of meshlet triangles back to triangle ids (against hand-made answers), what meshoptimizer 0.18
// itself does with degenerate and duplicate triangles (called directly), then the full contract on
// hard inputs and on the real meshes.
#include "toolkit/clustering/meshopt.h"

#include <gtest/gtest.h>

#include <meshoptimizer.h>

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
using namespace test_meshes;  // bumpy_grid, expect_partition_within_limits, joined

ClusterConfig config(std::uint32_t max_count, std::uint32_t max_triangles = 0) {
  ClusterConfig c;
  c.method = ClusterMethod::Meshopt;
  c.max_count = max_count;
  c.max_triangles = max_triangles;
  return c;
}


void expect_contract(const Mesh& m, const ClusterConfig& cfg) {
  const ClusterLimits lim = meshopt_limits(cfg);
  const Clustering meshlets = meshopt_meshlets(m, cfg);
  expect_partition_within_limits(meshlets, m, lim);
  const Clustering c = meshopt_clusters(m, cfg);
  expect_partition_within_limits(c, m, lim);
  const auto issues = validate(c, m.triangles(), lim);
  EXPECT_TRUE(issues.empty()) << joined(issues);
  const Ids meshlet_of = meshlets.cluster_of_triangle();
  for (std::size_t k = 0; k < c.cluster_count(); ++k)
    for (auto t : c.triangles_of(k)) EXPECT_EQ(meshlet_of[t], meshlet_of[c.triangles_of(k)[0]]);
  const Clustering again = meshopt_clusters(m, cfg);
  EXPECT_EQ(again.triangle_order, c.triangle_order);
  EXPECT_EQ(again.triangle_offsets, c.triangle_offsets);
  EXPECT_EQ(again.vertices, c.vertices);
  EXPECT_EQ(again.vertex_offsets, c.vertex_offsets);
}

// ---------------------------------------------------------------------------------------------
// Limits

TEST(MeshoptLimits, MapsOntoMeshoptimizer018Range) {
  EXPECT_THROW((void)meshopt_limits(config(2)), std::invalid_argument);
  EXPECT_THROW((void)meshopt_limits(config(0)), std::invalid_argument);
  EXPECT_THROW((void)meshopt_limits(config(256)), std::invalid_argument);
  EXPECT_THROW((void)meshopt_limits(config(50, 3)), std::invalid_argument);
  EXPECT_THROW((void)meshopt_limits(config(50, 513)), std::invalid_argument);
  EXPECT_EQ(meshopt_limits(config(50)).max_vertices, 50u);
  EXPECT_EQ(meshopt_limits(config(50)).max_triangles, 100u);
  EXPECT_EQ(meshopt_limits(config(25)).max_triangles, 48u);       // 50 rounded down to a multiple of 4
  EXPECT_EQ(meshopt_limits(config(64, 64)).max_triangles, 64u);
  EXPECT_EQ(meshopt_limits(config(50, 7)).max_triangles, 4u);
  EXPECT_EQ(meshopt_limits(config(255)).max_triangles, 508u);     // 510 -> 508
  EXPECT_EQ(meshopt_limits(config(255, 512)).max_triangles, 512u);
  EXPECT_EQ(meshopt_limits(config(3)).max_triangles, 4u);         // 6 -> 4
  try {
    (void)meshopt_limits(config(300));
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("[3, 255]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("300"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)meshopt_clusters(bumpy_grid(2, 2), config(256)), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// meshlet_labels: meshlet triangles back to triangle ids

TEST(MeshletLabels, HandMadeMeshletsWithDuplicatesAndMissingTriangles) {
  //                        0          1          2 (= 0)    3 (reversed 0) 4 (collapsed) 5
  const std::vector<Tri> tris{{0, 1, 2}, {1, 3, 2}, {0, 1, 2}, {2, 1, 0}, {4, 4, 4}, {1, 2, 3}};
  // Meshlet 0 emits the vertex set {0,1,2} twice (rotated) and (4,4,4); meshlet 1 emits {1,2,3}
  // twice and {0,1,2} once more. Nothing is missing.
  const Ids off{0, 3, 6};
  const std::vector<Tri> emitted{{1, 2, 0}, {4, 4, 4}, {2, 0, 1}, {3, 2, 1}, {0, 2, 1}, {2, 3, 1}};
  // Ascending ids of a vertex set are handed out in emission order: {0,1,2} -> 0, 2 (meshlet 0), 3
  // (meshlet 1); {1,2,3} -> 1, 5 (meshlet 1); (4,4,4) -> 4 (meshlet 0).
  EXPECT_EQ(meshlet_labels(tris, off, emitted), (Ids{0, 1, 0, 1, 0, 1}));
  // Triangles no meshlet emitted become clusters of their own, numbered after the meshlets.
  const Ids off2{0, 1, 2};
  const std::vector<Tri> emitted2{{3, 1, 2}, {2, 1, 0}};
  EXPECT_EQ(meshlet_labels(tris, off2, emitted2), (Ids{1, 0, 2, 3, 4, 5}));
  EXPECT_EQ(meshlet_labels(tris, Ids{0}, {}), (Ids{0, 1, 2, 3, 4, 5}));
  EXPECT_TRUE(meshlet_labels({}, Ids{0}, {}).empty());
}

TEST(MeshletLabels, InconsistentMeshletsThrow) {
  const std::vector<Tri> tris{{0, 1, 2}, {1, 3, 2}};
  const std::vector<Tri> unknown{{0, 1, 3}};
  EXPECT_THROW((void)meshlet_labels(tris, Ids{0, 1}, unknown), std::logic_error);
  const std::vector<Tri> twice{{0, 1, 2}, {2, 0, 1}};
  EXPECT_THROW((void)meshlet_labels(tris, Ids{0, 2}, twice), std::logic_error);
  const std::vector<Tri> one{{0, 1, 2}};
  EXPECT_THROW((void)meshlet_labels(tris, Ids{}, one), std::invalid_argument);
  EXPECT_THROW((void)meshlet_labels(tris, Ids{0, 2}, one), std::invalid_argument);
  EXPECT_THROW((void)meshlet_labels(tris, Ids{1, 1}, one), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// What meshoptimizer 0.18 itself does (the finding documented in meshopt.h): degenerate triangles
// (repeated indices, zero area) and duplicate triangles are all emitted, each exactly once.

TEST(Meshoptimizer018, EmitsDegenerateAndDuplicateTriangles) {
  std::vector<float> pos;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) pos.insert(pos.end(), {float(x), float(y), 0.0f});
  std::vector<unsigned> idx;
  for (unsigned y = 0; y < 3; ++y)
    for (unsigned x = 0; x < 3; ++x) {
      const unsigned a = y * 4 + x, b = a + 1, c = a + 4, d = a + 5;
      idx.insert(idx.end(), {a, b, d, a, d, c});
    }
  // collapsed, repeated index (two kinds), duplicate, reversed duplicate, collinear
  idx.insert(idx.end(), {5, 5, 5, 0, 0, 1, 2, 3, 3, 0, 1, 5, 0, 5, 1, 0, 1, 2});
  for (const auto& [max_v, max_t] : {std::pair<std::size_t, std::size_t>{3, 4}, {6, 8}, {255, 512}}) {
    const std::size_t bound = meshopt_buildMeshletsBound(idx.size(), max_v, max_t);
    std::vector<meshopt_Meshlet> ml(bound);
    std::vector<unsigned> mv(bound * max_v);
    std::vector<unsigned char> mt(bound * max_t * 3);
    const std::size_t n = meshopt_buildMeshlets(ml.data(), mv.data(), mt.data(), idx.data(), idx.size(), pos.data(),
                                                16, 12, max_v, max_t, 0.0f);
    std::multiset<std::vector<unsigned>> in, out;
    for (std::size_t t = 0; t < idx.size() / 3; ++t) in.insert({idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]});
    for (std::size_t m = 0; m < n; ++m)
      for (unsigned j = 0; j < ml[m].triangle_count; ++j) {
        const unsigned char* l = &mt[ml[m].triangle_offset + 3 * j];
        // Corners come back in input order (same rotation and orientation).
        out.insert({mv[ml[m].vertex_offset + l[0]], mv[ml[m].vertex_offset + l[1]], mv[ml[m].vertex_offset + l[2]]});
      }
    EXPECT_EQ(out, in) << "max_vertices " << max_v << ", max_triangles " << max_t;
  }
}

// ---------------------------------------------------------------------------------------------
// The full contract on hard inputs

TEST(Meshopt, EmptyMesh) {
  const Clustering c = meshopt_clusters(Mesh(), config(50));
  EXPECT_EQ(c.cluster_count(), 0u);
  EXPECT_EQ(c.triangle_offsets, Ids{0});
}

TEST(Meshopt, SingleTriangle) {
  const Mesh m({{0, 1, 2}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
  const Clustering c = meshopt_clusters(m, config(3));
  ASSERT_EQ(c.cluster_count(), 1u);
  EXPECT_EQ(c.vertices, (Ids{0, 1, 2}));
  expect_contract(m, config(3));
}

TEST(Meshopt, OnlyDegenerateTrianglesAndAllPositionsEqual) {
  const Mesh deg({{0, 0, 1}, {2, 2, 2}, {1, 1, 1}, {0, 1, 0}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)});
  expect_contract(deg, config(3));
  expect_contract(deg, config(50));
  const Mesh g = bumpy_grid(6, 6);
  expect_contract(g.with_positions(std::vector<Vec3>(g.vertex_count(), Vec3(1, 2, 3))), config(10));
}

TEST(Meshopt, ManyTinyComponents) {
  const Mesh m = triangle_lattice(600);
  expect_contract(m, config(50));
  EXPECT_EQ(meshopt_clusters(m, config(50)).cluster_count(), 600u);
  EXPECT_LT(meshopt_meshlets(m, config(50)).cluster_count(), 600u);  // meshlets mix components
}

TEST(Meshopt, NonManifoldFan) {
  const Mesh m = edge_fan(300);
  expect_contract(m, config(50));
  expect_contract(m, config(255, 512));
  expect_contract(m, config(3));
}

TEST(Meshopt, DegenerateAndDuplicateTriangles) {
  const Mesh g = bumpy_grid(10, 10);
  std::vector<Tri> t(g.triangles().begin(), g.triangles().end());
  const auto n = static_cast<std::uint32_t>(t.size());
  for (std::uint32_t i = 0; i < n; i += 3) t.push_back({t[i][0], t[i][2], t[i][1]});
  for (std::uint32_t i = 0; i < n; i += 7) t.push_back(t[i]);
  for (std::uint32_t i = 0; i < 5; ++i) t.push_back(t[0]);  // one triangle six times over
  for (std::uint32_t v = 0; v < 121; v += 5) t.push_back({v, v, v});
  for (std::uint32_t v = 0; v + 1 < 121; v += 4) t.push_back({v, v + 1, v});
  t.push_back({0, 1, 2});
  const Mesh m(std::move(t), std::vector<Vec3>(g.positions().begin(), g.positions().end()));
  expect_contract(m, config(50));
  expect_contract(m, config(4, 4));
  const Clustering c = meshopt_clusters(m, config(50));
  const Ids of = c.cluster_of_triangle();
  for (std::size_t tt = 0; tt < m.triangle_count(); ++tt) {
    const Tri& f = m.triangle(tt);
    if (f[0] == f[1] && f[1] == f[2]) {
      EXPECT_EQ(c.triangles_of(of[tt]).size(), 1u) << "triangle " << tt;
    }
  }
}

TEST(Meshopt, FarOffsetTinyAndHugeScales) {
  // Positions are normalised before the float conversion: far-away, tiny (below float's range)
  // and huge (above it) meshes still give valid clusters, and a power-of-two scale (exact in
  // every step) gives bit-identical ones.
  const Mesh g = bumpy_grid(20, 20);
  const Clustering base = meshopt_clusters(g, config(20));
  for (const double s : {std::ldexp(1.0, -140), std::ldexp(1.0, 140), 1e-45, 1e45}) {
    std::vector<Vec3> p;
    for (const Vec3& q : g.positions()) p.push_back(s * q);
    const Mesh m = g.with_positions(p);
    expect_contract(m, config(20));
    int exponent = 0;
    if (std::frexp(s, &exponent) == 0.5) {
      const Clustering c = meshopt_clusters(m, config(20));
      EXPECT_EQ(c.triangle_order, base.triangle_order) << "scale " << s;
      EXPECT_EQ(c.triangle_offsets, base.triangle_offsets) << "scale " << s;
    }
  }
  std::vector<Vec3> far;
  for (const Vec3& q : g.positions()) far.push_back(Vec3(1e7, -1e7, 1e7) + 1e-3 * q);
  expect_contract(g.with_positions(far), config(20));
  // Far away, the float conversion of raw coordinates would collapse the mesh to a few points
  // (ulp(1e7) = 1 in float); normalised, the clusters stay about as many as at the origin (not
  // bit-identical: the subtraction of the center rounds differently).
  const Clustering c = meshopt_clusters(g.with_positions(far), config(20));
  EXPECT_LE(c.cluster_count(), base.cluster_count() + base.cluster_count() / 10);
}

class MeshoptRealMesh : public ::testing::TestWithParam<std::string> {};

TEST_P(MeshoptRealMesh, ValidWithLimitsAndDeterministic) {
  const Mesh m = read_mesh(std::string(PTC_TEST_DATA) + "/meshes/" + GetParam()).mesh;
  expect_contract(m, config(50));
  expect_contract(m, config(64, 64));
  expect_contract(m, config(255, 512));
}

INSTANTIATE_TEST_SUITE_P(Cgal, MeshoptRealMesh, ::testing::Values("elephant.off", "armadillo.off"),
                         [](const auto& param_info) { return param_info.param.substr(0, param_info.param.find('.')); });

}  // namespace
}  // namespace ptc
