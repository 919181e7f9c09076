#include "bvh/aligned.h"

#include <sys/mman.h>

#include <algorithm>

namespace ptc::bvh {

namespace {

std::size_t alignment_for(std::size_t bytes, std::size_t align) {
  return bytes >= kHugePageFrom ? std::max(align, kHugePageBytes) : align;
}

// Bytes asked for: whole huge pages from kHugePageFrom on (a region of huge pages must span
// whole 2 MiB pages; the tail of the last one is not used, at most 1.75 MiB per array).
std::size_t size_for(std::size_t bytes) {
  return bytes >= kHugePageFrom ? (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes : bytes;
}

}  // namespace

void* allocate_aligned(std::size_t bytes, std::size_t align) {
  const std::size_t a = alignment_for(bytes, align);
  const std::size_t n = size_for(bytes);
  void* p = ::operator new(n, std::align_val_t{a});
  // Advice only: a kernel without THP (or with it set to "never") refuses or ignores it, and the
  // memory is then used with 4 KiB pages as before.
  if (a == kHugePageBytes) (void)madvise(p, n, MADV_HUGEPAGE);
  return p;
}

void free_aligned(void* p, std::size_t bytes, std::size_t align) noexcept {
  ::operator delete(p, size_for(bytes), std::align_val_t{alignment_for(bytes, align)});
}

}  // namespace ptc::bvh
