// End-point overlap (analysis/metrics/epo.h) against an all-pairs loop, node by node, for a
// triangle BVH and a cluster BVH; zero for geometry that no other node's box reaches.
#include <gtest/gtest.h>

#include <functional>

#include "analysis/metrics/epo.h"
#include "bvh/sah_builder.h"
#include "toolkit/anim/scene.h"
#include "toolkit/clustering/morton_runs.h"
#include "toolkit/geometry/clip.h"

namespace ptc {
namespace {

// The tree over primitive boxes (primitive p = the triangles `members(p)`).
bvh::Bvh build(const Mesh& m, std::size_t prims, const std::function<std::vector<std::uint32_t>(std::size_t)>& members,
               std::uint32_t leaf) {
  std::vector<bvh::Box3f> boxes;
  std::vector<bvh::Vec3f> centroids;
  for (std::size_t p = 0; p < prims; ++p) {
    Box3 b;
    for (std::uint32_t t : members(p))
      for (std::uint32_t v : m.triangle(t)) b.extend(m.position(v));
    boxes.push_back(bvh::to_frame(b, Vec3::Zero()));
    centroids.push_back(boxes.back().center());
  }
  bvh::BuildConfig cfg;
  cfg.max_leaf_size = leaf;
  return bvh::build_binned_sah({boxes, centroids, {}}, cfg);
}

// All pairs: for node i, every triangle outside its subtree clipped to the node's box.
std::vector<double> brute_force(const Mesh& m, const bvh::Bvh& t,
                                const std::function<std::vector<std::uint32_t>(std::size_t)>& members) {
  std::vector<double> out(t.nodes.size());
  std::function<void(std::uint32_t, std::vector<std::uint32_t>&)> collect = [&](std::uint32_t n, std::vector<std::uint32_t>& s) {
    const auto& nd = t.nodes[n];
    if (nd.is_leaf()) {
      for (std::uint32_t k = nd.index; k < nd.index + nd.count; ++k)
        for (std::uint32_t tri : members(t.prim_order[k])) s.push_back(tri);
      return;
    }
    collect(n + 1, s);
    collect(nd.index, s);
  };
  for (std::uint32_t i = 0; i < t.nodes.size(); ++i) {
    std::vector<std::uint32_t> inside;
    collect(i, inside);
    std::vector<bool> in(m.triangle_count(), false);
    Box3 b;
    for (std::uint32_t tri : inside) {
      in[tri] = true;
      for (std::uint32_t v : m.triangle(tri)) b.extend(m.position(v));
    }
    double a = 0;
    for (std::uint32_t tri = 0; tri < m.triangle_count(); ++tri)
      if (!in[tri]) {
        const auto c = m.corners(tri);
        a += clipped_area(c[0], c[1], c[2], b);
      }
    out[i] = a;
  }
  return out;
}

TEST(Epo, TriangleAndClusterBvhsAgreeWithAllPairs) {
  const Mesh m = make_sphere_mesh(Vec3(0.1, 0.2, 0.3), 1.0, 2);  // 320 triangles
  const bvh::SahCostModel cost{1.0, 0.3};
  {
    auto one = [](std::size_t p) { return std::vector<std::uint32_t>{std::uint32_t(p)}; };
    const bvh::Bvh t = build(m, m.triangle_count(), one, 4);
    const EpoResult r = end_point_overlap(t, m.triangles(), m.positions(), {}, {}, cost);
    const auto want = brute_force(m, t, one);
    double epo = 0;
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_NEAR(r.node_overlap[i], want[i], 1e-12 * (1 + want[i])) << "node " << i;
      epo += (t.nodes[i].is_leaf() ? cost.intersection * t.nodes[i].count : cost.traversal) * want[i];
    }
    EXPECT_NEAR(r.epo, epo / r.total_area, 1e-12);
    EXPECT_GT(r.epo, 0.0);  // a closed sphere: boxes always hold neighbours' pieces
    EXPECT_EQ(r.node_overlap[0], 0.0);  // the root's subtree is everything
  }
  {
    const Clustering c = morton_runs(m, 16);
    auto members = [&](std::size_t p) {
      const auto s = c.triangles_of(p);
      return std::vector<std::uint32_t>(s.begin(), s.end());
    };
    const bvh::Bvh t = build(m, c.cluster_count(), members, 1);
    const EpoResult r = end_point_overlap(t, m.triangles(), m.positions(), c.triangle_offsets, c.triangle_order, cost);
    const auto want = brute_force(m, t, members);
    double epo = 0;
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_NEAR(r.node_overlap[i], want[i], 1e-12 * (1 + want[i])) << "node " << i;
      double n = 0;  // a leaf's triangles
      if (t.nodes[i].is_leaf())
        for (std::uint32_t k = t.nodes[i].index; k < t.nodes[i].index + t.nodes[i].count; ++k)
          n += double(members(t.prim_order[k]).size());
      epo += (t.nodes[i].is_leaf() ? cost.intersection * n : cost.traversal) * want[i];
    }
    EXPECT_NEAR(r.epo, epo / r.total_area, 1e-12);
  }
}

TEST(Epo, SeparatedGeometryHasNone) {
  // Two triangles far apart: no box reaches the other one.
  const Mesh m({{0, 1, 2}, {3, 4, 5}},
               {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(10, 0, 0), Vec3(11, 0, 0), Vec3(10, 1, 0)});
  auto one = [](std::size_t p) { return std::vector<std::uint32_t>{std::uint32_t(p)}; };
  const bvh::Bvh t = build(m, 2, one, 1);
  ASSERT_EQ(t.nodes.size(), 3u);
  const EpoResult r = end_point_overlap(t, m.triangles(), m.positions(), {}, {}, {});
  EXPECT_EQ(r.epo, 0.0);
  EXPECT_DOUBLE_EQ(r.total_area, 1.0);
  EXPECT_EQ(end_point_overlap(bvh::Bvh{}, {}, {}, {}, {}, {}).epo, 0.0);
}

}  // namespace
}  // namespace ptc
