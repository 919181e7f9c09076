// A stand-in animation for the benchmarks until the animation issue brings real sources: a
// small pure function that deforms rest positions per frame. Swap it for an Animation
// (toolkit/anim/animation.h) source when one exists; nothing else in the benchmark depends on it.
#pragma once

#include <optional>
#include <span>
#include <string_view>

#include "toolkit/core/types.h"

namespace ptc {

enum class Deformation {
  None,   ///< positions stay the rest pose (every frame rebuilds over the same positions)
  Twist,  ///< rotation about the vertical (y) axis through the bounds' centre, angle growing linearly with height
  Wave,   ///< a travelling sine displacement along z, as a function of x
};
[[nodiscard]] const char* to_string(Deformation d);
[[nodiscard]] std::optional<Deformation> parse_deformation(std::string_view s);  ///< none|twist|wave

/// Frames per cycle: the amplitude of frame f is sin(2 pi f / kDeformPeriod), so frame 0 is the
/// rest pose and the motion is periodic.
inline constexpr int kDeformPeriod = 24;

/// out[v] = rest[v] deformed for frame `frame` (>= 0); `bounds` = the rest pose's bounds.
/// Twist: angle = 0.6 rad * a(f) * (y - y_min) / (y_max - y_min) about the y axis through the
/// bounds' centre (distances to that axis and y are preserved). Wave: z += 0.05 * diag * a(f) *
/// sin(2 pi (2 (x - x_min) / (x_max - x_min) + f / kDeformPeriod)) (only z changes).
/// out.size() must equal rest.size() (std::invalid_argument otherwise).
void deform(std::span<const Vec3> rest, const Box3& bounds, Deformation kind, int frame, std::span<Vec3> out);

}  // namespace ptc
