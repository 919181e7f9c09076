// Embree as the peer: it traces in our scenes' trace frame, scaled by the same power of two, with
// the rays' t scaled alike. The independent answer is Embree itself on the same mesh at a size it
// handles unscaled: a mesh moved to 2^61, 2^70 or 2^-90 times that size must give the same
// triangles, the same u and v and t times the size, ray for ray (before the scaled frame, Embree
// dropped every triangle beyond 1.8e18 and asserted on the rays). And a ray Embree cannot take is
// refused with an exception, never an abort.
#include "bvh/embree_peer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvh/scene_config.h"
#include "test_util.h"

namespace ptc::bvh {
namespace {

// The armadillo with its bounds' centre at `centre` and its largest |p - centre| coordinate in
// [0.5, 1) times `size` (a power of two): at size 1 the trace frame's scale is 1, at any other
// size the frame brings it back to exactly these floats.
Mesh normalised(const Mesh& m, const Vec3& centre, double size) {
  const Vec3 c = 0.5 * (m.bounds().lo + m.bounds().hi);
  double e = 0;
  for (const Vec3& p : m.positions()) e = std::max(e, (p - c).cwiseAbs().maxCoeff());
  const double k = std::ldexp(1.0, -std::ilogb(e) - 1);  // e * k in [0.5, 1)
  std::vector<Vec3> pos;
  for (const Vec3& p : m.positions()) pos.push_back(centre + ((p - c) * k) * size);
  return m.with_positions(pos);
}

RayBatch rays_around(const Vec3& centre, double size, int n, std::uint32_t seed) {
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  RayBatch r;
  r.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const Vec3 o = Vec3(U(g), U(g), U(g)) * 3.0;  // outside and inside the mesh's box
    const Vec3 aim = Vec3(U(g), U(g), U(g)) * 0.4;
    const Vec3 d = (aim - o).normalized();
    r.set(static_cast<std::size_t>(i), centre + o * size, Vec3f{float(d.x()), float(d.y()), float(d.z())},
          i % 5 == 0 ? 0.01f * static_cast<float>(size) : 0.0f,
          i % 7 == 0 ? 2.0f * static_cast<float>(size) : std::numeric_limits<float>::infinity());
  }
  return r;
}

TEST(EmbreePeer, TracesInTheScaledTraceFrameExactly) {
  const Mesh arm = test::load_mesh("armadillo.off");
  const Vec3 centre(3.0, -2.0, 1.0);
  const Mesh unit = normalised(arm, centre, 1.0);
  const RayBatch rays = rays_around(centre, 1.0, 4000, 7);
  for (const EmbreeMode mode : {EmbreeMode::StaticMedium, EmbreeMode::DynamicRefit})
    for (const int width : {1, 8}) {
      const EmbreeScene base(unit, centre, EmbreeConfig{mode, 1, "", StageClock::Wall});
      HitBatch want;
      (void)base.trace_packets(rays, want, HitMode::Closest, 1, width);
      std::size_t hits = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) hits += want.triangle[i] != kNoTriangle;
      ASSERT_GT(hits, rays.size() / 5);
      for (const int e : {61, 70, -90}) {
        const double size = std::ldexp(1.0, e);
        const Vec3 far_centre = centre * size;  // (the centre moves with the mesh)
        const Mesh m = normalised(arm, far_centre, size);
        ASSERT_EQ(trace_frame_scale(m, far_centre), 1.0 / size);
        const EmbreeScene s(m, far_centre, EmbreeConfig{mode, 1, "", StageClock::Wall});
        const RayBatch r = rays_around(far_centre, size, 4000, 7);
        HitBatch got;
        (void)s.trace_packets(r, got, HitMode::Closest, 1, width);
        const std::string what = std::string(to_string(mode)) + " width " + std::to_string(width) + " size 2^" +
                                 std::to_string(e);
        for (std::size_t i = 0; i < rays.size(); ++i) {
          ASSERT_EQ(got.triangle[i], want.triangle[i]) << what << " ray " << i;
          if (want.triangle[i] == kNoTriangle) continue;
          ASSERT_EQ(got.u[i], want.u[i]) << what << " ray " << i;
          ASSERT_EQ(got.v[i], want.v[i]) << what << " ray " << i;
          ASSERT_EQ(double(got.t[i]), double(want.t[i]) * size) << what << " ray " << i;
        }
        HitBatch any;
        (void)s.trace_packets(r, any, HitMode::Any, 1, width);
        for (std::size_t i = 0; i < rays.size(); ++i)
          ASSERT_EQ(any.triangle[i] != kNoTriangle, want.triangle[i] != kNoTriangle) << what << " any hit, ray " << i;
        // The incoherent context flag (Embree's default; the bench's shadow packets may take
        // it): the same closest hits and the same occluded rays.
        HitBatch loose, loose_any;
        (void)s.trace_packets(r, loose, HitMode::Closest, 1, width, /*coherent=*/false);
        (void)s.trace_packets(r, loose_any, HitMode::Any, 1, width, /*coherent=*/false);
        for (std::size_t i = 0; i < rays.size(); ++i) {
          ASSERT_EQ(loose.triangle[i], got.triangle[i]) << what << " incoherent, ray " << i;
          ASSERT_EQ(loose.t[i], got.t[i]) << what << " incoherent, ray " << i;
          ASSERT_EQ(loose_any.triangle[i] != kNoTriangle, any.triangle[i] != kNoTriangle)
              << what << " incoherent any hit, ray " << i;
        }
      }
    }
}

