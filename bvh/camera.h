// A pinhole camera and its primary rays (a first version of the cameras and ray sets).
#pragma once

#include <array>

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

/// The area weights (BuildConfig::area_weights) of a tree built for `rays`: 2 mean |d_a| over
/// their unit directions d, so that directions spread evenly over the sphere give about
/// (1, 1, 1), the plain SAH (a box's mean projected area is a quarter of its surface area), and
/// rays along one axis weight only the faces across it. Each weight is at least 1/64 of the
/// largest (a box flat across the rays keeps some area). Rays whose direction is zero or not
/// finite are left out; with none left: (1, 1, 1).
[[nodiscard]] std::array<float, 3> direction_area_weights(const RayBatch& rays);
/// The same for the primary rays of `cam` (primary_rays(cam, width, height), the same bits),
/// without making them.
[[nodiscard]] std::array<float, 3> direction_area_weights(const PinholeCamera& cam, int width, int height);

}  // namespace ptc::bvh
