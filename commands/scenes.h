// `ptc scenes` as a library call: the built-in scenes with their sizes and frame ranges.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "toolkit/anim/scene.h"

namespace ptc {

struct ScenesOptions {
  SceneOptions scene_options;
  std::vector<std::string> names;  ///< restrict the listing (empty = all built-in scenes)
  bool json = false;               ///< schema ptc-scenes/1
};
/// Builds each listed built-in scene to report its sizes; a scene whose data is missing is
/// listed as unavailable with the reason (not an error). An unknown name is an InputError.
void cmd_scenes(const ScenesOptions& opt, std::ostream& out);

}  // namespace ptc
