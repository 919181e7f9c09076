// The reference CPU tracer: rays in structure-of-arrays batches, closest hit or any hit, over a
// TriangleScene or a ClusterScene (both give a TraceData), multithreaded with oneTBB.
//
// One traversal code serves both queries (a compile-time flag): an 8-wide BVH (the 4-wide one
// regrouped, TraceData::wide8) walked with one 8-lane box test per node (two 4-lane ones on
// SSE2), children visited nearest first (closest hit) and the stack culled by the best hit so
// far; leaves test their triangles four (SSE2), eight (AVX2) or sixteen (AVX-512; chosen at run
// time, see TraceIsa) at a time with the watertight test of watertight.h (bit-identical to the
// scalar intersect_triangle).
// Robust traversal: the slab test uses (bound - origin) * (1/dir) with the near and far
// reciprocals scaled by (1 -/+ 2^-21), which covers the rounding of the subtraction, the
// reciprocal and the product (2 gamma_3 of Ize 2013 / pbrt), so a box the exact ray touches is
// never culled. A zero direction component gives 1/dir = +-inf; the 0 * inf = NaN of an origin
// exactly on a slab plane is dropped by the max/min order (the ray's own bound is the outer
// right-hand operand, so the result is never NaN; a NaN drops itself and possibly its partner:
// the interval only widens), so axis-aligned rays lose no rows of pixels.
// The closest hit is the smallest (t, triangle id) pair, so it does not depend on the tree:
// ties between triangles (rays through shared edges and vertices) resolve to the lower id.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string_view>

#include "bvh/aligned.h"
#include "bvh/trace_scene.h"

namespace ptc::bvh {

/// Rays: origins in world coordinates (double, so that far-away scenes keep their precision),
/// directions (not necessarily unit; t is in units of the direction's length) and the
/// parametric interval (tmin, tmax] (tmin >= 0; tmax = inf means unbounded; hits have finite t).
/// A ray whose direction is zero or not finite never hits.
struct RayBatch {
  AlignedVector<double> ox, oy, oz;
  AlignedVector<float> dx, dy, dz, tmin, tmax;

  [[nodiscard]] std::size_t size() const { return ox.size(); }
  void resize(std::size_t n);
  void set(std::size_t i, const Vec3& org, const Vec3f& dir, float t0 = 0.0f,
           float t1 = std::numeric_limits<float>::infinity()) {
    ox[i] = org.x(), oy[i] = org.y(), oz[i] = org.z();
    dx[i] = dir[0], dy[i] = dir[1], dz[i] = dir[2];
    tmin[i] = t0, tmax[i] = t1;
  }
};

/// Results, one entry per ray. triangle = kNoTriangle for a miss (t, u, v are then 0).
/// u, v: barycentric weights of the triangle's corners 1 and 2. Counters (when requested):
/// 8-wide nodes whose boxes were tested, and triangles tested (padding lanes not counted).
/// Threads write disjoint tiles of 64 rays: no cache line is shared between threads.
struct HitBatch {
  AlignedVector<float> t, u, v;
  AlignedVector<std::uint32_t> triangle;
  AlignedVector<std::uint32_t> nodes_visited, triangles_tested;

  [[nodiscard]] std::size_t size() const { return t.size(); }
  void resize(std::size_t n);
};

enum class HitMode { Closest, Any };

/// Instruction set of the traversal code (see tracer_isa.h). Auto, checked at run time: on a CPU
/// with AVX-512 (F, VL, DQ, BW) the 512-bit variant on AMD Zen 5 and later (family 1Ah), the
/// AVX-512VL one elsewhere (on the Intel Xeon and the AMD Zen 4 measured, 256-bit vectors were
/// the faster; docs/tracing.md), else AVX2, else SSE2.
/// All give bit-identical hits and counters; SSE2 tests the triangles of a leaf 4 at a time,
/// AVX2 and AVX-512VL 8 (AVX-512VL: the AVX2 code in AVX-512's encoding, 32 registers) and
/// AVX-512 16.
enum class TraceIsa { Auto, Sse2, Avx2, Avx512Vl, Avx512 };
[[nodiscard]] const char* to_string(TraceIsa isa);
/// "auto", "sse2", "avx2", "avx512vl" or "avx512"; nullopt for anything else.
[[nodiscard]] std::optional<TraceIsa> parse_trace_isa(std::string_view s);
/// The variant a request resolves to on this CPU: a forced variant the CPU lacks falls back to
/// the widest one below it.
[[nodiscard]] TraceIsa resolve(TraceIsa isa);
/// resolve's rule on a CPU with (or without) AVX2 and AVX-512 (F, VL, DQ, BW) and the given
/// amd_cpu_family(): Sse2 stays; Avx512 and Avx512Vl need AVX-512 (and Avx2 AVX2), else the
/// widest below; Auto is Avx512 from AMD family 1Ah on, else Avx512Vl, with AVX-512.
[[nodiscard]] TraceIsa choose_isa(TraceIsa isa, bool avx2, bool avx512, unsigned amd_family);
/// The CPU's family (CPUID leaf 1, base family plus extended family as AMD specifies it) on an AMD
/// CPU, 0 on any other: resolve(Auto) takes the 512-bit variant from family 1Ah (Zen 5) on.
[[nodiscard]] unsigned amd_cpu_family();

struct TraceOptions {
  HitMode mode = HitMode::Closest;
  unsigned threads = 0;   ///< worker threads; 0 = all cores (oneTBB's default)
  bool counters = true;   ///< fill nodes_visited / triangles_tested (false: those arrays are emptied)
  TraceIsa isa = TraceIsa::Auto;  ///< traversal variant (results do not depend on it)
  /// Packets of eight consecutive rays of the batch, one ray per AVX2 lane (bvh/tracer_packet.h),
  /// for coherent rays (a camera's rows, shadow rays from neighbouring pixels). Closest hits are
  /// bit-identical to single rays; an any-hit query reports some hit of each occluded ray (the
  /// same rays are occluded). Needs AVX2 or AVX-512 (isa other than Sse2, on a CPU with it); else
  /// single rays.
  bool packets = false;
  /// A hint for the peer only (ours ignores it): with packets, Embree's context flag,
  /// RTC_INTERSECT_CONTEXT_FLAG_COHERENT (true: a camera's rows) or _INCOHERENT (false: Embree's
  /// default, which its documentation advises for rays other than a camera's; docs/tracing.md,
  /// "Embree's shadow packets").
  bool coherent = true;
};

/// Sums over a batch.
struct TraceTotals {
  std::uint64_t rays = 0, hits = 0, nodes_visited = 0, triangles_tested = 0;
};

/// Traces every ray of the batch (hits is resized). Deterministic for any thread count.
TraceTotals trace(const TraceData& scene, const RayBatch& rays, HitBatch& hits, const TraceOptions& opt = {});

/// One ray, for tests and tools.
struct Hit {
  float t = 0, u = 0, v = 0;
  std::uint32_t triangle = kNoTriangle;
  std::uint32_t nodes_visited = 0, triangles_tested = 0;
  [[nodiscard]] bool hit() const { return triangle != kNoTriangle; }
};
[[nodiscard]] Hit trace_ray(const TraceData& scene, const Vec3& org, const Vec3f& dir, HitMode mode = HitMode::Closest,
                            float tmin = 0.0f, float tmax = std::numeric_limits<float>::infinity());
/// The same with an explicit traversal variant.
[[nodiscard]] Hit trace_ray(const TraceData& scene, const Vec3& org, const Vec3f& dir, HitMode mode, float tmin,
                            float tmax, TraceIsa isa);

}  // namespace ptc::bvh
