// Cloth simulation: invariants checked frame by frame (no NaN, energy never above the start,
// no particle inside the sphere or below the floor beyond rounding, fixed topology, bounded
// stretch), that the scene does what it claims (the cloth touches the sphere, then slides off
// onto the floor), determinism across runs and thread counts, restart and interpolation.
#include "toolkit/anim/cloth.h"

#include <gtest/gtest.h>

#include <oneapi/tbb/global_control.h>

#include <cmath>

#include "toolkit/core/error.h"

namespace ptc {
namespace {

std::vector<Vec3> frame(Animation& a, double t) {
  std::vector<Vec3> out(a.rest().vertex_count());
  a.positions(t, out);
  return out;
}

TEST(Cloth, RejectsBadParameters) {
  auto bad = [](auto&& edit) {
    ClothParams p;
    edit(p);
    EXPECT_THROW(ClothSimulation{p}, InputError);
  };
  bad([](ClothParams& p) { p.resolution = 1; });
  bad([](ClothParams& p) { p.resolution = -5; });
  bad([](ClothParams& p) { p.size = 0; });
  bad([](ClothParams& p) { p.sphere_radius = -1; });
  bad([](ClothParams& p) { p.sphere_center = Vec3(0, std::nan(""), 0); });
  bad([](ClothParams& p) { p.fps = 0; });
  bad([](ClothParams& p) { p.substeps = 0; });
  bad([](ClothParams& p) { p.iterations = 0; });
  bad([](ClothParams& p) { p.shear_stiffness = 1.5; });
  bad([](ClothParams& p) { p.friction = -0.1; });
  bad([](ClothParams& p) { p.gravity = INFINITY; });

  ClothSimulation c(ClothParams{});
  std::vector<Vec3> ok(c.rest().vertex_count()), wrong(3);
  EXPECT_THROW(c.positions(-1.0, ok), std::invalid_argument);
  EXPECT_THROW(c.positions(std::nan(""), ok), std::invalid_argument);
  EXPECT_THROW(c.positions(1.0, wrong), std::invalid_argument);
}

TEST(Cloth, SmallestGridAndTopology) {
  ClothParams p;
  p.resolution = 2;
  ClothSimulation c(p);
  EXPECT_EQ(c.rest().triangle_count(), 2u);
  EXPECT_EQ(c.rest().vertex_count(), 4u);
  for (int n : {3, 7, 20}) {
    p.resolution = n;
    ClothSimulation d(p);
    ASSERT_EQ(d.rest().triangle_count(), std::size_t(2 * (n - 1) * (n - 1)));
    // Every triangle faces +y at rest (counter-clockwise seen from above) and has area a^2 / 2.
    const double a = p.size / (n - 1);
    for (std::size_t t = 0; t < d.rest().triangle_count(); ++t) {
      const auto c3 = d.rest().corners(t);
      const Vec3 nrm = (c3[1] - c3[0]).cross(c3[2] - c3[0]);
      ASSERT_NEAR(nrm.y(), a * a, 1e-12);
      ASSERT_NEAR(nrm.norm(), a * a, 1e-12);
    }
  }
}

TEST(Cloth, InvariantsFrameByFrameAndSlidesOff) {
  ClothParams p;
  p.resolution = 16;
  ClothSimulation c(p);
  const auto tris0 = std::vector<Tri>(c.rest().triangles().begin(), c.rest().triangles().end());
  const double E0 = c.energy();
  const double R = c.collision_radius();
  const double floor_y = p.sphere_center.y() - p.sphere_radius + c.thickness();
  const double a = p.size / (p.resolution - 1);
  bool touched_sphere = false;
  std::size_t on_floor_last = 0;
  double max_energy = E0;
  for (int f = 1; f <= 150; ++f) {
    const auto x = frame(c, f);
    ASSERT_EQ(c.frame(), f);
    ASSERT_EQ(c.rest().triangle_count(), tris0.size());
    ASSERT_TRUE(std::equal(tris0.begin(), tris0.end(), c.rest().triangles().begin()));
    std::size_t on_floor = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      ASSERT_TRUE(x[i].allFinite()) << "frame " << f << " particle " << i;
      const double d = (x[i] - p.sphere_center).norm();
      ASSERT_GE(d, R * (1 - 1e-12)) << "inside the sphere: frame " << f << " particle " << i;
      ASSERT_GE(x[i].y(), floor_y - 1e-12) << "below the floor: frame " << f << " particle " << i;
      if (d < R * (1 + 1e-6)) touched_sphere = true;
      if (x[i].y() < floor_y + 1e-6) ++on_floor;
    }
    on_floor_last = on_floor;
    // Stretch stays bounded: no grid edge longer than 1.5 rest lengths.
    for (int i = 0; i < p.resolution; ++i)
      for (int j = 0; j + 1 < p.resolution; ++j) {
        const std::size_t u = std::size_t(i * p.resolution + j);
        ASSERT_LT((x[u + 1] - x[u]).norm(), 1.5 * a) << "frame " << f;
      }
    const double E = c.energy();
    max_energy = std::max(max_energy, E);
    // Energy (kinetic + potential above the floor) never rises above the start: gravity is
    // the only force doing work, damping and PBD projections remove energy.
    ASSERT_LE(E, E0 * (1 + 1e-9)) << "frame " << f;
  }
  EXPECT_TRUE(touched_sphere);
  // The cloth was off centre: by frame 150 most of it lies on the floor, off the sphere.
  EXPECT_GT(on_floor_last, c.rest().vertex_count() / 4) << "the cloth did not slide off onto the floor";
  EXPECT_LT(c.energy(), 0.5 * E0);
}

TEST(Cloth, DeterministicAcrossRunsAndThreadCounts) {
  ClothParams p;
  p.resolution = 70;  // 4900 particles: above the parallel grain, so classes really run in parallel
  p.substeps = 4;
  ClothSimulation a(p), b(p);
  const auto fa = frame(a, 12);
  std::vector<Vec3> fb;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    fb = frame(b, 12);
  }
  ASSERT_EQ(fa, fb);
}

TEST(Cloth, RestartAndInterpolation) {
  ClothParams p;
  p.resolution = 10;
  ClothSimulation c(p), fresh(p);
  const auto f5 = frame(c, 5);
  const auto f3 = frame(c, 3);  // earlier: restarts
  EXPECT_EQ(f3, frame(fresh, 3));
  EXPECT_NE(f3, f5);
  const auto f0 = frame(c, 0);
  const auto r = c.rest().positions();
  EXPECT_TRUE(std::equal(f0.begin(), f0.end(), r.begin()));

  ClothSimulation d(p);
  const auto g2 = frame(d, 2), g3 = frame(d, 3);
  ClothSimulation e(p);
  const auto half = frame(e, 2.5);
  for (std::size_t i = 0; i < half.size(); ++i)
    ASSERT_LT((half[i] - 0.5 * (g2[i] + g3[i])).norm(), 1e-12) << i;
}

TEST(Cloth, NoGravityStaysAtRest) {
  ClothParams p;
  p.resolution = 8;
  p.gravity = 0;
  ClothSimulation c(p);
  const auto f = frame(c, 20);
  const auto r = c.rest().positions();
  for (std::size_t i = 0; i < f.size(); ++i) ASSERT_LT((f[i] - r[i]).norm(), 1e-12) << i;
}

}  // namespace
}  // namespace ptc
