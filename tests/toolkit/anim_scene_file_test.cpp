// Scene files (toolkit/anim/scene_file.h): every key, and errors naming the file and the JSON
// path of the offending element.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "common/temp_dir.h"
#include "toolkit/anim/cloth.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/scene_file.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace fs = std::filesystem;

namespace ptc {
namespace {

const fs::path kData = PTC_TEST_DATA;

constexpr const char* kCube =
    "OFF\n8 12 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
    "3 0 2 1\n3 1 2 3\n3 4 5 6\n3 5 7 6\n3 0 1 4\n3 1 5 4\n3 2 6 3\n3 3 6 7\n3 0 4 2\n3 2 4 6\n3 1 3 5\n3 3 7 5\n";

class SceneFile : public test::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    write("cube.off", kCube);
  }
  fs::path write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    test::spit(p, text);
    return p;
  }
  // Error message of parsing `json` as a scene file (empty when it parses).
  std::string scene_error(const std::string& json) const {
    const fs::path p = write("scene.json", json);
    try {
      (void)load_scene_file(p);
    } catch (const InputError& e) {
      return e.what();
    }
    return {};
  }
};

// ---------------------------------------------------------------------------------------------
// Scene files

TEST_F(SceneFile, SceneFileGood) {
  const fs::path p = write("good.json", R"({
    "schema": "ptc-scene/1",
    "name": "mine",
    "frames": [2, 5],
    "camera": {"eye": [0, 1, 5], "look_at": [0, 0, 0], "fov": 30},
    "light": {"position": [3, 3, 3], "intensity": 2},
    "meshes": [
      {"name": "floor", "file": "cube.off"},
      {"name": "spin", "file": "cube.off", "subdivide": {"scheme": "loop", "levels": 1},
       "deform": {"kind": "rigid", "axis": "z", "period": 10}},
      {"name": "ball", "sphere": {"center": [0, 3, 0], "radius": 0.5, "levels": 1}},
      {"name": "sheet", "cloth": {"resolution": 5, "substeps": 2}},
      {"name": "arm", "file": "${data}/meshes/cube.off", "deform": {"kind": "wave", "axis": "x", "direction": "y", "amplitude": 0.1}}
    ]
  })");
  SceneOptions o;
  o.data_dir = kData;
  Scene s = load_scene_file(p, o);
  EXPECT_EQ(s.name(), "mine");
  ASSERT_EQ(s.part_count(), 5u);
  EXPECT_TRUE(s.is_static(0));
  EXPECT_FALSE(s.is_static(1));
  EXPECT_TRUE(s.is_static(2));
  EXPECT_FALSE(s.is_static(3));
  EXPECT_FALSE(s.is_static(4));
  EXPECT_EQ(s.triangle_offset(1), 12u);
  EXPECT_EQ(s.triangle_offset(2), 12u + 48u);        // Loop, one level
  EXPECT_EQ(s.triangle_offset(3), 60u + 80u);        // icosphere, one level
  EXPECT_EQ(s.triangle_offset(4), 140u + 2 * 4 * 4);  // 5 x 5 cloth
  EXPECT_EQ(s.frames().first, 2);
  EXPECT_EQ(s.frames().last, 5);
  EXPECT_EQ(s.camera().eye, Vec3(0, 1, 5));
  EXPECT_EQ(s.camera().fov_deg, 30);
  EXPECT_EQ(s.light().intensity, 2);
  // The cloth part is the cloth asked for: same positions as a ClothSimulation made here.
  ClothParams cp;
  cp.resolution = 5;
  cp.substeps = 2;
  ClothSimulation ref(cp);
  std::vector<Vec3> all(s.rest().vertex_count()), own(ref.rest().vertex_count());
  s.positions(4, all);
  ref.positions(4, own);
  for (std::size_t i = 0; i < own.size(); ++i) ASSERT_EQ(all[s.vertex_offset(3) + i], own[i]);
}

// "clusters": {"max_count": N} is the scene's own cluster size (what `ptc bench` clusters it with
// when given no --max-count): read exactly, absent without the key, refused outside [0, 2^20] or
// when not a whole number, kept by the stand-in motion of a static scene.
TEST_F(SceneFile, TheScenesOwnClusterSize) {
  const auto scene_with = [&](const std::string& clusters) {
    return load_scene_file(write("c.json", R"({"meshes": [{"file": "cube.off"}])" + clusters + "}"));
  };
  EXPECT_FALSE(scene_with("").cluster_max_count().has_value());
  for (const std::uint32_t n : {0u, 1u, 24u, kMaxSceneClusterCount}) {
    const Scene s = scene_with(R"(, "clusters": {"max_count": )" + std::to_string(n) + "}");
    ASSERT_TRUE(s.cluster_max_count().has_value()) << n;
    EXPECT_EQ(*s.cluster_max_count(), n);
    EXPECT_EQ(deform_scene(s, deform_preset(DeformKind::Twist)).cluster_max_count(), s.cluster_max_count());
  }
  const std::string f = (dir_ / "scene.json").string();
  const std::pair<const char*, const char*> bad[] = {
      {R"({"max_count": -1})", "clusters.max_count: -1 is outside [0, 1048576]"},
      {R"({"max_count": 1048577})", "clusters.max_count: 1048577 is outside [0, 1048576]"},
      {R"({"max_count": 24.5})", "clusters.max_count: expected an integer"},
      {R"({"max_count": "24"})", "clusters.max_count: expected an integer"},
      {R"({})", "clusters.max_count: missing"},
      {R"({"max_count": 24, "max_size": 24})", "clusters.max_size"},
      {R"(24)", "clusters"},
  };
  for (const auto& [value, want] : bad) {
    const std::string e = scene_error(R"({"meshes": [{"file": "cube.off"}], "clusters": )" + std::string(value) + "}");
    EXPECT_NE(e.find(f), std::string::npos) << e;
    EXPECT_NE(e.find(want), std::string::npos) << value << " -> " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;  // (one line)
  }
}

