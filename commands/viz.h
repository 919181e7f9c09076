// `ptc viz partition|heatmap|panel|export` as a library call (apps/ptc only parses the flags).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "render/camera.h"
#include "toolkit/anim/scene.h"

namespace ptc {

enum class VizKind { Partition, Heatmap, Panel, Export };
[[nodiscard]] std::optional<VizKind> parse_viz_kind(std::string_view s);  ///< partition|heatmap|panel|export
[[nodiscard]] std::string_view to_string(VizKind k);

/// Per-pixel metrics of the tracer (its counters of the primary rays).
inline constexpr const char* kPixelMetrics[] = {"nodes_visited", "triangles_tested"};

struct VizCommandOptions {
  VizKind kind = VizKind::Partition;
  std::filesystem::path input;       ///< SCENE as `ptc trace` takes it
  SceneOptions scene_options;
  std::optional<std::string> frame;  ///< "F" (default: the scene's first frame)
  std::optional<std::string> frames; ///< "A:B": a series (numbered files, one fixed colour range)
  bool extend_frames = false;
  std::optional<std::string> deform; ///< --deform KIND: a static scene's stand-in motion (twist, bend, wave, rigid, explode)
  std::filesystem::path clusters;    ///< `ptc cluster --out DIR` (needed by every kind but a pixel heatmap)
  std::string metric;                ///< heatmap / panel: a per-cluster metric or nodes_visited | triangles_tested
  std::optional<std::string> range;  ///< "MIN:MAX": the colour range (default: the values', over the series)
  bool borders = true;               ///< partition: cluster borders as lines
  bool lighting = true;              ///< false: flat colours (every pixel exactly its cluster's colour)
  int width = 640, height = 640;
  CameraSpec camera;
  std::optional<Vec3> light;
  bool shadows = false;              ///< panel / pixel heatmap: shadow rays in the shaded image
  unsigned threads = 0;
  bool interactive = false;          ///< partition / heatmap of one frame: a window on the user's display
  bool json = false;
  bool force_xvfb = false;           ///< --xvfb: render on a private Xvfb even when $DISPLAY answers
  std::filesystem::path out_dir;
  std::vector<std::string> argv;
};

/// Renders / exports the frames (kinds: docs/viz.md) into `out_dir` atomically with a manifest.
/// Bad input -> InputError; bad usage -> UsageError naming the flag.
void cmd_viz(const VizCommandOptions& opt, std::ostream& out);

}  // namespace ptc
