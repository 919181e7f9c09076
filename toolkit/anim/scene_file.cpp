#include "toolkit/anim/scene_file.h"
#include "toolkit/core/cancel.h"

#include "toolkit/anim/frame_sequence.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "toolkit/anim/cloth.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/static_source.h"
#include "toolkit/anim/subdivided.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"
#include "toolkit/core/input_log.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace ptc {
namespace {

/// An error raised by what a scene file's entry refers to (a mesh file, a frame), placed in the
/// scene file at the entry's JSON path; one already placed in this file is rethrown as it is
/// (the referred file keeps its own name in the message).
[[noreturn]] void rethrow_placed(const InputError& e, const std::string& file, const std::string& path) {
  if (e.file() == file) throw e;
  throw InputError(file, "", path, e.file().empty() ? e.reason() : e.what());
}

/// An animated part of a scene file: its source, with the scene file and the entry's JSON path
/// put in front of an error it raises while a frame is read (files read lazily, per frame).
class PlacedSource final : public Animation {
 public:
  PlacedSource(AnimationPtr source, std::string file, std::string path)
      : s_(std::move(source)), file_(std::move(file)), path_(std::move(path)) {}
  const Mesh& rest() const override { return s_->rest(); }
  std::size_t frame_count() const override { return s_->frame_count(); }
  double frames_per_second() const override { return s_->frames_per_second(); }
  void positions(double frame, std::span<Vec3> out) override {
    try {
      s_->positions(frame, out);
    } catch (const InputError& e) {
      rethrow_placed(e, file_, path_);
    }
  }
  std::string describe() const override { return s_->describe(); }
  bool is_static() const override { return s_->is_static(); }
  bool renumber_vertices_in_place(std::span<const std::uint32_t> to_old) override {
    return s_->renumber_vertices_in_place(to_old);
  }

 private:
  AnimationPtr s_;
  std::string file_, path_;
};

// Reads typed values out of a JSON object, naming the JSON path in every error.
class Reader {
 public:
  Reader(std::string file, fs::path base, const SceneOptions& opt) : file_(std::move(file)), base_(std::move(base)), opt_(opt) {}

  [[noreturn]] void fail(const std::string& path, const std::string& reason) const {
    throw InputError(file_, "", path, reason);
  }

  void expect_object(const json& j, const std::string& path) const {
    if (!j.is_object()) fail(path, fmt::format("expected an object, found {}", j.type_name()));
  }

  /// Rejects keys not in `allowed` (catches typos such as "amplitde").
  void only_keys(const json& j, const std::string& path, std::initializer_list<const char*> allowed) const {
    for (auto it = j.begin(); it != j.end(); ++it)
      if (std::none_of(allowed.begin(), allowed.end(), [&](const char* k) { return it.key() == k; }))
        fail(join(path, it.key()), "unknown key");
  }

