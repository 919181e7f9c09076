#include "bvh/box.h"

#include <emmintrin.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace ptc::bvh {

std::vector<Box3f> triangle_boxes(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                  const Vec3& origin) {
  std::vector<Box3f> boxes(triangles.size());
  const double ox = origin.x(), oy = origin.y(), oz = origin.z();
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3& a = positions[triangles[t][0]];
    const Vec3& b = positions[triangles[t][1]];
    const Vec3& c = positions[triangles[t][2]];
    // Min/max first in double (exact), then one outward rounding per bound.
    Box3f& box = boxes[t];
    box.lo = {round_down(std::min({a.x(), b.x(), c.x()}) - ox), round_down(std::min({a.y(), b.y(), c.y()}) - oy),
              round_down(std::min({a.z(), b.z(), c.z()}) - oz)};
    box.hi = {round_up(std::max({a.x(), b.x(), c.x()}) - ox), round_up(std::max({a.y(), b.y(), c.y()}) - oy),
              round_up(std::max({a.z(), b.z(), c.z()}) - oz)};
  }
  return boxes;
}

std::vector<Box3f> point_group_boxes(std::span<const Vec3> positions, std::span<const std::uint32_t> offsets,
                                     std::span<const std::uint32_t> indices, const Vec3& origin) {
  const std::size_t groups = offsets.empty() ? 0 : offsets.size() - 1;
  std::vector<Box3f> boxes(groups);
  constexpr double inf = std::numeric_limits<double>::infinity();
  for (std::size_t g = 0; g < groups; ++g) {
    double lx = inf, ly = inf, lz = inf, hx = -inf, hy = -inf, hz = -inf;
    for (std::uint32_t i = offsets[g]; i < offsets[g + 1]; ++i) {
      const Vec3& p = positions[indices[i]];
      lx = std::min(lx, p.x()), ly = std::min(ly, p.y()), lz = std::min(lz, p.z());
      hx = std::max(hx, p.x()), hy = std::max(hy, p.y()), hz = std::max(hz, p.z());
    }
    if (offsets[g] == offsets[g + 1]) continue;  // empty group: empty box
    boxes[g].lo = {round_down(lx - origin.x()), round_down(ly - origin.y()), round_down(lz - origin.z())};
    boxes[g].hi = {round_up(hx - origin.x()), round_up(hy - origin.y()), round_up(hz - origin.z())};
  }
  return boxes;
}

std::vector<Vec3f> box_centers(std::span<const Box3f> boxes) {
  std::vector<Vec3f> c(boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) c[i] = boxes[i].center();
  return c;
}

std::vector<Vec3f> triangle_centroids(std::span<const Vec3> positions, std::span<const Tri> triangles,
                                      const Vec3& origin) {
  std::vector<Vec3f> c(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3 m = (positions[triangles[t][0]] + positions[triangles[t][1]] + positions[triangles[t][2]]) / 3.0;
    c[t] = to_frame(m, origin);
  }
  return c;
}

void frame_positions(std::span<const Vec3> positions, const Vec3& origin, std::vector<Vec3f>& out) {
  out.resize(positions.size());
  for (std::size_t v = 0; v < positions.size(); ++v) out[v] = to_frame(positions[v], origin);
}

