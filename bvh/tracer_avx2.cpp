// The tracer's AVX2 variant, only called when the CPU has AVX2 (tracer.cpp); see tracer_isa.h.
// Every header is included first, compiled for the baseline; only the kernel code that follows
// the target pragma is compiled for AVX2. (Compiling the whole file with -mavx2 would also
// compile the inline functions of the headers for AVX2, and the linker may keep that copy for
// the whole program: an illegal instruction on a CPU without AVX2.) No FMA: the pragma does not
// enable it and the library is built with -ffp-contract=off, so the float operations stay those
// of the scalar watertight test.
#include <immintrin.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "bvh/tracer.h"
#include "bvh/tracer_isa.h"
#include "bvh/watertight.h"

#pragma GCC target("avx2")
#define PTC_TRACE_AVX2 1
#define PTC_TRACE_NS avx2
#include "bvh/tracer_kernel.h"
#include "bvh/tracer_packet.h"
