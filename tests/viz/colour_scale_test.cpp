// Colour scales and compositing: ranges from the values (sequential, diverging about a centre,
// constant and empty sets), a fixed range, end colours and NaN, out-of-range counts, tick values,
// and images stacked pixel for pixel.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "viz/colour_scale.h"

namespace ptc::viz {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(ColourScale, RangesFromTheValues) {
  const std::vector<double> v{3, kNaN, 7, 5};
  ColourScale s = make_scale("reg", v, false, 0, std::nullopt);
  EXPECT_EQ(s.min, 3);
  EXPECT_EQ(s.max, 7);
  EXPECT_EQ(s.colormap, "viridis");
  s = make_scale("nodes_visited", v, false, 0, std::nullopt, /*from_zero=*/true);
  EXPECT_EQ(s.min, 0);
  s = make_scale("box_area_ratio", std::vector<double>{0.9, 1.3}, true, 1.0, std::nullopt);
  EXPECT_EQ(s.colormap, "coolwarm");
  EXPECT_DOUBLE_EQ(s.min, 0.7);
  EXPECT_DOUBLE_EQ(s.max, 1.3);
  s = make_scale("c", std::vector<double>{2, 2}, false, 0, std::nullopt);
  EXPECT_EQ(s.min, 1.0);  // one value m: m -+ m / 2, its sign kept
  EXPECT_EQ(s.max, 3.0);
  // A constant zero (an area, a counter): 0 .. 1, no negative legend.
  s = make_scale("box_area", std::vector<double>{0, 0}, false, 0, std::nullopt);
  EXPECT_EQ(s.min, 0.0);
  EXPECT_EQ(s.max, 1.0);
  s = make_scale("triangles_tested", std::vector<double>{0, 0}, false, 0, std::nullopt, /*from_zero=*/true);
  EXPECT_EQ(s.min, 0.0);
  EXPECT_EQ(s.max, 1.0);
  s = make_scale("acc", std::vector<double>{-0.25, -0.25}, false, 0, std::nullopt);
  EXPECT_EQ(s.min, -0.375);
  EXPECT_EQ(s.max, -0.125);
  // Areas of a mesh of 1e-6 units (1e-14 .. 1e-12): a real spread, drawn as it is.
  s = make_scale("box_area", std::vector<double>{1e-14, 3e-13, 1e-12}, false, 0, std::nullopt);
  EXPECT_EQ(s.min, 1e-14);
  EXPECT_EQ(s.max, 1e-12);
  // Rounding noise relative to the values' size: one value.
  s = make_scale("box_area", std::vector<double>{1e-12, 1e-12 * (1 + 1e-15)}, false, 0, std::nullopt);
  EXPECT_DOUBLE_EQ(s.min, 0.5e-12);
  EXPECT_DOUBLE_EQ(s.max, 1.5e-12);
  s = make_scale("d", std::vector<double>{1, 1}, true, 1, std::nullopt);
  EXPECT_LT(s.min, 1);
  EXPECT_GT(s.max, 1);
  s = make_scale("r", std::vector<double>{1.0 - 2e-16, 1.0 + 2e-16}, true, 1.0, std::nullopt, false, 0.0);
  EXPECT_EQ(s.min, 0.5) << "rounding noise is not spread over the map";
  EXPECT_EQ(s.max, 1.5);
  s = make_scale("e", std::vector<double>{kNaN}, false, 0, std::nullopt);
  EXPECT_LT(s.min, s.max);
  s = make_scale("f", v, false, 0, std::pair{-1.0, 1.0});
  EXPECT_EQ(s.from, "--range");
  EXPECT_THROW((void)make_scale("g", v, false, 0, std::pair{1.0, 1.0}), std::invalid_argument);
}

TEST(ColourScale, RatiosStopAtZeroAndKeepTheCentreColour) {
  const ColourScale s = make_scale("box_area_ratio", std::vector<double>{0.5, 4.0}, true, 1.0, std::nullopt, false, 0.0);
  EXPECT_EQ(s.min, 0.0) << "not 1 - 3 = -2: a ratio is never negative";
  EXPECT_EQ(s.max, 4.0);
  EXPECT_TRUE(s.two_slope);
  EXPECT_EQ(colour_of(s, 1.0), coolwarm(0.5));
  EXPECT_EQ(colour_of(s, 0.0), coolwarm(0.0));
  EXPECT_EQ(colour_of(s, 4.0), coolwarm(1.0));
  EXPECT_DOUBLE_EQ(s.fraction(0.5), 0.25);
  EXPECT_DOUBLE_EQ(s.fraction(2.5), 0.75);
  for (double f : {0.0, 0.1, 0.5, 0.8, 1.0}) EXPECT_NEAR(s.fraction(s.value_at(f)), f, 1e-12);
  const auto t = ticks(s, 5);
  ASSERT_EQ(t.size(), 5u);
  EXPECT_EQ(t[0].text, "0");
  EXPECT_EQ(t[2].text, "1");
  EXPECT_EQ(t[3].text, "2.5");
  EXPECT_EQ(t[4].text, "4");
  EXPECT_DOUBLE_EQ(t[3].fraction, 0.75);
  // A fixed range without the centre is linear; with it, two-slope.
  EXPECT_FALSE(make_scale("r", std::vector<double>{}, true, 1.0, std::pair{2.0, 3.0}).two_slope);
  EXPECT_TRUE(make_scale("r", std::vector<double>{}, true, 1.0, std::pair{0.0, 3.0}).two_slope);
  // ... and coloured with the half of the map on its side of the centre: growth stays red (1.2
  // was drawn blue in a range 1.2 .. 2, found by a new user), shrinkage blue; ends clamp.
  const ColourScale up = make_scale("r", std::vector<double>{}, true, 1.0, std::pair{1.2, 2.0});
  EXPECT_EQ(colour_of(up, 2.0), coolwarm(1.0));
  EXPECT_EQ(colour_of(up, 1.2), coolwarm(0.6));
  EXPECT_EQ(colour_of(up, 1.6), coolwarm(0.8));
  EXPECT_EQ(colour_of(up, 1.0), coolwarm(0.6)) << "below the range: its end colour";
  EXPECT_EQ(colour_of(up, 9.0), coolwarm(1.0));
  EXPECT_DOUBLE_EQ(up.fraction(1.6), 0.5) << "laid out linearly on the legend";
  const ColourScale down = make_scale("r", std::vector<double>{}, true, 1.0, std::pair{0.2, 0.6});
  EXPECT_EQ(colour_of(down, 0.2), coolwarm(0.0));
  EXPECT_EQ(colour_of(down, 0.6), coolwarm(0.25));
  EXPECT_EQ(colour_of(down, 0.9), coolwarm(0.25));
  const ColourScale at = make_scale("r", std::vector<double>{}, true, 1.0, std::pair{1.0, 3.0});  // (from the centre)
  EXPECT_EQ(colour_of(at, 1.0), coolwarm(0.5));
  EXPECT_EQ(colour_of(at, 3.0), coolwarm(1.0));
}

TEST(ColourScale, ColoursEndsNanAndOutOfRange) {
  const ColourScale s = make_scale("m", std::vector<double>{}, false, 0, std::pair{10.0, 20.0});
  EXPECT_EQ(colour_of(s, 10), viridis(0));
  EXPECT_EQ(colour_of(s, 20), viridis(1));
  EXPECT_EQ(colour_of(s, 15), viridis(0.5));
  EXPECT_EQ(colour_of(s, -5), viridis(0));
  EXPECT_EQ(colour_of(s, 99), viridis(1));
  EXPECT_EQ(colour_of(s, kNaN), kNanColour);
  const std::vector<double> v{5, 10, 12, 20, 21, 22, kNaN};
  const OutOfRange o = out_of_range(s, v);
  EXPECT_EQ(o.below, 1u);
  EXPECT_EQ(o.above, 2u);
  EXPECT_EQ(o.nan, 1u);
  const ColourScale d = make_scale("d", std::vector<double>{}, true, 0, std::pair{-1.0, 1.0});
  EXPECT_EQ(colour_of(d, 0), coolwarm(0.5));
  EXPECT_EQ(colour_of(d, -1), coolwarm(0));
}

TEST(ColourScale, TicksSpanTheRangeAndIntegersStayIntegers) {
  ColourScale s = make_scale("m", std::vector<double>{}, false, 0, std::pair{0.0, 1.0});
  auto t = ticks(s, 5);
  ASSERT_EQ(t.size(), 5u);
  EXPECT_EQ(t.front().text, "0");
  EXPECT_EQ(t[1].text, "0.25");
  EXPECT_EQ(t.back().text, "1");
  s = make_scale("n", std::vector<double>{}, false, 0, std::pair{0.0, 41.0});
  s.integer = true;
  t = ticks(s, 5);
  ASSERT_EQ(t.size(), 5u);
  for (const Tick& k : t) {
    EXPECT_EQ(k.value, std::round(k.value));
    EXPECT_EQ(k.text, std::to_string(static_cast<int>(k.value)));
  }
  EXPECT_EQ(t.front().value, 0);
  EXPECT_EQ(t.back().value, 41);
  s = make_scale("n", std::vector<double>{}, false, 0, std::pair{0.0, 2.0});
  s.integer = true;
  t = ticks(s, 5);
  ASSERT_EQ(t.size(), 3u) << "0, 1, 2 once each";
  // A narrow range gets the digits that tell its ticks apart.
  s = make_scale("r", std::vector<double>{}, false, 0, std::pair{1.0, 1.0 + 4e-7});
  t = ticks(s, 5);
  std::set<std::string> texts;
  for (const Tick& k : t) texts.insert(k.text);
  EXPECT_EQ(texts.size(), 5u);
  EXPECT_EQ(t[0].text, "1");
}

TEST(ColourScale, StacksKeepEveryPixel) {
  RgbImage a(2, 3, {1, 2, 3}), b(4, 1, {9, 9, 9});
  b.set(3, 0, {7, 7, 7});
  const RgbImage h = hstack(std::vector<RgbImage>{a, b}, 1, {0, 0, 0});
  EXPECT_EQ(h.width, 7);
  EXPECT_EQ(h.height, 3);
  EXPECT_EQ(h.at(1, 2), (Rgb8{1, 2, 3}));
  EXPECT_EQ(h.at(2, 0), (Rgb8{0, 0, 0}));
  EXPECT_EQ(h.at(6, 0), (Rgb8{7, 7, 7}));
  EXPECT_EQ(h.at(6, 1), (Rgb8{0, 0, 0}));
  const RgbImage v = vstack(std::vector<RgbImage>{a, b}, 0, {5, 5, 5});
  EXPECT_EQ(v.width, 4);
  EXPECT_EQ(v.height, 4);
  EXPECT_EQ(v.at(3, 3), (Rgb8{7, 7, 7}));
  EXPECT_EQ(v.at(3, 0), (Rgb8{5, 5, 5}));
}

}  // namespace
}  // namespace ptc::viz
