// An independent double-precision answer for closest hits, and the errors of a float tracer
// against it (issue 12's `accuracy` experiment: the float trace frame against a double reference,
// hit ids and t; Embree against brute force).
//
// The reference is a brute-force loop over ALL triangles in double, with no BVH and no float:
// nothing it computes goes through the tracer's trace frame, its boxes or its rounding, so a
// disagreement is the tracer's error (up to the ties below). The ray is the batch's ray as the
// tracer is asked to trace it: origin (ox, oy, oz) in world coordinates (double), the float
// direction widened to double, the interval (tmin, tmax] of bvh/tracer.h (tmin excluded, tmax
// included, hits have finite t). With RayStart::AsTraced the origin is instead the float point
// the tracer actually starts from in its frame, frame + to_frame(o, frame) (bvh/box.h), which
// separates the rounding of the ray origin from that of the triangles.
//
// The test, per (ray, triangle), in world coordinates:
//   inside: the watertight edge functions of Woop, Benthin & Wald (JCGT 2(1), 2013), in double:
//     the vertices relative to the origin, A = v0 - o, B = v1 - o, C = v2 - o, are sheared so
//     that the ray is the kz axis (kz = the direction's dominant axis, sx = d[kx] / d[kz],
//     sy = d[ky] / d[kz]), and U = e(B, C), V = e(C, A), W = e(A, B), e(P, Q) = Q.x P.y - Q.y P.x.
//     The ray's line crosses the triangle when U, V, W are not of mixed signs and not all zero.
//     Edge rule: INCLUSIVE. e(Q, P) is the exact negative of e(P, Q) and a shared vertex is
//     sheared identically in every triangle (no fused multiply-add: this file is compiled with
//     -ffp-contract=off), so no ray passes between two triangles sharing an edge, and a ray
//     exactly through an edge or a vertex hits every triangle around it (a tie, counted below).
//     All three zero is a ray in the triangle's plane (or a zero-area triangle): a miss.
//   t: the plane distance t = ((v0 - o) . n) / (d . n), n = (v1 - v0) x (v2 - v0) precomputed in
//     double. Its relative error is a few ulp over cos(angle of incidence), whatever the size of
//     the triangle or its distance from the world origin (the differences v - o of nearby doubles
//     are exact), which is what a 1e-12 check at 1e7 from the world origin needs; Woop's
//     T / det instead loses log10(|v - o| / triangle size) digits. A zero-area triangle has
//     n = 0 and t = 0 / 0 = NaN, which no interval accepts: never hit, never a NaN out.
//   accepted when tmin < t <= tmax and t is finite; the closest hit is the smallest
//     (t, triangle id) pair (as bvh::trace resolves ties).
// A ray whose origin is not finite or whose direction is zero or not finite never hits.
//
// Ties: `ties` counts the triangles hit with |t - t_best| <= tie_rel |t_best| (default 1e-9):
// 1 for an ordinary hit, 2 through an edge, the fan size through a vertex; t_best is the closest.
//
// Speed: rays in blocks of up to 128 (a block shares each 256-triangle slice of a
// structure-of-arrays copy of the corners while the slice is in the L1 cache), blocks in
// parallel with oneTBB; the edge functions run branch-free over a slice (compiled for AVX-512,
// AVX2 and plain x86-64 from one text, chosen at run time), t only for the few triangles whose
// plane the ray's line crosses inside. Measured (Release, no -march=native) on this project's
// 2-core Xeon, armadillo subdivided twice (832,000 triangles) under camera rays, CPU time per
// ray-triangle pair on one core: 0.86 ns with AVX-512, 1.03 ns with AVX2, 4.0 ns with SSE2.
// So 832k triangles x 256 rays take 0.27 s of CPU, x 1024 rays 0.79 s, x 4096 rays 2.9 s
// (the wall time on a machine shared with other jobs; about half that on two idle cores).
//
// hit_errors() compares a float tracer's closest hits with the reference, ray by ray, with the
// tie rule of hit_agreement.h (different triangles within tie_rel of t are both correct).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "bvh/tracer.h"
#include "toolkit/core/stats.h"
#include "toolkit/core/types.h"

