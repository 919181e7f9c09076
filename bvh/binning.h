// The binned builder's records and bins (internal to bvh/: binned_sah_builder.cpp and binning.cpp).
//
// Primitive references are copied into 48-byte records (box, id, weight, centroid) that are
// partitioned in place, so the hot loops stream through memory instead of gathering from the
// input spans. Records are only moved as three 16-byte rows (see load_ref). The binning pass
// (bin_range, an SSE2 and an AVX2 variant in binning.cpp) fills the bins of a node and stores
// each record's bins for the partition.
#pragma once

#include <immintrin.h>  // SSE2 (the x86-64 baseline); AVX2 only in binning.cpp's bin_range_avx2

#include <cmath>
#include <cstdint>
#include <limits>

#include "bvh/box.h"

namespace ptc::bvh::binned {

struct alignas(16) Ref {
  float lo[3];
  std::uint32_t id;
  float hi[3];
  std::uint32_t weight;
  float c[3];
  std::uint32_t bins;  // scratch: the bins on x, y, z (one byte each) of the current node's binning
};
static_assert(sizeof(Ref) == 48);

inline constexpr std::uint32_t kMaxBins = 256;

// Per axis and bin: the box as eight floats, lo x y z . and -hi x y z . (the upper bound negated,
// so that one minimum updates both halves: one 8-wide min per axis and primitive with AVX, two
// 4-wide ones without; -max(a, b) = min(-a, -b) exactly, so both variants give the same bins).
struct Bins {
  alignas(32) float box[3][kMaxBins][8];
  std::uint32_t weight[3][kMaxBins];  // weights >= 1, so 0 means an empty bin

  [[nodiscard]] __m128 lo(int a, std::uint32_t b) const { return _mm_load_ps(box[a][b]); }
  [[nodiscard]] __m128 neg_hi(int a, std::uint32_t b) const { return _mm_load_ps(box[a][b] + 4); }
  void clear(std::uint32_t nbins) {
    const __m128 inf = _mm_set1_ps(kInf);
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t b = 0; b < nbins; ++b)
        _mm_store_ps(box[a][b], inf), _mm_store_ps(box[a][b] + 4, inf), weight[a][b] = 0;
  }
  void add(const std::int32_t* bin, __m128 l, __m128 nh, std::uint32_t w) {
    for (int a = 0; a < 3; ++a) {
      float* p = box[a][bin[a]];
      _mm_store_ps(p, _mm_min_ps(_mm_load_ps(p), l));
      _mm_store_ps(p + 4, _mm_min_ps(_mm_load_ps(p + 4), nh));
      weight[a][bin[a]] += w;
    }
  }
  void merge(const Bins& o, std::uint32_t nbins) {
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t b = 0; b < nbins; ++b) {
        float* p = box[a][b];
        const float* q = o.box[a][b];
        _mm_store_ps(p, _mm_min_ps(_mm_load_ps(p), _mm_load_ps(q)));
        _mm_store_ps(p + 4, _mm_min_ps(_mm_load_ps(p + 4), _mm_load_ps(q + 4)));
        weight[a][b] += o.weight[a][b];
      }
  }
};

// Lane 3 of the lo / hi rows holds the id / weight bits: small integers read as floats are
// denormals, and arithmetic on denormals takes a microcode assist (measured: 12% of the build in
// one multiply), so lane 3 is cleared on every load.
inline __m128 xyz_mask() { return _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)); }
inline __m128 load_lo(const Ref& r) { return _mm_and_ps(_mm_load_ps(r.lo), xyz_mask()); }
inline __m128 load_hi(const Ref& r) { return _mm_and_ps(_mm_load_ps(r.hi), xyz_mask()); }

// Whole-record moves as three 16-byte loads and stores (a struct copy may be split into 8- and
// 4-byte moves, and a later 16-byte load of the record then waits for them to retire: the
// store-to-load forwarding stall that cost 14% of the build in the partition loop).
struct RefBits {
  __m128 a, b, c;
};
inline RefBits load_ref(const Ref& x) { return {_mm_load_ps(x.lo), _mm_load_ps(x.hi), _mm_load_ps(x.c)}; }
inline void store_ref(Ref& x, const RefBits& v) { _mm_store_ps(x.lo, v.a), _mm_store_ps(x.hi, v.b), _mm_store_ps(x.c, v.c); }
// A new record from its rows (lane 3 of lo, hi zero; c: the centroid, lane 3 ignored), written
// with whole 16-byte stores (field-by-field stores followed by 16-byte loads defeat
// store-to-load forwarding: measured 6% of the build).
inline void store_record(Ref& r, __m128 lo, __m128 hi, __m128 c, std::uint32_t id, std::uint32_t weight) {
  _mm_store_ps(r.lo, _mm_or_ps(lo, _mm_castsi128_ps(_mm_setr_epi32(0, 0, 0, static_cast<int>(id)))));
  _mm_store_ps(r.hi, _mm_or_ps(hi, _mm_castsi128_ps(_mm_setr_epi32(0, 0, 0, static_cast<int>(weight)))));
  _mm_store_ps(r.c, c);
}

