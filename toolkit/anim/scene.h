// A scene: meshes (each static or animated by one Animation source), a camera, a point light
// and a frame range (issue 6, "Scenes"). Consumers see ONE combined mesh - the parts' triangle
// arrays concatenated in part order, indices shifted by the part's vertex offset - plus
// per-frame positions, and which parts (contiguous triangle / vertex ranges) are static, so that
// a per-frame loop keeps the static parts' BVHs and updates only the moving ones.
//
// Where a command takes SCENE (docs/animation.md), open_scene_input() accepts:
//   - a built-in scene name (builtin_scenes(); `ptc scenes` lists them),
//   - a mesh file (.off .obj .ply .stl): one static part,
//   - an animated asset file (MD2, MD3, skinned formats assimp reads) or a directory of frame
//     files: one animated part, through load_animation() (toolkit/anim/load_animation.h);
// scene files (.json) are parsed by toolkit/anim/scene_file.h (the JSON library is linked there),
// which calls back into this header for everything else.
//
// Built-in scenes read their meshes from a data directory: SceneOptions::data_dir, by default
// default_data_dir() = $PTC_DATA_DIR if set, else <directory of the running program>/../data
// (the build tree's data/, where CMake unpacks libcgal-demo's meshes next to bin/). Assets come
// from Debian's assimp-testmodels (/usr/share/assimp/models). A missing file is an InputError
// naming the path and how to point at another directory.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "toolkit/anim/animation.h"
#include "toolkit/anim/deformers.h"

namespace ptc {

struct SceneCamera {
  Vec3 eye = Vec3(0, 0, 1);
  Vec3 look_at = Vec3::Zero();
  Vec3 up = Vec3::UnitY();
  double fov_deg = 45.0;  ///< vertical field of view, degrees, in (0, 180)
};

struct SceneLight {
  Vec3 position = Vec3::Zero();
  double intensity = 1.0;  ///< >= 0, radiant intensity in arbitrary units
};

/// The largest frame number: a frame stands for the time double(f), exact up to 2^53 (beyond it
/// consecutive frames would be one time, and a loop to the largest int64 would never end).
inline constexpr std::int64_t kMaxFrame = std::int64_t(1) << 53;
inline constexpr const char* kMaxFrameWhy = "a frame is the time it stands for, a double";

/// Inclusive range of integer frame indices.
struct FrameRange {
  std::int64_t first = 0, last = 0;
  [[nodiscard]] std::int64_t count() const { return last - first + 1; }
};

/// The largest cluster size (MaxCount) a scene may carry; `ptc bench --max-count` takes the same range.
inline constexpr std::uint32_t kMaxSceneClusterCount = 1u << 20;

struct ScenePart {
  std::string name;
  AnimationPtr source;
};

class Scene {
 public:
  /// Builds the combined topology. Throws InputError (element "scene") for no parts, a part
  /// without a source or triangles, a combined size beyond 32-bit indices, or a frame range
  /// with first < 0, last < first or last beyond a part's finite frame_count(). Missing camera /
  /// light / frames get defaults: default_camera(rest bounds), a light above and behind the
  /// camera, frames 0 .. frame_count() - 1 (or 0 .. 59 when every part is unbounded).
  Scene(std::string name, std::vector<ScenePart> parts, std::optional<SceneCamera> camera = {},
        std::optional<SceneLight> light = {}, std::optional<FrameRange> frames = {});
  Scene(Scene&&) noexcept = default;
  Scene& operator=(Scene&&) noexcept = default;

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] std::size_t part_count() const { return parts_.size(); }
  [[nodiscard]] const ScenePart& part(std::size_t p) const { return parts_[p]; }
  [[nodiscard]] Animation& source(std::size_t p) { return *parts_[p].source; }
  [[nodiscard]] bool is_static(std::size_t p) const { return parts_[p].source->is_static(); }
  [[nodiscard]] bool all_static() const;
  /// Part p owns combined vertices [vertex_offset(p), vertex_offset(p + 1)) and triangles
  /// [triangle_offset(p), triangle_offset(p + 1)); p in 0 .. part_count().
  [[nodiscard]] std::size_t vertex_offset(std::size_t p) const { return vertex_offsets_[p]; }
  [[nodiscard]] std::size_t triangle_offset(std::size_t p) const { return triangle_offsets_[p]; }

  /// The combined topology with every part's rest positions.
  [[nodiscard]] const Mesh& rest() const { return parts_.size() == 1 ? parts_[0].source->rest() : rest_; }
  /// The camera and light: the scene's own, or the defaults of the constructor.
  [[nodiscard]] const SceneCamera& camera() const { return camera_; }
  [[nodiscard]] const SceneLight& light() const { return light_; }
  /// Whether camera() / light() are the scene's own (given to the constructor, a scene file's
  /// "camera" / "light", every built-in scene) rather than defaults: a command's rule is then
  /// flag > the scene's own > the command's framing of the mesh.
  [[nodiscard]] bool has_own_camera() const { return own_camera_; }
  [[nodiscard]] bool has_own_light() const { return own_light_; }
  /// Makes the current camera and light the scene's own (built-in scenes are composed with the
  /// constructor's defaults as their view).
  void adopt_view() { own_camera_ = own_light_ = true; }
  /// Gives the scene its own camera, or light (the view `ptc animate` recorded beside frames).
  void set_camera(const SceneCamera& camera) {
    camera_ = camera;
    own_camera_ = true;
  }
  void set_light(const SceneLight& light) {
    light_ = light;
    own_light_ = true;
  }
  [[nodiscard]] const FrameRange& frames() const { return frames_; }
  /// The scene's own cluster size: the MaxCount (= MaxSize) `ptc bench` clusters the scene with
  /// when given neither --max-count nor --clusters (`ptc cluster` and `ptc experiment` take their
  /// own flags). From a scene file's "clusters": {"max_count": N}, or a built-in scene's measured
  /// choice (docs/animation.md, the scene table); nullopt: the bench's default.
  [[nodiscard]] std::optional<std::uint32_t> cluster_max_count() const { return cluster_max_count_; }
  void set_cluster_max_count(std::optional<std::uint32_t> n) { cluster_max_count_ = n; }
  /// Smallest finite frame_count() over the parts; 0 when every part is unbounded.
  [[nodiscard]] std::size_t frame_count() const;

