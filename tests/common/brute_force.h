// The independent answer for every tracer test: the closest hit by a loop over all triangles
// with the scalar watertight test (bvh/watertight.h), in the scene's trace frame.
#pragma once

#include <algorithm>
#include <limits>

#include "bvh/box.h"
#include "bvh/tracer.h"
#include "bvh/watertight.h"
#include "toolkit/mesh/mesh.h"

namespace ptc::bvh::test {

/// Closest hit by a loop over all triangles in the trace frame `frame` (its origin and scale; the
/// direction is scaled with it, so t is the caller's): the smallest (t, triangle id) pair, which
/// is what the tracer returns whatever its tree.
inline Hit brute_force(const Mesh& m, const FrameMap& frame, const Vec3& org, const Vec3f& dir, float tmin = 0.0f,
                       float tmax = std::numeric_limits<float>::infinity()) {
  Hit best;
  const auto sc = static_cast<float>(frame.scale);
  const WatertightRay r = make_watertight_ray(to_frame(org, frame), {dir[0] * sc, dir[1] * sc, dir[2] * sc});
  float tm = std::min(tmax, std::numeric_limits<float>::max());
  for (std::uint32_t t = 0; t < m.triangle_count(); ++t) {
    const auto c = m.corners(t);
    const auto h = intersect_triangle(r, to_frame(c[0], frame), to_frame(c[1], frame), to_frame(c[2], frame), tmin, tm);
    if (!h) continue;
    if (h->t < best.t || !best.hit() || (h->t == best.t && t < best.triangle)) {
      best.t = h->t, best.u = h->u, best.v = h->v, best.triangle = t;
    }
  }
  return best;
}

}  // namespace ptc::bvh::test
