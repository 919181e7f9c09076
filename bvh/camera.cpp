#include "bvh/camera.h"

#include <algorithm>
#include <cmath>

namespace ptc::bvh {

PinholeCamera frame_box(const Box3& bounds, const Vec3& view_dir, const Vec3& up_hint, double fov_y_deg) {
  PinholeCamera c;
  c.fov_y_deg = fov_y_deg;
  c.forward = view_dir.normalized();
  c.right = c.forward.cross(up_hint).normalized();
  c.up = c.right.cross(c.forward);
  if (bounds.empty()) {
    c.eye = -c.forward;
    return c;
  }
  // Distance at which every corner of the box projects inside the square image (with a 5%
  // margin): for corner q relative to the centre, |q.right| and |q.up| <= tan(fov/2) * (d + q.fwd).
  const double t = std::tan(0.5 * fov_y_deg * M_PI / 180.0) / 1.05;
  double dist = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Vec3 q = Vec3(k & 1 ? bounds.hi.x() : bounds.lo.x(), k & 2 ? bounds.hi.y() : bounds.lo.y(),
                        k & 4 ? bounds.hi.z() : bounds.lo.z()) - bounds.center();
    const double lateral = std::max(std::abs(q.dot(c.right)), std::abs(q.dot(c.up)));
    dist = std::max(dist, lateral / t - q.dot(c.forward));
  }
  c.eye = bounds.center() - dist * c.forward;
  return c;
}

namespace {

// Calls f(i, d) for every pixel centre of a width x height image, row-major from the top left,
// with the unit direction d through it as the rays store it (float).
template <class F>
void for_pixel_directions(const PinholeCamera& cam, int width, int height, F&& f) {
  const double th = std::tan(0.5 * cam.fov_y_deg * M_PI / 180.0);
  const double tw = th * width / height;
  std::size_t i = 0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x, ++i) {
      const double sx = (2.0 * (x + 0.5) / width - 1.0) * tw;
      const double sy = (1.0 - 2.0 * (y + 0.5) / height) * th;
      const Vec3 d = (cam.forward + sx * cam.right + sy * cam.up).normalized();
      f(i, Vec3f{static_cast<float>(d.x()), static_cast<float>(d.y()), static_cast<float>(d.z())});
    }
}

// The sums of |d_a| / |d| over directions d, and direction_area_weights from them.
struct DirectionSums {
  double sum[3] = {0.0, 0.0, 0.0};
  std::size_t used = 0;
  void add(float x, float y, float z) {
    const double d[3] = {x, y, z};
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(len > 0.0) || !std::isfinite(len)) return;
    for (int a = 0; a < 3; ++a) sum[a] += std::abs(d[a]) / len;
    ++used;
  }
  [[nodiscard]] std::array<float, 3> weights() const {
    if (used == 0) return {1.0f, 1.0f, 1.0f};
    double w[3], top = 0.0;
    for (int a = 0; a < 3; ++a) w[a] = 2.0 * sum[a] / static_cast<double>(used), top = std::max(top, w[a]);
    std::array<float, 3> out{};
    for (int a = 0; a < 3; ++a) out[a] = static_cast<float>(std::max(w[a], top / 64.0));
    return out;
  }
};

}  // namespace

RayBatch primary_rays(const PinholeCamera& cam, int width, int height) {
  RayBatch rays;
  rays.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for_pixel_directions(cam, width, height, [&](std::size_t i, const Vec3f& d) { rays.set(i, cam.eye, d); });
  return rays;
}

std::array<float, 3> direction_area_weights(const RayBatch& rays) {
  DirectionSums s;
  for (std::size_t i = 0; i < rays.size(); ++i) s.add(rays.dx[i], rays.dy[i], rays.dz[i]);
  return s.weights();
}

std::array<float, 3> direction_area_weights(const PinholeCamera& cam, int width, int height) {
  DirectionSums s;
  for_pixel_directions(cam, width, height, [&](std::size_t, const Vec3f& d) { s.add(d[0], d[1], d[2]); });
  return s.weights();
}

}  // namespace ptc::bvh
