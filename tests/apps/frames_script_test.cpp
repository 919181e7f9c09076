// bench/frames/frames.py (the whole-frame table over the built-in scenes) as a user runs it: the
// table's medians and ratios recomputed here from the per-run rows and from every run's own
// summary.csv, and its usage errors.
#include <gtest/gtest.h>
#include <sched.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_harness.h"
#include "common/csv_rows.h"

namespace fs = std::filesystem;

namespace {

using ptc::test::csv_rows;
using ptc::test::lines;
using ptc::test::slurp;

class FramesScript : public ptc::test::CliTest {
 protected:
  ptc::test::RunResult frames(const std::vector<std::string>& args) const {
    const fs::path build = fs::path(PTC_BIN).parent_path().parent_path();
    std::vector<std::string> all{"--build", build.string()};
    all.insert(all.end(), args.begin(), args.end());
    return run({"/usr/bin/python3", std::string(PTC_SOURCE_DIR) + "/bench/frames/frames.py"}, all);
  }
  static double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  }
};

// The tables at one and two threads: ptc bench refuses more threads than the machine runs.
bool two_cores() {
  cpu_set_t set;
  return sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) >= 2;
}

TEST_F(FramesScript, TableIsTheMediansOfTheRunsAndTheirRatios) {
  if (!two_cores()) GTEST_SKIP() << "needs two cores (the table at one and two threads)";
  const fs::path out = dir_ / "out";
  const auto r = frames({"--threads", "1,2", "--frames", "0:3", "--width", "16", "--height", "12", "--repeat", "3", "--scenes",
                         "armadillo-twist,cloth-sphere-32", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto runs = csv_rows(slurp(out / "runs.csv"));
  const auto table = csv_rows(slurp(out / "frames.csv"));
  ASSERT_EQ(runs.size(), 3u * 2u * 2u * 3u);  // repeats x threads x scenes x configurations
  ASSERT_EQ(table.size(), 2u * 2u);
  // Every run row is its run's own summary.csv.
  for (const auto& row : runs) {
    const fs::path summary = out / "runs" / ("r" + row.at("repeat") + "_t" + row.at("threads") + "_" + row.at("scene")) /
                             "summary.csv";
    bool found = false;
    for (const auto& s : csv_rows(slurp(summary)))
      if (s.at("config") == row.at("config")) {
        found = true;
        EXPECT_DOUBLE_EQ(std::stod(s.at("whole_frame_ms")), std::stod(row.at("whole_frame_ms"))) << summary;
        EXPECT_DOUBLE_EQ(std::stod(s.at("update_build_ms")), std::stod(row.at("update_build_ms"))) << summary;
      }
    EXPECT_TRUE(found) << summary << " " << row.at("config");
  }
  for (const auto& t : table) {
    std::map<std::string, std::vector<double>> whole;  // config -> per repeat, in repeat order
    for (int rep = 0; rep < 3; ++rep)
      for (const auto& row : runs)
        if (row.at("threads") == t.at("threads") && row.at("scene") == t.at("scene") && row.at("repeat") == std::to_string(rep))
          whole[row.at("config")].push_back(std::stod(row.at("whole_frame_ms")));
    ASSERT_EQ(whole["ours_clusters"].size(), 3u);
    const double ours = median(whole["ours_clusters"]), refit = median(whole["embree_refit"]), low = median(whole["embree_low"]);
    const std::string what = t.at("scene") + " T=" + t.at("threads");
    EXPECT_NEAR(std::stod(t.at("ours_ms")), ours, 1e-9 * ours) << what;
    EXPECT_NEAR(std::stod(t.at("vs_refit")), refit / ours, 1e-9) << what;
    EXPECT_NEAR(std::stod(t.at("vs_low")), low / ours, 1e-9) << what;
    double lo = 1e300, hi = 0;
    for (int i = 0; i < 3; ++i) {
      const double q = whole["embree_refit"][i] / whole["ours_clusters"][i];
      lo = std::min(lo, q), hi = std::max(hi, q);
    }
    EXPECT_NEAR(std::stod(t.at("vs_refit_min")), lo, 1e-9) << what;
    EXPECT_NEAR(std::stod(t.at("vs_refit_max")), hi, 1e-9) << what;
    // The lowest single frame: from every run's bench.csv, Embree's whole frame / ours frame by
    // frame over the frames after the first (here frames 1-3 of 0:3: lower than the ratio of the
    // medians unless all three frames agree).
    double lowest_refit = 1e300, lowest_low = 1e300;
    for (int rep = 0; rep < 3; ++rep) {
      std::string run = "r";  // (one + chain with std::to_string's temporary set off GCC 12's -Wrestrict)
      run += std::to_string(rep);
      run += "_t" + t.at("threads") + "_" + t.at("scene");
      const fs::path bench = out / "runs" / run / "bench.csv";
      std::map<std::string, std::map<std::string, double>> at;  // frame -> config -> whole frame
      for (const auto& b : csv_rows(slurp(bench))) at[b.at("frame")][b.at("config")] = std::stod(b.at("whole_frame_ms"));
      for (const auto& [frame, c] : at) {
        if (frame == "0") continue;
        lowest_refit = std::min(lowest_refit, c.at("embree_refit") / c.at("ours_clusters"));
        lowest_low = std::min(lowest_low, c.at("embree_low") / c.at("ours_clusters"));
      }
    }
    EXPECT_NEAR(std::stod(t.at("vs_refit_lowest_frame")), lowest_refit, 1e-9 * lowest_refit) << what;
    EXPECT_NEAR(std::stod(t.at("vs_low_lowest_frame")), lowest_low, 1e-9 * lowest_low) << what;
    EXPECT_EQ(t.at("ours_mismatches"), "0") << what;
  }
  EXPECT_NE(r.out.find("| 2 | cloth-sphere-32 |"), std::string::npos) << r.out;

  // The stages of every run row: its bench.csv's medians over the frames after the first (here
  // frames 1-3 of 0:3).
  for (const auto& row : runs) {
    const fs::path bench = out / "runs" / ("r" + row.at("repeat") + "_t" + row.at("threads") + "_" + row.at("scene")) /
                           "bench.csv";
    for (const char* k : {"vertices_ms", "boxes_ms", "sah_build_ms", "collapse_ms", "leaf_data_ms", "overlap_ms"}) {
      std::vector<double> v;
      for (const auto& b : csv_rows(slurp(bench)))
        if (b.at("config") == row.at("config") && b.at("frame") != "0") v.push_back(std::stod(b.at(k)));
      ASSERT_EQ(v.size(), 3u) << bench;
      EXPECT_DOUBLE_EQ(std::stod(row.at(k)), median(v)) << bench << " " << k;
    }
  }
  // How each stage scales: per scene, configuration and stage, the medians over the repeats at
  // T=1 and T=2 and their ratio; the stages of our update for ours_clusters only.
  const auto scaling = csv_rows(slurp(out / "scaling.csv"));
  ASSERT_EQ(scaling.size(), 2u * (10u + 2u * 4u));  // scenes x (ours: 10 measures, Embree: 4 each)
  for (const auto& sc : scaling) {
    const std::string what = sc.at("scene") + " " + sc.at("config") + " " + sc.at("measure");
    EXPECT_EQ(sc.at("threads_base"), "1");
    EXPECT_EQ(sc.at("threads"), "2");
    std::map<std::string, std::vector<double>> at;  // threads -> per repeat
    for (const auto& row : runs)
      if (row.at("scene") == sc.at("scene") && row.at("config") == sc.at("config"))
        at[row.at("threads")].push_back(std::stod(row.at(sc.at("measure"))));
    ASSERT_EQ(at["1"].size(), 3u) << what;
    const double base = median(at["1"]), now = median(at["2"]);
    EXPECT_NEAR(std::stod(sc.at("base_ms")), base, 1e-9 * std::max(1.0, base)) << what;
    EXPECT_NEAR(std::stod(sc.at("ms")), now, 1e-9 * std::max(1.0, now)) << what;
    if (sc.at("measure") == "overlap_ms" || now == 0 || base == 0) {
      EXPECT_EQ(sc.at("speedup"), "nan") << what;  // (time two stages shared, or a stage on one side only)
    } else {
      EXPECT_NEAR(std::stod(sc.at("speedup")), base / now, 1e-9 * std::max(1.0, base / now)) << what;
    }
  }
  EXPECT_NE(r.out.find("how each stage scales"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(out / "manifest.json"));
  EXPECT_FALSE(fs::exists(dir_ / "out.tmp"));

  // Usage errors: one line, exit 2, nothing written; an existing output is never touched.
  const auto again = frames({"--scenes", "armadillo-twist", "--out", out.string()});
  EXPECT_EQ(again.code, 2);
  EXPECT_EQ(lines(again.err), 1u) << again.err;
  EXPECT_TRUE(fs::exists(out / "runs.csv"));
  for (const std::vector<std::string>& bad : {std::vector<std::string>{"--threads", "0"}, {"--threads", "a,b"},
                                              {"--threads", "1,4096"},
                                              {"--repeat", "0"}, {"--scenes", "no-such-scene"}, {"--max-count", "-1"},
                                              {"--max-count", "x"}}) {
    std::vector<std::string> args = bad;
    args.insert(args.end(), {"--out", (dir_ / "new").string()});
    const auto e = frames(args);
    EXPECT_EQ(e.code, 2) << bad[0] << ": " << e.err;
    EXPECT_EQ(lines(e.err), 1u) << e.err;
    EXPECT_FALSE(fs::exists(dir_ / "new"));
  }
}

// --max-count N,M,... reaches every ptc bench run: each value its own runs (each run's manifest
// records it, and the clusters' count follows it), runs.csv and frames.csv rows and the script's
// own manifest; without it the bench's own choice is used (the scene's, else 32), and the table
// says which.
TEST_F(FramesScript, MaxCountReachesEveryRun) {
  if (!two_cores()) GTEST_SKIP() << "needs two cores (a sweep at one and two threads)";
  const auto args = [&](const fs::path& out, const char* threads = "1") {
    return std::vector<std::string>{"--threads", threads, "--frames", "0:1", "--width", "8", "--height", "8", "--scenes",
                                    "armadillo-twist", "--out", out.string()};
  };
  std::map<std::string, std::size_t> clusters;  // value -> ours_clusters' cluster count
  {
    const fs::path out = dir_ / "sweep";
    auto a = args(out, "1,2");
    a.insert(a.end(), {"--max-count", "4,50"});
    const auto r = frames(a);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto m = nlohmann::json::parse(slurp(out / "manifest.json"));
    EXPECT_EQ(m["schema"], "ptc-frames/2");
    EXPECT_EQ(m["parameters"]["max_count"], nlohmann::json::array({4, 50}));
    for (const char* t : {"1", "2"})
      for (const char* mc : {"4", "50"}) {
        const auto run = nlohmann::json::parse(
            slurp(out / "runs" / (std::string("r0_t") + t + "_armadillo-twist_m" + mc) / "manifest.json"));
        EXPECT_EQ(run["parameters"]["max_count"], std::stoi(mc));
        EXPECT_EQ(run["parameters"]["max_count_from"], "--max-count");
        EXPECT_EQ(run["parameters"]["threads"], std::stoi(t));
        clusters[mc] = run["results"]["clusters"].get<std::size_t>();
      }
    const auto runs = csv_rows(slurp(out / "runs.csv"));
    ASSERT_EQ(runs.size(), 2u * 2u * 3u);  // threads x values x configurations
    for (const auto& row : runs) {
      EXPECT_EQ(row.at("sweep"), row.at("max_count"));
      EXPECT_EQ(row.at("max_count_from"), "--max-count");
    }
    const auto table = csv_rows(slurp(out / "frames.csv"));
    ASSERT_EQ(table.size(), 4u);  // threads x values
    // Each table row is its own thread count's and value's run (one repeat: the run's summary).
    std::set<std::string> seen;
    for (const auto& t : table) {
      seen.insert(t.at("threads") + "/" + t.at("max_count"));
      std::size_t matched = 0;
      for (const auto& row : runs)
        if (row.at("threads") == t.at("threads") && row.at("max_count") == t.at("max_count") &&
            row.at("config") == "ours_clusters") {
          ++matched;
          EXPECT_DOUBLE_EQ(std::stod(t.at("ours_ms")), std::stod(row.at("whole_frame_ms")));
        }
      EXPECT_EQ(matched, 1u);
    }
    EXPECT_EQ(seen, (std::set<std::string>{"1/4", "1/50", "2/4", "2/50"}));
    EXPECT_NE(r.out.find("| 1 | armadillo-twist | 4 |"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("| 2 | armadillo-twist | 50 |"), std::string::npos) << r.out;
    // How each stage scales, per value: T=1 against T=2 of that value's runs.
    const auto scaling = csv_rows(slurp(out / "scaling.csv"));
    ASSERT_EQ(scaling.size(), 2u * (10u + 2u * 4u));  // values x (ours: 10 measures, Embree: 4 each)
    for (const auto& sc : scaling) {
      EXPECT_EQ(sc.at("sweep"), sc.at("max_count"));
      std::map<std::string, double> at;  // threads -> the run's value
      for (const auto& row : runs)
        if (row.at("max_count") == sc.at("max_count") && row.at("config") == sc.at("config"))
          at[row.at("threads")] = std::stod(row.at(sc.at("measure")));
      ASSERT_EQ(at.size(), 2u);
      EXPECT_NEAR(std::stod(sc.at("base_ms")), at["1"], 1e-9 * std::max(1.0, at["1"])) << sc.at("measure");
      EXPECT_NEAR(std::stod(sc.at("ms")), at["2"], 1e-9 * std::max(1.0, at["2"])) << sc.at("measure");
    }
    EXPECT_NE(r.out.find("| 2 | armadillo-twist (MaxCount 50) | ours_clusters |"), std::string::npos) << r.out;
  }
  {
    const fs::path out = dir_ / "default";
    const auto r = frames(args(out));
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(nlohmann::json::parse(slurp(out / "manifest.json"))["parameters"]["max_count"].is_null());
    const auto run = nlohmann::json::parse(slurp(out / "runs" / "r0_t1_armadillo-twist" / "manifest.json"));
    EXPECT_EQ(run["parameters"]["max_count"], 32);  // the bench's default (the scene has none)
    EXPECT_EQ(run["parameters"]["max_count_from"], "default");
    EXPECT_EQ(csv_rows(slurp(out / "frames.csv")).at(0).at("max_count_from"), "default");
    EXPECT_NE(r.out.find("| 1 | armadillo-twist | 32 (default) |"), std::string::npos) << r.out;
    clusters[""] = run["results"]["clusters"].get<std::size_t>();
  }
  EXPECT_GT(clusters["4"], clusters[""]);  // smaller clusters, more of them
  EXPECT_GT(clusters[""], clusters["50"]);
  for (const char* bad : {"4,4", "4,", "4,-1"}) {
    const auto e = frames({"--max-count", bad, "--out", (dir_ / "bad").string()});
    EXPECT_EQ(e.code, 2) << bad << ": " << e.err;
    EXPECT_EQ(lines(e.err), 1u) << e.err;
    EXPECT_FALSE(fs::exists(dir_ / "bad"));
  }
}

// --frames all: no --frames for ptc bench, so each scene's whole animation (the run's manifest
// records the scene's own range), and the table's medians over all of it.
TEST_F(FramesScript, AllFramesRunTheWholeAnimation) {
  const fs::path out = dir_ / "all";
  const auto r = frames({"--threads", "1", "--frames", "all", "--width", "8", "--height", "8", "--scenes",
                         "cloth-sphere-32", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("--frames"), std::string::npos) << r.err;  // (the commands are echoed on stderr)
  const auto run = nlohmann::json::parse(slurp(out / "runs" / "r0_t1_cloth-sphere-32" / "manifest.json"));
  EXPECT_EQ(run["parameters"]["frames"], nlohmann::json::array({0, 119})) << run["parameters"].dump();
  const auto bench = csv_rows(slurp(out / "runs" / "r0_t1_cloth-sphere-32" / "bench.csv"));
  EXPECT_EQ(bench.size(), 120u * 5u);  // frames x configurations
  EXPECT_EQ(csv_rows(slurp(out / "frames.csv")).size(), 1u);
}

}  // namespace
