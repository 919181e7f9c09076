#include "toolkit/core/memory.h"

#include <cstdio>
#include <cstring>

namespace ptc {
namespace {

// The value of "KEY:   123 kB" in a /proc file, in MB; 0 when absent.
double status_mb(const char* key, const char* file = "/proc/self/status") {
  std::FILE* f = std::fopen(file, "r");
  if (!f) return 0;
  char line[256];
  double mb = 0;
  const std::size_t n = std::strlen(key);
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, key, n) == 0 && line[n] == ':') {
      long kb = 0;
      if (std::sscanf(line + n + 1, "%ld", &kb) == 1) mb = double(kb) / 1024.0;
      break;
    }
  std::fclose(f);
  return mb;
}

}  // namespace

double peak_rss_mb() { return status_mb("VmHWM"); }

double current_rss_mb() { return status_mb("VmRSS"); }

double machine_memory_mb() { return status_mb("MemTotal", "/proc/meminfo"); }

}  // namespace ptc
