/* What a first touch of fresh memory costs on this machine (docs/scale.md, "Validate, metrics
   and write" and "Warm memory"): maps G GiB four times, touches one byte a page (on T threads,
   each its own range of whole 2 MiB pages), then writes it all, and unmaps. Arguments, in any order: `huge` (the
   mapping asks for transparent huge pages, MADV_HUGEPAGE, as ptc's large arrays do), `threads=T`
   (default 1), `gib=G` (default 1).
     gcc -O2 -pthread bench/scale/first_touch.c -o /tmp/first_touch
     /tmp/first_touch && /tmp/first_touch huge && /tmp/first_touch huge threads=2 gib=3 */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <time.h>

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static char* mem;
static size_t bytes;
static int threads = 1;

static void* touch(void* arg) {
  const size_t k = (size_t)arg, huge_page = (size_t)2 << 20;
  const size_t pages = (bytes + huge_page - 1) / huge_page, per = (pages + (size_t)threads - 1) / (size_t)threads;
  const size_t begin = k * per * huge_page, end = (k + 1) * per * huge_page < bytes ? (k + 1) * per * huge_page : bytes;
  for (size_t i = begin; i < end; i += 4096) mem[i] = 1;
  return NULL;
}

static int usage(const char* what) {
  fprintf(stderr, "first_touch: %s (arguments: huge, threads=T with T from 1 to 64, gib=G with G at least 1/512)\n", what);
  return 2;
}

int main(int argc, char** argv) {
  int huge = 0;
  double gib = 1.0;
  for (int i = 1; i < argc; ++i) {
    char* end = NULL;
    errno = 0;
    if (strcmp(argv[i], "huge") == 0) {
      huge = 1;
    } else if (strncmp(argv[i], "threads=", 8) == 0) {
      const long t = strtol(argv[i] + 8, &end, 10);
      if (errno || end == argv[i] + 8 || *end || t < 1 || t > 64) return usage(argv[i]);
      threads = (int)t;
    } else if (strncmp(argv[i], "gib=", 4) == 0) {
      gib = strtod(argv[i] + 4, &end);
      if (errno || end == argv[i] + 4 || *end || !isfinite(gib) || gib < 1.0 / 512 || gib > 1 << 20) return usage(argv[i]);
    } else {
      return usage(argv[i]);
    }
  }
  bytes = (size_t)(gib * (double)((size_t)1 << 30));
  for (int r = 0; r < 4; ++r) {
    const size_t huge_page = (size_t)2 << 20;  // the mapping starts on a 2 MiB boundary
    char* const map = mmap(0, bytes + huge_page, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (map == MAP_FAILED) {
      perror("first_touch: mmap");
      return 1;
    }
    mem = (char*)(((uintptr_t)map + huge_page - 1) & ~(uintptr_t)(huge_page - 1));
    if (huge) madvise(mem, bytes, MADV_HUGEPAGE);
    const double t0 = now();
    pthread_t th[64];
    for (int k = 0; k < threads; ++k)
      if ((errno = pthread_create(&th[k], NULL, touch, (void*)(size_t)k)) != 0) {
        perror("first_touch: pthread_create");
        return 1;
      }
    for (int k = 0; k < threads; ++k) pthread_join(th[k], NULL);
    const double t1 = now();
    memset(mem, 2, bytes);
    const double t2 = now();
    printf("%s, %d thread(s), %.2f GiB, round %d: first touch %.3f s (%.2f s a GiB), then a memset %.3f s\n",
           huge ? "huge pages" : "4 KiB pages", threads, gib, r + 1, t1 - t0, (t1 - t0) / gib, t2 - t1);
    munmap(map, bytes + huge_page);
  }
  return 0;
}
