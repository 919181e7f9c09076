// Scene files (JSON, schema "ptc-scene/1", documented in docs/animation.md) and the one resolver
// of a command's SCENE argument. The scene model itself is toolkit/anim/scene.h; the JSON library
// is linked into toolkit privately and included by scene_file.cpp alone.
//
// Errors: InputError with file = the scene file, location = "byte N" for JSON syntax errors, and
// element = the JSON path of the offending element ("meshes[2].deform.amplitude"); errors of a
// file a mesh refers to keep that file's own message after the element.
#pragma once

#include <filesystem>
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

/// A command's SCENE argument: a path ending in .json (any case) is a scene file; anything else
/// goes to open_scene_input (built-in name, mesh file, asset file, frame directory).
[[nodiscard]] Scene open_scene(const std::string& arg, const SceneOptions& opt = {});
/// Whether open_scene(arg) takes `arg` as a scene file (.json, any case).
[[nodiscard]] bool is_scene_file(const std::string& arg);
/// Whether open_scene(arg) may read SceneOptions::data_dir: a scene file (its "${data}/" paths)
/// or a built-in scene (names_builtin_scene); a mesh, an asset, frames or a glob never do.
[[nodiscard]] bool scene_reads_data_dir(const std::string& arg);

}  // namespace ptc
