// Every subcommand as a library call (commands/), in-process: what it writes against an
// independent answer (the library computed directly, brute-force ray casting, the mesh read
// back), and its usage errors as UsageError naming the flag. The binary tests (tests/apps) are
// the extra layer on top.
#include <gtest/gtest.h>

#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "bvh/box.h"
#include "commands/animate.h"
#include "commands/bench.h"
#include "commands/commands.h"
#include "commands/scenes.h"
#include "commands/trace.h"
#include "common/brute_force.h"
#include "common/csv_rows.h"
#include "common/temp_dir.h"
#include "common/usage_flag.h"
#include "render/camera.h"
#include "toolkit/anim/scene_file.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/mesh_report.h"
#include "toolkit/mesh/subdivision.h"
#include "viz/png.h"

namespace fs = std::filesystem;

namespace ptc {
namespace {

using test::csv_rows;
using test::slurp;

const fs::path kMeshes = fs::path(PTC_TEST_DATA) / "meshes";

class Commands : public test::TempDirTest {};

using test::usage_flag;

TEST_F(Commands, InfoJsonCountsTheMesh) {
  std::ostringstream out;
  cmd_info({kMeshes / "elephant.off", true}, out);
  const auto j = nlohmann::json::parse(out.str());
  const LoadedMesh lm = read_mesh(kMeshes / "elephant.off");
  const MeshReport r = analyze_mesh(lm.mesh);
  EXPECT_EQ(j["triangles"], lm.mesh.triangle_count());
  EXPECT_EQ(j["vertices"], lm.mesh.vertex_count());
  EXPECT_EQ(j["edges"], r.edges);
  EXPECT_EQ(j["boundary_edges"], r.boundary_edges);
  EXPECT_EQ(j["triangle_area"]["p50"], r.triangle_area.p50);
}

TEST_F(Commands, SubdivideWritesWhatTheSubdividerGives) {
  SubdivideOptions o;
  o.input = kMeshes / "cross.off";
  o.output = dir_ / "cross2.ply";
  o.levels = 2;
  o.scheme = SubdivisionScheme::Loop;
  std::ostringstream out;
  cmd_subdivide(o, out);
  const Mesh got = read_mesh(o.output).mesh;
  const Mesh want = subdivide(read_mesh(o.input).mesh, SubdivisionScheme::Loop, 2);
  ASSERT_EQ(got.triangle_count(), want.triangle_count());
  ASSERT_EQ(got.vertex_count(), want.vertex_count());
  for (std::size_t v = 0; v < want.vertex_count(); ++v) ASSERT_EQ(got.position(v), want.position(v)) << v;
  for (std::size_t t = 0; t < want.triangle_count(); ++t) ASSERT_EQ(got.triangle(t), want.triangle(t)) << t;
  // The output never replaces the input, and STL is not written.
  o.output = o.input;
  EXPECT_EQ(usage_flag([&] { cmd_subdivide(o, out); }), "--out");
  o.output = dir_ / "x.stl";
  EXPECT_EQ(usage_flag([&] { cmd_subdivide(o, out); }), "--out");
}

TEST_F(Commands, SpheresExactMethodHasNoError) {
  SpheresOptions o;
  o.input = kMeshes / "elephant.off";
  o.out_dir = dir_ / "s";
  o.config.repeats = 1;
  o.config.methods = {SphereMethod::Exact, SphereMethod::Ritter};
  std::ostringstream out;
  cmd_spheres(o, out);
  const auto rows = csv_rows(slurp(dir_ / "s" / "spheres.csv"));
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("method"), "exact");
  EXPECT_EQ(std::stod(rows[0].at("rel_err_max")), 0.0);
  EXPECT_EQ(rows[0].at("not_containing"), "0");
  EXPECT_GE(std::stod(rows[1].at("rel_err_mean")), 0.0);  // Ritter's sphere is never smaller
  const auto m = nlohmann::json::parse(slurp(dir_ / "s" / "manifest.json"));
  EXPECT_EQ(m["output_schemas"]["spheres.csv"], "ptc-spheres/1");
  EXPECT_EQ(m["output_schemas"]["sphere_sets.csv"], "ptc-sphere-sets/1");
}

TEST_F(Commands, ClusterWritesTheLibrarysClustering) {
  ClusterOptions o;
  o.input = kMeshes / "mushroom.off";
  o.out_dir = dir_ / "c";
  o.config.method = ClusterMethod::Growth;
  o.config.max_count = 30;
  o.config.max_size = 30;
  std::ostringstream out;
  cmd_cluster(o, out);
  const Clustering want = cluster_mesh(read_mesh(o.input).mesh, o.config);
  const auto label = want.cluster_of_triangle();
  const auto rows = csv_rows(slurp(dir_ / "c" / "triangles.csv"));
  ASSERT_EQ(rows.size(), label.size());
  for (std::size_t t = 0; t < label.size(); ++t) {
    ASSERT_EQ(std::stoul(rows[t].at("triangle_id")), t);
    ASSERT_EQ(std::stoul(rows[t].at("cluster_id")), label[t]) << t;
  }
  EXPECT_EQ(csv_rows(slurp(dir_ / "c" / "clusters.csv")).size(), want.cluster_count());
  const auto m = nlohmann::json::parse(slurp(dir_ / "c" / "manifest.json"));
  EXPECT_EQ(m["parameters"]["start"], "spatial");  // growth reads it
  EXPECT_FALSE(m["parameters"].contains("target_clusters"));  // contraction only
}

TEST_F(Commands, ClusterRefusesWhatTheMethodDoesNotUse) {
  ClusterConfig c;
  c.method = ClusterMethod::SahSplit;
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {"objective"}); }), "--objective");
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {"max_size"}); }), "--max-size");
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {"max_count", "max_triangles"}); }), "");
  c.method = ClusterMethod::Growth;
  c.objective = ObjectiveKind::Naive;
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {"max_size"}); }), "--max-size");
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {"start"}); }), "");
  c.max_count = 2;  // Naive's vertex limit must let any triangle in
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {}); }), "--max-count");
  c.max_count = 50;
  c.method = ClusterMethod::Meshopt;
  c.max_count = 1000;  // meshoptimizer 0.18 takes at most 255 vertices
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {}); }), "--max-count");
  c.method = ClusterMethod::Growth;
  c.max_count = 50;
  c.objective = ObjectiveKind::Acc;
  c.max_count = 0;
  c.max_size = 5;
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {}); }), "--max-count");
  c.max_size = 0;  // both 0: one triangle per cluster, nothing else is read
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {}); }), "");
  EXPECT_EQ(usage_flag([&] { check_cluster_options(c, {"objective"}); }), "--objective");
}

