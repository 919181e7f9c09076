// A std::allocator with cache-line (or larger) alignment: SoA arrays that threads write in
// 16-element tiles never share a cache line, and SIMD blocks can use aligned loads.
//
// Large arrays (256 KiB or more: leaf blocks, nodes, boxes, rays, hits) are also placed on whole
// 2 MiB pages and advised as transparent huge pages (madvise MADV_HUGEPAGE; a no-op where the
// kernel's THP setting is "never"). A scene rewrites them every frame; at 4 KiB pages, on this
// project's development machine (a virtual machine), the cluster scene's 33 MB of leaf blocks
// took 28-44 ms to rewrite instead of 3 ms whenever another scene was updated in the same loop,
// with no page fault in the guest (docs/tracing.md, "Huge pages").
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace ptc::bvh {

/// A transparent huge page, and the array size from which AlignedAllocator asks for them.
inline constexpr std::size_t kHugePageBytes = std::size_t(2) << 20;
inline constexpr std::size_t kHugePageFrom = std::size_t(256) << 10;

/// Memory of `bytes` aligned to `align`; from kHugePageFrom bytes on, whole 2 MiB pages aligned
/// to 2 MiB and advised as huge pages. Free it with free_aligned(p, bytes, align).
void* allocate_aligned(std::size_t bytes, std::size_t align);
void free_aligned(void* p, std::size_t bytes, std::size_t align) noexcept;

template <class T, std::size_t Align = 64>
struct AlignedAllocator {
  using value_type = T;
  template <class U>
  struct rebind {
    using other = AlignedAllocator<U, Align>;
  };
  AlignedAllocator() = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U, Align>&) noexcept {}
  T* allocate(std::size_t n) {
    if (n > std::size_t(-1) / sizeof(T)) throw std::bad_array_new_length();
    return static_cast<T*>(allocate_aligned(n * sizeof(T), Align));
  }
  void deallocate(T* p, std::size_t n) noexcept { free_aligned(p, n * sizeof(T), Align); }
  template <class U>
  bool operator==(const AlignedAllocator<U, Align>&) const noexcept {
    return true;
  }
};

template <class T>
using AlignedVector = std::vector<T, AlignedAllocator<T>>;

}  // namespace ptc::bvh
