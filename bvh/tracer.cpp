#include "bvh/tracer.h"

#include <cpuid.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <limits>

#include "bvh/tracer_isa.h"

namespace ptc::bvh {

void RayBatch::resize(std::size_t n) {
  ox.resize(n), oy.resize(n), oz.resize(n);
  dx.resize(n), dy.resize(n), dz.resize(n);
  tmin.resize(n, 0.0f), tmax.resize(n, std::numeric_limits<float>::infinity());
}

void HitBatch::resize(std::size_t n) {
  t.resize(n), u.resize(n), v.resize(n), triangle.resize(n);
  nodes_visited.resize(n), triangles_tested.resize(n);
}

const char* to_string(TraceIsa isa) {
  switch (isa) {
    case TraceIsa::Auto: return "auto";
    case TraceIsa::Sse2: return "sse2";
    case TraceIsa::Avx2: return "avx2";
    case TraceIsa::Avx512Vl: return "avx512vl";
    case TraceIsa::Avx512: return "avx512";
  }
  return "?";
}

std::optional<TraceIsa> parse_trace_isa(std::string_view s) {
  for (TraceIsa i : {TraceIsa::Auto, TraceIsa::Sse2, TraceIsa::Avx2, TraceIsa::Avx512Vl, TraceIsa::Avx512})
    if (s == to_string(i)) return i;
  return std::nullopt;
}

unsigned amd_cpu_family() {
  if (!__builtin_cpu_is("amd")) return 0;
  unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
  if (!__get_cpuid(1, &eax, &ebx, &ecx, &edx)) return 0;
  const unsigned base = (eax >> 8) & 0xf;
  return base == 0xf ? base + ((eax >> 20) & 0xff) : base;
}

TraceIsa choose_isa(TraceIsa isa, bool avx2, bool avx512, unsigned amd_family) {
  // Auto takes the 512-bit variant only on AMD CPUs of family 1Ah and later (Zen 5): on the Zen 5
  // host (a server part, 512-bit vector units) it was the faster one. On the Intel Xeon host
  // (AVX-512 FP16, AMX) of 2026-12-05 the 256-bit ones were faster by 3-11% per frame, and on
  // the Zen 4 host of 2026-12-06 (family 19h, which splits a 512-bit operation in two 256-bit
  // halves) the AVX-512VL variant was faster on every scene measured, single rays and packets
  // alike (docs/tracing.md, "The machine changed" and "... again"). Zen 5 parts that split
  // 512-bit operations too (reportedly some mobile ones, also family 1Ah) were not measured. The
  // AVX-512VL variant (256-bit, EVEX) gave 0-8% faster whole frames than the AVX2 one at one
  // thread on the Intel host (docs/tracing.md, "The AVX-512VL variant").
  if (isa == TraceIsa::Sse2) return TraceIsa::Sse2;
  avx512 = avx512 && avx2;
  if (avx512) {
    if (isa == TraceIsa::Avx512 || (isa == TraceIsa::Auto && amd_family >= 0x1a)) return TraceIsa::Avx512;
    if (isa == TraceIsa::Avx512Vl || isa == TraceIsa::Auto) return TraceIsa::Avx512Vl;
  }
  return avx2 ? TraceIsa::Avx2 : TraceIsa::Sse2;
}

TraceIsa resolve(TraceIsa isa) {
  static const bool has_avx2 = __builtin_cpu_supports("avx2");
  static const bool has_avx512 = has_avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                                 __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw");
  static const unsigned family = amd_cpu_family();
  return choose_isa(isa, has_avx2, has_avx512, family);
}

namespace {
detail::RangeFn range_fn(TraceIsa isa, bool packets) {
  const TraceIsa r = resolve(isa);
  if (r == TraceIsa::Sse2) return &detail::trace_range_sse2;
  if (r == TraceIsa::Avx512) return packets ? &detail::trace_range_packet_avx512 : &detail::trace_range_avx512;
  if (r == TraceIsa::Avx512Vl) return packets ? &detail::trace_range_packet_avx512vl : &detail::trace_range_avx512vl;
  return packets ? &detail::trace_range_packet_avx2 : &detail::trace_range_avx2;
}
}  // namespace

TraceTotals trace(const TraceData& scene, const RayBatch& rays, HitBatch& hits, const TraceOptions& opt) {
  const std::size_t n = rays.size();
  hits.resize(n);
  if (!opt.counters) hits.nodes_visited.clear(), hits.triangles_tested.clear();
  const detail::RangeFn fn = range_fn(opt.isa, opt.packets);
  constexpr std::size_t kTile = 64;  // rays per task: 64 * 4 bytes = 4 cache lines per array
  const std::size_t tiles = (n + kTile - 1) / kTile;
  tbb::enumerable_thread_specific<TraceTotals> totals;
  auto body = [&](const tbb::blocked_range<std::size_t>& range) {
    fn(scene, rays, hits, range.begin() * kTile, std::min(n, range.end() * kTile), opt.mode, opt.counters,
       totals.local());
  };
  if (opt.threads == 1) {
    body(tbb::blocked_range<std::size_t>(0, tiles));
  } else {
    tbb::task_arena arena(opt.threads == 0 ? tbb::task_arena::automatic : static_cast<int>(opt.threads));
    arena.execute([&] { tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tiles, 1), body); });
  }
  TraceTotals sum;
  for (const TraceTotals& t : totals) {
    sum.rays += t.rays, sum.hits += t.hits, sum.nodes_visited += t.nodes_visited;
    sum.triangles_tested += t.triangles_tested;
  }
  return sum;
}

Hit trace_ray(const TraceData& scene, const Vec3& org, const Vec3f& dir, HitMode mode, float tmin, float tmax) {
  return trace_ray(scene, org, dir, mode, tmin, tmax, TraceIsa::Auto);
}

Hit trace_ray(const TraceData& scene, const Vec3& org, const Vec3f& dir, HitMode mode, float tmin, float tmax,
              TraceIsa isa) {
  switch (resolve(isa)) {
    case TraceIsa::Avx512: return detail::trace_one_avx512(scene, org, dir, mode, tmin, tmax);
    case TraceIsa::Avx512Vl: return detail::trace_one_avx512vl(scene, org, dir, mode, tmin, tmax);
    case TraceIsa::Avx2: return detail::trace_one_avx2(scene, org, dir, mode, tmin, tmax);
    default: return detail::trace_one_sse2(scene, org, dir, mode, tmin, tmax);
  }
}

}  // namespace ptc::bvh
