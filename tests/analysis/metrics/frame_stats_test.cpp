// Per-frame shape statistics (analysis/metrics/frame_stats.h) against hand-computed areas.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/metrics/frame_stats.h"

namespace ptc {
namespace {

TEST(FrameStatsFn, AreaRatiosOfAScaledTriangleAndADegenerateOne) {
  const std::vector<Tri> tris = {{0, 1, 2}, {3, 4, 5}};
  const std::vector<Vec3> a = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)};
  std::vector<Vec3> b = a;
  b[1] = Vec3(3, 0, 0);  // first triangle: area x3
  b[5] = Vec3(2, 5, 0);  // second: was degenerate, excluded from ratios
  const auto first = triangle_areas(tris, a);
  const FrameStats s = frame_stats(7, tris, b, first);
  EXPECT_EQ(s.frame, 7);
  EXPECT_EQ(s.degenerate_at_first, 1u);
  EXPECT_DOUBLE_EQ(s.area_ratio_min, 3.0);
  EXPECT_DOUBLE_EQ(s.area_ratio_max, 3.0);
  EXPECT_DOUBLE_EQ(s.total_area, 1.5 + 2.5);
  const FrameStats none = frame_stats(0, std::vector<Tri>{{3, 4, 5}}, a, std::vector<double>{0.0});
  EXPECT_TRUE(std::isnan(none.area_ratio_mean));
}

TEST(FrameStatsFn, NearDegenerateTrianglesAreDegenerate) {
  // A sliver whose apex is 1e-18 off its base (sine ~1e-18, below the toolkit's 1e-12: area 0 by
  // docs/mesh_policy.md) is left out of the ratios, as an exactly collinear one: bent later to a
  // real triangle, it would otherwise give a ratio of 1e18.
  const std::vector<Tri> tris = {{0, 1, 2}, {3, 4, 5}};
  const std::vector<Vec3> a = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 1e-18, 0)};
  const auto first = triangle_areas(tris, a);
  EXPECT_EQ(first[1], 0.0);
  EXPECT_EQ(first[0], 0.5);
  std::vector<Vec3> b = a;
  b[5] = Vec3(0.5, 1.0, 0);
  const FrameStats s = frame_stats(1, tris, b, first);
  EXPECT_EQ(s.degenerate_at_first, 1u);
  EXPECT_EQ(s.area_ratio_max, 1.0);
  EXPECT_DOUBLE_EQ(s.total_area, 0.5 + 0.5);
  // ... and counts 0 in a frame's total where it is near-degenerate.
  EXPECT_DOUBLE_EQ(frame_stats(0, tris, a, first).total_area, 0.5);
}

}  // namespace
}  // namespace ptc
