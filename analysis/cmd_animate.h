// `ptc animate` and `ptc scenes` as library calls (apps/ptc only parses arguments).
//
// animate: writes frames A..B of a scene as a mesh sequence, one file per frame
//   DIR/frame_<frame, 4+ digits>.<ply|obj>   the combined scene mesh (every part, concatenated
//                                             in part order; same topology in every file)
//   DIR/manifest.json                        schema ptc-animate/1: RunManifest + scene parts
//                                             (vertex/triangle ranges, static or animated),
//                                             camera, light, the frame list and files
//   DIR/stats.csv                            with --stats (columns below)
// The directory is written whole or not at all (analysis/output_dir.h).
//
// stats.csv (schema ptc-animate-stats/1), one row per frame:
//   frame, bbox_{min,max}_{x,y,z}, bbox_diagonal, total_area,
//   area_ratio_min, area_ratio_mean, area_ratio_max  - per-triangle area / its area at frame A,
//                                                       over triangles of non-zero area at A
//   degenerate_at_first                               - triangles of zero area at frame A (excluded)
#pragma once

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "toolkit/anim/scene.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {

/// "A:B" (inclusive, 0 <= A <= B) or "A" (one frame); decimal integers. InputError (element
/// "--frames") for anything else.
[[nodiscard]] FrameRange parse_frame_range(std::string_view s);

/// Per-frame shape statistics of `positions` against the first frame's (same topology).
struct FrameStats {
  std::int64_t frame = 0;
  Box3 bounds;
  double total_area = 0;
  double area_ratio_min = 0, area_ratio_mean = 0, area_ratio_max = 0;  ///< NaN when no triangle counts
  std::size_t degenerate_at_first = 0;
};
/// first_areas: per-triangle areas of the reference frame (triangle_areas()).
[[nodiscard]] FrameStats frame_stats(std::int64_t frame, std::span<const Tri> triangles, std::span<const Vec3> positions,
                                     std::span<const double> first_areas);
[[nodiscard]] std::vector<double> triangle_areas(std::span<const Tri> triangles, std::span<const Vec3> positions);

struct AnimateOptions {
  std::string scene;                     ///< SCENE (analysis/scene_file.h open_scene)
  SceneOptions scene_options;
  std::optional<std::string> frames;     ///< "A:B"; nullopt = the scene's own frame range
  std::filesystem::path out_dir;         ///< required
  MeshFormat format = MeshFormat::Ply;   ///< Ply (binary) or Obj
  bool stats = false;
  bool json = false;
  std::vector<std::string> argv;
};
void cmd_animate(const AnimateOptions& opt, std::ostream& out);

struct ScenesOptions {
  SceneOptions scene_options;
  std::vector<std::string> names;  ///< restrict the listing (empty = all built-in scenes)
  bool json = false;               ///< schema ptc-scenes/1
};
/// Builds each listed built-in scene to report its sizes; a scene whose data is missing is
/// listed as unavailable with the reason (not an error). An unknown name is an InputError.
void cmd_scenes(const ScenesOptions& opt, std::ostream& out);

}  // namespace ptc
