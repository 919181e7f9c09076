#include "bvh/box.h"

#include <fmt/format.h>

#include <immintrin.h>  // SSE2 (the x86-64 baseline)

#include <algorithm>
#include <stdexcept>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "bvh/box_simd.h"

namespace ptc::bvh {

namespace {
constexpr std::size_t kPointsPerTask = 1u << 14;  // vertices or triangles per task of the per-frame passes
}  // namespace

std::vector<Box3f> triangle_boxes(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                  const FrameMap& f) {
  std::vector<Box3f> boxes(triangles.size());
  const double ox = f.origin.x(), oy = f.origin.y(), oz = f.origin.z(), s = f.scale;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3& a = positions[triangles[t][0]];
    const Vec3& b = positions[triangles[t][1]];
    const Vec3& c = positions[triangles[t][2]];
    // Min/max first in double (exact), then one outward rounding per bound.
    Box3f& box = boxes[t];
    box.lo = {round_down((std::min({a.x(), b.x(), c.x()}) - ox) * s),
              round_down((std::min({a.y(), b.y(), c.y()}) - oy) * s),
              round_down((std::min({a.z(), b.z(), c.z()}) - oz) * s)};
    box.hi = {round_up((std::max({a.x(), b.x(), c.x()}) - ox) * s), round_up((std::max({a.y(), b.y(), c.y()}) - oy) * s),
              round_up((std::max({a.z(), b.z(), c.z()}) - oz) * s)};
  }
  return boxes;
}

std::vector<Vec3f> box_centers(std::span<const Box3f> boxes) {
  std::vector<Vec3f> c(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) c[i] = boxes[i].center();
  return c;
}

std::vector<Vec3f> triangle_centroids(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                      const FrameMap& origin) {
  std::vector<Vec3f> c(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3 m = (positions[triangles[t][0]] + positions[triangles[t][1]] + positions[triangles[t][2]]) / 3.0;
    c[t] = to_frame(m, origin);
  }
  return c;
}

void frame_positions(std::span<const Vec3> positions, const FrameMap& origin, AlignedVector<Vec3f>& out) {
  out.reserve(positions.size() + 2);  // room for add_sentinel's two entries: no second array
  out.resize(positions.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, positions.size(), kPointsPerTask),
                    [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v < r.end(); ++v) out[v] = to_frame(positions[v], origin);
  });
}

namespace {

using simd::load3;


// The box of the min / max rows lo, hi widened by one unit in the last place (see box.h).
inline void store_box(Box3f& box, __m128 lo, __m128 hi) {
  alignas(16) float l[4], h[4];
  _mm_store_ps(l, simd::widen_down(lo)), _mm_store_ps(h, simd::widen_up(hi));
  box.lo = {l[0], l[1], l[2]}, box.hi = {h[0], h[1], h[2]};
}

}  // namespace

void triangle_boxes(std::span<const Vec3f> fp, std::span<const Tri> triangles, std::span<Box3f> boxes) {
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const __m128 a = load3(fp[triangles[t][0]]), b = load3(fp[triangles[t][1]]), c = load3(fp[triangles[t][2]]);
    store_box(boxes[t], _mm_min_ps(_mm_min_ps(a, b), c), _mm_max_ps(_mm_max_ps(a, b), c));
  }
}

std::vector<Box3f> triangle_boxes(std::span<const Vec3f> fp, std::span<const Tri> triangles) {
  std::vector<Box3f> boxes(triangles.size());
  triangle_boxes(fp, triangles, boxes);
  return boxes;
}

void point_group_boxes(std::span<const Vec3f> fp, std::span<const std::uint32_t> offsets,
                       std::span<const std::uint32_t> indices, AlignedVector<Box3f>& out) {
  const std::size_t groups = offsets.empty() ? 0 : offsets.size() - 1;
  out.assign(groups, Box3f{});
  for (std::size_t g = 0; g < groups; ++g) {
    if (offsets[g] == offsets[g + 1]) continue;
    __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf);
    for (std::uint32_t i = offsets[g]; i < offsets[g + 1]; ++i) {
      const __m128 p = load3(fp[indices[i]]);
      lo = _mm_min_ps(lo, p), hi = _mm_max_ps(hi, p);
    }
    store_box(out[g], lo, hi);
  }
}

