#include "bvh/sah_builder.h"

#include <immintrin.h>  // SSE2 (the x86-64 baseline); AVX2 only in bin_range_avx2

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>

#include "bvh/aligned.h"

namespace ptc::bvh {

namespace {

// ------------------------------------------------------------------------------------------
// Shared skeleton: an explicit stack of pending subtrees, nodes emitted in depth-first
// pre-order (the first child is allocated right after its parent; the second child's index is
// patched into the parent when the second subtree is started).

struct CostAccumulator {  // sum of the tree's SAH terms (see sah_cost.h); divided by A(root) at the end
  double area_terms = 0.0;   // sum traversal * A(inner) + intersection * W * A(leaf)
  double count_terms = 0.0;  // the same sum with every A = 1 (used when A(root) = 0)
  void inner(const SahCostModel& m, double area) {
    area_terms += m.traversal * area;
    count_terms += m.traversal;
  }
  void leaf(const SahCostModel& m, double area, double weight) {
    area_terms += m.intersection * weight * area;
    count_terms += m.intersection * weight;
  }
  [[nodiscard]] double total(double root_area) const { return root_area > 0.0 ? area_terms / root_area : count_terms; }
};

double weight_of(const BuildInput& in, std::uint32_t prim) { return in.weights.empty() ? 1.0 : in.weights[prim]; }

// NaN in a box or centroid (comparisons with NaN break every ordering the builders rely on):
// std::invalid_argument naming the first such primitive. (The binned builder calls it only when
// its record pass saw a NaN.)
void check_no_nan(const BuildInput& in) {
  for (std::size_t i = 0; i < in.boxes.size(); ++i)
    for (int a = 0; a < 3; ++a)
      if (std::isnan(in.boxes[i].lo[a]) || std::isnan(in.boxes[i].hi[a]) || std::isnan(in.centroids[i][a]))
        throw std::invalid_argument("BVH build: the box or centroid of primitive " + std::to_string(i) + " holds NaN");
}

void check_input(const BuildInput& in, const BuildConfig& cfg) {
  assert(in.centroids.size() == in.boxes.size());
  assert(in.weights.empty() || in.weights.size() == in.boxes.size());
  assert(cfg.max_leaf_size >= 1);
  assert(cfg.bins >= 2 && cfg.bins <= 256);
  assert(cfg.cost.traversal > 0.0 && cfg.cost.intersection > 0.0);
  (void)in, (void)cfg;
}

// ------------------------------------------------------------------------------------------
// Full-sweep SAH.

struct SweepTask {
  std::uint32_t begin, end;
  std::uint32_t patch_parent;  // node whose `index` receives this subtree's root, or kNone
};
constexpr std::uint32_t kNone = 0xffffffffu;

}  // namespace

Bvh build_sweep_sah(const BuildInput& in, const BuildConfig& cfg) {
  check_input(in, cfg);
  check_no_nan(in);
  Bvh bvh;
  const auto n = static_cast<std::uint32_t>(in.boxes.size());
  if (n == 0) return bvh;
  bvh.prim_order.resize(n);
  std::iota(bvh.prim_order.begin(), bvh.prim_order.end(), 0u);
  bvh.nodes.reserve(2 * static_cast<std::size_t>(n));
  const SahCostModel& m = cfg.cost;
  CostAccumulator acc;
  std::vector<std::uint32_t> order(n);
  std::vector<double> suffix_area(n + 1), suffix_weight(n + 1);
  std::vector<SweepTask> stack{{0, n, kNone}};
  while (!stack.empty()) {
    const SweepTask task = stack.back();
    stack.pop_back();
    const auto idx = static_cast<std::uint32_t>(bvh.nodes.size());
    bvh.nodes.emplace_back();
    if (task.patch_parent != kNone) bvh.nodes[task.patch_parent].index = idx;
    std::uint32_t* prims = bvh.prim_order.data() + task.begin;
    const std::uint32_t count = task.end - task.begin;
    Box3f box;
    double weight = 0.0;
    for (std::uint32_t i = 0; i < count; ++i) box.extend(in.boxes[prims[i]]), weight += weight_of(in, prims[i]);
    bvh.nodes[idx].bounds = box;
    const double area = box.surface_area();
    const double leaf_cost = m.intersection * weight;

    // Best split over all axes and positions; split "after position k" of the sorted order.
    double best_cost = std::numeric_limits<double>::infinity();
    int best_axis = -1;
    std::uint32_t best_k = 0;
    if (count > 1 && area > 0.0) {
      for (int axis = 0; axis < 3; ++axis) {
        std::copy(prims, prims + count, order.begin());
        std::sort(order.begin(), order.begin() + count, [&](std::uint32_t a, std::uint32_t b) {
          const float ca = in.centroids[a][axis], cb = in.centroids[b][axis];
          return ca != cb ? ca < cb : a < b;
        });
        Box3f right;
        double wr = 0.0;
        for (std::uint32_t i = count; i-- > 0;) {
          right.extend(in.boxes[order[i]]);
          wr += weight_of(in, order[i]);
          suffix_area[i] = right.surface_area();
          suffix_weight[i] = wr;
        }
        Box3f left;
        double wl = 0.0;
        for (std::uint32_t k = 1; k < count; ++k) {  // left = order[0, k), right = order[k, count)
          left.extend(in.boxes[order[k - 1]]);
          wl += weight_of(in, order[k - 1]);
          const double c = m.traversal + m.intersection * (left.surface_area() * wl + suffix_area[k] * suffix_weight[k]) / area;
          if (c < best_cost) best_cost = c, best_axis = axis, best_k = k;
        }
      }
    }
    const bool must_split = count > cfg.max_leaf_size;
    if (count == 1 || (!must_split && leaf_cost <= best_cost)) {
      bvh.nodes[idx].index = task.begin;
      bvh.nodes[idx].count = count;
      acc.leaf(m, area, weight);
      continue;
    }
    std::uint32_t k = count / 2;  // no usable plane (zero-area node): object median in current order
    if (best_axis >= 0) {
      std::sort(prims, prims + count, [&](std::uint32_t a, std::uint32_t b) {
        const float ca = in.centroids[a][best_axis], cb = in.centroids[b][best_axis];
        return ca != cb ? ca < cb : a < b;
      });
      k = best_k;
    }
    acc.inner(m, area);
    stack.push_back({task.begin + k, task.end, idx});  // second child, patched into idx
    stack.push_back({task.begin, task.begin + k, kNone});  // first child = idx + 1
  }
  bvh.cost = acc.total(bvh.nodes[0].bounds.surface_area());
  return bvh;
}

// ------------------------------------------------------------------------------------------
// Binned SAH. Primitive references are copied into 48-byte records (box, id, weight, centroid)
// that are partitioned in place, so the hot loops stream through memory instead of gathering
// from the input spans. Records are only moved as three 16-byte rows (see load_ref). Per large
// node: one binning pass (which also stores each record's bins for the partition), a sweep over
// the bins, one partition pass (which also gathers the children's centroid bounds). Per small
// node: ranks by centroid (skipped when already in order), one right and one left sweep (which
// also give the records in order and the children's boxes), one copy back.

namespace {

struct alignas(16) Ref {
  float lo[3];
  std::uint32_t id;
  float hi[3];
  std::uint32_t weight;
  float c[3];
  std::uint32_t bins;  // scratch: the bins on x, y, z (one byte each) of the current node's binning
};
static_assert(sizeof(Ref) == 48);

struct BinnedTask {
  std::uint32_t begin, end, patch_parent;
  Box3f box;   // union of the primitive boxes
  Box3f cbox;  // bounds of the centroids, gathered by the parent's partition; empty: not known
  std::uint32_t groups = 0;  // 1: a range of group records (BuildInput::groups), 0: of primitives
};

constexpr std::uint32_t kMaxBins = 256;
constexpr std::uint32_t kSweepBelow = 16;   // nodes of at most this many primitives are swept exactly
constexpr std::uint32_t kTwoSetsFrom = 256;  // binning into two bin sets from this many primitives up (below: one)

// Per axis and bin: the box as eight floats, lo x y z . and -hi x y z . (the upper bound negated,
// so that one minimum updates both halves: one 8-wide min per axis and primitive with AVX, two
// 4-wide ones without; -max(a, b) = min(-a, -b) exactly, so both variants give the same bins).
struct Bins {
  alignas(32) float box[3][kMaxBins][8];
  std::uint32_t weight[3][kMaxBins];  // weights >= 1, so 0 means an empty bin

