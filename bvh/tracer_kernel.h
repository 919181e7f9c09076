// Internal: the tracer's traversal and leaf kernels, compiled once per instruction set (see
// tracer_isa.h). Include only from tracer_sse2.cpp / tracer_avx2.cpp / tracer_avx512.cpp, after defining
// PTC_TRACE_NS (the namespace that keeps the two compilations apart: no symbol of one can be
// picked by the linker for the other).
#ifndef PTC_TRACE_NS
#error "define PTC_TRACE_NS before including bvh/tracer_kernel.h"
#endif

#include <immintrin.h>

#include <cmath>
#include <limits>
#include <vector>

#include "bvh/tracer.h"
#include "bvh/tracer_isa.h"
#include "bvh/watertight.h"

namespace ptc::bvh::detail::PTC_TRACE_NS {
namespace {

constexpr float kBig = std::numeric_limits<float>::max();
// Conservative slab test: 2^-21 > 2 gamma_3 = 6u / (1 - 3u), u = 2^-24 (see tracer.h).
constexpr float kNearScale = 1.0f - 1.0f / 2097152.0f;
constexpr float kFarScale = 1.0f + 1.0f / 2097152.0f;

struct StackEntry {
  std::uint32_t ref;    // inner: node index; leaf: first range
  std::uint32_t count;  // 0: inner; > 0: number of ranges
  float t;              // entry distance of the box (conservative)
};

// Everything a ray needs during traversal, precomputed once.
struct RayState {
  // slab test
  __m128 ox, oy, oz, inx, iny, inz, ifx, ify, ifz;
  int nx, ny, nz, fx, fy, fz;  // float offsets of the near/far rows in WideNode8::bounds
  // watertight test: made when the ray reaches its first leaf (most primary rays never do)
  bool watertight_ready;
  int kx4, ky4, kz4;  // 4 * permuted axes (offsets inside a corner's 3x4 block)
  __m128 okx, oky, okz, sx, sy, sz;
#if defined(PTC_TRACE_AVX2)
  __m256 okx8, oky8, okz8, sx8, sy8, sz8;
#endif
#if defined(PTC_TRACE_AVX512)
  __m512 okx16, oky16, okz16, sx16, sy16, sz16;
#endif
  float tmin, tmax;  // tmax: the best hit so far (closest) or the ray's end
  Vec3f org, dir;
};

void prepare_watertight(RayState& r) {
  const WatertightRay w = make_watertight_ray(r.org, r.dir);
  r.kx4 = 4 * w.kx, r.ky4 = 4 * w.ky, r.kz4 = 4 * w.kz;
  r.okx = _mm_set1_ps(r.org[w.kx]), r.oky = _mm_set1_ps(r.org[w.ky]), r.okz = _mm_set1_ps(r.org[w.kz]);
  r.sx = _mm_set1_ps(w.sx), r.sy = _mm_set1_ps(w.sy), r.sz = _mm_set1_ps(w.sz);
#if defined(PTC_TRACE_AVX2)
  r.okx8 = _mm256_set1_ps(r.org[w.kx]), r.oky8 = _mm256_set1_ps(r.org[w.ky]), r.okz8 = _mm256_set1_ps(r.org[w.kz]);
  r.sx8 = _mm256_set1_ps(w.sx), r.sy8 = _mm256_set1_ps(w.sy), r.sz8 = _mm256_set1_ps(w.sz);
#endif
#if defined(PTC_TRACE_AVX512)
  r.okx16 = _mm512_set1_ps(r.org[w.kx]), r.oky16 = _mm512_set1_ps(r.org[w.ky]), r.okz16 = _mm512_set1_ps(r.org[w.kz]);
  r.sx16 = _mm512_set1_ps(w.sx), r.sy16 = _mm512_set1_ps(w.sy), r.sz16 = _mm512_set1_ps(w.sz);
#endif
  r.watertight_ready = true;
}

struct Result {
  float t = 0, u = 0, v = 0;
  std::uint32_t tri = kNoTriangle;
  std::uint32_t nodes = 0, tris = 0;
};

// Returns false for a ray that cannot hit (zero or non-finite direction, empty interval).
// The ray's state from its set-up values: origin and direction in the trace frame, the slab
// constants 1/d x kNearScale and 1/d x kFarScale, per axis whether 1/d is negative, and the
// interval (tmax already clamped to kBig). setup() and the batched set-up (setup8) both end here.
[[gnu::always_inline]] inline void fill_state(RayState& r, const Vec3f& o, const Vec3f& d, const float* in,
                                              const float* fa, const bool* neg, float tmin, float tmax) {
  r.tmin = tmin, r.tmax = tmax;
  r.ox = _mm_set1_ps(o[0]), r.oy = _mm_set1_ps(o[1]), r.oz = _mm_set1_ps(o[2]);
  r.inx = _mm_set1_ps(in[0]), r.iny = _mm_set1_ps(in[1]), r.inz = _mm_set1_ps(in[2]);
  r.ifx = _mm_set1_ps(fa[0]), r.ify = _mm_set1_ps(fa[1]), r.ifz = _mm_set1_ps(fa[2]);
  int near[3];
  for (int a = 0; a < 3; ++a) near[a] = 2 * a + (neg[a] ? 1 : 0);
  r.nx = 8 * near[0], r.ny = 8 * near[1], r.nz = 8 * near[2];  // rows of eight floats (WideNode8)
  r.fx = 8 * (near[0] ^ 1), r.fy = 8 * (near[1] ^ 1), r.fz = 8 * (near[2] ^ 1);
  r.org = o, r.dir = d;
  r.watertight_ready = false;
}

bool setup(RayState& r, const Vec3f& o, const Vec3f& d, float tmin, float tmax) {
  if (!(std::isfinite(d[0]) && std::isfinite(d[1]) && std::isfinite(d[2]))) return false;
  if (d[0] == 0.0f && d[1] == 0.0f && d[2] == 0.0f) return false;
  if (!(std::isfinite(o[0]) && std::isfinite(o[1]) && std::isfinite(o[2]))) return false;
  const float tmax_c = tmax < kBig ? tmax : kBig;
  if (!(tmin < tmax_c) || !(tmin >= 0.0f)) return false;
  float in[3], fa[3];
  bool neg[3];
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.0f / d[a];  // +-inf for a zero component (its sign follows the zero's sign)
    in[a] = inv * kNearScale, fa[a] = inv * kFarScale, neg[a] = std::signbit(inv);
  }
  fill_state(r, o, d, in, fa, neg, tmin, tmax_c);
  return true;
}

inline int ctz(unsigned m) { return __builtin_ctz(m); }

// The lanes of `m` (in/range hits, lowest lane first) against the best hit so far: closest
// keeps the smallest (t, id), any-hit takes the first. t, V, W, det per lane; shared by the 4-
// and 8-wide kernels, so both choose identically.
template <bool AnyHit>
inline bool take_hits(int m, const float* ft, const float* fv, const float* fw, const float* fd,
                      const std::uint32_t* ids, float& tmax, Result& res) {
  bool found = false;
  for (; m; m &= m - 1) {
    const int l = ctz(static_cast<unsigned>(m));
    const std::uint32_t id = ids[l];
    if constexpr (!AnyHit) {
      if (!(ft[l] < tmax || (ft[l] == tmax && id < res.tri))) continue;
    }
    res.t = ft[l];
    res.tri = id;
    res.u = fv[l] / fd[l];
    res.v = fw[l] / fd[l];
    found = true;
    if constexpr (AnyHit) return true;
    tmax = ft[l];
  }
  return found;
}

// The lanes of `on_edge` with an edge function of exactly 0: all three recomputed in double.
inline void redo_edges_in_double(int on_edge, const float* ax, const float* ay, const float* bx, const float* by,
                                 const float* cx, const float* cy, float* u, float* v, float* w) {
  for (; on_edge; on_edge &= on_edge - 1) {
    const int l = ctz(static_cast<unsigned>(on_edge));
    edge_functions_double(ax[l], ay[l], bx[l], by[l], cx[l], cy[l], u[l], v[l], w[l]);
  }
}

// Four triangles of one block against the ray; updates `res` and `tmax` (closest: the
// smallest (t, id); any: the first hit). Returns true when a hit was recorded. The float
// operations and their order are those of intersect_triangle (watertight.cpp).
template <bool AnyHit>
[[gnu::always_inline]] inline bool intersect_block(const TriBlock& blk, const std::uint32_t* ids, const RayState& r,
                                                   float& tmax, Result& res) {
  const float* v = &blk.v[0][0][0];
  const __m128 a_x = _mm_sub_ps(_mm_load_ps(v + r.kx4), r.okx);
  const __m128 a_y = _mm_sub_ps(_mm_load_ps(v + r.ky4), r.oky);
  const __m128 a_z = _mm_sub_ps(_mm_load_ps(v + r.kz4), r.okz);
  const __m128 b_x = _mm_sub_ps(_mm_load_ps(v + 12 + r.kx4), r.okx);
  const __m128 b_y = _mm_sub_ps(_mm_load_ps(v + 12 + r.ky4), r.oky);
  const __m128 b_z = _mm_sub_ps(_mm_load_ps(v + 12 + r.kz4), r.okz);
  const __m128 c_x = _mm_sub_ps(_mm_load_ps(v + 24 + r.kx4), r.okx);
  const __m128 c_y = _mm_sub_ps(_mm_load_ps(v + 24 + r.ky4), r.oky);
  const __m128 c_z = _mm_sub_ps(_mm_load_ps(v + 24 + r.kz4), r.okz);
  const __m128 ax = _mm_sub_ps(a_x, _mm_mul_ps(r.sx, a_z)), ay = _mm_sub_ps(a_y, _mm_mul_ps(r.sy, a_z));
  const __m128 bx = _mm_sub_ps(b_x, _mm_mul_ps(r.sx, b_z)), by = _mm_sub_ps(b_y, _mm_mul_ps(r.sy, b_z));
  const __m128 cx = _mm_sub_ps(c_x, _mm_mul_ps(r.sx, c_z)), cy = _mm_sub_ps(c_y, _mm_mul_ps(r.sy, c_z));
  __m128 U = _mm_sub_ps(_mm_mul_ps(cx, by), _mm_mul_ps(cy, bx));
  __m128 V = _mm_sub_ps(_mm_mul_ps(ax, cy), _mm_mul_ps(ay, cx));
  __m128 W = _mm_sub_ps(_mm_mul_ps(bx, ay), _mm_mul_ps(by, ax));
  const __m128 zero = _mm_setzero_ps();
  const int on_edge = _mm_movemask_ps(
      _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(U, zero), _mm_cmpeq_ps(V, zero)), _mm_cmpeq_ps(W, zero)));
  if (on_edge) [[unlikely]] {  // exact signs in double for the lanes with a zero edge function
    alignas(16) float fax[4], fay[4], fbx[4], fby[4], fcx[4], fcy[4], fu[4], fv[4], fw[4];
    _mm_store_ps(fax, ax), _mm_store_ps(fay, ay), _mm_store_ps(fbx, bx), _mm_store_ps(fby, by);
    _mm_store_ps(fcx, cx), _mm_store_ps(fcy, cy), _mm_store_ps(fu, U), _mm_store_ps(fv, V), _mm_store_ps(fw, W);
    redo_edges_in_double(on_edge, fax, fay, fbx, fby, fcx, fcy, fu, fv, fw);
    U = _mm_load_ps(fu), V = _mm_load_ps(fv), W = _mm_load_ps(fw);
  }
  const __m128 neg = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(U, zero), _mm_cmplt_ps(V, zero)), _mm_cmplt_ps(W, zero));
  const __m128 pos = _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(U, zero), _mm_cmpgt_ps(V, zero)), _mm_cmpgt_ps(W, zero));
  const __m128 det = _mm_add_ps(_mm_add_ps(U, V), W);
  const __m128 det_ok = _mm_or_ps(_mm_cmplt_ps(det, zero), _mm_cmpgt_ps(det, zero));  // false for NaN lanes
  const __m128 valid = _mm_andnot_ps(_mm_and_ps(neg, pos), det_ok);
  if (!_mm_movemask_ps(valid)) return false;
  const __m128 az = _mm_mul_ps(r.sz, a_z), bz = _mm_mul_ps(r.sz, b_z), cz = _mm_mul_ps(r.sz, c_z);
  const __m128 T = _mm_add_ps(_mm_add_ps(_mm_mul_ps(U, az), _mm_mul_ps(V, bz)), _mm_mul_ps(W, cz));
  const __m128 t = _mm_div_ps(T, det);
  const __m128 in_range = _mm_and_ps(_mm_cmpgt_ps(t, _mm_set1_ps(r.tmin)), _mm_cmple_ps(t, _mm_set1_ps(tmax)));
  int m = _mm_movemask_ps(_mm_and_ps(valid, in_range));
  if (!m) return false;
  alignas(16) float ft[4], fv[4], fw[4], fd[4];
  _mm_store_ps(ft, t), _mm_store_ps(fv, V), _mm_store_ps(fw, W), _mm_store_ps(fd, det);
  return take_hits<AnyHit>(m, ft, fv, fw, fd, ids, tmax, res);
}