void point_group_boxes(std::span<const Vec3f> fp, std::span<const std::uint32_t> offsets,
                       std::span<const std::uint32_t> indices, AlignedVector<Box3f>& out, AlignedVector<Vec3f>& centers) {
  const std::size_t groups = offsets.empty() ? 0 : offsets.size() - 1;
  out.resize(groups);
  centers.resize(groups);
  const simd::VertexLoader load(fp);
  for (std::size_t g = 0; g < groups; ++g) {
    std::uint32_t i = offsets[g];
    const std::uint32_t end = offsets[g + 1];
    if (i == end) {
      simd::store_empty(out[g], centers[g]);
      continue;
    }
    // Two accumulators: the min/max chains of consecutive vertices run in parallel.
    __m128 lo0 = load(indices[i]), hi0 = lo0, lo1 = lo0, hi1 = lo0;
    for (++i; i + 1 < end; i += 2) {
      const __m128 p = load(indices[i]), q = load(indices[i + 1]);
      lo0 = _mm_min_ps(lo0, p), hi0 = _mm_max_ps(hi0, p);
      lo1 = _mm_min_ps(lo1, q), hi1 = _mm_max_ps(hi1, q);
    }
    if (i < end) {
      const __m128 p = load(indices[i]);
      lo0 = _mm_min_ps(lo0, p), hi0 = _mm_max_ps(hi0, p);
    }
    simd::store_widened(_mm_min_ps(lo0, lo1), _mm_max_ps(hi0, hi1), out[g], centers[g]);
  }
}

void point_group_boxes(std::span<const Vec3> positions, const FrameMap& frame, std::span<const std::uint32_t> offsets,
                       std::span<const std::uint32_t> indices, AlignedVector<Box3f>& out, AlignedVector<Vec3f>& centers) {
  const std::size_t groups = offsets.empty() ? 0 : offsets.size() - 1;
  out.resize(groups);
  centers.resize(groups);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t g = r.begin(); g < r.end(); ++g) {
      if (offsets[g] == offsets[g + 1]) {
        simd::store_empty(out[g], centers[g]);
        continue;
      }
      // (min and max are exact, so their order does not matter; store_widened maps both zeros
      // alike, so neither does a zero's sign)
      __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf);
      for (std::uint32_t i = offsets[g]; i < offsets[g + 1]; ++i) {
        const Vec3f f = to_frame(positions[indices[i]], frame);
        const __m128 p = _mm_setr_ps(f[0], f[1], f[2], 0.0f);
        lo = _mm_min_ps(lo, p), hi = _mm_max_ps(hi, p);
      }
      simd::store_widened(lo, hi, out[g], centers[g]);
    }
  });
}

void check_finite(std::span<const Vec3> positions, std::span<const Vec3f> frame_pos, const FrameMap& origin) {
  __m128 bad = _mm_setzero_ps();
  const std::size_t n = std::min(positions.size(), frame_pos.size());
  for (std::size_t v = 0; v < n; ++v) bad = _mm_or_ps(bad, _mm_sub_ps(load3(frame_pos[v]), load3(frame_pos[v])));
  if (_mm_movemask_ps(_mm_cmpunord_ps(bad, bad)) & 7) throw_not_finite(positions, origin);
}

void throw_not_finite(std::span<const Vec3> positions, const FrameMap& origin) {
  for (std::size_t v = 0; v < positions.size(); ++v) {
    const Vec3f f = to_frame(positions[v], origin);
    if (!(std::isfinite(f[0]) && std::isfinite(f[1]) && std::isfinite(f[2])))
      throw FrameRangeError(fmt::format("vertex {}: position ({:g}, {:g}, {:g})", v, positions[v].x(), positions[v].y(),
                                        positions[v].z()) +
                            " is not finite in single precision (NaN, infinite, or beyond the float range "
                                  "in the trace frame)");
  }
  throw FrameRangeError("a position is not finite in single precision");
}

void triangle_centroids(std::span<const Vec3f> fp, std::span<const Tri> triangles, std::span<Vec3f> c) {
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3f& a = fp[triangles[t][0]];
    const Vec3f& b = fp[triangles[t][1]];
    const Vec3f& d = fp[triangles[t][2]];
    for (int k = 0; k < 3; ++k) c[t][k] = (a[k] + b[k] + d[k]) * (1.0f / 3.0f);
  }
}

void triangle_boxes_and_centroids(std::span<const Vec3f> fp, std::span<const Tri> triangles, std::span<Box3f> boxes,
                                  std::span<Vec3f> centroids) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size(), kPointsPerTask),
                    [&](const tbb::blocked_range<std::size_t>& r) {
    const __m128 third = _mm_set1_ps(1.0f / 3.0f);
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      const __m128 a = load3(fp[triangles[t][0]]), b = load3(fp[triangles[t][1]]), c = load3(fp[triangles[t][2]]);
      store_box(boxes[t], _mm_min_ps(_mm_min_ps(a, b), c), _mm_max_ps(_mm_max_ps(a, b), c));
      // (a + b + c) * (1/3), per lane in triangle_centroids' order: the same bits
      alignas(16) float m[4];
      _mm_store_ps(m, _mm_mul_ps(_mm_add_ps(_mm_add_ps(a, b), c), third));
      centroids[t] = {m[0], m[1], m[2]};
    }
  });
}

std::vector<Vec3f> triangle_centroids(std::span<const Vec3f> fp, std::span<const Tri> triangles) {
  std::vector<Vec3f> c(triangles.size());
  triangle_centroids(fp, triangles, c);
  return c;
}

Box3f union_of(std::span<const Box3f> boxes) {
  Box3f u;
  for (const Box3f& b : boxes) u.extend(b);
  return u;
}

}  // namespace ptc::bvh
