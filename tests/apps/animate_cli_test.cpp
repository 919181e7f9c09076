// Scene files (good and bad, errors naming the file and the JSON path), `ptc animate` round
// trips (frames written, read back with read_mesh, equal to the scene's positions bit for bit),
// --stats against an independent recomputation, bad --frames, and `ptc scenes`.
#include <algorithm>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands/animate.h"
#include "toolkit/anim/scene_file.h"
#include "toolkit/anim/cloth.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

#include "cli_harness.h"

namespace fs = std::filesystem;

namespace ptc {
namespace {

const fs::path kData = PTC_TEST_DATA;

using test::kCube;
using test::RunResult;
using test::slurp;

class Animate : public test::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    write("cube.off", kCube);
  }
};

TEST_F(Animate, RoundTripThreeFramesPlyAndObj) {
  const fs::path scene = write("twist.json", R"({"meshes": [
      {"name": "still", "file": "cube.off"},
      {"name": "twisted", "file": "cube.off", "subdivide": {"levels": 2}, "deform": {"kind": "twist", "amplitude": 1.3, "period": 7}}]})");
  for (const std::string fmt : {"ply", "obj"}) {
    const fs::path out = dir_ / ("out_" + fmt);
    const RunResult r = ptc({"animate", scene.string(), "--frames", "3:5", "--out", out.string(), "--format", fmt});
    ASSERT_EQ(r.code, 0) << r.err;
    Scene s = load_scene_file(scene);
    std::vector<Vec3> expect(s.rest().vertex_count());
    for (int f = 3; f <= 5; ++f) {
      const fs::path file = out / ("frame_000" + std::to_string(f) + "." + fmt);
      ASSERT_TRUE(fs::exists(file)) << file;
      const Mesh m = read_mesh(file).mesh;
      s.positions(f, expect);
      ASSERT_EQ(m.vertex_count(), expect.size());
      ASSERT_EQ(m.triangle_count(), s.rest().triangle_count());
      for (std::size_t i = 0; i < expect.size(); ++i) ASSERT_EQ(m.position(i), expect[i]) << fmt << " frame " << f << " v " << i;
      for (std::size_t t = 0; t < m.triangle_count(); ++t) ASSERT_EQ(m.triangle(t), s.rest().triangle(t));
    }
    EXPECT_FALSE(fs::exists(out / "frame_0002.ply"));
    EXPECT_FALSE(fs::exists(out / "frame_0006.ply"));
    const auto man = nlohmann::json::parse(slurp(out / "manifest.json"));
    EXPECT_EQ(man["schema"], "ptc-animate/1");
    EXPECT_EQ(man["results"]["files"].size(), 3u);
    EXPECT_EQ(man["results"]["parts"][0]["static"], true);
    EXPECT_EQ(man["results"]["parts"][1]["static"], false);
    EXPECT_EQ(man["results"]["parts"][1]["triangle_begin"], 12);
  }
}

