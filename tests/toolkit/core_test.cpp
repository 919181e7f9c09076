// toolkit/core: the one median / percentile / summary, the stopwatch, list splitting.
#include <gtest/gtest.h>

#include <cmath>
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

}  // namespace
}  // namespace ptc