  [[nodiscard]] __m128 lo(int a, std::uint32_t b) const { return _mm_load_ps(box[a][b]); }
  [[nodiscard]] __m128 neg_hi(int a, std::uint32_t b) const { return _mm_load_ps(box[a][b] + 4); }
  void clear(std::uint32_t nbins) {
    const __m128 inf = _mm_set1_ps(kInf);
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t b = 0; b < nbins; ++b)
        _mm_store_ps(box[a][b], inf), _mm_store_ps(box[a][b] + 4, inf), weight[a][b] = 0;
  }
  void add(const std::int32_t* bin, __m128 l, __m128 nh, std::uint32_t w) {
    for (int a = 0; a < 3; ++a) {
      float* p = box[a][bin[a]];
      _mm_store_ps(p, _mm_min_ps(_mm_load_ps(p), l));
      _mm_store_ps(p + 4, _mm_min_ps(_mm_load_ps(p + 4), nh));
      weight[a][bin[a]] += w;
    }
  }
  void merge(const Bins& o, std::uint32_t nbins) {
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t b = 0; b < nbins; ++b) {
        float* p = box[a][b];
        const float* q = o.box[a][b];
        _mm_store_ps(p, _mm_min_ps(_mm_load_ps(p), _mm_load_ps(q)));
        _mm_store_ps(p + 4, _mm_min_ps(_mm_load_ps(p + 4), _mm_load_ps(q + 4)));
        weight[a][b] += o.weight[a][b];
      }
  }
};

// Lane 3 of the lo / hi rows holds the id / weight bits: small integers read as floats are
// denormals, and arithmetic on denormals takes a microcode assist (measured: 12% of the build in
// one multiply), so lane 3 is cleared on every load.
inline __m128 xyz_mask() { return _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)); }
inline __m128 load_lo(const Ref& r) { return _mm_and_ps(_mm_load_ps(r.lo), xyz_mask()); }
inline __m128 load_hi(const Ref& r) { return _mm_and_ps(_mm_load_ps(r.hi), xyz_mask()); }

