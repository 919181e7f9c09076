#include "bvh/vertex_order.h"

#include <immintrin.h>  // SSE2 (the x86-64 baseline); AVX2 only in own_range_avx2

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <limits>
#include <stdexcept>
#include <string>

#include "bvh/box_simd.h"

namespace ptc::bvh {

const char* to_string(VertexOrder o) { return o == VertexOrder::Clusters ? "clusters" : "input"; }

std::optional<VertexOrder> parse_vertex_order(std::string_view s) {
  if (s == "clusters") return VertexOrder::Clusters;
  if (s == "input") return VertexOrder::Input;
  return std::nullopt;
}


namespace {

/// Groups (clusters) per task of the fused per-frame pass: about 60k vertices, 0.1-0.2 ms of work.
constexpr std::size_t kGroupsPerTask = 2048;
/// Vertices per task of the streamed conversion (frame_positions_streamed): 1.5 MB of input.
constexpr std::size_t kVerticesPerTask = 65536;

// Four vertices as 48 contiguous bytes in three registers, lanes (x y z x)(y z x y)(z x y z),
// reduced per register by `op` (min or max) and folded back to one (x y z .) row: a, (a3 b0 b1),
// (b2 b3 c0), (c1 c2 c3).
inline __m128 min_ps(__m128 x, __m128 y) { return _mm_min_ps(x, y); }
inline __m128 max_ps(__m128 x, __m128 y) { return _mm_max_ps(x, y); }
inline __m128 fold_rows(__m128 a, __m128 b, __m128 c, __m128 (*op)(__m128, __m128)) {
  const __m128 t = _mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 0, 3, 3));
  const __m128 r1 = _mm_shuffle_ps(t, t, _MM_SHUFFLE(3, 3, 2, 0));
  const __m128 r2 = _mm_shuffle_ps(b, c, _MM_SHUFFLE(0, 0, 3, 2));
  const __m128 r3 = _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 2, 1));
  return op(op(a, r1), op(r2, r3));
}

}  // namespace

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

