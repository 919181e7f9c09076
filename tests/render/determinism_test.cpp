// Determinism across thread counts (issue 15): the clustering (growth and contraction), the
// per-frame update and build of the triangle and cluster BVHs, and every traced pass (closest
// hits with counters, shadow rays, AO rays) give bit-identical results at 1, 2 and 4 threads.
// The reference is the one-thread run, compared item by item (hit distances and barycentrics as
// bits, triangle ids, per-ray node and triangle counts, lit flags, AO fractions, pass counters).
#include <gtest/gtest.h>

#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "bvh/trace_scene.h"
#include "render/camera.h"
#include "render/view.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/io/mesh_io.h"

using ptc::Mesh;
using ptc::Vec3;
namespace bvh = ptc::bvh;

namespace {

struct Outcome {
  std::vector<std::uint32_t> growth, contraction;  // cluster of each triangle
  std::vector<ptc::Render> renders;                // triangle BVH, cluster BVH (growth), cluster BVH (contraction)
};

// A twist about y: the frame every BVH is updated to before tracing.
std::vector<Vec3> twisted(const Mesh& m) {
  const ptc::Box3 b = m.bounds();
  std::vector<Vec3> p(m.positions().begin(), m.positions().end());
  for (Vec3& v : p) {
    const double a = 0.8 * (v.y() - b.lo.y()) / (b.hi.y() - b.lo.y());
    v = Vec3(std::cos(a) * v.x() - std::sin(a) * v.z(), v.y(), std::sin(a) * v.x() + std::cos(a) * v.z());
  }
  return p;
}

Outcome run_with(int threads, const Mesh& mesh) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  tbb::task_arena arena(threads);
  Outcome r;
  arena.execute([&] {
    ptc::ClusterConfig g;
    g.method = ptc::ClusterMethod::Growth;
    const ptc::Clustering growth = ptc::cluster_mesh(mesh, g);
    ptc::ClusterConfig c;
    c.method = ptc::ClusterMethod::Contraction;
    const ptc::Clustering contraction = ptc::cluster_mesh(mesh, c);
    r.growth = growth.cluster_of_triangle();
    r.contraction = contraction.cluster_of_triangle();

    const std::vector<Vec3> frame = twisted(mesh);
    const Mesh moved = mesh.with_positions(frame);
    ptc::RenderConfig rc;
    rc.width = 160, rc.height = 128;  // 20480 rays: above the 4096 at which passes go parallel
    rc.shadows = true;
    rc.ao_samples = 2;
    rc.threads = static_cast<unsigned>(threads);
    const auto cam = ptc::make_camera({}, mesh.bounds(), rc.width, rc.height);
    bvh::TriangleScene ts(mesh);
    ts.update(frame);
    r.renders.push_back(ptc::render_view(ts.data(), moved, cam, rc));
    for (const ptc::Clustering* cl : {&growth, &contraction}) {
      bvh::ClusterScene cs(mesh, bvh::view_of(*cl));
      cs.update(frame);
      r.renders.push_back(ptc::render_view(cs.data(), moved, cam, rc));
    }
  });
  return r;
}

template <class T>
std::size_t differing(const T& a, const T& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size());
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof a[i]) != 0;
  return n;
}

TEST(Determinism, ClustersBvhsAndEveryPassAreIdenticalAt1_2And4Threads) {
  const Mesh mesh = ptc::read_mesh(std::string(PTC_TEST_DATA) + "/meshes/armadillo.off").mesh;
  const Outcome one = run_with(1, mesh);
  ASSERT_EQ(one.renders.size(), 3u);
  ASSERT_GT(one.renders[0].primary_stats.hits, 3000u);  // the armadillo fills a sixth of the view
  for (int threads : {2, 4}) {
    SCOPED_TRACE(std::to_string(threads) + " threads");
    const Outcome r = run_with(threads, mesh);
    EXPECT_EQ(differing(one.growth, r.growth), 0u);
    EXPECT_EQ(differing(one.contraction, r.contraction), 0u);
    for (std::size_t k = 0; k < one.renders.size(); ++k) {
      SCOPED_TRACE("scene " + std::to_string(k) + " (triangles, growth clusters, contraction clusters)");
      const ptc::Render &a = one.renders[k], &b = r.renders[k];
      EXPECT_EQ(differing(a.primary.t, b.primary.t), 0u);
      EXPECT_EQ(differing(a.primary.u, b.primary.u), 0u);
      EXPECT_EQ(differing(a.primary.v, b.primary.v), 0u);
      EXPECT_EQ(differing(a.primary.triangle, b.primary.triangle), 0u);
      EXPECT_EQ(differing(a.primary.nodes_visited, b.primary.nodes_visited), 0u);
      EXPECT_EQ(differing(a.primary.triangles_tested, b.primary.triangles_tested), 0u);
      EXPECT_EQ(differing(a.lit, b.lit), 0u);
      EXPECT_EQ(differing(a.ao, b.ao), 0u);
      for (const auto& [sa, sb] : {std::pair{a.primary_stats, b.primary_stats}, std::pair{a.shadow_stats, b.shadow_stats},
                                   std::pair{a.ao_stats, b.ao_stats}}) {
        EXPECT_EQ(sa.rays, sb.rays);
        EXPECT_EQ(sa.hits, sb.hits);
        EXPECT_EQ(sa.nodes_visited, sb.nodes_visited);
        EXPECT_EQ(sa.triangles_tested, sb.triangles_tested);
      }
      EXPECT_EQ(ptc::shaded_image(a).rgb, ptc::shaded_image(b).rgb);
    }
  }
}

}  // namespace