  static std::string join(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

  double number(const json& j, const std::string& path) const {
    if (!j.is_number()) fail(path, fmt::format("expected a number, found {}", j.type_name()));
    const double x = j.get<double>();
    if (!std::isfinite(x)) fail(path, "not a finite number");
    return x;
  }
  std::int64_t integer(const json& j, const std::string& path) const {
    // A whole number beyond 64 bits (JSON reads it as a float) or above INT64_MAX (an unsigned
    // one, which get<int64_t> would wrap to a negative value) is out of range, not a fraction.
    const bool too_big = (j.is_number_unsigned() && j.get<std::uint64_t>() > std::uint64_t(INT64_MAX)) ||
                         (j.is_number_float() && std::abs(j.get<double>()) >= 9223372036854775808.0 &&
                          std::isfinite(j.get<double>()) && j.get<double>() == std::floor(j.get<double>()));
    if (too_big) fail(path, fmt::format("{} is out of the 64-bit integer range", j.dump()));
    if (!j.is_number_integer()) fail(path, fmt::format("expected an integer, found {}", j.type_name()));
    return j.get<std::int64_t>();
  }
  std::string string(const json& j, const std::string& path) const {
    if (!j.is_string()) fail(path, fmt::format("expected a string, found {}", j.type_name()));
    return j.get<std::string>();
  }
  bool boolean(const json& j, const std::string& path) const {
    if (!j.is_boolean()) fail(path, fmt::format("expected true or false, found {}", j.type_name()));
    return j.get<bool>();
  }
  Vec3 vec3(const json& j, const std::string& path) const {
    if (!j.is_array() || j.size() != 3) fail(path, "expected an array of 3 numbers");
    return {number(j[0], path + "[0]"), number(j[1], path + "[1]"), number(j[2], path + "[2]")};
  }
  int axis(const json& j, const std::string& path) const {
    const auto a = parse_axis(string(j, path));
    if (!a) fail(path, "expected \"x\", \"y\" or \"z\"");
    return *a;
  }

  fs::path resolve(const std::string& s, const std::string& path) const {
    if (s.empty()) fail(path, "empty path");
    auto under = [&](std::string_view prefix, const fs::path& dir) -> std::optional<fs::path> {
      if (s.rfind(prefix, 0) != 0) return std::nullopt;
      if (dir.empty()) fail(path, "no data directory (pass --data-dir or set PTC_DATA_DIR)");
      return dir / s.substr(prefix.size());
    };
    if (auto p = under("${data}/", opt_.data_dir.empty() ? default_data_dir() : opt_.data_dir)) return *p;
    if (auto p = under("${assets}/", opt_.assets_dir)) return *p;
    const fs::path p(s);
    return p.is_absolute() ? p : base_ / p;
  }

  const std::string& file() const { return file_; }

 private:
  std::string file_;
  fs::path base_;
  const SceneOptions& opt_;
};

DeformParams read_deform(const Reader& r, const json& j, const std::string& path) {
  r.expect_object(j, path);
  r.only_keys(j, path, {"kind", "axis", "direction", "amplitude", "period", "wavelength", "velocity"});
  DeformParams d;
  if (!j.contains("kind")) r.fail(path + ".kind", "missing (twist, bend, wave, rigid or explode)");
  const auto kind = parse_deform_kind(r.string(j["kind"], path + ".kind"));
  if (!kind) r.fail(path + ".kind", "expected twist, bend, wave, rigid or explode");
  d.kind = *kind;
  // A key the kind does not read is refused, as the command line refuses a flag that does nothing.
  {
    std::vector<std::string> used{"kind", "amplitude"};
    switch (d.kind) {
      case DeformKind::Twist: used.insert(used.end(), {"axis", "period"}); break;
      case DeformKind::Bend: used.insert(used.end(), {"axis", "direction", "period"}); break;
      case DeformKind::Wave: used.insert(used.end(), {"axis", "direction", "period", "wavelength"}); break;
      case DeformKind::Rigid: used.insert(used.end(), {"axis", "period", "velocity"}); break;
      case DeformKind::Explode: break;
    }
    for (auto it = j.begin(); it != j.end(); ++it)
      if (std::find(used.begin(), used.end(), it.key()) == used.end()) {
        std::string list;
        for (const std::string& u : used) list += (list.empty() ? "" : ", ") + u;
        r.fail(path + "." + it.key(), fmt::format("not used by the {} deformer (it reads {})", to_string(d.kind), list));
      }
  }
  if (j.contains("axis")) d.axis = r.axis(j["axis"], path + ".axis");
  if (j.contains("direction")) d.direction = r.axis(j["direction"], path + ".direction");
  else if (d.direction == d.axis) d.direction = (d.axis + 1) % 3;
  if (j.contains("amplitude")) d.amplitude = r.number(j["amplitude"], path + ".amplitude");
  if (j.contains("period")) d.period = r.number(j["period"], path + ".period");
  if (j.contains("wavelength")) d.wavelength = r.number(j["wavelength"], path + ".wavelength");
  if (j.contains("velocity")) d.velocity = r.vec3(j["velocity"], path + ".velocity");
  if (const std::string why = check(d); !why.empty()) r.fail(path, why);
  return d;
}

ClothParams read_cloth(const Reader& r, const json& j, const std::string& path) {
  r.expect_object(j, path);
  r.only_keys(j, path,
              {"resolution", "size", "sphere_center", "sphere_radius", "drop", "offset", "floor", "gravity", "fps",
               "substeps", "iterations", "stretch_stiffness", "shear_stiffness", "bend_stiffness", "damping", "friction",
               "thickness"});
  ClothParams c;
  auto num = [&](const char* k, double& v) {
    if (j.contains(k)) v = r.number(j[k], path + "." + k);
  };
  auto integer = [&](const char* k, int& v) {
    if (!j.contains(k)) return;
    const std::int64_t x = r.integer(j[k], path + "." + k);
    if (x < 0 || x > 1000000) r.fail(path + "." + k, "out of range");
    v = static_cast<int>(x);
  };
  integer("resolution", c.resolution);
  num("size", c.size);
  if (j.contains("sphere_center")) c.sphere_center = r.vec3(j["sphere_center"], path + ".sphere_center");
  num("sphere_radius", c.sphere_radius);
  num("drop", c.drop);
  num("offset", c.offset);
  if (j.contains("floor")) c.floor = r.boolean(j["floor"], path + ".floor");
  num("gravity", c.gravity);
  num("fps", c.fps);
  integer("substeps", c.substeps);
  integer("iterations", c.iterations);
  num("stretch_stiffness", c.stretch_stiffness);
  num("shear_stiffness", c.shear_stiffness);
  num("bend_stiffness", c.bend_stiffness);
  num("damping", c.damping);
  num("friction", c.friction);
  num("thickness", c.thickness);
  if (const std::string why = check(c); !why.empty()) r.fail(path, why);
  return c;
}

ScenePart read_mesh_entry(const Reader& r, const json& j, const std::string& path, std::size_t index) {
  r.expect_object(j, path);
  r.only_keys(j, path, {"name", "file", "cloth", "sphere", "deform", "subdivide"});
  const int sources = int(j.contains("file")) + int(j.contains("cloth")) + int(j.contains("sphere"));
  if (sources != 1) r.fail(path, "needs exactly one of \"file\", \"cloth\" or \"sphere\"");

  std::optional<DeformParams> deform;
  if (j.contains("deform")) deform = read_deform(r, j["deform"], path + ".deform");
  std::optional<std::pair<SubdivisionScheme, int>> sub;
  if (j.contains("subdivide")) {
    const std::string sp = path + ".subdivide";
    const json& s = j["subdivide"];
    r.expect_object(s, sp);
    r.only_keys(s, sp, {"scheme", "levels"});
    SubdivisionScheme scheme = SubdivisionScheme::Midpoint;
    if (s.contains("scheme")) {
      const auto sc = parse_subdivision_scheme(r.string(s["scheme"], sp + ".scheme"));
      if (!sc) r.fail(sp + ".scheme", "expected \"midpoint\" or \"loop\"");
      scheme = *sc;
    }
    const std::int64_t levels = s.contains("levels") ? r.integer(s["levels"], sp + ".levels") : 1;
    if (levels < 0 || levels > 8) r.fail(sp + ".levels", "expected 0..8");
    sub = std::make_pair(scheme, static_cast<int>(levels));
  }

  ScenePart part;
  part.name = j.contains("name") ? r.string(j["name"], path + ".name") : fmt::format("mesh{}", index);
  // Errors of what an entry refers to (a bad mesh file, Loop on a non-manifold mesh) name the
  // entry's JSON path and keep their own message.
  auto wrap = [&](const std::string& where, auto&& f) {
    try {
      return f();
    } catch (const InputError& e) {
      rethrow_placed(e, r.file(), where);
    }
  };

  std::optional<Mesh> mesh;  // a static mesh that a deformer or StaticSource will own
  AnimationPtr anim;
  if (j.contains("file")) {
    const fs::path p = r.resolve(r.string(j["file"], path + ".file"), path + ".file");
    // A glob ("frames/f_*.ply") is a frame sequence, as on the command line (unless a file of
    // that very name exists).
    std::error_code ec;
    const bool glob = is_glob_pattern(p.string()) && !fs::exists(p, ec);
    if (!glob && !fs::is_directory(p) && format_from_extension(p)) {
      mesh = wrap(path + ".file", [&] { return read_mesh(p).mesh; });
    } else {
      if (deform) r.fail(path + ".deform", "a deformer applies to a mesh file or sphere, not to an animated source");
      anim = wrap(path + ".file", [&] { return open_animation_file(p); });
    }
  } else if (j.contains("sphere")) {
    const std::string sp = path + ".sphere";
    const json& s = j["sphere"];
    r.expect_object(s, sp);
    r.only_keys(s, sp, {"center", "radius", "levels"});
    const Vec3 c = s.contains("center") ? r.vec3(s["center"], sp + ".center") : Vec3::Zero();
    const double rad = s.contains("radius") ? r.number(s["radius"], sp + ".radius") : 1.0;
    if (!(rad > 0)) r.fail(sp + ".radius", "must be > 0");
    const std::int64_t lv = s.contains("levels") ? r.integer(s["levels"], sp + ".levels") : 3;
    if (lv < 0 || lv > 8) r.fail(sp + ".levels", "expected 0..8");
    mesh = make_sphere_mesh(c, rad, static_cast<int>(lv));
  } else {
    if (deform) r.fail(path + ".deform", "a deformer applies to a mesh file or sphere, not to a cloth");
    anim = wrap(path + ".cloth", [&] { return AnimationPtr(std::make_unique<ClothSimulation>(read_cloth(r, j["cloth"], path + ".cloth"))); });
  }

  if (mesh) {
    if (sub) mesh = wrap(path + ".subdivide", [&] { return subdivide(*mesh, sub->first, sub->second); });
    if (deform)
      part.source = wrap(path + ".deform", [&] { return make_deformer(std::move(*mesh), *deform); });
    else
      part.source = std::make_unique<StaticSource>(std::move(*mesh), part.name);
  } else {
    if (sub)
      anim = wrap(path + ".subdivide",
                  [&] { return AnimationPtr(std::make_unique<SubdividedAnimation>(std::move(anim), sub->first, sub->second)); });
    // Frames read later (a frame sequence reads each file when it is asked for) keep this
    // entry's place in their errors.
    part.source = std::make_unique<PlacedSource>(std::move(anim), r.file(), path + ".file");
  }
  // A part whose rest positions overflow (a sphere of radius 1e308): said here, with its JSON
  // path, not later by whatever first stumbles on an infinite box.
  for (const Vec3& q : part.source->rest().positions())
    if (!q.allFinite()) r.fail(path, "its rest positions are not finite (beyond double's range)");
  return part;
}

}  // namespace

namespace {

// A camera object ({"eye", "look_at", "up", "fov"}) at JSON path `at`: a scene file's "camera",
// the "results.camera" `ptc animate` records.
SceneCamera read_camera(const Reader& r, const json& c, const std::string& at) {
  r.expect_object(c, at);
  r.only_keys(c, at, {"eye", "look_at", "up", "fov"});
  SceneCamera sc;
  if (!c.contains("eye")) r.fail(at + ".eye", "missing");
  if (!c.contains("look_at")) r.fail(at + ".look_at", "missing");
  sc.eye = r.vec3(c["eye"], at + ".eye");
  sc.look_at = r.vec3(c["look_at"], at + ".look_at");
  if (c.contains("up")) sc.up = r.vec3(c["up"], at + ".up");
  if (c.contains("fov")) sc.fov_deg = r.number(c["fov"], at + ".fov");
  if (!(sc.fov_deg > 0 && sc.fov_deg < 180)) r.fail(at + ".fov", "expected a vertical field of view in (0, 180) degrees");
  if ((sc.eye - sc.look_at).norm() == 0) r.fail(at, "eye and look_at coincide");
  // (finite coordinates whose difference or its length overflow: no direction to look in)
  if (!std::isfinite((sc.look_at - sc.eye).norm()) || !std::isfinite(sc.up.norm()))
    r.fail(at, "eye, look_at and up must be within double's range of each other (a length overflows)");
  if (sc.up.norm() == 0 || sc.up.cross(sc.look_at - sc.eye).norm() == 0) r.fail(at + ".up", "zero or parallel to the view direction");
  return sc;
}

// A light object ({"position", "intensity"}) at JSON path `at`.
SceneLight read_light(const Reader& r, const json& l, const std::string& at) {
  r.expect_object(l, at);
  r.only_keys(l, at, {"position", "intensity"});
  SceneLight sl;
  if (!l.contains("position")) r.fail(at + ".position", "missing");
  sl.position = r.vec3(l["position"], at + ".position");
  if (l.contains("intensity")) sl.intensity = r.number(l["intensity"], at + ".intensity");
  if (sl.intensity < 0) r.fail(at + ".intensity", "must be >= 0");
  return sl;
}

}  // namespace

Scene parse_scene_json(std::string_view text, const std::string& name, const fs::path& base_dir, const SceneOptions& opt) {
  json root;
  // Each object's keys so far: a key given twice is refused (nlohmann keeps the last one silently,
  // and a second "meshes" would replace the first without a word).
  std::vector<std::vector<std::string>> keys;
  const json::parser_callback_t no_duplicates = [&](int, json::parse_event_t ev, json& parsed) {
    if (ev == json::parse_event_t::object_start) {
      keys.emplace_back();
    } else if (ev == json::parse_event_t::object_end) {
      if (!keys.empty()) keys.pop_back();
    } else if (ev == json::parse_event_t::key && !keys.empty()) {
      const std::string k = parsed.get<std::string>();
      if (std::find(keys.back().begin(), keys.back().end(), k) != keys.back().end())
        throw InputError(name, "", "key \"" + k + "\"", "given twice in one object (each key once)");
      keys.back().push_back(k);
    }
    return true;
  };
  try {
    root = json::parse(text.begin(), text.end(), no_duplicates);
  } catch (const json::exception& e) {
    // nlohmann's message: "[json.exception.parse_error.101] parse error at line 1, column 5: ...".
    std::string why = e.what();
    if (const auto k = why.find("] "); k != std::string::npos) why = why.substr(k + 2);
    std::string where;
    if (const auto* pe = dynamic_cast<const json::parse_error*>(&e)) {
      where = json_byte_loc(pe->byte);
    } else if (const auto q = why.find('\''), q2 = why.rfind('\''); q != std::string::npos && q2 > q) {
      // A number beyond double ("1e999": out_of_range.406) has no byte position: the number's
      // own text, quoted in the message, is found in the file instead.
      if (const auto at = text.find(why.substr(q + 1, q2 - q - 1)); at != std::string_view::npos) where = byte_loc(at);
    }
    throw InputError(name, where, "", "invalid JSON: " + why);
  }
  const Reader r(name, base_dir, opt);
  r.expect_object(root, "(root)");
  r.only_keys(root, "", {"schema", "name", "frames", "camera", "light", "clusters", "meshes"});
  if (root.contains("schema") && r.string(root["schema"], "schema") != "ptc-scene/1")
    r.fail("schema", "unsupported schema (expected \"ptc-scene/1\")");

  std::string scene_name = fs::path(name).stem().string();
  if (root.contains("name")) scene_name = r.string(root["name"], "name");

  if (!root.contains("meshes")) r.fail("meshes", "missing (an array of mesh entries)");
  const json& meshes = root["meshes"];
  if (!meshes.is_array() || meshes.empty()) r.fail("meshes", "expected a non-empty array");
  std::vector<ScenePart> parts;
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    parts.push_back(read_mesh_entry(r, meshes[i], fmt::format("meshes[{}]", i), i));
    // Parts are named in manifests and listings: each name once.
    for (std::size_t k = 0; k + 1 < parts.size(); ++k)
      if (parts[k].name == parts.back().name)
        r.fail(fmt::format("meshes[{}].name", i), fmt::format("'{}' is the name of meshes[{}] too (each part's name once)",
                                                              parts.back().name, k));
  }

