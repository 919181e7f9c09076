// Watertight ray/triangle intersection (Woop, Benthin, Wald: "Watertight Ray/Triangle
// Intersection", JCGT 2(1), 2013), scalar reference version. The tracer's SIMD kernel performs
// exactly the same float operations in the same order, so both give bit-identical t, u, v.
//
// The ray is made the +z axis of a sheared frame: kz = the dominant axis of the direction, kx/ky
// the other two (swapped when dir[kz] < 0 to keep the winding), vertices relative to the origin
// are sheared by S = (dir[kx]/dir[kz], dir[ky]/dir[kz], 1/dir[kz]). The 2D edge functions
//   U = e(B, C), V = e(C, A), W = e(A, B),  e(P, Q) = Q.x P.y - Q.y P.x
// of the sheared vertices A, B, C depend only on the edge's two vertices, and e(Q, P) is computed
// as the exact negative of e(P, Q) (round-to-nearest is symmetric; no fused multiply-add: the
// library is compiled with -ffp-contract=off). So for two triangles sharing an edge the ray is on
// the inner side of at least one of them: no ray passes between them. An edge function of exactly
// 0 is recomputed in double from the same float inputs (the products are exact there, so the sign
// is exact), as the paper does; a ray exactly through an edge or vertex then hits every triangle
// around it, never none.
// A hit is accepted when U, V, W do not have mixed signs (both faces are hit), det = U + V + W
// is nonzero, and t = T / det, T = U A.z + V B.z + W C.z, satisfies tmin < t <= tmax and t is
// finite. Barycentrics: u = V / det (weight of v1), v = W / det (weight of v2).
#pragma once

#include <optional>

#include "bvh/box.h"

namespace ptc::bvh {

/// Per-ray constants of the test.
struct WatertightRay {
  Vec3f org{}, dir{};
  int kx = 0, ky = 1, kz = 2;
  float sx = 0, sy = 0, sz = 1;
};

/// Precondition: dir is finite and not zero.
[[nodiscard]] WatertightRay make_watertight_ray(const Vec3f& org, const Vec3f& dir);

struct TriangleHit {
  float t = 0, u = 0, v = 0;
};

/// The test described above; nullopt for a miss.
[[nodiscard]] std::optional<TriangleHit> intersect_triangle(const WatertightRay& r, const Vec3f& v0, const Vec3f& v1,
                                                            const Vec3f& v2, float tmin, float tmax);

/// The double-precision recomputation of the three edge functions from the sheared float
/// coordinates (used by intersect_triangle and the SIMD kernels when one of them is 0).
void edge_functions_double(float ax, float ay, float bx, float by, float cx, float cy, float& u, float& v, float& w);

}  // namespace ptc::bvh
