// What the per-frame vertex data of the cluster BVH would cost in a leaf format of vertex tables
// (docs/tracing.md, "The floor of the per-frame update on one thread"). A probe, not part of the
// build: it needs AVX-512 and reads only what ptc writes (a binary little-endian PLY of double
// positions from `ptc subdivide`, `triangles.csv` from `ptc cluster`):
//     g++ -O2 -march=native bench/scale/leaf_tables_probe.cpp -o /tmp/leaf_tables_probe
//     /tmp/leaf_tables_probe a2.ply D/triangles.csv
// Each cluster's triangles go greedily into groups of at most 16 triangles using at most 16
// distinct vertices (the triangle adding the fewest new vertices first). Vertices are renumbered
// in first-touch order over the groups (as the scene's cluster vertex order does). Per frame
// (positions scaled a little, so that every frame writes new values), one thread, ms:
//   today:   conversion to floats and cluster boxes over each cluster's vertex list, then the
//            blocks of four triangles from corner indices (16-byte loads, transposes, streaming
//            stores), as ClusterScene does;
//   tables:  the conversion (AVX-512, in input order), then each group's table x[16] y[16]
//            z[16] by 16-byte loads and transposes, cluster boxes from the same loads; streaming
//            or ordinary stores;
//   direct:  the tables straight from the double positions (256-bit loads, no float copy);
//   gather:  the tables with AVX-512 gathers of the doubles.
// Prints each variant's median over frames 2..11 and its range.
#include <immintrin.h>
#include <sys/mman.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "probe_input.h"

namespace {
using u32 = std::uint32_t;
double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
template <class T>
T* huge_alloc(std::size_t n) {  // 2 MiB-aligned, transparent huge pages (as bvh/aligned.h)
  const std::size_t bytes = ((n * sizeof(T) + (2u << 20) - 1) / (2u << 20)) * (2u << 20);
  void* p = std::aligned_alloc(2u << 20, bytes);
  madvise(p, bytes, MADV_HUGEPAGE);
  return static_cast<T*>(p);
}
struct alignas(64) Table { float v[3][16]; };
struct alignas(16) Block { float v[3][3][4]; };
}  // namespace

