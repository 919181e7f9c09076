// Scene model: the combined mesh is the parts concatenated (checked element by element), frame
// positions land in each part's range, static parts can be skipped, frame ranges are checked
// against finite sources; built-in scenes build from the data directory or fail naming it;
// SCENE arguments resolve to the right kind of source.
#include "toolkit/anim/scene.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <initializer_list>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <random>
#include <set>

#include "toolkit/anim/cloth.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/static_source.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace fs = std::filesystem;

namespace ptc {
namespace {

const fs::path kData = PTC_TEST_DATA;

// A finite keyframed source for the tests: frame k moves every vertex by (k, 0, 0).
class Shifted final : public Animation {
 public:
  Shifted(Mesh m, std::size_t frames) : m_(std::move(m)), frames_(frames) {}
  const Mesh& rest() const override { return m_; }
  std::size_t frame_count() const override { return frames_; }
  void positions(double t, std::span<Vec3> out) override {
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = m_.position(i) + Vec3(t, 0, 0);
  }
  std::string describe() const override { return "shifted"; }

 private:
  Mesh m_;
  std::size_t frames_;
};

Mesh tri_mesh(double z) { return Mesh({{0, 1, 2}}, {Vec3(0, 0, z), Vec3(1, 0, z), Vec3(0, 1, z)}); }
Mesh quad_mesh() { return Mesh({{0, 1, 2}, {0, 2, 3}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)}); }

TEST(SceneModel, RejectsEmptyAndBadFrameRanges) {
  EXPECT_THROW(Scene("s", {}), InputError);
  {
    std::vector<ScenePart> parts;
    parts.push_back({"none", nullptr});
    EXPECT_THROW(Scene("s", std::move(parts)), InputError);
  }
  {
    std::vector<ScenePart> parts;
    parts.push_back({"empty", std::make_unique<StaticSource>(Mesh())});
    EXPECT_THROW(Scene("s", std::move(parts)), InputError);
  }
  auto two = [] {
    std::vector<ScenePart> parts;
    parts.push_back({"a", std::make_unique<Shifted>(tri_mesh(0), 10)});
    parts.push_back({"b", std::make_unique<Shifted>(tri_mesh(1), 7)});
    return parts;
  };
  EXPECT_THROW(Scene("s", two(), {}, {}, FrameRange{0, 7}), InputError);   // beyond the shorter source
  EXPECT_THROW(Scene("s", two(), {}, {}, FrameRange{3, 2}), InputError);   // last < first
  EXPECT_THROW(Scene("s", two(), {}, {}, FrameRange{-1, 2}), InputError);  // negative
  const Scene ok("s", two(), {}, {}, FrameRange{2, 6});
  EXPECT_EQ(ok.frame_count(), 7u);
  const Scene dflt("s", two());
  EXPECT_EQ(dflt.frames().first, 0);
  EXPECT_EQ(dflt.frames().last, 6);
}

TEST(SceneModel, CombinedMeshIsThePartsConcatenated) {
  std::vector<ScenePart> parts;
  DeformParams dp;
  dp.kind = DeformKind::Twist;
  dp.amplitude = 0.7;
  Mesh sphere = make_sphere_mesh(Vec3(1, 2, 3), 0.5, 1);
  Mesh quad = quad_mesh();
  parts.push_back({"ball", make_deformer(sphere, dp)});
  parts.push_back({"quad", std::make_unique<StaticSource>(quad, "quad")});
  parts.push_back({"tri", std::make_unique<Shifted>(tri_mesh(5), 4)});
  Scene s("combo", std::move(parts));
  ASSERT_EQ(s.part_count(), 3u);
  EXPECT_FALSE(s.is_static(0));
  EXPECT_TRUE(s.is_static(1));
  EXPECT_FALSE(s.is_static(2));
  EXPECT_FALSE(s.all_static());
  ASSERT_EQ(s.vertex_offset(0), 0u);
  ASSERT_EQ(s.vertex_offset(1), sphere.vertex_count());
  ASSERT_EQ(s.vertex_offset(2), sphere.vertex_count() + 4);
  ASSERT_EQ(s.vertex_offset(3), sphere.vertex_count() + 7);
  ASSERT_EQ(s.triangle_offset(3), sphere.triangle_count() + 3);
  const Mesh& r = s.rest();
  ASSERT_EQ(r.triangle_count(), sphere.triangle_count() + 3);
  for (std::size_t t = 0; t < sphere.triangle_count(); ++t) ASSERT_EQ(r.triangle(t), sphere.triangle(t));
  for (std::size_t t = 0; t < 2; ++t)
    for (int k = 0; k < 3; ++k)
      ASSERT_EQ(r.triangle(sphere.triangle_count() + t)[k], quad.triangle(t)[k] + sphere.vertex_count());
  for (int k = 0; k < 3; ++k) ASSERT_EQ(r.triangle(sphere.triangle_count() + 2)[k], std::uint32_t(k + sphere.vertex_count() + 4));

  // Frame positions: each part's own positions in its range.
  std::vector<Vec3> out(r.vertex_count(), Vec3::Constant(-99));
  s.positions(3.0, out);
  auto twist = make_deformer(sphere, dp);
  std::vector<Vec3> own(sphere.vertex_count());
  twist->positions(3.0, own);
  for (std::size_t i = 0; i < own.size(); ++i) ASSERT_EQ(out[i], own[i]);
  for (std::size_t i = 0; i < 4; ++i) ASSERT_EQ(out[sphere.vertex_count() + i], quad.position(i));
  ASSERT_EQ(out[sphere.vertex_count() + 4], Vec3(3, 0, 5));

  // update_static = false leaves the static range untouched.
  std::fill(out.begin(), out.end(), Vec3::Constant(-99));
  s.positions(1.0, out, false);
  for (std::size_t i = 0; i < 4; ++i) ASSERT_EQ(out[sphere.vertex_count() + i], Vec3::Constant(-99));
  ASSERT_EQ(out[sphere.vertex_count() + 4], Vec3(1, 0, 5));

  std::vector<Vec3> wrong(3);
  EXPECT_THROW(s.positions(0.0, wrong), std::invalid_argument);
  EXPECT_NE(s.describe().find("quad (static)"), std::string::npos);
}


// A random permutation of 0 .. n-1 that keeps the ranges [offsets[p], offsets[p+1]).
std::vector<std::uint32_t> shuffled_within(const std::vector<std::size_t>& offsets, unsigned seed) {
  std::mt19937 g(seed);
  std::vector<std::uint32_t> to_old(offsets.back());
  for (std::size_t i = 0; i < to_old.size(); ++i) to_old[i] = static_cast<std::uint32_t>(i);
  for (std::size_t p = 0; p + 1 < offsets.size(); ++p)
    std::shuffle(to_old.begin() + offsets[p], to_old.begin() + offsets[p + 1], g);
  return to_old;
}

// Renumbering a source: every deformer kind (explode keeps each soup vertex's own flight),
// static meshes in place; a source that cannot (a keyframed test source) through the per-frame
// gather. Against the unrenumbered source, vertex by vertex at several times; triangles renamed.
TEST(Renumbering, SourcesProduceTheirPositionsInTheNewOrder) {
  const Mesh sphere = make_sphere_mesh(Vec3(1, 2, 3), 0.5, 2);
  std::vector<AnimationPtr> a, b;
  for (DeformKind k : {DeformKind::Twist, DeformKind::Bend, DeformKind::Wave, DeformKind::Rigid, DeformKind::Explode}) {
    DeformParams dp;
    dp.kind = k;
    dp.amplitude = 0.4;
    dp.velocity = Vec3(0.1, 0, 0);
    a.push_back(make_deformer(sphere, dp));
    b.push_back(make_deformer(sphere, dp));
  }
  a.push_back(std::make_unique<StaticSource>(sphere, "s"));
  b.push_back(std::make_unique<StaticSource>(sphere, "s"));
  a.push_back(std::make_unique<Shifted>(sphere, 9));
  b.push_back(std::make_unique<Shifted>(sphere, 9));
  for (std::size_t k = 0; k < a.size(); ++k) {
    const Mesh& rest = a[k]->rest();
    const std::size_t V = rest.vertex_count();
    const std::vector<std::uint32_t> to_old = shuffled_within({0, V}, 11 + unsigned(k));
    const bool in_place = k + 1 < a.size();
    Animation* before = b[k].get();
    b[k] = renumber_vertices(std::move(b[k]), to_old);
    EXPECT_EQ(b[k].get() == before, in_place) << a[k]->describe();
    EXPECT_EQ(b[k]->describe().find("gather") != std::string::npos, !in_place) << b[k]->describe();
    EXPECT_EQ(b[k]->is_static(), a[k]->is_static());
    EXPECT_EQ(b[k]->frame_count(), a[k]->frame_count());
    const Mesh& r2 = b[k]->rest();
    ASSERT_EQ(r2.vertex_count(), V);
    for (std::size_t t = 0; t < rest.triangle_count(); ++t)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(to_old[r2.triangle(t)[c]], rest.triangle(t)[c]) << "triangle " << t;
    std::vector<Vec3> pa(V), pb(V);
    for (double t : {0.0, 1.0, 2.5, 7.0}) {
      a[k]->positions(t, pa);
      b[k]->positions(t, pb);
      for (std::size_t i = 0; i < V; ++i) ASSERT_EQ(pb[i], pa[to_old[i]]) << a[k]->describe() << " t " << t << " v " << i;
    }
    // A second renumbering composes with the first.
    const std::vector<std::uint32_t> again = shuffled_within({0, V}, 99);
    b[k] = renumber_vertices(std::move(b[k]), again);
    b[k]->positions(2.0, pb);
    a[k]->positions(2.0, pa);
    for (std::size_t i = 0; i < V; ++i) ASSERT_EQ(pb[i], pa[to_old[again[i]]]) << a[k]->describe();
  }
  // Not a permutation / wrong size: std::invalid_argument, the source unchanged.
  auto d = make_deformer(sphere, DeformParams{});
  std::vector<std::uint32_t> bad(sphere.vertex_count(), 0);
  EXPECT_THROW((void)renumber_vertices(std::move(d), bad), std::invalid_argument);
  auto e = std::make_unique<StaticSource>(sphere, "s");
  EXPECT_THROW((void)e->renumber_vertices_in_place(std::vector<std::uint32_t>{0, 1}), std::invalid_argument);
  EXPECT_EQ(e->rest().positions()[0], sphere.positions()[0]);
}

// b is a renumbered with to_old: b's rest triangles and positions, and its positions at `times`,
// are a's through to_old, item by item.
void expect_renumbered(Scene& a, Scene& b, const std::vector<std::uint32_t>& to_old, std::initializer_list<double> times) {
  const std::size_t V = a.rest().vertex_count();
  ASSERT_EQ(b.rest().vertex_count(), V);
  ASSERT_EQ(b.rest().triangle_count(), a.rest().triangle_count());
  for (std::size_t t = 0; t < a.rest().triangle_count(); ++t)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(to_old[b.rest().triangle(t)[c]], a.rest().triangle(t)[c]);
  for (std::size_t i = 0; i < V; ++i) ASSERT_EQ(b.rest().position(i), a.rest().position(to_old[i]));
  std::vector<Vec3> pa(V), pb(V);
  for (double t : times) {
    a.positions(t, pa);
    b.positions(t, pb);
    for (std::size_t i = 0; i < V; ++i) ASSERT_EQ(pb[i], pa[to_old[i]]) << "t " << t << " v " << i;
  }
}

TEST(Renumbering, SceneRenumbersEachPartWithinItsRange) {
  auto make = [] {
    std::vector<ScenePart> parts;
    DeformParams dp;
    dp.kind = DeformKind::Twist;
    dp.amplitude = 0.7;
    parts.push_back({"ball", make_deformer(make_sphere_mesh(Vec3(1, 2, 3), 0.5, 1), dp)});
    parts.push_back({"quad", std::make_unique<StaticSource>(quad_mesh(), "quad")});
    parts.push_back({"tri", std::make_unique<Shifted>(tri_mesh(5), 4)});
    return Scene("combo", std::move(parts));
  };
  Scene a = make(), b = make();
  const std::vector<std::size_t> offs(b.vertex_offsets().begin(), b.vertex_offsets().end());
  ASSERT_EQ(offs.size(), 4u);
  const std::vector<std::uint32_t> to_old = shuffled_within(offs, 5);
  b.renumber_vertices(to_old);
  expect_renumbered(a, b, to_old, {0.0, 2.0, 3.0});
  const std::size_t V = a.rest().vertex_count();
  EXPECT_NE(b.describe().find("gather"), std::string::npos);  // the test source cannot renumber itself
  // A permutation that moves a vertex into another part's range is refused, nothing changed.
  Scene c = make();
  std::vector<std::uint32_t> across(V);
  for (std::size_t i = 0; i < V; ++i) across[i] = static_cast<std::uint32_t>(V - 1 - i);
  EXPECT_THROW(c.renumber_vertices(across), std::invalid_argument);
  EXPECT_EQ(c.rest().position(0), a.rest().position(0));
  EXPECT_THROW(c.renumber_vertices(std::vector<std::uint32_t>(V, 0)), std::invalid_argument);
  EXPECT_THROW(c.renumber_vertices(std::vector<std::uint32_t>{0}), std::invalid_argument);
}

// One part (the scene's rest is then the part's own rest mesh, its triangle array shared): the
// same checks, with a source that renumbers itself in place and one that needs a gather.
TEST(Renumbering, SceneOfOnePartRenumbersItsRest) {
  for (const bool in_place : {true, false}) {
    auto make = [&] {
      std::vector<ScenePart> parts;
      DeformParams dp;
      dp.kind = DeformKind::Explode;
      dp.amplitude = 0.3;
      if (in_place)
        parts.push_back({"ball", make_deformer(make_sphere_mesh(Vec3(1, 2, 3), 0.5, 1), dp)});
      else
        parts.push_back({"tri", std::make_unique<Shifted>(tri_mesh(7), 4)});
      return Scene("one", std::move(parts));
    };
    Scene a = make(), b = make();
    const std::size_t V = a.rest().vertex_count();
    const std::vector<std::uint32_t> to_old = shuffled_within({0, V}, 11);
    b.renumber_vertices(to_old);
    expect_renumbered(a, b, to_old, {0.0, 1.0, 2.5});
    EXPECT_EQ(b.describe().find("gather") != std::string::npos, !in_place);
    // Twice: the second renumbering composes with the first.
    const std::vector<std::uint32_t> again = shuffled_within({0, V}, 12);
    b.renumber_vertices(again);
    for (std::size_t i = 0; i < V; ++i) ASSERT_EQ(b.rest().position(i), a.rest().position(to_old[again[i]]));
    // Refused permutations leave the rest as it was.
    EXPECT_THROW(b.renumber_vertices(std::vector<std::uint32_t>(V, 0)), std::invalid_argument);
    for (std::size_t i = 0; i < V; ++i) ASSERT_EQ(b.rest().position(i), a.rest().position(to_old[again[i]]));
  }
}

TEST(SceneModel, DefaultCameraSeesTheBounds) {
  Box3 b;
  b.extend(Vec3(-1, -2, -3));
  b.extend(Vec3(5, 4, 3));
  const SceneCamera c = default_camera(b);
  EXPECT_EQ(c.look_at, b.center());
  // The bounding sphere fits in the vertical field of view.
  const double dist = (c.eye - c.look_at).norm();
  const double r = 0.5 * b.extent().norm();
  EXPECT_LT(std::asin(r / dist), 0.5 * c.fov_deg * M_PI / 180.0);
}

TEST(SphereMesh, VerticesOnTheSphereFacesOutward) {
  for (int levels : {0, 1, 3}) {
    const Vec3 c(1e3, -2, 0.5);
    const Mesh m = make_sphere_mesh(c, 0.25, levels);
    ASSERT_EQ(m.triangle_count(), std::size_t(20) << (2 * levels));
    for (const Vec3& p : m.positions()) ASSERT_NEAR((p - c).norm(), 0.25, 1e-12);
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const auto k = m.corners(t);
      const Vec3 n = (k[1] - k[0]).cross(k[2] - k[0]);
      ASSERT_GT(n.dot((k[0] + k[1] + k[2]) / 3 - c), 0) << "triangle " << t << " faces inward";
    }
  }
  EXPECT_THROW((void)make_sphere_mesh(Vec3::Zero(), 1, -1), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Built-in scenes

TEST(BuiltinScenes, ListedNamesAreUniqueAndBuildOrFailClearly) {
  const auto& list = builtin_scenes();
  ASSERT_GE(list.size(), 5u);
  std::set<std::string> names;
  for (const auto& b : list) EXPECT_TRUE(names.insert(b.name).second) << b.name;
  EXPECT_TRUE(is_builtin_scene("cloth-sphere-32"));
  EXPECT_FALSE(is_builtin_scene("cloth-sphere-33"));
  EXPECT_THROW((void)make_builtin_scene("no-such-scene"), InputError);
}

TEST(BuiltinScenes, ClothSphereHasAnimatedClothAndStaticObstacles) {
  Scene s = make_builtin_scene("cloth-sphere-32");
  ASSERT_EQ(s.part_count(), 3u);
  EXPECT_EQ(s.part(0).name, "cloth");
  EXPECT_FALSE(s.is_static(0));
  EXPECT_TRUE(s.is_static(1));
  EXPECT_TRUE(s.is_static(2));
  EXPECT_EQ(s.triangle_offset(1), std::size_t(2 * 31 * 31));
  EXPECT_EQ(s.frames().first, 0);
  EXPECT_EQ(s.frames().last, 119);
  // Frame 40: every cloth vertex outside the rendered sphere, whose vertices lie on radius r.
  std::vector<Vec3> x(s.rest().vertex_count());
  s.positions(40, x);
  const auto& cloth = dynamic_cast<const ClothSimulation&>(*s.part(0).source);
  for (std::size_t i = 0; i < s.vertex_offset(1); ++i)
    ASSERT_GE((x[i] - cloth.params().sphere_center).norm(), cloth.params().sphere_radius) << i;
}

// The built-in scenes' own cluster sizes (docs/tracing.md, "The cloth's own cluster size"): the
// 646 x 646 cloth carries the 28 its sweep chose; the smaller cloths and the armadillo none.
TEST(BuiltinScenes, OwnClusterSizes) {
  EXPECT_EQ(make_builtin_scene("cloth-sphere-832k").cluster_max_count(), std::optional<std::uint32_t>(28));
  EXPECT_FALSE(make_builtin_scene("cloth-sphere-128").cluster_max_count().has_value());
  EXPECT_FALSE(make_builtin_scene("cloth-sphere-32").cluster_max_count().has_value());
  SceneOptions o;
  o.data_dir = kData;
  EXPECT_FALSE(make_builtin_scene("armadillo-twist", o).cluster_max_count().has_value());
}

TEST(BuiltinScenes, ArmadilloFromTheDataDirectory) {
  SceneOptions o;
  o.data_dir = kData;
  Scene s = make_builtin_scene("armadillo-twist", o);
  const Mesh arm = read_mesh(kData / "meshes/armadillo.off").mesh;
  ASSERT_EQ(s.rest().triangle_count(), arm.triangle_count());
  ASSERT_EQ(s.rest().vertex_count(), arm.vertex_count());
  EXPECT_FALSE(s.is_static(0));
  Scene e = make_builtin_scene("armadillo-explode", o);
  EXPECT_EQ(e.rest().vertex_count(), 3 * arm.triangle_count());  // a soup

  SceneOptions missing;
  missing.data_dir = "/nonexistent/ptc-data";
  try {
    (void)make_builtin_scene("armadillo-twist", missing);
    FAIL() << "no error";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("/nonexistent/ptc-data/meshes/armadillo.off"), std::string::npos) << err.what();
    EXPECT_NE(std::string(err.what()).find("--data-dir"), std::string::npos) << err.what();
  }
}

TEST(BuiltinScenes, DefaultDataDirFollowsTheEnvironment) {
  const char* old = std::getenv("PTC_DATA_DIR");
  const std::string saved = old ? old : "";
  ::setenv("PTC_DATA_DIR", kData.c_str(), 1);
  EXPECT_EQ(default_data_dir(), kData);
  EXPECT_NO_THROW((void)make_builtin_scene("armadillo-rigid"));
  ::setenv("PTC_DATA_DIR", "/nonexistent/x", 1);
  EXPECT_THROW((void)make_builtin_scene("armadillo-rigid"), InputError);
  if (old)
    ::setenv("PTC_DATA_DIR", saved.c_str(), 1);
  else
    ::unsetenv("PTC_DATA_DIR");
}

// ---------------------------------------------------------------------------------------------
// SCENE arguments

TEST(SceneInput, MeshFileIsOneStaticPart) {
  Scene s = open_scene_input((kData / "meshes/cube.off").string());
  ASSERT_EQ(s.part_count(), 1u);
  EXPECT_TRUE(s.all_static());
  EXPECT_EQ(s.rest().triangle_count(), read_mesh(kData / "meshes/cube.off").mesh.triangle_count());
}

TEST(SceneInput, MissingPathOrUnknownNameIsAnInputErrorNamingIt) {
  try {
    (void)open_scene_input("/nonexistent/frames_dir");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/frames_dir"), std::string::npos);
  }
  EXPECT_THROW((void)open_scene_input("cloth-sphere-999"), InputError);
  // A truncated mesh file: the reader's error, naming the file.
  const fs::path bad = fs::temp_directory_path() / ("ptc_scene_bad_" + std::to_string(::getpid()) + ".off");
  std::ofstream(bad) << "OFF\n3 1 0\n0 0 0\n1 0 0\n";
  try {
    (void)open_scene_input(bad.string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos);
  }
  fs::remove(bad);
}

}  // namespace
}  // namespace ptc
