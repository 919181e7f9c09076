// A pinhole camera and its primary rays (a first version of the cameras and ray sets).
#pragma once

#include "bvh/tracer.h"

namespace ptc::bvh {

struct PinholeCamera {
  Vec3 eye = Vec3::Zero();
  Vec3 forward = Vec3(0, 0, -1);  ///< unit view direction
  Vec3 right = Vec3(1, 0, 0);     ///< unit, image x
  Vec3 up = Vec3(0, 1, 0);        ///< unit, image y (rows go down)
  double fov_y_deg = 45.0;        ///< vertical field of view, degrees, in (0, 180)
};

/// A camera looking along `view_dir` (any non-zero vector) at the centre of `bounds`, just far
/// enough back that all eight corners of the box project into a square image (5% margin).
/// `up_hint` picks the image's up direction (must not be parallel to view_dir).
[[nodiscard]] PinholeCamera frame_box(const Box3& bounds, const Vec3& view_dir = Vec3(0, 0, -1),
                                      const Vec3& up_hint = Vec3(0, 1, 0), double fov_y_deg = 45.0);

/// width x height rays through the pixel centres, row-major from the top-left pixel; unit
/// directions, tmin = 0, tmax = inf. Square pixels.
[[nodiscard]] RayBatch primary_rays(const PinholeCamera& cam, int width, int height);

}  // namespace ptc::bvh