void frame_positions(std::span<const Vec3> positions, std::span<const std::uint32_t> to_old, const FrameMap& origin,
                     AlignedVector<Vec3f>& out) {
  out.reserve(to_old.size() + 2);  // room for add_sentinel's two entries: no second array
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

void point_group_boxes(std::span<const Vec3f> fp, const GroupVertexOrder& order, AlignedVector<Box3f>& out,
                       AlignedVector<Vec3f>& centers) {
  const std::size_t groups = order.own_offsets.empty() ? 0 : order.own_offsets.size() - 1;
  out.resize(groups);
  centers.resize(groups);
  const simd::VertexLoader load(fp);
  const float* base = fp.empty() ? nullptr : fp[0].data();
  for (std::size_t g = 0; g < groups; ++g) {
    std::uint32_t i = order.own_offsets[g];
    const std::uint32_t end = order.own_offsets[g + 1];
    const std::uint32_t s0 = order.shared_offsets[g], s1 = order.shared_offsets[g + 1];
    if (i == end && s0 == s1) {
      simd::store_empty(out[g], centers[g]);
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
      lo = fold_rows(la, lb, lc, min_ps), hi = fold_rows(ha, hb, hc, max_ps);
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
    // Min and max are exact and, on NaN-free values, independent of the order up to the sign of
    // zero, which the widening erases (+-0 -> -+denorm_min): the same bits as the plain version.
    simd::store_widened(_mm_min_ps(lo, lo1), _mm_max_ps(hi, hi1), out[g], centers[g]);
  }
}

std::optional<GroupRuns> group_runs(const GroupVertexOrder& order) {
  const std::size_t groups = order.own_offsets.empty() ? 0 : order.own_offsets.size() - 1;
  const std::size_t V = order.to_old.size();
  GroupRuns r;
  r.vertex_count = V;
  r.own_begin.resize(groups);
  r.own_count.resize(groups);
  std::vector<std::uint8_t> owned(V, 0);
  for (std::size_t g = 0; g < groups; ++g) {
    const std::uint32_t a = order.own_offsets[g], b = order.own_offsets[g + 1];
    r.own_begin[g] = a < b ? order.to_old[a] : 0;
    r.own_count[g] = b - a;
    for (std::uint32_t i = a; i < b; ++i) {
      if (order.to_old[i] != r.own_begin[g] + (i - a)) return std::nullopt;
      owned[order.to_old[i]] = 1;
    }
  }
  r.shared_offsets = order.shared_offsets;
  r.shared.resize(order.shared.size());
  for (std::size_t k = 0; k < order.shared.size(); ++k) r.shared[k] = order.to_old[order.shared[k]];
  for (std::uint32_t v = 0; v < V;) {
    if (owned[v]) {
      ++v;
      continue;
    }
    std::uint32_t e = v;
    while (e < V && !owned[e]) ++e;
    r.gaps.emplace_back(v, e);
    v = e;
  }
  return r;
}

std::vector<std::uint32_t> cluster_vertex_order(std::size_t vertex_count, std::span<const std::uint32_t> offsets,
                                                std::span<const std::uint32_t> indices,
                                                std::span<const std::size_t> part_offsets) {
  GroupVertexOrder o = first_touch_order(vertex_count, offsets, indices);
  if (part_offsets.empty()) return std::move(o.to_old);
  if (part_offsets.front() != 0 || part_offsets.back() != vertex_count)
    throw std::invalid_argument("cluster_vertex_order: part offsets do not span the " + std::to_string(vertex_count) +
                                " vertices");
  for (std::size_t p = 0; p + 1 < part_offsets.size(); ++p)
    if (part_offsets[p + 1] < part_offsets[p])
      throw std::invalid_argument("cluster_vertex_order: part offsets decrease at part " + std::to_string(p));
  // Stable by part: within a part the first-touch order (then its untouched vertices), and part
  // p lands exactly on [part_offsets[p], part_offsets[p+1]).
  std::vector<std::uint32_t> part_of(vertex_count);
  for (std::size_t p = 0; p + 1 < part_offsets.size(); ++p)
    for (std::size_t v = part_offsets[p]; v < part_offsets[p + 1]; ++v) part_of[v] = static_cast<std::uint32_t>(p);
  std::vector<std::size_t> next(part_offsets.begin(), part_offsets.end() - 1);
  std::vector<std::uint32_t> to_old(vertex_count);
  for (std::uint32_t v : o.to_old) to_old[next[part_of[v]]++] = v;
  return to_old;
}

namespace {

// to_frame(p, frame) as (x, y, z, 0): the same double subtraction, product by the (power of
// two) scale and round-to-nearest.
inline __m128 convert(const double* d, __m128d oxy, __m128d oz, __m128d s) {
  const __m128d xy = _mm_mul_pd(_mm_sub_pd(_mm_loadu_pd(d), oxy), s);
  const __m128d z = _mm_mul_sd(_mm_sub_sd(_mm_load_sd(d + 2), oz), s);
  return _mm_movelh_ps(_mm_cvtpd_ps(xy), _mm_cvtpd_ps(z));
}
// Exactly 12 bytes (the next vertex may belong to a group converted earlier).
inline void store3(float* q, __m128 v) {
  _mm_storel_pi(reinterpret_cast<__m64*>(q), v);
  _mm_store_ss(q + 2, _mm_movehl_ps(v, v));
}

// A group's own vertices [b, b + n): converted, stored, and their min / max (x y z .) returned.
// `bad` collects x - x of every converted value: NaN in some lane iff a value is not finite.
using OwnRangeFn = void (*)(const double* in, float* out, std::uint32_t n, const FrameMap& frame, __m128& lo,
                            __m128& hi, __m128& bad);

void own_range_sse2(const double* in, float* q, std::uint32_t n, const FrameMap& frame, __m128& lo, __m128& hi,
                    __m128& bad) {
  const Vec3& origin = frame.origin;
  const __m128d oxy = _mm_setr_pd(origin.x(), origin.y()), oz = _mm_set_sd(origin.z()), s = _mm_set1_pd(frame.scale);
  __m128 lo1 = lo, hi1 = hi;
  std::uint32_t i = 0;
  for (; i + 1 < n; i += 2) {  // two independent min/max chains
    const __m128 p = convert(in + 3 * std::size_t(i), oxy, oz, s);
    const __m128 r = convert(in + 3 * std::size_t(i) + 3, oxy, oz, s);
    store3(q + 3 * std::size_t(i), p), store3(q + 3 * std::size_t(i) + 3, r);
    lo = _mm_min_ps(lo, p), hi = _mm_max_ps(hi, p), lo1 = _mm_min_ps(lo1, r), hi1 = _mm_max_ps(hi1, r);
    bad = _mm_or_ps(bad, _mm_or_ps(_mm_sub_ps(p, p), _mm_sub_ps(r, r)));
  }
  if (i < n) {
    const __m128 p = convert(in + 3 * std::size_t(i), oxy, oz, s);
    store3(q + 3 * std::size_t(i), p);
    lo = _mm_min_ps(lo, p), hi = _mm_max_ps(hi, p);
    bad = _mm_or_ps(bad, _mm_sub_ps(p, p));
  }
  lo = _mm_min_ps(lo, lo1), hi = _mm_max_ps(hi, hi1);
}

// The same with AVX: four vertices (12 doubles) per step in three 4-wide conversions
// (convert4_avx2), which land as three (x y z x)(y z x y)(z x y z) float rows stored as 48
// contiguous bytes. The last step ends at the range's end and may overlap the previous one (same
// values stored again; min and max are idempotent). Ranges of fewer than four take the SSE2
// path. Same roundings, same bits.
struct Rows3 {
  __m128 la, lb, lc, ha, hb, hc, bad;
};
// The origin as the three rows of four doubles that four vertices' 12 coordinates meet, and the scale.
struct FrameRows4 {
  __m256d o0, o1, o2, s;
};
__attribute__((target("avx2"))) inline void frame_rows4(const FrameMap& frame, FrameRows4& f) {
  const Vec3& o = frame.origin;
  f.o0 = _mm256_setr_pd(o.x(), o.y(), o.z(), o.x());
  f.o1 = _mm256_setr_pd(o.y(), o.z(), o.x(), o.y());
  f.o2 = _mm256_setr_pd(o.z(), o.x(), o.y(), o.z());
  f.s = _mm256_set1_pd(frame.scale);
}
// Four vertices (12 doubles at p) converted into the rows a, b, c.
__attribute__((target("avx2"))) inline void convert4_avx2(const double* p, const FrameRows4& f, __m128& a, __m128& b,
                                                           __m128& c) {
  a = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(p), f.o0), f.s));
  b = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(p + 4), f.o1), f.s));
  c = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_sub_pd(_mm256_loadu_pd(p + 8), f.o2), f.s));
}
// x - x of every value of the rows into bad (NaN in some lane iff a value is not finite).
inline void collect_bad(__m128 a, __m128 b, __m128 c, __m128& bad) {
  bad = _mm_or_ps(bad, _mm_or_ps(_mm_sub_ps(a, a), _mm_or_ps(_mm_sub_ps(b, b), _mm_sub_ps(c, c))));
}
// (every lane of the rows is data: fold lane 3 into lane 0, since the callers test lanes 0-2)
inline __m128 fold_bad(__m128 rows_bad) {
  return _mm_or_ps(rows_bad, _mm_shuffle_ps(rows_bad, rows_bad, _MM_SHUFFLE(0, 0, 0, 3)));
}
__attribute__((target("avx2"))) inline void own_step_avx2(const double* p, float* d, const FrameRows4& f, Rows3& r) {
  __m128 a, b, c;
  convert4_avx2(p, f, a, b, c);
  _mm_storeu_ps(d, a), _mm_storeu_ps(d + 4, b), _mm_storeu_ps(d + 8, c);
  r.la = _mm_min_ps(r.la, a), r.lb = _mm_min_ps(r.lb, b), r.lc = _mm_min_ps(r.lc, c);
  r.ha = _mm_max_ps(r.ha, a), r.hb = _mm_max_ps(r.hb, b), r.hc = _mm_max_ps(r.hc, c);
  collect_bad(a, b, c, r.bad);
}