  std::optional<FrameRange> frames;
  if (root.contains("frames")) {
    const json& f = root["frames"];
    if (!f.is_array() || f.size() != 2) r.fail("frames", "expected [first, last]");
    frames = FrameRange{r.integer(f[0], "frames[0]"), r.integer(f[1], "frames[1]")};
    if (frames->first < 0) r.fail("frames[0]", "must be >= 0");
    if (frames->last < frames->first) r.fail("frames[1]", "the last frame is before the first");
    if (frames->last > kMaxFrame)
      r.fail("frames[1]", "frame numbers go up to 2^53 = " + std::to_string(kMaxFrame) + " (" + kMaxFrameWhy + ")");
  }
  std::optional<SceneCamera> cam;
  if (root.contains("camera")) cam = read_camera(r, root["camera"], "camera");
  std::optional<SceneLight> light;
  if (root.contains("light")) light = read_light(r, root["light"], "light");
  // The scene's own cluster size (Scene::cluster_max_count): MaxCount = MaxSize for a command that
  // clusters the scene itself and is given none.
  std::optional<std::uint32_t> max_count;
  if (root.contains("clusters")) {
    const json& c = root["clusters"];
    r.expect_object(c, "clusters");
    r.only_keys(c, "clusters", {"max_count"});
    if (!c.contains("max_count")) r.fail("clusters.max_count", "missing");
    const std::int64_t n = r.integer(c["max_count"], "clusters.max_count");
    if (n < 0 || n > kMaxSceneClusterCount)
      r.fail("clusters.max_count", fmt::format("{} is outside [0, {}] (0: one triangle per cluster)", n, kMaxSceneClusterCount));
    max_count = static_cast<std::uint32_t>(n);
  }
  try {
    Scene s(scene_name, std::move(parts), cam, light, frames);
    s.set_cluster_max_count(max_count);
    return s;
  } catch (const InputError& e) {
    if (e.element() == "scene frames") r.fail("frames", e.reason());
    r.fail("", e.reason());
  }
}

