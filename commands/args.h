// The one parser of each argument shape that several commands share: frame numbers and ranges
// ("F", "A:B"), vectors ("X,Y,Z"); and the one check of a frame range against a scene. Errors
// are UsageError (exit 2) with the flag as the element, in the flag's own words.
#pragma once

#include <cstdint>
#include <optional>
#include <utility>
#include <string>
#include <string_view>

#include "toolkit/anim/scene.h"
#include "toolkit/core/types.h"

namespace ptc {

/// "F": a frame number, a decimal integer >= 0. `flag` names the option in errors ("--frame").
[[nodiscard]] std::int64_t parse_frame(std::string_view s, std::string_view flag);

/// "A:B" (inclusive, 0 <= A <= B) or "A" (the one frame A); decimal integers.
[[nodiscard]] FrameRange parse_frame_range(std::string_view s, std::string_view flag);

/// "X,Y,Z" (three finite decimal numbers separated by commas, blanks around them allowed) or
/// nullopt with `why` set ("expected 3 comma-separated numbers", "not a finite number 'nan'").
/// "MIN:MAX" with two finite numbers, MIN < MAX, either possibly negative ("-1:1", "-2.5:-0.5");
/// UsageError naming `flag` otherwise.
[[nodiscard]] std::pair<double, double> parse_value_range(const std::string& s, std::string_view flag);

[[nodiscard]] std::optional<Vec3> parse_vec3(std::string_view s, std::string* why = nullptr);

/// --width/--height: 1..kMaxImageSide (render/camera.h) each; UsageError otherwise.
void check_image_size(int width, int height);

/// --threads: 0 (not given) = all cores (oneTBB's default concurrency), the one default of every
/// command; any other value as given.
[[nodiscard]] unsigned resolve_threads(unsigned threads);

/// auto (auto_value), off (0) or a finite number above `above`; nothing for anything else (the
/// two flags below).
[[nodiscard]] std::optional<double> parse_auto_off_or_above(const std::string& s, double auto_value, double above);
/// --cluster-fallback of `ptc bench` and `ptc trace`: auto (bvh::kAutoFallbackSwelling), off (0)
/// or a finite swelling above 1; nothing for anything else.
[[nodiscard]] std::optional<double> parse_cluster_fallback(const std::string& s);
/// --fallback-refit of `ptc bench` and `ptc trace`: auto (bvh::kAutoFallbackRefitGrowth), off (0)
/// or a finite growth above 0; nothing for anything else.
[[nodiscard]] std::optional<double> parse_fallback_refit(const std::string& s);

/// Frames a command may use: those of the scene's listed range (Scene::frames(): a scene file's
/// "frames", a built-in scene's range), or with `extend` (--extend-frames) any frame the sources
/// can give (procedural sources go on forever; a finite source stops at its last frame).
/// UsageError naming `flag` and the scene's range otherwise.
void check_frames(const Scene& scene, const FrameRange& range, const std::string& scene_arg, std::string_view flag,
                  bool extend);

}  // namespace ptc