#if defined(PTC_TRACE_AVX2)
// The watertight test (intersect_triangle's float operations, in its order) on eight (ray,
// triangle) pairs at once, from the corners relative to the ray origin in the ray's permuted
// axes (a_x .. c_z) and its shear constants. Eight triangles against one ray (a block pair) and
// one triangle against eight rays (the packet path's ray-parallel leaves) both call it, so both
// give the single-ray bits. `live`: the lanes that are real pairs (only they get their zero edge
// functions redone in double). Returns the lanes with a hit inside the triangle (valid), and for
// those t = T / det with V, W and det for the barycentrics; t is computed only when some live
// lane is valid.
struct Pairs8 {
  __m256 valid, t, V, W, det;
  int valid_bits;  // movemask(valid) & live
};
inline Pairs8 watertight8(__m256 a_x, __m256 a_y, __m256 a_z, __m256 b_x, __m256 b_y, __m256 b_z, __m256 c_x, __m256 c_y,
                          __m256 c_z, __m256 sx, __m256 sy, __m256 sz, int live) {
  const __m256 ax = _mm256_sub_ps(a_x, _mm256_mul_ps(sx, a_z)), ay = _mm256_sub_ps(a_y, _mm256_mul_ps(sy, a_z));
  const __m256 bx = _mm256_sub_ps(b_x, _mm256_mul_ps(sx, b_z)), by = _mm256_sub_ps(b_y, _mm256_mul_ps(sy, b_z));
  const __m256 cx = _mm256_sub_ps(c_x, _mm256_mul_ps(sx, c_z)), cy = _mm256_sub_ps(c_y, _mm256_mul_ps(sy, c_z));
  __m256 U = _mm256_sub_ps(_mm256_mul_ps(cx, by), _mm256_mul_ps(cy, bx));
  __m256 V = _mm256_sub_ps(_mm256_mul_ps(ax, cy), _mm256_mul_ps(ay, cx));
  __m256 W = _mm256_sub_ps(_mm256_mul_ps(bx, ay), _mm256_mul_ps(by, ax));
  const __m256 zero = _mm256_setzero_ps();
  const int on_edge = _mm256_movemask_ps(_mm256_or_ps(
      _mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_EQ_OQ), _mm256_cmp_ps(V, zero, _CMP_EQ_OQ)), _mm256_cmp_ps(W, zero, _CMP_EQ_OQ))) &
      live;
  if (on_edge) [[unlikely]] {
    alignas(32) float fax[8], fay[8], fbx[8], fby[8], fcx[8], fcy[8], fu[8], fv[8], fw[8];
    _mm256_store_ps(fax, ax), _mm256_store_ps(fay, ay), _mm256_store_ps(fbx, bx), _mm256_store_ps(fby, by);
    _mm256_store_ps(fcx, cx), _mm256_store_ps(fcy, cy), _mm256_store_ps(fu, U), _mm256_store_ps(fv, V);
    _mm256_store_ps(fw, W);
    redo_edges_in_double(on_edge, fax, fay, fbx, fby, fcx, fcy, fu, fv, fw);
    U = _mm256_load_ps(fu), V = _mm256_load_ps(fv), W = _mm256_load_ps(fw);
  }
  const __m256 neg = _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_LT_OQ), _mm256_cmp_ps(V, zero, _CMP_LT_OQ)),
                                  _mm256_cmp_ps(W, zero, _CMP_LT_OQ));
  const __m256 pos = _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_GT_OQ), _mm256_cmp_ps(V, zero, _CMP_GT_OQ)),
                                  _mm256_cmp_ps(W, zero, _CMP_GT_OQ));
  Pairs8 p;
  p.det = _mm256_add_ps(_mm256_add_ps(U, V), W);
  const __m256 det_ok = _mm256_or_ps(_mm256_cmp_ps(p.det, zero, _CMP_LT_OQ), _mm256_cmp_ps(p.det, zero, _CMP_GT_OQ));
  p.valid = _mm256_andnot_ps(_mm256_and_ps(neg, pos), det_ok);
  p.valid_bits = _mm256_movemask_ps(p.valid) & live;
  p.V = V, p.W = W;
  if (!p.valid_bits) return p;
  const __m256 az = _mm256_mul_ps(sz, a_z), bz = _mm256_mul_ps(sz, b_z), cz = _mm256_mul_ps(sz, c_z);
  const __m256 T = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(U, az), _mm256_mul_ps(V, bz)), _mm256_mul_ps(W, cz));
  p.t = _mm256_div_ps(T, p.det);
  return p;
}

