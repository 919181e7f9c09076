// SSE2 pieces of the per-frame box passes (internal to bvh/: box.cpp, vertex_order.cpp,
// leaf_blocks.cpp, leaf_tables.cpp, cluster_scene.cpp's refit and the binned builder's records),
// and the one AVX2 check of the loops that keep an AVX2 copy (those and binning.cpp).
#pragma once

#include <immintrin.h>

#include <cstring>
#include <limits>
#include <span>

#include "bvh/box.h"

namespace ptc::bvh::simd {

// Whether the CPU runs AVX2 code (asked once): the per-frame loops and the binning keep an AVX2
// (or VEX-encoded) copy beside their SSE2 one and pick it with this.
inline bool cpu_has_avx2() {
  static const bool yes = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") != 0;
  }();
  return yes;
}

// A box's lo and hi as (x y z .) rows by two 16-byte loads, reading no byte past it (lane 3 of
// lo holds hi.x, of hi lo.z).
inline void load_box(const Box3f& b, __m128& lo, __m128& hi) {
  const float* f = b.lo.data();
  lo = _mm_loadu_ps(f);      // lo xyz, hi x
  hi = _mm_loadu_ps(f + 2);  // lo z, hi xyz
  hi = _mm_shuffle_ps(hi, hi, _MM_SHUFFLE(0, 3, 2, 1));
}

// (x, y, z, 0) from a float triple, reading exactly 12 bytes.
inline __m128 load3(const Vec3f& p) {
  double xy_bits;  // memcpy: a float triple is only 4-byte aligned (compiles to one movsd)
  std::memcpy(&xy_bits, p.data(), sizeof xy_bits);
  const __m128 xy = _mm_castpd_ps(_mm_set_sd(xy_bits));
  return _mm_movelh_ps(xy, _mm_load_ss(p.data() + 2));
}

// A vertex of frame positions as (x, y, z, .): a 16-byte load at vertex v reads x, y, z of v
// and x of v + 1, allowed for every vertex but the last (lane 3 is never stored).
struct VertexLoader {
  explicit VertexLoader(std::span<const Vec3f> fp) : fp_(fp), wide_ok_(fp.empty() ? 0 : fp.size() - 1) {}
  __m128 operator()(std::uint32_t v) const { return v < wide_ok_ ? _mm_loadu_ps(fp_[v].data()) : load3(fp_[v]); }

 private:
  std::span<const Vec3f> fp_;
  std::size_t wide_ok_;
};

// next_below / next_above of four finite floats at once (see box.h): on the bit pattern,
// -1 for positive, +1 for negative values, and +-0 to -+denorm_min.
inline __m128 widen_down(__m128 x) {
  const __m128i b = _mm_castps_si128(x);
  const __m128i step = _mm_or_si128(_mm_slli_epi32(_mm_srai_epi32(b, 31), 1), _mm_set1_epi32(1));  // +1 / -1
  const __m128 r = _mm_castsi128_ps(_mm_sub_epi32(b, step));
  const __m128 zero = _mm_cmpeq_ps(x, _mm_setzero_ps());
  return _mm_or_ps(_mm_andnot_ps(zero, r), _mm_and_ps(zero, _mm_set1_ps(-std::numeric_limits<float>::denorm_min())));
}
inline __m128 widen_up(__m128 x) {
  const __m128i b = _mm_castps_si128(x);
  const __m128i step = _mm_or_si128(_mm_slli_epi32(_mm_srai_epi32(b, 31), 1), _mm_set1_epi32(1));
  const __m128 r = _mm_castsi128_ps(_mm_add_epi32(b, step));
  const __m128 zero = _mm_cmpeq_ps(x, _mm_setzero_ps());
  return _mm_or_ps(_mm_andnot_ps(zero, r), _mm_and_ps(zero, _mm_set1_ps(std::numeric_limits<float>::denorm_min())));
}

// The box of the min / max rows lo, hi widened by one unit in the last place, and its centre
// (= Box3f::center(), bit for bit).
inline void store_widened(__m128 lo, __m128 hi, Box3f& box, Vec3f& center) {
  lo = widen_down(lo), hi = widen_up(hi);
  alignas(16) float l[4], h[4], c[4];
  _mm_store_ps(l, lo), _mm_store_ps(h, hi);
  _mm_store_ps(c, _mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(lo, hi)));
  box.lo = {l[0], l[1], l[2]}, box.hi = {h[0], h[1], h[2]};
  center = {c[0], c[1], c[2]};
}

// Rows of minima and maxima of four lanes each (lo[a], hi[a]: axis a) folded into one box,
// stored widened (store_widened): the box of everything the rows took.
inline void fold_rows_store_widened(const __m128 (&lo)[3], const __m128 (&hi)[3], Box3f& box, Vec3f& center) {
  __m128 l = _mm_unpacklo_ps(lo[0], lo[1]), l2 = _mm_unpackhi_ps(lo[0], lo[1]);
  __m128 h = _mm_unpacklo_ps(hi[0], hi[1]), h2 = _mm_unpackhi_ps(hi[0], hi[1]);
  // lanes: l = (x0 y0 x1 y1), l2 = (x2 y2 x3 y3)
  __m128 lxy = _mm_min_ps(l, l2);                  // (x02 y02 x13 y13)
  lxy = _mm_min_ps(lxy, _mm_movehl_ps(lxy, lxy));  // (x y . .)
  __m128 hxy = _mm_max_ps(h, h2);
  hxy = _mm_max_ps(hxy, _mm_movehl_ps(hxy, hxy));
  __m128 lz = _mm_min_ps(lo[2], _mm_movehl_ps(lo[2], lo[2]));
  lz = _mm_min_ss(lz, _mm_shuffle_ps(lz, lz, 1));
  __m128 hz = _mm_max_ps(hi[2], _mm_movehl_ps(hi[2], hi[2]));
  hz = _mm_max_ss(hz, _mm_shuffle_ps(hz, hz, 1));
  store_widened(_mm_movelh_ps(lxy, lz), _mm_movelh_ps(hxy, hz), box, center);
}

// An empty group: the empty box and its centre.
inline void store_empty(Box3f& box, Vec3f& center) {
  box = Box3f{};
  center = box.center();
}

}  // namespace ptc::bvh::simd
