// Golden runs: every `ptc` subcommand on small inputs, compared with outputs recorded from the
// code before the redesign of issue 11 (tests/golden/<case>/). What is deterministic must stay
// byte for byte the same: PLY/OFF meshes and PNG images by their bytes, CSV files cell by cell
// in every recorded column except timings (a column is matched by its name, so new columns and
// a new column order do not fail a run; a recorded column that disappears does), JSON on stdout
// after the machine's paths are replaced by placeholders.
//
// Recording: PTC_GOLDEN_RECORD=1 ctest -R Golden (or the test binary) rewrites tests/golden/ from
// the current code. A change of a golden file is a change of behaviour: say why in the commit.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_harness.h"
#include "common/csv_rows.h"

namespace fs = std::filesystem;

namespace {

using ptc::test::csv_table;
using ptc::test::run_dependent_column;
using ptc::test::slurp;

const fs::path kGolden = fs::path(PTC_SOURCE_DIR) / "tests" / "golden";
const std::string kData = std::string(PTC_TEST_DATA) + "/meshes";

bool recording() {
  const char* e = std::getenv("PTC_GOLDEN_RECORD");
  return e && std::string(e) == "1";
}

// Every non-timing column of `want` must exist in `got` with the same value, row by row.
void expect_same_csv(const std::string& name, const std::string& want_text, const std::string& got_text) {
  const auto want = csv_table(want_text), got = csv_table(got_text);
  ASSERT_FALSE(want.empty()) << name;
  ASSERT_FALSE(got.empty()) << name << ": empty";
  ASSERT_EQ(got.size(), want.size()) << name << ": row count";
  std::map<std::string, std::size_t> col;
  for (std::size_t c = 0; c < got[0].size(); ++c) col[got[0][c]] = c;
  int reported = 0;
  for (std::size_t c = 0; c < want[0].size(); ++c) {
    const std::string& cn = want[0][c];
    if (run_dependent_column(cn)) continue;
    ASSERT_TRUE(col.count(cn)) << name << ": column '" << cn << "' is gone";
    const std::size_t gc = col[cn];
    for (std::size_t r = 1; r < want.size(); ++r) {
      const std::string w = c < want[r].size() ? want[r][c] : "", g = gc < got[r].size() ? got[r][gc] : "";
      if (w != g && reported++ < 10)
        ADD_FAILURE() << name << ": row " << r << " column '" << cn << "': want '" << w << "', got '" << g << "'";
    }
  }
}

struct Case {
  std::string name;
  std::vector<std::vector<std::string>> commands;  // {out} = the case's temporary directory, {data} = meshes
  std::vector<std::string> files;                   // relative to {out}; "stdout" = the last command's stdout
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

std::string expand(std::string s, const std::string& out) {
  for (auto [key, val] : {std::pair<std::string, std::string>{"{out}", out}, {"{data}", kData}})
    for (std::size_t p; (p = s.find(key)) != std::string::npos;) s.replace(p, key.size(), val);
  return s;
}

// The machine's paths in text output, replaced by placeholders.
std::string normalise(std::string s, const std::string& out) {
  for (auto [key, val] : {std::pair<std::string, std::string>{out, "{out}"}, {kData, "{data}"}})
    for (std::size_t p; (p = s.find(key)) != std::string::npos;) s.replace(p, key.size(), val);
  return s;
}

const char* const kScene = R"({"schema": "ptc-scene/1", "frames": [0, 5],
  "meshes": [{"name": "ball", "file": "{data}/sphere.off",
              "deform": {"kind": "twist", "axis": "y", "amplitude": 1.0, "period": 12}}]})";

