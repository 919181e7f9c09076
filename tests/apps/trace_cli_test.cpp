// `ptc trace` and `ptc bench` as a user runs them: outputs, exit codes and one-line errors.
#include <gtest/gtest.h>

#include <fmt/format.h>
#include <tbb/info.h>
#include <sys/wait.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli_harness.h"
#include "common/csv_rows.h"
#include "common/fnv.h"

namespace fs = std::filesystem;

namespace {

using ptc::test::kCube;
using ptc::test::lines;
using ptc::test::slurp;
using CmdResult = ptc::test::RunResult;
using ptc::test::csv_rows;

class TraceCli : public ptc::test::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    cube_ = write("cube.off", kCube);
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
  // The cube subdivided four times (fine.ply, 3072 triangles) and its growth clustering of at
  // most six triangles a cluster in cl/.
  fs::path clustered_fine_mesh() const {
    const fs::path fine = dir_ / "fine.ply";
    EXPECT_EQ(ptc({"subdivide", cube_.string(), "--levels", "4", "--out", fine.string()}).code, 0);
    EXPECT_EQ(ptc({"cluster", fine.string(), "--method", "growth", "--max-count", "6", "--max-size", "6", "--out",
                   (dir_ / "cl").string()})
                  .code,
              0);
    return fine;
  }
  fs::path cube_;
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
  ASSERT_EQ(lines(csv), 4u) << csv;  // one row per pass: primary, shadow, ao
  EXPECT_EQ(csv.rfind("mesh,bvh,triangles,clusters,width,height,threads,frame,pass,rays,hits,trace_ms,mrays_per_s,", 0), 0u);
  EXPECT_NE(csv.find(",triangles,12,0,24,16,2,0,primary,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",triangles,12,0,24,16,2,0,shadow,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",triangles,12,0,24,16,2,0,ao,"), std::string::npos) << csv;
  // A mesh file is one static part: built once, no per-frame update.
  const auto rows = csv_rows(csv);
  EXPECT_EQ(rows[0].at("frame"), "0");
  EXPECT_EQ(rows[0].at("static_triangles"), "12");
  EXPECT_EQ(rows[0].at("moving_triangles"), "0");
  EXPECT_GT(std::stod(rows[0].at("static_build_ms")), 0.0);
  EXPECT_EQ(std::stod(rows[0].at("update_ms")), 0.0);
  const auto m = nlohmann::json::parse(slurp(dir_ / "out" / "manifest.json"));
  EXPECT_EQ(m["schema"], "ptc-trace/5");
  EXPECT_EQ(m["output_schemas"]["trace.csv"], "ptc-trace/5");
  EXPECT_EQ(m["parameters"]["camera"]["from_scene"], false);
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

// A still scene's cluster BVH is built once: by default with the plain build (its tree is the
// rest tree), since the groups of the two-level build only make a per-frame rebuild cheap. An
// explicit --cluster-groups N still gives the two-level build (the same hits, so the same
// images), a moving scene keeps the default groups (smaller for this small one), and --group-trees without --cluster-groups
// on a still scene does nothing, so it is refused.
TEST_F(TraceCli, AStillSceneTakesThePlainBuildUnlessGroupsAreGiven) {
  const fs::path fine = clustered_fine_mesh();
  auto trace = [&](const std::string& name, std::vector<std::string> extra) {
    std::vector<std::string> args{"trace", fine.string(), "--clusters", (dir_ / "cl").string(), "--width", "40",
                                  "--height", "30", "--out", (dir_ / name).string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const CmdResult r = ptc(args);
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
    return nlohmann::json::parse(slurp(dir_ / name / "manifest.json"))["parameters"];
  };
  const auto plain = trace("plain", {});
  EXPECT_EQ(plain["cluster_group_size"], 0);
  EXPECT_FALSE(plain.contains("group_trees"));
  const auto groups = trace("groups", {"--cluster-groups", "16"});
  EXPECT_EQ(groups["cluster_group_size"], 16);
  EXPECT_EQ(groups["group_trees"], "refit");
  for (const char* img : {"shaded.png", "depth.png", "normal.png"})
    EXPECT_EQ(slurp(dir_ / "plain" / img), slurp(dir_ / "groups" / img)) << img;
  // Moving: the default groups, of 32 clusters but at least 1024 groups, so smaller for this
  // scene of a few thousand clusters (bvh::cluster_group_size_used); an explicit N is exact.
  const auto twist = trace("twist", {"--deform", "twist"});
  EXPECT_GT(twist["cluster_group_size"], 1);
  EXPECT_LT(twist["cluster_group_size"], 16);
  EXPECT_EQ(twist["min_cluster_groups"], 1024);
  EXPECT_EQ(twist["group_trees"], "refit");
  const auto twist16 = trace("twist16", {"--deform", "twist", "--cluster-groups", "16"});
  EXPECT_EQ(twist16["cluster_group_size"], 16);
  EXPECT_EQ(twist16["min_cluster_groups"], 0);
  EXPECT_EQ(twist16["group_trees"], "refit");
  EXPECT_EQ(trace("twist0", {"--deform", "twist", "--cluster-groups", "0"})["cluster_group_size"], 0);
  expect_error({"trace", fine.string(), "--clusters", (dir_ / "cl").string(), "--group-trees", "rebuild", "--out",
                (dir_ / "out").string()},
               2, "--group-trees");
}

TEST_F(TraceCli, BadCamerasAndClustersAreOneLineErrors) {
  const std::string out = (dir_ / "out").string(), mesh = cube_.string();
  expect_error({"trace", mesh, "--eye", "1,2", "--out", out}, 2, "--eye");
  expect_error({"trace", mesh, "--eye", "nan,0,0", "--out", out}, 2, "finite");
  expect_error({"trace", mesh, "--look-at", "a,b,c", "--out", out}, 2, "--look-at");
  expect_error({"trace", mesh, "--fov", "180", "--out", out}, 2, "--fov");
  expect_error({"trace", mesh, "--fov", "0", "--out", out}, 2, "--fov");
  expect_error({"trace", mesh, "--up", "0,0,0", "--out", out}, 2, "--up: the up vector is zero");
  expect_error({"trace", mesh, "--ao", "2", "--ao-distance", "nan", "--out", out}, 2, "--ao-distance: nan is not a finite number in [1e-09, 1e+09]");
  expect_error({"trace", mesh, "--ao", "2", "--ao-distance", "0", "--out", out}, 2, "0 is not a finite number in [1e-09, 1e+09]");
  expect_error({"trace", mesh, "--ao", "2", "--seed", "-5", "--out", out}, 2, "'-5' is not a seed");
  // Flags that would do nothing: refused, naming what they need.
  expect_error({"trace", mesh, "--cluster-groups", "4", "--out", out}, 2, "--cluster-groups: needs a cluster BVH");
  expect_error({"trace", mesh, "--ao-distance", "0.5", "--out", out}, 2, "--ao-distance: needs ambient occlusion");
  expect_error({"trace", mesh, "--seed", "7", "--out", out}, 2, "--seed: needs ambient occlusion");
  expect_error({"trace", mesh, "--cost-range", "-5:-1", "--out", out}, 2, "MAX must be above 0");
  expect_error({"bench", mesh, "--no-shadows", "--light", "1,1,1", "--out", out}, 2, "--light: needs shadow rays");
  // A camera the flags make inconsistent: usage errors, as a zero --up (exit 2).
  expect_error({"trace", mesh, "--eye", "0.5,0.5,5", "--up", "0,0,1", "--out", out}, 2, "--up: the up vector 0,0,1 is parallel");
  expect_error({"trace", mesh, "--eye", "0.5,0.5,0.5", "--out", out}, 2, "--eye: eye and look-at are the same point");
  {  // only --look-at given, on the eye of the scene's own camera: that flag is named (it said --eye)
    const fs::path scene = dir_ / "cam.json";
    std::ofstream(scene) << R"({"camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]}, "meshes": [{"file": ")" << mesh
                         << R"("}]})";
    expect_error({"trace", scene.string(), "--look-at", "0,0,5", "--out", out}, 2,
                 "--look-at: eye and look-at are the same point");
  }
  expect_error({"trace", mesh, "--eye", "1e308,0,0", "--look-at", "-1e308,0,0", "--out", out}, 2,
               "--eye: eye 1e+308,0,0 and look-at -1e+308,0,0 are too far apart");
  // A far eye whose difference to look-at does not overflow: the view direction is right (the
  // norm of 1e300 overflowed before, and the message blamed --up), but the eye lies beyond the
  // tracer's reach (before the fortieth session: Embree's check, exit 1, "beyond what Embree
  // accepts"; now the flag's usage error, as in ptc trace).
  expect_error({"bench", mesh, "--eye", "1e300,0,0", "--width", "4", "--height", "4", "--frames", "0:1", "--out", out},
               2, "--eye: the camera's eye (1e+300, 0, 0) lies 1e+300 units from the scene's centre, beyond the tracer's reach");
  expect_error({"trace", mesh, "--clusters", (dir_ / "none").string(), "--out", out}, 1, "none: no such file");
  // Clusters of another mesh: a 2-triangle quad's clustering against the 12-triangle cube.
  fs::create_directories(dir_ / "quad");
  std::ofstream(dir_ / "quad" / "triangles.csv") << "triangle_id,cluster_id\n0,0\n1,0\n";
  expect_error({"trace", mesh, "--clusters", (dir_ / "quad").string(), "--out", out}, 1, "triangles.csv: line 3");
  expect_error({"trace", (dir_ / "missing.off").string(), "--out", out}, 1, "missing.off");
  expect_error({"bench", mesh, "--clusters", (dir_ / "quad").string(), "--max-count", "5", "--out", out}, 2, "excludes");
  expect_error({"bench", mesh, "--deform", "spin", "--out", out}, 2, "--deform");
  expect_error({"bench", mesh, "--vertex-order", "random", "--out", out}, 2, "--vertex-order");
  expect_error({"bench", mesh, "--light", "1,nan,2", "--out", out}, 2, "--light");
  expect_error({"bench", mesh, "--leaf-format", "soup", "--out", out}, 2, "--leaf-format");
  expect_error({"bench", mesh, "--leaf-format", "tables", "--cluster-leaf", "block-tree", "--out", out}, 2,
               "--leaf-format: tables needs linear cluster leaves");
  for (const char* bad : {"0.5", "1", "nan", "inf", "never", "-3"})
    expect_error({"bench", mesh, "--cluster-fallback", bad, "--out", out}, 2, "--cluster-fallback");
  for (const char* bad : {"0", "-0.1", "nan", "inf", "always", "0.2x"})
    expect_error({"bench", mesh, "--fallback-refit", bad, "--out", out}, 2, "--fallback-refit");
  expect_error({"bench", mesh, "--cluster-fallback", "off", "--fallback-refit", "0.3", "--out", out}, 2,
               "--fallback-refit: needs the triangle fallback");
  for (const char* bad : {"", "camera", "EYE", "rays", "uniform"})
    expect_error({"bench", mesh, "--fallback-sah", bad, "--out", out}, 2, "--fallback-sah");
  expect_error({"bench", mesh, "--cluster-fallback", "off", "--fallback-sah", "plain", "--out", out}, 2,
               "--fallback-sah: needs the triangle fallback");
}

