/* What a first touch of fresh memory costs on this machine (docs/scale.md, "Validate, metrics
   and write"): maps 1 GiB four times, touches one byte a page, then writes it all, and unmaps.
   With an argument, the mapping asks for transparent huge pages (MADV_HUGEPAGE).
     gcc -O2 bench/scale/first_touch.c -o /tmp/first_touch && /tmp/first_touch && /tmp/first_touch huge */
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char** argv) {
  const size_t n = (size_t)1 << 30;
  const int huge = argc > 1;
  (void)argv;
  for (int r = 0; r < 4; ++r) {
    char* p = mmap(0, n, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) return 1;
    if (huge) madvise(p, n, MADV_HUGEPAGE);
    const double t0 = now();
    for (size_t i = 0; i < n; i += 4096) p[i] = 1;
    const double t1 = now();
    memset(p, 2, n);
    const double t2 = now();
    printf("%s round %d: first touch %.3f s (%.2f GiB/s), then a memset %.3f s\n", huge ? "huge pages" : "4 KiB pages",
           r + 1, t1 - t0, 1.0 / (t1 - t0), t2 - t1);
    munmap(p, n);
  }
  return 0;
}