// The hits of a test of eight (`live`: its real lanes) within the ray's interval, taken into the
// best hit (take_hits). Returns true when a hit was recorded.
template <bool AnyHit>
[[gnu::always_inline]] inline bool take_pairs8(const Pairs8& h, int live, const std::uint32_t* ids, const RayState& r,
                                               float& tmax, Result& res) {
  if (!h.valid_bits) return false;
  const __m256 in_range = _mm256_and_ps(_mm256_cmp_ps(h.t, _mm256_set1_ps(r.tmin), _CMP_GT_OQ),
                                        _mm256_cmp_ps(h.t, _mm256_set1_ps(tmax), _CMP_LE_OQ));
  const int m = _mm256_movemask_ps(_mm256_and_ps(h.valid, in_range)) & live;
  if (!m) return false;
  alignas(32) float ft[8], fv[8], fw[8], fd[8];
  _mm256_store_ps(ft, h.t), _mm256_store_ps(fv, h.V), _mm256_store_ps(fw, h.W), _mm256_store_ps(fd, h.det);
  return take_hits<AnyHit>(m, ft, fv, fw, fd, ids, tmax, res);
}

// Two consecutive blocks (8 triangles, ids[0..8)) in one 256-bit test: lane l < 4 is block 0's
// lane l, lane l >= 4 block 1's lane l - 4. The same float operations per lane as
// intersect_block, and lanes are taken in the same order (block 0 first), so hits and any-hit
// choices are identical to two calls of intersect_block.
template <bool AnyHit>
[[gnu::always_inline]] inline bool intersect_block_pair(const TriBlock* blk, const std::uint32_t* ids,
                                                        const RayState& r, float& tmax, Result& res) {
  const float* v0 = &blk[0].v[0][0][0];
  const float* v1 = &blk[1].v[0][0][0];
  auto ld = [&](int off) {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(v0 + off)), _mm_load_ps(v1 + off), 1);
  };
  const Pairs8 h = watertight8(
      _mm256_sub_ps(ld(r.kx4), r.okx8), _mm256_sub_ps(ld(r.ky4), r.oky8), _mm256_sub_ps(ld(r.kz4), r.okz8),
      _mm256_sub_ps(ld(12 + r.kx4), r.okx8), _mm256_sub_ps(ld(12 + r.ky4), r.oky8), _mm256_sub_ps(ld(12 + r.kz4), r.okz8),
      _mm256_sub_ps(ld(24 + r.kx4), r.okx8), _mm256_sub_ps(ld(24 + r.ky4), r.oky8), _mm256_sub_ps(ld(24 + r.kz4), r.okz8),
      r.sx8, r.sy8, r.sz8, 0xff);
  return take_pairs8<AnyHit>(h, 0xff, ids, r, tmax, res);
}
#endif

