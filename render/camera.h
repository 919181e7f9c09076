// Cameras of `ptc trace` / `ptc bench`: a pinhole camera from eye / look-at / up / field of
// view with every degenerate case refused, and the default camera that frames the whole mesh.
//
// Conventions (docs/tracing.md): right-handed world; the camera looks along
// forward = normalize(look_at - eye); image x runs along right = normalize(forward x up), image y
// along up' = right x forward (the component of `up` orthogonal to forward); pixel (0, 0) is the
// top-left one; `fov` is the VERTICAL field of view in degrees; pixels are square, so the
// horizontal field of view follows from width / height. Primary rays go through pixel centres
// (bvh::primary_rays) with unit directions, so a hit's t is its distance from the eye.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "bvh/camera.h"

namespace ptc {

/// What the user asked for; every field optional (the default camera fills the gaps).
struct CameraSpec {
  std::optional<Vec3> eye, look_at, up;
  std::optional<double> fov_deg;  ///< vertical, degrees, in (0, 180)
  /// The flag an error about the eye and look-at point names: the eye's, unless the eye came from
  /// the scene and --look-at was given (camera_for sets it).
  const char* eye_look_flag = "--eye";
};

/// Largest image side (pixels) a camera, a command and the benchmark accept.
inline constexpr int kMaxImageSide = 16384;

/// Default field of view, degrees.
inline constexpr double kDefaultFovDeg = 45.0;

/// The camera for a mesh with bounds `bounds` and an image of width x height pixels:
/// - look_at defaults to the centre of the bounds, up to +y, fov to 45 degrees;
/// - with eye, the camera is used as given;
/// - without eye, the camera looks along -z (along -y when `up` is parallel to z, for z-up
///   meshes) at look_at and stands just far enough back that every corner of the bounds
///   projects inside the image with a 5% margin, for any aspect ratio.
/// Throws UsageError (exit 2; element = the offending option: "--eye", "--up", "--fov") for: a
/// non-finite value, fov outside (0, 180), eye == look_at or so far apart that their difference
/// overflows, a zero up, an up parallel to the view direction; and InputError naming
/// `mesh_name` for a mesh whose bounds are empty or not finite without an explicit eye, or too
/// large for the default camera to frame.
[[nodiscard]] bvh::PinholeCamera make_camera(const CameraSpec& spec, const Box3& bounds, int width, int height,
                                             std::string_view mesh_name = {});

/// Primary rays of the camera (bvh::primary_rays; validates the image size: 1..kMaxImageSide per side,
/// std::invalid_argument otherwise).
[[nodiscard]] bvh::RayBatch camera_rays(const bvh::PinholeCamera& cam, int width, int height);

}  // namespace ptc
