// Secondary rays of the reference tracer: shadow rays towards a point light and ambient-occlusion
// rays (seeded, cosine-weighted over the hemisphere), both traced with any-hit.
//
// Where a secondary ray starts (docs/tracing.md, "Ray offsets"):
//  1. The surface point is rebuilt from the primary hit's barycentrics on the DOUBLE triangle,
//     p = (1 - u - v) v0 + u v1 + v v2, so it lies on the mesh's triangle up to double rounding
//     instead of drifting along the ray by the float error of t.
//  2. The normal n is the triangle's geometric normal (double cross product), turned to face the
//     side the primary ray came from (meshes may be open or inconsistently oriented).
//  3. The origin is p + eps n with a scale-aware eps = 2^-18 * M, where M is the largest absolute
//     coordinate, in the trace frame (bvh/box.h), of the scene bounds and of p. The tracer's
//     vertices and ray origins are floats in that frame, each within half a unit in the last
//     place (<= 2^-24 M) of the double value, so every point of the float triangle lies within
//     about 2^-23 M of the double plane: the offset clears it by a factor of 32, and since a
//     secondary ray leaves the offset point with dir . n > 0 it can never come back to its own
//     triangle or to a neighbour across a convex edge. Scale-aware: the same relative offset
//     for a scene of size 1e-6 or one at 1e7 from the world origin (no absolute epsilon).
//     Cost: contact shadows/occlusion closer than eps (about 4e-6 of the scene size) are lost.
// Rays use tmin = 0 from the offset origin.
#pragma once

#include <cstdint>
#include <concepts>
#include <functional>
#include <span>
#include <vector>

#include "bvh/tracer.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

/// The offset factor of step 3 (2^-18).
inline constexpr double kRayOffsetScale = 1.0 / 262144.0;

/// Surface points of the primary hits (entries of missed rays: hit = 0, point/normal zero).
struct SurfaceHits {
  std::vector<Vec3> point;   ///< world, rebuilt from barycentrics on the double triangle
  std::vector<Vec3> normal;  ///< unit geometric normal facing the incoming ray
  std::vector<std::uint8_t> hit;
  [[nodiscard]] std::size_t size() const { return hit.size(); }
};
/// `hits` are the closest hits of `rays` on `mesh` (same positions as the traced scene).
[[nodiscard]] SurfaceHits surface_hits(const Mesh& mesh, const bvh::RayBatch& rays, const bvh::HitBatch& hits);

/// What the offsets and distances are measured against: the scene's world bounds and the
/// trace frame's origin (bvh::TraceData::origin).
struct RayFrame {
  Box3 bounds;
  Vec3 origin = Vec3::Zero();
  /// eps of step 3 for a surface point p.
  [[nodiscard]] double offset_eps(const Vec3& p) const;
  /// p + offset_eps(p) * n.
  [[nodiscard]] Vec3 offset_origin(const Vec3& p, const Vec3& n) const { return p + offset_eps(p) * n; }
  /// Length of the bounds' diagonal (0 for empty bounds).
  [[nodiscard]] double diagonal() const;
};

/// What a pass traces: a function tracing a batch (hits resized, triangle ids of the mesh the
/// pass was given) and the trace frame origin of its data (for the ray offsets). One BVH:
/// target_of(data); a scene with a static and a moving BVH: target_of(bvh::SceneTracer)
/// (bvh/scene_tracer.h).
struct TraceTarget {
  std::function<bvh::TraceTotals(const bvh::RayBatch&, bvh::HitBatch&, const bvh::TraceOptions&)> trace;
  Vec3 origin = Vec3::Zero();
};
/// bvh::trace over `data` (kept by reference).
[[nodiscard]] TraceTarget target_of(const bvh::TraceData& data);
/// Any tracer with trace(rays, hits, options) and origin() (bvh::SceneTracer, an acceleration
/// configuration of analysis/loop), kept by reference.
template <class Tracer>
  requires requires(const Tracer& t, const bvh::RayBatch& r, bvh::HitBatch& h, const bvh::TraceOptions& o) {
    { t.trace(r, h, o) } -> std::same_as<bvh::TraceTotals>;
    { t.origin() } -> std::convertible_to<Vec3>;
  }
[[nodiscard]] TraceTarget target_of(const Tracer& tracer) {
  return {[&tracer](const bvh::RayBatch& r, bvh::HitBatch& h, const bvh::TraceOptions& o) { return tracer.trace(r, h, o); },
          tracer.origin()};
}

