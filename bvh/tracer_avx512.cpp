// The tracer's AVX-512 variant, only called when the CPU has AVX-512 F, VL, DQ and BW (tracer.cpp);
// see tracer_isa.h. As tracer_avx2.cpp: every header first, compiled for the baseline, then the
// kernel code after the target pragma. It is the AVX2 kernel (single rays and packets) with the
// leaf test taking four blocks (16 triangles) per 512-bit test; no FMA (-ffp-contract=off), so the float operations stay those
// of the scalar watertight test and the hits and counters are the other variants' bits.
#include <immintrin.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "bvh/tracer.h"
#include "bvh/tracer_isa.h"
#include "bvh/watertight.h"

#pragma GCC target("avx2,avx512f,avx512vl,avx512dq,avx512bw")
#define PTC_TRACE_AVX2 1
#define PTC_TRACE_AVX512 1
#define PTC_TRACE_EVEX 1
#define PTC_TRACE_NS avx512
#include "bvh/tracer_kernel.h"
#include "bvh/tracer_packet.h"
