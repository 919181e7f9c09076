// Shadow and ambient-occlusion rays: against analytic answers and a brute-force double-precision
// loop over all triangles, on the cases where ray offsets fail first (open planes, tilted
// planes, far from the origin, tiny scenes, closed boxes).
#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <map>
#include <random>
#include <tuple>

#include "render/rays.h"
#include "toolkit/geometry/triangle.h"
#include "bvh/trace_scene.h"

using ptc::Mesh;
using ptc::Tri;
using ptc::Vec3;
namespace bvh = ptc::bvh;

namespace {

// n x n grid of quads over [lo, hi]^2 at z = h (two triangles per quad), then `xf` applied.
Mesh grid(int n, double lo, double hi, double h, const std::function<Vec3(const Vec3&)>& xf = {}) {
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const Vec3 q(lo + (hi - lo) * i / n, lo + (hi - lo) * j / n, h);
      p.push_back(xf ? xf(q) : q);
    }
  auto id = [n](int i, int j) { return std::uint32_t(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      t.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      t.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return Mesh(std::move(t), std::move(p));
}

Mesh append(const Mesh& a, const Mesh& b) {
  std::vector<Vec3> p(a.positions().begin(), a.positions().end());
  std::vector<Tri> t(a.triangles().begin(), a.triangles().end());
  const auto off = std::uint32_t(p.size());
  p.insert(p.end(), b.positions().begin(), b.positions().end());
  for (Tri f : b.triangles()) t.push_back({f[0] + off, f[1] + off, f[2] + off});
  return Mesh(std::move(t), std::move(p));
}

// Closed cube [0, s]^3, every face an n x n grid, vertices welded by integer lattice position.
Mesh closed_box(int n, double s) {
  std::map<std::tuple<int, int, int>, std::uint32_t> index;
  std::vector<Vec3> p;
  std::vector<Tri> t;
  auto vid = [&](int a, int b, int c) {
    auto [it, fresh] = index.try_emplace({a, b, c}, std::uint32_t(p.size()));
    if (fresh) p.push_back(Vec3(s * a / n, s * b / n, s * c / n));
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          auto at = [&](int u, int v) {
            int c[3];
            c[axis] = side * n, c[(axis + 1) % 3] = u, c[(axis + 2) % 3] = v;
            return vid(c[0], c[1], c[2]);
          };
          t.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
          t.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
  return Mesh(std::move(t), std::move(p));
}

// Double-precision segment/triangle test (Moller-Trumbore), for the brute-force answer.
bool segment_hits(const Vec3& o, const Vec3& d, double tmax, const std::array<Vec3, 3>& c) {
  const Vec3 e1 = c[1] - c[0], e2 = c[2] - c[0], pv = d.cross(e2);
  const double det = e1.dot(pv);
  if (std::abs(det) < 1e-300) return false;
  const Vec3 tv = o - c[0];
  const double u = tv.dot(pv) / det;
  if (u < 0 || u > 1) return false;
  const Vec3 qv = tv.cross(e1);
  const double v = d.dot(qv) / det;
  if (v < 0 || u + v > 1) return false;
  const double t = e2.dot(qv) / det;
  return t > 1e-9 && t < tmax;
}

// Rays straight down (-z) from height `top` through (x, y) points of a regular grid.
bvh::RayBatch rays_down(int n, double lo, double hi, double top) {
  bvh::RayBatch r;
  r.resize(std::size_t(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      r.set(std::size_t(j) * n + i, Vec3(lo + (hi - lo) * (i + 0.5) / n, lo + (hi - lo) * (j + 0.5) / n, top),
            {0.0f, 0.0f, -1.0f});
  return r;
}

struct Traced {
  bvh::HitBatch hits;
  ptc::SurfaceHits s;
};
Traced primary(const bvh::TraceData& d, const Mesh& m, const bvh::RayBatch& rays) {
  Traced t;
  (void)bvh::trace(d, rays, t.hits);
  t.s = ptc::surface_hits(m, rays, t.hits);
  return t;
}

}  // namespace

TEST(TraceRays, ShadowOfABlockerMatchesAnalyticAndBruteForce) {
  // Ground z = 0 and a blocker square at z = 1 in a local frame; the world is that frame rotated
  // (tilted: no axis-aligned normal, so rounding hits every coordinate) or not.
  for (bool tilt : {false, true}) {
    const Eigen::Matrix3d R = tilt ? Eigen::Matrix3d(Eigen::AngleAxisd(0.9, Vec3(2, -1, 1).normalized()))
                                   : Eigen::Matrix3d::Identity();
    auto world = [&](const Vec3& q) { return Vec3(R * q); };
    const Mesh ground = grid(24, -2, 2, 0, world);
    const Mesh blocker =
        grid(3, 0, 1, 0, [&](const Vec3& q) { return world(Vec3(-0.5 + q.x(), -0.3 + 0.7 * q.y(), 1.0)); });
    const Mesh m = append(ground, blocker);
    const bvh::TriangleScene scene(m);
    const Vec3 light_local(0.3, 0.2, 3.0), light = world(light_local);
    bvh::RayBatch rays = rays_down(97, -1.95, 1.95, 5.0);
    for (std::size_t i = 0; i < rays.size(); ++i) {  // into the world frame
      const Vec3 o = world(Vec3(rays.ox[i], rays.oy[i], rays.oz[i])), d = world(Vec3(0, 0, -1));
      rays.set(i, o, {float(d.x()), float(d.y()), float(d.z())});
    }
    const Traced tr = primary(scene.data(), m, rays);
    const ptc::RayFrame frame{m.bounds(), scene.data().origin};
    const ptc::ShadowResult sh = ptc::trace_shadows(scene.data(), tr.s, light, frame, 2);
    std::size_t shadowed = 0, lit = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      ASSERT_TRUE(tr.s.hit[i]) << i;
      const Vec3& p = tr.s.point[i];
      EXPECT_NEAR(tr.s.normal[i].dot(world(Vec3(0, 0, 1))), 1.0, 1e-12);  // faces the ray, which came from above
      if (tr.hits.triangle[i] >= ground.triangle_count()) {  // on the blocker's top: the light is above
        EXPECT_EQ(sh.lit[i], 1) << i;
        continue;
      }
      // Analytic, in the local frame: where the segment p -> light crosses z = 1.
      const Vec3 pl = R.transpose() * p;
      const Vec3 q = pl + (light_local - pl) * ((1.0 - pl.z()) / (light_local.z() - pl.z()));
      const double inside = std::min({q.x() + 0.5, 0.5 - q.x(), q.y() + 0.3, 0.4 - q.y()});
      if (std::abs(inside) < 1e-6) continue;  // the shadow's edge: either answer is right
      const bool analytic_shadow = inside > 0;
      bool brute = false;  // every triangle, double precision, from the surface point itself
      const Vec3 d = light - p;
      for (std::size_t t = 0; t < m.triangle_count() && !brute; ++t) brute = segment_hits(p, d, 1.0, m.corners(t));
      EXPECT_EQ(analytic_shadow, brute) << i;
      EXPECT_EQ(sh.lit[i], analytic_shadow ? 0 : 1) << "tilt " << tilt << " point " << i << " at " << p.transpose();
      (analytic_shadow ? shadowed : lit) += 1;
    }
    EXPECT_GT(shadowed, 200u);
    EXPECT_GT(lit, 2000u);
    EXPECT_EQ(sh.stats.rays, rays.size());  // every point faces the light
    EXPECT_EQ(sh.stats.hits, shadowed);
  }
}

// A light so far that its squared distance overflows (1e308) shadows as a far light in the same
// direction (1e30): the same lit points, point by point, and a blocker's shadow (before, the
// direction was taken as l / |l| with |l| = inf: zero, and no shadow at all).
TEST(TraceRays, AFarLightShadowsAsANearerOneInItsDirection) {
  const Mesh ground = grid(24, -2, 2, 0);
  const Mesh blocker = grid(3, 0, 1, 0, [](const Vec3& q) { return Vec3(-0.5 + q.x(), -0.3 + 0.7 * q.y(), 1.0); });
  const Mesh m = append(ground, blocker);
  const bvh::TriangleScene scene(m);
  const Traced tr = primary(scene.data(), m, rays_down(97, -1.95, 1.95, 5.0));
  const ptc::RayFrame frame{m.bounds(), scene.data().origin};
  const Vec3 dir(0.6, 0.4, 1.0);  // (times 1.7e308: a length of 2.1e308, beyond double)
  const ptc::ShadowResult nearer = ptc::trace_shadows(scene.data(), tr.s, 1e30 * dir, frame, 2);
  const ptc::ShadowResult far = ptc::trace_shadows(scene.data(), tr.s, 1.7e308 * dir, frame, 2);
  ASSERT_FALSE(std::isfinite((1.7e308 * dir).norm()));
  EXPECT_GT(nearer.stats.hits, 200u);
  EXPECT_EQ(far.stats.rays, nearer.stats.rays);
  EXPECT_EQ(far.stats.hits, nearer.stats.hits);
  EXPECT_EQ(far.lit, nearer.lit);
  EXPECT_LT((ptc::unit_vector(Vec3(1e308, 1.5e308, 0)) - Vec3(1.0, 1.5, 0.0).normalized()).norm(), 1e-15);
  EXPECT_EQ(Vec3(1e308, 1.5e308, 0).stableNormalized(), Vec3::Zero());  // (why unit_vector: Eigen's overflows)
}

// morton_order: a permutation of the points, the hits first; the shadow pass over it lights the
// same points as in pixel order; and neighbours in it lie near each other where pixel order
// scatters them (the points of a shuffled grid: the mean step between consecutive hits falls).
TEST(TraceRays, MortonOrderedShadowsLightTheSamePoints) {
  const Mesh ground = grid(24, -2, 2, 0);
  const Mesh blocker = grid(3, 0, 1, 0, [](const Vec3& q) { return Vec3(-0.5 + q.x(), -0.3 + 0.7 * q.y(), 1.0); });
  const Mesh m = append(ground, blocker);
  const bvh::TriangleScene scene(m);
  bvh::RayBatch rays = rays_down(61, -2.5, 2.5, 5.0);  // (some miss the ground)
  const Traced tr = primary(scene.data(), m, rays);
  // Shuffle the points (a scattered pixel order).
  ptc::SurfaceHits s = tr.s;
  std::mt19937 rng(7);
  for (std::size_t i = s.size(); i > 1; --i) {
    const std::size_t j = rng() % i;
    std::swap(s.point[i - 1], s.point[j]), std::swap(s.normal[i - 1], s.normal[j]);
    const std::uint8_t h = s.hit[i - 1];
    s.hit[i - 1] = s.hit[j], s.hit[j] = h;
  }
  const std::vector<std::uint32_t> order = ptc::morton_order(s, m.bounds());
  ASSERT_EQ(order.size(), s.size());
  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::uint32_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  std::size_t hits = 0;
  for (std::uint8_t h : s.hit) hits += h;
  ASSERT_GT(hits, 100u);
  ASSERT_LT(hits, s.size());
  for (std::size_t k = 0; k < order.size(); ++k) EXPECT_EQ(s.hit[order[k]] != 0, k < hits) << k;
  auto mean_step = [&](auto index) {
    double sum = 0;
    for (std::size_t k = 1; k < hits; ++k) sum += (s.point[index(k)] - s.point[index(k - 1)]).norm();
    return sum / double(hits - 1);
  };
  std::vector<std::uint32_t> hit_ids;
  for (std::uint32_t i = 0; i < s.size(); ++i)
    if (s.hit[i]) hit_ids.push_back(i);
  const double scattered = mean_step([&](std::size_t k) { return hit_ids[k]; });
  const double ordered = mean_step([&](std::size_t k) { return order[k]; });
  EXPECT_LT(ordered, 0.2 * scattered) << ordered << " " << scattered;
  const ptc::RayFrame frame{m.bounds(), scene.data().origin};
  const Vec3 light(0.6, 0.4, 3.0);
  for (const bool packets : {false, true}) {
    const ptc::ShadowResult a = ptc::trace_shadows(ptc::target_of(scene.data()), s, light, frame, 2, packets);
    const ptc::ShadowResult b = ptc::trace_shadows(ptc::target_of(scene.data()), s, light, frame, 2, packets, order);
    EXPECT_GT(a.stats.hits, 50u);
    EXPECT_EQ(a.lit, b.lit) << packets;
    EXPECT_EQ(a.stats.rays, b.stats.rays);
    EXPECT_EQ(a.stats.hits, b.stats.hits);
  }
  EXPECT_THROW((void)ptc::trace_shadows(ptc::target_of(scene.data()), s, light, frame, 1, false,
                                        std::span<const std::uint32_t>(order.data(), 3)),
               std::invalid_argument);
}

// with_coherence hands its hint to the target's options, whatever the pass asks (Embree's packets
// read it; the hits do not show it, so the options themselves are checked).
TEST(TraceRays, WithCoherenceSetsTheHint) {
  std::vector<bool> seen;
  const ptc::TraceTarget target{[&](const bvh::RayBatch&, bvh::HitBatch&, const bvh::TraceOptions& o) {
                                  seen.push_back(o.coherent);
                                  return bvh::TraceTotals{};
                                },
                                Vec3::Zero()};
  bvh::RayBatch rays;
  bvh::HitBatch hits;
  bvh::TraceOptions asked;
  asked.coherent = true;
  (void)ptc::with_coherence(target, false).trace(rays, hits, asked);
  asked.coherent = false;
  (void)ptc::with_coherence(target, true).trace(rays, hits, asked);
  (void)target.trace(rays, hits, asked);
  EXPECT_EQ(seen, (std::vector<bool>{false, true, false}));
}

TEST(TraceRays, LightBehindTheSurfaceIsUnlitWithoutARay) {
  const Mesh m = grid(4, -1, 1, 0);
  const bvh::TriangleScene scene(m);
  const Traced tr = primary(scene.data(), m, rays_down(8, -0.9, 0.9, 2.0));
  const ptc::ShadowResult sh =
      ptc::trace_shadows(scene.data(), tr.s, Vec3(0, 0, -3), ptc::RayFrame{m.bounds(), scene.data().origin}, 1);
  EXPECT_EQ(sh.stats.rays, 0u);
  for (auto l : sh.lit) EXPECT_EQ(l, 0);
}

TEST(TraceRays, OpenPlanesAreFullyUnoccludedAtAnyScaleAndTilt) {
  // The self-intersection cases: a flat open plane must see the whole hemisphere. Tilted (no
  // axis-aligned normal: rounding in every coordinate), far from the world origin, and tiny.
  const Eigen::Matrix3d rot = (Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized())).toRotationMatrix();
  struct Case {
    const char* name;
    double scale;
    Vec3 shift;
    bool tilt;
  };
  for (const Case& c : {Case{"unit", 1.0, Vec3::Zero(), false}, Case{"tilted", 1.0, Vec3::Zero(), true},
                        Case{"far", 1.0, Vec3(1e6, -2e6, 3e6), true}, Case{"tiny", 1e-6, Vec3::Zero(), true},
                        Case{"huge", 1e7, Vec3::Zero(), true}}) {
    auto xf = [&](const Vec3& q) { return Vec3(c.scale * (c.tilt ? Vec3(rot * q) : q) + c.shift); };
    const Mesh m = grid(16, -1, 1, 0, xf);
    const bvh::TriangleScene scene(m);
    // Rays towards the plane from above (in the plane's own frame), through jittered points.
    bvh::RayBatch rays;
    const int n = 20;
    rays.resize(std::size_t(n) * n);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> jit(-0.02, 0.02);
    const Vec3 nrm = c.tilt ? Vec3(rot * Vec3(0, 0, 1)) : Vec3(0, 0, 1);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 target = xf(Vec3(-0.95 + 1.9 * (i + 0.5) / n + jit(rng), -0.95 + 1.9 * (j + 0.5) / n + jit(rng), 0));
        const Vec3 eye = target + c.scale * (2.0 * nrm + Vec3(0.1, -0.2, 0.05));
        const Vec3 d = (target - eye).normalized();
        rays.set(std::size_t(j) * n + i, eye, {float(d.x()), float(d.y()), float(d.z())});
      }
    const Traced tr = primary(scene.data(), m, rays);
    ptc::AoConfig ac;
    ac.samples = 64;
    ac.max_distance_rel = 2.0;
    const ptc::AoResult ao = ptc::trace_ao(scene.data(), tr.s, ac, ptc::RayFrame{m.bounds(), scene.data().origin}, 2);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      ASSERT_TRUE(tr.s.hit[i]) << c.name << " ray " << i;
      EXPECT_EQ(ao.ao[i], 1.0f) << c.name << " point " << i;
    }
    EXPECT_EQ(ao.stats.hits, 0u) << c.name;
    EXPECT_EQ(ao.stats.rays, 64u * rays.size()) << c.name;
  }
}