__attribute__((target("avx2"))) void own_range_avx2(const double* in, float* q, std::uint32_t n, const FrameMap& frame,
                                                     __m128& lo, __m128& hi, __m128& bad) {
  if (n < 4) return own_range_sse2(in, q, n, frame, lo, hi, bad);
  FrameRows4 f;
  frame_rows4(frame, f);
  Rows3 r{_mm_set1_ps(kInf),  _mm_set1_ps(kInf),  _mm_set1_ps(kInf), _mm_set1_ps(-kInf),
          _mm_set1_ps(-kInf), _mm_set1_ps(-kInf), bad};
  std::uint32_t i = 0;
  for (; i + 4 < n; i += 4) own_step_avx2(in + 3 * std::size_t(i), q + 3 * std::size_t(i), f, r);
  own_step_avx2(in + 3 * std::size_t(n - 4), q + 3 * std::size_t(n - 4), f, r);
  lo = _mm_min_ps(lo, fold_rows(r.la, r.lb, r.lc, min_ps)), hi = _mm_max_ps(hi, fold_rows(r.ha, r.hb, r.hc, max_ps));
  bad = fold_bad(r.bad);
}

// frame_positions_streamed's AVX2 loop: convert4_avx2's four vertices stored as three 16-byte
// streaming stores (the vertices before the first 16-byte boundary, and those after the last
// whole step of four, take the SSE2 path's ordinary stores), without the min / max nobody
// reads. The output is read next by the fill, which finds it in memory as fast as in the cache
// while the input stays there: ordinary stores read every line for ownership first (twist at one
// thread: the stage 0.39-0.49 -> 0.27-0.31 ms, docs/tracing.md). Fenced at the end, so the
// caller's next reads see it.
__attribute__((target("avx2"))) void stream_range_avx2(const double* in, float* q, std::uint32_t n,
                                                        const FrameMap& frame, __m128& bad) {
  FrameRows4 f;
  frame_rows4(frame, f);
  __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf);  // (the SSE2 path's, not read)
  std::uint32_t i = 0;
  while (i < n && (reinterpret_cast<std::uintptr_t>(q + 3 * std::size_t(i)) & 15)) ++i;
  if (i) own_range_sse2(in, q, i, frame, lo, hi, bad);
  __m128 rows_bad = _mm_setzero_ps();
  for (; i + 4 <= n; i += 4) {
    float* d = q + 3 * std::size_t(i);
    __m128 a, b, c;
    convert4_avx2(in + 3 * std::size_t(i), f, a, b, c);
    _mm_stream_ps(d, a), _mm_stream_ps(d + 4, b), _mm_stream_ps(d + 8, c);
    collect_bad(a, b, c, rows_bad);
  }
  bad = _mm_or_ps(bad, fold_bad(rows_bad));
  if (i < n) own_range_sse2(in + 3 * std::size_t(i), q + 3 * std::size_t(i), n - i, frame, lo, hi, bad);
  _mm_sfence();
}

}  // namespace

