/* What writing N MB costs on this machine, the floor of a per-frame fill (docs/tracing.md,
   "Groups of 32 clusters, ..."): the median of 200 passes of streaming stores (`movntps`, then a
   fence), of ordinary 16-byte stores (into lines that stay in the L3 from one pass to the next
   when N MB fit), and of a streamed copy (load, add, streaming store), ms and GB/s each.
     gcc -O2 bench/scale/store_probe.c -o /tmp/store_probe && /tmp/store_probe 18.6 */
#include <emmintrin.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

static int cmp(const void* a, const void* b) {
  const double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

int main(int argc, char** argv) {
  if (argc != 2 || atof(argv[1]) <= 0) {
    fprintf(stderr, "usage: store_probe MB\n");
    return 2;
  }
  const size_t bytes = ((size_t)(atof(argv[1]) * 1e6) + 63) / 64 * 64;
  float* a = aligned_alloc(64, bytes);
  float* src = aligned_alloc(64, bytes);
  if (!a || !src) {
    fprintf(stderr, "store_probe: out of memory\n");
    return 1;
  }
  memset(a, 0, bytes);
  memset(src, 1, bytes);
  const char* names[3] = {"streaming stores", "ordinary stores", "streamed copy"};
  enum { R = 200 };
  double t[R];
  for (int mode = 0; mode < 3; ++mode) {
    for (int rep = 0; rep < R; ++rep) {
      const double t0 = now_ms();
      const __m128 v = _mm_set1_ps((float)rep);
      if (mode == 0) {
        for (size_t i = 0; i < bytes / 4; i += 4) _mm_stream_ps(a + i, v);
        _mm_sfence();
      } else if (mode == 1) {
        for (size_t i = 0; i < bytes / 4; i += 4) _mm_store_ps(a + i, v);
      } else {
        for (size_t i = 0; i < bytes / 4; i += 4) _mm_stream_ps(a + i, _mm_add_ps(_mm_load_ps(src + i), v));
        _mm_sfence();
      }
      t[rep] = now_ms() - t0;
    }
    qsort(t, R, sizeof t[0], cmp);
    printf("%-17s %.3f ms  %.1f GB/s\n", names[mode], t[R / 2], (double)bytes / t[R / 2] / 1e6);
  }
  free(a);
  free(src);
  return 0;
}
