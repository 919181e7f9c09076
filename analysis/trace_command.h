// `ptc trace` and `ptc bench` as library calls (apps/ptc only parses the arguments).
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "analysis/images.h"
#include "analysis/peer_bench.h"
#include "analysis/trace_camera.h"
#include "analysis/trace_render.h"
#include "toolkit/anim/scene.h"

namespace ptc {

/// Writes an image file (viz::write_png in the command; analysis itself never includes VTK).
/// Must replace the file atomically and throw on failure.
using ImageWriter = std::function<void(const std::filesystem::path&, const RgbImage&)>;

struct TraceCommandOptions {
  std::filesystem::path input;         ///< SCENE: built-in name, .json scene file, mesh/asset file, frame directory
  SceneOptions scene_options;          ///< data and assets directories of built-in scenes / scene files
  std::optional<std::string> frame;    ///< "F": one frame (default: the scene's first)
  std::optional<std::string> frames;   ///< "A:B": a sequence (images named shaded_0000.png ..., one CSV row per frame)
  std::filesystem::path clusters;      ///< directory of `ptc cluster` (triangles.csv); empty: triangle BVH
  std::uint32_t cluster_group_size = bvh::cluster_scene_defaults().cluster_group_size;  ///< two-level build (0: plain)
  std::filesystem::path out_dir;       ///< images, trace.csv, manifest.json (required)
  CameraSpec camera;
  RenderConfig render;                 ///< size, shadows, AO, seed, light, threads (0 = all cores)
  std::vector<std::string> argv;       ///< recorded in the manifest
};

/// Opens the scene (analysis/scene_file.h open_scene) and its clusters, builds the static parts'
/// BVH once and the moving parts' BVH (analysis/scene_trace.h), and per frame (one: --frame or
/// the scene's first; a sequence: --frames A:B) updates the moving BVH from the positions,
/// renders the view and writes shaded, depth, normal, cost_nodes, cost_triangles (and ao) PNGs
/// (named shaded.png for one frame, shaded_0007.png for frame 7 of a sequence), cost_legend.png,
/// trace.csv (one row per frame, columns in docs/tracing.md) and manifest.json into `out_dir`
/// atomically; prints a summary table to `out`. Camera: given fields > the scene's camera
/// (built-in scenes, scene files with "camera") > framing the first frame; light likewise.
/// Bad input -> InputError.
void cmd_trace(const TraceCommandOptions& opt, const ImageWriter& write_image, std::ostream& out);

/// The column list of trace.csv (schema ptc-trace/1).
[[nodiscard]] std::vector<std::string> trace_csv_columns();

struct BenchCommandOptions {
  std::filesystem::path input;     ///< SCENE (as for cmd_trace)
  SceneOptions scene_options;
  /// "A:B" (scene frames A..B) or "N" (N frames from the scene's first, or 0..N-1 of the stand-in
  /// deformation); nullopt: the scene's range when it is animated, else config.frames frames.
  std::optional<std::string> frames;
  /// --deform was given explicitly: twist/wave on an animated scene is then an error.
  bool deform_given = false;
  std::filesystem::path clusters;  ///< triangles.csv directory; empty: growth/Acc clustering with max_count
  std::filesystem::path out_dir;   ///< bench.csv, summary.csv, manifest.json (required)
  PeerBenchConfig config;
  std::vector<std::string> argv;
};
/// Runs the peer benchmark (analysis/peer_bench.h) on the scene's combined mesh, frames from the
/// scene when it has moving parts, else the stand-in deformation config.deformation of its
/// positions, and writes bench.csv (per frame and configuration), summary.csv (medians and
/// ratios) and manifest.json; prints the tables.
void cmd_bench(const BenchCommandOptions& opt, std::ostream& out);

}  // namespace ptc
