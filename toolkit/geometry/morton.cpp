#include "toolkit/geometry/morton.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

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
                                        MortonGrid grid) {
  std::vector<std::uint64_t> codes;
  if (triangles.empty()) return codes;
  const std::size_t n = positions.size();
  // Centroids are computed twice (bounds, then codes) instead of kept: 24 bytes a triangle less
  // at the peak of a clustering of 13M triangles; triangle_centroid gives the same bits both times.
  Box3 box;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Tri& f = triangles[t];
    for (std::uint32_t v : f)
      if (v >= n)
        throw std::invalid_argument("morton_codes: triangle " + std::to_string(t) + " refers to vertex " +
                                    std::to_string(v) + " of " + std::to_string(n));
    box.extend(triangle_centroid(positions[f[0]], positions[f[1]], positions[f[2]]));
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
                                        MortonGrid grid) {
  const std::vector<std::uint64_t> codes = morton_codes(positions, triangles, grid);
  std::vector<std::uint32_t> order(codes.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::uint32_t>(i);
  // (code, id) is a total order: any sort, parallel or not, gives this one permutation.
  tbb::parallel_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return codes[a] != codes[b] ? codes[a] < codes[b] : a < b;
  });
  return order;
}

}  // namespace ptc
