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

TEST(Csv, ReadsBackWhatItWritesCellByCell) {
  CsvTable t({"name", "n", "x", "empty"});
  t.add_row({std::string("a,b \"q\"\nz"), std::int64_t{-3}, 0.1, std::string()});
  t.add_row({std::string(""), std::uint64_t{18446744073709551615ull}, std::numeric_limits<double>::quiet_NaN(),
             std::string("\r\n")});
  const CsvText r = parse_csv(t.str());
  ASSERT_EQ(r.header, (std::vector<std::string>{"name", "n", "x", "empty"}));
  ASSERT_EQ(r.rows.size(), 2u);
  EXPECT_EQ(r.rows[0][0], "a,b \"q\"\nz");
  EXPECT_EQ(r.rows[0][1], "-3");
  EXPECT_EQ(r.number(0, r.column("x")), 0.1);
  EXPECT_EQ(r.rows[0][3], "");
  EXPECT_EQ(r.rows[1][1], "18446744073709551615");
  EXPECT_TRUE(std::isnan(r.number(1, 2)));
  EXPECT_EQ(r.rows[1][3], "\r\n");
  EXPECT_EQ(r.str(), t.str());  // written back unchanged
  EXPECT_THROW((void)r.column("nope"), std::invalid_argument);
  EXPECT_TRUE(r.has_column("x"));
  EXPECT_FALSE(r.has_column("X"));
}

TEST(Csv, ReadingRefusesBrokenTextNamingTheLine) {
  EXPECT_TRUE(parse_csv("").header.empty());
  EXPECT_EQ(parse_csv("a,b").header, (std::vector<std::string>{"a", "b"}));  // no final line end
  EXPECT_EQ(parse_csv("a,b\r\n1,2\r\n").rows, (std::vector<std::vector<std::string>>{{"1", "2"}}));
  try {
    (void)parse_csv("a,b\n1,2\n3\n");
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  try {
    (void)parse_csv("a,b\n1,\"2\n");
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
  }
  const CsvText bad = parse_csv("x\n1.5x\n");
  try {
    (void)bad.number(0, 0);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("row 1, column 'x'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ptc
