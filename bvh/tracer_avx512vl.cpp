// The tracer's AVX-512VL variant, only called when the CPU has AVX-512 F, VL, DQ and BW
// (tracer.cpp); see tracer_isa.h. It is the AVX2 kernel (single rays and packets, eight
// triangles per leaf test, 256-bit vectors) compiled for AVX-512: the same operations in the
// EVEX encoding, with 32 vector registers instead of 16 (the packet walk's slab constants no
// longer spill) and a plane broadcast from memory inside the subtraction of the packets' node
// test. No 512-bit vectors (prefer-vector-width=256): on the Intel Xeon host the 512-bit leaf
// tests of tracer_avx512.cpp were the slower ones. The tables leaf format (LeafFormat::Tables)
// takes its corner rows with 256-bit permutes of two 8-slot chunks of the rows (AVX-512VL's
// two-source vpermt2ps; PTC_TRACE_EVEX, tracer_kernel.h's intersect_group). No FMA
// (-ffp-contract=off), so the hits and counters are the other variants' bits. As tracer_avx2.cpp:
// every header first, compiled for the baseline, then the kernel code after the target pragma.
#include <immintrin.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "bvh/tracer.h"
#include "bvh/tracer_isa.h"
#include "bvh/watertight.h"

#pragma GCC target("avx2,avx512f,avx512vl,avx512dq,avx512bw,prefer-vector-width=256")
#define PTC_TRACE_AVX2 1
#define PTC_TRACE_EVEX 1
#define PTC_TRACE_NS avx512vl
#include "bvh/tracer_kernel.h"
#include "bvh/tracer_packet.h"