TEST_F(Animate, StatsAgainstIndependentRecomputation) {
  const fs::path scene = write("rigid.json", R"({"meshes": [
      {"file": "cube.off", "deform": {"kind": "rigid", "axis": "y", "period": 8, "velocity": [0.1, 0, 0]}}]})");
  const fs::path out = dir_ / "out";
  const RunResult r = ptc({"animate", scene.string(), "--frames", "0:4", "--out", out.string(), "--stats"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("ratio_min"), std::string::npos);
  std::istringstream csv(slurp(out / "stats.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line,
            "frame,bbox_min_x,bbox_min_y,bbox_min_z,bbox_max_x,bbox_max_y,bbox_max_z,bbox_diagonal,total_area,"
            "area_ratio_min,area_ratio_mean,area_ratio_max,degenerate_at_first");
  int rows = 0;
  Scene s = load_scene_file(scene);
  std::vector<Vec3> x(s.rest().vertex_count());
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream ls(line);
    for (std::string c; std::getline(ls, c, ',');) f.push_back(c);
    ASSERT_EQ(f.size(), 13u);
    ASSERT_EQ(std::stoi(f[0]), rows);
    s.positions(rows, x);
    Box3 b;
    for (const Vec3& p : x) b.extend(p);
    EXPECT_DOUBLE_EQ(std::stod(f[1]), b.lo.x());
    EXPECT_DOUBLE_EQ(std::stod(f[5]), b.hi.y());
    // A rigid motion keeps every area: total 6 (unit cube), ratios 1.
    EXPECT_NEAR(std::stod(f[8]), 6.0, 1e-12);
    EXPECT_NEAR(std::stod(f[9]), 1.0, 1e-12);
    EXPECT_NEAR(std::stod(f[11]), 1.0, 1e-12);
    EXPECT_EQ(f[12], "0");
    ++rows;
  }
  EXPECT_EQ(rows, 5);
  // --json carries the same rows (it left them out): every value of stats.csv, frame by frame.
  const RunResult j = ptc({"animate", scene.string(), "--frames", "0:4", "--out", (dir_ / "js").string(), "--stats", "--json"});
  ASSERT_EQ(j.code, 0) << j.err;
  const nlohmann::json doc = nlohmann::json::parse(j.out);
  ASSERT_EQ(doc["stats"].size(), 5u);
  std::istringstream again(slurp(dir_ / "js" / "stats.csv"));
  std::getline(again, line);
  for (const auto& row : doc["stats"]) {
    ASSERT_TRUE(std::getline(again, line));
    std::vector<std::string> f;
    std::stringstream ls(line);
    for (std::string c; std::getline(ls, c, ',');) f.push_back(c);
    // The CSV's columns by name, value by value.
    const std::vector<std::string> names = {"frame", "bbox_min_x", "bbox_min_y", "bbox_min_z", "bbox_max_x",
                                            "bbox_max_y", "bbox_max_z", "bbox_diagonal", "total_area",
                                            "area_ratio_min", "area_ratio_mean", "area_ratio_max",
                                            "degenerate_at_first"};
    ASSERT_EQ(f.size(), names.size());
    EXPECT_EQ(row.size(), names.size());
    for (std::size_t c = 0; c < names.size(); ++c) EXPECT_EQ(row.at(names[c]).get<double>(), std::stod(f[c])) << names[c];
  }
}