// Whole-record moves as three 16-byte loads and stores (a struct copy may be split into 8- and
// 4-byte moves, and a later 16-byte load of the record then waits for them to retire: the
// store-to-load forwarding stall that cost 14% of the build in the partition loop).
struct RefBits {
  __m128 a, b, c;
};
inline RefBits load_ref(const Ref& x) { return {_mm_load_ps(x.lo), _mm_load_ps(x.hi), _mm_load_ps(x.c)}; }
inline void store_ref(Ref& x, const RefBits& v) { _mm_store_ps(x.lo, v.a), _mm_store_ps(x.hi, v.b), _mm_store_ps(x.c, v.c); }

inline Box3f to_box(__m128 lo, __m128 hi) {
  alignas(16) float l[4], h[4];
  _mm_store_ps(l, lo), _mm_store_ps(h, hi);
  return {{l[0], l[1], l[2]}, {h[0], h[1], h[2]}};
}

// Half the surface area, xy + yz + zx, of a non-empty box (lanes 0-2), in float: only compared.
inline float half_area(__m128 lo, __m128 hi) {
  const __m128 e = _mm_sub_ps(hi, lo);                                 // x y z .
  const __m128 r = _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1));       // y z x .
  const __m128 p = _mm_mul_ps(e, r);                                   // xy yz zx .
  const __m128 s = _mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 3, 3, 1)));
  return _mm_cvtss_f32(_mm_add_ss(s, _mm_movehl_ps(p, p)));
}

// A child's box, gathered while the primitives are put in place.
struct SideBounds {
  __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf);
  void add(const Ref& x) { lo = _mm_min_ps(lo, load_lo(x)), hi = _mm_max_ps(hi, load_hi(x)); }
};

// Ranks of r[0 .. count) by (centroid on axis a, position), count <= kSweepBelow: order[rank] = i.
// Branch-free, four comparisons per instruction (positions past count are padded with +inf and
// never counted, since their position is larger than every i).
constexpr std::uint8_t kBits4[16] = {0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};
// Returns true, with order = the identity, when r is already in that order: a child often is
// (its parent was swept along the same axis). The check runs over a fixed number of positions
// (padding +inf keeps the order), so it costs no mispredicted loop exit.
inline bool rank_by_centroid(const Ref* r, std::uint32_t count, int a, std::uint8_t* order) {
  alignas(16) float cs[kSweepBelow];
  for (std::uint32_t i = 0; i < kSweepBelow; ++i) cs[i] = i < count ? r[i].c[a] : kInf;
  bool in_order = true;
  for (std::uint32_t i = 1; i < kSweepBelow; ++i) in_order &= cs[i - 1] <= cs[i];
  if (in_order) {
    for (std::uint32_t i = 0; i < kSweepBelow; ++i) order[i] = static_cast<std::uint8_t>(i);
    return true;
  }
  const std::uint32_t q = (count + 3) / 4;
  __m128 cv[kSweepBelow / 4];
  __m128i pos[kSweepBelow / 4];
  for (std::uint32_t k = 0; k < q; ++k)
    cv[k] = _mm_load_ps(cs + 4 * k), pos[k] = _mm_setr_epi32(int(4 * k), int(4 * k + 1), int(4 * k + 2), int(4 * k + 3));
  for (std::uint32_t i = 0; i < count; ++i) {
    const __m128 ci = _mm_set1_ps(cs[i]);
    const __m128i ii = _mm_set1_epi32(static_cast<int>(i));
    int rank = 0;
    for (std::uint32_t k = 0; k < q; ++k) {
      const __m128 before = _mm_or_ps(_mm_cmplt_ps(cv[k], ci),
                                      _mm_and_ps(_mm_cmpeq_ps(cv[k], ci), _mm_castsi128_ps(_mm_cmplt_epi32(pos[k], ii))));
      rank += kBits4[_mm_movemask_ps(before)];  // (no POPCNT in the x86-64 baseline: a table)
    }
    order[rank] = static_cast<std::uint8_t>(i);
  }
  return false;
}

// The binning pass of a node: primitive i into b0 (even i) or b1 (odd i): two bin sets, since
// consecutive updates of the same bin would otherwise wait for each other through memory. The
// bins on x, y, z (the one bin formula: clamp((c - clo) * sc, 0, maxbin), truncated) are also
// kept in Ref::bins for the partition. Returns the summed weight.
struct BinParams {
  __m128 clo, sc, maxbin;
};

inline __m128i bins_of(__m128 c, const BinParams& p) {
  c = _mm_and_ps(c, xyz_mask());  // lane 3 holds Ref::bins
  return _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c, p.clo), p.sc), _mm_setzero_ps()), p.maxbin));
}
inline std::uint32_t pack_bins(__m128i b) {  // x | y << 8 | z << 16 (each in [0, 255])
  const __m128i y8 = _mm_slli_epi32(_mm_srli_si128(b, 4), 8), z16 = _mm_slli_epi32(_mm_srli_si128(b, 8), 16);
  return static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_or_si128(_mm_or_si128(b, y8), z16)));
}
inline __m128 negate(__m128 x) { return _mm_xor_ps(x, _mm_set1_ps(-0.0f)); }