// A glob in `file` is a frame sequence, as on the command line (it was read as one mesh file
// named with the '*').
TEST_F(SceneFile, AGlobIsAFrameSequence) {
  fs::create_directories(dir_ / "frames");
  const std::string moved =
      "OFF\n8 12 0\n0 0 2\n1 0 2\n0 1 2\n1 1 2\n0 0 3\n1 0 3\n0 1 3\n1 1 3\n"
      "3 0 2 1\n3 1 2 3\n3 4 5 6\n3 5 7 6\n3 0 1 4\n3 1 5 4\n3 2 6 3\n3 3 6 7\n3 0 4 2\n3 2 4 6\n3 1 3 5\n3 3 7 5\n";
  write("frames/f_0.off", kCube);
  write("frames/f_1.off", moved);
  for (const std::string glob : {"frames/f_*.off", "frames/f_?.off"}) {
    Scene s = load_scene_file(write("glob.json", R"({"meshes": [{"file": ")" + glob + R"("}]})"));
    EXPECT_FALSE(s.all_static()) << glob;
    EXPECT_EQ(s.frames().last, 1) << glob;
    std::vector<Vec3> p(s.rest().vertex_count());
    s.positions(1.0, p);
    EXPECT_EQ(p[0], Vec3(0, 0, 2)) << glob;
  }
}

// A frame read later (a sequence reads each file when asked) that is bad keeps the scene file
// and the entry's JSON path in its error, before the frame file's own message.
TEST_F(SceneFile, ALateFrameErrorNamesTheSceneEntry) {
  fs::create_directories(dir_ / "mixed");
  write("mixed/f_0.off", kCube);
  write("mixed/f_1.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");  // another vertex count
  const fs::path scene = write("lazy.json", R"({"meshes": [{"file": "cube.off"}, {"file": "mixed"}]})");
  Scene s = load_scene_file(scene);
  std::vector<Vec3> p(s.rest().vertex_count());
  try {
    s.positions(1.0, p);
    FAIL() << "a frame of another vertex count was read";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(scene.string() + ": meshes[1].file: ", 0), 0u) << m;
    EXPECT_NE(m.find("f_1.off"), std::string::npos) << m;
  }
}

