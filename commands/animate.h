// `ptc animate` as a library call (apps/ptc only parses arguments).
//
// animate: writes frames A..B of a scene as a mesh sequence, one file per frame
//   DIR/frame_<frame, 4+ digits>.<ply|obj>   the combined scene mesh (every part, concatenated
//                                             in part order; same topology in every file)
//   DIR/manifest.json                        schema ptc-animate/1: RunManifest + scene parts
//                                             (vertex/triangle ranges, static or animated),
//                                             camera, light, the frame list and files
//   DIR/stats.csv                            with --stats (columns below)
// The directory is written whole or not at all (commands/output_dir.h).
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

struct AnimateOptions {
  std::string scene;                     ///< SCENE (toolkit/anim/scene_file.h open_scene)
  SceneOptions scene_options;
  std::optional<std::string> frames;     ///< "A:B"; nullopt = the scene's own frame range
  bool extend_frames = false;            ///< --extend-frames: frames outside the scene's listed range
  /// --deform KIND|none: the stand-in motion of a static scene (commands/scene_args.h
  /// apply_stand_in, the motion ptc bench measures); nullopt or none: the scene as it is.
  std::optional<std::string> deform;
  std::filesystem::path out_dir;         ///< required
  MeshFormat format = MeshFormat::Ply;   ///< Ply (binary) or Obj
  bool stats = false;
  bool json = false;
  std::vector<std::string> argv;
};
void cmd_animate(const AnimateOptions& opt, std::ostream& out);

}  // namespace ptc