std::vector<Case> cases() {
  const std::vector<std::string> pngs{"shaded", "depth", "normal", "cost_nodes", "cost_triangles"};
  auto images = [&](const std::string& dir, const std::string& suffix, bool ao) {
    std::vector<std::string> f;
    for (const auto& p : pngs) f.push_back(dir + "/" + p + suffix + ".png");
    if (ao) f.push_back(dir + "/ao" + suffix + ".png");
    return f;
  };
  std::vector<Case> c;
  c.push_back({"info_json", {{"info", "{data}/elephant.off", "--json"}}, {"stdout"}});
  c.push_back({"subdivide_midpoint", {{"subdivide", "{data}/cross.off", "--levels", "2", "--out", "{out}/m.ply"}}, {"m.ply"}});
  c.push_back({"subdivide_loop",
               {{"subdivide", "{data}/cross.off", "--levels", "2", "--scheme", "loop", "--out", "{out}/m.off"}},
               {"m.off"}});
  c.push_back({"spheres", {{"spheres", "{data}/elephant.off", "--repeats", "1", "--out", "{out}/s"}},
               {"s/spheres.csv", "s/sphere_sets.csv"}});
  const std::vector<std::string> cluster_files{"c/triangles.csv", "c/clusters.csv"};
  c.push_back({"cluster_growth_acc",
               {{"cluster", "{data}/elephant.off", "--method", "growth", "--objective", "acc", "--max-count", "50",
                 "--max-size", "50", "--out", "{out}/c"}},
               {"c/triangles.csv", "c/clusters.csv", "c/clusters.ply"}});
  c.push_back({"cluster_contraction_acc",
               {{"cluster", "{data}/mushroom.off", "--method", "contraction", "--max-count", "30", "--max-size", "30",
                 "--out", "{out}/c"}},
               cluster_files});
  c.push_back({"cluster_growth_naive",
               {{"cluster", "{data}/mushroom.off", "--method", "growth", "--objective", "naive", "--max-count", "40",
                 "--out", "{out}/c"}},
               cluster_files});
  c.push_back({"cluster_contraction_gwh01",
               {{"cluster", "{data}/mushroom.off", "--method", "contraction", "--objective", "gwh01", "--max-count",
                 "40", "--out", "{out}/c"}},
               cluster_files});
  c.push_back({"cluster_sah_split",
               {{"cluster", "{data}/mushroom.off", "--method", "sah-split", "--max-count", "40", "--out", "{out}/c"}},
               cluster_files});
  c.push_back({"cluster_meshopt",
               {{"cluster", "{data}/mushroom.off", "--method", "meshopt", "--max-count", "40", "--out", "{out}/c"}},
               cluster_files});
  {
    Case t{"trace_triangles",
           {{"trace", "{data}/elephant.off", "--width", "40", "--height", "30", "--shadows", "--out", "{out}/t"}},
           images("t", "", false)};
    t.files.push_back("t/trace.csv");
    t.files.push_back("t/cost_legend.png");
    c.push_back(t);
  }
  {
    Case t{"trace_clusters_ao",
           {{"cluster", "{data}/elephant.off", "--method", "growth", "--max-count", "50", "--max-size", "50", "--out",
             "{out}/c"},
            {"trace", "{data}/elephant.off", "--clusters", "{out}/c", "--width", "48", "--height", "32", "--shadows",
             "--ao", "2", "--eye", "0.1,0.1,0.9", "--out", "{out}/t"}},
           images("t", "", true)};
    t.files.push_back("t/trace.csv");
    c.push_back(t);
  }
  {
    Case t{"trace_scene_frames",
           {{"write-scene"},
            {"cluster", "{data}/sphere.off", "--method", "growth", "--max-count", "12", "--max-size", "12", "--out",
             "{out}/c"},
            {"trace", "{out}/scene.json", "--clusters", "{out}/c", "--frames", "1:3", "--width", "32", "--height",
             "24", "--shadows", "--out", "{out}/t"}},
           {}};
    for (const char* s : {"_0001", "_0002", "_0003"})
      for (const auto& f : images("t", s, false)) t.files.push_back(f);
    t.files.push_back("t/trace.csv");
    c.push_back(t);
  }
  c.push_back({"animate_stats",
               {{"write-scene"}, {"animate", "{out}/scene.json", "--frames", "0:2", "--stats", "--out", "{out}/a"}},
               {"a/frame_0000.ply", "a/frame_0001.ply", "a/frame_0002.ply", "a/stats.csv"}});
  c.push_back({"animate_obj",
               {{"write-scene"}, {"animate", "{out}/scene.json", "--frames", "4:4", "--format", "obj", "--out", "{out}/a"}},
               {"a/frame_0004.obj"}});
  c.push_back({"bench_mesh",
               {{"bench", "{data}/elephant.off", "--frames", "0:2", "--width", "48", "--height", "48", "--out", "{out}/b"}},
               {"b/bench.csv", "b/summary.csv"}});
  c.push_back({"bench_scene",
               {{"write-scene"},
                {"bench", "{out}/scene.json", "--frames", "0:2", "--width", "32", "--height", "32", "--out", "{out}/b"}},
               {"b/bench.csv", "b/summary.csv"}});
  c.push_back({"scenes_json", {{"scenes", "armadillo-twist", "cloth-sphere-32", "--json"}}, {"stdout"}});
  return c;
}

