// SceneTracer (a static BVH built once + a moving BVH updated per frame, hits merged per ray)
// against an independent answer: ONE triangle BVH over the combined mesh at the same frame, ray by
// ray (closest triangle id and t bit for bit), for several frames, with static and moving parts
// interleaved in part order, with and without a cluster BVH for the moving parts; any-hit agrees
// with closest-hit on occlusion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>

#include "bvh/scene_tracer.h"
#include "bvh/tracer.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/static_source.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/morton_runs.h"
#include "common/same_trace_data.h"

using ptc::Mesh;
using ptc::Vec3;

namespace {

// Parts in the order moving, static, moving, static: a rigidly moving sphere that passes through
// the static one, the static sphere, a twisted ellipsoid and a static floor quad.
ptc::Scene make_scene() {
  std::vector<ptc::ScenePart> parts;
  ptc::DeformParams rigid;
  rigid.kind = ptc::DeformKind::Rigid;
  rigid.amplitude = 0.25;
  rigid.velocity = Vec3(-0.08, 0.01, 0.0);
  parts.push_back({"mover", ptc::make_deformer(ptc::make_sphere_mesh(Vec3(1.6, 0.1, 0.0), 0.7, 2), rigid)});
  parts.push_back({"ball", std::make_unique<ptc::StaticSource>(ptc::make_sphere_mesh(Vec3(0, 0, 0), 1.0, 2), "ball")});
  ptc::DeformParams twist;
  twist.kind = ptc::DeformKind::Twist;
  twist.amplitude = 1.2;
  twist.period = 8;
  Mesh e = ptc::make_sphere_mesh(Vec3(-1.5, 0.0, 0.3), 1.0, 2);
  std::vector<Vec3> q;
  for (const Vec3& v : e.positions()) q.push_back(Vec3(-1.5 + 0.5 * (v.x() + 1.5), 1.5 * v.y(), v.z()));
  parts.push_back({"twisted", ptc::make_deformer(e.with_positions(std::move(q)), twist)});
  Mesh floor({{0, 1, 2}, {0, 2, 3}}, {Vec3(-4, -1.6, -4), Vec3(-4, -1.6, 4), Vec3(4, -1.6, 4), Vec3(4, -1.6, -4)});
  parts.push_back({"floor", std::make_unique<ptc::StaticSource>(std::move(floor), "floor")});
  return ptc::Scene("test", std::move(parts));
}

// Seeded random rays through the scene's box, plus rays aimed exactly at vertices (ties on
// shared edges and vertices) and axis-aligned rays.
ptc::bvh::RayBatch make_rays(std::span<const Vec3> pos, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<std::pair<Vec3, Vec3>> r;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 o(u(rng), u(rng), 6.0 + u(rng)), target(0.5 * u(rng), 0.5 * u(rng), 0.5 * u(rng));
    r.push_back({o, target - o});
  }
  for (std::size_t v = 0; v < pos.size(); v += 7) r.push_back({Vec3(0.3, 0.4, 7.0), pos[v] - Vec3(0.3, 0.4, 7.0)});
  for (int i = 0; i < 200; ++i) {
    const Vec3 o(u(rng), u(rng), u(rng));
    r.push_back({o + Vec3(0, 0, 10), Vec3(0, 0, -1)});
    r.push_back({o + Vec3(10, 0, 0), Vec3(-1, 0, 0)});
    r.push_back({o - Vec3(0, 10, 0), Vec3(0, 1, 0)});
  }
  ptc::bvh::RayBatch b;
  b.resize(r.size());
  for (std::size_t i = 0; i < r.size(); ++i)
    b.set(i, r[i].first, ptc::bvh::Vec3f{float(r[i].second.x()), float(r[i].second.y()), float(r[i].second.z())});
  return b;
}