// `ptc bench --cluster-fallback auto|off|X`: the threshold in the manifest (auto: 64, off: 0), the
// frames traced on the fallback counted there and in bench.csv's fallback column, and the
// summary line; a threshold just above 1 sends every frame of the bunny's twist to it, with zero
// mismatches.
TEST_F(TraceCli, BenchClusterFallbackIsRecorded) {
  const std::string mesh = (fs::path(PTC_TEST_DATA) / "meshes" / "bunny00.off").string();
  const std::pair<const char*, double> cases[] = {{"", 64.0}, {"off", 0.0}, {"1.0001", 1.0001}};
  for (const auto& [arg, want] : cases) {
    const fs::path out = dir_ / (std::string("fb_") + (*arg ? arg : "auto"));
    std::vector<std::string> args{"bench", mesh, "--frames", "0:2", "--width", "24", "--height", "24",
                                  "--max-count", "40", "--threads", "1", "--out", out.string()};
    if (*arg) args.insert(args.end(), {"--cluster-fallback", arg});
    const CmdResult r = ptc(args);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(out / "manifest.json"));
    EXPECT_EQ(j["parameters"]["cluster_fallback"].get<double>(), want) << arg;
    std::uint64_t fell = 0;
    for (const auto& row : csv_rows(slurp(out / "bench.csv"))) {
      EXPECT_EQ(row.at("mismatches"), "0");
      if (row.at("config") != "ours_clusters") {
        EXPECT_EQ(row.at("fallback"), "0");
        continue;
      }
      EXPECT_GT(std::stod(row.at("swelling")), 1.0);
      fell += row.at("fallback") == "1";
    }
    EXPECT_EQ(j["results"]["cluster_fallback_frames"].get<std::uint64_t>(), fell) << arg;
    EXPECT_EQ(fell, want == 1.0001 ? 3u : 0u) << arg;
    EXPECT_NE(r.out.find(want > 0 ? fmt::format("triangle fallback above {:g}: {} of 3 frames", want, fell)
                                  : std::string("triangle fallback off")),
              std::string::npos)
        << r.out;
    EXPECT_EQ(j["parameters"]["fallback_refit"].get<double>(), want > 0 ? 0.2 : 0.0) << arg;  // (auto; none without a fallback)
    // (the fallback built for the primary rays' directions by default: their weights; plain
    // without one)
    EXPECT_EQ(j["parameters"]["fallback_sah"].get<std::string>(), want > 0 ? "directions" : "plain") << arg;
    EXPECT_EQ(j["parameters"]["fallback_area_weights"].get<std::vector<double>>() == std::vector<double>({1.0, 1.0, 1.0}),
              !(want > 0))
        << arg;
    EXPECT_TRUE(j["parameters"]["fallback_area_eye"].is_null()) << arg;
    if (want > 0 && fell > 0) {
      EXPECT_NE(r.out.find("; SAH for the camera's ray directions"), std::string::npos) << r.out;
    }
  }
  // --fallback-sah eye: the camera's eye, weights 1; directions: the primary rays' weights, no
  // point; plain: neither; the same hits.
  for (const char* sah : {"eye", "directions", "plain"}) {
    const fs::path out = dir_ / (std::string("fb_sah_") + sah);
    const CmdResult r = ptc({"bench", mesh, "--frames", "0:2", "--width", "24", "--height", "24", "--max-count", "40",
                             "--threads", "1", "--cluster-fallback", "1.0001", "--fallback-sah", sah, "--out",
                             out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(out / "manifest.json"));
    EXPECT_EQ(j["parameters"]["fallback_sah"].get<std::string>(), sah);
    EXPECT_EQ(j["parameters"]["fallback_area_eye"].is_null(), std::string(sah) != "eye") << sah;
    const auto w = j["parameters"]["fallback_area_weights"].get<std::vector<double>>();
    ASSERT_EQ(w.size(), 3u);
    if (std::string(sah) == "eye") {
      EXPECT_EQ(w, std::vector<double>({1.0, 1.0, 1.0}));
      EXPECT_EQ(j["parameters"]["fallback_area_eye"].size(), 3u);
      EXPECT_NE(r.out.find("; SAH for rays from the camera's eye"), std::string::npos) << r.out;
    } else if (std::string(sah) == "plain") {
      EXPECT_EQ(w, std::vector<double>({1.0, 1.0, 1.0}));
      EXPECT_NE(r.out.find("; plain SAH"), std::string::npos) << r.out;
    } else {
      EXPECT_NE(w, std::vector<double>({1.0, 1.0, 1.0}));
      for (const double x : w) EXPECT_TRUE(x > 0.0 && x <= 2.0) << x;
      EXPECT_NE(r.out.find("; SAH for the camera's ray directions (area weights"), std::string::npos) << r.out;
    }
    for (const auto& row : csv_rows(slurp(out / "bench.csv"))) EXPECT_EQ(row.at("mismatches"), "0") << sah;
  }
  // --fallback-refit: a limit no growth reaches keeps the fallback's tree on every frame (it is made
  // with the scene, at the rest pose, whose swelling is above 1.0001: frame 0 refits it too;
  // bench.csv's fallback_refit on each, no binary SAH cost there), off rebuilds it on each; the
  // same hits either way.
  const std::pair<const char*, std::uint64_t> refits[] = {{"1e9", 3u}, {"off", 0u}};
  for (const auto& [arg, want] : refits) {
    const fs::path out = dir_ / (std::string("fr_") + arg);
    const CmdResult r = ptc({"bench", mesh, "--frames", "0:2", "--width", "24", "--height", "24", "--max-count", "40",
                             "--threads", "1", "--cluster-fallback", "1.0001", "--fallback-refit", arg, "--out",
                             out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(out / "manifest.json"));
    EXPECT_EQ(j["parameters"]["fallback_refit"].get<double>(), want ? 1e9 : 0.0) << arg;
    EXPECT_EQ(j["results"]["fallback_refit_frames"].get<std::uint64_t>(), want) << arg;
    std::uint64_t kept = 0;
    for (const auto& row : csv_rows(slurp(out / "bench.csv"))) {
      EXPECT_EQ(row.at("mismatches"), "0") << arg;
      EXPECT_EQ(row.at("shadow_mismatches"), "0") << arg;
      const bool refitted = row.at("fallback_refit") == "1";
      kept += refitted;
      if (row.at("config") == "ours_clusters") {
        EXPECT_EQ(refitted, want > 0) << arg << " frame " << row.at("frame");
        EXPECT_EQ(row.at("sah_cost") == "nan", refitted) << arg;
      }
    }
    EXPECT_EQ(kept, want) << arg;
    EXPECT_NE(r.out.find(want ? std::string("its tree refitted on 3 of them (cost growth at most 1e+09)")
                              : std::string("its tree rebuilt on each")),
              std::string::npos)
        << r.out;
  }
}

// The bench's cluster size: --max-count, else the scene's own ("clusters" in a scene file), else
// 32; the manifest says which, and the run clusters with it (the same clusters as --max-count N).
TEST_F(TraceCli, BenchTakesTheScenesClusterSize) {
  const std::string bunny = (fs::path(PTC_TEST_DATA) / "meshes" / "bunny00.off").string();
  const auto scene_file = [&](const std::string& name, const std::string& clusters) {
    return write(name, R"({"meshes": [{"file": ")" + bunny + R"(", "deform": {"kind": "twist"}}], "frames": [0, 2])" +
                           clusters + "}")
        .string();
  };
  const std::string own = scene_file("own.json", R"(, "clusters": {"max_count": 12})");
  const std::string none = scene_file("none.json", "");
  // A static scene file: the bench's stand-in motion (twist by default, or --deform) keeps its size.
  const std::string still =
      write("still.json", R"({"meshes": [{"file": ")" + bunny + R"("}], "clusters": {"max_count": 12}})").string();
  const std::string zero = scene_file("zero.json", R"(, "clusters": {"max_count": 0})");
  struct Case {
    std::string scene, flag, from;
    std::uint32_t used;
    std::vector<std::string> more = {};
  };
  const Case cases[] = {{own, "", "scene", 12},
                        {own, "40", "--max-count", 40},
                        {none, "", "default", 32},
                        {none, "12", "--max-count", 12},
                        {still, "", "scene", 12, {"--frames", "0:2"}},
                        {still, "", "scene", 12, {"--frames", "0:2", "--deform", "wave"}},
                        {zero, "", "scene", 0}};
  std::map<std::uint32_t, std::uint64_t> clusters;
  for (std::size_t k = 0; k < std::size(cases); ++k) {
    const Case& c = cases[k];
    const fs::path out = dir_ / fmt::format("mc_{}", k);
    std::vector<std::string> args{"bench", c.scene, "--width", "16", "--height", "16", "--threads", "1", "--out", out.string()};
    if (!c.flag.empty()) args.insert(args.end(), {"--max-count", c.flag});
    args.insert(args.end(), c.more.begin(), c.more.end());
    const CmdResult r = ptc(args);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(out / "manifest.json"));
    EXPECT_EQ(j["parameters"]["max_count"].get<std::uint32_t>(), c.used) << k;
    EXPECT_EQ(j["parameters"]["max_count_from"].get<std::string>(), c.from) << k;
    EXPECT_NE(r.out.find(c.used == 0 ? std::string("one triangle per cluster (MaxCount = MaxSize = 0)")
                                     : fmt::format("MaxCount={} MaxSize={}", c.used, c.used)),
              std::string::npos)
        << r.out;
    EXPECT_EQ(r.out.find("(the scene's cluster size)") != std::string::npos, c.from == "scene") << r.out;
    const auto n = j["results"]["clusters"].get<std::uint64_t>();
    if (const auto it = clusters.find(c.used); it != clusters.end()) {
      EXPECT_EQ(it->second, n) << k;
    }
    clusters[c.used] = n;
  }
  EXPECT_GT(clusters.at(0), clusters.at(12));  // (smaller clusters: more of them)
  EXPECT_GT(clusters.at(12), clusters.at(32));
  EXPECT_GE(clusters.at(32), clusters.at(40));
  // A given clustering (--clusters) is used as it is: no cluster size recorded or printed.
  const fs::path cl = dir_ / "bunny_clusters";
  ASSERT_EQ(ptc({"cluster", bunny, "--out", cl.string()}).code, 0);
  {
    const fs::path out = dir_ / "mc_given";
    const CmdResult r = ptc({"bench", own, "--clusters", cl.string(), "--width", "16", "--height", "16", "--threads", "1",
                             "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    const auto j = nlohmann::json::parse(slurp(out / "manifest.json"));
    EXPECT_FALSE(j["parameters"].contains("max_count"));
    EXPECT_FALSE(j["parameters"].contains("max_count_from"));
    EXPECT_EQ(j["parameters"]["clustering"], "given");
    EXPECT_EQ(r.out.find("(the scene's cluster size)"), std::string::npos) << r.out;
  }
  // The clustering flags exclude a given clustering, and a value outside the range is bad usage:
  // exit 2, nothing written.
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--max-count", "1048577"}, {"--max-count", "12", "--clusters", cl.string()}}) {
    std::vector<std::string> args{"bench", own, "--out", (dir_ / "bad").string()};
    args.insert(args.end(), bad.begin(), bad.end());
    const CmdResult r = ptc(args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "bad"));
  }
}