TEST_F(Animate, DeformGivesAMeshFileTheStandInMotion) {
  // A mesh file moved by --deform: every frame equals the deformer's positions (computed here
  // from the rest mesh and deform_preset, not through the scene), and the frames differ.
  write("cube2.off", kCube);
  const std::string cube = (dir_ / "cube2.off").string();
  const Mesh rest = read_mesh(cube).mesh;
  for (const std::string kind : {"twist", "wave", "rigid"}) {
    const fs::path out = dir_ / ("deform_" + kind);
    const RunResult r = ptc({"animate", cube, "--deform", kind, "--frames", "5:6", "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("does not move"), std::string::npos) << r.err;
    const AnimationPtr d = make_deformer(rest, deform_preset(*parse_deform_kind(kind)));
    std::vector<Vec3> expect(rest.vertex_count());
    std::vector<Vec3> frame5;
    for (int f = 5; f <= 6; ++f) {
      const Mesh m = read_mesh(out / ("frame_000" + std::to_string(f) + ".ply")).mesh;
      d->positions(f, expect);
      ASSERT_EQ(m.vertex_count(), expect.size());
      for (std::size_t i = 0; i < expect.size(); ++i) ASSERT_EQ(m.position(i), expect[i]) << kind << " frame " << f << " v " << i;
      if (f == 5) frame5.assign(m.positions().begin(), m.positions().end());
      else EXPECT_NE(frame5, std::vector<Vec3>(m.positions().begin(), m.positions().end())) << kind;
    }
    const auto man = nlohmann::json::parse(slurp(out / "manifest.json"));
    EXPECT_NE(man["parameters"]["motion"].get<std::string>().find(kind), std::string::npos) << man["parameters"];
  }
  // Frames beyond 0..59: the motion is periodic, so no --extend-frames is needed.
  EXPECT_EQ(ptc({"animate", cube, "--deform", "twist", "--frames", "100:100", "--out", (dir_ / "late").string()}).code, 0);
  // But frames that would not fit on the disk are refused before one is written (a typo's range
  // of 10^11 frames of this cube is some 10 PB): bad usage, nothing left behind, a previous
  // output kept.
  for (const char* frames : {"0:99999999999", "5:9007199254740992"}) {  // (2^53: the largest frame)
    const RunResult huge = ptc({"animate", cube, "--deform", "twist", "--frames", frames, "--out", (dir_ / "late").string()});
    EXPECT_EQ(huge.code, 2) << huge.err;
    EXPECT_NE(huge.err.find(std::string("--frames: frames ") + frames + " ("), std::string::npos) << huge.err;
    EXPECT_NE(huge.err.find("would take at least"), std::string::npos) << huge.err;
    EXPECT_NE(huge.err.find("free"), std::string::npos) << huge.err;
    EXPECT_TRUE(fs::exists(dir_ / "late" / "frame_0100.ply"));
    for (const auto& e : fs::directory_iterator(dir_))
      EXPECT_EQ(e.path().filename().string().find(".late.tmp"), std::string::npos) << e.path();
  }
  {  // The same range as a scene file's own "frames": bad input naming the file (it blamed --frames)
    const fs::path scene = dir_ / "long.json";
    std::ofstream(scene) << R"({"frames": [0, 99999999999], "meshes": [{"file": ")" << cube
                         << R"(", "deform": {"kind": "twist"}}]})";
    const RunResult huge = ptc({"animate", scene.string(), "--out", (dir_ / "late").string()});
    EXPECT_EQ(huge.code, 1) << huge.err;
    EXPECT_NE(huge.err.find(scene.string() + ": frames: frames 0:99999999999 ("), std::string::npos) << huge.err;
    EXPECT_NE(huge.err.find("(its own range; --frames A:B takes fewer)"), std::string::npos) << huge.err;
    EXPECT_EQ(huge.err.find("--frames:"), std::string::npos) << huge.err;
    EXPECT_TRUE(fs::exists(dir_ / "late" / "frame_0100.ply"));
  }
  // Without --deform the mesh stays still, and the user is told.
  const RunResult still = ptc({"animate", cube, "--frames", "0:1", "--out", (dir_ / "still").string()});
  ASSERT_EQ(still.code, 0) << still.err;
  EXPECT_NE(still.err.find("does not move"), std::string::npos) << still.err;
  EXPECT_NE(still.err.find("--deform"), std::string::npos) << still.err;
  const Mesh still1 = read_mesh(dir_ / "still" / "frame_0001.ply").mesh;
  ASSERT_EQ(still1.vertex_count(), rest.vertex_count());
  for (std::size_t i = 0; i < rest.vertex_count(); ++i) ASSERT_EQ(still1.position(i), rest.position(i));
  // --deform none is the default; an unknown kind and a kind on an animated scene are bad usage.
  EXPECT_EQ(ptc({"animate", cube, "--deform", "none", "--frames", "0:0", "--out", (dir_ / "none").string()}).code, 0);
  EXPECT_EQ(ptc({"animate", cube, "--deform", "melt", "--out", (dir_ / "bad").string()}).code, 2);
  const fs::path scene = write("moving.json", R"({"meshes": [
      {"file": "cube.off", "deform": {"kind": "rigid", "axis": "y", "period": 8}}]})");
  const RunResult animated = ptc({"animate", scene.string(), "--deform", "twist", "--out", (dir_ / "bad").string()});
  EXPECT_EQ(animated.code, 2);
  EXPECT_NE(animated.err.find("--deform"), std::string::npos) << animated.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