namespace {

// (x, y, z, 0) from a float triple, reading exactly 12 bytes.
inline __m128 load3(const Vec3f& p) {
  double xy_bits;  // memcpy: a float triple is only 4-byte aligned (compiles to one movsd)
  std::memcpy(&xy_bits, p.data(), sizeof xy_bits);
  const __m128 xy = _mm_castpd_ps(_mm_set_sd(xy_bits));
  return _mm_movelh_ps(xy, _mm_load_ss(p.data() + 2));
}

// next_below / next_above of four finite floats at once (see box.h): on the bit pattern,
// -1 for positive, +1 for negative values, and +-0 to -+denorm_min.
inline __m128 widen_down(__m128 x) {
  const __m128i b = _mm_castps_si128(x);
  const __m128i step = _mm_or_si128(_mm_slli_epi32(_mm_srai_epi32(b, 31), 1), _mm_set1_epi32(1));  // +1 / -1
  const __m128 r = _mm_castsi128_ps(_mm_sub_epi32(b, step));
  const __m128 zero = _mm_cmpeq_ps(x, _mm_setzero_ps());
  return _mm_or_ps(_mm_andnot_ps(zero, r), _mm_and_ps(zero, _mm_set1_ps(-std::numeric_limits<float>::denorm_min())));
}
inline __m128 widen_up(__m128 x) {
  const __m128i b = _mm_castps_si128(x);
  const __m128i step = _mm_or_si128(_mm_slli_epi32(_mm_srai_epi32(b, 31), 1), _mm_set1_epi32(1));
  const __m128 r = _mm_castsi128_ps(_mm_add_epi32(b, step));
  const __m128 zero = _mm_cmpeq_ps(x, _mm_setzero_ps());
  return _mm_or_ps(_mm_andnot_ps(zero, r), _mm_and_ps(zero, _mm_set1_ps(std::numeric_limits<float>::denorm_min())));
}

inline void store_box(Box3f& box, __m128 lo, __m128 hi) {
  alignas(16) float l[4], h[4];
  _mm_store_ps(l, widen_down(lo)), _mm_store_ps(h, widen_up(hi));
  box.lo = {l[0], l[1], l[2]}, box.hi = {h[0], h[1], h[2]};
}

}  // namespace

std::vector<Box3f> triangle_boxes(std::span<const Vec3f> fp, std::span<const Tri> triangles) {
  std::vector<Box3f> boxes(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const __m128 a = load3(fp[triangles[t][0]]), b = load3(fp[triangles[t][1]]), c = load3(fp[triangles[t][2]]);
    store_box(boxes[t], _mm_min_ps(_mm_min_ps(a, b), c), _mm_max_ps(_mm_max_ps(a, b), c));
  }
  return boxes;
}

void point_group_boxes(std::span<const Vec3f> fp, std::span<const std::uint32_t> offsets,
                       std::span<const std::uint32_t> indices, std::vector<Box3f>& out) {
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
                       std::span<const std::uint32_t> indices, std::vector<Box3f>& out, std::vector<Vec3f>& centers) {
  const std::size_t groups = offsets.empty() ? 0 : offsets.size() - 1;
  out.resize(groups);
  centers.resize(groups);
  // A 16-byte load at vertex v reads x, y, z of v and x of v + 1: allowed for every vertex but
  // the last (lane 3 is never stored).
  const std::size_t wide_ok = fp.empty() ? 0 : fp.size() - 1;
  auto load = [&](std::uint32_t v) { return v < wide_ok ? _mm_loadu_ps(fp[v].data()) : load3(fp[v]); };
  for (std::size_t g = 0; g < groups; ++g) {
    std::uint32_t i = offsets[g];
    const std::uint32_t end = offsets[g + 1];
    if (i == end) {
      out[g] = Box3f{};
      centers[g] = out[g].center();
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
    const __m128 lo = widen_down(_mm_min_ps(lo0, lo1)), hi = widen_up(_mm_max_ps(hi0, hi1));
    alignas(16) float l[4], h[4], c[4];
    _mm_store_ps(l, lo), _mm_store_ps(h, hi);
    _mm_store_ps(c, _mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(lo, hi)));  // = Box3f::center()
    out[g].lo = {l[0], l[1], l[2]}, out[g].hi = {h[0], h[1], h[2]};
    centers[g] = {c[0], c[1], c[2]};
  }
}