// check_rays (which the benchmarks run before their timed traces) refuses what Embree would
// assert on; what it accepts, Embree traces.
TEST(EmbreePeer, RaysBeyondItsRangeAreRefusedNotAborted) {
  const Mesh arm = test::load_mesh("armadillo.off");
  const Vec3 centre = Vec3::Zero();
  const Mesh unit = normalised(arm, centre, 1.0);
  const EmbreeScene s(unit, centre, EmbreeConfig{EmbreeMode::DynamicRefit, 1, "", StageClock::Wall});
  RayBatch r = rays_around(centre, 1.0, 37, 3);
  HitBatch h;
  EXPECT_NO_THROW(s.check_rays(r));
  r.set(20, Vec3(2e18, 0, 0), Vec3f{-1, 0, 0});  // beyond 1e18 in the frame
  try {
    s.check_rays(r);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("a ray from (2e+18, 0, 0)"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--eye or --light"), std::string::npos) << e.what();
  }
  r.set(20, Vec3(9e17, 0, 0), Vec3f{-1, 0, 0});  // within: traced
  EXPECT_NO_THROW(s.check_rays(r));
  for (const int width : {1, 4, 8, 16}) EXPECT_NO_THROW((void)s.trace_packets(r, h, HitMode::Any, 1, width)) << width;
  r.set(20, Vec3(0, 0, 3), Vec3f{std::nanf(""), 0, -1});  // a NaN direction
  EXPECT_THROW(s.check_rays(r), std::invalid_argument);
  r.set(20, Vec3(0, 0, 3), Vec3f{0, 2e18f, -1});  // a direction beyond its range
  EXPECT_THROW(s.check_rays(r), std::invalid_argument);
  // The frame's scale counts: 2e18 units from the centre of a mesh of 2^40 units is near.
  const Mesh big = normalised(arm, centre, std::ldexp(1.0, 40));
  const EmbreeScene sb(big, centre, EmbreeConfig{EmbreeMode::DynamicRefit, 1, "", StageClock::Wall});
  r.set(20, Vec3(2e18, 0, 0), Vec3f{-1, 0, 0});
  EXPECT_NO_THROW(sb.check_rays(r));
  EXPECT_NO_THROW((void)sb.trace_packets(r, h, HitMode::Closest, 1, 8));
}

}  // namespace
}  // namespace ptc::bvh
