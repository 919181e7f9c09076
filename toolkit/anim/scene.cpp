#include "toolkit/anim/scene.h"

#include "toolkit/anim/frame_sequence.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <map>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "toolkit/anim/cloth.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/static_source.h"
#include "toolkit/anim/subdivided.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"

#if __has_include("toolkit/anim/load_animation.h")
#include "toolkit/anim/load_animation.h"
#define PTC_HAVE_LOAD_ANIMATION 1
#else
#define PTC_HAVE_LOAD_ANIMATION 0
#endif

namespace fs = std::filesystem;

namespace ptc {

// ------------------------------------------------------------------------------------------------
// Scene

Scene::Scene(std::string name, std::vector<ScenePart> parts, std::optional<SceneCamera> camera,
             std::optional<SceneLight> light, std::optional<FrameRange> frames)
    : name_(std::move(name)), parts_(std::move(parts)) {
  if (parts_.empty()) throw InputError("", "", "scene", "a scene needs at least one mesh");
  std::size_t V = 0, T = 0;
  vertex_offsets_.push_back(0);
  triangle_offsets_.push_back(0);
  for (const ScenePart& p : parts_) {
    if (!p.source) throw InputError("", "", "scene", fmt::format("part '{}' has no source", p.name));
    if (p.source->rest().empty()) throw InputError("", "", "scene", fmt::format("part '{}' has no triangles", p.name));
    V += p.source->rest().vertex_count();
    T += p.source->rest().triangle_count();
    vertex_offsets_.push_back(V);
    triangle_offsets_.push_back(T);
  }
  if (V > 0xffffffffull || T > 0xffffffffull)
    throw InputError("", "", "scene", "the combined mesh exceeds 32-bit vertex or triangle indices");
  combine_rest();

  const std::size_t fc = frame_count();
  if (frames) {
    if (frames->first < 0) throw InputError("", "", "scene frames", "the first frame must be >= 0");
    if (frames->last < frames->first) throw InputError("", "", "scene frames", "the last frame is before the first");
    if (fc > 0 && frames->last >= static_cast<std::int64_t>(fc))
      throw InputError("", "", "scene frames",
                       fmt::format("frame {} is beyond the last frame of the source ({})", frames->last, fc - 1));
    frames_ = *frames;
  } else {
    frames_ = {0, fc > 0 ? static_cast<std::int64_t>(fc) - 1 : 59};
  }
  own_camera_ = camera.has_value();
  own_light_ = light.has_value();
  camera_ = camera ? *camera : default_camera(rest().referenced_bounds());
  if (light) {
    light_ = *light;
  } else {
    // Above and behind the camera's right shoulder: the lit side faces the viewer.
    const Box3 b = rest().referenced_bounds();
    const double d = b.extent().norm();
    light_.position = camera_.eye + Vec3(0.5, 1.0, 0.5) * d;
    light_.intensity = 1.0;
  }
}

Scene deform_scene(const Scene& scene, const DeformParams& params, std::optional<FrameRange> frames) {
  std::vector<ScenePart> parts;
  parts.push_back({scene.name(), make_deformer(scene.rest(), params)});
  Scene s(scene.name(), std::move(parts), scene.has_own_camera() ? std::optional(scene.camera()) : std::nullopt,
          scene.has_own_light() ? std::optional(scene.light()) : std::nullopt,
          frames ? frames : std::optional(FrameRange{0, 59}));
  s.set_cluster_max_count(scene.cluster_max_count());
  return s;
}

bool Scene::all_static() const {
  return std::ranges::all_of(parts_, [](const ScenePart& p) { return p.source->is_static(); });
}

std::size_t Scene::frame_count() const {
  std::size_t fc = 0;
  for (const ScenePart& p : parts_) {
    const std::size_t c = p.source->frame_count();
    if (c > 0 && (fc == 0 || c < fc)) fc = c;
  }
  return fc;
}

void Scene::positions(double frame, std::span<Vec3> out, bool update_static) {
  if (out.size() != rest().vertex_count())
    throw std::invalid_argument(
        fmt::format("positions: output holds {} vertices, the scene has {}", out.size(), rest().vertex_count()));
  for (std::size_t k = 0; k < parts_.size(); ++k) {
    if (!update_static && parts_[k].source->is_static()) continue;
    parts_[k].source->positions(frame, out.subspan(vertex_offsets_[k], vertex_offsets_[k + 1] - vertex_offsets_[k]));
  }
}

void Scene::renumber_vertices(std::span<const std::uint32_t> to_old) {
  if (to_old.size() != rest().vertex_count())
    throw std::invalid_argument(fmt::format("renumber_vertices: {} entries for {} vertices", to_old.size(),
                                            rest().vertex_count()));
  check_permutation(to_old);  // before anything changes
  for (std::size_t k = 0; k < parts_.size(); ++k)
    for (std::size_t i = vertex_offsets_[k]; i < vertex_offsets_[k + 1]; ++i)
      if (to_old[i] < vertex_offsets_[k] || to_old[i] >= vertex_offsets_[k + 1])
        throw std::invalid_argument(fmt::format("renumber_vertices: new vertex {} of part '{}' comes from another part",
                                                i, parts_[k].name));
  for (std::size_t k = 0; k < parts_.size(); ++k) {
    const std::size_t a = vertex_offsets_[k], n = vertex_offsets_[k + 1] - a;
    std::vector<std::uint32_t> shifted;  // the part's own numbering (the first part's is to_old's)
    if (a > 0) {
      shifted.resize(n);
      for (std::size_t i = 0; i < n; ++i) shifted[i] = static_cast<std::uint32_t>(to_old[a + i] - a);
    }
    const std::span<const std::uint32_t> local = a > 0 ? std::span<const std::uint32_t>(shifted) : to_old.subspan(0, n);
    bool identity = true;
    for (std::size_t i = 0; i < n && identity; ++i) identity = local[i] == i;
    if (!identity) parts_[k].source = ptc::renumber_vertices(std::move(parts_[k].source), local);
  }
  combine_rest();  // the parts' renumbered rests, as the constructor combined them
}

void Scene::combine_rest() {
  // One part: rest() is the part's own rest mesh, nothing combined (at 13M triangles a copy is
  // 320 MB). Several: concatenated, each part's corners moved past the vertices of the parts
  // before it.
  if (parts_.size() == 1) {
    rest_ = Mesh();
    return;
  }
  std::vector<Tri> tris;
  tris.reserve(triangle_offsets_.back());
  std::vector<Vec3> pos;
  pos.reserve(vertex_offsets_.back());
  for (std::size_t k = 0; k < parts_.size(); ++k) {
    const Mesh& m = parts_[k].source->rest();
    const auto off = static_cast<std::uint32_t>(vertex_offsets_[k]);
    for (const Tri& t : m.triangles()) tris.push_back({t[0] + off, t[1] + off, t[2] + off});
    pos.insert(pos.end(), m.positions().begin(), m.positions().end());
  }
  rest_ = Mesh(std::move(tris), std::move(pos));
}

std::string Scene::describe() const {
  std::string s;
  for (std::size_t k = 0; k < parts_.size(); ++k)
    s += fmt::format("{} ({}): {}\n", parts_[k].name, is_static(k) ? "static" : "animated", parts_[k].source->describe());
  return s;
}

SceneCamera default_camera(const Box3& bounds) {
  SceneCamera c;
  c.look_at = bounds.empty() ? Vec3::Zero() : bounds.center();
  const double radius = bounds.empty() ? 1.0 : std::max(0.5 * bounds.extent().norm(), 1e-30);
  c.fov_deg = 45.0;
  const double dist = radius / std::tan(0.5 * c.fov_deg * std::numbers::pi / 180.0) / 0.8;
  c.eye = c.look_at + Vec3(1.0 / 3.0, 1.0 / 3.0, 1.0).normalized() * dist;
  c.up = Vec3::UnitY();
  return c;
}

// ------------------------------------------------------------------------------------------------
// Geometry helpers

Mesh make_sphere_mesh(const Vec3& center, double radius, int levels) {
  if (levels < 0 || levels > 8) throw std::invalid_argument("make_sphere_mesh: levels must be in 0..8");
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Tri> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                        {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                        {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  Mesh m = subdivide(Mesh(std::move(f), std::move(v)), SubdivisionScheme::Midpoint, levels);
  std::vector<Vec3> p(m.positions().begin(), m.positions().end());
  for (Vec3& q : p) q = center + radius * q.normalized();
  return m.with_positions(std::move(p));
}

namespace {

Mesh make_floor(double y, const Vec3& center, double half) {
  std::vector<Vec3> v = {{center.x() - half, y, center.z() - half},
                         {center.x() + half, y, center.z() - half},
                         {center.x() + half, y, center.z() + half},
                         {center.x() - half, y, center.z() + half}};
  std::vector<Tri> f = {{0, 2, 1}, {0, 3, 2}};  // facing +y
  return Mesh(std::move(f), std::move(v));
}

fs::path resolve_data_dir(const SceneOptions& opt) { return opt.data_dir.empty() ? default_data_dir() : opt.data_dir; }

fs::path data_file(const SceneOptions& opt, const std::string& rel) {
  const fs::path dir = resolve_data_dir(opt);
  if (dir.empty())
    throw InputError("", "", "data directory",
                     "no data directory found (pass --data-dir or set PTC_DATA_DIR to the build tree's data/)");
  const fs::path p = dir / rel;
  if (!fs::is_regular_file(p)) {
    // Say which of the user's settings points where: the flag, the variable or the default.
    const char* env = std::getenv("PTC_DATA_DIR");
    const char* given = !opt.data_dir.empty() ? "--data-dir" : env && *env ? "PTC_DATA_DIR" : nullptr;
    std::error_code ec;
    if (given && !fs::is_directory(dir, ec))
      throw InputError(p.string(), "", "", std::string("missing: the data directory given by ") + given + ", " +
                                                dir.string() + ", does not exist (it should be the build tree's data/)");
    throw InputError(p.string(), "", "",
                     given ? std::string("missing from the data directory given by ") + given +
                                 " (it should be the build tree's data/)"
                           : std::string("missing (pass --data-dir or set PTC_DATA_DIR to the build tree's data/)"));
  }
  return p;
}

fs::path asset_file(const SceneOptions& opt, const std::string& rel) {
  const fs::path p = opt.assets_dir / rel;
  if (!fs::is_regular_file(p)) throw InputError(p.string(), "", "", "missing (install Debian's assimp-testmodels)");
  return p;
}

Mesh read_data_mesh(const SceneOptions& opt, const std::string& rel) { return read_mesh(data_file(opt, rel)).mesh; }

ClothParams cloth_params(int n) {
  ClothParams p;
  p.resolution = n;
  return p;
}

Scene cloth_scene(const std::string& name, int n) {
  const ClothParams cp = cloth_params(n);
  std::vector<ScenePart> parts;
  parts.push_back({"cloth", std::make_unique<ClothSimulation>(cp)});
  parts.push_back({"sphere", std::make_unique<StaticSource>(make_sphere_mesh(cp.sphere_center, cp.sphere_radius, 4), "sphere")});
  parts.push_back({"floor", std::make_unique<StaticSource>(
                                make_floor(cp.sphere_center.y() - cp.sphere_radius, cp.sphere_center, 2.0 * cp.size), "floor")});
  SceneCamera cam;
  cam.look_at = cp.sphere_center;
  cam.eye = cp.sphere_center + Vec3(1.2, 1.4, 2.6);
  cam.fov_deg = 45;
  SceneLight light{cp.sphere_center + Vec3(2.0, 4.0, 3.0), 1.0};
  Scene s(name, std::move(parts), cam, light, FrameRange{0, 119});
  // The 646 x 646 cloth's own cluster size, measured (docs/tracing.md, "The cloth's own cluster
  // size"): over its whole animation MaxCount 28 gave the fastest whole frames of 20, 24, 28 and 32
  // (the bench's default); the smaller cloths keep the default, which was fastest on the 128 x 128.
  if (n == 646) s.set_cluster_max_count(28);
  return s;
}

Scene deformer_scene(const std::string& name, Mesh rest, const DeformParams& dp, const std::string& label) {
  std::vector<ScenePart> parts;
  parts.push_back({label, make_deformer(std::move(rest), dp)});
  return Scene(name, std::move(parts), std::nullopt, std::nullopt, FrameRange{0, 59});
}

AnimationPtr load_asset(const fs::path& p) {
#if PTC_HAVE_LOAD_ANIMATION
  return load_animation(p.string());
#else
  throw InputError(p.string(), "", "", "animated assets and frame directories are not supported by this build");
#endif
}

Scene asset_scene(const std::string& name, AnimationPtr a, int levels) {
  if (levels > 0) a = std::make_unique<SubdividedAnimation>(std::move(a), SubdivisionScheme::Midpoint, levels);
  std::vector<ScenePart> parts;
  parts.push_back({name, std::move(a)});
  return Scene(name, std::move(parts));
}

struct Builtin {
  BuiltinSceneInfo info;
  std::function<Scene(const SceneOptions&)> make;
};

const std::vector<Builtin>& registry() {
  static const std::vector<Builtin> r = [] {
    std::vector<Builtin> b;
    for (int n : {32, 128, 646}) {
      const std::string name = n == 646 ? "cloth-sphere-832k" : fmt::format("cloth-sphere-{}", n);
      b.push_back({{name, fmt::format("PBD cloth {}x{} falling onto a sphere and sliding off onto the floor", n, n)},
                   [name, n](const SceneOptions&) { return cloth_scene(name, n); }});
    }
    for (DeformKind k : {DeformKind::Twist, DeformKind::Bend, DeformKind::Wave, DeformKind::Rigid, DeformKind::Explode}) {
      const std::string name = fmt::format("armadillo-{}", to_string(k));
      b.push_back({{name, fmt::format("armadillo.off (52k triangles) under the {} deformer", to_string(k))},
                   [name, k](const SceneOptions& o) {
                     return deformer_scene(name, read_data_mesh(o, "meshes/armadillo.off"), deform_preset(k), "armadillo");
                   }});
    }
    for (DeformKind k : {DeformKind::Wave, DeformKind::Twist, DeformKind::Explode}) {
      const std::string name = fmt::format("armadillo-832k-{}", to_string(k));
      b.push_back({{name, fmt::format("armadillo.off Loop-subdivided twice (832k triangles) under the {} deformer",
                                      to_string(k))},
                   [name, k](const SceneOptions& o) {
                     return deformer_scene(name, subdivide(read_data_mesh(o, "meshes/armadillo.off"), SubdivisionScheme::Loop, 2),
                                           deform_preset(k), "armadillo-832k");
                   }});
    }
    b.push_back({{"faerie", "faerie.md2 (assimp-testmodels): MD2 vertex keyframes, welded"},
                 [](const SceneOptions& o) { return asset_scene("faerie", load_asset(asset_file(o, "MD2/faerie.md2")), 0); }});
    b.push_back({{"faerie-670k", "faerie.md2 midpoint-subdivided 5 times (670k triangles), carrying its keyframes"},
                 [](const SceneOptions& o) { return asset_scene("faerie-670k", load_asset(asset_file(o, "MD2/faerie.md2")), 5); }});
    b.push_back({{"epileptic", "BCN_Epileptic.X (assimp-testmodels): linear blend skinning"},
                 [](const SceneOptions& o) { return asset_scene("epileptic", load_asset(asset_file(o, "X/BCN_Epileptic.X")), 0); }});
    b.push_back({{"epileptic-1.3m", "BCN_Epileptic.X midpoint-subdivided 4 times, carrying its skinned motion"},
                 [](const SceneOptions& o) {
                   return asset_scene("epileptic-1.3m", load_asset(asset_file(o, "X/BCN_Epileptic.X")), 4);
                 }});
    return b;
  }();
  return r;
}

bool is_mesh_file(const fs::path& p) { return format_from_extension(p).has_value(); }

}  // namespace

fs::path default_data_dir() {
  if (const char* env = std::getenv("PTC_DATA_DIR"); env && *env) return env;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const fs::path d = exe.parent_path().parent_path() / "data";
  return fs::is_directory(d, ec) ? d : fs::path();
}

const std::vector<BuiltinSceneInfo>& builtin_scenes() {
  static const std::vector<BuiltinSceneInfo> v = [] {
    std::vector<BuiltinSceneInfo> out;
    for (const Builtin& b : registry()) out.push_back(b.info);
    return out;
  }();
  return v;
}

bool is_builtin_scene(const std::string& name) {
  return std::ranges::any_of(registry(), [&](const Builtin& b) { return b.info.name == name; });
}

Scene make_builtin_scene(const std::string& name, const SceneOptions& opt) {
  for (const Builtin& b : registry())
    if (b.info.name == name) {
      Scene s = b.make(opt);
      s.adopt_view();
      return s;
    }
  throw InputError("", "", name, "no such built-in scene (run 'ptc scenes' for the list)");
}

AnimationPtr open_animation_file(const fs::path& path) {
  std::error_code ec;
  // A glob of frame files ("frames/*.ply") names no existing path; load_animation expands it.
  if (!fs::exists(path, ec) && PTC_HAVE_LOAD_ANIMATION && is_glob_pattern(path.string()))
    return load_asset(path);
  if (!fs::exists(path, ec)) throw InputError(path.string(), "", "", "no such file or directory");
  if (!fs::is_directory(path, ec) && is_mesh_file(path))
    return std::make_unique<StaticSource>(read_mesh(path).mesh, path.filename().string());
  return load_asset(path);
}

bool names_builtin_scene(const std::string& arg) {
  std::error_code ec;
  return !fs::exists(arg, ec) && is_builtin_scene(arg);
}

Scene open_scene_input(const std::string& arg, const SceneOptions& opt) {
  std::error_code ec;
  if (names_builtin_scene(arg)) return make_builtin_scene(arg, opt);
  const fs::path p(arg);
  std::string label = p.filename().string();
  if (label.empty()) label = p.parent_path().filename().string();
  std::vector<ScenePart> parts;
  if (!fs::exists(arg, ec)) {
    // A glob of frame files ("frames/*.ply") names no existing path; load_animation expands it.
    if (PTC_HAVE_LOAD_ANIMATION && is_glob_pattern(arg)) {
      // Named by the whole pattern: "*.off" alone does not say which folder's frames.
      parts.push_back({arg, load_asset(p)});
      return Scene(arg, std::move(parts));
    }
    throw InputError(arg, "", "", "neither a file, a directory nor a built-in scene (run 'ptc scenes' for the list)");
  }
  parts.push_back({label, open_animation_file(p)});
  return Scene(label, std::move(parts));
}

}  // namespace ptc