// `ptc bench --leaf-format blocks|tables|auto` (and auto by default): the cluster BVH's leaves as
// blocks or vertex tables, recorded in the manifest with the estimate auto chose by, with the same
// hits and zero mismatches against brute force.
TEST_F(TraceCli, BenchTracesTheTablesFormatLikeTheBlocks) {
  std::vector<std::string> hits[4];
  // (the last: no --leaf-format, which is auto)
  const char* formats[] = {"blocks", "tables", "auto", "auto"};
  for (int f = 0; f < 4; ++f) {
    const fs::path out = dir_ / ("lf_" + std::to_string(f));
    std::vector<std::string> args{"bench", (fs::path(PTC_TEST_DATA) / "meshes" / "bunny00.off").string(), "--frames",
                                  "0:2", "--width", "32", "--height", "32", "--max-count", "40", "--threads", "1",
                                  "--out", out.string()};
    if (f < 3) args.insert(args.end(), {"--leaf-format", formats[f]});
    const CmdResult r = ptc(args);
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string manifest = slurp(out / "manifest.json");
    EXPECT_NE(manifest.find(std::string("\"leaf_format\": \"") + formats[f] + "\""), std::string::npos);
    // The cluster leaves' shape, printed and in the manifest (every triangle in them once); auto
    // takes the tables when the estimated bytes in the manifest say so (this mesh: it does).
    const auto j = nlohmann::json::parse(manifest);
    const auto& leaves = j["results"]["cluster_leaves"];
    const double est_blocks = leaves["estimated_blocks_bytes"], est_tables = leaves["estimated_tables_bytes"];
    EXPECT_GT(est_blocks, 0.0);
    const std::string used = f < 2 ? formats[f] : est_tables <= 0.85 * est_blocks ? "tables" : "blocks";
    if (f >= 2) {
      EXPECT_EQ(used, "tables") << est_tables << " " << est_blocks;
    }
    EXPECT_EQ(leaves["format"], used);
    EXPECT_EQ(j["results"]["cluster_leaves"]["triangles"], j["results"]["triangles"]);
    EXPECT_NE(r.out.find("cluster leaves: " + used), std::string::npos) << r.out;
    for (const auto& row : csv_rows(slurp(out / "bench.csv"))) {
      if (row.at("config") != "ours_clusters") continue;
      EXPECT_EQ(row.at("mismatches"), "0") << formats[f];
      hits[f].push_back(row.at("hits") + " " + row.at("shadow_occluded"));
    }
  }
  ASSERT_EQ(hits[0].size(), 3u);
  for (int f = 1; f < 4; ++f) EXPECT_EQ(hits[0], hits[f]) << formats[f];
}

// `ptc trace --clusters D --cluster-fallback X`: with X just above 1 every frame of the bunny's
// twist is traced on the moving cluster BVH's triangle fallback, and the images and hits are
// those of the cluster BVH on every frame (off): the same bytes, frame by frame; the manifest
// records the threshold, each frame's swelling and flag, and the count; the summary says it.
// Without --clusters the flag is a usage error.
TEST_F(TraceCli, TraceClusterFallbackDrawsTheSameImages) {
  const std::string mesh = (fs::path(PTC_TEST_DATA) / "meshes" / "bunny00.off").string();
  const std::string cl = (dir_ / "fbc").string();
  ASSERT_EQ(ptc({"cluster", mesh, "--method", "growth", "--max-count", "24", "--out", cl}).code, 0);
  auto run = [&](const std::string& x, const char* refit = nullptr, const char* sah = nullptr) {
    const fs::path out = dir_ / ("fbt_" + x + (refit ? std::string("_") + refit : std::string()) +
                                 (sah ? std::string("_") + sah : std::string()));
    std::vector<std::string> args{"trace", mesh, "--clusters", cl, "--deform", "twist", "--frames", "0:3", "--width",
                                  "40", "--height", "32", "--shadows", "--cluster-fallback", x, "--out", out.string()};
    if (refit) args.insert(args.end(), {"--fallback-refit", refit});
    if (sah) args.insert(args.end(), {"--fallback-sah", sah});
    const CmdResult r = ptc(args);
    EXPECT_EQ(r.code, 0) << r.err;
    return std::pair{out, r.out};
  };
  const auto [on, on_text] = run("1.0001");
  const auto [off, off_text] = run("off");
  const auto [kept, kept_text] = run("1.0001", "1e9");  // (the fallback, made at the rest pose, refitted on every frame)
  const auto [plain, plain_text] = run("1.0001", nullptr, "plain");
  const auto [eyes, eyes_text] = run("1.0001", nullptr, "eye");
  for (int f = 0; f <= 3; ++f)
    for (const char* img : {"shaded", "depth", "normal"}) {
      const std::string name = fmt::format("{}_{:04d}.png", img, f);
      EXPECT_EQ(slurp(on / name), slurp(off / name)) << name;
      EXPECT_EQ(slurp(kept / name), slurp(off / name)) << name;
      EXPECT_EQ(slurp(plain / name), slurp(off / name)) << name;
      EXPECT_EQ(slurp(eyes / name), slurp(off / name)) << name;
    }
  // The fallback built for the primary rays' directions by default, for rays from the camera's
  // eye (the manifest's camera eye) or plain on request; the summary says which.
  const auto jp = nlohmann::json::parse(slurp(plain / "manifest.json"));
  EXPECT_EQ(jp["parameters"]["fallback_sah"].get<std::string>(), "plain");
  EXPECT_EQ(jp["parameters"]["fallback_area_weights"].get<std::vector<double>>(), std::vector<double>({1.0, 1.0, 1.0}));
  EXPECT_TRUE(jp["parameters"]["fallback_area_eye"].is_null());
  EXPECT_NE(plain_text.find("; plain SAH"), std::string::npos) << plain_text;
  {
    const auto je = nlohmann::json::parse(slurp(eyes / "manifest.json"));
    EXPECT_EQ(je["parameters"]["fallback_sah"].get<std::string>(), "eye");
    EXPECT_EQ(je["parameters"]["fallback_area_eye"], je["parameters"]["camera"]["eye"]);
    EXPECT_EQ(je["parameters"]["fallback_area_weights"].get<std::vector<double>>(), std::vector<double>({1.0, 1.0, 1.0}));
    EXPECT_NE(eyes_text.find("; SAH for rays from the camera's eye"), std::string::npos) << eyes_text;
    const auto jd = nlohmann::json::parse(slurp(on / "manifest.json"));
    EXPECT_EQ(jd["parameters"]["fallback_sah"].get<std::string>(), "directions");
    EXPECT_NE(jd["parameters"]["fallback_area_weights"].get<std::vector<double>>(), std::vector<double>({1.0, 1.0, 1.0}));
    EXPECT_TRUE(jd["parameters"]["fallback_area_eye"].is_null());
    EXPECT_NE(on_text.find("; SAH for the camera's ray directions"), std::string::npos) << on_text;
  }
  const auto jk = nlohmann::json::parse(slurp(kept / "manifest.json"));
  EXPECT_EQ(jk["parameters"]["fallback_refit"].get<double>(), 1e9);
  EXPECT_EQ(jk["results"]["fallback_refit_frames"].get<std::uint64_t>(), 4u);
  for (int f = 0; f <= 3; ++f) EXPECT_TRUE(jk["results"]["frames"][f]["fallback_refit"].get<bool>()) << f;
  EXPECT_NE(kept_text.find("its tree refitted on 4 of them (cost growth at most 1e+09)"), std::string::npos) << kept_text;
  const auto a = csv_rows(slurp(on / "trace.csv")), b = csv_rows(slurp(off / "trace.csv"));
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].at("hits"), b[i].at("hits")) << i;
  const auto jon = nlohmann::json::parse(slurp(on / "manifest.json")), joff = nlohmann::json::parse(slurp(off / "manifest.json"));
  EXPECT_EQ(jon["parameters"]["cluster_fallback"].get<double>(), 1.0001);
  EXPECT_EQ(joff["parameters"]["cluster_fallback"].get<double>(), 0.0);
  EXPECT_EQ(jon["results"]["cluster_fallback_frames"].get<std::uint64_t>(), 4u);
  EXPECT_EQ(joff["results"]["cluster_fallback_frames"].get<std::uint64_t>(), 0u);
  for (int f = 0; f <= 3; ++f) {
    EXPECT_TRUE(jon["results"]["frames"][f]["fallback"].get<bool>()) << f;
    EXPECT_FALSE(joff["results"]["frames"][f]["fallback"].get<bool>()) << f;
    EXPECT_GT(jon["results"]["frames"][f]["swelling"].get<double>(), 1.0001) << f;
    EXPECT_EQ(jon["results"]["frames"][f]["swelling"].get<double>(), joff["results"]["frames"][f]["swelling"].get<double>()) << f;
  }
  EXPECT_NE(on_text.find("cluster BVH: 4 of 4 frames traced on the triangle fallback (swelling above 1.0001)"),
            std::string::npos) << on_text;
  expect_error({"trace", mesh, "--cluster-fallback", "2", "--out", (dir_ / "fb_bad").string()}, 2,
               "--cluster-fallback: needs a cluster BVH");
  expect_error({"trace", mesh, "--fallback-refit", "0.3", "--out", (dir_ / "fb_bad").string()}, 2,
               "--fallback-refit: needs a cluster BVH");
  expect_error({"trace", mesh, "--clusters", cl, "--deform", "twist", "--cluster-fallback", "off", "--fallback-refit",
                "0.3", "--out", (dir_ / "fb_bad").string()},
               2, "--fallback-refit: needs the triangle fallback");
  for (const char* bad : {"0", "-1", "nan", "never"})
    expect_error({"trace", mesh, "--clusters", cl, "--deform", "twist", "--fallback-refit", bad, "--out",
                  (dir_ / "fb_bad").string()},
                 2, "--fallback-refit");
  expect_error({"trace", mesh, "--clusters", cl, "--fallback-refit", "0.3", "--out", (dir_ / "fb_bad").string()}, 2,
               "--fallback-refit: a still scene is built once");
  expect_error({"trace", mesh, "--fallback-sah", "plain", "--out", (dir_ / "fb_bad").string()}, 2,
               "--fallback-sah: needs a cluster BVH");
  expect_error({"trace", mesh, "--clusters", cl, "--deform", "twist", "--cluster-fallback", "off", "--fallback-sah",
                "eye", "--out", (dir_ / "fb_bad").string()},
               2, "--fallback-sah: needs the triangle fallback");
  expect_error({"trace", mesh, "--clusters", cl, "--deform", "twist", "--fallback-sah", "camera", "--out",
                (dir_ / "fb_bad").string()},
               2, "--fallback-sah");
  expect_error({"trace", mesh, "--clusters", cl, "--fallback-sah", "directions", "--out", (dir_ / "fb_bad").string()}, 2,
               "--fallback-sah: a still scene is built once");
  expect_error({"trace", mesh, "--clusters", cl, "--deform", "twist", "--cluster-fallback", "0.9", "--out",
                (dir_ / "fb_bad").string()},
               2, "--cluster-fallback");
  // A still scene (no --deform) is built once: nothing can fall back, so the flag is refused, and
  // without it the manifest says nothing of a fallback.
  expect_error({"trace", mesh, "--clusters", cl, "--cluster-fallback", "auto", "--out", (dir_ / "fb_bad").string()}, 2,
               "--cluster-fallback: a still scene is built once");
  const fs::path still = dir_ / "fb_still";
  ASSERT_EQ(ptc({"trace", mesh, "--clusters", cl, "--width", "8", "--height", "8", "--out", still.string()}).code, 0);
  const auto js = nlohmann::json::parse(slurp(still / "manifest.json"));
  EXPECT_FALSE(js["parameters"].contains("cluster_fallback"));
  EXPECT_FALSE(js["results"].contains("cluster_fallback_frames"));
  EXPECT_FALSE(js["parameters"].contains("fallback_refit"));
  EXPECT_FALSE(js["parameters"].contains("fallback_sah"));
}