// Frames that `ptc animate` wrote are traced from the view it recorded: the same pictures as the
// scene's own (found by a new user: they were framed anew, 892 hits where the scene gives 475),
// and a directory of later frames says which frames it holds. A malformed recorded camera is an
// error naming manifest.json and the element; another program's manifest.json is not read.
TEST_F(Animate, FramesKeepTheViewTheyWereAnimatedWith) {
  const std::string scene = write("tw.json", R"({"meshes": [{"file": "cube.off", "subdivide": {"levels": 2},
      "deform": {"kind": "twist", "amplitude": 1.3, "period": 7}}],
      "camera": {"eye": [2.5, 0.9, 3.1], "look_at": [0.4, 0.5, 0.5], "fov": 30}, "light": {"position": [4, 5, 6]}})")
                                .string();
  const fs::path frames = dir_ / "frames";
  ASSERT_EQ(ptc({"animate", scene, "--frames", "2:3", "--out", frames.string()}).code, 0);
  auto trace = [&](const std::string& in, const std::string& range, const char* out) {
    return ptc({"trace", in, "--frames", range, "--width", "24", "--height", "24", "--shadows", "--threads", "1", "--out",
                (dir_ / out).string()});
  };
  const RunResult from_scene = trace(scene, "2:3", "ts");
  ASSERT_EQ(from_scene.code, 0) << from_scene.err;
  const RunResult from_frames = trace(frames.string(), "0:1", "tf");
  ASSERT_EQ(from_frames.code, 0) << from_frames.err;
  for (const auto& [f, g] : {std::pair{"shaded_0002.png", "shaded_0000.png"}, {"depth_0003.png", "depth_0001.png"}})
    EXPECT_EQ(slurp(dir_ / "ts" / f), slurp(dir_ / "tf" / g)) << f << " vs " << g;
  EXPECT_NE(from_frames.err.find("holds frames 2..3 of '" + scene + "' (ptc animate); they are read as frames 0..1"),
            std::string::npos)
      << from_frames.err;
  const auto m = nlohmann::json::parse(slurp(dir_ / "tf" / "manifest.json"));
  EXPECT_EQ(m["parameters"]["camera"]["from_scene"], true);
  bool manifest_read = false;
  for (const auto& in : m["inputs"]) manifest_read = manifest_read || in["path"] == (frames / "manifest.json").string();
  EXPECT_TRUE(manifest_read) << m["inputs"];
  // A broken recorded camera: named.
  auto man = nlohmann::json::parse(slurp(frames / "manifest.json"));
  man["results"]["camera"]["fov"] = 180;
  std::ofstream(frames / "manifest.json") << man.dump(2);
  RunResult bad = trace(frames.string(), "0:1", "tb");
  EXPECT_EQ(bad.code, 1) << bad.err;
  EXPECT_NE(bad.err.find((frames / "manifest.json").string()), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("results.camera.fov"), std::string::npos) << bad.err;
  // A recorded flag that is not true or false: named too (the recorded camera was dropped silently)
  man["results"]["camera"]["fov"] = 45;
  man["results"]["camera_own"] = "yes";
  std::ofstream(frames / "manifest.json") << man.dump(2);
  bad = trace(frames.string(), "0:1", "tb");
  EXPECT_EQ(bad.code, 1) << bad.err;
  EXPECT_NE(bad.err.find("results.camera_own: expected true or false"), std::string::npos) << bad.err;
  man["results"]["camera_own"] = true;
  // Another schema (or none): the frames are framed as any directory's, without a word on it.
  man["schema"] = "someone-else/1";
  std::ofstream(frames / "manifest.json") << man.dump(2);
  const RunResult foreign = trace(frames.string(), "0:1", "tg");
  ASSERT_EQ(foreign.code, 0) << foreign.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "tg" / "manifest.json"))["parameters"]["camera"]["from_scene"], false);
  EXPECT_EQ(foreign.err.find("ptc animate"), std::string::npos) << foreign.err;
  // A mesh file's frames: its view was the defaults, which a command replaces by its own framing
  // (results.camera_own false), so the frames trace as the mesh with --deform does (review).
  const fs::path mesh_frames = dir_ / "mesh_frames";
  ASSERT_EQ(ptc({"animate", (dir_ / "cube.off").string(), "--deform", "twist", "--frames", "0:1", "--out",
                 mesh_frames.string()})
                .code,
            0);
  const auto mm = nlohmann::json::parse(slurp(mesh_frames / "manifest.json"));
  EXPECT_EQ(mm["results"]["camera_own"], false);
  EXPECT_EQ(mm["results"]["light_own"], false);
  ASSERT_EQ(trace(mesh_frames.string(), "0:1", "tm").code, 0);
  ASSERT_EQ(ptc({"trace", (dir_ / "cube.off").string(), "--deform", "twist", "--frames", "0:1", "--width", "24",
                 "--height", "24", "--shadows", "--threads", "1", "--out", (dir_ / "tmd").string()})
                .code,
            0);
  for (const char* f : {"shaded_0000.png", "shaded_0001.png"}) EXPECT_EQ(slurp(dir_ / "tm" / f), slurp(dir_ / "tmd" / f)) << f;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "tm" / "manifest.json"))["parameters"]["camera"]["from_scene"], false);
}

