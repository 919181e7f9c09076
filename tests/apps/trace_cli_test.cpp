// `ptc trace` and `ptc bench` as a user runs them: outputs, exit codes and one-line errors.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

struct CmdResult {
  int code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::size_t lines(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

// A closed cube, and a second closed mesh with the same number of triangles but another topology.
const char* kCube =
    "OFF\n8 12 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
    "3 0 2 1\n3 1 2 3\n3 4 5 6\n3 5 7 6\n3 0 1 4\n3 1 5 4\n3 2 6 3\n3 3 6 7\n3 0 4 2\n3 2 4 6\n3 1 3 5\n3 3 7 5\n";

class TraceCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("ptc_trace_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cube_ = dir_ / "cube.off";
    std::ofstream(cube_) << kCube;
  }
  void TearDown() override { fs::remove_all(dir_); }

  CmdResult ptc(const std::vector<std::string>& args) const {
    std::string cmd = quote(PTC_BIN);
    for (const auto& a : args) cmd.append(" ").append(quote(a));
    const fs::path o = dir_ / "stdout.txt", e = dir_ / "stderr.txt";
    cmd.append(" >").append(quote(o.string())).append(" 2>").append(quote(e.string()));
    const int status = std::system(cmd.c_str());
    CmdResult r;
    if (WIFEXITED(status)) r.code = WEXITSTATUS(status);
    if (WIFSIGNALED(status)) r.code = -WTERMSIG(status);
    r.out = slurp(o);
    r.err = slurp(e);
    return r;
  }
  // An error: the given exit code, exactly one line on stderr containing `needle`, no output dir.
  void expect_error(const std::vector<std::string>& args, int code, const std::string& needle) const {
    const CmdResult r = ptc(args);
    EXPECT_EQ(r.code, code) << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << r.err;
    fs::remove_all(dir_ / "out");
  }
  fs::path dir_, cube_;
};

// Width and height from a PNG's IHDR chunk (signature checked).
std::pair<int, int> png_size(const fs::path& p) {
  const std::string s = slurp(p);
  if (s.size() < 24 || s.substr(0, 8) != std::string("\x89PNG\r\n\x1a\n", 8) || s.substr(12, 4) != "IHDR") return {0, 0};
  auto be = [&](std::size_t i) {
    return int((std::uint8_t(s[i]) << 24) | (std::uint8_t(s[i + 1]) << 16) | (std::uint8_t(s[i + 2]) << 8) | std::uint8_t(s[i + 3]));
  };
  return {be(16), be(20)};
}

}  // namespace