void check_frames(ptc::Scene& scene, const ptc::Clustering* clusters, bool expect_split) {
  std::vector<Vec3> pos(scene.rest().vertex_count());
  scene.positions(0, pos);
  const Mesh first = scene.rest().with_positions(pos);
  ptc::bvh::SceneTracerConfig cfg;
  cfg.clusters = clusters;
  ptc::bvh::SceneTracer tracer(first, ptc::bvh::PartLayout::of(scene), cfg);
  EXPECT_EQ(tracer.split(), expect_split);
  ptc::bvh::SceneConfig rc = ptc::bvh::triangle_scene_defaults();
  rc.origin = tracer.origin();
  ptc::bvh::TriangleScene ref(first, rc);
  const std::vector<Vec3> frame0 = pos;
  std::size_t moving_hits = 0, static_hits = 0;
  for (int f : {0, 3, 7}) {
    scene.positions(f, pos);
    if (f > 0) {
      ref.update(pos);
      // Only the moving parts' positions are read: poison the static ranges.
      std::vector<Vec3> partial = pos;
      for (std::size_t p = 0; p < scene.part_count(); ++p) {
        if (!scene.is_static(p) || !expect_split) continue;
        for (std::size_t v = scene.vertex_offset(p); v < scene.vertex_offset(p + 1); ++v) partial[v] = Vec3(1e30, 0, 0);
      }
      tracer.update(partial);
    }
    if (f == 7) {
      EXPECT_NE(pos, frame0);  // the scene does move
    }
    const auto rays = make_rays(pos, 11 + f);
    ptc::bvh::HitBatch want, got, any;
    ptc::bvh::TraceOptions opt;
    opt.threads = 2;
    (void)ptc::bvh::trace(ref.data(), rays, want, opt);
    const auto tt = tracer.trace(rays, got, opt);
    opt.mode = ptc::bvh::HitMode::Any;
    (void)tracer.trace(rays, any, opt);
    ASSERT_EQ(got.size(), rays.size());
    std::uint64_t hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      ASSERT_EQ(got.triangle[i], want.triangle[i]) << "frame " << f << " ray " << i;
      if (want.triangle[i] == ptc::bvh::kNoTriangle) continue;
      ++hits;
      ASSERT_EQ(got.t[i], want.t[i]) << "frame " << f << " ray " << i;
      ASSERT_EQ(got.u[i], want.u[i]);
      ASSERT_EQ(got.v[i], want.v[i]);
      std::size_t p = 0;
      while (scene.triangle_offset(p + 1) <= want.triangle[i]) ++p;
      (scene.is_static(p) ? static_hits : moving_hits)++;
    }
    EXPECT_EQ(tt.hits, hits);
    for (std::size_t i = 0; i < rays.size(); ++i)
      ASSERT_EQ(any.triangle[i] != ptc::bvh::kNoTriangle, want.triangle[i] != ptc::bvh::kNoTriangle) << i;
    // Any-hit with tmax just short of / at the closest hit: occluded iff t_closest <= tmax.
    ptc::bvh::RayBatch shorter = rays;
    for (std::size_t i = 0; i < rays.size(); ++i)
      if (want.triangle[i] != ptc::bvh::kNoTriangle) shorter.tmax[i] = i % 2 ? want.t[i] : want.t[i] * 0.999f;
    (void)tracer.trace(shorter, any, opt);
    ptc::bvh::HitBatch any_ref;
    (void)ptc::bvh::trace(ref.data(), shorter, any_ref, opt);
    for (std::size_t i = 0; i < rays.size(); ++i)
      ASSERT_EQ(any.triangle[i] != ptc::bvh::kNoTriangle, any_ref.triangle[i] != ptc::bvh::kNoTriangle) << i;
  }
  // Both kinds of parts were actually hit (the test exercises the merge).
  EXPECT_GT(static_hits, 100u);
  EXPECT_GT(moving_hits, 100u);
}

}  // namespace

TEST(SceneTrace, StaticPlusMovingEqualsOneBvhOverTheCombinedMesh) {
  ptc::Scene scene = make_scene();
  ASSERT_TRUE(scene.is_static(1) && scene.is_static(3) && !scene.is_static(0) && !scene.is_static(2));
  check_frames(scene, nullptr, true);
}

TEST(SceneTrace, ClusterBvhForTheMovingPartsAlsoMatches) {
  ptc::Scene scene = make_scene();
  ptc::ClusterConfig cc;
  cc.method = ptc::ClusterMethod::Growth;
  cc.objective = ptc::ObjectiveKind::Acc;
  cc.max_count = 20;
  cc.max_size = 20;
  const ptc::Clustering c = ptc::cluster_mesh(scene.rest(), cc);
  check_frames(scene, &c, true);
}

