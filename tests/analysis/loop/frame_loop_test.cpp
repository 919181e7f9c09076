// The one frame loop and the acceleration configurations (analysis/loop): every configuration's
// closest hits against brute force ray by ray, the loop's order and its positions against the
// scene's own, the static + moving scene against one BVH over the whole mesh.
#include <gtest/gtest.h>

#include <vector>

#include "analysis/loop/accel.h"
#include "analysis/loop/frame_loop.h"
#include "common/brute_force.h"
#include "render/camera.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/static_source.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/core/cancel.h"

namespace ptc::loop {
namespace {

Scene twisting_ball(int levels = 2) {
  std::vector<ScenePart> parts;
  parts.push_back({"ball", make_deformer(make_sphere_mesh(Vec3(0.2, 0.1, 0.0), 1.0, levels), deform_preset(DeformKind::Twist))});
  return Scene("ball", std::move(parts), std::nullopt, std::nullopt, FrameRange{0, 59});
}

bvh::RayBatch rays_for(const Mesh& m, int w, int h) {
  return camera_rays(make_camera({}, m.bounds(), w, h), w, h);
}

TEST(AccelKinds, NamesRoundTrip) {
  for (AccelKind k : kAllAccelKinds) EXPECT_EQ(parse_accel_kind(to_string(k)), k);
  EXPECT_FALSE(parse_accel_kind("embree"));
  EXPECT_TRUE(is_embree(AccelKind::EmbreeRefit));
  EXPECT_FALSE(is_embree(AccelKind::OursClusters));
}

// Every configuration, updated over three frames of a twist, hits what a loop over all
// triangles hits, ray by ray (Embree may differ only by a tie on a shared edge).
TEST(FrameLoop, EveryConfigurationAgreesWithBruteForceEveryFrame) {
  Scene scene = twisting_ball();
  const Mesh rest = scene.rest();
  ClusterConfig cc;
  cc.method = ClusterMethod::Growth;
  cc.max_count = 20;
  cc.max_size = 20;
  const Clustering clusters = cluster_mesh(rest, cc);
  AccelSetup setup;
  setup.origin = rest.bounds().center();
  setup.clusters = &clusters;
  std::vector<std::unique_ptr<Accel>> owned;
  std::vector<Accel*> accels;
  for (AccelKind k : kAllAccelKinds) {
    owned.push_back(make_accel(k, rest, setup));
    accels.push_back(owned.back().get());
    EXPECT_EQ(accels.back()->name(), to_string(k));
    EXPECT_EQ(accels.back()->sah_cost().has_value(), !is_embree(k));
  }
  EXPECT_NE(cluster_scene_of(*accels[1]), nullptr);
  EXPECT_EQ(cluster_scene_of(*accels[0]), nullptr);
  const bvh::RayBatch rays = rays_for(rest, 24, 18);
  std::vector<Vec3> pos(rest.positions().begin(), rest.positions().end()), want(pos.size());
  LoopOptions lo;
  lo.frames = {2, 4};
  std::vector<std::pair<std::int64_t, std::size_t>> order;
  run_frame_loop(scene, pos, accels, lo, [&](const FrameRecord& r, Accel& a, std::span<const Vec3> p) {
    order.emplace_back(r.frame, r.accel);
    EXPECT_EQ(r.index, int(r.frame - 2));
    EXPECT_EQ(&a, accels[r.accel]);
    // The positions the configuration was updated with are the scene's at that frame.
    scene.positions(double(r.frame), want);
    for (std::size_t v = 0; v < want.size(); ++v) ASSERT_EQ(p[v], want[v]) << "frame " << r.frame;
    EXPECT_GE(r.update_wall_ms, 0.0);
    EXPECT_GE(r.times.build_ms, 0.0);
    const Mesh now = rest.with_positions(std::vector<Vec3>(p.begin(), p.end()));
    bvh::HitBatch hits;
    bvh::TraceOptions opt;
    opt.threads = 1;
    a.trace(rays, hits, opt);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const bvh::Hit bf = bvh::test::brute_force(now, a.origin(), Vec3(rays.ox[i], rays.oy[i], rays.oz[i]),
                                                 {rays.dx[i], rays.dy[i], rays.dz[i]});
      ASSERT_EQ(hits.triangle[i] != bvh::kNoTriangle, bf.hit()) << a.name() << " frame " << r.frame << " ray " << i;
      if (bf.hit() && hits.triangle[i] != bf.triangle) {  // only a tie may differ
        EXPECT_NEAR(hits.t[i], bf.t, 1e-5f * bf.t) << a.name() << " frame " << r.frame << " ray " << i;
      }
      if (!is_embree(parse_accel_kind(a.name()).value()) && bf.hit()) {
        ASSERT_EQ(hits.triangle[i], bf.triangle) << a.name() << " ray " << i;  // ours: the smallest (t, id)
      }
    }
  });
  // Frame-major, configurations in order.
  ASSERT_EQ(order.size(), 3 * accels.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    EXPECT_EQ(order[i].first, 2 + std::int64_t(i / accels.size()));
    EXPECT_EQ(order[i].second, i % accels.size());
  }
  // The buffer holds the last frame.
  scene.positions(4.0, want);
  EXPECT_EQ(pos, want);
}

// Without fresh copies every configuration reads the loop's buffer itself; with update_static
// false the static parts are written on the first frame only.
TEST(FrameLoop, BufferAndStaticParts) {
  std::vector<ScenePart> parts;
  parts.push_back({"floor", std::make_unique<StaticSource>(make_sphere_mesh(Vec3(0, -3, 0), 1.0, 1), "floor")});
  parts.push_back({"ball", make_deformer(make_sphere_mesh(Vec3::Zero(), 1.0, 1), deform_preset(DeformKind::Wave))});
  Scene scene("two", std::move(parts), std::nullopt, std::nullopt, FrameRange{0, 9});
  const Mesh rest = scene.rest();
  AccelSetup setup;
  setup.origin = rest.bounds().center();
  auto tri = make_accel(AccelKind::OursTriangles, rest, setup);
  Accel* accels[] = {tri.get()};
  std::vector<Vec3> pos(rest.vertex_count(), Vec3(9, 9, 9));  // not the rest pose
  LoopOptions lo;
  lo.frames = {0, 2};
  lo.fresh_positions = false;
  lo.update_static = false;
  std::vector<Vec3> want(pos.size());
  run_frame_loop(scene, pos, accels, lo, [&](const FrameRecord& r, Accel&, std::span<const Vec3> p) {
    EXPECT_EQ(p.data(), pos.data());  // the buffer itself
    scene.positions(double(r.frame), want);
    for (std::size_t v = 0; v < want.size(); ++v) ASSERT_EQ(p[v], want[v]) << "frame " << r.frame << " vertex " << v;
  });
  // A first frame the caller already made is not made again.
  std::vector<Vec3> given(pos.size(), Vec3(7, 7, 7));
  lo.first_frame_given = true;
  run_frame_loop(scene, given, accels, lo, [&](const FrameRecord& r, Accel&, std::span<const Vec3> p) {
    if (r.index == 0) {
      EXPECT_EQ(p[0], Vec3(7, 7, 7));
      return;
    }
    scene.positions(double(r.frame), want);
    EXPECT_EQ(p[p.size() - 1], want.back()) << "frame " << r.frame;
  });
  lo.first_frame_given = false;
  std::vector<Vec3> small(3);
  EXPECT_THROW(run_frame_loop(scene, small, accels, lo, [](const FrameRecord&, Accel&, std::span<const Vec3>) {}),
               std::invalid_argument);
  lo.frames = {3, 2};
  EXPECT_THROW(run_frame_loop(scene, pos, accels, lo, [](const FrameRecord&, Accel&, std::span<const Vec3>) {}),
               std::invalid_argument);
  // ours_clusters without a clustering is refused.
  EXPECT_THROW((void)make_accel(AccelKind::OursClusters, rest, setup), std::invalid_argument);
}

// A still scene handed its rest positions: every configuration sees the rest mesh's own array in
// every frame, the caller's buffer (empty here) is not touched, the source takes no time, and a
// scene with a moving part is refused.
TEST(FrameLoop, RestPositionsOfAStillScene) {
  std::vector<ScenePart> parts;
  parts.push_back({"a", std::make_unique<StaticSource>(make_sphere_mesh(Vec3(0, -3, 0), 1.0, 1), "a")});
  parts.push_back({"b", std::make_unique<StaticSource>(make_sphere_mesh(Vec3(2, 0, 0), 0.5, 2), "b")});
  Scene scene("still", std::move(parts), std::nullopt, std::nullopt, FrameRange{0, 9});
  ASSERT_TRUE(scene.all_static());
  AccelSetup setup;
  setup.origin = scene.rest().bounds().center();
  auto tri = make_accel(AccelKind::OursTriangles, scene.rest(), setup);
  Accel* accels[] = {tri.get()};
  LoopOptions lo;
  lo.frames = {2, 5};
  lo.fresh_positions = false;
  lo.update_static = false;
  lo.rest_positions = true;
  const bvh::RayBatch rays = rays_for(scene.rest(), 16, 16);
  std::vector<std::int64_t> frames;
  run_frame_loop(scene, {}, accels, lo, [&](const FrameRecord& r, Accel& a, std::span<const Vec3> p) {
    frames.push_back(r.frame);
    EXPECT_EQ(p.data(), scene.rest().positions().data());  // the rest's own array, no copy
    EXPECT_EQ(p.size(), scene.rest().vertex_count());
    EXPECT_LT(r.source_ms, 1.0);
    // (the option's premise: a still scene's positions at any frame are its rest positions)
    std::vector<Vec3> want(p.size());
    scene.positions(double(r.frame), want);
    for (std::size_t v = 0; v < want.size(); ++v) ASSERT_EQ(p[v], want[v]) << "frame " << r.frame << " vertex " << v;
    // the configuration traces the rest mesh: its hits are brute force's
    bvh::HitBatch hits;
    bvh::TraceOptions opt;
    opt.threads = 1;
    a.trace(rays, hits, opt);
    std::size_t hit_count = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const bvh::Hit bf = bvh::test::brute_force(scene.rest(), a.origin(), Vec3(rays.ox[i], rays.oy[i], rays.oz[i]),
                                                 {rays.dx[i], rays.dy[i], rays.dz[i]});
      ASSERT_EQ(hits.triangle[i], bf.hit() ? bf.triangle : bvh::kNoTriangle) << "frame " << r.frame << " ray " << i;
      hit_count += bf.hit();
    }
    EXPECT_GT(hit_count, rays.size() / 10);  // (the camera frames the mesh)
  });
  EXPECT_EQ(frames, (std::vector<std::int64_t>{2, 3, 4, 5}));
  // With fresh copies the configuration reads a copy of the rest instead.
  lo.fresh_positions = true;
  run_frame_loop(scene, {}, accels, lo, [&](const FrameRecord&, Accel&, std::span<const Vec3> p) {
    EXPECT_NE(p.data(), scene.rest().positions().data());
    EXPECT_TRUE(std::equal(p.begin(), p.end(), scene.rest().positions().begin(), scene.rest().positions().end()));
  });
  // A scene with a moving part is refused, also when its first part is static.
  Scene moving = twisting_ball(1);
  std::vector<ScenePart> mixed_parts;
  mixed_parts.push_back({"floor", std::make_unique<StaticSource>(make_sphere_mesh(Vec3(0, -3, 0), 1.0, 1), "floor")});
  mixed_parts.push_back({"ball", make_deformer(make_sphere_mesh(Vec3::Zero(), 1.0, 1), deform_preset(DeformKind::Wave))});
  Scene mixed("mixed", std::move(mixed_parts), std::nullopt, std::nullopt, FrameRange{0, 9});
  ASSERT_TRUE(mixed.is_static(0));
  for (Scene* sc : {&moving, &mixed}) {
    AccelSetup ms;
    ms.origin = sc->rest().bounds().center();
    auto mt = make_accel(AccelKind::OursTriangles, sc->rest(), ms);
    Accel* maccels[] = {mt.get()};
    EXPECT_THROW(run_frame_loop(*sc, {}, maccels, lo, [](const FrameRecord&, Accel&, std::span<const Vec3>) {}),
                 std::invalid_argument)
        << sc->name();
  }
}

