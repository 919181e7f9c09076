// `ptc trace` as a library call (apps/ptc only parses the arguments).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "render/images.h"
#include "render/camera.h"
#include "render/view.h"
#include "bvh/scene_config.h"
#include "bvh/vertex_order.h"
#include "toolkit/anim/scene.h"

namespace ptc {

struct TraceCommandOptions {
  std::filesystem::path input;         ///< SCENE: built-in name, .json scene file, mesh/asset file, frame directory
  SceneOptions scene_options;          ///< data and assets directories of built-in scenes / scene files
  std::optional<std::string> frame;    ///< "F": one frame (default: the scene's first)
  std::optional<std::string> frames;   ///< "A:B": a sequence (images named shaded_0000.png ..., CSV rows per frame)
  bool extend_frames = false;          ///< --extend-frames: frames outside the scene's listed range
  /// --deform KIND|none: a static scene's stand-in motion (the one `ptc bench` measures; none, the
  /// default here, keeps it still); refused for an animated scene.
  std::optional<std::string> deform;
  std::filesystem::path clusters;      ///< directory of `ptc cluster` (triangles.csv); empty: triangle BVH
  /// --cluster-groups: the cluster BVH's two-level build over groups of at most N clusters (0:
  /// the plain build). Unset: the scene's moving parts take cluster_scene_defaults() (16), and a
  /// still scene (every part static, built once) the plain build: the groups make the per-frame
  /// rebuild cheap, and its one tree is never rebuilt (docs/tracing.md, "A still scene").
  std::optional<std::uint32_t> cluster_group_size;
  /// --cluster-fallback: the moving cluster BVH traces a frame on a triangle BVH when its swelling
  /// exceeds this (bvh::SceneConfig::fallback_swelling; 0: never). Unset: bvh::kAutoFallbackSwelling;
  /// given for a still scene (built once, nothing moves), a usage error.
  std::optional<double> cluster_fallback;
  /// --fallback-refit: the triangle fallback's bvh::SceneConfig::refit_growth (0: rebuilt every
  /// frame). Unset: bvh::kAutoFallbackRefitGrowth.
  std::optional<double> fallback_refit;
  /// --fallback-sah: how the triangle fallback is built (bvh::FallbackSah; unset: Directions, for
  /// the primary rays' mean directions).
  std::optional<bvh::FallbackSah> fallback_sah;
  /// --group-trees: what the two-level build does inside a group (unset: the default, refit).
  /// Given for a still scene without --cluster-groups, it is a usage error (nothing to do).
  std::optional<bvh::GroupTrees> group_trees;
  /// --vertex-order: with --clusters, Clusters renumbers the scene's vertices once so that each
  /// cluster's are consecutive (the method's precomputation, as in `ptc bench`: the cluster BVH's
  /// per-frame pass then streams instead of gathering, which pays over a sequence); Input, the
  /// default, keeps the file's order. The images, counters and hits are the same either way.
  bvh::VertexOrder vertex_order = bvh::VertexOrder::Input;
  std::filesystem::path out_dir;       ///< images, trace.csv, manifest.json (required)
  CameraSpec camera;
  RenderConfig render;                 ///< size, shadows, AO, seed, light, threads (0 = all cores)
  /// "MIN:MAX": the cost images' colour range (default: each image's 0..max), so that frames,
  /// runs and the triangle and cluster BVHs compare; `ptc viz heatmap` draws them with numbers.
  std::optional<std::string> cost_range;
  bool json = false;                   ///< stdout: JSON (schema ptc-trace-summary/1) instead of the table
  std::vector<std::string> argv;       ///< recorded in the manifest
};

/// Opens the scene (toolkit/anim/scene_file.h open_scene) and its clusters, builds the static parts'
/// BVH once and the moving parts' BVH (bvh/scene_tracer.h), and per frame (one: --frame or
/// the scene's first; a sequence: --frames A:B) updates the moving BVH from the positions,
/// renders the view and writes shaded, depth, normal, cost_nodes, cost_triangles (and ao) PNGs
/// (named shaded.png for one frame, shaded_0007.png for frame 7 of a sequence), cost_legend.png,
/// trace.csv (rows per frame and pass, analysis/experiments/trace.h) and manifest.json into `out_dir`
/// atomically; prints a summary table to `out`. Camera: given fields > the scene's camera
/// (built-in scenes, scene files with "camera") > framing the first frame; light likewise.
/// Bad input -> InputError.
void cmd_trace(const TraceCommandOptions& opt, std::ostream& out);

}  // namespace ptc
