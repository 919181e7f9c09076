// Internal: the tracer's instruction-set variants and the runtime choice between them.
// tracer_kernel.h holds the one traversal code; it is compiled four times, by tracer_sse2.cpp
// (the x86-64 baseline, 4 triangles per SIMD test), tracer_avx2.cpp (for AVX2: the leaf test
// takes two blocks = 8 triangles per test, everything else VEX-encoded), tracer_avx512vl.cpp
// (the AVX2 code for AVX-512 F/VL/DQ/BW on 256-bit vectors: EVEX-encoded, 32 registers) and
// tracer_avx512.cpp (for AVX-512 F/VL/DQ/BW: four blocks = 16 triangles per test, comparisons
// into mask registers). All give bit-identical hits and counters (same float operations per
// triangle, same visiting order). trace() picks one at run time (__builtin_cpu_supports; see
// tracer.h), as Embree dispatches at runtime; TraceOptions::isa forces one (tests compare them).
#pragma once

#include <cstddef>

#include "bvh/tracer.h"

namespace ptc::bvh::detail {

/// Traces rays [begin, end) of the batch into hits (already sized; counters arrays sized when
/// `counters`), adding to `totals`.
using RangeFn = void (*)(const TraceData&, const RayBatch&, HitBatch&, std::size_t begin, std::size_t end,
                         HitMode mode, bool counters, TraceTotals& totals);
using OneFn = Hit (*)(const TraceData&, const Vec3& org, const Vec3f& dir, HitMode mode, float tmin, float tmax);

void trace_range_sse2(const TraceData&, const RayBatch&, HitBatch&, std::size_t, std::size_t, HitMode, bool,
                      TraceTotals&);
Hit trace_one_sse2(const TraceData&, const Vec3&, const Vec3f&, HitMode, float, float);
void trace_range_avx2(const TraceData&, const RayBatch&, HitBatch&, std::size_t, std::size_t, HitMode, bool,
                      TraceTotals&);
Hit trace_one_avx2(const TraceData&, const Vec3&, const Vec3f&, HitMode, float, float);
void trace_range_avx512vl(const TraceData&, const RayBatch&, HitBatch&, std::size_t, std::size_t, HitMode, bool,
                          TraceTotals&);
Hit trace_one_avx512vl(const TraceData&, const Vec3&, const Vec3f&, HitMode, float, float);
void trace_range_avx512(const TraceData&, const RayBatch&, HitBatch&, std::size_t, std::size_t, HitMode, bool,
                        TraceTotals&);
Hit trace_one_avx512(const TraceData&, const Vec3&, const Vec3f&, HitMode, float, float);
/// The packet path (tracer_packet.h, compiled into the AVX2, AVX-512VL and AVX-512 variants): eight
/// consecutive rays per packet; not in the SSE2 variant.
void trace_range_packet_avx2(const TraceData&, const RayBatch&, HitBatch&, std::size_t, std::size_t, HitMode, bool,
                             TraceTotals&);
void trace_range_packet_avx512vl(const TraceData&, const RayBatch&, HitBatch&, std::size_t, std::size_t, HitMode,
                                 bool, TraceTotals&);
void trace_range_packet_avx512(const TraceData&, const RayBatch&, HitBatch&, std::size_t, std::size_t, HitMode, bool,
                               TraceTotals&);

}  // namespace ptc::bvh::detail