// A mesh of 1e13 units: our tracer's float products overflowed there, every ray missed, and the
// bench charged Embree with the difference. The trace frame's scale (docs/tracing.md, "The trace
// frame at any scale") makes them hit, and a mesh beyond the float range is refused, naming it.
TEST_F(TraceCli, HugeAndTinyMeshesTraceOrAreRefusedNamingTheFile) {
  auto quad = [&](const std::string& name, const char* e) {
    return write(name, std::string("OFF\n4 2 0\n0 0 0\n") + e + " 0 0\n0 " + e + " 0\n" + e + " " + e +
                           " 0\n3 0 1 2\n3 1 3 2\n").string();
  };
  for (const char* e : {"1e13", "1e-20"}) {
    const std::string mesh = quad(std::string("quad") + e + ".off", e);
    const fs::path out = dir_ / (std::string("b") + e);
    const CmdResult r = ptc({"bench", mesh, "--deform", "none", "--frames", "0:1", "--width", "16", "--height", "16",
                             "--threads", "1", "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    std::vector<std::string> hits;
    for (const auto& row : csv_rows(slurp(out / "bench.csv"))) {
      if (row.at("config").rfind("ours_", 0) != 0) continue;
      EXPECT_GE(std::stoi(row.at("hits")), 200) << e << " " << row.at("config");  // most of the 256 pixels
      hits.push_back(row.at("hits"));
    }
    ASSERT_EQ(hits.size(), 4u) << e;  // two configurations, two frames
    EXPECT_EQ(std::count(hits.begin(), hits.end(), hits[0]), 4) << e;
  }
  expect_error({"trace", quad("quad1e35.off", "1e35"), "--out", (dir_ / "out").string()}, 1,
               "quad1e35.off: the mesh reaches 5e+34 units from its centre: beyond the single-precision tracer's range");
  expect_error({"bench", quad("quad1e-35.off", "1e-35"), "--out", (dir_ / "out").string()}, 1,
               "quad1e-35.off: the mesh reaches");
}

// A ground plane (y = 0) under the default camera: seen from 45 degrees, not edge-on (where no
// ray hit it); a camera that sees nothing of the mesh is told so, once.
TEST_F(TraceCli, FlatMeshIsSeenAndAnEmptyViewIsNoted) {
  const std::string plane = write("plane.off", "OFF\n4 2 0\n-1 0 -1\n1 0 -1\n-1 0 1\n1 0 1\n3 0 2 1\n3 1 2 3\n").string();
  CmdResult r = ptc({"trace", plane, "--width", "16", "--height", "16", "--json", "--out", (dir_ / "p").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["rows"][0]["hits"].get<int>(), 64) << r.out;
  EXPECT_EQ(r.err.find("no primary ray hit"), std::string::npos) << r.err;
  r = ptc({"trace", plane, "--width", "16", "--height", "16", "--eye", "0,5,0", "--look-at", "0,10,0", "--up", "1,0,0",
           "--out", (dir_ / "q").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("ptc: note: no primary ray hit the mesh in frame 0"), std::string::npos) << r.err;
  // A sequence: the first such frame named, the later ones counted (one note each, not one a frame).
  r = ptc({"trace", plane, "--deform", "wave", "--frames", "0:3", "--width", "16", "--height", "16", "--eye", "0,5,0",
           "--look-at", "0,10,0", "--up", "1,0,0", "--out", (dir_ / "s").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("in frame 0 "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("nor in 3 later frames"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 2u) << r.err;
  // The bench says it too (its times would measure empty rays).
  r = ptc({"bench", plane, "--frames", "0:1", "--width", "8", "--height", "8", "--eye", "0,5,0", "--look-at", "0,10,0",
           "--up", "1,0,0", "--out", (dir_ / "b").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("ptc: note: no primary ray hit the mesh in any frame"), std::string::npos) << r.err;
  // The twist (about y) leaves a plane flat across y still, and says so.
  r = ptc({"trace", plane, "--deform", "twist", "--frames", "0:1", "--width", "8", "--height", "8", "--out",
           (dir_ / "t").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("the twist deformer leaves"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("no extent along y"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(dir_ / "t" / "depth_0000.png"), slurp(dir_ / "t" / "depth_0001.png"));
}

// The default camera frames the triangles: a vertex no triangle uses, far away, does not shrink
// the mesh to a dot (same image as without it); a small mesh far from the origin fills the view
// (the eye stood 1e-6 of its distance back before, 100 units for a 2-unit quad at 1e11).
TEST_F(TraceCli, TheDefaultCameraFramesTheTriangles) {
  auto hits = [&](const std::string& mesh, const std::string& out) {
    const CmdResult r = ptc({"trace", mesh, "--width", "32", "--height", "32", "--json", "--out", (dir_ / out).string()});
    EXPECT_EQ(r.code, 0) << r.err;
    return r.code == 0 ? nlohmann::json::parse(r.out)["rows"][0]["hits"].get<int>() : -1;
  };
  const std::string quad = "4 2 0\n-1 -1 0\n1 -1 0\n-1 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n";
  const int plain = hits(write("q.off", "OFF\n" + quad).string(), "q");
  EXPECT_GT(plain, 300);
  const std::string lone = "OFF\n5 2 0\n-1 -1 0\n1 -1 0\n-1 1 0\n1 1 0\n1000 1000 1000\n3 0 1 2\n3 1 3 2\n";
  EXPECT_EQ(hits(write("lone.off", lone).string(), "lone"), plain);
  EXPECT_EQ(slurp(dir_ / "lone" / "depth_0000.png"), slurp(dir_ / "q" / "depth_0000.png"));
  const std::string far = "OFF\n4 2 0\n1e11 -1 0\n100000000002 -1 0\n1e11 1 0\n100000000002 1 0\n3 0 1 2\n3 1 3 2\n";
  EXPECT_GT(hits(write("far.off", far).string(), "far"), 300);
}

// --deform: a mesh file traced with the stand-in motion ptc bench measures (frames of a periodic
// motion, so no range of its own); an animated scene refuses it. Without it, a mesh stays still.
TEST_F(TraceCli, TraceShowsTheStandInMotionOfTheBench) {
  CmdResult r = ptc({"trace", cube_.string(), "--deform", "twist", "--frames", "0:70", "--width", "16", "--height", "16",
                     "--out", (dir_ / "d").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(slurp(dir_ / "d" / "depth_0000.png"), slurp(dir_ / "d" / "depth_0001.png"));  // it moved
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "d" / "manifest.json"))["parameters"]["motion"],
            "stand-in: the twist deformer (deform_preset)");
  r = ptc({"trace", cube_.string(), "--deform", "none", "--frames", "0:1", "--width", "16", "--height", "16", "--out",
           (dir_ / "n").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(slurp(dir_ / "n" / "depth_0000.png"), slurp(dir_ / "n" / "depth_0001.png"));
  const fs::path scene = write("anim.json", R"({"meshes": [{"file": "cube.off", "deform": {"kind": "wave"}}]})");
  expect_error({"trace", scene.string(), "--deform", "twist", "--out", (dir_ / "out").string()}, 2, "--deform");
}

// A frame traces the same whichever range it is traced in: the BVH (its cluster order and
// fixed group trees) and the trace frame are set up at the rest pose, not at the range's first
// frame (a study split over runs reproduces the single run's counters).
TEST_F(TraceCli, AFrameTracesTheSameInAnyRange) {
  const fs::path fine = clustered_fine_mesh();
  ASSERT_FALSE(HasFailure());
  auto trace = [&](const std::string& name, std::vector<std::string> frames) {
    std::vector<std::string> a = {"trace", fine.string(), "--deform", "twist", "--clusters", (dir_ / "cl").string(),
                                  "--eye", "3,2,4", "--look-at", "0.5,0.5,0.5", "--shadows", "--width", "48",
                                  "--height", "48", "--out", (dir_ / name).string()};
    a.insert(a.end(), frames.begin(), frames.end());
    const CmdResult r = ptc(a);
    EXPECT_EQ(r.code, 0) << r.err;
    std::map<std::string, std::map<std::string, std::string>> rows;  // "frame/pass" -> row
    for (const auto& row : csv_rows(slurp(dir_ / name / "trace.csv"))) rows[row.at("frame") + "/" + row.at("pass")] = row;
    return rows;
  };
  const auto all = trace("all", {"--frames", "0:5"});
  const auto late = trace("late", {"--frames", "4:5"});
  const auto one = trace("one", {"--frame", "5"});
  for (const auto* other : {&late, &one})
    for (const std::string pass : {"primary", "shadow"})
      for (const char* col : {"hits", "nodes_visited", "triangles_tested"})
        EXPECT_EQ(all.at("5/" + pass).at(col), other->at("5/" + pass).at(col)) << pass << " " << col;
  // The manifest's hits: the primary hits of every frame traced.
  std::uint64_t sum = 0;
  for (const auto& [key, row] : all)
    if (row.at("pass") == "primary") sum += std::stoull(row.at("hits"));
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "all" / "manifest.json"))["results"]["hits"].get<std::uint64_t>(), sum);
  EXPECT_EQ(slurp(dir_ / "all" / "depth_0005.png"), slurp(dir_ / "one" / "depth.png"));
  EXPECT_EQ(slurp(dir_ / "all" / "depth_0005.png"), slurp(dir_ / "late" / "depth_0005.png"));
  EXPECT_EQ(slurp(dir_ / "all" / "normal_0004.png"), slurp(dir_ / "late" / "normal_0004.png"));
}

// The manifest lists every file the scene read, with its hash: a scene file and the mesh it
// names, a built-in scene's data file (the files a command is not given by name).
TEST_F(TraceCli, ManifestHashesEveryFileTheSceneRead) {
  auto fnv = [](const fs::path& p) { return ptc::test::fnv1a64_hex(slurp(p)); };
  auto inputs = [](const fs::path& out) {
    std::map<std::string, std::string> in;  // absolute path -> hash
    const auto m = nlohmann::json::parse(slurp(out / "manifest.json"));
    for (const auto& i : m["inputs"])
      in[fs::path(i["absolute_path"].get<std::string>()).lexically_normal().string()] = i["fnv1a64"];
    return in;
  };
  const fs::path scene = write("scene.json", R"({"meshes": [{"file": ")" + cube_.string() + R"(", "deform": {"kind": "wave"}}]})");
  ASSERT_EQ(ptc({"trace", scene.string(), "--width", "8", "--height", "8", "--out", (dir_ / "s").string()}).code, 0);
  const auto in = inputs(dir_ / "s");
  EXPECT_EQ(in.size(), 2u);
  EXPECT_EQ(in.at(fs::absolute(scene).lexically_normal().string()), fnv(scene));
  EXPECT_EQ(in.at(fs::absolute(cube_).lexically_normal().string()), fnv(cube_));
}

// A built-in scene's data file, which the command is not given by name, with its hash.
TEST_F(TraceCli, ManifestHashesABuiltInScenesDataFile) {
  const fs::path x = "/usr/share/assimp/models/X/BCN_Epileptic.X";
  if (!fs::exists(x)) GTEST_SKIP() << x << " (Debian's assimp-testmodels) is not installed";
  ASSERT_EQ(ptc({"trace", "epileptic", "--width", "8", "--height", "8", "--out", (dir_ / "e").string()}).code, 0);
  const auto m = nlohmann::json::parse(slurp(dir_ / "e" / "manifest.json"));
  ASSERT_EQ(m["inputs"].size(), 1u);
  EXPECT_EQ(m["inputs"][0]["absolute_path"], x.string());
  EXPECT_EQ(m["inputs"][0]["fnv1a64"], ptc::test::fnv1a64_hex(slurp(x)));
}

TEST_F(TraceCli, BenchWritesEveryConfigurationPerFrame) {
  const CmdResult r = ptc({"bench", cube_.string(), "--frames", "0:1", "--width", "8", "--height", "8", "--max-count", "4",
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
  // The one thread default of every command: all cores; --threads 1 gives one-thread figures.
  EXPECT_EQ(m["parameters"]["threads"], tbb::info::default_concurrency());
  EXPECT_EQ(m["parameters"]["embree_set_affinity"], false);
  const CmdResult one = ptc({"bench", cube_.string(), "--frames", "0:1", "--width", "8", "--height", "8", "--threads", "1",
                             "--out", (dir_ / "one").string()});
  ASSERT_EQ(one.code, 0) << one.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "one" / "manifest.json"))["parameters"]["threads"], 1);
  // The whole frame includes shadow rays to the light by default; --no-shadows leaves them out.
  EXPECT_NE(r.out.find("whole frame = update + build + primary + shadow rays"), std::string::npos) << r.out;
  EXPECT_LT(r.out.find("whole frame"), r.out.find("update_ms")) << r.out;
  EXPECT_EQ(m["parameters"]["shadows"], true);
  EXPECT_EQ(m["parameters"]["light"]["from"], "default");
  const auto with = csv_rows(csv);
  ASSERT_FALSE(with.empty());
  std::uint64_t shadow_rays = 0;
  for (const auto& row : with) shadow_rays += std::stoull(row.at("shadow_rays"));
  EXPECT_GT(shadow_rays, 0u);
  const CmdResult none = ptc({"bench", cube_.string(), "--frames", "0:1", "--width", "8", "--height", "8", "--no-shadows",
                              "--out", (dir_ / "none").string()});
  ASSERT_EQ(none.code, 0) << none.err;
  EXPECT_NE(none.out.find("whole frame = update + build + primary (>"), std::string::npos) << none.out;
  for (const auto& row : csv_rows(slurp(dir_ / "none" / "bench.csv"))) {
    EXPECT_EQ(row.at("shadow_rays"), "0");
    EXPECT_EQ(row.at("shadow_ms"), "0");
  }
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "none" / "manifest.json"))["parameters"]["shadows"], false);
  EXPECT_EQ(m["parameters"]["packets"], false);
  // --packets: both sides trace in packets of 8, the same hits and shadows as single rays.
  const CmdResult packed = ptc({"bench", cube_.string(), "--frames", "0:1", "--width", "8", "--height", "8", "--packets",
                                "--out", (dir_ / "packed").string()});
  ASSERT_EQ(packed.code, 0) << packed.err;
  EXPECT_NE(packed.out.find("rays in packets (ours: 8, one per AVX2 lane; Embree: 8,"), std::string::npos) << packed.out;
  const nlohmann::json pm = nlohmann::json::parse(slurp(dir_ / "packed" / "manifest.json"));
  EXPECT_EQ(pm["parameters"]["packets"], true);
  EXPECT_EQ(pm["parameters"]["embree_shadow_hint"], "best");
  EXPECT_NE(packed.out.find("rtcOccluded8 with the faster of its coherent and incoherent flags each frame"), std::string::npos)
      << packed.out;
  // --embree-shadow-hint: one flag for Embree's shadow packets, recorded per row; usage errors
  // without packets, without shadow rays and for another value.
  const CmdResult incoherent = ptc({"bench", cube_.string(), "--frames", "0:1", "--width", "8", "--height", "8", "--packets",
                                    "--embree-shadow-hint", "incoherent", "--out", (dir_ / "incoherent").string()});
  ASSERT_EQ(incoherent.code, 0) << incoherent.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "incoherent" / "manifest.json"))["parameters"]["embree_shadow_hint"],
            "incoherent");
  for (const auto& row : csv_rows(slurp(dir_ / "incoherent" / "bench.csv"))) {
    const bool embree = row.at("config").rfind("embree_", 0) == 0;
    EXPECT_EQ(row.at("shadow_hint"), embree ? "incoherent" : "") << row.at("config");
  }
  // --shadow-order morton: recorded, the same occluded points; usage errors as the hint's.
  const CmdResult morton = ptc({"bench", cube_.string(), "--frames", "0:1", "--width", "8", "--height", "8", "--packets",
                                "--shadow-order", "morton", "--out", (dir_ / "morton").string()});
  ASSERT_EQ(morton.code, 0) << morton.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "morton" / "manifest.json"))["parameters"]["shadow_order"], "morton");
  EXPECT_EQ(pm["parameters"]["shadow_order"], "pixel");
  {
    const auto mrows = csv_rows(slurp(dir_ / "morton" / "bench.csv"));
    const auto prows = csv_rows(slurp(dir_ / "packed" / "bench.csv"));
    ASSERT_EQ(mrows.size(), prows.size());
    for (std::size_t i = 0; i < prows.size(); ++i)
      EXPECT_EQ(mrows[i].at("shadow_occluded"), prows[i].at("shadow_occluded")) << mrows[i].at("config");
  }
  struct Bad {
    std::vector<std::string> args;
    const char* name;
    const char* flag;  // the flag the one-line error names
  };
  for (const Bad& b : {Bad{{"--packets", "--shadow-order", "zigzag"}, "badorder", "--shadow-order"},
                       Bad{{"--no-shadows", "--shadow-order", "morton"}, "noshadoworder", "--shadow-order"},
                       Bad{{"--embree-shadow-hint", "coherent"}, "nopackets", "--embree-shadow-hint"},
                       Bad{{"--packets", "--no-shadows", "--embree-shadow-hint", "coherent"}, "noshadows",
                           "--embree-shadow-hint"},
                       Bad{{"--packets", "--embree-shadow-hint", "sometimes"}, "badhint", "--embree-shadow-hint"}}) {
    std::vector<std::string> argv = {"bench", cube_.string()};
    argv.insert(argv.end(), b.args.begin(), b.args.end());
    argv.insert(argv.end(), {"--out", (dir_ / b.name).string()});
    const CmdResult bad = ptc(argv);
    EXPECT_EQ(bad.code, 2) << b.name << ": " << bad.err;
    EXPECT_NE(bad.err.find(b.flag), std::string::npos) << b.name << ": " << bad.err;
    EXPECT_FALSE(fs::exists(dir_ / b.name)) << b.name;
  }
  // Embree's packet width means nothing without packets: a usage error, nothing written.
  const CmdResult width = ptc({"bench", cube_.string(), "--embree-packet-width", "16", "--out", (dir_ / "width").string()});
  EXPECT_EQ(width.code, 2) << width.err;
  EXPECT_NE(width.err.find("--embree-packet-width"), std::string::npos) << width.err;
  EXPECT_FALSE(fs::exists(dir_ / "width"));
  const auto rows = csv_rows(slurp(dir_ / "packed" / "bench.csv"));
  ASSERT_EQ(rows.size(), with.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].at("config"), with[i].at("config"));
    EXPECT_EQ(rows[i].at("hits"), with[i].at("hits")) << rows[i].at("config");
    EXPECT_EQ(rows[i].at("mismatches"), "0") << rows[i].at("config");
    EXPECT_EQ(rows[i].at("shadow_rays"), with[i].at("shadow_rays")) << rows[i].at("config");
    EXPECT_EQ(rows[i].at("shadow_occluded"), with[i].at("shadow_occluded")) << rows[i].at("config");
  }
  // --isa: our tracer's variant, recorded; the same hits, shadows and counters as with the default:
  // single rays with the baseline SSE2 variant and with AVX2, packets with AVX2 (the packet path is
  // AVX2 / AVX-512 code: --packets --isa sse2 is a usage error below).
  for (const char* isa : {"sse2", "avx2"}) {
    for (bool pk : {false, true}) {
      if (pk && std::string(isa) == "sse2") continue;
      const fs::path d = dir_ / (std::string("isa_") + isa + (pk ? "_packets" : ""));
      std::vector<std::string> args = {"bench", cube_.string(), "--frames", "0:1", "--width", "8", "--height", "8",
                                       "--isa", isa, "--out", d.string()};
      if (pk) args.push_back("--packets");  // as `packed` above
      else args.insert(args.end(), {"--max-count", "4"});  // as `with` above
      const CmdResult run = ptc(args);
      ASSERT_EQ(run.code, 0) << run.err;
      EXPECT_EQ(nlohmann::json::parse(slurp(d / "manifest.json"))["parameters"]["isa"], isa);
      const auto got = csv_rows(slurp(d / "bench.csv"));
      const auto& want = pk ? rows : with;
      ASSERT_EQ(got.size(), want.size());
      for (std::size_t i = 0; i < got.size(); ++i) {
        for (const char* col : {"config", "hits", "mismatches", "shadow_rays", "shadow_occluded"})
          EXPECT_EQ(got[i].at(col), want[i].at(col)) << isa << " " << col << " " << got[i].at("config");
        if (got[i].at("config").rfind("ours_", 0) != 0) continue;
        for (const char* col : {"nodes_per_ray", "triangles_per_ray"}) {
          EXPECT_EQ(got[i].at(col), want[i].at(col)) << isa << " " << col << " " << got[i].at("config");
        }
      }
    }
  }
  const CmdResult bad = ptc({"bench", cube_.string(), "--isa", "avx9", "--out", (dir_ / "isa_bad").string()});
  EXPECT_EQ(bad.code, 2) << bad.err;
  EXPECT_NE(bad.err.find("--isa"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir_ / "isa_bad"));
  const CmdResult sse2_packets =
      ptc({"bench", cube_.string(), "--packets", "--isa", "sse2", "--out", (dir_ / "isa_sse2_packets").string()});
  EXPECT_EQ(sse2_packets.code, 2) << sse2_packets.err;
  EXPECT_EQ(lines(sse2_packets.err), 1u) << sse2_packets.err;
  EXPECT_NE(sse2_packets.err.find("--packets"), std::string::npos) << sse2_packets.err;
  EXPECT_FALSE(fs::exists(dir_ / "isa_sse2_packets"));
}