namespace ptc {

/// Where the reference ray starts.
enum class RayStart {
  /// (ox, oy, oz) as given, in double: the float frame's rounding of the origin counts as part
  /// of the tracer's error (the default: the ray the caller asked for).
  World,
  /// frame + to_frame((ox, oy, oz), frame): the origin the float tracer in that frame really
  /// starts from, so the error left is the triangles' rounding and the float arithmetic.
  AsTraced,
};

struct ReferenceConfig {
  RayStart start = RayStart::World;
  /// AsTraced: the trace frame's origin of the tracer compared (loop::Accel::origin(),
  /// bvh::TraceData::origin). Unused by World.
  Vec3 frame = Vec3::Zero();
  /// AsTraced: the trace frame's scale (bvh::TraceData::scale, a power of two; 1 for every mesh
  /// of ordinary size). Unused by World.
  double frame_scale = 1.0;
  /// Relative t window of `ties` (> 0): rays through an edge or vertex hit its triangles at t
  /// equal to a few ulp of double, far inside 1e-9; distinct surfaces this close are not
  /// resolved by any float tracer either.
  double tie_rel = 1e-9;
};

/// One entry per sampled ray, in the order of `sample`.
struct ReferenceHits {
  std::vector<std::uint32_t> triangle;  ///< closest triangle (smallest id among equal t), or bvh::kNoTriangle
  std::vector<double> t;                ///< its t (units of the direction's length); 0 for a miss
  std::vector<std::uint32_t> ties;      ///< triangles hit within tie_rel of t (>= 1 for a hit, 0 for a miss)
  [[nodiscard]] std::size_t size() const { return triangle.size(); }
};

/// The closest hit of every ray rays[sample[i]] over all triangles `tris` of the mesh at
/// `positions_world` (double, world), in double precision (see above). Every sample index must
/// be < rays.size() and every corner index < positions_world.size() (std::invalid_argument
/// otherwise; also for tie_rel <= 0). An empty mesh misses every ray; an empty sample gives an
/// empty result. Deterministic for any thread count (oneTBB, the caller's arena).
[[nodiscard]] ReferenceHits reference_hits(std::span<const Tri> tris, std::span<const Vec3> positions_world,
                                           const bvh::RayBatch& rays, std::span<const std::size_t> sample,
                                           const ReferenceConfig& cfg = {});

/// A float tracer's closest hits against the reference over the sampled rays.
/// mismatches() = hit_miss() + other_triangle, as in hit_agreement.h.
struct HitErrors {
  std::uint64_t rays = 0;            ///< sampled rays compared
  std::uint64_t ref_hits = 0;        ///< of them, rays the reference hits
  std::uint64_t missed = 0;          ///< the reference hits, the tracer misses
  std::uint64_t spurious = 0;        ///< the tracer hits, the reference misses
  std::uint64_t other_triangle = 0;  ///< both hit, different triangles, |t_got - t_ref| > tie_rel |t_ref|
  std::uint64_t ties = 0;            ///< both hit, different triangles within the tie rule
  std::uint64_t same_triangle = 0;   ///< both hit the same triangle: the rays of t_rel
  std::uint64_t ref_edge = 0;        ///< rays the reference hits with ties > 1 (through an edge or vertex)
  Summary t_rel;                     ///< |t_got - t_ref| / |t_ref| over the same_triangle rays
  [[nodiscard]] std::uint64_t hit_miss() const { return missed + spurious; }
  [[nodiscard]] std::uint64_t mismatches() const { return hit_miss() + other_triangle; }
};

/// `ref` = reference_hits(..., sample, ...) and `got` the tracer's closest hits of the WHOLE
/// batch (got entry sample[i] is compared with ref entry i). std::invalid_argument when
/// ref.size() != sample.size(), a sample index is >= got.size(), tie_rel < 0, or `got` holds
/// bvh::kUnknownTriangle (an any-hit batch: no triangle to compare).
[[nodiscard]] HitErrors hit_errors(const ReferenceHits& ref, const bvh::HitBatch& got,
                                   std::span<const std::size_t> sample, double tie_rel = 1e-5);

/// k distinct indices out of 0 .. n-1, sorted ascending, drawn uniformly (Floyd's algorithm on
/// a SplitMix64 stream): the same for the same (n, k, seed) on every platform. All n indices
/// when k >= n.
[[nodiscard]] std::vector<std::size_t> sample_rays(std::size_t n, std::size_t k, std::uint64_t seed);

}  // namespace ptc