  /// Combined positions at `frame` (out.size() == rest().vertex_count(), else
  /// std::invalid_argument). With update_static = false the static parts' ranges are left as
  /// they are (a caller that filled them once saves the copy). Sources keep their own scratch:
  /// no allocation in the steady state.
  void positions(double frame, std::span<Vec3> out, bool update_static = true);

  /// Renumbers the combined vertices once (to_old[new] = old, a permutation that maps every
  /// part's range [vertex_offset(p), vertex_offset(p + 1)) onto itself, as
  /// bvh::cluster_vertex_order with the part offsets makes it; std::invalid_argument otherwise):
  /// each part renumbers its source (renumber_vertices: in place, or by a gather per frame,
  /// which describe() then says), rest() is renumbered, triangles keep their ids. A reference to
  /// rest() taken before does not survive it (one part: rest() is the part's source's own mesh).
  void renumber_vertices(std::span<const std::uint32_t> to_old);
  /// The vertex offsets of the parts (part_count() + 1 entries).
  [[nodiscard]] std::span<const std::size_t> vertex_offsets() const { return vertex_offsets_; }

  /// Several lines: one per part (name, static/animated, sizes, source description).
  [[nodiscard]] std::string describe() const;

 private:
  void combine_rest();  // rest_ from the parts' rest meshes (several parts; one part: rest() is its own)

  std::string name_;
  std::vector<ScenePart> parts_;
  std::vector<std::size_t> vertex_offsets_, triangle_offsets_;
  Mesh rest_;
  SceneCamera camera_;
  SceneLight light_;
  bool own_camera_ = false, own_light_ = false;
  FrameRange frames_;
  std::optional<std::uint32_t> cluster_max_count_;
};

/// The whole scene (its combined rest mesh) as one part moved by a deformer (toolkit/anim/
/// deformers.h): the stand-in motion of a static scene (`ptc bench --deform`). The scene's own
/// camera, light and cluster size are kept; frames default to 0..59. InputError for bad parameters.
[[nodiscard]] Scene deform_scene(const Scene& scene, const DeformParams& params, std::optional<FrameRange> frames = {});

/// Camera looking at the centre of `bounds` from the front-right-above direction (1/3, 1/3, 1)
/// normalised, far enough back for the bounding sphere to fill ~80% of a 45 degree view; up +y.
[[nodiscard]] SceneCamera default_camera(const Box3& bounds);

struct SceneOptions {
  /// Directory holding meshes/armadillo.off etc.; empty = default_data_dir().
  std::filesystem::path data_dir;
  /// Debian assimp-testmodels.
  std::filesystem::path assets_dir = "/usr/share/assimp/models";
};

/// $PTC_DATA_DIR when set and non-empty, else <dir of /proc/self/exe>/../data when that is a
/// directory, else "" (built-in scenes that need data then fail with a message saying so).
[[nodiscard]] std::filesystem::path default_data_dir();

struct BuiltinSceneInfo {
  std::string name;
  std::string description;  ///< one line
};
/// Every built-in scene, in listing order.
[[nodiscard]] const std::vector<BuiltinSceneInfo>& builtin_scenes();
[[nodiscard]] bool is_builtin_scene(const std::string& name);
/// Builds a built-in scene (InputError for an unknown name or missing data/asset files).
[[nodiscard]] Scene make_builtin_scene(const std::string& name, const SceneOptions& opt = {});

/// An animation from a file or directory: a mesh file (.off .obj .ply .stl) is a StaticSource;
/// anything else goes to load_animation() (frame directories, MD2, MD3, skinned assets).
/// InputError for a missing path or unreadable content.
[[nodiscard]] AnimationPtr open_animation_file(const std::filesystem::path& path);

/// Whether open_scene_input takes `arg` as a built-in scene: its name, and no existing path (a
/// path wins).
[[nodiscard]] bool names_builtin_scene(const std::string& arg);

/// SCENE argument: built-in name, mesh file, asset file or frame directory (not .json; see the
/// file comment). InputError naming the argument when it is none of them.
[[nodiscard]] Scene open_scene_input(const std::string& arg, const SceneOptions& opt = {});

/// Icosphere: the icosahedron subdivided `levels` times (midpoint) with every vertex projected
/// onto the sphere (20 * 4^levels triangles, outward-facing); vertices lie ON the sphere, facets
/// inside it. levels in 0..8.
[[nodiscard]] Mesh make_sphere_mesh(const Vec3& center, double radius, int levels);

}  // namespace ptc
