// What the single-ray leaf test (eight triangles against one ray, the AVX2 pair test of
// bvh/tracer_kernel.h) costs when its nine corner rows come from per-group vertex tables instead
// of today's blocks (docs/tracing.md, "Vertex tables on AVX-512VL"). A probe, not part of the
// build; compile it once per instruction set and run both on the same inputs (a binary PLY of
// double positions from `ptc subdivide`, `triangles.csv` from `ptc cluster`):
//     g++ -O2 -ffp-contract=off -mavx2 bench/scale/leaf_test_probe.cpp -o /tmp/ltp_avx2
//     g++ -O2 -ffp-contract=off -mavx2 -mavx512f -mavx512vl -mavx512bw -mavx512dq
//         -mprefer-vector-width=256 bench/scale/leaf_test_probe.cpp -o /tmp/ltp_vl
//     /tmp/ltp_avx2 a2.ply D/triangles.csv; /tmp/ltp_vl a2.ply D/triangles.csv
// Groups as in leaf_tables_probe.cpp (each cluster's triangles greedily into groups of at most 16
// triangles on at most 16 distinct vertices). Per group, both layouts hold the same 16 triangle
// slots (unused slots: NaN corners):
//   blocks: four blocks of v[corner][axis][lane] (576 bytes), the rows of a pair test taken as
//           two 16-byte loads and an insert each (as the scene's blocks);
//   tables: x[16] y[16] z[16] (192 bytes, written per frame) and one byte per corner and slot
//           (48 bytes, fixed); a pair test's row is one vpermt2ps of the table's two halves
//           with AVX-512VL, two vpermps and a blend with AVX2.
// One ray per group, aimed at the centroid of one of its triangles from a random direction;
// both layouts run the same watertight arithmetic (tracer_kernel.h's watertight8, without the
// double-precision redo of zero edge functions), two pair tests a group, and the two results
// are checked to agree. The groups are visited in memory order, in a shuffled order, and the
// first 1024 of them over and over (in the caches: the arithmetic alone); the medians of 15
// passes, ns a pair test.
#include <immintrin.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "probe_input.h"

namespace {
using u32 = std::uint32_t;
double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
struct alignas(64) Table { float v[3][16]; };
struct alignas(16) Block { float v[3][3][4]; };
struct alignas(16) Idx { std::uint8_t c[3][16]; };  // corner c of slot s: table entry c[c][s]
struct alignas(32) Ray {                               // the watertight constants (make_watertight_ray)
  float ok[3], s[3];
  int k[3];
};

// tracer_kernel.h's watertight8, without the double redo: the hit lanes (inside, det != 0).
inline int watertight8(__m256 a_x, __m256 a_y, __m256 a_z, __m256 b_x, __m256 b_y, __m256 b_z, __m256 c_x, __m256 c_y,
                       __m256 c_z, __m256 sx, __m256 sy, __m256 sz, __m256& t) {
  const __m256 ax = _mm256_sub_ps(a_x, _mm256_mul_ps(sx, a_z)), ay = _mm256_sub_ps(a_y, _mm256_mul_ps(sy, a_z));
  const __m256 bx = _mm256_sub_ps(b_x, _mm256_mul_ps(sx, b_z)), by = _mm256_sub_ps(b_y, _mm256_mul_ps(sy, b_z));
  const __m256 cx = _mm256_sub_ps(c_x, _mm256_mul_ps(sx, c_z)), cy = _mm256_sub_ps(c_y, _mm256_mul_ps(sy, c_z));
  const __m256 U = _mm256_sub_ps(_mm256_mul_ps(cx, by), _mm256_mul_ps(cy, bx));
  const __m256 V = _mm256_sub_ps(_mm256_mul_ps(ax, cy), _mm256_mul_ps(ay, cx));
  const __m256 W = _mm256_sub_ps(_mm256_mul_ps(bx, ay), _mm256_mul_ps(by, ax));
  const __m256 zero = _mm256_setzero_ps();
  const __m256 neg = _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_LT_OQ), _mm256_cmp_ps(V, zero, _CMP_LT_OQ)),
                                  _mm256_cmp_ps(W, zero, _CMP_LT_OQ));
  const __m256 pos = _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(U, zero, _CMP_GT_OQ), _mm256_cmp_ps(V, zero, _CMP_GT_OQ)),
                                  _mm256_cmp_ps(W, zero, _CMP_GT_OQ));
  const __m256 det = _mm256_add_ps(_mm256_add_ps(U, V), W);
  const __m256 det_ok = _mm256_or_ps(_mm256_cmp_ps(det, zero, _CMP_LT_OQ), _mm256_cmp_ps(det, zero, _CMP_GT_OQ));
  const __m256 valid = _mm256_andnot_ps(_mm256_and_ps(neg, pos), det_ok);
  const int m = _mm256_movemask_ps(valid);
  if (!m) return 0;
  const __m256 az = _mm256_mul_ps(sz, a_z), bz = _mm256_mul_ps(sz, b_z), cz = _mm256_mul_ps(sz, c_z);
  t = _mm256_div_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(U, az), _mm256_mul_ps(V, bz)), _mm256_mul_ps(W, cz)), det);
  return m;
}