// An ours_triangles configuration that counts its updates, so that a test sees which updates the
// loop made before it stopped.
class CountingAccel final : public Accel {
 public:
  explicit CountingAccel(std::unique_ptr<Accel> inner) : inner_(std::move(inner)) {}
  std::string_view name() const override { return inner_->name(); }
  void update(std::span<const Vec3> positions) override {
    ++updates;
    inner_->update(positions);
  }
  UpdateTimes last_update() const override { return inner_->last_update(); }
  bvh::TraceTotals trace(const bvh::RayBatch& rays, bvh::HitBatch& hits, const bvh::TraceOptions& opt) const override {
    return inner_->trace(rays, hits, opt);
  }
  Vec3 origin() const override { return inner_->origin(); }
  int updates = 0;

 private:
  std::unique_ptr<Accel> inner_;
};

// The cancel flag is process-wide: cleared before and after, whatever the test asserts.
class FrameLoopCancel : public ::testing::Test {
 protected:
  void SetUp() override { reset_cancel(); }
  void TearDown() override { reset_cancel(); }
};

// A Ctrl-C (toolkit/core/cancel.h) stops the loop before the next frame or configuration: what
// ran is exactly the steps before the request, and nothing after it.
TEST_F(FrameLoopCancel, StopsBeforeTheNextFrameAndTheNextConfiguration) {
  Scene scene = twisting_ball(1);
  const Mesh rest = scene.rest();
  AccelSetup setup;
  setup.origin = rest.bounds().center();
  CountingAccel a0(make_accel(AccelKind::OursTriangles, rest, setup)), a1(make_accel(AccelKind::OursTriangles, rest, setup));
  Accel* accels[] = {&a0, &a1};
  std::vector<Vec3> pos(rest.positions().begin(), rest.positions().end()), want(pos.size());
  LoopOptions lo;
  lo.frames = {0, 9};
  using Step = std::pair<std::int64_t, std::size_t>;
  std::vector<Step> order;
  auto record = [&](const FrameRecord& r, Accel&, std::span<const Vec3>) { order.emplace_back(r.frame, r.accel); };

  // Requested before the loop: no frame is made, no configuration updated or measured.
  request_cancel();
  std::vector<Vec3> untouched(pos.size(), Vec3(9, 9, 9));
  EXPECT_THROW(run_frame_loop(scene, untouched, accels, lo, record), Interrupted);
  EXPECT_TRUE(order.empty());
  EXPECT_EQ(a0.updates, 0);
  EXPECT_EQ(a1.updates, 0);
  EXPECT_EQ(untouched.front(), Vec3(9, 9, 9));  // scene.positions was not called
  EXPECT_TRUE(cancel_requested());              // the request stays for every loop up the stack
  reset_cancel();

  // Requested while configuration 0 of frame 3 is measured: configuration 1 is not updated for
  // frame 3, and frame 4 is never made.
  EXPECT_THROW(run_frame_loop(scene, pos, accels, lo,
                              [&](const FrameRecord& r, Accel& a, std::span<const Vec3> p) {
                                record(r, a, p);
                                if (r.frame == 3 && r.accel == 0) request_cancel();
                              }),
               Interrupted);
  std::vector<Step> expected;
  for (std::int64_t f = 0; f <= 3; ++f)
    for (std::size_t k = 0; k < 2; ++k)
      if (!(f == 3 && k == 1)) expected.emplace_back(f, k);
  EXPECT_EQ(order, expected);
  EXPECT_EQ(a0.updates, 4);
  EXPECT_EQ(a1.updates, 3);
  scene.positions(3.0, want);
  for (std::size_t v = 0; v < want.size(); ++v) ASSERT_EQ(pos[v], want[v]) << "vertex " << v;  // still frame 3

  // Requested after the last configuration of the last frame: the loop has nothing left to stop.
  reset_cancel();
  order.clear();
  lo.frames = {0, 1};
  EXPECT_NO_THROW(run_frame_loop(scene, pos, accels, lo, [&](const FrameRecord& r, Accel& a, std::span<const Vec3> p) {
    record(r, a, p);
    if (r.frame == 1 && r.accel == 1) request_cancel();
  }));
  EXPECT_EQ(order, (std::vector<Step>{{0, 0}, {0, 1}, {1, 0}, {1, 1}}));

  // After reset_cancel() the loop runs every frame again.
  reset_cancel();
  order.clear();
  lo.frames = {0, 2};
  EXPECT_NO_THROW(run_frame_loop(scene, pos, accels, lo, record));
  EXPECT_EQ(order.size(), 6u);

  // A still scene handed its rest positions stops the same way: before the next configuration
  // and the next frame.
  reset_cancel();
  order.clear();
  std::vector<ScenePart> parts;
  parts.push_back({"a", std::make_unique<StaticSource>(make_sphere_mesh(Vec3::Zero(), 1.0, 1), "a")});
  Scene still("still", std::move(parts), std::nullopt, std::nullopt, FrameRange{0, 9});
  CountingAccel s0(make_accel(AccelKind::OursTriangles, still.rest(), setup)),
      s1(make_accel(AccelKind::OursTriangles, still.rest(), setup));
  Accel* still_accels[] = {&s0, &s1};
  LoopOptions rest_lo;
  rest_lo.frames = {0, 9};
  rest_lo.fresh_positions = false;
  rest_lo.rest_positions = true;
  EXPECT_THROW(run_frame_loop(still, {}, still_accels, rest_lo,
                              [&](const FrameRecord& r, Accel& a, std::span<const Vec3> p) {
                                record(r, a, p);
                                if (r.frame == 2 && r.accel == 0) request_cancel();
                              }),
               Interrupted);
  EXPECT_EQ(order, (std::vector<Step>{{0, 0}, {0, 1}, {1, 0}, {1, 1}, {2, 0}}));
  EXPECT_EQ(s0.updates, 3);
  EXPECT_EQ(s1.updates, 2);
  request_cancel();  // and before the loop: nothing runs
  order.clear();
  EXPECT_THROW(run_frame_loop(still, {}, still_accels, rest_lo, record), Interrupted);
  EXPECT_TRUE(order.empty());
}