TEST_F(Animate, BadFramesAndUsage) {
  const fs::path out = dir_ / "out";
  const std::string cube = (dir_ / "cube.off").string();
  for (const std::string bad : {"5:2", "a:b", "1:", ":3", "-1:2", "1.5:3", "2:3:4", ""}) {
    const RunResult r = ptc({"animate", cube, "--frames", bad, "--out", out.string()});
    EXPECT_TRUE(r.code == 1 || r.code == 2) << "'" << bad << "' exit " << r.code;
    EXPECT_NE(r.err.find("--frames"), std::string::npos) << "'" << bad << "': " << r.err;
    EXPECT_FALSE(fs::exists(out)) << bad;
  }
  EXPECT_EQ(ptc({"animate", cube, "--frames", "0:1"}).code, 2);  // no --out
  const RunResult unknown = ptc({"animate", "no-such-scene", "--out", out.string()});
  EXPECT_EQ(unknown.code, 1);
  EXPECT_NE(unknown.err.find("no-such-scene"), std::string::npos);
  EXPECT_EQ(ptc({"animate", cube, "--out", out.string(), "--format", "stl"}).code, 2);
}

TEST_F(Animate, FramesBeyondAFiniteSource) {
  // A directory of three frame files is a finite source (frames 0..2).
  const fs::path frames = dir_ / "frames";
  fs::create_directories(frames);
  const Mesh cube = read_mesh(dir_ / "cube.off").mesh;
  for (int f = 0; f < 3; ++f) {
    std::vector<Vec3> p(cube.positions().begin(), cube.positions().end());
    for (Vec3& q : p) q.x() += f;
    std::string name = "f";
    name += std::to_string(f) + ".off";
    write_mesh(frames / name, cube.with_positions(p));
  }
  const fs::path out = dir_ / "out";
  const RunResult beyond = ptc({"animate", frames.string(), "--frames", "1:3", "--out", out.string()});
  EXPECT_EQ(beyond.code, 2) << beyond.err;  // frames the scene does not have: bad usage
  EXPECT_NE(beyond.err.find("--frames"), std::string::npos) << beyond.err;
  EXPECT_NE(beyond.err.find("0:2"), std::string::npos) << beyond.err;  // names the scene's range
  // --extend-frames cannot go past a finite source either.
  const RunResult past = ptc({"animate", frames.string(), "--frames", "1:3", "--extend-frames", "--out", out.string()});
  EXPECT_EQ(past.code, 2) << past.err;
  EXPECT_NE(past.err.find("beyond the last frame"), std::string::npos) << past.err;
  EXPECT_FALSE(fs::exists(out));
  const RunResult ok = ptc({"animate", frames.string(), "--frames", "0:2", "--out", out.string()});
  ASSERT_EQ(ok.code, 0) << ok.err;
  for (int f = 0; f < 3; ++f) {
    const Mesh m = read_mesh(out / ("frame_000" + std::to_string(f) + ".ply")).mesh;
    for (std::size_t i = 0; i < m.vertex_count(); ++i) ASSERT_EQ(m.position(i), cube.position(i) + Vec3(f, 0, 0));
  }
}

TEST_F(Animate, ScenesListing) {
  const RunResult r = ptc({"scenes", "--json", "cloth-sphere-32", "armadillo-twist", "--data-dir", kData.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["schema"], "ptc-scenes/1");
  ASSERT_EQ(j["scenes"].size(), 2u);
  // cloth 2 (n-1)^2 + icosphere 20 * 4^4 + floor 2.
  EXPECT_EQ(j["scenes"][0]["triangles"], 2 * 31 * 31 + 20 * 256 + 2);
  EXPECT_EQ(j["scenes"][0]["static_parts"], 2);
  EXPECT_EQ(j["scenes"][1]["triangles"], read_mesh(kData / "meshes/armadillo.off").mesh.triangle_count());
  EXPECT_EQ(j["scenes"][1]["frames"][1], 59);
  // A scene asked for by name that cannot be made: listed as unavailable, and a failure (exit 1,
  // one line naming it), as in the commands that would trace it; the whole listing still exits 0.
  const RunResult missing = ptc({"scenes", "armadillo-twist", "--data-dir", "/nonexistent/d"});
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.out.find("unavailable"), std::string::npos);
  EXPECT_NE(missing.out.find("/nonexistent/d"), std::string::npos);
  EXPECT_NE(missing.err.find("ptc: error: armadillo-twist: unavailable"), std::string::npos) << missing.err;
  EXPECT_EQ(std::count(missing.err.begin(), missing.err.end(), '\n'), 1) << missing.err;
  const RunResult all = ptc({"scenes", "--data-dir", "/nonexistent/d"});
  EXPECT_EQ(all.code, 0) << all.err;
  EXPECT_NE(all.out.find("unavailable"), std::string::npos);
  EXPECT_EQ(ptc({"scenes", "bogus"}).code, 1);
}

}  // namespace
}  // namespace ptc
