/* What a two-table permute costs on this machine against the blocks' 128-bit insert
   (docs/tracing.md, "Vertex tables in the walk"): twelve independent chains of `vpermt2ps` of
   512 bits (a row of 16 from 32 entries, what the tables' AVX-512VL test takes a row with), of
   256 bits (16 entries), and of `vinsertf128` (half a blocks' row), ns an instruction.
     gcc -O2 -march=native bench/scale/permute_probe.c -o /tmp/permute_probe && /tmp/permute_probe */
#include <immintrin.h>
#include <stdio.h>
#include <time.h>

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(void) {
  enum { K = 12 };
  const long n = 200000000;
  __m512 a[K];
  __m256 b[K];
  const __m512i ia = _mm512_set_epi32(1, 5, 9, 13, 17, 21, 25, 29, 3, 7, 11, 15, 19, 23, 27, 31);
  const __m256i ib = _mm256_set_epi32(1, 5, 9, 13, 3, 7, 11, 15);
  for (int i = 0; i < K; ++i) a[i] = _mm512_set1_ps((float)i), b[i] = _mm256_set1_ps((float)i);
  const double t0 = now();
  for (long r = 0; r < n; ++r) {
#pragma GCC unroll 12
    for (int i = 0; i < K; ++i) a[i] = _mm512_permutex2var_ps(a[i], ia, a[(i + 1) % K]);
  }
  const double t1 = now();
  for (long r = 0; r < n; ++r) {
#pragma GCC unroll 12
    for (int i = 0; i < K; ++i) b[i] = _mm256_permutex2var_ps(b[i], ib, b[(i + 1) % K]);
  }
  const double t2 = now();
  for (long r = 0; r < n; ++r) {
#pragma GCC unroll 12
    for (int i = 0; i < K; ++i) b[i] = _mm256_insertf128_ps(b[i], _mm256_castps256_ps128(b[(i + 5) % K]), 1);
  }
  const double t3 = now();
  float s = 0;  /* (keeps the chains alive) */
  for (int i = 0; i < K; ++i) s += _mm512_reduce_add_ps(a[i]) + b[i][0];
  const double per = 1e9 / ((double)n * K);
  printf("vpermt2ps 512-bit %.3f ns, 256-bit %.3f ns, vinsertf128 %.3f ns an instruction (checksum %g)\n",
         (t1 - t0) * per, (t2 - t1) * per, (t3 - t2) * per, s);
  return 0;
}