TEST(TraceRays, InsideAClosedBoxEverythingIsOccludedUnlessTheDistanceIsShort) {
  for (double s : {1.0, 1e-5, 3e5}) {
    const Mesh m = closed_box(6, s);
    const bvh::TriangleScene scene(m);
    const Vec3 centre = Vec3::Constant(0.5 * s);
    bvh::RayBatch rays;
    const int n = 600;
    rays.resize(n);
    std::mt19937 rng(11);
    std::normal_distribution<double> g;
    for (int i = 0; i < n; ++i) {
      const Vec3 d = Vec3(g(rng), g(rng), g(rng)).normalized();
      rays.set(i, centre + 0.1 * s * Vec3(g(rng), g(rng), g(rng)).cwiseMax(-2).cwiseMin(2), {float(d.x()), float(d.y()), float(d.z())});
    }
    const Traced tr = primary(scene.data(), m, rays);
    const ptc::RayFrame frame{m.bounds(), scene.data().origin};
    ptc::AoConfig ac;
    ac.samples = 32;
    ac.max_distance_rel = 1.0;  // the diagonal: longer than any chord inside the box
    const ptc::AoResult ao = ptc::trace_ao(scene.data(), tr.s, ac, frame, 2);
    for (int i = 0; i < n; ++i) {
      ASSERT_TRUE(tr.s.hit[i]) << "a ray from inside left the closed box: " << i;
      // The facing normal points into the box.
      EXPECT_GT(tr.s.normal[i].dot(centre - tr.s.point[i]), 0.0);
      EXPECT_EQ(ao.ao[i], 0.0f) << "scale " << s << " point " << i;
    }
    // Short AO distance: points at least 0.05 s from every edge of their face see nothing.
    ac.max_distance_rel = 0.02;  // 0.035 s
    const ptc::AoResult near = ptc::trace_ao(scene.data(), tr.s, ac, frame, 1);
    std::size_t checked = 0;
    for (int i = 0; i < n; ++i) {
      const Vec3 q = tr.s.point[i] / s;
      int interior = 0;  // coordinates away from 0 and 1
      for (int a = 0; a < 3; ++a) interior += q[a] > 0.05 && q[a] < 0.95;
      if (interior < 2) continue;
      ++checked;
      EXPECT_EQ(near.ao[i], 1.0f) << "scale " << s << " point " << i;
    }
    EXPECT_GT(checked, 400u);
  }
}