GroupVertexOrder first_touch_order(std::size_t vertex_count, std::span<const std::uint32_t> offsets,
                                   std::span<const std::uint32_t> indices) {
  const std::size_t groups = offsets.empty() ? 0 : offsets.size() - 1;
  if (!offsets.empty() && (offsets.front() != 0 || offsets.back() != indices.size()))
    throw std::invalid_argument("first_touch_order: offsets do not span the " + std::to_string(indices.size()) +
                                " indices");
  if (vertex_count >= std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("first_touch_order: too many vertices");
  constexpr std::uint32_t none = std::numeric_limits<std::uint32_t>::max();
  GroupVertexOrder o;
  o.to_new.assign(vertex_count, none);
  o.to_old.reserve(vertex_count);
  o.own_offsets.assign(groups + 1, 0);
  o.shared_offsets.assign(groups + 1, 0);
  std::vector<std::uint32_t> last_group(vertex_count, none);  // the last group that listed a shared vertex
  for (std::size_t g = 0; g < groups; ++g) {
    if (offsets[g + 1] < offsets[g])
      throw std::invalid_argument("first_touch_order: offsets decrease at group " + std::to_string(g));
    const auto first_own = static_cast<std::uint32_t>(o.to_old.size());
    for (std::uint32_t i = offsets[g]; i < offsets[g + 1]; ++i) {
      const std::uint32_t v = indices[i];
      if (v >= vertex_count)
        throw std::invalid_argument("first_touch_order: index " + std::to_string(v) + " at " + std::to_string(i) +
                                    " >= vertex count " + std::to_string(vertex_count));
      if (o.to_new[v] == none) {
        o.to_new[v] = static_cast<std::uint32_t>(o.to_old.size());
        o.to_old.push_back(v);
      } else if (o.to_new[v] < first_own) {
        if (last_group[v] != g) last_group[v] = static_cast<std::uint32_t>(g), o.shared.push_back(o.to_new[v]);
      }
    }
    o.own_offsets[g + 1] = static_cast<std::uint32_t>(o.to_old.size());
    o.shared_offsets[g + 1] = static_cast<std::uint32_t>(o.shared.size());
  }
  for (std::uint32_t v = 0; v < vertex_count; ++v)
    if (o.to_new[v] == none) o.to_new[v] = static_cast<std::uint32_t>(o.to_old.size()), o.to_old.push_back(v);
  return o;
}

void frame_positions(std::span<const Vec3> positions, std::span<const std::uint32_t> to_old, const Vec3& origin,
                     std::vector<Vec3f>& out) {
  out.resize(to_old.size());
  const std::size_t n = to_old.size();
  constexpr std::size_t ahead = 16;  // a gather: the positions are fetched ahead (24 bytes, <= 2 lines)
  for (std::size_t i = 0; i < n; ++i) {
    if (i + ahead < n) {
      const char* q = reinterpret_cast<const char*>(positions.data() + to_old[i + ahead]);
      _mm_prefetch(q, _MM_HINT_T0), _mm_prefetch(q + 23, _MM_HINT_T0);
    }
    out[i] = to_frame(positions[to_old[i]], origin);
  }
}

void point_group_boxes(std::span<const Vec3f> fp, const GroupVertexOrder& order, std::vector<Box3f>& out,
                       std::vector<Vec3f>& centers) {
  const std::size_t groups = order.own_offsets.empty() ? 0 : order.own_offsets.size() - 1;
  out.resize(groups);
  centers.resize(groups);
  const std::size_t wide_ok = fp.empty() ? 0 : fp.size() - 1;  // see the other point_group_boxes
  auto load = [&](std::uint32_t v) { return v < wide_ok ? _mm_loadu_ps(fp[v].data()) : load3(fp[v]); };
  const float* base = fp.empty() ? nullptr : fp[0].data();
  for (std::size_t g = 0; g < groups; ++g) {
    std::uint32_t i = order.own_offsets[g];
    const std::uint32_t end = order.own_offsets[g + 1];
    const std::uint32_t s0 = order.shared_offsets[g], s1 = order.shared_offsets[g + 1];
    if (i == end && s0 == s1) {
      out[g] = Box3f{};
      centers[g] = out[g].center();
      continue;
    }
    // Four own vertices per step: 48 contiguous bytes in three loads, lanes (x y z x)(y z x y)(z x y z).
    // The last step ends at the range's end and may overlap the previous one (min and max are
    // idempotent), so there is no tail loop; ranges of fewer than four take single loads.
    __m128 la = _mm_set1_ps(kInf), lb = la, lc = la, ha = _mm_set1_ps(-kInf), hb = ha, hc = ha;
    __m128 lo = la, hi = ha, lo1 = la, hi1 = ha;
    if (end - i >= 4) {
      auto step = [&](std::uint32_t at) {
        const float* p = base + 3 * std::size_t(at);
        const __m128 a = _mm_loadu_ps(p), b = _mm_loadu_ps(p + 4), c = _mm_loadu_ps(p + 8);
        la = _mm_min_ps(la, a), lb = _mm_min_ps(lb, b), lc = _mm_min_ps(lc, c);
        ha = _mm_max_ps(ha, a), hb = _mm_max_ps(hb, b), hc = _mm_max_ps(hc, c);
      };
      for (; i + 4 < end; i += 4) step(i);
      step(end - 4);
      // Back to (x y z .) rows: a, (a3 b0 b1), (b2 b3 c0), (c1 c2 c3).
      auto rows = [](__m128 a, __m128 b, __m128 c, __m128 (*op)(__m128, __m128)) {
        const __m128 t = _mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 0, 3, 3));
        const __m128 r1 = _mm_shuffle_ps(t, t, _MM_SHUFFLE(3, 3, 2, 0));
        const __m128 r2 = _mm_shuffle_ps(b, c, _MM_SHUFFLE(0, 0, 3, 2));
        const __m128 r3 = _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 2, 1));
        return op(op(a, r1), op(r2, r3));
      };
      lo = rows(la, lb, lc, [](__m128 x, __m128 y) { return _mm_min_ps(x, y); });
      hi = rows(ha, hb, hc, [](__m128 x, __m128 y) { return _mm_max_ps(x, y); });
    } else {
      for (; i < end; ++i) {
        const __m128 p = load(i);
        lo = _mm_min_ps(lo, p), hi = _mm_max_ps(hi, p);
      }
    }
    // Shared vertices two at a time (two independent min/max chains).
    std::uint32_t k = s0;
    for (; k + 1 < s1; k += 2) {
      const __m128 p = load(order.shared[k]), q = load(order.shared[k + 1]);
      lo = _mm_min_ps(lo, p), hi = _mm_max_ps(hi, p);
      lo1 = _mm_min_ps(lo1, q), hi1 = _mm_max_ps(hi1, q);
    }
    if (k < s1) {
      const __m128 p = load(order.shared[k]);
      lo = _mm_min_ps(lo, p), hi = _mm_max_ps(hi, p);
    }
    lo = _mm_min_ps(lo, lo1), hi = _mm_max_ps(hi, hi1);
    // Min and max are exact and, on NaN-free values, independent of the order up to the sign of
    // zero, which the widening erases (+-0 -> -+denorm_min): the same bits as the plain version.
    lo = widen_down(lo), hi = widen_up(hi);
    alignas(16) float l[4], h[4], c[4];
    _mm_store_ps(l, lo), _mm_store_ps(h, hi);
    _mm_store_ps(c, _mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(lo, hi)));  // = Box3f::center()
    out[g].lo = {l[0], l[1], l[2]}, out[g].hi = {h[0], h[1], h[2]};
    centers[g] = {c[0], c[1], c[2]};
  }
}

std::vector<Vec3f> triangle_centroids(std::span<const Vec3f> fp, std::span<const Tri> triangles) {
  std::vector<Vec3f> c(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Vec3f& a = fp[triangles[t][0]];
    const Vec3f& b = fp[triangles[t][1]];
    const Vec3f& d = fp[triangles[t][2]];
    for (int k = 0; k < 3; ++k) c[t][k] = (a[k] + b[k] + d[k]) * (1.0f / 3.0f);
  }
  return c;
}

Box3f union_of(std::span<const Box3f> boxes) {
  Box3f u;
  for (const Box3f& b : boxes) u.extend(b);
  return u;
}

}  // namespace ptc::bvh