#if defined(PTC_TRACE_AVX512)
// watertight8 on sixteen (ray, triangle) pairs: the same float operations per pair, the
// comparisons into mask registers. Four blocks against one ray (intersect_block_quad) and two
// triangles against eight rays (the packet path's ray-parallel leaves) call it.
struct Pairs16 {
  __m512 t, V, W, det;
  __mmask16 valid;  // valid lanes among `live`; t is computed only when there is one
};
inline Pairs16 watertight16(__m512 a_x, __m512 a_y, __m512 a_z, __m512 b_x, __m512 b_y, __m512 b_z, __m512 c_x,
                            __m512 c_y, __m512 c_z, __m512 sx, __m512 sy, __m512 sz, __mmask16 live) {
  const __m512 ax = _mm512_sub_ps(a_x, _mm512_mul_ps(sx, a_z)), ay = _mm512_sub_ps(a_y, _mm512_mul_ps(sy, a_z));
  const __m512 bx = _mm512_sub_ps(b_x, _mm512_mul_ps(sx, b_z)), by = _mm512_sub_ps(b_y, _mm512_mul_ps(sy, b_z));
  const __m512 cx = _mm512_sub_ps(c_x, _mm512_mul_ps(sx, c_z)), cy = _mm512_sub_ps(c_y, _mm512_mul_ps(sy, c_z));
  __m512 U = _mm512_sub_ps(_mm512_mul_ps(cx, by), _mm512_mul_ps(cy, bx));
  __m512 V = _mm512_sub_ps(_mm512_mul_ps(ax, cy), _mm512_mul_ps(ay, cx));
  __m512 W = _mm512_sub_ps(_mm512_mul_ps(bx, ay), _mm512_mul_ps(by, ax));
  const __m512 zero = _mm512_setzero_ps();
  const int on_edge = (_mm512_cmp_ps_mask(U, zero, _CMP_EQ_OQ) | _mm512_cmp_ps_mask(V, zero, _CMP_EQ_OQ) |
                       _mm512_cmp_ps_mask(W, zero, _CMP_EQ_OQ)) &
                      live;
  if (on_edge) [[unlikely]] {  // exact signs in double for the lanes with a zero edge function
    alignas(64) float fax[16], fay[16], fbx[16], fby[16], fcx[16], fcy[16], fu[16], fv[16], fw[16];
    _mm512_store_ps(fax, ax), _mm512_store_ps(fay, ay), _mm512_store_ps(fbx, bx), _mm512_store_ps(fby, by);
    _mm512_store_ps(fcx, cx), _mm512_store_ps(fcy, cy), _mm512_store_ps(fu, U), _mm512_store_ps(fv, V);
    _mm512_store_ps(fw, W);
    redo_edges_in_double(on_edge, fax, fay, fbx, fby, fcx, fcy, fu, fv, fw);
    U = _mm512_load_ps(fu), V = _mm512_load_ps(fv), W = _mm512_load_ps(fw);
  }
  const __mmask16 neg = _mm512_cmp_ps_mask(U, zero, _CMP_LT_OQ) | _mm512_cmp_ps_mask(V, zero, _CMP_LT_OQ) |
                        _mm512_cmp_ps_mask(W, zero, _CMP_LT_OQ);
  const __mmask16 pos = _mm512_cmp_ps_mask(U, zero, _CMP_GT_OQ) | _mm512_cmp_ps_mask(V, zero, _CMP_GT_OQ) |
                        _mm512_cmp_ps_mask(W, zero, _CMP_GT_OQ);
  Pairs16 p;
  p.det = _mm512_add_ps(_mm512_add_ps(U, V), W);
  const __mmask16 det_ok = _mm512_cmp_ps_mask(p.det, zero, _CMP_LT_OQ) | _mm512_cmp_ps_mask(p.det, zero, _CMP_GT_OQ);
  p.valid = det_ok & static_cast<__mmask16>(~(neg & pos)) & live;
  p.V = V, p.W = W;
  if (!p.valid) return p;
  const __m512 az = _mm512_mul_ps(sz, a_z), bz = _mm512_mul_ps(sz, b_z), cz = _mm512_mul_ps(sz, c_z);
  const __m512 T = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(U, az), _mm512_mul_ps(V, bz)), _mm512_mul_ps(W, cz));
  p.t = _mm512_div_ps(T, p.det);
  return p;
}

// take_pairs8 for a test of sixteen (its valid lanes are live ones already).
template <bool AnyHit>
[[gnu::always_inline]] inline bool take_pairs16(const Pairs16& h, const std::uint32_t* ids, const RayState& r,
                                                float& tmax, Result& res) {
  if (!h.valid) return false;
  const int m = h.valid & _mm512_cmp_ps_mask(h.t, _mm512_set1_ps(r.tmin), _CMP_GT_OQ) &
                _mm512_cmp_ps_mask(h.t, _mm512_set1_ps(tmax), _CMP_LE_OQ);
  if (!m) return false;
  alignas(64) float ft[16], fv[16], fw[16], fd[16];
  _mm512_store_ps(ft, h.t), _mm512_store_ps(fv, h.V), _mm512_store_ps(fw, h.W), _mm512_store_ps(fd, h.det);
  return take_hits<AnyHit>(m, ft, fv, fw, fd, ids, tmax, res);
}

// Four consecutive blocks (16 triangles, ids[0..16)) in one 512-bit test: lane l is block l / 4's
// lane l % 4. The float operations per lane are intersect_block's, and lanes are taken lowest
// first, so hits and any-hit choices are identical to four calls of intersect_block (and to two
// of intersect_block_pair).
template <bool AnyHit>
[[gnu::always_inline]] inline bool intersect_block_quad(const TriBlock* blk, const std::uint32_t* ids,
                                                        const RayState& r, float& tmax, Result& res) {
  const float* v0 = &blk[0].v[0][0][0];
  const float* v1 = &blk[1].v[0][0][0];
  const float* v2 = &blk[2].v[0][0][0];
  const float* v3 = &blk[3].v[0][0][0];
  auto ld = [&](int off) {
    __m512 x = _mm512_castps128_ps512(_mm_load_ps(v0 + off));
    x = _mm512_insertf32x4(x, _mm_load_ps(v1 + off), 1);
    x = _mm512_insertf32x4(x, _mm_load_ps(v2 + off), 2);
    return _mm512_insertf32x4(x, _mm_load_ps(v3 + off), 3);
  };
  const Pairs16 h = watertight16(
      _mm512_sub_ps(ld(r.kx4), r.okx16), _mm512_sub_ps(ld(r.ky4), r.oky16), _mm512_sub_ps(ld(r.kz4), r.okz16),
      _mm512_sub_ps(ld(12 + r.kx4), r.okx16), _mm512_sub_ps(ld(12 + r.ky4), r.oky16),
      _mm512_sub_ps(ld(12 + r.kz4), r.okz16), _mm512_sub_ps(ld(24 + r.kx4), r.okx16),
      _mm512_sub_ps(ld(24 + r.ky4), r.oky16), _mm512_sub_ps(ld(24 + r.kz4), r.okz16), r.sx16, r.sy16, r.sz16, 0xffff);
  return take_pairs16<AnyHit>(h, ids, r, tmax, res);
}
#endif

// A table group's triangles as blocks (NaN corners in the lanes at or beyond its count): the
// leaf tests of the variants without AVX-512 and the packets' ray-parallel test read tables this
// way. The same floats as the group's rows, so the same hits as the permutes of intersect_group.
inline void expand_group(const TableGroup& g, TriBlock* out) {
  const std::uint32_t n = g.count, nb = (n + 3) / 4;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::uint32_t i = 0; i < 4 * nb; ++i)
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) out[i / 4].v[c][a][i % 4] = i < n ? g.v[a][g.corner[c][i]] : nan;
}

#if defined(PTC_TRACE_EVEX) && !defined(PTC_TRACE_AVX512)
// intersect_group's test of the eight triangles i .. i + 7 (AVX-512VL): the chunks at slots e
// (even) and o (odd) of the rows tx, ty, tz, each corner row by a 256-bit permute.
template <bool AnyHit>
[[gnu::always_inline]] inline bool group_test8(const TableGroup& g, const float* tx, const float* ty, const float* tz,
                                               int i, int e, int o, int n, const std::uint32_t* ids, const RayState& r,
                                               float& tmax, Result& res) {
  const __m256 xe = _mm256_sub_ps(_mm256_load_ps(tx + e), r.okx8), xo = _mm256_sub_ps(_mm256_load_ps(tx + o), r.okx8);
  const __m256 ye = _mm256_sub_ps(_mm256_load_ps(ty + e), r.oky8), yo = _mm256_sub_ps(_mm256_load_ps(ty + o), r.oky8);
  const __m256 ze = _mm256_sub_ps(_mm256_load_ps(tz + e), r.okz8), zo = _mm256_sub_ps(_mm256_load_ps(tz + o), r.okz8);
  // The slots (bit 3 picks the odd chunk; the higher bits are not read). (No lambdas: they would
  // not carry the variant's target, and returned vectors change the ABI.)
  const __m256i s0 = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(g.corner[0] + i)));
  const __m256i s1 = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(g.corner[1] + i)));
  const __m256i s2 = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(g.corner[2] + i)));
  const int live = n - i >= 8 ? 0xff : (1 << (n - i)) - 1;
  const Pairs8 h = watertight8(
      _mm256_permutex2var_ps(xe, s0, xo), _mm256_permutex2var_ps(ye, s0, yo), _mm256_permutex2var_ps(ze, s0, zo),
      _mm256_permutex2var_ps(xe, s1, xo), _mm256_permutex2var_ps(ye, s1, yo), _mm256_permutex2var_ps(ze, s1, zo),
      _mm256_permutex2var_ps(xe, s2, xo), _mm256_permutex2var_ps(ye, s2, yo), _mm256_permutex2var_ps(ze, s2, zo),
      r.sx8, r.sy8, r.sz8, live);
  return take_pairs8<AnyHit>(h, live, ids + i, r, tmax, res);
}
#endif

