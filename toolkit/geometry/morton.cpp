#include "toolkit/geometry/morton.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "toolkit/geometry/triangle.h"

namespace ptc {

namespace {

// Spreads the low 21 bits of v so that bit i lands on bit 3i.
std::uint64_t spread3(std::uint32_t v) {
  std::uint64_t x = v & 0x1fffffu;
  x = (x | (x << 32)) & 0x1f00000000ffffULL;
  x = (x | (x << 16)) & 0x1f0000ff0000ffULL;
  x = (x | (x << 8)) & 0x100f00f00f00f00fULL;
  x = (x | (x << 4)) & 0x10c30c30c30c30c3ULL;
  x = (x | (x << 2)) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

std::uint64_t morton_encode(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return (spread3(x) << 2) | (spread3(y) << 1) | spread3(z);
}

std::vector<std::uint64_t> morton_codes(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                        MortonGrid grid, const Box3* centroid_bounds) {
  std::vector<std::uint64_t> codes;
  if (triangles.empty()) return codes;
  const std::size_t n = positions.size();
  // Without the caller's box, centroids are computed twice (bounds, then codes) instead of kept:
  // 24 bytes a triangle less at the peak of a clustering of 13M triangles; triangle_centroid
  // gives the same bits both times.
  Box3 box;
  if (centroid_bounds) {
    box = *centroid_bounds;
  } else {
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      const Tri& f = triangles[t];
      for (std::uint32_t v : f)
        if (v >= n)
          throw std::invalid_argument("morton_codes: triangle " + std::to_string(t) + " refers to vertex " +
                                      std::to_string(v) + " of " + std::to_string(n));
      box.extend(triangle_centroid(positions[f[0]], positions[f[1]], positions[f[2]]));
    }
  }
  constexpr double cells = static_cast<double>(1u << kMortonBits);
  constexpr std::uint32_t max_cell = (1u << kMortonBits) - 1;
  const Vec3 extent = box.hi - box.lo;
  Vec3 scale;
  for (int a = 0; a < 3; ++a) {
    const double e = grid == MortonGrid::Cube ? extent.maxCoeff() : extent[a];
    scale[a] = e > 0.0 ? cells / e : 0.0;  // degenerate axis: every centroid in cell 0
  }
  codes.resize(triangles.size());
  // Per triangle, independent: in parallel (the caller's concurrency), the same codes.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      if (t + kCornerPrefetchAhead < r.end()) prefetch_corners(positions.data(), triangles[t + kCornerPrefetchAhead]);
      const Tri& f = triangles[t];
      const Vec3 c = triangle_centroid(positions[f[0]], positions[f[1]], positions[f[2]]);
      std::uint32_t cell[3];
      for (int a = 0; a < 3; ++a) {
        const double q = std::floor((c[a] - box.lo[a]) * scale[a]);
        cell[a] = q >= static_cast<double>(max_cell) ? max_cell : static_cast<std::uint32_t>(std::max(0.0, q));
      }
      codes[t] = morton_encode(cell[0], cell[1], cell[2]);
    }
  });
  return codes;
}

std::vector<std::uint32_t> morton_order(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                        MortonGrid grid, const Box3* centroid_bounds) {
  const std::vector<std::uint64_t> codes = morton_codes(positions, triangles, grid, centroid_bounds);
  const std::size_t n = codes.size();
  std::vector<std::uint32_t> order(n);
  if (n == 0) return order;
  // (code, id) order in cache-friendly steps (at 13M triangles they replaced a comparison sort
  // that looked each code up through its id; docs/scale.md, "Open (issue 15)"):
  // 1. ids scattered by the code's top 11 bits, in ascending id order (a counting sort);
  // 2. each bucket as (code, id) pairs, in buffers of the bucket's size (per task). A bucket's ids
  //    ascend, so its codes are read front to back. A small bucket is sorted by (code, id) as it
  //    is; a large one is first scattered by the next 11 bits of the code (stable, so ids still
  //    ascend within each sub-bucket), then each sub-bucket sorted by (code, id): the same order,
  //    with a comparison sort of a few dozen pairs where one of thousands took most of the time.
  constexpr int kTopBits = 11, kShift = 3 * kMortonBits - kTopBits;
  constexpr int kSubBits = 11, kSubShift = kShift - kSubBits;
  constexpr std::size_t kBuckets = std::size_t{1} << kTopBits, kSubBuckets = std::size_t{1} << kSubBits;
  constexpr std::size_t kLargeBucket = 1024;  // below: one comparison sort
  std::vector<std::size_t> start(kBuckets + 1, 0);
  for (const std::uint64_t c : codes) ++start[(c >> kShift) + 1];
  for (std::size_t b = 0; b < kBuckets; ++b) start[b + 1] += start[b];
  {
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < n; ++i) order[fill[codes[i] >> kShift]++] = static_cast<std::uint32_t>(i);
  }
  // The buckets are independent: sorted on the caller's threads, the same order at any count.
  using Pair = std::pair<std::uint64_t, std::uint32_t>;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, kBuckets, 64), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Pair> pairs, scattered;
    std::vector<std::uint32_t> sub(kSubBuckets + 1);
    for (std::size_t b = r.begin(); b < r.end(); ++b) {
      const std::size_t lo = start[b], hi = start[b + 1];
      if (hi - lo < 2) continue;
      pairs.clear();
      for (std::size_t i = lo; i < hi; ++i) pairs.emplace_back(codes[order[i]], order[i]);
      if (hi - lo < kLargeBucket) {
        std::sort(pairs.begin(), pairs.end());
        for (std::size_t i = lo; i < hi; ++i) order[i] = pairs[i - lo].second;
        continue;
      }
      auto sub_of = [&](std::uint64_t c) { return static_cast<std::size_t>(c >> kSubShift) & (kSubBuckets - 1); };
      std::fill(sub.begin(), sub.end(), 0u);
      for (const Pair& p : pairs) ++sub[sub_of(p.first) + 1];
      for (std::size_t s = 0; s < kSubBuckets; ++s) sub[s + 1] += sub[s];
      scattered.resize(pairs.size());
      for (const Pair& p : pairs) scattered[sub[sub_of(p.first)]++] = p;  // sub[s] ends as the start of s + 1
      std::size_t s_lo = 0;
      for (std::size_t s = 0; s < kSubBuckets; ++s) {
        const std::size_t s_hi = sub[s];
        if (s_hi - s_lo > 1) std::sort(scattered.begin() + static_cast<std::ptrdiff_t>(s_lo),
                                       scattered.begin() + static_cast<std::ptrdiff_t>(s_hi));
        s_lo = s_hi;
      }
      for (std::size_t i = lo; i < hi; ++i) order[i] = scattered[i - lo].second;
    }
  });
  return order;
}

}  // namespace ptc
