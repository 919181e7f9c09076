/* What a first touch of fresh memory costs on this machine (docs/scale.md, "Validate, metrics
   and write" and "Warm memory"): maps G GiB four times, touches one byte a page (on T threads,
   pages interleaved), then writes it all, and unmaps. Arguments, in any order: `huge` (the
   mapping asks for transparent huge pages, MADV_HUGEPAGE, as ptc's large arrays do), `threads=T`
   (default 1), `gib=G` (default 1).
     gcc -O2 -pthread bench/scale/first_touch.c -o /tmp/first_touch
     /tmp/first_touch && /tmp/first_touch huge && /tmp/first_touch huge threads=2 gib=3 */
#include <pthread.h>
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
  const size_t k = (size_t)arg;
  for (size_t i = k * 4096; i < bytes; i += (size_t)threads * 4096) mem[i] = 1;
  return NULL;
}

int main(int argc, char** argv) {
  int huge = 0;
  double gib = 1.0;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "huge") == 0) huge = 1;
    else if (strncmp(argv[i], "threads=", 8) == 0) threads = atoi(argv[i] + 8);
    else if (strncmp(argv[i], "gib=", 4) == 0) gib = atof(argv[i] + 4);
    else {
      fprintf(stderr, "first_touch: unknown argument %s (huge, threads=T, gib=G)\n", argv[i]);
      return 2;
    }
  }
  if (threads < 1 || threads > 64 || !(gib > 0)) {
    fprintf(stderr, "first_touch: threads must be 1 to 64 and gib more than 0\n");
    return 2;
  }
  bytes = (size_t)(gib * (double)((size_t)1 << 30));
  for (int r = 0; r < 4; ++r) {
    mem = mmap(0, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (mem == MAP_FAILED) return 1;
    if (huge) madvise(mem, bytes, MADV_HUGEPAGE);
    const double t0 = now();
    pthread_t th[64];
    for (int k = 0; k < threads; ++k) pthread_create(&th[k], NULL, touch, (void*)(size_t)k);
    for (int k = 0; k < threads; ++k) pthread_join(th[k], NULL);
    const double t1 = now();
    memset(mem, 2, bytes);
    const double t2 = now();
    printf("%s, %d thread(s), %.2f GiB, round %d: first touch %.3f s (%.2f s a GiB), then a memset %.3f s\n",
           huge ? "huge pages" : "4 KiB pages", threads, gib, r + 1, t1 - t0, (t1 - t0) / gib, t2 - t1);
    munmap(mem, bytes);
  }
  return 0;
}