TEST(TraceRays, CosineHemisphereSamplesAreUnitCosineDistributed) {
  for (const Vec3& n : {Vec3(0, 0, 1), Vec3(0, 0, -1), Vec3(1, 0, 0), Vec3(1, -2, 3).normalized(), Vec3(0, -1, 1e-9).normalized()}) {
    double sum_cos = 0, sum_cos2 = 0;
    const int N = 40000;
    Vec3 mean_tangent = Vec3::Zero();
    for (int k = 0; k < N; ++k) {
      const auto [u1, u2] = ptc::ao_uniforms(7, 123, std::uint64_t(k));
      ASSERT_GE(u1, 0.0);
      ASSERT_LT(u1, 1.0);
      const Vec3 d = ptc::cosine_hemisphere(n, u1, u2);
      ASSERT_NEAR(d.norm(), 1.0, 1e-12);
      const double c = d.dot(n);
      ASSERT_GT(c, 0.0);
      sum_cos += c, sum_cos2 += c * c;
      mean_tangent += d - c * n;
    }
    // pdf cos/pi: E[cos] = 2/3, E[cos^2] = 1/2, tangent components average to 0.
    EXPECT_NEAR(sum_cos / N, 2.0 / 3.0, 0.006) << n.transpose();
    EXPECT_NEAR(sum_cos2 / N, 0.5, 0.006) << n.transpose();
    EXPECT_LT((mean_tangent / N).norm(), 0.015) << n.transpose();
  }
}