#if defined(PTC_TRACE_EVEX)
// One table group against the ray: the rows relative to the ray origin (the single-ray test's
// first subtraction, done per vertex, AVX-512VL: per chunk and test, instead of once per corner:
// the same values), then per test each corner row of 16 (AVX-512) or 8 (AVX-512VL) triangles by
// one permute of two pieces of the table's row by the corner slots. AVX-512: the row's two
// 512-bit halves, loaded once per group. AVX-512VL: the two 256-bit chunks of the test's pair (TableGroup::pair), loaded per
// test, and a 256-bit permute, which costs half a 512-bit one on the Zen 4 host (a branch to
// 256-bit permutes for groups of at most 16 vertices, before the chunks, made the cloth's
// primary rays 40% slower: the branch is taken about half the time). Lanes at or beyond the count
// are not live. The per-pair float operations are intersect_block's, and the closest hit is the
// smallest (t, id), so the hits are the blocks' bits.
template <bool AnyHit>
[[gnu::always_inline]] inline bool intersect_group(const TableGroup& g, const std::uint32_t* ids, const RayState& r,
                                                   float& tmax, Result& res) {
  const float* tx = g.v[0] + 8 * r.kx4;  // v[kx] (kx4 = 4 kx, a row is 32 floats)
  const float* ty = g.v[0] + 8 * r.ky4;
  const float* tz = g.v[0] + 8 * r.kz4;
  const int n = static_cast<int>(g.count);
  bool found = false;
#if defined(PTC_TRACE_AVX512)
  const __m512 okx = r.okx16, oky = r.oky16, okz = r.okz16;
  const __m512 xl = _mm512_sub_ps(_mm512_load_ps(tx), okx), xh = _mm512_sub_ps(_mm512_load_ps(tx + 16), okx);
  const __m512 yl = _mm512_sub_ps(_mm512_load_ps(ty), oky), yh = _mm512_sub_ps(_mm512_load_ps(ty + 16), oky);
  const __m512 zl = _mm512_sub_ps(_mm512_load_ps(tz), okz), zh = _mm512_sub_ps(_mm512_load_ps(tz + 16), okz);
  for (int i = 0; i < n; i += 16) {
    auto slots = [&](int c) {
      // (the maskz form: the plain one reads an undefined operand, which GCC 12 warns about)
      return _mm512_maskz_cvtepu8_epi32(0xffff, _mm_load_si128(reinterpret_cast<const __m128i*>(g.corner[c] + i)));
    };
    const __m512i s0 = slots(0), s1 = slots(1), s2 = slots(2);
    const __mmask16 live = static_cast<__mmask16>(n - i >= 16 ? 0xffffu : (1u << (n - i)) - 1u);
    const Pairs16 h = watertight16(
        _mm512_permutex2var_ps(xl, s0, xh), _mm512_permutex2var_ps(yl, s0, yh), _mm512_permutex2var_ps(zl, s0, zh),
        _mm512_permutex2var_ps(xl, s1, xh), _mm512_permutex2var_ps(yl, s1, yh), _mm512_permutex2var_ps(zl, s1, zh),
        _mm512_permutex2var_ps(xl, s2, xh), _mm512_permutex2var_ps(yl, s2, yh), _mm512_permutex2var_ps(zl, s2, zh),
        r.sx16, r.sy16, r.sz16, live);
    if (take_pairs16<AnyHit>(h, ids + i, r, tmax, res)) {
      if constexpr (AnyHit) return true;
      found = true;
    }
  }
#else
  // Test 0 reads chunks 0 and 1 in every group (TableGroup::pair[0] is 0): its loads do not wait
  // for the group's pair codes, which share a cache line with its count.
  if (group_test8<AnyHit>(g, tx, ty, tz, 0, 0, 8, n, ids, r, tmax, res)) {
    if constexpr (AnyHit) return true;
    found = true;
  }
  for (int i = 8; i < n; i += 8) {
    const std::uint8_t pair = g.pair[i / 8];
    if (group_test8<AnyHit>(g, tx, ty, tz, i, table_even_chunk(pair), table_odd_chunk(pair), n, ids, r, tmax, res)) {
      if constexpr (AnyHit) return true;
      found = true;
    }
  }
#endif
  return found;
}
#endif

struct Flat {  // raw views of TraceData for the hot loop (the 8-wide nodes: both walks read those)
  const WideNode8* nodes;
  const LeafRange* ranges;
  const TriBlock* blocks;
  const TableGroup* tables;  // LeafFormat::Tables (then `blocks` is empty)
  const std::uint32_t* ids;
  std::uint32_t root;
  bool empty;
  bool use_tables;
};

// Asks for the cache lines of what a pushed child is read from when it is popped: its 8-wide
// node (four lines: the boxes' rows, then the children), or a direct leaf's first block (the
// three lines it touches; the blocks after it follow in memory). An indirect leaf reads its
// ranges first: not prefetched. The packets' walk issues it for every child it pushes: on the
// Zen 4 host the rays took 1-4% less (docs/tracing.md, "Prefetching the pushed children in the
// packets' walk"); the hits do not change. The single-ray walk does not: there the same
// prefetches made the rays slower.
[[gnu::always_inline]] inline void prefetch_child(const Flat& d, std::uint32_t child, std::uint32_t count) {
  const char* p = nullptr;
  if (count == 0) p = reinterpret_cast<const char*>(d.nodes + child);
  else if (count & kIndirectLeaf) return;
  else if (d.use_tables) {  // a group's rows (six lines) and corner slots (two)
    p = reinterpret_cast<const char*>(d.tables + child);
    for (int k = 0; k < 8; ++k) _mm_prefetch(p + 64 * k, _MM_HINT_T0);
    return;
  } else {
    p = reinterpret_cast<const char*>(d.blocks + child);
  }
  _mm_prefetch(p, _MM_HINT_T0);
  _mm_prefetch(p + 64, _MM_HINT_T0);
  _mm_prefetch(p + 128, _MM_HINT_T0);
  if (count == 0) _mm_prefetch(p + 192, _MM_HINT_T0);
}