namespace {
// The cube file and a sphere above it, with the scene's own camera: the sphere moving rigidly
// down onto the cube (moving = true), or at rest (a still scene of two static parts).
std::string box_and_ball_scene(bool moving) {
  return std::string(R"({
  "schema": "ptc-scene/1",
  "frames": [0, 9],
  "camera": {"eye": [0.5, 1.5, 5], "look_at": [0.5, 1.0, 0.5], "fov": 50},
  "meshes": [
    {"name": "box", "file": "cube.off"},
    {"name": "ball", "sphere": {"center": [0.5, 2.2, 0.5], "radius": 0.5, "levels": 2})") +
         (moving ? R"(,
     "deform": {"kind": "rigid", "amplitude": 0.1, "velocity": [0, -0.03, 0]})" : "") + R"(}
  ]
})";
}
const std::string kSceneJson = box_and_ball_scene(true);
const std::string kStillSceneJson = box_and_ball_scene(false);
// Two clusters over kSceneJson's 332 combined triangles, the cube (0..11) and the sphere
// (12..331), as DIR/triangles.csv.
void write_box_and_ball_clusters(const fs::path& dir) {
  fs::create_directories(dir);
  std::ofstream csv(dir / "triangles.csv");
  csv << "triangle_id,cluster_id\n";
  for (int t = 0; t < 332; ++t) csv << t << "," << (t < 12 ? 0 : 1) << "\n";
}
}  // namespace