struct Consts {
  __m256 okx, oky, okz, sx, sy, sz;
  int kx4, ky4, kz4, kx, ky, kz;
};
inline Consts consts_of(const Ray& r) {
  return {_mm256_set1_ps(r.ok[0]), _mm256_set1_ps(r.ok[1]), _mm256_set1_ps(r.ok[2]), _mm256_set1_ps(r.s[0]),
          _mm256_set1_ps(r.s[1]), _mm256_set1_ps(r.s[2]), 4 * r.k[0], 4 * r.k[1], 4 * r.k[2], r.k[0], r.k[1], r.k[2]};
}

// Blocks b[0], b[1] (eight slots) against the ray: the hit mask, t summed into acc.
inline int pair_blocks(const Block* b, const Consts& c, __m256& acc) {
  const float* v0 = &b[0].v[0][0][0];
  const float* v1 = &b[1].v[0][0][0];
  auto ld = [&](int off) {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(v0 + off)), _mm_load_ps(v1 + off), 1);
  };
  __m256 t = _mm256_setzero_ps();
  const int m = watertight8(_mm256_sub_ps(ld(c.kx4), c.okx), _mm256_sub_ps(ld(c.ky4), c.oky), _mm256_sub_ps(ld(c.kz4), c.okz),
                            _mm256_sub_ps(ld(12 + c.kx4), c.okx), _mm256_sub_ps(ld(12 + c.ky4), c.oky),
                            _mm256_sub_ps(ld(12 + c.kz4), c.okz), _mm256_sub_ps(ld(24 + c.kx4), c.okx),
                            _mm256_sub_ps(ld(24 + c.ky4), c.oky), _mm256_sub_ps(ld(24 + c.kz4), c.okz), c.sx, c.sy, c.sz, t);
  if (m) acc = _mm256_add_ps(acc, _mm256_and_ps(t, _mm256_cmp_ps(t, t, _CMP_ORD_Q)));
  return m;
}

// Slots [8h, 8h + 8) of a table against the ray.
inline int pair_table(const Table& tb, const Idx& ix, int h, const Consts& c, __m256& acc) {
  const __m256 xl = _mm256_load_ps(tb.v[c.kx]), xh = _mm256_load_ps(tb.v[c.kx] + 8);
  const __m256 yl = _mm256_load_ps(tb.v[c.ky]), yh = _mm256_load_ps(tb.v[c.ky] + 8);
  const __m256 zl = _mm256_load_ps(tb.v[c.kz]), zh = _mm256_load_ps(tb.v[c.kz] + 8);
  __m256i i[3];
  for (int k = 0; k < 3; ++k)
    i[k] = _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(ix.c[k] + 8 * h)));
#if defined(__AVX512VL__)
  auto row = [&](__m256 lo, __m256 hi, __m256i j) { return _mm256_permutex2var_ps(lo, j, hi); };
#else
  __m256 sel[3];
  for (int k = 0; k < 3; ++k) sel[k] = _mm256_castsi256_ps(_mm256_slli_epi32(i[k], 28));  // bit 3 -> sign
  auto row = [&](__m256 lo, __m256 hi, int k) {
    return _mm256_blendv_ps(_mm256_permutevar8x32_ps(lo, i[k]), _mm256_permutevar8x32_ps(hi, i[k]), sel[k]);
  };