// The triangles of blocks [0, nb) (ids: 4 a block) against the ray, as many per test as the
// variant takes.
template <bool AnyHit>
[[gnu::always_inline]] inline bool intersect_blocks(const TriBlock* blocks, const std::uint32_t* ids, std::uint32_t nb,
                                                    RayState& r, float& tmax, Result& res) {
  std::uint32_t bk = 0;
  bool found = false;
#if defined(PTC_TRACE_AVX512)
  for (; bk + 3 < nb; bk += 4)
    if (intersect_block_quad<AnyHit>(blocks + bk, ids + 4 * std::size_t(bk), r, tmax, res)) {
      if constexpr (AnyHit) return true;
      found = true;
    }
#endif
#if defined(PTC_TRACE_AVX2)
  for (; bk + 1 < nb; bk += 2)
    if (intersect_block_pair<AnyHit>(blocks + bk, ids + 4 * std::size_t(bk), r, tmax, res)) {
      if constexpr (AnyHit) return true;
      found = true;
    }
#endif
  for (; bk < nb; ++bk)
    if (intersect_block<AnyHit>(blocks[bk], ids + 4 * std::size_t(bk), r, tmax, res)) {
      if constexpr (AnyHit) return true;
      found = true;
    }
  return found;
}

// Table group g against the ray: by permutes with AVX-512, else as blocks on the stack.
template <bool AnyHit>
[[gnu::always_inline]] inline bool intersect_table(const Flat& d, std::uint32_t g, RayState& r, float& tmax,
                                                   Result& res) {
#if defined(PTC_TRACE_EVEX)
  return intersect_group<AnyHit>(d.tables[g], d.ids + std::size_t{kTableSlots} * g, r, tmax, res);
#else
  TriBlock blk[kTableSlots / 4];
  expand_group(d.tables[g], blk);
  return intersect_blocks<AnyHit>(blk, d.ids + std::size_t{kTableSlots} * g, (d.tables[g].count + 3) / 4, r, tmax, res);
#endif
}

// Tests the triangles of one leaf child (direct: `count` triangles from block `ref`, or with
// tables from group `ref` up to the cluster's last group; indirect: the ranges ranges[ref .. ref
// + n)). Returns true for an any-hit query's hit.
template <bool AnyHit>
[[gnu::always_inline]] inline bool intersect_leaf(const Flat& d, std::uint32_t ref, std::uint32_t count, RayState& r,
                                                  float& tmax, Result& res, std::uint32_t& tris) {
  if (!r.watertight_ready) [[unlikely]] prepare_watertight(r);
  if (d.use_tables) {
    if (count & kIndirectLeaf) {
      const LeafRange* ranges = d.ranges + ref;
      const std::uint32_t nr = count & ~kIndirectLeaf;
      for (std::uint32_t i = 0; i < nr; ++i) {
        const LeafRange lr = ranges[i];
        tris += lr.triangle_count;
        for (std::uint32_t g = lr.first_block; g < lr.first_block + lr.block_count; ++g)
          if (intersect_table<AnyHit>(d, g, r, tmax, res) && AnyHit) return true;
      }
      return false;
    }
    tris += count;
    for (std::uint32_t g = ref;; ++g) {  // the cluster's groups, up to its last
      if (intersect_table<AnyHit>(d, g, r, tmax, res) && AnyHit) return true;
      if (d.tables[g].last) return false;
    }
  }
  LeafRange one{ref, (count + 3) / 4, count};
  const LeafRange* ranges = &one;
  std::uint32_t nr = 1;
  if (count & kIndirectLeaf) ranges = d.ranges + ref, nr = count & ~kIndirectLeaf;
  for (std::uint32_t i = 0; i < nr; ++i) {
    const LeafRange lr = ranges[i];
    tris += lr.triangle_count;
    if (intersect_blocks<AnyHit>(d.blocks + lr.first_block, d.ids + 4 * std::size_t(lr.first_block), lr.block_count, r,
                                 tmax, res) &&
        AnyHit)
      return true;
  }
  return false;
}

template <bool AnyHit>
[[gnu::always_inline]] inline void traverse(const Flat& d, RayState& r, Result& res, StackEntry* stack) {
  if (d.empty) return;
  // The slab constants as locals: nothing the loop stores (stack entries, results) can alias
  // them, so they stay in registers (through `r` every store forced reloads and spills). A node's
  // eight children are tested at once (AVX2 / AVX-512: one 8-lane test; SSE2: two 4-lane tests of
  // the same float operations, lane by lane), so every variant visits the same nodes in the same
  // order.
  const std::ptrdiff_t nx = r.nx, ny = r.ny, nz = r.nz, fx = r.fx, fy = r.fy, fz = r.fz;
#if defined(PTC_TRACE_AVX2)
  const __m256 ox = _mm256_broadcastss_ps(r.ox), oy = _mm256_broadcastss_ps(r.oy), oz = _mm256_broadcastss_ps(r.oz);
  const __m256 inx = _mm256_broadcastss_ps(r.inx), iny = _mm256_broadcastss_ps(r.iny), inz = _mm256_broadcastss_ps(r.inz);
  const __m256 ifx = _mm256_broadcastss_ps(r.ifx), ify = _mm256_broadcastss_ps(r.ify), ifz = _mm256_broadcastss_ps(r.ifz);
  const __m256 tmin8 = _mm256_set1_ps(r.tmin);
#else
  const __m128 ox = r.ox, oy = r.oy, oz = r.oz;
  const __m128 inx = r.inx, iny = r.iny, inz = r.inz, ifx = r.ifx, ify = r.ify, ifz = r.ifz;
  const __m128 tmin4 = _mm_set1_ps(r.tmin);
#endif
  const WideNode8* const nodes = d.nodes;
  float tmax = r.tmax;
#if defined(PTC_TRACE_AVX2)
  __m256 tmax8 = _mm256_set1_ps(tmax);
#else
  __m128 tmax4 = _mm_set1_ps(tmax);
#endif
  StackEntry* sp = stack;
  std::uint32_t ref = d.root, cnt = 0;  // the entry being visited (the root: entered at -inf)
  std::uint32_t visited = 0, tris = 0;
  // The next entry into (ref, cnt); false when the stack is empty. Closest hit skips the entries
  // whose box starts beyond the best hit found since they were pushed.
  auto pop = [&] {
    while (sp != stack) {
      --sp;
      if (AnyHit || !(sp->t > tmax)) {
        ref = sp->ref, cnt = sp->count;
        return true;
      }
    }
    return false;
  };
  do {
    bool miss = false;
    while (cnt == 0) {
      const float* b = &nodes[ref].bounds[0][0];
      ++visited;
      // A tree of two levels for the max and the min (the chain of three was the longest part of
      // a node's latency). max(a, b) returns b when either is NaN (0 * inf: an origin on a slab
      // plane of an axis the ray does not move along). The outer max's right-hand operand holds
      // the ray's own bound and is never NaN, so the result is never NaN; a NaN drops itself and
      // possibly its partner of the inner max (tny NaN drops tnx too): the interval only widens,
      // no box the ray touches is culled, and an axis-aligned ray on a slab plane may visit a box
      // its other slab would have culled.
#if defined(PTC_TRACE_AVX2)
      const __m256 tnx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + nx), ox), inx);
      const __m256 tny = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + ny), oy), iny);
      const __m256 tnz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + nz), oz), inz);
      const __m256 tfx = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + fx), ox), ifx);
      const __m256 tfy = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + fy), oy), ify);
      const __m256 tfz = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(b + fz), oz), ifz);
      const __m256 tn = _mm256_max_ps(_mm256_max_ps(tnx, tny), _mm256_max_ps(tnz, tmin8));
      const __m256 tf = _mm256_min_ps(_mm256_min_ps(tfx, tfy), _mm256_min_ps(tfz, tmax8));
      unsigned mask = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(tn, tf, _CMP_LE_OQ)));