// --group-trees refit (the groups' trees fixed at the rest pose and refitted): the same hits and
// shadows as the rebuilt groups, no mismatch, recorded in the manifest; a bad value is a usage
// error naming the flag.
TEST_F(TraceCli, BenchGroupTreesRefitTracesTheSameHits) {
  std::ofstream(dir_ / "scene.json") << kSceneJson;
  const std::string scene = (dir_ / "scene.json").string();
  std::vector<decltype(csv_rows(std::string()))> rows;
  for (const char* trees : {"rebuild", "refit"}) {
    const fs::path out = dir_ / trees;
    const CmdResult r = ptc({"bench", scene, "--frames", "3:5", "--width", "24", "--height", "16", "--max-count", "4",
                             "--cluster-groups", "3", "--group-trees", trees, "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.out.find(std::string("two-level, groups of <= 3 clusters, each group's tree ") +
                         (std::string(trees) == "rebuild" ? "rebuilt" : "fixed and refitted")),
              std::string::npos)
        << r.out;
    EXPECT_EQ(nlohmann::json::parse(slurp(out / "manifest.json"))["parameters"]["group_trees"], trees);
    rows.push_back(csv_rows(slurp(out / "bench.csv")));
  }
  // The plain build has no group trees, and its manifest says so.
  {
    const fs::path out = dir_ / "plain";
    const CmdResult r = ptc({"bench", scene, "--frames", "3:4", "--width", "8", "--height", "8", "--max-count", "4",
                             "--cluster-groups", "0", "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(slurp(out / "manifest.json"))["parameters"]["group_trees"], "none (plain build)");
  }
  ASSERT_EQ(rows[0].size(), rows[1].size());
  for (std::size_t i = 0; i < rows[0].size(); ++i) {
    if (rows[1][i].at("config") != "ours_clusters") continue;
    EXPECT_EQ(rows[1][i].at("hits"), rows[0][i].at("hits")) << i;
    EXPECT_EQ(rows[1][i].at("mismatches"), "0") << i;
    EXPECT_EQ(rows[1][i].at("shadow_occluded"), rows[0][i].at("shadow_occluded")) << i;
    EXPECT_EQ(rows[1][i].at("shadow_mismatches"), "0") << i;
  }
  expect_error({"bench", scene, "--group-trees", "fixed", "--out", (dir_ / "bad").string()}, 2, "--group-trees");
  expect_error({"bench", scene, "--cluster-groups", "0", "--group-trees", "refit", "--out", (dir_ / "bad").string()}, 2,
               "--group-trees: needs the two-level build");
  expect_error({"trace", scene, "--group-trees", "rebuild", "--out", (dir_ / "bad").string()}, 2, "--group-trees: needs a cluster BVH");
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

TEST_F(TraceCli, SceneFileSequenceWritesOneRowAndOneImageSetPerFrame) {
  std::ofstream(dir_ / "scene.json") << kSceneJson;
  const CmdResult r = ptc({"trace", (dir_ / "scene.json").string(), "--frames", "0:2", "--width", "20", "--height", "14",
                           "--shadows", "--out", (dir_ / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* base : {"shaded", "depth", "normal", "cost_nodes", "cost_triangles"})
    for (const char* f : {"_0000", "_0001", "_0002"})
      EXPECT_EQ(png_size(dir_ / "out" / (std::string(base) + f + ".png")), std::make_pair(20, 14)) << base << f;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "shaded.png"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "shaded_0003.png"));
  auto rows = csv_rows(slurp(dir_ / "out" / "trace.csv"));
  ASSERT_EQ(rows.size(), 6u);  // primary and shadow rows per frame
  std::erase_if(rows, [](const auto& row) { return row.at("pass") != "primary"; });
  ASSERT_EQ(rows.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(rows[i].at("frame"), std::to_string(i));
    EXPECT_EQ(rows[i].at("triangles"), "332");  // 12 + 320
    EXPECT_EQ(rows[i].at("static_triangles"), "12");
    EXPECT_EQ(rows[i].at("moving_triangles"), "320");
    EXPECT_EQ(rows[i].at("rays"), "280");
    EXPECT_GT(std::stoi(rows[i].at("hits")), 0);
    // The static BVH is built for the first frame only; the moving one is updated every frame.
    if (i == 0) {
      EXPECT_GT(std::stod(rows[i].at("static_build_ms")), 0.0);
    } else {
      EXPECT_EQ(std::stod(rows[i].at("static_build_ms")), 0.0);
      EXPECT_EQ(std::stod(rows[i].at("setup_ms")), 0.0);
    }
    EXPECT_GT(std::stod(rows[i].at("update_ms")) + std::stod(rows[i].at("build_ms")), 0.0);
  }
  const auto m = nlohmann::json::parse(slurp(dir_ / "out" / "manifest.json"));
  EXPECT_EQ(m["parameters"]["camera"]["from_scene"], true);
  EXPECT_EQ(m["parameters"]["camera"]["eye"][2], 5.0);
  EXPECT_EQ(m["parameters"]["camera"]["fov_y_deg"], 50.0);
  EXPECT_EQ(m["parameters"]["frames"], nlohmann::json::array({0, 2}));
  EXPECT_EQ(m["parameters"]["parts"][1]["static"], false);
  // --eye overrides the scene's camera; --frame picks one frame and keeps the plain names.
  const CmdResult r2 = ptc({"trace", (dir_ / "scene.json").string(), "--frame", "4", "--eye", "0.5,1,6", "--width", "8",
                            "--height", "8", "--out", (dir_ / "out2").string()});
  ASSERT_EQ(r2.code, 0) << r2.err;
  EXPECT_EQ(png_size(dir_ / "out2" / "shaded.png"), std::make_pair(8, 8));
  const auto m2 = nlohmann::json::parse(slurp(dir_ / "out2" / "manifest.json"));
  EXPECT_EQ(m2["parameters"]["camera"]["eye"][2], 6.0);
  EXPECT_EQ(csv_rows(slurp(dir_ / "out2" / "trace.csv")).at(0).at("frame"), "4");
}

TEST_F(TraceCli, BuiltinSceneSequence) {
  const CmdResult r = ptc({"trace", "cloth-sphere-32", "--frames", "0:2", "--width", "16", "--height", "12", "--out",
                           (dir_ / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  auto rows = csv_rows(slurp(dir_ / "out" / "trace.csv"));
  ASSERT_EQ(rows.size(), 3u);  // primary rows only (no --shadows)
  std::erase_if(rows, [](const auto& row) { return row.at("pass") != "primary"; });
  ASSERT_EQ(rows.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(rows[i].at("frame"), std::to_string(i));
    EXPECT_EQ(std::stoul(rows[i].at("static_triangles")) + std::stoul(rows[i].at("moving_triangles")),
              std::stoul(rows[i].at("triangles")));
    EXPECT_GT(std::stoul(rows[i].at("static_triangles")), 0u);
    EXPECT_GT(std::stoul(rows[i].at("moving_triangles")), 0u);
    EXPECT_EQ(png_size(dir_ / "out" / ("shaded_000" + std::to_string(i) + ".png")), std::make_pair(16, 12));
  }
  EXPECT_NE(r.out.find("static triangle BVH + moving triangle BVH"), std::string::npos) << r.out;
}

// A scene file's light.intensity reaches the shaded image (it was read, checked and ignored),
// also when --light moves the light; the manifest records it.
TEST_F(TraceCli, TheScenesLightIntensityShades) {
  auto shaded = [&](const std::string& light, const std::vector<std::string>& extra = {}) {
    const fs::path scene = dir_ / "lit.json";
    std::ofstream(scene) << R"({"frames": [0, 0], "light": )" << light << R"(, "meshes": [{"file": ")" << cube_.string()
                         << R"("}]})";
    std::vector<std::string> args = {"trace", scene.string(), "--width", "24", "--height", "24", "--shadows", "--out",
                                     (dir_ / "lit").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const CmdResult r = ptc(args);
    EXPECT_EQ(r.code, 0) << r.err;
    const auto m = nlohmann::json::parse(slurp(dir_ / "lit" / "manifest.json"));
    return std::pair{slurp(dir_ / "lit" / "shaded.png"), m["parameters"]["light"]};
  };
  const auto [plain, plain_light] = shaded(R"({"position": [3, 4, 5]})");
  EXPECT_EQ(plain_light["intensity"], 1.0);
  const auto [one, one_light] = shaded(R"({"position": [3, 4, 5], "intensity": 1})");
  EXPECT_EQ(one, plain);
  const auto [dim, dim_light] = shaded(R"({"position": [3, 4, 5], "intensity": 0.25})");
  EXPECT_NE(dim, plain);
  EXPECT_EQ(dim_light["intensity"], 0.25);
  const auto [off, off_light] = shaded(R"({"position": [3, 4, 5], "intensity": 0})");
  EXPECT_NE(off, dim);
  const auto [moved, moved_light] = shaded(R"({"position": [3, 4, 5], "intensity": 0.25})", {"--light", "-3,4,5"});
  EXPECT_EQ(moved_light["from"], "--light");
  EXPECT_EQ(moved_light["intensity"], 0.25);
  const auto [moved1, moved1_light] = shaded(R"({"position": [3, 4, 5]})", {"--light", "-3,4,5"});
  EXPECT_NE(moved, moved1);
}

// A directory of frames named like a scene file (`ptc animate s.json --out frames.json`) is read as
// the directory it is (it was refused: "is a directory, not a scene file").
TEST_F(TraceCli, AFrameDirectoryNamedDotJsonIsADirectory) {
  const std::string frames = (dir_ / "frames.json").string();
  ASSERT_EQ(ptc({"animate", cube_.string(), "--deform", "twist", "--frames", "0:1", "--out", frames}).code, 0);
  const CmdResult r = ptc({"trace", frames, "--frames", "0:1", "--width", "8", "--height", "8", "--out",
                           (dir_ / "t").string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "t" / "shaded_0001.png"));
}

// A frame whose positions leave the float range is named, by trace, bench and experiment alike
// (bench and experiment named the file only).
TEST_F(TraceCli, AFrameBeyondTheFloatRangeIsNamed) {
  const fs::path scene = dir_ / "fast.json";
  std::ofstream(scene) << R"({"meshes": [{"file": ")" << cube_.string()
                       << R"(", "deform": {"kind": "rigid", "velocity": [1e308, 0, 0]}}]})";
  const std::string at = scene.string() + ": frame 1: vertex ";
  for (const std::vector<std::string>& cmd :
       {std::vector<std::string>{"trace", scene.string(), "--frames", "0:3"},
        std::vector<std::string>{"bench", scene.string(), "--frames", "0:3"},
        std::vector<std::string>{"experiment", "compare", scene.string(), "--frames", "0:3", "--quiet"}}) {
    std::vector<std::string> args = cmd;
    args.insert(args.end(), {"--width", "8", "--height", "8", "--out", (dir_ / "out").string()});
    expect_error(args, 1, at);
    expect_error(args, 1, "is not finite in single precision");
  }
}

