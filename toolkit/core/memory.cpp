#include "toolkit/core/memory.h"

#include <cstdio>
#include <cstring>
#include <fstream>

namespace ptc {
namespace {

// The values of "KEY:   123 kB" lines of a /proc file, in MB (0 for a key that is absent).
template <std::size_t N>
void read_kb_lines(const char* file, const char* const (&keys)[N], double (&mb)[N]) {
  for (double& m : mb) m = 0;
  std::FILE* f = std::fopen(file, "r");
  if (!f) return;
  char line[256];
  while (std::fgets(line, sizeof line, f))
    for (std::size_t k = 0; k < N; ++k) {
      const std::size_t n = std::strlen(keys[k]);
      long kb = 0;
      if (std::strncmp(line, keys[k], n) == 0 && line[n] == ':' && std::sscanf(line + n + 1, "%ld", &kb) == 1)
        mb[k] = double(kb) / 1024.0;
    }
  std::fclose(f);
}

}  // namespace

RssSample rss_sample() {
  static const char* const keys[] = {"VmRSS", "VmHWM"};
  double mb[2];
  read_kb_lines("/proc/self/status", keys, mb);
  return {mb[0], mb[1]};
}

double machine_memory_mb() {
  static const char* const keys[] = {"MemTotal"};
  double mb[1];
  read_kb_lines("/proc/meminfo", keys, mb);
  return mb[0];
}

namespace {
bool g_malloc_huge_pages = false;
}  // namespace

std::string transparent_huge_page_mode() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  if (!std::getline(in, line)) return "";
  const auto a = line.find('['), b = line.find(']');
  return a != std::string::npos && b != std::string::npos && b > a ? line.substr(a + 1, b - a - 1) : "";
}

void set_malloc_huge_pages(bool on) { g_malloc_huge_pages = on; }
bool malloc_huge_pages() { return g_malloc_huge_pages; }

}  // namespace ptc