#endif
#if defined(__AVX512VL__)
#define ROW(lo, hi, k) row(lo, hi, i[k])
#else
#define ROW(lo, hi, k) row(lo, hi, k)
#endif
  __m256 t = _mm256_setzero_ps();
  const int m = watertight8(_mm256_sub_ps(ROW(xl, xh, 0), c.okx), _mm256_sub_ps(ROW(yl, yh, 0), c.oky),
                            _mm256_sub_ps(ROW(zl, zh, 0), c.okz), _mm256_sub_ps(ROW(xl, xh, 1), c.okx),
                            _mm256_sub_ps(ROW(yl, yh, 1), c.oky), _mm256_sub_ps(ROW(zl, zh, 1), c.okz),
                            _mm256_sub_ps(ROW(xl, xh, 2), c.okx), _mm256_sub_ps(ROW(yl, yh, 2), c.oky),
                            _mm256_sub_ps(ROW(zl, zh, 2), c.okz), c.sx, c.sy, c.sz, t);
#undef ROW
  if (m) acc = _mm256_add_ps(acc, _mm256_and_ps(t, _mm256_cmp_ps(t, t, _CMP_ORD_Q)));
  return m;
}
}  // namespace

int main(int argc, char** argv) {
  probe::Input input = probe::read_input(argc, argv);
  const std::size_t V = input.V, T = input.T;
  const std::vector<double>& P = input.P;
  std::vector<u32>& tri = input.tri;
  const u32 C = input.C;
  const std::vector<std::vector<u32>>& cl = input.clusters;
  // Float positions (centred, as the trace frame).
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t v = 0; v < V; ++v)
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], P[3 * v + a]), hi[a] = std::max(hi[a], P[3 * v + a]);
  std::vector<float> fp(3 * V);
  for (std::size_t v = 0; v < V; ++v)
    for (int a = 0; a < 3; ++a) fp[3 * v + a] = static_cast<float>(P[3 * v + a] - 0.5 * (lo[a] + hi[a]));

  // Groups: at most 16 triangles and 16 distinct vertices (as leaf_tables_probe.cpp).
  std::vector<Table> tables;
  std::vector<Idx> idx;
  std::vector<Block> blocks;
  std::vector<u32> first_tri;  // a triangle of each group (the ray's target)
  const float nan = std::nanf("");
  for (u32 c = 0; c < C; ++c) {
    for (const probe::Group& gr : probe::greedy_groups(cl[c], tri)) {
      const std::vector<u32>&vs = gr.verts, &ts = gr.tris;
      auto slot = [&](u32 v) { return static_cast<int>(std::find(vs.begin(), vs.end(), v) - vs.begin()); };
      Table tb;
      for (int e = 0; e < 16; ++e)
        for (int a = 0; a < 3; ++a) tb.v[a][e] = e < static_cast<int>(vs.size()) ? fp[3 * vs[e] + a] : nan;
      Idx ix;
      Block bl[4];
      for (int sl = 0; sl < 16; ++sl)
        for (int k = 0; k < 3; ++k) {
          const int e = sl < static_cast<int>(ts.size()) ? slot(tri[3 * ts[sl] + k]) : 15;
          ix.c[k][sl] = static_cast<std::uint8_t>(sl < static_cast<int>(ts.size()) ? e : (vs.size() < 16 ? 15 : 0));
          for (int a = 0; a < 3; ++a)
            bl[sl / 4].v[k][a][sl % 4] = sl < static_cast<int>(ts.size()) ? fp[3 * tri[3 * ts[sl] + k] + a] : nan;
        }
      if (ts.size() < 16 && vs.size() == 16)  // no NaN entry to point the unused slots at
        for (int sl = static_cast<int>(ts.size()); sl < 16; ++sl) ix.c[0][sl] = ix.c[1][sl] = ix.c[2][sl] = 0;
      tables.push_back(tb), idx.push_back(ix);
      for (const Block& b : bl) blocks.push_back(b);
      first_tri.push_back(ts[0]);
    }
  }
  const std::size_t G = tables.size();
  // One ray a group, at the centroid of its first triangle from a random direction.
  std::mt19937 rng(7);
  std::normal_distribution<float> N(0.0f, 1.0f);
  std::vector<Ray> rays(G);
  for (std::size_t g = 0; g < G; ++g) {
    float ctr[3], d[3];
    for (int a = 0; a < 3; ++a)
      ctr[a] = (fp[3 * tri[3 * first_tri[g]] + a] + fp[3 * tri[3 * first_tri[g] + 1] + a] + fp[3 * tri[3 * first_tri[g] + 2] + a]) / 3.0f;
    for (float& x : d) x = N(rng);
    float o[3];
    for (int a = 0; a < 3; ++a) o[a] = ctr[a] - 2.0f * d[a];
    int kz = 0;
    for (int a = 1; a < 3; ++a)
      if (std::fabs(d[a]) > std::fabs(d[kz])) kz = a;
    int kx = kz == 2 ? 0 : kz + 1, ky = kx == 2 ? 0 : kx + 1;
    if (d[kz] < 0) std::swap(kx, ky);
    Ray& r = rays[g];
    r.k[0] = kx, r.k[1] = ky, r.k[2] = kz;
    r.ok[0] = o[kx], r.ok[1] = o[ky], r.ok[2] = o[kz];
    r.s[0] = d[kx] / d[kz], r.s[1] = d[ky] / d[kz], r.s[2] = 1.0f / d[kz];
  }
  std::vector<u32> order(G);
  for (std::size_t g = 0; g < G; ++g) order[g] = static_cast<u32>(g);
  std::vector<u32> shuffled = order;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  std::vector<u32> hot(G);  // the first 1024 groups over and over (in the caches: the arithmetic alone)
  for (std::size_t g = 0; g < G; ++g) hot[g] = static_cast<u32>(g % std::min<std::size_t>(G, 1024));
  std::printf("%zu groups (%.2f triangles a group): tables %.1f MB + indices %.1f MB, blocks %.1f MB; %s\n", G,
              double(T) / double(G), G * sizeof(Table) / 1e6, G * sizeof(Idx) / 1e6, blocks.size() * sizeof(Block) / 1e6,
#if defined(__AVX512VL__)
              "AVX-512VL (vpermt2ps)"
#else
              "AVX2 (two vpermps and a blend)"
#endif
  );
  long hits_b = 0, hits_t = 0;
  for (const auto* ord : {&order, &shuffled, &hot}) {
    std::vector<double> tb_ms, tt_ms;
    for (int pass = 0; pass < 15; ++pass) {
      __m256 acc = _mm256_setzero_ps();
      long hb = 0, ht = 0;
      double t0 = now_ms();
      for (u32 g : *ord) {
        const Consts c = consts_of(rays[g]);
        hb += __builtin_popcount(pair_blocks(&blocks[4 * std::size_t(g)], c, acc));
        hb += __builtin_popcount(pair_blocks(&blocks[4 * std::size_t(g) + 2], c, acc));
      }
      tb_ms.push_back(now_ms() - t0);
      t0 = now_ms();
      for (u32 g : *ord) {
        const Consts c = consts_of(rays[g]);
        ht += __builtin_popcount(pair_table(tables[g], idx[g], 0, c, acc));
        ht += __builtin_popcount(pair_table(tables[g], idx[g], 1, c, acc));
      }
      tt_ms.push_back(now_ms() - t0);
      alignas(32) float sink[8];
      _mm256_store_ps(sink, acc);
      if (sink[0] == 12345.0f) std::printf(" ");
      hits_b = hb, hits_t = ht;
    }
    std::sort(tb_ms.begin(), tb_ms.end());
    std::sort(tt_ms.begin(), tt_ms.end());
    const double pairs = 2.0 * double(G);
    std::printf("%s order: blocks %.2f ns a pair test [%.2f, %.2f], tables %.2f [%.2f, %.2f]; hits %ld / %ld%s\n",
                ord == &order ? "memory" : ord == &shuffled ? "shuffled" : "cached (1024 groups)", 1e6 * tb_ms[7] / pairs, 1e6 * tb_ms[0] / pairs,
                1e6 * tb_ms[14] / pairs, 1e6 * tt_ms[7] / pairs, 1e6 * tt_ms[0] / pairs, 1e6 * tt_ms[14] / pairs, hits_b,
                hits_t, hits_b == hits_t ? "" : "  MISMATCH");
  }
  return hits_b == hits_t ? 0 : 1;
}