/// The same target tracing with the per-ray counters on, whatever the pass asks (the untimed
/// counted trace of the experiments and benchmarks).
[[nodiscard]] TraceTarget with_counters(TraceTarget target);
/// The same target with the rays' coherence hint (bvh::TraceOptions::coherent: Embree's packets'
/// context flag; our tracer ignores it), whatever the pass asks.
[[nodiscard]] TraceTarget with_coherence(TraceTarget target, bool coherent);
/// The same target tracing with our tracer's instruction-set variant `isa`, whatever the pass
/// asks (Embree's targets ignore it).
[[nodiscard]] TraceTarget with_isa(TraceTarget target, bvh::TraceIsa isa);

/// Totals and wall time of one trace pass.
struct PassStats {
  std::uint64_t rays = 0, hits = 0, nodes_visited = 0, triangles_tested = 0;
  double trace_ms = 0;
  [[nodiscard]] double mrays_per_s() const { return trace_ms > 0 ? double(rays) / (trace_ms * 1e3) : 0.0; }
  void add(const bvh::TraceTotals& t, double ms);
};

/// Shadow rays from every surface point towards a point light, any-hit, tmax = 1 - 2^-20 of
/// the distance to the light (an occluder beyond the light does not count). A point whose
/// facing normal points away from the light (n . (light - p) <= 0) is unlit without a ray.
/// lit[i] = 1 when point i is hit and sees the light.
struct ShadowResult {
  std::vector<std::uint8_t> lit;
  PassStats stats;
};
/// packets: trace them in packets (bvh::TraceOptions::packets; the points are taken in pixel order,
/// so neighbouring rays leave neighbouring points). order: when not empty, the points in this
/// order instead (a permutation of 0 .. s.size() - 1, e.g. morton_order; lit stays indexed by
/// point, and the same points are lit).
[[nodiscard]] ShadowResult trace_shadows(const TraceTarget& scene, const SurfaceHits& s, const Vec3& light,
                                         const RayFrame& frame, unsigned threads = 0, bool packets = false,
                                         std::span<const std::uint32_t> order = {});
/// The surface points ordered by the Morton code of their position in `bounds` (21 bits an axis;
/// ties and the points without a hit in index order): neighbouring shadow rays then leave
/// neighbouring points, which pixel order does not give where the hits are scattered (a cloud of
/// separated triangles; docs/tracing.md, "Shadow rays in Morton order").
[[nodiscard]] std::vector<std::uint32_t> morton_order(const SurfaceHits& s, const Box3& bounds);
[[nodiscard]] ShadowResult trace_shadows(const bvh::TraceData& scene, const SurfaceHits& s, const Vec3& light,
                                         const RayFrame& frame, unsigned threads = 0);

struct AoConfig {
  int samples = 16;                ///< rays per surface point (>= 1)
  double max_distance_rel = 0.25;  ///< occluders count up to this fraction of the scene's bounds diagonal (> 0)
  std::uint64_t seed = 1;          ///< the directions depend only on (seed, point index, sample index)
};
/// Ambient occlusion: ao[i] = fraction of the samples of point i that reach max distance
/// unoccluded (1 = open, 0 = enclosed); 0 for missed pixels. Any-hit rays, tmax = max distance.
/// Processed in chunks, so memory stays bounded for any samples x points.
struct AoResult {
  std::vector<float> ao;
  PassStats stats;
};
[[nodiscard]] AoResult trace_ao(const TraceTarget& scene, const SurfaceHits& s, const AoConfig& cfg,
                                const RayFrame& frame, unsigned threads = 0);
[[nodiscard]] AoResult trace_ao(const bvh::TraceData& scene, const SurfaceHits& s, const AoConfig& cfg,
                                const RayFrame& frame, unsigned threads = 0);

/// Sample `k` of point `i` with `seed` as two uniforms in [0, 1) (counter-based: SplitMix64 of
/// the triple, so any thread order gives the same directions).
[[nodiscard]] std::pair<double, double> ao_uniforms(std::uint64_t seed, std::uint64_t i, std::uint64_t k);
/// Cosine-weighted direction about unit n (Malley's method: uniform on the disk, lifted to the
/// hemisphere; pdf = cos(theta) / pi). cos(theta) is kept >= 2^-12 so that the float direction
/// still leaves the surface (a change of probability below 1e-7). Unit length.
[[nodiscard]] Vec3 cosine_hemisphere(const Vec3& n, double u1, double u2);

}  // namespace ptc