int main(int argc, char** argv) {
  probe::Input input = probe::read_input(argc, argv);
  const std::size_t V = input.V, T = input.T;
  const std::vector<double>& P = input.P;
  std::vector<u32>& tri = input.tri;
  const u32 C = input.C;
  const std::vector<std::vector<u32>>& cl = input.clusters;

  // Groups: at most 16 triangles and 16 distinct vertices; unused slots repeat the first vertex.
  std::vector<u32> gverts, coff{0};
  std::size_t G = 0, slots_used = 0;
  for (u32 c = 0; c < C; ++c) {
    for (probe::Group& gr : probe::greedy_groups(cl[c], tri)) {
      std::vector<u32>& vs = gr.verts;
      slots_used += vs.size();
      vs.resize(16, vs[0]);
      gverts.insert(gverts.end(), vs.begin(), vs.end());
      ++G;
    }
    coff.push_back(static_cast<u32>(G));
  }
  std::vector<u32> to_new(V, ~0u);
  u32 next = 0;
  for (u32 x : gverts)
    if (to_new[x] == ~0u) to_new[x] = next++;
  for (std::size_t v = 0; v < V; ++v)
    if (to_new[v] == ~0u) to_new[v] = next++;  // (vertices of no triangle)
  std::vector<double> Q(3 * V);
  for (std::size_t v = 0; v < V; ++v)
    for (int a = 0; a < 3; ++a) Q[3 * to_new[v] + a] = P[3 * v + a];
  for (u32& x : gverts) x = to_new[x];
  for (u32& x : tri) x = to_new[x];
  // Today's layout: blocks of four triangles per cluster, corner indices per block; vertex lists.
  std::vector<u32> corners, cv, cvoff{0};
  std::size_t nb = 0;
  for (u32 c = 0; c < C; ++c) {
    const auto& ts = cl[c];
    for (std::size_t i = 0; i < ts.size(); i += 4, ++nb)
      for (int k = 0; k < 3; ++k)
        for (std::size_t l = 0; l < 4; ++l) corners.push_back(tri[3 * ts[i + l < ts.size() ? i + l : i] + k]);
    std::vector<u32> vs;
    for (u32 t : ts)
      for (int k = 0; k < 3; ++k) vs.push_back(tri[3 * t + k]);
    std::sort(vs.begin(), vs.end());
    vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
    cv.insert(cv.end(), vs.begin(), vs.end());
    cvoff.push_back(static_cast<u32>(cv.size()));
  }
  std::printf("%zu triangles, %zu vertices, %u clusters: %zu groups, %.2f triangles and %.2f vertices a group; "
              "tables %.1f MB a frame, blocks %.1f MB\n",
              T, V, C, G, double(T) / double(G), double(slots_used) / double(G), G * sizeof(Table) / 1e6,
              nb * sizeof(Block) / 1e6);

  double* in = huge_alloc<double>(3 * V);
  float* fpos = huge_alloc<float>(3 * V + 8);
  Block* blocks = huge_alloc<Block>(nb);
  Table* tables = huge_alloc<Table>(G);
  float* boxes = huge_alloc<float>(6 * C);
  const double ox = 0.1, oy = 0.2, oz = 0.3, sc = 0.5;
  auto box_out = [&](u32 c, __m128 lo, __m128 hi) {
    alignas(16) float l[4], h[4];
    _mm_store_ps(l, lo), _mm_store_ps(h, hi);
    for (int a = 0; a < 3; ++a) boxes[6 * c + a] = l[a], boxes[6 * c + 3 + a] = h[a];
  };
  auto convert = [&] {  // AoS doubles -> AoS floats in the trace frame, 8 values at a time
    const __m512d s8 = _mm512_set1_pd(sc);
    const __m512d o0 = _mm512_setr_pd(ox, oy, oz, ox, oy, oz, ox, oy), o1 = _mm512_setr_pd(oz, ox, oy, oz, ox, oy, oz, ox),
                  o2 = _mm512_setr_pd(oy, oz, ox, oy, oz, ox, oy, oz);
    const std::size_t n = 3 * V;
    std::size_t i = 0;
    for (; i + 24 <= n; i += 24) {
      _mm256_storeu_ps(fpos + i, _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_sub_pd(_mm512_loadu_pd(in + i), o0), s8)));
      _mm256_storeu_ps(fpos + i + 8, _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_sub_pd(_mm512_loadu_pd(in + i + 8), o1), s8)));
      _mm256_storeu_ps(fpos + i + 16, _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_sub_pd(_mm512_loadu_pd(in + i + 16), o2), s8)));
    }
    for (; i < n; ++i) fpos[i] = static_cast<float>((in[i] - (i % 3 == 0 ? ox : i % 3 == 1 ? oy : oz)) * sc);
  };
  // Four rows (x y z w) -> the table's x, y, z at slots 4q..4q+3, and the box.
  auto put4 = [&](Table& tb, int q, __m128 r0, __m128 r1, __m128 r2, __m128 r3, __m128& lo, __m128& hi, bool stream) {
    lo = _mm_min_ps(lo, _mm_min_ps(_mm_min_ps(r0, r1), _mm_min_ps(r2, r3)));
    hi = _mm_max_ps(hi, _mm_max_ps(_mm_max_ps(r0, r1), _mm_max_ps(r2, r3)));
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    if (stream) _mm_stream_ps(tb.v[0] + 4 * q, r0), _mm_stream_ps(tb.v[1] + 4 * q, r1), _mm_stream_ps(tb.v[2] + 4 * q, r2);
    else _mm_store_ps(tb.v[0] + 4 * q, r0), _mm_store_ps(tb.v[1] + 4 * q, r1), _mm_store_ps(tb.v[2] + 4 * q, r2);
  };
  auto tables_from_floats = [&](bool stream) {
    for (u32 c = 0; c < C; ++c) {
      __m128 lo = _mm_set1_ps(INFINITY), hi = _mm_set1_ps(-INFINITY);
      for (u32 g = coff[c]; g < coff[c + 1]; ++g) {
        const u32* v = &gverts[16 * std::size_t(g)];
        for (int q = 0; q < 4; ++q)
          put4(tables[g], q, _mm_loadu_ps(fpos + 3 * std::size_t(v[4 * q])), _mm_loadu_ps(fpos + 3 * std::size_t(v[4 * q + 1])),
               _mm_loadu_ps(fpos + 3 * std::size_t(v[4 * q + 2])), _mm_loadu_ps(fpos + 3 * std::size_t(v[4 * q + 3])), lo, hi,
               stream);
      }
      box_out(c, lo, hi);
    }
    _mm_sfence();
  };

  enum { kToday, kTables, kTablesOrdinary, kDirect, kGather, kN };
  const char* names[kN] = {"today: conversion + boxes, then blocks", "tables: conversion, then tables (streaming stores)",
                           "tables: conversion, then tables (ordinary stores)", "direct: tables from the doubles",
                           "gather: tables by AVX-512 gathers of the doubles"};
  std::vector<double> ms[kN], part1[kN];
  for (int frame = 0; frame < 12; ++frame) {
    for (std::size_t i = 0; i < 3 * V; ++i) in[i] = Q[i] * (1 + 1e-3 * frame);
    double t[kN], p[kN];
    // today
    double t0 = now_ms();
    for (std::size_t v = 0; v < V; ++v)
      for (int a = 0; a < 3; ++a) fpos[3 * v + a] = static_cast<float>((in[3 * v + a] - (a == 0 ? ox : a == 1 ? oy : oz)) * sc);
    for (u32 c = 0; c < C; ++c) {
      __m128 lo = _mm_set1_ps(INFINITY), hi = _mm_set1_ps(-INFINITY);
      for (u32 i = cvoff[c]; i < cvoff[c + 1]; ++i) {
        const __m128 q = _mm_loadu_ps(fpos + 3 * std::size_t(cv[i]));
        lo = _mm_min_ps(lo, q), hi = _mm_max_ps(hi, q);
      }
      box_out(c, lo, hi);
    }
    p[kToday] = now_ms() - t0;
    for (std::size_t b = 0; b < nb; ++b) {
      const u32* v = &corners[12 * b];
      for (int k = 0; k < 3; ++k) {
        __m128 r0 = _mm_loadu_ps(fpos + 3 * std::size_t(v[4 * k])), r1 = _mm_loadu_ps(fpos + 3 * std::size_t(v[4 * k + 1]));
        __m128 r2 = _mm_loadu_ps(fpos + 3 * std::size_t(v[4 * k + 2])), r3 = _mm_loadu_ps(fpos + 3 * std::size_t(v[4 * k + 3]));
        _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
        _mm_stream_ps(blocks[b].v[k][0], r0), _mm_stream_ps(blocks[b].v[k][1], r1), _mm_stream_ps(blocks[b].v[k][2], r2);
      }
    }
    _mm_sfence();
    t[kToday] = now_ms() - t0;
    // tables, streaming and ordinary stores
    for (int kind : {kTables, kTablesOrdinary}) {
      t0 = now_ms();
      convert();
      p[kind] = now_ms() - t0;
      tables_from_floats(kind == kTables);
      t[kind] = now_ms() - t0;
    }
    // direct
    t0 = now_ms();
    {
      const __m256d org4 = _mm256_setr_pd(ox, oy, oz, 0), s4 = _mm256_set1_pd(sc);
      for (u32 c = 0; c < C; ++c) {
        __m128 lo = _mm_set1_ps(INFINITY), hi = _mm_set1_ps(-INFINITY);
        for (u32 g = coff[c]; g < coff[c + 1]; ++g) {
          const u32* v = &gverts[16 * std::size_t(g)];
          for (int q = 0; q < 4; ++q) {
            __m128 r[4];
            for (int l = 0; l < 4; ++l)  // (reads one double past a vertex: the next one's x, or the padding)
              r[l] = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(in + 3 * std::size_t(v[4 * q + l])), org4), s4));
            put4(tables[g], q, r[0], r[1], r[2], r[3], lo, hi, true);
          }
        }
        box_out(c, lo, hi);
      }
      _mm_sfence();
    }
    t[kDirect] = now_ms() - t0, p[kDirect] = 0;
    // gather
    t0 = now_ms();
    {
      const __m512d s8 = _mm512_set1_pd(sc), o[3] = {_mm512_set1_pd(ox), _mm512_set1_pd(oy), _mm512_set1_pd(oz)};
      for (u32 c = 0; c < C; ++c) {
        __m512 lo[3], hi[3];
        for (int a = 0; a < 3; ++a) lo[a] = _mm512_set1_ps(INFINITY), hi[a] = _mm512_set1_ps(-INFINITY);
        for (u32 g = coff[c]; g < coff[c + 1]; ++g) {
          const __m512i idx = _mm512_mullo_epi32(_mm512_loadu_si512(&gverts[16 * std::size_t(g)]), _mm512_set1_epi32(3));
          const __m256i il = _mm512_castsi512_si256(idx), ih = _mm512_extracti64x4_epi64(idx, 1);
          for (int a = 0; a < 3; ++a) {
            const __m256 fl = _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_sub_pd(_mm512_i32gather_pd(il, in + a, 8), o[a]), s8));
            const __m256 fh = _mm512_cvtpd_ps(_mm512_mul_pd(_mm512_sub_pd(_mm512_i32gather_pd(ih, in + a, 8), o[a]), s8));
            const __m512 x = _mm512_insertf32x8(_mm512_castps256_ps512(fl), fh, 1);
            _mm512_stream_ps(tables[g].v[a], x);
            lo[a] = _mm512_min_ps(lo[a], x), hi[a] = _mm512_max_ps(hi[a], x);
          }
        }
        for (int a = 0; a < 3; ++a)
          boxes[6 * c + a] = _mm512_reduce_min_ps(lo[a]), boxes[6 * c + 3 + a] = _mm512_reduce_max_ps(hi[a]);
      }
      _mm_sfence();
    }
    t[kGather] = now_ms() - t0, p[kGather] = 0;
    if (frame >= 2)
      for (int k = 0; k < kN; ++k) ms[k].push_back(t[k]), part1[k].push_back(p[k]);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  };
  std::printf("ms a frame, median [min, max] of frames 2..11 (first part: conversion, with boxes for today)\n");
  for (int k = 0; k < kN; ++k)
    std::printf("%-52s %6.2f [%5.2f, %5.2f]   first part %5.2f\n", names[k], median(ms[k]),
                *std::min_element(ms[k].begin(), ms[k].end()), *std::max_element(ms[k].begin(), ms[k].end()),
                median(part1[k]));
  std::printf("(boxes: %g)\n", double(boxes[0]));  // keeps the stores
  return 0;
}
