// toolkit/core: the one median / percentile / summary, the stopwatch, list splitting.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <thread>

#include "toolkit/core/stats.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/core/strings.h"

namespace ptc {
namespace {

TEST(Stats, MedianAndPercentilesInterpolateBetweenOrderStatistics) {
  EXPECT_EQ(median({}), 0.0);
  EXPECT_EQ(median({3}), 3.0);
  EXPECT_EQ(median({4, 1, 3}), 3.0);
  EXPECT_EQ(median({4, 1, 3, 10}), 3.5);
  EXPECT_EQ(percentile({}, 0.5), 0.0);
  // Type 7: p (n - 1) = 0.25 * 4 = 1 -> the second smallest; 0.1 * 4 = 0.4 -> 1 + 0.4 (2 - 1).
  const std::vector<double> v{5, 1, 4, 2, 3};
  EXPECT_EQ(percentile(v, 0.25), 2.0);
  EXPECT_DOUBLE_EQ(percentile(v, 0.1), 1.4);
  EXPECT_EQ(percentile(v, 0.0), 1.0);
  EXPECT_EQ(percentile(v, 1.0), 5.0);
  const Summary s = summarize(v);
  EXPECT_EQ(s.count, 5u);
  EXPECT_EQ(s.p50, median(v));
  EXPECT_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.p5, percentile(v, 0.05));
  EXPECT_DOUBLE_EQ(s.p95, percentile(v, 0.95));
}

TEST(Stats, InfinitiesAndHugeValuesKeepTheirOrderStatistics) {
  // Areas of a mesh of 1e160 units overflow to inf: the median of equal infinities is inf, not
  // the NaN of inf - inf; values near DBL_MAX do not overflow on the way.
  const double inf = std::numeric_limits<double>::infinity(), big = std::numeric_limits<double>::max();
  EXPECT_EQ(median({inf, inf}), inf);
  EXPECT_EQ(median({-inf, -inf, 1.0}), -inf);
  EXPECT_EQ(percentile({inf, inf, inf}, 0.3), inf);
  EXPECT_EQ(percentile({1.0, inf}, 0.5), inf);
  EXPECT_EQ(percentile({-inf, 1.0}, 0.5), -inf);
  EXPECT_EQ(median({big, big}), big);
  EXPECT_EQ(median({big, big / 2}), 0.75 * big);
  EXPECT_EQ(median({-big, big}), 0.0);
  EXPECT_EQ(percentile({-big, big}, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(percentile({-big, big}, 0.25), -0.5 * big);
  const Summary s = summarize(std::vector<double>{inf, inf});
  EXPECT_EQ(s.p5, inf);
  EXPECT_EQ(s.p50, inf);
  EXPECT_EQ(s.p95, inf);
}

TEST(Stats, RanksAndCorrelations) {
  EXPECT_EQ(fractional_ranks(std::vector<double>{10, 30, 20, 30}), (std::vector<double>{1, 3.5, 2, 3.5}));
  const std::vector<double> x{1, 2, 3, 4, 5}, y{5, 6, 7, 8, 7};
  // By hand: ranks of y = 1, 2, 3.5, 5, 3.5; sum dx dy = 8, sum dx^2 = 10, sum dy^2 = 9.5.
  EXPECT_NEAR(spearman(x, y), 8.0 / std::sqrt(95.0), 1e-15);
  EXPECT_NEAR(pearson(x, std::vector<double>{2, 4, 6, 8, 10}), 1.0, 1e-15);
  const std::vector<double> cubes{1, 8, 27, 64, 125}, down{9, 7, 5, 3, 1};
  EXPECT_EQ(spearman(x, cubes), 1.0);  // monotone, not linear
  EXPECT_LT(pearson(x, cubes), 1.0);
  EXPECT_EQ(spearman(x, down), -1.0);
  EXPECT_TRUE(std::isnan(spearman(x, std::vector<double>{3, 3, 3, 3, 3})));
  EXPECT_TRUE(std::isnan(spearman(std::vector<double>{1}, std::vector<double>{2})));
  EXPECT_THROW((void)spearman(x, std::vector<double>{1, 2}), std::invalid_argument);
}

TEST(Stopwatch, MeasuresAndLaps) {
  Stopwatch sw;
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const double a = sw.lap_ms();
  EXPECT_GE(a, 4.0);
  EXPECT_LT(sw.ms(), a + 1000.0);
  sw.restart();
  EXPECT_LT(sw.ms(), 1000.0);
}

TEST(Strings, SplitListDropsEmptyItems) {
  EXPECT_EQ(split_list(""), std::vector<std::string>{});
  EXPECT_EQ(split_list("acc"), std::vector<std::string>{"acc"});
  EXPECT_EQ(split_list("acc,,meshopt,"), (std::vector<std::string>{"acc", "meshopt"}));
  EXPECT_EQ(split_list(",a, b"), (std::vector<std::string>{"a", " b"}));
  EXPECT_EQ(split_list("1:2", ':'), (std::vector<std::string>{"1", "2"}));
}

TEST(Strings, CountedNounsTakeTheirNumber) {
  EXPECT_EQ(counted(1, "triangle"), "1 triangle");
  EXPECT_EQ(counted(0, "triangle"), "0 triangles");
  EXPECT_EQ(counted(2, "cluster"), "2 clusters");
  EXPECT_EQ(counted(1, "vertex", "vertices"), "1 vertex");
  EXPECT_EQ(counted(3, "vertex", "vertices"), "3 vertices");
  EXPECT_EQ(counted(18446744073709551615ull, "later frame"), "18446744073709551615 later frames");
}

}  // namespace
}  // namespace ptc