#else
      auto half = [&](int h, __m128& tn) {
        const float* bh = b + 4 * h;
        const __m128 tnx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(bh + nx), ox), inx);
        const __m128 tny = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(bh + ny), oy), iny);
        const __m128 tnz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(bh + nz), oz), inz);
        const __m128 tfx = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(bh + fx), ox), ifx);
        const __m128 tfy = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(bh + fy), oy), ify);
        const __m128 tfz = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(bh + fz), oz), ifz);
        tn = _mm_max_ps(_mm_max_ps(tnx, tny), _mm_max_ps(tnz, tmin4));
        const __m128 tf = _mm_min_ps(_mm_min_ps(tfx, tfy), _mm_min_ps(tfz, tmax4));
        return static_cast<unsigned>(_mm_movemask_ps(_mm_cmple_ps(tn, tf)));
      };
      __m128 tn_lo, tn_hi;
      unsigned mask = half(0, tn_lo) | half(1, tn_hi) << 4;
#endif
      if (!mask) {
        miss = true;
        break;
      }
      const WideNode8& n = nodes[ref];
      const int i0 = ctz(mask);
      mask &= mask - 1;
      if (!mask) {
        ref = n.child[i0], cnt = n.count[i0];
        continue;
      }
      if constexpr (AnyHit) {
        // Any hit visits every entered child until a hit ends the walk; the pop ignores entry
        // distances, so none are stored: the lowest entered slot is visited first, the others
        // pushed in slot order (so popped from the highest down). Shadow rays to a point light
        // mostly reach it (97% on the twist view), when the order does not matter; the
        // distances' round trip through memory and the two-child compare did (docs/tracing.md).
        for (unsigned mm = mask; mm; mm &= mm - 1) {
          const int i = ctz(mm);
          *sp++ = {n.child[i], n.count[i], 0.0f};
        }
        ref = n.child[i0], cnt = n.count[i0];
        continue;
      }
      alignas(32) float dist[8];
#if defined(PTC_TRACE_AVX2)
      _mm256_store_ps(dist, tn);
#else
      _mm_store_ps(dist, tn_lo);
      _mm_store_ps(dist + 4, tn_hi);
#endif
      const int i1 = ctz(mask);
      mask &= mask - 1;
      if (!mask) {
        const bool first_near = dist[i0] <= dist[i1];
        const int nearer = first_near ? i0 : i1, farther = first_near ? i1 : i0;
        *sp++ = {n.child[farther], n.count[farther], dist[farther]};
        ref = n.child[nearer], cnt = n.count[nearer];
        continue;
      }
      // Three or more children: sorted by entry distance in place on the stack, farthest
      // deepest, and the nearest (the last) taken off again. Sorting a local array and copying
      // it onto the stack compiled to `rep movsq` (a variable-length copy), whose start-up cost
      // was a tenth of the walk's samples on the twist. The stack has room for eight entries at
      // any node (stack_size: at most seven pushed per level, plus eight).
      StackEntry* const c = sp;
      int k = 0;
      c[k++] = {n.child[i0], n.count[i0], dist[i0]};
      c[k++] = {n.child[i1], n.count[i1], dist[i1]};
      for (; mask; mask &= mask - 1) {
        const int i = ctz(mask);
        c[k++] = {n.child[i], n.count[i], dist[i]};
      }
      for (int i = 1; i < k; ++i)  // insertion sort, descending distance
        for (int j = i; j > 0 && c[j - 1].t < c[j].t; --j) std::swap(c[j - 1], c[j]);
      sp += k - 1;
      ref = c[k - 1].ref, cnt = c[k - 1].count;
    }
    if (!miss) {
      const float before = tmax;
      if (intersect_leaf<AnyHit>(d, ref, cnt, r, tmax, res, tris)) break;  // any hit: done
#if defined(PTC_TRACE_AVX2)
      if (tmax != before) tmax8 = _mm256_set1_ps(tmax);
#else
      if (tmax != before) tmax4 = _mm_set1_ps(tmax);
#endif
    }
  } while (pop());
  res.nodes = visited, res.tris = tris;
}

Flat flat_of(const TraceData& s) {
  return {s.wide8.nodes.data(), s.ranges.data(), s.blocks.data(), s.tables.data(), s.triangle_ids.data(), s.wide8.root,
          s.wide8.nodes.empty(), s.format == LeafFormat::Tables};
}

std::size_t stack_size(const TraceData& s) { return 7 * std::size_t(s.wide8.depth) + 8; }

// The walk of one set-up ray, closest or any hit.
template <bool AnyHit>
[[gnu::noinline]] void traverse_one(const Flat& f, RayState& r, Result& res, StackEntry* stack) {
  traverse<AnyHit>(f, r, res, stack);
}
inline void walk(const Flat& f, RayState& r, Result& res, HitMode mode, StackEntry* stack) {
  if (mode == HitMode::Closest)
    traverse_one<false>(f, r, res, stack);
  else
    traverse_one<true>(f, r, res, stack);
}

Result trace_single(const TraceData& s, const Flat& f, const Vec3& org, const Vec3f& dir, float tmin, float tmax,
                    HitMode mode, StackEntry* stack) {
  Result res;
  RayState r;
  // The ray in the trace frame (box.h, FrameMap): origin (org - origin) * scale, direction
  // dir * scale (exact: a power of two), so t is the caller's.
  const float sc = static_cast<float>(s.scale);
  if (!setup(r, to_frame(org, s.frame()), {dir[0] * sc, dir[1] * sc, dir[2] * sc}, tmin, tmax)) return res;
  walk(f, r, res, mode, stack);
  return res;
}

// One ray's result into the batch (a miss: t = 0, as u and v) and the totals.
inline void store_result(HitBatch& hits, std::size_t i, const Result& res, bool counters, TraceTotals& tot) {
  const bool hit = res.tri != kNoTriangle;
  hits.t[i] = hit ? res.t : 0.0f, hits.u[i] = res.u, hits.v[i] = res.v, hits.triangle[i] = res.tri;
  if (counters) hits.nodes_visited[i] = res.nodes, hits.triangles_tested[i] = res.tris;
  tot.rays += 1;
  tot.hits += hit;
  tot.nodes_visited += res.nodes;
  tot.triangles_tested += res.tris;
}

// A stack on the C++ stack for the usual depths, on the heap for degenerate trees.
struct Stack {
  StackEntry local[512];
  std::vector<StackEntry> heap;
  StackEntry* get(std::size_t n) {
    if (n <= 512) return local;
    heap.resize(n);
    return heap.data();
  }
};

#if defined(PTC_TRACE_AVX2)
// setup() for eight consecutive rays of a batch at once: the origins into the trace frame (double
// subtraction and product, rounded to float), the directions times the frame's scale, their
// reciprocals and the slab constants, and setup()'s checks, each the same IEEE operation as the
// per-ray code (trace_single and setup), so the same bits and the same rays refused.
struct Setup8 {
  alignas(32) float o[3][8], d[3][8], in[3][8], fa[3][8], tmin[8], tmax[8];
  unsigned valid = 0;  // bit l: ray l passes setup()'s checks
  unsigned neg[3] = {0, 0, 0};  // bit l: ray l's reciprocal on that axis is negative
};