// `ptc trace`'s configuration (static parts built once + moving parts per frame) returns what a
// triangle BVH over the whole mesh returns, ray by ray, frame by frame.
TEST(SceneAccel, EqualsOneBvhOverTheWholeMesh) {
  std::vector<ScenePart> parts;
  parts.push_back({"floor", std::make_unique<StaticSource>(make_sphere_mesh(Vec3(0, -1.5, 0), 1.0, 2), "floor")});
  parts.push_back({"ball", make_deformer(make_sphere_mesh(Vec3(0.3, 0.4, 0), 0.8, 2), deform_preset(DeformKind::Rigid))});
  Scene scene("two", std::move(parts), std::nullopt, std::nullopt, FrameRange{0, 9});
  const Mesh rest = scene.rest();
  bvh::SceneTracerConfig tcfg;
  tcfg.origin = rest.bounds().center();
  SceneAccel split(rest, bvh::PartLayout::of(scene), tcfg);
  AccelSetup setup;
  setup.origin = *tcfg.origin;
  auto whole = make_accel(AccelKind::OursTriangles, rest, setup);
  EXPECT_TRUE(split.tracer().split());
  EXPECT_FALSE(split.sah_cost());
  Accel* accels[] = {&split, whole.get()};
  const bvh::RayBatch rays = rays_for(rest, 20, 20);
  std::vector<Vec3> pos(rest.positions().begin(), rest.positions().end());
  LoopOptions lo;
  lo.frames = {0, 3};
  bvh::HitBatch first;
  run_frame_loop(scene, pos, accels, lo, [&](const FrameRecord& r, Accel& a, std::span<const Vec3>) {
    bvh::HitBatch h;
    a.trace(rays, h, {});
    if (r.accel == 0) {
      first = h;
      return;
    }
    for (std::size_t i = 0; i < rays.size(); ++i) {
      ASSERT_EQ(first.triangle[i], h.triangle[i]) << "frame " << r.frame << " ray " << i;
      ASSERT_EQ(first.t[i], h.t[i]) << "frame " << r.frame << " ray " << i;
    }
  });
}

}  // namespace
}  // namespace ptc::loop
