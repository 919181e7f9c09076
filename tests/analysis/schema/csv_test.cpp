#include <gtest/gtest.h>
#include <unistd.h>

#include <charconv>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "analysis/schema/csv.h"
#include "analysis/schema/manifest.h"
#include "toolkit/core/error.h"

namespace ptc {
namespace {
namespace fs = std::filesystem;


TEST(Csv, DoublesRoundTripBitExactly) {
  std::mt19937_64 rng(1);
  for (int i = 0; i < 10000; ++i) {
    std::uint64_t bits = rng();
    double x;
    std::memcpy(&x, &bits, sizeof x);
    if (!std::isfinite(x)) continue;
    const std::string s = format_double(x);
    double y = 0;
    std::from_chars(s.data(), s.data() + s.size(), y);
    ASSERT_EQ(std::memcmp(&x, &y, sizeof x), 0) << s;
  }
  EXPECT_EQ(format_double(std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(format_double(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(format_double(0.1), "0.1");
}

TEST(Csv, QuotesFieldsThatNeedIt) {
  CsvTable t({"name", "n", "x"});
  t.add_row({std::string("plain"), std::int64_t{-3}, 1.5});
  t.add_row({std::string("a,b \"q\"\nz"), std::uint64_t{7}, 2.0});
  EXPECT_EQ(t.str(), "name,n,x\nplain,-3,1.5\n\"a,b \"\"q\"\"\nz\",7,2\n");
  EXPECT_THROW(t.add_row({std::int64_t{1}}), std::invalid_argument);
}

}  // namespace
}  // namespace ptc