inline void setup8(Setup8& s, const RayBatch& rays, std::size_t i0, const FrameMap& fm) {
  const __m256d sc2 = _mm256_set1_pd(fm.scale);
  const __m256 sc = _mm256_set1_ps(static_cast<float>(fm.scale));
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity()), zero = _mm256_setzero_ps();
  auto finite = [&](__m256 x) { return _mm256_cmp_ps(_mm256_and_ps(x, abs_mask), inf, _CMP_LT_OQ); };
  const double* org[3] = {rays.ox.data() + i0, rays.oy.data() + i0, rays.oz.data() + i0};
  const float* dir[3] = {rays.dx.data() + i0, rays.dy.data() + i0, rays.dz.data() + i0};
  __m256 ok = _mm256_castsi256_ps(_mm256_set1_epi32(-1)), nonzero = zero;
  for (int a = 0; a < 3; ++a) {
    const __m256d origin = _mm256_set1_pd(fm.origin[a]);
    const __m128 lo = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(org[a]), origin), sc2));
    const __m128 hi = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(org[a] + 4), origin), sc2));
    const __m256 o = _mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1);
    const __m256 d = _mm256_mul_ps(_mm256_loadu_ps(dir[a]), sc);
    const __m256 inv = _mm256_div_ps(_mm256_set1_ps(1.0f), d);  // +-inf for a zero component
    _mm256_store_ps(s.o[a], o);
    _mm256_store_ps(s.d[a], d);
    _mm256_store_ps(s.in[a], _mm256_mul_ps(inv, _mm256_set1_ps(kNearScale)));
    _mm256_store_ps(s.fa[a], _mm256_mul_ps(inv, _mm256_set1_ps(kFarScale)));
    s.neg[a] = static_cast<unsigned>(_mm256_movemask_ps(inv));
    ok = _mm256_and_ps(ok, _mm256_and_ps(finite(d), finite(o)));
    nonzero = _mm256_or_ps(nonzero, _mm256_cmp_ps(d, zero, _CMP_NEQ_OQ));
  }
  const __m256 t0 = _mm256_loadu_ps(rays.tmin.data() + i0), t1 = _mm256_loadu_ps(rays.tmax.data() + i0);
  const __m256 big = _mm256_set1_ps(kBig);
  const __m256 t1c = _mm256_blendv_ps(big, t1, _mm256_cmp_ps(t1, big, _CMP_LT_OQ));  // tmax < kBig ? tmax : kBig
  _mm256_store_ps(s.tmin, t0);
  _mm256_store_ps(s.tmax, t1c);
  ok = _mm256_and_ps(ok, _mm256_and_ps(nonzero, _mm256_cmp_ps(t0, t1c, _CMP_LT_OQ)));
  ok = _mm256_and_ps(ok, _mm256_cmp_ps(t0, zero, _CMP_GE_OQ));
  s.valid = static_cast<unsigned>(_mm256_movemask_ps(ok));
}

// Ray l of `s` into `r`: what setup() makes of it.
inline void state_of(RayState& r, const Setup8& s, int l) {
  const float in[3] = {s.in[0][l], s.in[1][l], s.in[2][l]}, fa[3] = {s.fa[0][l], s.fa[1][l], s.fa[2][l]};
  const bool neg[3] = {(s.neg[0] >> l & 1) != 0, (s.neg[1] >> l & 1) != 0, (s.neg[2] >> l & 1) != 0};
  fill_state(r, {s.o[0][l], s.o[1][l], s.o[2][l]}, {s.d[0][l], s.d[1][l], s.d[2][l]}, in, fa, neg, s.tmin[l], s.tmax[l]);
}
#endif

#if defined(PTC_TRACE_AVX2)
// The eight rays of a set-up, each walking the tree alone, in one function. The closest-hit walk
// is inlined, so its prologue (the stack's alignment, the saved registers) is paid once for eight
// rays (twist primary single rays 2-3% faster); the any-hit walk inlined the same way was 2%
// slower on the twist's shadow rays, so it keeps its call per ray (traverse_one).
template <bool AnyHit>
[[gnu::noinline]] void walk8(const Flat& f, const Setup8& s, HitBatch& hits, std::size_t first, bool counters,
                             TraceTotals& tot, StackEntry* stack) {
  for (int l = 0; l < 8; ++l) {
    Result res;
    if (s.valid >> l & 1) {
      RayState r;
      state_of(r, s, l);
      if constexpr (AnyHit)
        traverse_one<true>(f, r, res, stack);
      else
        traverse<false>(f, r, res, stack);
    }
    store_result(hits, first + l, res, counters, tot);
  }
}
#endif

void trace_range_impl(const TraceData& scene, const RayBatch& rays, HitBatch& hits, std::size_t begin,
                      std::size_t end, HitMode mode, bool counters, TraceTotals& tot) {
  const Flat f = flat_of(scene);
  Stack st;
  StackEntry* stack = st.get(stack_size(scene));
#if defined(PTC_TRACE_AVX2)
  // Eight rays' set-up at once (setup8), then each ray walks the tree alone.
  {
    const FrameMap fm = scene.frame();
    Setup8 s;
    for (; begin + 8 <= end; begin += 8) {
      setup8(s, rays, begin, fm);
      if (mode == HitMode::Closest)
        walk8<false>(f, s, hits, begin, counters, tot, stack);
      else
        walk8<true>(f, s, hits, begin, counters, tot, stack);
    }
  }
#endif
  for (std::size_t i = begin; i < end; ++i) {
    store_result(hits, i,
                 trace_single(scene, f, Vec3(rays.ox[i], rays.oy[i], rays.oz[i]), {rays.dx[i], rays.dy[i], rays.dz[i]},
                              rays.tmin[i], rays.tmax[i], mode, stack),
                 counters, tot);
  }
}

Hit trace_one_impl(const TraceData& scene, const Vec3& org, const Vec3f& dir, HitMode mode, float tmin, float tmax) {
  Stack st;
  const Result r = trace_single(scene, flat_of(scene), org, dir, tmin, tmax, mode, st.get(stack_size(scene)));
  return {r.tri == kNoTriangle ? 0.0f : r.t, r.u, r.v, r.tri, r.nodes, r.tris};
}

}  // namespace
}  // namespace ptc::bvh::detail::PTC_TRACE_NS

// The variant's entry points, named after it (detail::trace_range_sse2, ..._avx2; tracer_isa.h).
#define PTC_TRACE_CAT2(a, b) a##b
#define PTC_TRACE_CAT(a, b) PTC_TRACE_CAT2(a, b)
namespace ptc::bvh::detail {
void PTC_TRACE_CAT(trace_range_, PTC_TRACE_NS)(const TraceData& s, const RayBatch& r, HitBatch& h, std::size_t b,
                                               std::size_t e, HitMode m, bool c, TraceTotals& t) {
  PTC_TRACE_NS::trace_range_impl(s, r, h, b, e, m, c, t);
}
Hit PTC_TRACE_CAT(trace_one_, PTC_TRACE_NS)(const TraceData& s, const Vec3& o, const Vec3f& d, HitMode m, float t0,
                                            float t1) {
  return PTC_TRACE_NS::trace_one_impl(s, o, d, m, t0, t1);
}
}  // namespace ptc::bvh::detail
