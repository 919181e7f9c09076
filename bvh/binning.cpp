#include "bvh/binning.h"

#include "bvh/box_simd.h"

namespace ptc::bvh::binned {

namespace {

std::uint64_t bin_range_sse2(Ref* r, std::uint32_t count, const BinParams& p, Bins& b0, Bins& b1) {
  std::uint64_t total = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    alignas(16) std::int32_t bi[4];
    store_bins(r[i], p, bi);
    (i & 1 ? b1 : b0).add(bi, load_lo(r[i]), negate(load_hi(r[i])), r[i].weight);
    total += r[i].weight;
  }
  return total;
}

__attribute__((target("avx2"))) inline void add8(Bins& bins, const std::int32_t* bi, __m256 v, std::uint32_t w) {
  for (int a = 0; a < 3; ++a) {
    float* q = bins.box[a][bi[a]];
    _mm256_store_ps(q, _mm256_min_ps(_mm256_load_ps(q), v));
    bins.weight[a][bi[a]] += w;
  }
}

// The same with AVX2 (only called when the CPU has it): the bin indices of two primitives per
// instruction, and one 8-wide min per axis and primitive. Same float operations, same bins.
__attribute__((target("avx2"))) std::uint64_t bin_range_avx2(Ref* r, std::uint32_t count, const BinParams& p,
                                                              Bins& b0, Bins& b1) {
  const __m256 clo = _mm256_broadcast_ps(&p.clo), sc = _mm256_broadcast_ps(&p.sc), maxbin = _mm256_broadcast_ps(&p.maxbin);
  const __m256 cmask = _mm256_castsi256_ps(_mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, 0));
  // [lo | hi] of a record -> [lo | -hi], lanes 3 and 7 (id, weight) cleared
  const __m256 bmask = cmask;
  const __m256 sign = _mm256_setr_ps(0.0f, 0.0f, 0.0f, 0.0f, -0.0f, -0.0f, -0.0f, 0.0f);
  std::uint64_t total = 0;
  std::uint32_t i = 0;
  for (; i + 1 < count; i += 2) {
    const __m256 c = _mm256_and_ps(_mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(r[i].c)),
                                                        _mm_load_ps(r[i + 1].c), 1),
                                   cmask);
    const __m256i b = _mm256_cvttps_epi32(
        _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(c, clo), sc), _mm256_setzero_ps()), maxbin));
    alignas(32) std::int32_t bi[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(bi), b);
    r[i].bins = static_cast<std::uint32_t>(bi[0] | bi[1] << 8 | bi[2] << 16);
    r[i + 1].bins = static_cast<std::uint32_t>(bi[4] | bi[5] << 8 | bi[6] << 16);
    const __m256 v0 = _mm256_xor_ps(_mm256_and_ps(_mm256_loadu_ps(r[i].lo), bmask), sign);
    const __m256 v1 = _mm256_xor_ps(_mm256_and_ps(_mm256_loadu_ps(r[i + 1].lo), bmask), sign);
    add8(b0, bi, v0, r[i].weight);
    add8(b1, bi + 4, v1, r[i + 1].weight);
    total += r[i].weight + r[i + 1].weight;
  }
  if (i < count) {
    alignas(16) std::int32_t bi[4];
    store_bins(r[i], p, bi);
    add8(b0, bi, _mm256_xor_ps(_mm256_and_ps(_mm256_loadu_ps(r[i].lo), bmask), sign), r[i].weight);
    total += r[i].weight;
  }
  return total;
}

}  // namespace

BinRangeFn bin_range_for(bool allow_avx2) {
  return allow_avx2 && simd::cpu_has_avx2() ? &bin_range_avx2 : &bin_range_sse2;
}

}  // namespace ptc::bvh::binned
