// The area of a triangle inside a box (toolkit/geometry/clip.h) against hand-computed areas and
// a seeded Monte Carlo estimate; far offsets and degenerate triangles.
#include <gtest/gtest.h>

#include <random>

#include "toolkit/geometry/clip.h"

namespace ptc {
namespace {

Box3 box(Vec3 lo, Vec3 hi) {
  Box3 b;
  b.extend(lo);
  b.extend(hi);
  return b;
}

TEST(ClippedArea, HandComputedCases) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);  // area 1/2
  EXPECT_DOUBLE_EQ(clipped_area(a, b, c, box(Vec3(-1, -1, -1), Vec3(2, 2, 2))), 0.5);  // inside
  EXPECT_EQ(clipped_area(a, b, c, box(Vec3(2, 2, -1), Vec3(3, 3, 1))), 0.0);            // outside
  // x <= 1/2 under the hypotenuse: integral of (1 - x) over [0, 1/2] = 3/8.
  EXPECT_NEAR(clipped_area(a, b, c, box(Vec3(-1, -1, -1), Vec3(0.5, 2, 1))), 0.375, 1e-15);
  // The square [0, 1/2]^2 lies under x + y <= 1 whole.
  EXPECT_NEAR(clipped_area(a, b, c, box(Vec3(0, 0, -1), Vec3(0.5, 0.5, 1))), 0.25, 1e-15);
  // A corner square [1/2, 1]^2 holds only the triangle x + y <= 1 above (1/2, 1/2): nothing.
  EXPECT_NEAR(clipped_area(a, b, c, box(Vec3(0.5, 0.5, -1), Vec3(1, 1, 1))), 0.0, 1e-15);
  // The triangle in the box's face plane z = 0 counts (the box is closed); just above it not.
  EXPECT_DOUBLE_EQ(clipped_area(a, b, c, box(Vec3(-1, -1, -1), Vec3(2, 2, 0))), 0.5);
  EXPECT_EQ(clipped_area(a, b, c, box(Vec3(-1, -1, 1e-9), Vec3(2, 2, 1))), 0.0);
  // A slanted triangle through a slab: the part between two planes.
  const Vec3 d(0, 0, 0), e(2, 0, 2), f(0, 2, 2);  // on z = x + y, area 2 sqrt(3)
  // z in [0, 1] <=> x + y <= 1: the triangle's lower quarter, area sqrt(3) / 2.
  EXPECT_NEAR(clipped_area(d, e, f, box(Vec3(-5, -5, 0), Vec3(5, 5, 1))), std::sqrt(3.0) / 2, 1e-14);
  // Degenerate triangles have no area.
  EXPECT_EQ(clipped_area(a, a, b, box(Vec3(-1, -1, -1), Vec3(2, 2, 2))), 0.0);
  EXPECT_EQ(clipped_area(a, b, Vec3(2, 0, 0), box(Vec3(-1, -1, -1), Vec3(2, 2, 2))), 0.0);
  EXPECT_EQ(clipped_area(a, b, c, Box3{}), 0.0);
}

TEST(ClippedArea, AgreesWithMonteCarloAndFarAway) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0), w(0.0, 1.0);
  for (int k = 0; k < 20; ++k) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Box3 bx = box(Vec3(u(rng), u(rng), u(rng)) * 0.5, Vec3(u(rng), u(rng), u(rng)) * 0.5 + Vec3(0.6, 0.6, 0.6));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    // Uniform points on the triangle (square-root parametrisation), fraction inside the box.
    const int n = 200000;
    int in = 0;
    for (int i = 0; i < n; ++i) {
      const double r1 = std::sqrt(w(rng)), r2 = w(rng);
      const Vec3 p = (1 - r1) * a + r1 * (1 - r2) * b + r1 * r2 * c;
      in += (p.array() >= bx.lo.array()).all() && (p.array() <= bx.hi.array()).all();
    }
    const double mc = area * double(in) / n;
    const double got = clipped_area(a, b, c, bx);
    EXPECT_NEAR(got, mc, 4.0 * area * std::sqrt(0.25 / n) + 1e-12) << k;  // 4 sigma
    // The same triangle and box 1e7 away: the same area to ~1e-8 relative (box-centred frame).
    const Vec3 t(1e7, -3e7, 2e7);
    Box3 far = bx;
    far.lo += t, far.hi += t;
    EXPECT_NEAR(clipped_area(a + t, b + t, c + t, far), got, 1e-7 * (area + 1e-3)) << k;
  }
}

}  // namespace
}  // namespace ptc