const char* const kScene = R"({"schema": "ptc-scene/1", "frames": [0, 5],
  "meshes": [{"name": "ball", "file": "MESHES/sphere.off",
              "deform": {"kind": "twist", "axis": "y", "amplitude": 1.0, "period": 12}}]})";

fs::path write_scene(const fs::path& dir) {
  std::string s = kScene;
  s.replace(s.find("MESHES"), 6, kMeshes.string());
  test::spit(dir / "scene.json", s);
  return dir / "scene.json";
}

TEST_F(Commands, AnimateWritesTheScenesPositions) {
  AnimateOptions o;
  o.scene = write_scene(dir_).string();
  o.out_dir = dir_ / "a";
  o.frames = "2:4";
  std::ostringstream out;
  cmd_animate(o, out);
  Scene scene = load_scene_file(o.scene);
  std::vector<Vec3> p(scene.rest().vertex_count());
  for (int f = 2; f <= 4; ++f) {
    scene.positions(f, p);
    const Mesh got = read_mesh(dir_ / "a" / ("frame_000" + std::to_string(f) + ".ply")).mesh;
    ASSERT_EQ(got.vertex_count(), p.size());
    for (std::size_t v = 0; v < p.size(); ++v) ASSERT_EQ(got.position(v), p[v]) << "frame " << f << " vertex " << v;
  }
  EXPECT_FALSE(fs::exists(dir_ / "a" / "frame_0005.ply"));
  // Frames outside the scene's range need --extend-frames; a malformed range is bad usage.
  o.frames = "4:9";
  EXPECT_EQ(usage_flag([&] { cmd_animate(o, out); }), "--frames");
  o.extend_frames = true;
  EXPECT_EQ(usage_flag([&] { cmd_animate(o, out); }), "");  // a deformer gives any frame
  o.frames = "5:2";
  EXPECT_EQ(usage_flag([&] { cmd_animate(o, out); }), "--frames");
}

TEST_F(Commands, ScenesListsWhatTheSceneHas) {
  ScenesOptions o;
  o.names = {"cloth-sphere-32"};
  o.json = true;
  std::ostringstream out;
  cmd_scenes(o, out);
  const auto j = nlohmann::json::parse(out.str());
  const Scene s = make_builtin_scene("cloth-sphere-32");
  ASSERT_EQ(j["scenes"].size(), 1u);
  EXPECT_EQ(j["scenes"][0]["triangles"], s.rest().triangle_count());
  EXPECT_EQ(j["scenes"][0]["frames"], nlohmann::json::array({s.frames().first, s.frames().last}));
  o.names = {"no-such-scene"};
  EXPECT_THROW(cmd_scenes(o, out), InputError);
}

// The primary hits of `ptc trace` and `ptc bench` against a brute-force loop over all
// triangles, ray by ray, for the same camera.
std::uint64_t brute_force_hits(const Mesh& m, const CameraSpec& spec, int w, int h) {
  const bvh::PinholeCamera cam = make_camera(spec, m.bounds(), w, h);
  const bvh::RayBatch rays = camera_rays(cam, w, h);
  const Vec3 frame = m.bounds().center();
  std::uint64_t hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Vec3 org(rays.ox[i], rays.oy[i], rays.oz[i]);
    const bvh::Vec3f dir{rays.dx[i], rays.dy[i], rays.dz[i]};
    hits += bvh::test::brute_force(m, frame, org, dir, rays.tmin[i], rays.tmax[i]).hit();
  }
  return hits;
}

