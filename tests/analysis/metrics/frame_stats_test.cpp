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

}  // namespace
}  // namespace ptc