std::uint64_t bin_range_sse2(Ref* r, std::uint32_t count, const BinParams& p, Bins& b0, Bins& b1) {
  std::uint64_t total = 0;
  for (std::uint32_t i = 0; i < count; ++i) {
    alignas(16) std::int32_t bi[4];
    const __m128i b = bins_of(_mm_load_ps(r[i].c), p);
    _mm_store_si128(reinterpret_cast<__m128i*>(bi), b);
    r[i].bins = pack_bins(b);
    (i & 1 ? b1 : b0).add(bi, load_lo(r[i]), negate(load_hi(r[i])), r[i].weight);
    total += r[i].weight;
  }
  return total;
}

__attribute__((target("avx2"))) inline void add8(Bins& bins, const std::int32_t* bi, __m256 v, std::uint32_t w) {
  for (int a = 0; a < 3; ++a) {
    float* q = bins.box[a][bi[a]];
    _mm256_store_ps(q, _mm256_min_ps(_mm256_load_ps(q), v));
    bins.weight[a][bi[a]] += w;
  }
}

// The same with AVX2 (only called when the CPU has it): the bin indices of two primitives per
// instruction, and one 8-wide min per axis and primitive. Same float operations, same bins.
__attribute__((target("avx2"))) std::uint64_t bin_range_avx2(Ref* r, std::uint32_t count, const BinParams& p,
                                                              Bins& b0, Bins& b1) {
  const __m256 clo = _mm256_broadcast_ps(&p.clo), sc = _mm256_broadcast_ps(&p.sc), maxbin = _mm256_broadcast_ps(&p.maxbin);
  const __m256 cmask = _mm256_castsi256_ps(_mm256_setr_epi32(-1, -1, -1, 0, -1, -1, -1, 0));
  // [lo | hi] of a record -> [lo | -hi], lanes 3 and 7 (id, weight) cleared
  const __m256 bmask = cmask;
  const __m256 sign = _mm256_setr_ps(0.0f, 0.0f, 0.0f, 0.0f, -0.0f, -0.0f, -0.0f, 0.0f);
  std::uint64_t total = 0;
  std::uint32_t i = 0;
  for (; i + 1 < count; i += 2) {
    const __m256 c = _mm256_and_ps(_mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(r[i].c)),
                                                        _mm_load_ps(r[i + 1].c), 1),
                                   cmask);
    const __m256i b = _mm256_cvttps_epi32(
        _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(c, clo), sc), _mm256_setzero_ps()), maxbin));
    alignas(32) std::int32_t bi[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(bi), b);
    r[i].bins = static_cast<std::uint32_t>(bi[0] | bi[1] << 8 | bi[2] << 16);
    r[i + 1].bins = static_cast<std::uint32_t>(bi[4] | bi[5] << 8 | bi[6] << 16);
    const __m256 v0 = _mm256_xor_ps(_mm256_and_ps(_mm256_loadu_ps(r[i].lo), bmask), sign);
    const __m256 v1 = _mm256_xor_ps(_mm256_and_ps(_mm256_loadu_ps(r[i + 1].lo), bmask), sign);
    add8(b0, bi, v0, r[i].weight);
    add8(b1, bi + 4, v1, r[i + 1].weight);
    total += r[i].weight + r[i + 1].weight;
  }
  if (i < count) {
    alignas(16) std::int32_t bi[4];
    const __m128i b = bins_of(_mm_load_ps(r[i].c), p);
    _mm_store_si128(reinterpret_cast<__m128i*>(bi), b);
    r[i].bins = pack_bins(b);
    add8(b0, bi, _mm256_xor_ps(_mm256_and_ps(_mm256_loadu_ps(r[i].lo), bmask), sign), r[i].weight);
    total += r[i].weight;
  }
  return total;
}

using BinRangeFn = std::uint64_t (*)(Ref*, std::uint32_t, const BinParams&, Bins&, Bins&);
BinRangeFn pick_bin_range() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") ? &bin_range_avx2 : &bin_range_sse2;
}

}  // namespace

struct BuildWorkspace::Impl {
  std::vector<Ref, AlignedAllocator<Ref>> refs;
  std::vector<Ref, AlignedAllocator<Ref>> group_refs;  // two-level build: one record per group
  std::vector<BinnedTask> stack;
  Bins bins[2];
};

BuildWorkspace::BuildWorkspace() : impl_(std::make_unique<Impl>()) {}
BuildWorkspace::~BuildWorkspace() = default;
BuildWorkspace::BuildWorkspace(const BuildWorkspace&) : impl_(std::make_unique<Impl>()) {}
BuildWorkspace& BuildWorkspace::operator=(const BuildWorkspace&) { return *this; }
BuildWorkspace::BuildWorkspace(BuildWorkspace&&) noexcept = default;
BuildWorkspace& BuildWorkspace::operator=(BuildWorkspace&&) noexcept = default;

Bvh build_binned_sah(const BuildInput& in, const BuildConfig& cfg) {
  Bvh bvh;
  BuildWorkspace ws;
  build_binned_sah(in, cfg, bvh, ws);
  return bvh;
}

