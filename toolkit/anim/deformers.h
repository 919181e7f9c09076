// Procedural deformers: an Animation that moves the vertices of any rest mesh by a closed-form
// function of (rest position, frame time). They make animated scenes out of the static sample
// meshes at any size (deform a subdivided mesh), and one of them, Explode, is the hostile case
// the method names as its limit (Garanzha 2009: clusters whose triangles fly apart).
//
// Frame of reference: every parameter is relative to the rest mesh's axis-aligned bounding box
// B (centre c, extent e, diagonal d = |e|), so one parameter set fits a mesh of any scale and
// position. "axis" names a box axis (x, y or z) and the line through c along it.
//
// Kinds (t = frame time, s(t) = sin(2 pi t / period); all identities at amplitude 0):
//   twist    rotate each vertex about `axis` by  amplitude * s(t) * u,   u = (p_axis - c_axis) / (e_axis / 2)
//            in [-1, 1]: the two ends of the box turn by +-amplitude radians, the middle stays.
//   bend     bend the box about an axis perpendicular to `axis` and `direction`, in their plane
//            (Barr 1984, "Global and local deformations of solid primitives", SIGGRAPH, eq. for
//            the bend): curvature k = amplitude * s(t) / e_axis (total bend angle amplitude * s(t)
//            radians over the box length), theta = k (p_axis - c_axis);
//              axis'      = c_axis + sin(theta) / k - w sin(theta)
//              direction' = c_dir  + w cos(theta) + (1 - cos(theta)) / k,   w = p_dir - c_dir
//            (evaluated without cancellation: sin(theta)/k through sinc, (1 - cos)/k through
//            2 sin^2(theta/2)/k; k = 0 is the identity exactly). The centre slice stays put.
//   wave     travelling sine along `axis`, displacing along `direction`:
//              p_dir += amplitude * d * sin(2 pi ((p_axis - lo_axis) / (wavelength * e_axis) - t / period))
//            amplitude is a fraction of the diagonal, wavelength a fraction of the axis extent.
//   rigid    rotation about `axis` (through c) by 2 pi t / period radians (times amplitude: 1 =
//            one full turn per period, 0 = no rotation) then a translation velocity * d * t.
//            Edge lengths are unchanged to rounding.
//   explode  every triangle flies along its rest unit normal (the direction from c to its
//            centroid for a zero-area triangle) by amplitude * d * t * f, f in [0.5, 1.5) a
//            deterministic hash of the triangle index, so triangles separate. Triangles of a
//            mesh share vertices, so the deformer first turns the mesh into a triangle SOUP (3
//            own vertices per triangle, triangle t uses 3t, 3t+1, 3t+2): rest() is that soup,
//            not the input; triangle count, order and every triangle's shape and area are kept,
//            connectivity is not. This is the method's limit case: a precomputed cluster's
//            triangles drift apart and its bounding sphere grows without bound.
//
// Cost: positions() is one pass over the vertices (rest positions and per-vertex constants
// precomputed at construction), multithreaded with oneTBB, no allocation.
#pragma once

#include <optional>
#include <string_view>

#include "toolkit/anim/animation.h"

namespace ptc {

enum class DeformKind { Twist, Bend, Wave, Rigid, Explode };

/// "twist", "bend", "wave", "rigid", "explode"; nullopt for anything else.
[[nodiscard]] std::optional<DeformKind> parse_deform_kind(std::string_view name);
[[nodiscard]] std::string_view to_string(DeformKind kind);
/// "x", "y", "z" -> 0, 1, 2; nullopt otherwise.
[[nodiscard]] std::optional<int> parse_axis(std::string_view name);

struct DeformParams {
  DeformKind kind = DeformKind::Twist;
  /// Box axis the deformation runs along (twist, bend, wave) or turns about (rigid): 0 x, 1 y, 2 z.
  int axis = 1;
  /// Box axis that is displaced (bend, wave); must differ from `axis`. Unused otherwise.
  int direction = 0;
  /// twist: end angle (radians); bend: total bend angle (radians); wave: fraction of the box
  /// diagonal; rigid: turns per period; explode: fraction of the diagonal per frame. Finite.
  double amplitude = 1.0;
  /// Frames per cycle (twist, bend, wave, rigid); > 0. Unused by explode.
  double period = 60.0;
  /// wave: wavelength as a fraction of the box extent along `axis`; > 0.
  double wavelength = 0.5;
  /// rigid: translation per frame in units of the box diagonal (finite).
  Vec3 velocity = Vec3::Zero();
};

/// The parameters of the built-in scenes' deformers (armadillo-twist, ...), also the stand-in
/// motion of `ptc bench --deform KIND` on a static scene: twist about y by up to pi/2 and bend
/// of pi/2 (period 60), wave along x displacing z by 3% of the diagonal (wavelength half the
/// width, period 30), rigid: one turn per 60 frames about y while moving 0.5% of the diagonal
/// per frame along x; explode: 0.4% of the diagonal per frame.
[[nodiscard]] DeformParams deform_preset(DeformKind kind);

/// Checks the parameters; returns "" or the reason they are invalid ("period must be > 0").
[[nodiscard]] std::string check(const DeformParams& p);

/// A deformer of `rest` (which must have at least one triangle). Throws InputError (element =
/// "deformer", reason from check()) for bad parameters and for a rest mesh that is empty or
/// with a non-finite vertex.
[[nodiscard]] AnimationPtr make_deformer(Mesh rest, const DeformParams& params);

}  // namespace ptc
