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

#include "analysis/csv.h"
#include "analysis/manifest.h"
#include "analysis/output_dir.h"
#include "toolkit/core/error.h"

namespace ptc {
namespace {
namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

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

TEST(OutputDir, CommitReplacesAndFailureKeepsTheOld) {
  const fs::path base = fs::temp_directory_path() / ("ptc_outdir_" + std::to_string(::getpid()));
  fs::remove_all(base);
  const fs::path target = base / "nested" / "run";
  {
    OutputDir d(target);
    d.write("a.csv", "first\n");
    EXPECT_FALSE(fs::exists(target));  // nothing visible before commit
    d.commit();
  }
  EXPECT_EQ(slurp(target / "a.csv"), "first\n");
  {
    OutputDir d(target);
    d.write("a.csv", "second\n");
    // destroyed without commit: a failed run
  }
  EXPECT_EQ(slurp(target / "a.csv"), "first\n");
  {
    OutputDir d(target);
    d.write("b.csv", "third\n");
    d.commit();
  }
  EXPECT_FALSE(fs::exists(target / "a.csv"));  // the whole directory was replaced
  EXPECT_EQ(slurp(target / "b.csv"), "third\n");
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(base / "nested")) ++entries;
  EXPECT_EQ(entries, 1u);  // no temporaries left behind
  // A file where the directory should go is a clear error.
  std::ofstream(base / "file") << "x";
  EXPECT_THROW(OutputDir(base / "file"), InputError);
  fs::remove_all(base);
}

TEST(OutputDir, NeverReplacesADirectoryItDidNotWrite) {
  const fs::path base = fs::temp_directory_path() / ("ptc_outdir2_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base / "precious");
  std::ofstream(base / "precious" / "thesis.txt") << "years of work";
  try {
    OutputDir d(base / "precious");
    FAIL() << "a foreign directory was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("precious"), std::string::npos) << e.what();
  }
  EXPECT_EQ(slurp(base / "precious" / "thesis.txt"), "years of work");
  // An empty directory is fine, and so is a trailing separator.
  fs::create_directories(base / "empty");
  {
    OutputDir d(base / "empty/");
    d.write("x.csv", "1\n");
    d.commit();
    EXPECT_EQ(d.target(), base / "empty");
  }
  EXPECT_EQ(slurp(base / "empty" / "x.csv"), "1\n");
  EXPECT_TRUE(fs::exists(base / "empty" / OutputDir::kMarker));
  // ... and the marked directory can be replaced by the next run.
  {
    OutputDir d(base / "empty");
    d.write("y.csv", "2\n");
    d.commit();
  }
  EXPECT_FALSE(fs::exists(base / "empty" / "x.csv"));
  EXPECT_THROW(OutputDir(base / ".."), InputError);
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(base)) ++entries;
  EXPECT_EQ(entries, 2u);  // precious and empty, no temporaries
  fs::remove_all(base);
}

TEST(Manifest, HashIsFnv1aAndRecordsEverything) {
  const fs::path p = fs::temp_directory_path() / ("ptc_hash_" + std::to_string(::getpid()));
  std::ofstream(p, std::ios::binary) << "a";
  // FNV-1a 64 of "a" (published test vector).
  EXPECT_EQ(file_fnv1a64(p), "af63dc4c8601ec8c");
  std::ofstream(p, std::ios::binary | std::ios::trunc) << "";
  EXPECT_EQ(file_fnv1a64(p), "cbf29ce484222325");
  EXPECT_THROW((void)file_fnv1a64(p.string() + ".missing"), InputError);
  RunManifest m("test", {"ptc", "test"});
  m.add_input(p);
  m.set_parameter("k", 3);
  m.add_timing_ms("stage", 1.5);
  const auto j = m.to_json();
  EXPECT_EQ(j["parameters"]["k"], 3);
  EXPECT_EQ(j["timings_ms"]["stage"], 1.5);
  EXPECT_EQ(j["inputs"][0]["bytes"], 0);
  EXPECT_EQ(j["build"]["git_commit"].get<std::string>().size() >= 7 || j["build"]["git_commit"] == "unknown", true);
  fs::remove(p);
}

}  // namespace
}  // namespace ptc
