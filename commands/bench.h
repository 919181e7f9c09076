// `ptc bench SCENE ... --out DIR` as a library call: the side-by-side benchmark against Embree
// (analysis/experiments/bench.h) over a scene's frames, or over the stand-in motion of a static
// scene (--deform), writing bench.csv, summary.csv and manifest.json.
#pragma once

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "analysis/experiments/bench.h"
#include "toolkit/anim/scene.h"

namespace ptc {

struct BenchCommandOptions {
  std::filesystem::path input;     ///< SCENE: built-in name, .json scene file, mesh/asset file, frame directory
  SceneOptions scene_options;
  /// --frames "A:B" (or "F"): scene frames; nullopt: an animated scene's range, else 0:4 of the stand-in motion.
  std::optional<std::string> frames;
  bool extend_frames = false;      ///< --extend-frames: frames outside the scene's listed range
  /// --deform KIND: the stand-in motion of a static scene (deform_preset(KIND)), or "none" (the
  /// rest pose every frame); nullopt: twist for a static scene. An animated scene refuses it.
  std::optional<std::string> deform;
  std::filesystem::path clusters;  ///< triangles.csv directory; empty: growth/Acc clustering with max_count
  /// --max-count N: MaxCount = MaxSize of that clustering; nullopt: the scene's own
  /// (Scene::cluster_max_count), else config.max_count.
  std::optional<std::uint32_t> max_count;
  std::filesystem::path out_dir;   ///< bench.csv, summary.csv, manifest.json (required)
  PeerBenchConfig config;          ///< frames are set from `frames`; threads 0 = all cores; light from `light`
  /// --light X,Y,Z: the shadow rays' point light; nullopt: the scene's own, else render's
  /// default_light for the camera (commands/scene_args.h light_for).
  std::optional<Vec3> light;
  bool shadows = true;             ///< false (--no-shadows): primary rays only
  bool json = false;               ///< print the summary as JSON
  std::vector<std::string> argv;
};

/// Runs the benchmark and writes its outputs atomically; prints the tables (or JSON) to `out`.
/// Bad input -> InputError.
void cmd_bench(const BenchCommandOptions& opt, std::ostream& out);

}  // namespace ptc