inline Box3f to_box(__m128 lo, __m128 hi) {
  alignas(16) float l[4], h[4];
  _mm_store_ps(l, lo), _mm_store_ps(h, hi);
  return {{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
}

// Lanes 0 + 1 + 2 of x, in that order.
inline float sum3(__m128 x) {
  const __m128 s = _mm_add_ss(x, _mm_shuffle_ps(x, x, _MM_SHUFFLE(3, 3, 3, 1)));
  return _mm_cvtss_f32(_mm_add_ss(s, _mm_movehl_ps(x, x)));
}

// Half the weighted surface area, w_z xy + w_x yz + w_y zx, of a non-empty box (lanes 0-2), in
// float: only compared. w: area_weights_of(BuildConfig::area_weights).
inline float half_area(__m128 lo, __m128 hi, __m128 w) {
  const __m128 e = _mm_sub_ps(hi, lo);                                 // x y z .
  const __m128 r = _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1));       // y z x .
  return sum3(_mm_mul_ps(_mm_mul_ps(e, r), w));                        // w_z xy + w_x yz + w_y zx
}

// Half of Box3f::area_from in float: the solid angle a non-empty box (lanes 0-2) shows the point
// `eye` (lanes 0-2), roughly (BuildConfig::area_eye); only compared.
inline float half_area_from(__m128 lo, __m128 hi, __m128 eye) {
  const __m128 e = _mm_sub_ps(hi, lo);
  const __m128 v = _mm_sub_ps(_mm_mul_ps(_mm_add_ps(lo, hi), _mm_set1_ps(0.5f)), eye);
  const __m128 av = _mm_andnot_ps(_mm_set1_ps(-0.0f), v);
  const __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));  // xy yz zx .
  const __m128 w = _mm_shuffle_ps(av, av, _MM_SHUFFLE(3, 1, 0, 2));               // |v_z| |v_x| |v_y| .
  const float seen = sum3(_mm_mul_ps(p, w)), all = sum3(p);
  const float d2 = sum3(_mm_mul_ps(v, v)), r2 = 0.25f * sum3(_mm_mul_ps(e, e));
  const float D2 = d2 > r2 ? d2 : r2;
  if (!(D2 >= std::numeric_limits<float>::min())) return 0.0f;
  // 1 / D from the reciprocal square root estimate and one Newton step (about 22 bits; no
  // square root or division in the builder's inner loops)
  const __m128 x = _mm_set_ss(D2);
  __m128 r = _mm_rsqrt_ss(x);
  r = _mm_mul_ss(r, _mm_sub_ss(_mm_set_ss(1.5f), _mm_mul_ss(_mm_mul_ss(_mm_set_ss(0.5f), x), _mm_mul_ss(r, r))));
  const float inv = _mm_cvtss_f32(r);
  return (seen * inv + static_cast<float>(kEyeAreaIsotropic) * all) * (inv * inv);
}

// The weights of half_area's products xy, yz, zx (1, 1, 1: the plain half area, the same bits).
inline __m128 area_weights_of(const std::array<float, 3>& w) { return _mm_setr_ps(w[2], w[0], w[1], 0.0f); }

inline __m128 negate(__m128 x) { return _mm_xor_ps(x, _mm_set1_ps(-0.0f)); }

// A child's box, gathered while the primitives are put in place.
struct SideBounds {
  __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf);
  void add(const Ref& x) { lo = _mm_min_ps(lo, load_lo(x)), hi = _mm_max_ps(hi, load_hi(x)); }
};

// The one bin formula of binning and partition: clamp((c - clo) * sc, 0, maxbin), truncated.
struct BinParams {
  __m128 clo, sc, maxbin;
};
inline __m128i bins_of(__m128 c, const BinParams& p) {
  c = _mm_and_ps(c, xyz_mask());  // lane 3 holds Ref::bins
  return _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c, p.clo), p.sc), _mm_setzero_ps()), p.maxbin));
}
inline std::uint32_t pack_bins(__m128i b) {  // x | y << 8 | z << 16 (each in [0, 255])
  const __m128i y8 = _mm_slli_epi32(_mm_srli_si128(b, 4), 8), z16 = _mm_slli_epi32(_mm_srli_si128(b, 8), 16);
  return static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_or_si128(_mm_or_si128(b, y8), z16)));
}
// The bins of record r, also kept in r.bins for the partition; bi (16-byte aligned) receives
// them as four ints (x, y, z, .).
inline void store_bins(Ref& r, const BinParams& p, std::int32_t* bi) {
  const __m128i b = bins_of(_mm_load_ps(r.c), p);
  _mm_store_si128(reinterpret_cast<__m128i*>(bi), b);
  r.bins = pack_bins(b);
}

// The binning pass of a node: record i into b0 (even i) or b1 (odd i; b1 may be b0): two bin
// sets, since consecutive updates of the same bin would otherwise wait for each other through
// memory. The bins on x, y, z are also kept in Ref::bins for the partition. Returns the summed
// weight.
using BinRangeFn = std::uint64_t (*)(Ref* r, std::uint32_t count, const BinParams& p, Bins& b0, Bins& b1);
/// The AVX2 variant when allow_avx2 and the CPU has it (checked once), else the SSE2 one: both
/// give the same bins (the same float operations).
[[nodiscard]] BinRangeFn bin_range_for(bool allow_avx2);

}  // namespace ptc::bvh::binned