class Golden : public ptc::test::CliTest, public ::testing::WithParamInterface<Case> {};

TEST_P(Golden, SameOutputsAsRecorded) {
  const Case& k = GetParam();
  const std::string out = dir_.string();
  std::string last_stdout;
  for (const auto& cmd : k.commands) {
    if (cmd.size() == 1 && cmd[0] == "write-scene") {
      std::ofstream(dir_ / "scene.json") << expand(kScene, out);
      continue;
    }
    std::vector<std::string> args;
    for (const auto& a : cmd) args.push_back(expand(a, out));
    const auto r = ptc(args);
    ASSERT_EQ(r.code, 0) << args[0] << ": " << r.err;
    last_stdout = r.out;
  }
  const fs::path gdir = kGolden / k.name;
  if (recording()) fs::create_directories(gdir);
  for (const auto& f : k.files) {
    const bool is_stdout = f == "stdout";
    const bool text = is_stdout || fs::path(f).extension() == ".csv";
    const std::string got = is_stdout ? normalise(last_stdout, out)
                            : text    ? normalise(slurp(dir_ / f), out)
                                      : slurp(dir_ / f);
    const fs::path gfile = gdir / (is_stdout ? "stdout.json" : fs::path(f).filename().string());
    if (!is_stdout) {
      ASSERT_TRUE(fs::exists(dir_ / f)) << f << " was not written";
    }
    if (recording()) {
      std::ofstream(gfile, std::ios::binary) << got;
      continue;
    }
    ASSERT_TRUE(fs::exists(gfile)) << gfile << " is missing (record with PTC_GOLDEN_RECORD=1)";
    const std::string want = slurp(gfile);
    if (is_stdout) {
      // What depends on the machine: its memory and what fits into it, its cores and the
      // estimates with regions that follow from them (ptc info).
      auto machine_free = [](nlohmann::json j) {
        if (j.contains("memory_estimate")) {
          nlohmann::json& e = j["memory_estimate"];
          e.erase("machine_memory_mb");
          e.erase("largest_triangles_for_machine");
          e.erase("threads");
          if (e.contains("peak_mb"))
            for (const char* k : {"cluster_growth_regions_8", "cluster_growth_regions_32", "cluster_contraction_regions_8",
                                  "cluster_contraction_regions_32"})
              e["peak_mb"].erase(k);
        }
        return j;
      };
      EXPECT_EQ(machine_free(nlohmann::json::parse(got)), machine_free(nlohmann::json::parse(want))) << f;
    } else if (fs::path(f).extension() == ".csv") {
      expect_same_csv(k.name + "/" + f, want, got);
    } else {
      EXPECT_TRUE(got == want) << k.name << "/" << f << ": bytes differ (" << got.size() << " vs " << want.size()
                               << " recorded)";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Runs, Golden, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& i) { return i.param.name; });

}  // namespace
