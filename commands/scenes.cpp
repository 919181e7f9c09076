// `ptc scenes`.
#include "commands/scenes.h"

#include <optional>
#include <ostream>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/schema/json.h"
#include "toolkit/core/error.h"

namespace ptc {

void cmd_scenes(const ScenesOptions& opt, std::ostream& out) {
  std::vector<std::string> names = opt.names;
  if (names.empty())
    for (const auto& b : builtin_scenes()) names.push_back(b.name);
  for (const auto& n : names)
    if (!is_builtin_scene(n)) throw InputError("", "", n, "no such built-in scene");

  nlohmann::json list = nlohmann::json::array();
  if (!opt.json)
    out << fmt::format("{:<22} {:>10} {:>10} {:>8} {:>7} {:>10} {:>9}  {}\n", "scene", "triangles", "vertices", "animated",
                       "static", "frames", "max_count", "description");
  std::optional<std::pair<std::string, std::string>> missing;  // a scene the user named that cannot be made
  for (const auto& n : names) {
    std::string desc;
    for (const auto& b : builtin_scenes())
      if (b.name == n) desc = b.description;
    nlohmann::json row{{"name", n}, {"description", desc}};
    try {
      const Scene s = make_builtin_scene(n, opt.scene_options);
      std::size_t animated = 0;
      for (std::size_t k = 0; k < s.part_count(); ++k) animated += !s.is_static(k);
      row["available"] = true;
      row["triangles"] = s.rest().triangle_count();
      row["vertices"] = s.rest().vertex_count();
      row["animated_parts"] = animated;
      row["static_parts"] = s.part_count() - animated;
      row["frames"] = {s.frames().first, s.frames().last};
      row["source_frames"] = s.frame_count();  // 0 = unbounded
      // The scene's own cluster size (`ptc bench` clusters with it unless given --max-count); null: none.
      row["cluster_max_count"] = s.cluster_max_count() ? nlohmann::json(*s.cluster_max_count()) : nlohmann::json();
      if (!opt.json)
        out << fmt::format("{:<22} {:>10} {:>10} {:>8} {:>7} {:>10} {:>9}  {}\n", n, s.rest().triangle_count(),
                           s.rest().vertex_count(), animated, s.part_count() - animated,
                           fmt::format("{}:{}", s.frames().first, s.frames().last),
                           s.cluster_max_count() ? std::to_string(*s.cluster_max_count()) : std::string("-"), desc);
    } catch (const InputError& e) {
      row["available"] = false;
      row["reason"] = e.what();
      if (!opt.json) out << fmt::format("{:<22} unavailable: {}\n", n, e.what());
      if (!opt.names.empty() && !missing) missing.emplace(n, e.what());
    }
    list.push_back(std::move(row));
  }
  if (opt.json) out << dump_json({{"schema", "ptc-scenes/1"}, {"scenes", list}});
  // The listing is printed either way; a scene asked for by name that is unavailable is a failure
  // (exit 1), as it is for the commands that would trace it.
  if (missing) throw InputError("", "", "", missing->first + ": unavailable: " + missing->second);
}

}  // namespace ptc