// ptc bench records the camera its rays came from as ptc trace does (it was only in argv): the same
// eye, axes and field of view for the same flags.
TEST_F(TraceCli, BenchRecordsItsCameraAsTraceDoes) {
  const std::string cube = cube_.string();
  const std::vector<std::string> view = {"--eye", "0.5,0.5,3", "--fov", "30", "--width", "8", "--height", "8"};
  auto with = [&](std::vector<std::string> a) {
    a.insert(a.end(), view.begin(), view.end());
    return a;
  };
  ASSERT_EQ(ptc(with({"bench", cube, "--deform", "twist", "--frames", "0:1", "--out", (dir_ / "b").string()})).code, 0);
  ASSERT_EQ(ptc(with({"trace", cube, "--deform", "twist", "--frames", "0:1", "--out", (dir_ / "t").string()})).code, 0);
  const auto b = nlohmann::json::parse(slurp(dir_ / "b" / "manifest.json"))["parameters"]["camera"];
  const auto t = nlohmann::json::parse(slurp(dir_ / "t" / "manifest.json"))["parameters"]["camera"];
  ASSERT_TRUE(b.is_object());
  EXPECT_EQ(b, t);
  EXPECT_EQ(b["fov_y_deg"], 30.0);
  EXPECT_EQ(b["given"]["eye"], true);
  EXPECT_EQ(b["given"]["look_at"], false);
}

TEST_F(TraceCli, BadFramesAreOneLineErrors) {
  std::ofstream(dir_ / "scene.json") << kSceneJson;
  const std::string out = (dir_ / "out").string(), scene = (dir_ / "scene.json").string();
  // A directory of two frame files: frames 0..1 only.
  fs::create_directories(dir_ / "seq");
  fs::copy_file(cube_, dir_ / "seq" / "f_0000.off");
  fs::copy_file(cube_, dir_ / "seq" / "f_0001.off");
  // Frames and ranges have one syntax and one meaning in every command; a malformed one, or one
  // outside the scene's range, is bad usage (exit 2).
  expect_error({"trace", (dir_ / "seq").string(), "--frame", "5", "--out", out}, 2, "--frame: frame 5 is outside");
  expect_error({"trace", (dir_ / "seq").string(), "--frames", "0:2", "--out", out}, 2, "--frames: frames 0:2 are outside");
  expect_error({"trace", (dir_ / "seq").string(), "--frames", "0:2", "--extend-frames", "--out", out}, 2,
               "--frames: frame 2 is beyond");
  expect_error({"trace", scene, "--frame", "abc", "--out", out}, 2, "--frame");
  expect_error({"trace", scene, "--frame", "1.5", "--out", out}, 2, "--frame");
  expect_error({"trace", scene, "--frames", "3:1", "--out", out}, 2, "--frames");
  expect_error({"trace", scene, "--frames", "0:x", "--out", out}, 2, "--frames");
  expect_error({"trace", scene, "--frame", "1", "--frames", "0:2", "--out", out}, 2, "--frame");
  expect_error({"trace", scene, "--frame", "10", "--out", out}, 2, "outside the range 0:9");
  expect_error({"trace", "no-such-scene", "--out", out}, 1, "no-such-scene");
  expect_error({"bench", scene, "--frames", "2:1", "--out", out}, 2, "--frames");
  expect_error({"bench", scene, "--frames", "5:12", "--out", out}, 2, "outside the range 0:9");
  expect_error({"bench", scene, "--deform", "twist", "--out", out}, 2, "--deform");
  // The largest int64 as a frame: refused at once (the loops to it never ended: found by a new
  // user), with --extend-frames and a deformer too; 2^53 is the largest frame number.
  const std::string cube = cube_.string();
  const std::string beyond = "--frame: frame 9223372036854775807 is beyond the largest frame number, 2^53";
  expect_error({"trace", cube, "--deform", "twist", "--frame", "9223372036854775807", "--out", out}, 2, beyond);
  expect_error({"bench", cube, "--frames", "9223372036854775807:9223372036854775807", "--out", out}, 2,
               "--frames: frame 9223372036854775807 is beyond");
  expect_error({"animate", cube, "--deform", "twist", "--frames", "0:9223372036854775807", "--out", out}, 2,
               "--frames: frame 9223372036854775807 is beyond");
  expect_error({"trace", cube, "--deform", "twist", "--frame", "9007199254740993", "--out", out}, 2, "--frame: frame 9007199254740993 is beyond");
  EXPECT_EQ(ptc({"trace", cube, "--deform", "twist", "--frame", "9007199254740992", "--width", "4", "--height", "4",
                 "--out", out})
                .code,
            0);
  // The frame directory traces fine within its range.
  EXPECT_EQ(ptc({"trace", (dir_ / "seq").string(), "--frames", "0:1", "--width", "4", "--height", "4", "--out", out}).code, 0);
}

