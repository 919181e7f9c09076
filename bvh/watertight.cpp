#include "bvh/watertight.h"

#include <cmath>
#include <limits>
#include <utility>

namespace ptc::bvh {

WatertightRay make_watertight_ray(const Vec3f& org, const Vec3f& dir) {
  WatertightRay r;
  r.org = org;
  r.dir = dir;
  int kz = 0;
  if (std::abs(dir[1]) > std::abs(dir[kz])) kz = 1;
  if (std::abs(dir[2]) > std::abs(dir[kz])) kz = 2;
  int kx = kz == 2 ? 0 : kz + 1;
  int ky = kx == 2 ? 0 : kx + 1;
  if (dir[kz] < 0.0f) std::swap(kx, ky);  // keep the winding of the sheared triangle
  r.kx = kx, r.ky = ky, r.kz = kz;
  r.sx = dir[kx] / dir[kz];
  r.sy = dir[ky] / dir[kz];
  r.sz = 1.0f / dir[kz];
  return r;
}

void edge_functions_double(float ax, float ay, float bx, float by, float cx, float cy, float& u, float& v, float& w) {
  u = static_cast<float>(double(cx) * double(by) - double(cy) * double(bx));
  v = static_cast<float>(double(ax) * double(cy) - double(ay) * double(cx));
  w = static_cast<float>(double(bx) * double(ay) - double(by) * double(ax));
}

std::optional<TriangleHit> intersect_triangle(const WatertightRay& r, const Vec3f& v0, const Vec3f& v1,
                                              const Vec3f& v2, float tmin, float tmax) {
  const int kx = r.kx, ky = r.ky, kz = r.kz;
  // Vertices relative to the origin, in the permuted axes.
  const float a_x = v0[kx] - r.org[kx], a_y = v0[ky] - r.org[ky], a_z = v0[kz] - r.org[kz];
  const float b_x = v1[kx] - r.org[kx], b_y = v1[ky] - r.org[ky], b_z = v1[kz] - r.org[kz];
  const float c_x = v2[kx] - r.org[kx], c_y = v2[ky] - r.org[ky], c_z = v2[kz] - r.org[kz];
  // Shear.
  const float ax = a_x - r.sx * a_z, ay = a_y - r.sy * a_z;
  const float bx = b_x - r.sx * b_z, by = b_y - r.sy * b_z;
  const float cx = c_x - r.sx * c_z, cy = c_y - r.sy * c_z;
  float u = cx * by - cy * bx;
  float v = ax * cy - ay * cx;
  float w = bx * ay - by * ax;
  if (u == 0.0f || v == 0.0f || w == 0.0f) edge_functions_double(ax, ay, bx, by, cx, cy, u, v, w);
  if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return std::nullopt;
  const float det = u + v + w;
  if (!(det < 0.0f || det > 0.0f)) return std::nullopt;
  const float az = r.sz * a_z, bz = r.sz * b_z, cz = r.sz * c_z;
  const float T = u * az + v * bz + w * cz;
  const float t = T / det;
  constexpr float big = std::numeric_limits<float>::max();
  if (!(t > tmin && t <= tmax && t <= big)) return std::nullopt;
  return TriangleHit{t, v / det, w / det};
}

}  // namespace ptc::bvh