TEST_F(Commands, TraceHitsEqualBruteForce) {
  TraceCommandOptions o;
  o.input = kMeshes / "mushroom.off";
  o.out_dir = dir_ / "t";
  o.render.width = 40;
  o.render.height = 30;
  o.render.shadows = true;
  std::ostringstream out;
  cmd_trace(o, out);
  const auto rows = csv_rows(slurp(dir_ / "t" / "trace.csv"));
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("pass"), "primary");
  EXPECT_EQ(rows[1].at("pass"), "shadow");
  const Mesh m = read_mesh(o.input).mesh;
  const std::uint64_t want = brute_force_hits(m, {}, 40, 30);
  EXPECT_GT(want, 100u);
  EXPECT_EQ(std::stoull(rows[0].at("hits")), want);
  // A shadow ray per hit point that faces the light: at most one per primary hit.
  EXPECT_LE(std::stoull(rows[1].at("rays")), want);
  EXPECT_GT(std::stoull(rows[1].at("rays")), 0u);
  for (const char* f : {"shaded.png", "depth.png", "normal.png", "cost_nodes.png", "cost_triangles.png", "cost_legend.png"})
    EXPECT_TRUE(fs::exists(dir_ / "t" / f)) << f;
  // --cost-range: counts 0, 1 and >= 2 are the only colours of the nodes image with 0:2.
  o.cost_range = "0:2";
  o.out_dir = dir_ / "tr";
  cmd_trace(o, out);
  {
    const nlohmann::json man = nlohmann::json::parse(slurp(dir_ / "tr" / "manifest.json"));
    EXPECT_EQ(man["parameters"]["cost_range"], nlohmann::json::array({0.0, 2.0}));
    EXPECT_EQ(man["results"]["images"]["cost_nodes.png"]["max"], 2.0);
    EXPECT_NE(man["results"]["images"]["cost_nodes.png"]["note"].get<std::string>().find("above the range"), std::string::npos);
    const RgbImage img = viz::read_png(dir_ / "tr" / "cost_nodes.png");
    for (std::size_t i = 0; i < img.pixel_count(); ++i) {
      const Rgb8 p{img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]};
      EXPECT_TRUE(p == viridis(0) || p == viridis(0.5) || p == viridis(1)) << "pixel " << i;
    }
  }
  o.cost_range = "2:1";
  EXPECT_EQ(usage_flag([&] { cmd_trace(o, out); }), "--cost-range");
  o.cost_range.reset();
  o.out_dir = dir_ / "t";
  // Usage errors name their flag.
  o.frame = "x";
  EXPECT_EQ(usage_flag([&] { cmd_trace(o, out); }), "--frame");
  o.frame.reset();
  o.frames = "0:3";  // a mesh file has the default range 0:59 of a static scene
  o.out_dir = dir_ / "t2";
  EXPECT_EQ(usage_flag([&] { cmd_trace(o, out); }), "");
  o.frames = "0:60";
  EXPECT_EQ(usage_flag([&] { cmd_trace(o, out); }), "--frames");
  o.frames.reset();
  o.out_dir = "";
  EXPECT_EQ(usage_flag([&] { cmd_trace(o, out); }), "--out");
}

TEST_F(Commands, BenchEveryConfigurationHitsWhatBruteForceHits) {
  BenchCommandOptions o;
  o.input = kMeshes / "mushroom.off";
  o.out_dir = dir_ / "b";
  o.frames = "0:1";
  o.config.width = 24;
  o.config.height = 20;
  o.config.threads = 1;
  o.config.max_count = 20;
  std::ostringstream out;
  cmd_bench(o, out);
  const auto rows = csv_rows(slurp(dir_ / "b" / "bench.csv"));
  ASSERT_EQ(rows.size(), 10u);
  // Frame 0 of the stand-in twist is the rest pose: the brute-force hits of the mesh itself.
  const std::uint64_t want = brute_force_hits(read_mesh(o.input).mesh, {}, 24, 20);
  std::set<std::string> configs;
  for (const auto& r : rows) {
    configs.insert(r.at("config"));
    if (r.at("frame") == "0") {
      EXPECT_EQ(std::stoull(r.at("hits")), want) << r.at("config");
    }
    EXPECT_EQ(r.at("mismatches"), "0") << r.at("config");
  }
  EXPECT_EQ(configs.size(), 5u);
  const auto m = nlohmann::json::parse(slurp(dir_ / "b" / "manifest.json"));
  EXPECT_EQ(m["output_schemas"]["bench.csv"], "ptc-bench/8");
  EXPECT_EQ(m["parameters"]["threads"], 1);
  // An animated scene refuses a stand-in motion; frames outside its range are refused.
  o.input = write_scene(dir_);
  o.deform = "wave";
  EXPECT_EQ(usage_flag([&] { cmd_bench(o, out); }), "--deform");
  o.deform.reset();
  o.frames = "3:7";
  EXPECT_EQ(usage_flag([&] { cmd_bench(o, out); }), "--frames");
}

}  // namespace
}  // namespace ptc