TEST_F(TraceCli, TraceWritesImagesCsvAndManifest) {
  const CmdResult r = ptc({"trace", cube_.string(), "--width", "24", "--height", "16", "--shadows", "--ao", "4", "--threads",
                     "2", "--eye", "2.5,1.8,3", "--look-at", "0.5,0.5,0.5", "--out", (dir_ / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* f : {"shaded.png", "depth.png", "normal.png", "cost_nodes.png", "cost_triangles.png", "ao.png"})
    EXPECT_EQ(png_size(dir_ / "out" / f), std::make_pair(24, 16)) << f;
  EXPECT_EQ(png_size(dir_ / "out" / "cost_legend.png"), std::make_pair(256, 16));
  const std::string csv = slurp(dir_ / "out" / "trace.csv");
  ASSERT_EQ(lines(csv), 2u) << csv;
  EXPECT_EQ(csv.rfind("mesh,bvh,triangles,clusters,width,height,threads,setup_ms,build_ms,rays,hits,trace_ms,mrays_per_s,", 0), 0u);
  EXPECT_NE(csv.find(",triangles,12,0,24,16,2,"), std::string::npos) << csv;
  const auto m = nlohmann::json::parse(slurp(dir_ / "out" / "manifest.json"));
  EXPECT_EQ(m["schema"], "ptc-trace/1");
  EXPECT_EQ(m["results"]["rays"], 24 * 16);
  EXPECT_EQ(m["results"]["images"]["cost_nodes.png"]["quantity"], "nodes_visited");
  EXPECT_GE(m["results"]["images"]["cost_nodes.png"]["max"].get<double>(), 1.0);
  EXPECT_EQ(m["parameters"]["camera"]["eye"][0], 2.5);
  EXPECT_NE(r.out.find("primary"), std::string::npos);
  EXPECT_NE(r.out.find("shadow"), std::string::npos);
}

TEST_F(TraceCli, TraceWithClustersFromPtcCluster) {
  ASSERT_EQ(ptc({"cluster", cube_.string(), "--method", "growth", "--max-count", "4", "--out", (dir_ / "cl").string()}).code, 0);
  const CmdResult r = ptc({"trace", cube_.string(), "--clusters", (dir_ / "cl").string(), "--width", "8", "--height", "8",
                     "--out", (dir_ / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(dir_ / "out" / "trace.csv").find(",clusters,12,"), std::string::npos);
}

TEST_F(TraceCli, BadCamerasAndClustersAreOneLineErrors) {
  const std::string out = (dir_ / "out").string(), mesh = cube_.string();
  expect_error({"trace", mesh, "--eye", "1,2", "--out", out}, 2, "--eye");
  expect_error({"trace", mesh, "--eye", "nan,0,0", "--out", out}, 2, "finite");
  expect_error({"trace", mesh, "--look-at", "a,b,c", "--out", out}, 2, "--look-at");
  expect_error({"trace", mesh, "--fov", "180", "--out", out}, 2, "--fov");
  expect_error({"trace", mesh, "--fov", "0", "--out", out}, 2, "--fov");
  expect_error({"trace", mesh, "--up", "0,0,0", "--out", out}, 1, "--up: the up vector is zero");
  expect_error({"trace", mesh, "--eye", "0.5,0.5,5", "--up", "0,0,1", "--out", out}, 1, "parallel");
  expect_error({"trace", mesh, "--eye", "0.5,0.5,0.5", "--out", out}, 1, "same point");
  expect_error({"trace", mesh, "--clusters", (dir_ / "none").string(), "--out", out}, 1, "none: no such file");
  // Clusters of another mesh: a 2-triangle quad's clustering against the 12-triangle cube.
  fs::create_directories(dir_ / "quad");
  std::ofstream(dir_ / "quad" / "triangles.csv") << "triangle_id,cluster_id\n0,0\n1,0\n";
  expect_error({"trace", mesh, "--clusters", (dir_ / "quad").string(), "--out", out}, 1, "triangles.csv: line 3");
  expect_error({"trace", (dir_ / "missing.off").string(), "--out", out}, 1, "missing.off");
  expect_error({"bench", mesh, "--clusters", (dir_ / "quad").string(), "--max-count", "5", "--out", out}, 2, "excludes");
  expect_error({"bench", mesh, "--deform", "spin", "--out", out}, 2, "--deform");
}

TEST_F(TraceCli, BenchWritesEveryConfigurationPerFrame) {
  const CmdResult r = ptc({"bench", cube_.string(), "--frames", "2", "--width", "8", "--height", "8", "--max-count", "4",
                     "--out", (dir_ / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string csv = slurp(dir_ / "out" / "bench.csv");
  EXPECT_EQ(lines(csv), 1u + 2u * 5u) << csv;
  for (const char* c : {"ours_triangles", "ours_clusters", "embree_medium", "embree_low", "embree_refit"}) {
    EXPECT_NE(csv.find(std::string("1,") + c + ","), std::string::npos) << c;
    EXPECT_NE(r.out.find(c), std::string::npos) << c;
  }
  EXPECT_EQ(lines(slurp(dir_ / "out" / "summary.csv")), 6u);
  const auto m = nlohmann::json::parse(slurp(dir_ / "out" / "manifest.json"));
  EXPECT_EQ(m["parameters"]["threads"], 1);
  EXPECT_EQ(m["parameters"]["embree_set_affinity"], false);
}