TEST_F(TraceCli, BenchTakesPositionsFromTheScene) {
  std::ofstream(dir_ / "scene.json") << kSceneJson;
  const CmdResult r = ptc({"bench", (dir_ / "scene.json").string(), "--frames", "3:4", "--width", "8", "--height", "8",
                           "--max-count", "8", "--out", (dir_ / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = csv_rows(slurp(dir_ / "out" / "bench.csv"));
  ASSERT_EQ(rows.size(), 2u * 5u);
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("scene_frame"), std::to_string(3 + std::stoi(row.at("frame"))));
    EXPECT_EQ(row.at("mismatches"), "0") << row.at("config");
  }
  const auto m = nlohmann::json::parse(slurp(dir_ / "out" / "manifest.json"));
  EXPECT_EQ(m["parameters"]["motion"], "scene");
  EXPECT_EQ(m["results"]["triangles"], 332);
  // The medians' frames named as the table names them (scene frames; the run's first is out).
  EXPECT_NE(r.out.find("medians over frame 4 (1 frame)"), std::string::npos) << r.out;
  EXPECT_EQ(m["results"]["median_frames"], nlohmann::json::array({1, 1}));
  EXPECT_EQ(m["results"]["median_scene_frames"], nlohmann::json::array({4, 4}));
  // Vertices renumbered in the clusters' order (the default), within each part of the scene.
  EXPECT_EQ(m["parameters"]["vertex_order"], "clusters");
  EXPECT_EQ(m["results"]["fused_vertex_pass"], true);
  EXPECT_NE(r.out.find("conversion and boxes in one pass"), std::string::npos) << r.out;
  const CmdResult ri = ptc({"bench", (dir_ / "scene.json").string(), "--frames", "3:4", "--width", "8", "--height", "8",
                            "--max-count", "8", "--vertex-order", "input", "--out", (dir_ / "outi").string()});
  ASSERT_EQ(ri.code, 0) << ri.err;
  const auto rows_i = csv_rows(slurp(dir_ / "outi" / "bench.csv"));
  ASSERT_EQ(rows_i.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) EXPECT_EQ(rows_i[i].at("hits"), rows[i].at("hits"));
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "outi" / "manifest.json"))["results"]["fused_vertex_pass"], false);
  // A mesh file moves by the stand-in motion: the built-in scenes' deformer of that kind.
  const CmdResult r2 = ptc({"bench", cube_.string(), "--frames", "0:1", "--deform", "wave", "--width", "4", "--height", "4",
                            "--max-count", "4", "--out", (dir_ / "out2").string()});
  ASSERT_EQ(r2.code, 0) << r2.err;
  const auto m2 = nlohmann::json::parse(slurp(dir_ / "out2" / "manifest.json"));
  EXPECT_EQ(m2["parameters"]["motion"], "stand-in: the wave deformer (deform_preset)");
  EXPECT_EQ(m2["parameters"]["frames"], nlohmann::json::array({0, 1}));
}

TEST_F(TraceCli, SceneWithClustersOfTheCombinedMesh) {
  std::ofstream(dir_ / "scene.json") << kSceneJson;
  write_box_and_ball_clusters(dir_ / "cl");
  const CmdResult r = ptc({"trace", (dir_ / "scene.json").string(), "--clusters", (dir_ / "cl").string(), "--frames",
                           "1:2", "--width", "12", "--height", "10", "--out", (dir_ / "out").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = csv_rows(slurp(dir_ / "out" / "trace.csv"));
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("bvh"), "clusters");
  EXPECT_EQ(rows[0].at("clusters"), "2");
  EXPECT_EQ(rows[1].at("frame"), "2");
  EXPECT_NE(r.out.find("static triangle BVH + moving cluster BVH"), std::string::npos) << r.out;
  // A clustering of the cube alone does not fit the combined mesh.
  fs::remove_all(dir_ / "out");
  fs::create_directories(dir_ / "cube_cl");
  {
    std::ofstream csv(dir_ / "cube_cl" / "triangles.csv");
    csv << "triangle_id,cluster_id\n";
    for (int t = 0; t < 12; ++t) csv << t << ",0\n";
  }
  expect_error({"trace", (dir_ / "scene.json").string(), "--clusters", (dir_ / "cube_cl").string(), "--out",
                (dir_ / "out").string()},
               1, "triangles.csv");
}

// --vertex-order clusters (the method's precomputation, as in ptc bench) renumbers the scene's
// vertices: every image and every counter stay those of the file's order, over a moving sequence
// with shadows and AO and over a scene of a static and a moving part; without clusters the flag
// does nothing and is refused.
TEST_F(TraceCli, VertexOrderClustersTracesTheSameAsInput) {
  const fs::path fine = clustered_fine_mesh();
  ASSERT_FALSE(HasFailure());
  std::ofstream(dir_ / "scene.json") << kSceneJson;
  std::ofstream(dir_ / "still.json") << kStillSceneJson;
  write_box_and_ball_clusters(dir_ / "scl");
  struct Case {
    std::string name;
    std::vector<std::string> args;
    bool still = false;  // every part static: traced from the rest mesh itself (no first_positions stage)
  };
  // (That a still scene's images are those of the copy it was traced from before is what the
  // golden runs trace_triangles and trace_clusters_ao check, byte for byte.)
  const std::vector<Case> cases = {
      {"mesh", {"trace", fine.string(), "--deform", "twist", "--clusters", (dir_ / "cl").string(), "--frames", "0:3",
                "--shadows", "--ao", "2", "--width", "40", "--height", "32"}},
      {"scene", {"trace", (dir_ / "scene.json").string(), "--clusters", (dir_ / "scl").string(), "--frames", "1:2",
                 "--shadows", "--width", "24", "--height", "20"}},
      {"stillmesh", {"trace", fine.string(), "--clusters", (dir_ / "cl").string(), "--frames", "0:1", "--shadows",
                     "--ao", "2", "--width", "40", "--height", "32"}, true},
      {"stillscene", {"trace", (dir_ / "still.json").string(), "--clusters", (dir_ / "scl").string(), "--frames",
                      "1:2", "--shadows", "--width", "24", "--height", "20"}, true}};
  for (const Case& c : cases) {
    std::map<std::string, std::map<std::string, std::string>> rows[2];
    for (int k = 0; k < 2; ++k) {
      const std::string order = k == 0 ? "input" : "clusters";
      std::vector<std::string> a = c.args;
      a.insert(a.end(), {"--vertex-order", order, "--out", (dir_ / (c.name + order)).string()});
      const CmdResult r = ptc(a);
      ASSERT_EQ(r.code, 0) << r.err;
      for (const auto& row : csv_rows(slurp(dir_ / (c.name + order) / "trace.csv")))
        rows[k][row.at("frame") + "/" + row.at("pass")] = row;
      const auto m = nlohmann::json::parse(slurp(dir_ / (c.name + order) / "manifest.json"));
      EXPECT_EQ(m["parameters"]["vertex_order"], order) << c.name;
      EXPECT_EQ(m["timings_ms"].contains("renumber_vertices"), k == 1) << c.name;
      EXPECT_EQ(m["results"].contains("scene_after_renumbering"), k == 1) << c.name;
      EXPECT_EQ(m["timings_ms"].contains("first_positions"), !c.still) << c.name;
    }
    ASSERT_FALSE(rows[0].empty()) << c.name;
    ASSERT_EQ(rows[0].size(), rows[1].size()) << c.name;
    for (const auto& [key, row] : rows[0])
      for (const char* col : {"rays", "hits", "nodes_visited", "triangles_tested"})
        EXPECT_EQ(row.at(col), rows[1].at(key).at(col)) << c.name << " " << key << " " << col;
    std::size_t images = 0;
    for (const auto& e : fs::directory_iterator(dir_ / (c.name + "input")))
      if (e.path().extension() == ".png") {
        ++images;
        EXPECT_EQ(slurp(e.path()), slurp(dir_ / (c.name + "clusters") / e.path().filename())) << c.name << " " << e.path();
      }
    EXPECT_GE(images, 5u) << c.name;
  }
  expect_error({"trace", cube_.string(), "--vertex-order", "clusters", "--out", (dir_ / "out").string()}, 2,
               "--vertex-order");
  expect_error({"trace", fine.string(), "--clusters", (dir_ / "cl").string(), "--vertex-order", "sorted", "--out",
                (dir_ / "out").string()},
               2, "--vertex-order");
}

namespace {
// A vertex no triangle uses, far away (1e8 and 1e30 units): the trace frame, camera, light, ray
// offsets, the stand-in motion and animate's statistics are those of the mesh without it (found
// by a new user: at 1e8 the grid's floats collapsed to 256 of its 900 hits, at 1e30 to none,
// and the twist carried the grid 2,300 units away). Images and hits byte for byte the same.
TEST_F(TraceCli, AnUnusedVertexFarAwayChangesNothing) {
  auto grid = [&](const std::string& name, const std::string& extra) {
    std::ostringstream f;
    f << "OFF\n" << (extra.empty() ? 25 : 26) << " 32 0\n";
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 5; ++i) f << i << " " << j << " 0\n";
    if (!extra.empty()) f << extra << "\n";
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i)
        f << "3 " << j * 5 + i << " " << j * 5 + i + 1 << " " << j * 5 + i + 6 << "\n3 " << j * 5 + i << " " << j * 5 + i + 6
          << " " << j * 5 + i + 5 << "\n";
    const fs::path p = dir_ / name;
    std::ofstream(p) << f.str();
    return p.string();
  };
  struct Run {
    std::string shaded, depth, hits, bench_hits, stats;
  };
  auto run = [&](const std::string& mesh) {
    Run r;
    fs::remove_all(dir_ / "t");
    const CmdResult t = ptc({"trace", mesh, "--width", "32", "--height", "32", "--shadows", "--out", (dir_ / "t").string()});
    EXPECT_EQ(t.code, 0) << t.err;
    r.shaded = slurp(dir_ / "t" / "shaded.png");
    r.depth = slurp(dir_ / "t" / "depth.png");
    for (const auto& row : csv_rows(slurp(dir_ / "t" / "trace.csv"))) r.hits += row.at("pass") + row.at("hits") + " ";
    fs::remove_all(dir_ / "b");
    const CmdResult b = ptc({"bench", mesh, "--frames", "0:2", "--width", "32", "--height", "32", "--max-count", "8", "--out",
                             (dir_ / "b").string()});
    EXPECT_EQ(b.code, 0) << b.err;
    for (const auto& row : csv_rows(slurp(dir_ / "b" / "bench.csv"))) {
      r.bench_hits += row.at("config") + row.at("frame") + ":" + row.at("hits") + " ";
      EXPECT_EQ(row.at("mismatches"), "0") << mesh << " " << row.at("config");
    }
    fs::remove_all(dir_ / "a");
    const CmdResult a = ptc({"animate", mesh, "--deform", "twist", "--frames", "0:2", "--stats", "--out", (dir_ / "a").string()});
    EXPECT_EQ(a.code, 0) << a.err;
    r.stats = slurp(dir_ / "a" / "stats.csv");
    return r;
  };
  const Run plain = run(grid("plain.off", ""));
  EXPECT_NE(plain.hits.find("primary900 "), std::string::npos) << plain.hits;
  for (const std::string far : {"1e8 1e8 1e8", "1e30 0 0"}) {
    const Run r = run(grid("far.off", far));
    EXPECT_EQ(r.shaded, plain.shaded) << far;
    EXPECT_EQ(r.depth, plain.depth) << far;
    EXPECT_EQ(r.hits, plain.hits) << far;
    EXPECT_EQ(r.bench_hits, plain.bench_hits) << far;
    EXPECT_EQ(r.stats, plain.stats) << far;
  }
}
}  // namespace