void frame_positions_streamed(std::span<const Vec3> positions, const FrameMap& frame, std::span<Vec3f> out_pos,
                              bool allow_avx2) {
  const bool avx2 = allow_avx2 && simd::cpu_has_avx2();
  if (out_pos.size() < positions.size())
    throw std::invalid_argument("frame_positions_streamed: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(out_pos.size()) + " outputs");
  const std::size_t V = positions.size();
  if (V == 0) return;
  const double* in = positions[0].data();
  float* base = out_pos[0].data();
  std::atomic<bool> any_bad{false};
  // Chunks of vertices on the caller's threads; each value is converted alone, so the same bits
  // at any count. (The min / max the range function takes is not used here.)
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, V, kVerticesPerTask), [&](const tbb::blocked_range<std::size_t>& r) {
    __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf), bad = _mm_setzero_ps();
    const auto n = static_cast<std::uint32_t>(r.size());
    if (avx2) stream_range_avx2(in + 3 * r.begin(), base + 3 * r.begin(), n, frame, bad);
    else own_range_sse2(in + 3 * r.begin(), base + 3 * r.begin(), n, frame, lo, hi, bad);
    if (_mm_movemask_ps(_mm_cmpunord_ps(bad, bad)) & 7) any_bad.store(true, std::memory_order_relaxed);
  });
  if (any_bad.load()) throw_not_finite(positions, frame);
}

