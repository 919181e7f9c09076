// `ptc trace` at --threads 1, 2 and 4 as a user runs it (issue 15): every image byte for byte, and
// every column of trace.csv that is not a time or the thread count (rays, hits, nodes and
// triangles visited per pass and frame), for the triangle BVH and a cluster BVH, with shadow and
// AO rays, over three frames of an animated scene.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>

#include "cli_harness.h"
#include "common/csv_rows.h"

namespace fs = std::filesystem;

namespace {

using ptc::test::RunResult;
using ptc::test::slurp;

class Determinism : public ptc::test::CliTest {};

TEST_F(Determinism, TraceImagesAndCountersAreIdenticalAt1_2And4Threads) {
  const std::string data = PTC_TEST_DATA;
  const fs::path clusters = dir_ / "clusters";
  ASSERT_EQ(ptc({"cluster", data + "/meshes/armadillo.off", "--out", clusters.string()}).code, 0);
  for (const bool with_clusters : {false, true}) {
    std::map<std::string, std::string> first_files;
    std::vector<std::map<std::string, std::string>> first_rows;
    for (const char* threads : {"1", "2", "4"}) {
      SCOPED_TRACE(std::string(with_clusters ? "cluster BVH, " : "triangle BVH, ") + threads + " threads");
      const fs::path out = dir_ / (std::string("t") + threads + (with_clusters ? "c" : ""));
      std::vector<std::string> args{"trace", "armadillo-twist", "--data-dir", data, "--frames", "0:2", "--width", "160",
                                    "--height", "128", "--shadows", "--ao", "2", "--threads", threads,
                                    "--out", out.string()};
      if (with_clusters) args.insert(args.end(), {"--clusters", clusters.string()});
      const RunResult r = ptc(args);
      ASSERT_EQ(r.code, 0) << r.err;
      std::map<std::string, std::string> files;
      for (const auto& e : fs::directory_iterator(out))
        if (e.path().extension() == ".png") files[e.path().filename().string()] = slurp(e.path());
      auto rows = ptc::test::csv_rows(slurp(out / "trace.csv"));
      for (auto& row : rows)
        for (auto it = row.begin(); it != row.end();) it = ptc::test::run_dependent_column(it->first) ? row.erase(it) : std::next(it);
      if (first_files.empty()) {
        ASSERT_GE(files.size(), 15u);  // 5 kinds x 3 frames, and the legend
        ASSERT_EQ(rows.size(), 9u);    // primary, shadow, ao per frame
        first_files = files;
        first_rows = rows;
        continue;
      }
      for (const auto& [name, bytes] : first_files) EXPECT_TRUE(files[name] == bytes) << name << " differs";
      ASSERT_EQ(rows.size(), first_rows.size());
      for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(rows[i], first_rows[i]) << "trace.csv row " << i;
    }
  }
}

}  // namespace

// `ptc cluster --regions 8` (growth in regions, the parallel mode) at --threads 1, 2 and 4: the
// same triangles.csv and clusters.csv byte for byte, and the manifest records the regions.
TEST_F(Determinism, ClusterRegionsAreIdenticalAt1_2And4Threads) {
  const std::string mesh = std::string(PTC_TEST_DATA) + "/meshes/armadillo.off";
  {  // contraction in regions
    std::string first;
    for (const char* threads : {"1", "2", "4"}) {
      const fs::path out = dir_ / (std::string("k") + threads);
      const RunResult r = ptc({"cluster", mesh, "--method", "contraction", "--regions", "8", "--threads", threads,
                               "--out", out.string()});
      ASSERT_EQ(r.code, 0) << r.err;
      const std::string tri = slurp(out / "triangles.csv");
      if (first.empty()) first = tri;
      else EXPECT_EQ(tri, first) << "contraction, " << threads << " threads";
    }
  }
  std::string first_triangles, first_clusters;
  for (const char* threads : {"1", "2", "4"}) {
    SCOPED_TRACE(std::string(threads) + " threads");
    const fs::path out = dir_ / (std::string("r") + threads);
    const RunResult r = ptc({"cluster", mesh, "--method", "growth", "--regions", "8", "--threads", threads, "--out",
                             out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string tri = slurp(out / "triangles.csv"), cl = slurp(out / "clusters.csv");
    if (first_triangles.empty()) {
      first_triangles = tri, first_clusters = cl;
      EXPECT_NE(slurp(out / "manifest.json").find("\"regions\": 8"), std::string::npos);
    } else {
      EXPECT_EQ(tri, first_triangles);
      EXPECT_EQ(cl, first_clusters);
    }
  }
  // Not the one-run clusters: they stop at region borders.
  const fs::path seq = dir_ / "seq";
  ASSERT_EQ(ptc({"cluster", mesh, "--method", "growth", "--out", seq.string()}).code, 0);
  EXPECT_NE(slurp(seq / "triangles.csv"), first_triangles);
}
