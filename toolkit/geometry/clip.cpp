#include "toolkit/geometry/clip.h"

#include <array>
#include <cstddef>

namespace ptc {
namespace {

// A convex polygon of at most 3 + 6 vertices (each plane adds at most one).
struct Poly {
  std::array<Vec3, 12> v;
  std::size_t n = 0;
};

// Keeps the part with sign * (p[axis] - bound) <= 0.
Poly clip(const Poly& in, int axis, double bound, double sign) {
  Poly out;
  for (std::size_t i = 0; i < in.n; ++i) {
    const Vec3& p = in.v[i];
    const Vec3& q = in.v[(i + 1) % in.n];
    const double dp = sign * (p[axis] - bound), dq = sign * (q[axis] - bound);
    if (dp <= 0) out.v[out.n++] = p;
    if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) {
      const double t = dp / (dp - dq);
      Vec3 x = p + t * (q - p);
      x[axis] = bound;  // exactly on the plane
      out.v[out.n++] = x;
    }
  }
  return out;
}

}  // namespace

double clipped_area(const Vec3& a, const Vec3& b, const Vec3& c, const Box3& box) {
  if (box.empty()) return 0.0;
  const Vec3 o = box.center();
  Poly p;
  p.v[0] = a - o, p.v[1] = b - o, p.v[2] = c - o;
  p.n = 3;
  const Vec3 lo = box.lo - o, hi = box.hi - o;
  for (int axis = 0; axis < 3 && p.n >= 3; ++axis) {
    p = clip(p, axis, hi[axis], 1.0);
    if (p.n >= 3) p = clip(p, axis, lo[axis], -1.0);
  }
  if (p.n < 3) return 0.0;
  Vec3 sum = Vec3::Zero();
  for (std::size_t i = 1; i + 1 < p.n; ++i) sum += (p.v[i] - p.v[0]).cross(p.v[i + 1] - p.v[0]);
  return 0.5 * sum.norm();
}

}  // namespace ptc