TEST(TraceRays, AoIsDeterministicAcrossThreadsAndDependsOnTheSeed) {
  // Ground with a blocker: partial occlusion, so seeds matter.
  const Mesh m = append(grid(12, -2, 2, 0), grid(2, -0.5, 0.5, 0.3));
  const bvh::TriangleScene scene(m);
  const Traced tr = primary(scene.data(), m, rays_down(40, -1.9, 1.9, -3.0 + 8.0));
  const ptc::RayFrame frame{m.bounds(), scene.data().origin};
  ptc::AoConfig ac;
  ac.samples = 8;
  ac.max_distance_rel = 0.5;
  const auto a1 = ptc::trace_ao(scene.data(), tr.s, ac, frame, 1);
  const auto a2 = ptc::trace_ao(scene.data(), tr.s, ac, frame, 2);
  EXPECT_EQ(a1.ao, a2.ao);
  ac.seed = 2;
  const auto b = ptc::trace_ao(scene.data(), tr.s, ac, frame, 2);
  EXPECT_NE(a1.ao, b.ao);
  std::size_t partial = 0;
  for (float v : a1.ao) partial += v > 0 && v < 1;
  EXPECT_GT(partial, 50u);
}

TEST(TraceRays, OffsetIsRelativeToTheScene) {
  ptc::Box3 b;
  b.extend(Vec3(-1, -1, -1));
  b.extend(Vec3(1, 1, 1));
  const ptc::RayFrame f{b, Vec3::Zero()};
  EXPECT_DOUBLE_EQ(f.offset_eps(Vec3::Zero()), ptc::kRayOffsetScale);
  ptc::Box3 t;
  t.extend(Vec3(-1e-6, -1e-6, -1e-6));
  t.extend(Vec3(1e-6, 1e-6, 1e-6));
  const ptc::RayFrame tf{t, Vec3::Zero()};
  EXPECT_DOUBLE_EQ(tf.offset_eps(Vec3::Zero()), 1e-6 * ptc::kRayOffsetScale);
  // Measured in the trace frame: a scene far from the world origin gets the same offset.
  ptc::Box3 far = b;
  far.lo += Vec3(1e7, 0, 0), far.hi += Vec3(1e7, 0, 0);
  const ptc::RayFrame ff{far, Vec3(1e7, 0, 0)};
  EXPECT_DOUBLE_EQ(ff.offset_eps(Vec3(1e7, 0, 0)), ptc::kRayOffsetScale);
  const Vec3 o = f.offset_origin(Vec3(0.5, 0, 0), Vec3(0, 1, 0));
  EXPECT_EQ(o, Vec3(0.5, ptc::kRayOffsetScale, 0));
}