void frame_positions_and_boxes(std::span<const Vec3> positions, const FrameMap& frame, const GroupRuns& runs,
                               std::span<Vec3f> out_pos, AlignedVector<Box3f>& out, AlignedVector<Vec3f>& centers,
                               bool allow_avx2) {
  const OwnRangeFn own_range = allow_avx2 && simd::cpu_has_avx2() ? &own_range_avx2 : &own_range_sse2;
  if (positions.size() != runs.vertex_count || out_pos.size() < positions.size())
    throw std::invalid_argument("frame_positions_and_boxes: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(runs.vertex_count) + " vertices (" + std::to_string(out_pos.size()) +
                                " outputs)");
  const std::size_t groups = runs.own_begin.size();
  out.resize(groups);
  centers.resize(groups);
  const Vec3& origin = frame.origin;
  const __m128d oxy = _mm_setr_pd(origin.x(), origin.y()), oz = _mm_set_sd(origin.z()), s = _mm_set1_pd(frame.scale);
  const Vec3* in = positions.data();
  float* base = out_pos.empty() ? nullptr : out_pos[0].data();
  // Groups are independent (own ranges are disjoint and stored exactly, shared vertices only
  // read), so chunks of groups run on the caller's threads: the same outputs at any count.
  std::atomic<bool> any_bad{false};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups, kGroupsPerTask), [&](const tbb::blocked_range<std::size_t>& r) {
    __m128 bad = _mm_setzero_ps();
    for (std::size_t g = r.begin(); g < r.end(); ++g) {
      const std::uint32_t b = runs.own_begin[g], n = runs.own_count[g];
      const std::uint32_t s0 = runs.shared_offsets[g], s1 = runs.shared_offsets[g + 1];
      if (n == 0 && s0 == s1) {
        simd::store_empty(out[g], centers[g]);
        continue;
      }
      __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf), lo1 = lo, hi1 = hi;
      if (n) own_range(in[b].data(), base + 3 * std::size_t(b), n, frame, lo, hi, bad);
      // Shared vertices (owned by earlier groups) are converted again from the input rather than
      // read back from out_pos: the same bits, and no 16-byte load across the two recent stores
      // of a vertex (a failed store-to-load forwarding stalled half of this loop).
      for (std::uint32_t k = s0; k < s1; ++k) {
        const __m128 p = convert(in[runs.shared[k]].data(), oxy, oz, s);
        lo1 = _mm_min_ps(lo1, p), hi1 = _mm_max_ps(hi1, p);
      }
      simd::store_widened(_mm_min_ps(lo, lo1), _mm_max_ps(hi, hi1), out[g], centers[g]);
    }
    if (_mm_movemask_ps(_mm_cmpunord_ps(bad, bad)) & 7) any_bad.store(true, std::memory_order_relaxed);
  });
  __m128 bad = _mm_setzero_ps();
  for (const auto& [a, e] : runs.gaps)
    for (std::uint32_t v = a; v < e; ++v) {
      const __m128 p = convert(in[v].data(), oxy, oz, s);
      store3(base + 3 * std::size_t(v), p);
      bad = _mm_or_ps(bad, _mm_sub_ps(p, p));
    }
  if (any_bad.load() || (_mm_movemask_ps(_mm_cmpunord_ps(bad, bad)) & 7)) throw_not_finite(positions, frame);
}

}  // namespace ptc::bvh
