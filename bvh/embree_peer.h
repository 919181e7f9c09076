// Embree 3 as the performance peer: the same mesh, the same trace frame (positions minus the
// same origin, times the same power-of-two scale as our scenes', trace_frame_scale, in float) and
// the same rays, traced with rtcIntersect1 / rtcOccluded1. The rays' directions are passed as
// they are and their t (tmin, tmax, hits) scaled with the frame: exact, and Embree sees a mesh of
// 1e30 or 1e-30 units at a size it can trace (beyond 1.8e18 it drops triangles and asserts on
// rays). Rays must lie within 1e18 of the frame's origin, directions within 1e18 too, no NaN:
// check_rays() says so (callers run it outside their timed spans: a check inside the trace loops
// cost Embree 1-3% of its single-ray time); surface rays (shadows, AO) are within by construction.
//
// Modes (Embree's own names):
//   - StaticMedium: RTC_BUILD_QUALITY_MEDIUM, static scene (Embree's default SAH build);
//   - DynamicLow: RTC_SCENE_FLAG_DYNAMIC + RTC_BUILD_QUALITY_LOW (Morton build), rebuilt per frame;
//   - DynamicRefit: RTC_SCENE_FLAG_DYNAMIC, scene quality LOW, geometry quality REFIT: the first
//     commit builds, every later commit refits the tree to the new vertices.
// Threads: the device is created with "threads=N" (N = 0: Embree's default, all cores);
// set_affinity is never used.
#pragma once

#include <memory>
#include <string>

#include "bvh/stage_clock.h"
#include "bvh/tracer.h"

namespace ptc::bvh {

/// Triangle id reported for an occluded ray (rtcOccluded1 does not say which triangle).
inline constexpr std::uint32_t kUnknownTriangle = 0xfffffffeu;

enum class EmbreeMode { StaticMedium, DynamicLow, DynamicRefit };
[[nodiscard]] const char* to_string(EmbreeMode m);

struct EmbreeConfig {
  EmbreeMode mode = EmbreeMode::StaticMedium;
  unsigned threads = 0;  ///< Embree worker threads for commits (0: all cores)
  /// Device ISA ("sse2", "sse4.2", "avx", "avx2", "avx512"); empty: Embree picks the best the
  /// CPU supports (BVH8 with AVX and above). "sse2" gives the like-for-like comparison with our
  /// SSE2 BVH4.
  std::string isa;
  StageClock clock = StageClock::Wall;  ///< clock of last_vertex_ms / last_commit_ms
};

class EmbreeScene {
 public:
  /// Creates the device and scene and commits the first frame. Throws std::runtime_error when
  /// Embree reports an error.
  EmbreeScene(const Mesh& mesh, const Vec3& origin, const EmbreeConfig& cfg = {});
  ~EmbreeScene();
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  /// One frame: new positions (same count) converted into the shared vertex buffer, then
  /// rtcCommitScene (build or refit by mode). Times in milliseconds of the last update.
  void update(std::span<const Vec3> positions);
  [[nodiscard]] double last_vertex_ms() const { return vertex_ms_; }
  [[nodiscard]] double last_commit_ms() const { return commit_ms_; }

  /// Traces the batch with rtcIntersect1 (Closest) or rtcOccluded1 (Any); hits as in the
  /// tracer (triangle = primID; for Any, triangle = kUnknownTriangle, t = the ray's tmax and
  /// u = v = 0: Embree reports no hit data for occlusion). threads = 1: the calling thread only; else oneTBB.
  TraceTotals trace(const RayBatch& rays, HitBatch& hits, HitMode mode = HitMode::Closest, unsigned threads = 1) const;
  /// Throws std::invalid_argument (one line naming the ray and the flags --eye and --light) for a
  /// ray Embree cannot take: an origin or direction coordinate beyond 1e18 in the trace frame, or
  /// NaN. trace() and trace_packets() assume the rays passed it (Embree asserts and aborts otherwise).
  void check_rays(const RayBatch& rays) const;
  /// The same with packets of `width` (4, 8 or 16) consecutive rays: rtcIntersect4/8/16 or
  /// rtcOccluded4/8/16 with the coherent context flag (RTC_INTERSECT_CONTEXT_FLAG_COHERENT), the
  /// peer of our packet path (TraceOptions::packets). width 1: trace() above; else std::invalid_argument.
  /// coherent: the packets' context flag, RTC_INTERSECT_CONTEXT_FLAG_COHERENT (true) or
  /// _INCOHERENT (false, Embree's default); the same hits either way.
  TraceTotals trace_packets(const RayBatch& rays, HitBatch& hits, HitMode mode, unsigned threads, int width,
                            bool coherent = true) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double vertex_ms_ = 0, commit_ms_ = 0;
  StageClock clock_ = StageClock::Wall;
};

}  // namespace ptc::bvh
