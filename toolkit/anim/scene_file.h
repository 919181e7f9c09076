// Scene files (JSON, schema "ptc-scene/1", documented in docs/animation.md) and the one resolver
// of a command's SCENE argument. The scene model itself is toolkit/anim/scene.h; the JSON library
// is linked into toolkit privately and included by scene_file.cpp alone.
//
// Errors: InputError with file = the scene file, location = "byte N" for JSON syntax errors, and
// element = the JSON path of the offending element ("meshes[2].deform.amplitude"); errors of a
// file a mesh refers to keep that file's own message after the element.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "toolkit/anim/scene.h"

namespace ptc {

/// Reads and builds a scene file. Relative paths inside are relative to the file's directory;
/// "${data}/..." and "${assets}/..." refer to opt.data_dir (or default_data_dir()) and
/// opt.assets_dir.
[[nodiscard]] Scene load_scene_file(const std::filesystem::path& path, const SceneOptions& opt = {});

/// Same, from text in memory; `name` stands for the file in messages, `base_dir` resolves
/// relative paths.
[[nodiscard]] Scene parse_scene_json(std::string_view text, const std::string& name,
                                     const std::filesystem::path& base_dir, const SceneOptions& opt = {});

/// The view `ptc animate` recorded beside the frames it wrote (DIR/manifest.json of schema
/// "ptc-animate/1": results.camera and results.light where results.camera_own and
/// results.light_own say they were the scene's own, not the defaults a command replaces with its
/// own framing; a manifest without those flags gives neither), and parameters.scene and .frames;
/// nullopt for a path that is no such directory (another program's manifest.json, or none, is
/// not read). A malformed camera or light there: InputError naming manifest.json and the element.
struct AnimateView {
  std::optional<SceneCamera> camera;
  std::optional<SceneLight> light;
  std::string scene;  ///< the scene the frames were made from ("" if not recorded)
  std::optional<FrameRange> frames;  ///< the scene's frames they are (parameters.frames)
};
[[nodiscard]] std::optional<AnimateView> animate_view(const std::filesystem::path& dir);

/// A command's SCENE argument: a path ending in .json (any case) is a scene file; anything else
/// goes to open_scene_input (built-in name, mesh file, asset file, frame directory). A frame
/// directory `ptc animate` wrote takes the camera and light it recorded (animate_view).
[[nodiscard]] Scene open_scene(const std::string& arg, const SceneOptions& opt = {});
/// Whether open_scene(arg) takes `arg` as a scene file (.json, any case, and not a directory).
[[nodiscard]] bool is_scene_file(const std::string& arg);
/// Whether open_scene(arg) may read SceneOptions::data_dir: a scene file (its "${data}/" paths)
/// or a built-in scene (names_builtin_scene); a mesh, an asset, frames or a glob never do.
[[nodiscard]] bool scene_reads_data_dir(const std::string& arg);

}  // namespace ptc
