// Every input a fuzz target once failed on (tests/fuzz_inputs/TARGET/NAME, one file per finding,
// named after what it found) replayed through the same code the fuzz target runs (fuzz/targets.h):
// a result or an InputError, nothing else; under ./run.sh's sanitizer build without any report.
// Also the seeds ptc writes for the fuzzers (make_fuzz_seeds), which must all load: a seed that
// is refused would fuzz the error path only.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "fuzz/seeds.h"
#include "fuzz/targets.h"

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(FuzzInputs, EveryRegressionInputGivesAResultOrAnInputError) {
  const fs::path root = fs::path(PTC_SOURCE_DIR) / "tests" / "fuzz_inputs";
  ASSERT_TRUE(fs::is_directory(root)) << root;
  std::size_t replayed = 0;
  for (const auto& dir : fs::directory_iterator(root)) {
    if (!dir.is_directory()) continue;
    const std::string target = dir.path().filename().string();
    ASSERT_NE(std::find(ptc::fuzz::target_names().begin(), ptc::fuzz::target_names().end(), target),
              ptc::fuzz::target_names().end())
        << "tests/fuzz_inputs/" << target << " is not a fuzz target";
    for (const auto& f : fs::directory_iterator(dir.path())) {
      SCOPED_TRACE(f.path().string());
      EXPECT_NO_THROW(ptc::fuzz::run_target(target, slurp(f.path())));
      ++replayed;
    }
  }
  std::cout << "  " << replayed << " regression inputs replayed\n";
}

TEST(FuzzInputs, EveryGeneratedSeedLoads) {
  std::set<std::string> seeded;
  for (const ptc::fuzz::Seed& s : ptc::fuzz::generated_seeds()) {
    SCOPED_TRACE(s.target + "/" + s.name);
    EXPECT_NO_THROW(ptc::fuzz::run_target(s.target, s.bytes, /*input_errors=*/false));
    seeded.insert(s.target);
  }
  for (const std::string& t : ptc::fuzz::target_names()) EXPECT_TRUE(seeded.count(t)) << t << " has no seed";
}

TEST(FuzzInputs, UnknownTargetIsRefused) {
  EXPECT_THROW(ptc::fuzz::run_target("png", ""), std::invalid_argument);
}

}  // namespace