Scene load_scene_file(const fs::path& path, const SceneOptions& opt) {
  note_input_file(path);
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path.string(), "", "", "no such file");
  if (fs::is_directory(path, ec)) throw InputError(path.string(), "", "", "is a directory, not a scene file");
  const BlockingWaitFor waiting(path);  // (a FIFO: a stop request ends the run at once meanwhile)
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "", "", "cannot open");
  std::stringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path.string(), "", "", "read error");
  return parse_scene_json(ss.str(), path.string(), path.parent_path(), opt);
}

bool is_scene_file(const std::string& arg) {
  // (a directory named x.json is a directory of frames, such as `ptc animate s.json --out x.json` writes)
  std::error_code ec;
  if (fs::is_directory(arg, ec)) return false;
  std::string ext = fs::path(arg).extension().string();
  std::ranges::transform(ext, ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".json";
}

bool scene_reads_data_dir(const std::string& arg) { return is_scene_file(arg) || names_builtin_scene(arg); }

std::optional<AnimateView> animate_view(const fs::path& dir) {
  std::error_code ec;
  const fs::path m = dir / "manifest.json";
  if (!fs::is_directory(dir, ec) || !fs::is_regular_file(m, ec)) return std::nullopt;
  std::ifstream in(m, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  const json root = json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  // Another program's manifest, or none of ptc animate's: not ours to read.
  if (!root.is_object() || root.value("schema", json()) != json("ptc-animate/1")) return std::nullopt;
  note_input_file(m);
  Reader r(m.string(), dir, SceneOptions{});
  if (!root.contains("results") || !root["results"].is_object()) r.fail("results", "missing (an object)");
  const json& res = root["results"];
  // Only a view that was the scene's own (a frame directory of a mesh file was framed by the
  // defaults, which a command replaces with its own framing).
  // (absent: not the scene's own; present but not true or false: an edited manifest, named)
  const auto own = [&](const char* key) {
    if (!res.contains(key)) return false;
    if (!res[key].is_boolean()) r.fail(std::string("results.") + key, "expected true or false");
    return res[key].get<bool>();
  };
  AnimateView v;
  if (own("camera_own")) {
    if (!res.contains("camera")) r.fail("results.camera", "missing");
    v.camera = read_camera(r, res["camera"], "results.camera");
  }
  if (own("light_own")) {
    if (!res.contains("light")) r.fail("results.light", "missing");
    v.light = read_light(r, res["light"], "results.light");
  }
  const json params = root.value("parameters", json::object());  // (recorded facts: read where well formed)
  if (params.is_object() && params.contains("scene") && params["scene"].is_string()) v.scene = params["scene"].get<std::string>();
  if (params.is_object() && params.contains("frames")) {
    const json& f = params["frames"];
    if (f.is_array() && f.size() == 2 && f[0].is_number_integer() && f[1].is_number_integer())
      v.frames = FrameRange{f[0].get<std::int64_t>(), f[1].get<std::int64_t>()};
  }
  return v;
}

Scene open_scene(const std::string& arg, const SceneOptions& opt) {
  if (is_scene_file(arg)) return load_scene_file(arg, opt);
  Scene s = open_scene_input(arg, opt);
  // Frames `ptc animate` wrote: traced from the view it recorded (the scene's own camera and
  // light), as the scene itself would be, not from a framing of the first frame.
  if (const auto v = animate_view(arg)) {
    if (v->camera) s.set_camera(*v->camera);
    if (v->light) s.set_light(*v->light);
    // Frames are the files in name order: frames 5..7 of a scene are this input's 0..2.
    if (v->frames && v->frames->first > 0 && v->frames->count() == s.frames().count())
      read_note(arg, fmt::format("holds frames {}..{} of '{}' (ptc animate); they are read as frames 0..{}, in file name "
                                 "order",
                                 v->frames->first, v->frames->last, v->scene.empty() ? std::string("its scene") : v->scene,
                                 v->frames->count() - 1));
  }
  return s;
}

}  // namespace ptc