TEST_F(SceneFile, SceneFileErrorsNameFileAndJsonPath) {
  const std::string f = (dir_ / "scene.json").string();
  auto has = [&](const std::string& msg, const std::string& part) {
    EXPECT_NE(msg.find(part), std::string::npos) << "message: " << msg << "\nexpected to contain: " << part;
  };
  std::string e;
  e = scene_error(R"({"meshes": [{"file": "cube.off"}, {"file": "cube.off", "deform": {"kind": "twist", "amplitude": "big"}}]})");
  has(e, f);
  has(e, "meshes[1].deform.amplitude");
  has(e, "expected a number");
  // A number beyond double is invalid JSON with its position, not an escaped library exception
  // (found by the scene_json fuzz target: tests/fuzz_inputs/scene_json/number_overflow_1e999).
  e = scene_error(R"({"frames": [0, 1e999]})");
  has(e, f + ": byte 15: invalid JSON: number overflow parsing '1e999'");  // (offsets count from 0)
  e = scene_error("");  // an empty file: byte 0 (it said byte 1)
  has(e, f + ": byte 0: invalid JSON");
  e = scene_error("{\"frames\": [0, 1]");  // cut short after 17 bytes: at its end, offset 17
  has(e, f + ": byte 17: invalid JSON");
  e = scene_error(R"({"meshes": [{"file": "cube.off", "deform": {"kind": "wobble"}}]})");
  has(e, "meshes[0].deform.kind");
  e = scene_error(R"({"meshes": [{"file": "cube.off", "deform": {"kind": "bend", "axis": "y", "direction": "y"}}]})");
  has(e, "meshes[0].deform");
  has(e, "direction must differ");
  e = scene_error(R"({"meshes": [{"file": "missing.off"}]})");
  has(e, f);
  has(e, "meshes[0].file");
  has(e, "missing.off");
  e = scene_error(R"({"meshes": [{"cloth": {"resolution": 1}}]})");
  has(e, "meshes[0].cloth");
  has(e, "resolution must be >= 2");
  // said once: file and path, then the reason (they were repeated, "f: meshes[0].cloth: f: meshes[0].cloth: ...")
  EXPECT_EQ(e.find(f), e.rfind(f)) << e;
  EXPECT_EQ(e.find("meshes[0].cloth"), e.rfind("meshes[0].cloth")) << e;
  e = scene_error(R"({"meshes": [{"cloth": {"resolution": 0}}]})");
  EXPECT_EQ(e.find("meshes[0].cloth"), e.rfind("meshes[0].cloth")) << e;
  e = scene_error(R"({"meshes": [{"file": "cube.off", "colour": "red"}]})");
  has(e, "meshes[0].colour");
  has(e, "unknown key");
  e = scene_error(R"({"meshes": [{"file": "cube.off", "cloth": {}}]})");
  has(e, "needs exactly one of");
  e = scene_error(R"({"meshes": [{"file": "cube.off"}], "meshes": [{"file": "nope.off"}]})");
  has(e, f);
  has(e, "key \"meshes\": given twice in one object");
  e = scene_error(R"({"meshes": [{"file": "cube.off", "deform": {"kind": "twist", "kind": "wave"}}]})");
  has(e, "key \"kind\": given twice");
  // Whole numbers beyond 64 bits: out of range (2^64 - 1 was wrapped to -1 before).
  e = scene_error(R"({"meshes": [{"file": "cube.off"}], "frames": [0, 18446744073709551615]})");
  has(e, "frames[1]: 18446744073709551615 is out of the 64-bit integer range");
  e = scene_error(R"({"meshes": [{"file": "cube.off"}], "frames": [0, 99999999999999999999]})");
  has(e, "is out of the 64-bit integer range");
  // The largest int64 as the last frame: refused (the frame loops to it never ended), 2^53 taken
  e = scene_error(R"({"meshes": [{"file": "cube.off"}], "frames": [0, 9223372036854775807]})");
  has(e, "frames[1]: frame numbers go up to 2^53 = 9007199254740992");
  e = scene_error(R"({"meshes": [{"file": "cube.off"}], "frames": [0, 9007199254740993]})");
  has(e, "frames[1]: frame numbers go up to 2^53");
  // A deform key the kind does not read, and a part name given twice.
  e = scene_error(R"({"meshes": [{"file": "cube.off", "deform": {"kind": "twist", "velocity": [1, 0, 0]}}]})");
  has(e, f);
  has(e, "meshes[0].deform.velocity: not used by the twist deformer (it reads kind, amplitude, axis, period)");
  e = scene_error(R"({"meshes": [{"file": "cube.off", "deform": {"kind": "explode", "axis": "x"}}]})");
  has(e, "meshes[0].deform.axis: not used by the explode deformer");
  e = scene_error(R"({"meshes": [{"name": "a", "file": "cube.off"}, {"name": "a", "file": "cube.off"}]})");
  has(e, f);
  has(e, "meshes[1].name: 'a' is the name of meshes[0] too");
  // Finite numbers whose results overflow: named in the file, not blamed on a flag later.
  e = scene_error(R"({"meshes": [{"sphere": {"radius": 1e308, "center": [1e308, 0, 0]}}]})");
  has(e, f);
  has(e, "meshes[0]: its rest positions are not finite");
  e = scene_error(R"({"meshes": [{"file": "cube.off"}], "camera": {"eye": [1e308, 0, 5], "look_at": [-1e308, 0, 0]}})");
  has(e, f);
  has(e, "camera: eye, look_at and up must be within double's range");
    e = scene_error(R"({"meshes": []})");
  has(e, "meshes");
  e = scene_error(R"({"frames": [5, 2], "meshes": [{"file": "cube.off"}]})");
  has(e, "frames[1]");
  e = scene_error(R"({"camera": {"eye": [0, 0, 1], "look_at": [0, 0, 1]}, "meshes": [{"file": "cube.off"}]})");
  has(e, "camera");
  e = scene_error(R"({"camera": {"eye": [0, 0], "look_at": [0, 0, 1]}, "meshes": [{"file": "cube.off"}]})");
  has(e, "camera.eye");
  e = scene_error(R"({"meshes": [{"file": "cube.off"}], "schema": "ptc-scene/9"})");
  has(e, "schema");
  e = scene_error("{\"meshes\": [{\"file\": \"cube.off\"}");  // truncated
  has(e, f);
  has(e, "byte");
  has(e, "invalid JSON");
  e = scene_error("[1, 2]");
  has(e, "expected an object");
  // Loop on a non-manifold mesh: the subdivider's reason under the entry's path.
  write("book.off", "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 -1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n3 0 1 4\n");
  e = scene_error(R"({"meshes": [{"file": "book.off", "subdivide": {"scheme": "loop"}}]})");
  has(e, "meshes[0].subdivide");
  try {
    (void)load_scene_file(dir_ / "nope.json");
    FAIL();
  } catch (const InputError& err) {
    has(err.what(), (dir_ / "nope.json").string());
  }
}

// ---------------------------------------------------------------------------------------------
// ptc animate

}  // namespace
}  // namespace ptc