TEST(SceneTrace, StaticBvhIsBuiltOnceAndNeverUpdated) {
  ptc::Scene scene = make_scene();
  std::vector<Vec3> pos(scene.rest().vertex_count());
  scene.positions(0, pos);
  ptc::bvh::SceneTracer t(scene.rest().with_positions(pos), ptc::bvh::PartLayout::of(scene));
  ASSERT_TRUE(t.split());
  EXPECT_EQ(t.static_triangles(), std::size_t(320 + 2));
  EXPECT_EQ(t.moving_triangles(), std::size_t(320 + 320));
  const auto* static_blocks = t.static_data().blocks.data();
  const std::size_t nblocks = t.static_data().blocks.size();
  std::vector<unsigned char> before(nblocks * sizeof(ptc::bvh::TriBlock));
  std::memcpy(before.data(), static_blocks, before.size());  // bytes: padding lanes are NaN
  scene.positions(5, pos);
  t.update(pos);
  EXPECT_GT(t.moving_times().total_ms(), 0.0);
  EXPECT_EQ(t.static_data().blocks.data(), static_blocks);
  ASSERT_EQ(t.static_data().blocks.size(), nblocks);
  EXPECT_EQ(std::memcmp(before.data(), static_blocks, before.size()), 0);
  EXPECT_TRUE(ptc::bvh::validate(t.static_data(), t.static_triangles()).empty());
  EXPECT_TRUE(ptc::bvh::validate(t.moving_data(), t.moving_triangles()).empty());

  // All static: one BVH, update is a no-op; none static: one BVH updated per frame.
  const Mesh m = ptc::make_sphere_mesh(Vec3(0, 0, 0), 1.0, 1);
  ptc::bvh::SceneTracer s(m, ptc::bvh::PartLayout::single(m, true));
  EXPECT_TRUE(s.all_static());
  EXPECT_FALSE(s.split());
  s.update(m.positions());
  EXPECT_EQ(s.moving_times().total_ms(), 0.0);
  EXPECT_EQ(s.static_triangles(), m.triangle_count());
  EXPECT_EQ(s.moving_triangles(), 0u);
  ptc::bvh::SceneTracer d(m, ptc::bvh::PartLayout::single(m, false));
  EXPECT_FALSE(d.split());
  d.update(m.positions());
  EXPECT_GT(d.moving_times().total_ms(), 0.0);
  EXPECT_EQ(d.static_triangles(), 0u);
  EXPECT_EQ(d.moving_triangles(), m.triangle_count());
  // With clusters, all static: the one BVH is the cluster BVH, counted as moving (built once).
  const ptc::Clustering one = ptc::clustering_from_labels(std::vector<std::uint32_t>(m.triangle_count(), 0), m.triangles());
  ptc::bvh::SceneTracerConfig cc;
  cc.clusters = &one;
  ptc::bvh::SceneTracer sc(m, ptc::bvh::PartLayout::single(m, true), cc);
  EXPECT_TRUE(sc.all_static());
  EXPECT_TRUE(sc.moving_is_clusters());
  EXPECT_EQ(sc.static_triangles(), 0u);
  EXPECT_EQ(sc.moving_triangles(), m.triangle_count());
  EXPECT_TRUE(ptc::bvh::validate(sc.moving_data(), sc.moving_triangles()).empty());
  // That BVH is built once (SceneConfig::built_once, its own path: blocks filled from the lanes'
  // triangles, no vertex order): it must be the same bytes as the first frame of the all-moving
  // scene's cluster BVH, at the same positions and origin. (ClusterScene's own test checks that
  // a scene built once refuses update().)
  const ptc::Clustering runs = ptc::morton_runs(m, 5);
  cc.clusters = &runs;
  const ptc::bvh::SceneTracer once(m, ptc::bvh::PartLayout::single(m, true), cc);
  const ptc::bvh::SceneTracer moving(m, ptc::bvh::PartLayout::single(m, false), cc);
  ASSERT_GT(once.moving_data().blocks.size(), 4u);
  ptc::bvh::test::expect_same_data(once.moving_data(), moving.moving_data(), "built once against the first frame");
}

TEST(SceneTrace, BadLayoutsAndSizesAreRefused) {
  const Mesh m = ptc::make_sphere_mesh(Vec3(0, 0, 0), 1.0, 1);
  ptc::bvh::PartLayout bad = ptc::bvh::PartLayout::single(m, true);
  bad.triangle_offsets.back() -= 1;
  EXPECT_THROW(ptc::bvh::SceneTracer(m, bad), std::invalid_argument);
  // Two parts splitting the triangles in the middle of the vertex range: a triangle of part 0
  // uses a vertex of part 1.
  ptc::bvh::PartLayout two;
  two.vertex_offsets = {0, 3, m.vertex_count()};
  two.triangle_offsets = {0, 40, m.triangle_count()};
  two.is_static = {true, false};
  EXPECT_THROW(ptc::bvh::SceneTracer(m, two), std::invalid_argument);
  ptc::bvh::SceneTracer ok(m, ptc::bvh::PartLayout::single(m, false));
  std::vector<Vec3> few(3);
  EXPECT_THROW(ok.update(few), std::invalid_argument);
}
