#include "render/camera.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "toolkit/core/error.h"

namespace ptc {
namespace {

bool finite(const Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

std::string fmt_vec(const Vec3& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%g,%g,%g", v.x(), v.y(), v.z());
  return buf;
}

}  // namespace

bvh::PinholeCamera make_camera(const CameraSpec& spec, const Box3& bounds, int width, int height,
                               std::string_view mesh_name) {
  if (width < 1 || height < 1) throw std::invalid_argument("make_camera: image size must be positive");
  const double fov = spec.fov_deg.value_or(kDefaultFovDeg);
  if (!(fov > 0.0 && fov < 180.0))
    throw UsageError("--fov", "the field of view must be in (0, 180) degrees, got " + std::to_string(fov));
  for (const auto& [name, v] : {std::pair{"--eye", spec.eye}, std::pair{"--look-at", spec.look_at}, std::pair{"--up", spec.up}})
    if (v && !finite(*v)) throw UsageError(name, "not a finite vector");
  const bool box_ok = !bounds.empty() && finite(bounds.lo) && finite(bounds.hi);
  if (!spec.look_at && !box_ok)
    throw InputError(std::string(mesh_name), "", "--look-at", "the mesh has no finite bounds to look at");
  const Vec3 look = spec.look_at.value_or(box_ok ? bounds.center() : Vec3::Zero());
  const Vec3 up = spec.up.value_or(Vec3(0, 1, 0));
  if (!(up.cwiseAbs().maxCoeff() > 0.0)) throw UsageError("--up", "the up vector is zero");
  const Vec3 upn = up.stableNormalized();  // (the norm of a finite vector may overflow)

  Vec3 forward;
  if (spec.eye) {
    const Vec3 d = look - *spec.eye;
    if (!finite(d))  // a difference that overflows
      throw UsageError(spec.eye_look_flag, "eye " + fmt_vec(*spec.eye) + " and look-at " + fmt_vec(look) +
                                               " are too far apart (their difference overflows)");
    if (!(d.cwiseAbs().maxCoeff() > 0.0))
      throw UsageError(spec.eye_look_flag, "eye and look-at are the same point " + fmt_vec(*spec.eye));
    forward = d.stableNormalized();
  } else {
    forward = Vec3(0, 0, -1);
    if (upn.cross(forward).norm() < 1e-6) forward = Vec3(0, -1, 0);  // a z-up mesh: look along -y
    // A flat mesh (one side of its box under 1e-3 of the longest) whose plane contains the view
    // direction would be seen edge-on, as a line no ray hits: look at it from 45 degrees instead.
    if (box_ok) {
      const Vec3 ext = bounds.hi - bounds.lo;
      const double longest = ext.maxCoeff();
      for (int a = 0; a < 3 && longest > 0.0; ++a)
        if (ext[a] <= 1e-3 * longest && std::abs(forward[a]) < 0.5) {
          Vec3 tilt = forward;
          tilt[a] = -1.0;
          if (upn.cross(tilt.normalized()).norm() >= 1e-6) forward = tilt.normalized();
          break;
        }
    }
  }
  // sin of the angle between up and the view direction; below 1e-6 the image's up is undefined.
  if (upn.cross(forward).norm() < 1e-6)
    throw UsageError("--up", "the up vector " + fmt_vec(up) + " is parallel to the view direction " + fmt_vec(forward));

  bvh::PinholeCamera c;
  c.fov_y_deg = fov;
  c.forward = forward;
  c.right = forward.cross(upn).normalized();
  c.up = c.right.cross(forward);
  if (spec.eye) {
    c.eye = *spec.eye;
    return c;
  }
  if (!box_ok) throw InputError(std::string(mesh_name), "", "--eye", "the mesh has no finite bounds to frame");
  // Distance d from look_at such that every corner q (relative to look_at) satisfies
  // |q.right| <= tw (d + q.fwd) / 1.05 and |q.up| <= th (d + q.fwd) / 1.05 (5% margin).
  const double th = std::tan(0.5 * fov * M_PI / 180.0);
  const double tw = th * double(width) / double(height);
  double dist = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Vec3 q = Vec3(k & 1 ? bounds.hi.x() : bounds.lo.x(), k & 2 ? bounds.hi.y() : bounds.lo.y(),
                        k & 4 ? bounds.hi.z() : bounds.lo.z()) - look;
    const double need = std::max(std::abs(q.dot(c.right)) / tw, std::abs(q.dot(c.up)) / th) * 1.05 - q.dot(forward);
    dist = std::max(dist, need);
  }
  // A box that is a point (or a line along the view) needs no distance; keep the eye off it.
  const double diag = (bounds.hi - bounds.lo).norm();
  // (The floor relative to |look_at| keeps a point box far from the origin a few thousand ulps of
  // a double away from the eye; 1e-6 of |look_at|, as before, pushed a small mesh at 1e11 back
  // by 100 units, where it covered no pixel.)
  const double scale = std::max({diag, look.cwiseAbs().maxCoeff() * 1e-12, 1e-30});
  dist = std::max(dist, 1e-3 * scale);
  c.eye = look - dist * forward;
  if (!finite(c.eye))  // (no --eye was given: the default camera's distance overflows)
    throw InputError(std::string(mesh_name), "", "",
                     "the default camera cannot frame the mesh: its bounds are too large (give --eye, or scale the mesh)");
  return c;
}

bvh::RayBatch camera_rays(const bvh::PinholeCamera& cam, int width, int height) {
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide)
    throw std::invalid_argument("camera_rays: image size must be 1..16384 per side");
  return bvh::primary_rays(cam, width, height);
}

}  // namespace ptc