void build_binned_sah(const BuildInput& in, const BuildConfig& cfg, Bvh& bvh, BuildWorkspace& ws) {
  check_input(in, cfg);
  bvh.nodes.clear();
  bvh.prim_order.clear();
  bvh.cost = 0.0;
  const auto n = static_cast<std::uint32_t>(in.boxes.size());
  if (n == 0) return;
  const SahCostModel& m = cfg.cost;
  if (!ws.impl_) ws.impl_ = std::make_unique<BuildWorkspace::Impl>();  // (a moved-from workspace)
  BuildWorkspace::Impl& w = *ws.impl_;

  w.refs.resize(n);
  Ref* const refs = w.refs.data();
  __m128 rlo = _mm_set1_ps(kInf), rhi = _mm_set1_ps(-kInf);
  // Records assembled in registers and written with whole 16-byte stores (field-by-field
  // stores followed by 16-byte loads defeat store-to-load forwarding: measured 6% of the build).
  static_assert(sizeof(Box3f) == 24 && sizeof(Vec3f) == 12);
  const float* bf = in.boxes.empty() ? nullptr : in.boxes[0].lo.data();
  const float* cf = in.centroids.empty() ? nullptr : in.centroids[0].data();
  const __m128 mask = xyz_mask();
  __m128 rclo = _mm_set1_ps(kInf), rchi = _mm_set1_ps(-kInf), nan = _mm_setzero_ps();
  for (std::uint32_t i = 0; i < n; ++i) {
    const __m128 l = _mm_and_ps(_mm_loadu_ps(bf + 6 * std::size_t(i)), mask);  // lo.xyz, (hi.x cleared)
    __m128 h = _mm_loadu_ps(bf + 6 * std::size_t(i) + 2);                      // lo.z, hi.xyz
    h = _mm_shuffle_ps(h, h, _MM_SHUFFLE(0, 3, 2, 1));                          // hi.xyz, lo.z
    h = _mm_and_ps(h, mask);
    // Centroid: a 16-byte load reads one float past the element, allowed but for the last one.
    __m128 c;
    if (i + 1 < n) {
      c = _mm_and_ps(_mm_loadu_ps(cf + 3 * std::size_t(i)), mask);
    } else {
      const Vec3f& v = in.centroids[i];
      c = _mm_setr_ps(v[0], v[1], v[2], 0.0f);
    }
    const std::uint32_t wt = in.weights.empty() ? 1u : in.weights[i];
    Ref& r = refs[i];
    _mm_store_ps(r.lo, _mm_or_ps(l, _mm_castsi128_ps(_mm_setr_epi32(0, 0, 0, static_cast<int>(i)))));
    _mm_store_ps(r.hi, _mm_or_ps(h, _mm_castsi128_ps(_mm_setr_epi32(0, 0, 0, static_cast<int>(wt)))));
    _mm_store_ps(r.c, c);
    rlo = _mm_min_ps(rlo, l), rhi = _mm_max_ps(rhi, h);
    rclo = _mm_min_ps(rclo, c), rchi = _mm_max_ps(rchi, c);
    nan = _mm_or_ps(nan, _mm_or_ps(_mm_cmpunord_ps(l, h), _mm_cmpunord_ps(c, c)));
  }
  if (_mm_movemask_ps(nan)) check_no_nan(in);
  bvh.nodes.reserve(2 * static_cast<std::size_t>(n));
  CostAccumulator acc;
  std::vector<BinnedTask>& stack = w.stack;
  stack.clear();
  const __m128 inf = _mm_set1_ps(kInf), ninf = _mm_set1_ps(-kInf);
  // Two-level build (BuildInput::groups): one record per group (the union of its primitives'
  // boxes, the box centre, the summed weight); the top levels split groups, and a node of one
  // group continues with the group's primitives (contiguous in refs).
  const std::size_t G = in.groups.empty() ? 0 : in.groups.size() - 1;
  if (!in.groups.empty() && (G == 0 || in.groups.front() != 0 || in.groups.back() != n))
    throw std::invalid_argument("build_binned_sah: group offsets do not span the " + std::to_string(n) + " primitives");
  if (G > 1) {
    w.group_refs.resize(G);
    __m128 gclo = inf, gchi = ninf;
    for (std::size_t g = 0; g < G; ++g) {
      const std::uint32_t a = in.groups[g], e = in.groups[g + 1];
      if (e <= a || e > n) throw std::invalid_argument("build_binned_sah: empty or decreasing group " + std::to_string(g));
      __m128 lo = inf, hi = ninf;
      std::uint64_t wt = 0;
      for (std::uint32_t i = a; i < e; ++i) {
        lo = _mm_min_ps(lo, load_lo(refs[i])), hi = _mm_max_ps(hi, load_hi(refs[i]));
        wt += refs[i].weight;
      }
      const __m128 c = _mm_and_ps(_mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(lo, hi)), mask);
      Ref& gr = w.group_refs[g];
      _mm_store_ps(gr.lo, _mm_or_ps(lo, _mm_castsi128_ps(_mm_setr_epi32(0, 0, 0, static_cast<int>(g)))));
      _mm_store_ps(gr.hi, _mm_or_ps(hi, _mm_castsi128_ps(_mm_setr_epi32(0, 0, 0, static_cast<int>(wt)))));
      _mm_store_ps(gr.c, c);
      gclo = _mm_min_ps(gclo, c), gchi = _mm_max_ps(gchi, c);
    }
    stack.push_back({0, static_cast<std::uint32_t>(G), kNone, to_box(rlo, rhi), to_box(gclo, gchi), 1});
  } else {
    stack.push_back({0, n, kNone, to_box(rlo, rhi), to_box(rclo, rchi), 0});
  }
  static const BinRangeFn best_bin_range = pick_bin_range();
  const BinRangeFn bin_range = cfg.allow_avx2 ? best_bin_range : &bin_range_sse2;

  while (!stack.empty()) {
    BinnedTask task = stack.back();
    stack.pop_back();
    if (task.groups && task.end - task.begin == 1) {  // one group: continue with its primitives
      const std::uint32_t g = w.group_refs[task.begin].id;
      task = {in.groups[g], in.groups[g + 1], task.patch_parent, task.box, Box3f{}, 0};
    }
    const auto idx = static_cast<std::uint32_t>(bvh.nodes.size());
    bvh.nodes.emplace_back();
    if (task.patch_parent != kNone) bvh.nodes[task.patch_parent].index = idx;
    bvh.nodes[idx].bounds = task.box;
    Ref* r = (task.groups ? w.group_refs.data() : refs) + task.begin;
    const std::uint32_t count = task.end - task.begin;
    const double area = task.box.surface_area();
    auto make_leaf = [&] {
      std::uint64_t wt = 0;
      for (std::uint32_t i = 0; i < count; ++i) wt += r[i].weight;
      bvh.nodes[idx].index = task.begin;
      bvh.nodes[idx].count = count;
      acc.leaf(m, area, static_cast<double>(wt));
    };
    if (count == 1) {
      make_leaf();
      continue;
    }
    const bool must_split = count > cfg.max_leaf_size || task.groups;  // (a leaf holds primitives, not groups)
    // Early leaf: every split costs at least traversal + intersection * sum_p A(p) w_p / A
    // (each primitive lies in a child whose area is at least its own), so a leaf that is no
    // dearer than that bound wins without evaluating any split.
    if (!must_split && area > 0.0) {
      double wt = 0.0, aw = 0.0;
      for (std::uint32_t i = 0; i < count; ++i) {
        wt += r[i].weight;
        aw += 2.0 * static_cast<double>(half_area(load_lo(r[i]), load_hi(r[i]))) * r[i].weight;
      }
      if (m.intersection * wt <= m.traversal + m.intersection * aw / area) {
        make_leaf();
        continue;
      }
    }

    // Split evaluation. Two primitives that must be split have one partition only: no search.
    // Small nodes: exact sweep over the primitives sorted by centroid on each axis (cheaper than
    // clearing and sweeping bins, and exact). Larger nodes: bins.
    const bool trivial = count == 2 && must_split;
    const bool small = count <= kSweepBelow;
    std::uint8_t order[3][kSweepBelow];
    bool sorted[3] = {false, false, false};  // order[a] is the identity
    RefBits swept[3][kSweepBelow];           // the records in order[a]
    SideBounds sweep_left, sweep_right;      // the children's boxes of the best sweep split
    int sweep_axis = -1;
    std::uint32_t sweep_k = 0;
    // Bins per axis: cfg.bins, but no more than count / 4 (at least 4) in nodes of few
    // primitives, where most of 16 bins would stay empty while costing a clear and a sweep step.
    const std::uint32_t nbins = std::min(cfg.bins, std::max(4u, count / 4));
    // Bin along every axis whose centroid extent is positive. (The centroid bounds are only
    // needed here, so they are gathered here rather than during the parent's partition.)
    Box3f cb = task.cbox;
    if (!small && !trivial && area > 0.0 && cb.empty()) {
      __m128 clo4 = inf, chi4 = ninf;
      for (std::uint32_t i = 0; i < count; ++i) {
        const __m128 c = _mm_and_ps(_mm_load_ps(r[i].c), xyz_mask());
        clo4 = _mm_min_ps(clo4, c), chi4 = _mm_max_ps(chi4, c);
      }
      cb = to_box(clo4, chi4);
    }
    float scale[3];
    bool usable[3];
    for (int a = 0; a < 3; ++a) {
      const float ext = cb.hi[a] - cb.lo[a];
      // bins * (1 - 2^-20) / ext keeps the largest centroid inside the last bin; the clamp below
      // catches what rounding still pushes out.
      usable[a] = ext > 0.0f && area > 0.0 && !small && !trivial;
      scale[a] = usable[a] ? static_cast<float>(nbins) * (1.0f - 1.0f / 1048576.0f) / ext : 0.0f;
      if (usable[a] && !std::isfinite(scale[a])) usable[a] = false;  // extent below ~1e-38: too small to bin
    }
    int best_axis = -1;
    std::uint32_t best_split = 0;  // left = bins [0, best_split)
    double best_cost = std::numeric_limits<double>::infinity();
    std::uint64_t total_weight = 0;
    const __m128 clo = _mm_setr_ps(cb.lo[0], cb.lo[1], cb.lo[2], 0.0f);
    const __m128 sc = _mm_setr_ps(scale[0], scale[1], scale[2], 0.0f);
    const __m128 maxbin = _mm_set1_ps(static_cast<float>(nbins - 1));
    const BinParams bp{clo, sc, maxbin};
    Bins& b0 = w.bins[0];
    if (usable[0] || usable[1] || usable[2]) {
      // Two bin sets (alternate primitives) hide the latency of consecutive updates of one bin;
      // in nodes of few primitives clearing and merging the second set costs more than it hides.
      if (count >= kTwoSetsFrom) {
        Bins& b1 = w.bins[1];
        b0.clear(nbins);
        b1.clear(nbins);
        total_weight = bin_range(r, count, bp, b0, b1);
        b0.merge(b1, nbins);
      } else {
        b0.clear(nbins);
        total_weight = bin_range(r, count, bp, b0, b0);
      }
      // Only non-empty bins matter: a boundary next to an empty bin gives the same partition as
      // the boundary before it (small nodes, the majority, have few non-empty bins).
      float right_area[kMaxBins], right_weight[kMaxBins];
      std::uint32_t used[kMaxBins];
      float best_sum = std::numeric_limits<float>::infinity();
      for (int a = 0; a < 3; ++a) {
        if (!usable[a]) continue;
        std::uint32_t k = 0;
        for (std::uint32_t b = 0; b < nbins; ++b)
          if (b0.weight[a][b]) used[k++] = b;
        __m128 lo = inf, nhi = inf;
        std::uint64_t wr = 0;
        for (std::uint32_t j = k; j-- > 1;) {  // right side = used[j .. k)
          const std::uint32_t b = used[j];
          lo = _mm_min_ps(lo, b0.lo(a, b)), nhi = _mm_min_ps(nhi, b0.neg_hi(a, b));
          wr += b0.weight[a][b];
          right_area[j] = half_area(lo, negate(nhi));
          right_weight[j] = static_cast<float>(wr);
        }
        lo = inf, nhi = inf;
        std::uint64_t wl = 0;
        for (std::uint32_t j = 1; j < k; ++j) {  // left = used[0 .. j), split before bin used[j]
          const std::uint32_t b = used[j - 1];
          lo = _mm_min_ps(lo, b0.lo(a, b)), nhi = _mm_min_ps(nhi, b0.neg_hi(a, b));
          wl += b0.weight[a][b];
          const float sum = half_area(lo, negate(nhi)) * static_cast<float>(wl) + right_area[j] * right_weight[j];
          if (sum < best_sum) best_sum = sum, best_axis = a, best_split = used[j];
        }
      }
      if (best_axis >= 0) best_cost = m.traversal + m.intersection * 2.0 * static_cast<double>(best_sum) / area;
    } else {
      const bool sweep = small && !trivial && area > 0.0;
      if (!sweep)
        for (std::uint32_t i = 0; i < count; ++i) total_weight += r[i].weight;
      if (sweep) {
        float right_area[kSweepBelow], right_weight[kSweepBelow];
        __m128 suffix_lo[kSweepBelow], suffix_hi[kSweepBelow];
        const __m128 mask3 = xyz_mask();
        float best_sum = std::numeric_limits<float>::infinity();
        int longest = 0;
        for (int a = 1; a < 3; ++a)
          if (task.box.hi[a] - task.box.lo[a] > task.box.hi[longest] - task.box.lo[longest]) longest = a;
        for (int a = 0; a < 3; ++a) {
          if (cfg.small_nodes_longest_axis && a != longest) continue;
          std::uint8_t* o = order[a];
          sorted[a] = rank_by_centroid(r, count, a, o);
          // Right sweep down to position 0 (the total weight), keeping the suffix boxes (the
          // right child's box) and the records in sweep order (the reordering); the left sweep
          // keeps the best split's prefix box (the left child's box). No other pass over the
          // node: each variable-length loop costs a mispredicted exit, and small nodes are many.
          __m128 lo = inf, hi = ninf;
          std::uint64_t wr = 0;
          for (std::uint32_t j = count; j-- > 0;) {
            const RefBits x = load_ref(r[o[j]]);
            swept[a][j] = x;
            lo = _mm_min_ps(lo, _mm_and_ps(x.a, mask3)), hi = _mm_max_ps(hi, _mm_and_ps(x.b, mask3));
            wr += r[o[j]].weight;
            suffix_lo[j] = lo, suffix_hi[j] = hi;
            right_area[j] = half_area(lo, hi);
            right_weight[j] = static_cast<float>(wr);
          }
          total_weight = wr;
          lo = inf, hi = ninf;
          wr = 0;
          if (must_split && count <= cfg.median_split_below) {
            const std::uint32_t j = count / 2;
            for (std::uint32_t i = 0; i < j; ++i) {
              lo = _mm_min_ps(lo, _mm_and_ps(swept[a][i].a, mask3));
              hi = _mm_max_ps(hi, _mm_and_ps(swept[a][i].b, mask3));
              wr += r[o[i]].weight;
            }
            const float sum = half_area(lo, hi) * static_cast<float>(wr) + right_area[j] * right_weight[j];
            if (sum < best_sum) {
              best_sum = sum, sweep_axis = a, sweep_k = j;
              sweep_left = {lo, hi}, sweep_right = {suffix_lo[j], suffix_hi[j]};
            }
            continue;
          }
          for (std::uint32_t j = 1; j < count; ++j) {
            lo = _mm_min_ps(lo, _mm_and_ps(swept[a][j - 1].a, mask3));
            hi = _mm_max_ps(hi, _mm_and_ps(swept[a][j - 1].b, mask3));
            wr += r[o[j - 1]].weight;
            const float sum = half_area(lo, hi) * static_cast<float>(wr) + right_area[j] * right_weight[j];
            if (sum < best_sum) {
              best_sum = sum, sweep_axis = a, sweep_k = j;
              sweep_left = {lo, hi}, sweep_right = {suffix_lo[j], suffix_hi[j]};
            }
          }
        }
        if (sweep_axis >= 0) best_cost = m.traversal + m.intersection * 2.0 * static_cast<double>(best_sum) / area;
      }
    }
    if (!must_split && m.intersection * static_cast<double>(total_weight) <= best_cost) {
      make_leaf();
      continue;
    }

    // Put the primitives in place (left child first) and gather the children's bounds on the way:
    // an in-place partition by bin, the swept order, or (no plane separates the centroids: all equal,
    // a zero-area node, or two primitives) the object median of the current order.
    std::uint32_t k;
    SideBounds left, right;
    Box3f left_cb, right_cb;  // empty: not gathered
    if (best_axis >= 0) {
      // The children's boxes are the unions of their bins (partition and binning use the same
      // bin formula); the partition is in place and branch-free (the side is a coin flip to the
      // branch predictor): [0, k) goes left, [k, i) right, and r[i] is swapped to position k.
      const int a = best_axis;
      for (std::uint32_t b = 0; b < nbins; ++b) {
        SideBounds& s = b < best_split ? left : right;
        s.lo = _mm_min_ps(s.lo, b0.lo(a, b)), s.hi = _mm_max_ps(s.hi, negate(b0.neg_hi(a, b)));
      }
      // The children's centroid bounds are gathered on the way (their binning needs them, and
      // a separate pass would read the records once more): the centroid, or NaN on the other
      // side, which _mm_min_ps / _mm_max_ps (second operand returned on NaN) ignore. Lane 3
      // holds Ref::bins and is never read from these bounds.
      k = 0;
      const unsigned shift = 8u * static_cast<unsigned>(a);
      const __m128 ones = _mm_castsi128_ps(_mm_set1_epi32(-1));
      __m128 lcl = inf, lch = ninf, rcl = inf, rch = ninf;
      for (std::uint32_t i = 0; i < count; ++i) {
        const std::uint32_t bin = (r[i].bins >> shift) & 0xffu;
        const RefBits x = load_ref(r[i]);
        store_ref(r[i], load_ref(r[k]));
        store_ref(r[k], x);
        const std::uint32_t goes_left = bin < best_split;
        const __m128 mk = _mm_castsi128_ps(_mm_set1_epi32(-static_cast<std::int32_t>(goes_left)));
        const __m128 cl = _mm_or_ps(x.c, _mm_xor_ps(mk, ones)), cr = _mm_or_ps(x.c, mk);
        lcl = _mm_min_ps(cl, lcl), lch = _mm_max_ps(cl, lch), rcl = _mm_min_ps(cr, rcl), rch = _mm_max_ps(cr, rch);
        k += goes_left;
      }
      left_cb = to_box(lcl, lch), right_cb = to_box(rcl, rch);
    } else {
      if (sweep_axis >= 0) {
        if (!sorted[sweep_axis])
          for (std::uint32_t i = 0; i < count; ++i) store_ref(r[i], swept[sweep_axis][i]);
        k = sweep_k;
        left = sweep_left, right = sweep_right;
      } else {
        k = count / 2;
        for (std::uint32_t i = 0; i < k; ++i) left.add(r[i]);
        for (std::uint32_t i = k; i < count; ++i) right.add(r[i]);
      }
    }
    assert(k > 0 && k < count);
    acc.inner(m, area);
    // Children of one primitive are leaves: emitted at once (pre-order: the first child is
    // idx + 1; the second follows it when the first is a leaf), the rest goes on the stack.
    auto emit_leaf = [&](std::uint32_t begin, const Box3f& box) {
      BvhNode& leaf = bvh.nodes.emplace_back();
      leaf.bounds = box, leaf.index = begin, leaf.count = 1;
      acc.leaf(m, box.surface_area(), static_cast<double>(refs[begin].weight));
    };
    if (task.groups) {  // children of one group continue as tasks (see the top of the loop)
      stack.push_back({task.begin + k, task.end, idx, to_box(right.lo, right.hi), right_cb, 1});
      stack.push_back({task.begin, task.begin + k, kNone, to_box(left.lo, left.hi), left_cb, 1});
      continue;
    }
    if (k == 1) {
      emit_leaf(task.begin, to_box(left.lo, left.hi));
      if (count - k == 1) {
        bvh.nodes[idx].index = idx + 2;
        emit_leaf(task.begin + 1, to_box(right.lo, right.hi));
      } else {
        stack.push_back({task.begin + k, task.end, idx, to_box(right.lo, right.hi), right_cb, 0});
      }
      continue;
    }
    stack.push_back({task.begin + k, task.end, idx, to_box(right.lo, right.hi), right_cb, 0});
    stack.push_back({task.begin, task.begin + k, kNone, to_box(left.lo, left.hi), left_cb, 0});
  }
  bvh.prim_order.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) bvh.prim_order[i] = refs[i].id;
  bvh.cost = acc.total(bvh.nodes[0].bounds.surface_area());
}

}  // namespace ptc::bvh
