/* A neighbour that streams through memory (docs/scale.md, "And at 832k: a 480 MB L3 cache"):
   reads and writes one byte every 64 over a 1 GiB array for SECONDS seconds, which keeps the
   shared L3 cache busy while a command runs on the other core.
     gcc -O2 bench/scale/thrash.c -o /tmp/thrash && taskset -c 0 /tmp/thrash 8 &
     taskset -c 1 build/bin/ptc trace MESH --clusters D --frame 0 --width 64 --height 64 --threads 1 --out T */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char** argv) {
  if (argc != 2 || atof(argv[1]) <= 0) {
    fprintf(stderr, "usage: thrash SECONDS\n");
    return 2;
  }
  const double seconds = atof(argv[1]);
  const size_t n = (size_t)1 << 30;
  char* b = malloc(n);
  if (!b) return 1;
  memset(b, 1, n);
  unsigned long s = 0;
  const double t0 = now();
  while (now() - t0 < seconds)
    for (size_t i = 0; i < n; i += 64) {
      s += (unsigned char)b[i];
      b[i] = (char)s;
    }
  printf("%lu\n", s & 1); /* (keeps the loop) */
  free(b);
  return 0;
}
