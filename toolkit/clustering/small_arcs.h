// SmallArcs: the out-edge list of contraction.cpp's cluster graph (Boost.Graph adjacency_list
// with a container of its own, plugged in through Boost's container_gen): arcs of 4 bytes, up to
// three in place. Here so that a test can compare it with std::vector operation by operation.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <new>
#include <type_traits>

namespace ptc {

/// Out-edge list of the cluster graph without edge data (ClusterGraph<false>): arcs of 4 bytes,
/// up to three of them in place (a triangle's neighbours), more in one heap block. 16 bytes, so
/// a Boost vertex with it takes 20 where a std::vector of 8-byte arcs took 32 plus a heap block of
/// 32 (docs/scale.md, "Contraction in one run: the memory"). The std::vector subset Boost's
/// adjacency_list uses with a vector-like out-edge list (push_back, erase of a range, clear,
/// size, begin/end), plus reserve and shrink_to_fit.
template <class T>
class SmallArcs {
  static_assert(sizeof(T) == 4 && std::is_trivially_copyable_v<T> && std::is_trivially_default_constructible_v<T>,
                "4-byte trivial arcs (assigning one in place begins its lifetime in the union)");

 public:
  using value_type = T;
  using iterator = T*;
  using const_iterator = const T*;
  using reference = T&;
  using const_reference = const T&;
  using size_type = std::size_t;
  using difference_type = std::ptrdiff_t;

  SmallArcs() = default;
  SmallArcs(const SmallArcs& o) { assign(o.begin(), o.size()); }
  SmallArcs(SmallArcs&& o) noexcept : st_(o.st_), size_(o.size_) { o.size_ = 0; }
  SmallArcs& operator=(const SmallArcs& o) {
    if (this != &o) {
      release();
      assign(o.begin(), o.size());
    }
    return *this;
  }
  SmallArcs& operator=(SmallArcs&& o) noexcept {
    if (this != &o) {
      release();
      st_ = o.st_;
      size_ = o.size_;
      o.size_ = 0;
    }
    return *this;
  }
  ~SmallArcs() { release(); }

  [[nodiscard]] std::size_t size() const { return size_ & ~kHeap; }
  [[nodiscard]] bool empty() const { return size() == 0; }
  [[nodiscard]] std::size_t capacity() const { return heap() ? st_.heap.cap : kInline; }
  T* begin() { return data(); }
  T* end() { return data() + size(); }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size(); }

  void push_back(const T& x) {
    const T v = x;  // (x may be an element of this list, which reserve frees)
    const std::size_t n = size();
    // Grows by about half; 4 * cap + 8 a multiple of 16 (malloc's chunks): 6, 14, 26, 42, ...
    if (n == capacity()) reserve(n < 6 ? 6 : ((n + n / 2 + 3) & ~std::size_t{3}) + 2);
    data()[n] = v;
    ++size_;
  }
  iterator erase(iterator first, iterator last) {
    const std::size_t n = size();
    T* d = data();
    std::memmove(first, last, sizeof(T) * static_cast<std::size_t>(d + n - last));
    size_ -= static_cast<std::uint32_t>(last - first);
    return first;
  }
  void clear() { size_ &= kHeap; }
  void reserve(std::size_t cap) {
    if (cap <= capacity()) return;
    T* block = static_cast<T*>(::operator new(sizeof(T) * cap));
    const std::size_t n = size();
    std::memcpy(block, data(), sizeof(T) * n);
    release();
    set_heap(block, static_cast<std::uint32_t>(cap));
    size_ = static_cast<std::uint32_t>(n) | kHeap;
  }
  /// Back in place when the arcs fit (a dead cluster has none), else a block of exactly size().
  void shrink_to_fit() {
    const std::size_t n = size();
    if (!heap() || n == st_.heap.cap) return;
    T* old = st_.heap.ptr;
    if (n <= kInline) {
      std::memcpy(st_.inl, old, sizeof(T) * n);
      size_ = static_cast<std::uint32_t>(n);
    } else {
      T* block = static_cast<T*>(::operator new(sizeof(T) * n));
      std::memcpy(block, old, sizeof(T) * n);
      set_heap(block, static_cast<std::uint32_t>(n));
    }
    ::operator delete(old);
  }

 private:
  static constexpr std::uint32_t kHeap = 0x80000000u;
  static constexpr std::size_t kInline = 3;
  [[nodiscard]] bool heap() const { return (size_ & kHeap) != 0; }
  void set_heap(T* p, std::uint32_t cap) {
    st_.heap.ptr = p;
    st_.heap.cap = cap;
  }
  T* data() { return heap() ? st_.heap.ptr : st_.inl; }
  const T* data() const { return heap() ? st_.heap.ptr : st_.inl; }
  void release() {
    if (heap()) ::operator delete(st_.heap.ptr);
    size_ = 0;
  }
  void assign(const T* src, std::size_t n) {
    size_ = 0;
    if (n > kInline) reserve(n);
    std::memcpy(data(), src, sizeof(T) * n);
    size_ = static_cast<std::uint32_t>(n) | (size_ & kHeap);
  }
  // In place: three arcs. On the heap: the block's pointer and capacity, packed into the same 12
  // bytes (the pointer 4-aligned; x86-64 reads it so at no cost).
  struct [[gnu::packed]] Block {
    T* ptr;
    std::uint32_t cap;
  };
  union Storage {
    T inl[kInline];
    Block heap;
    Storage() : heap{nullptr, 0} {}
  };
  static_assert(sizeof(Storage) == 12);
  Storage st_;
  std::uint32_t size_ = 0;  // arc count, kHeap when on the heap
};
static_assert(sizeof(SmallArcs<std::uint32_t>) == 16);

}  // namespace ptc
