#include "bvh/sah_builder.h"

#include <emmintrin.h>  // SSE2: the x86-64 baseline

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>

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
// from the input spans.

namespace {

struct alignas(16) Ref {
  float lo[3];
  std::uint32_t id;
  float hi[3];
  std::uint32_t weight;
  float c[3];
  float pad;
};
static_assert(sizeof(Ref) == 48);

struct BinnedTask {
  std::uint32_t begin, end, patch_parent;
  Box3f box;  // union of the primitive boxes
};

constexpr std::uint32_t kMaxBins = 256;
constexpr std::uint32_t kSweepBelow = 16;  // nodes of at most this many primitives are swept exactly

struct Bins {
  __m128 lo[3][kMaxBins], hi[3][kMaxBins];
  std::uint32_t weight[3][kMaxBins];  // weights >= 1, so 0 means an empty bin

  void clear(std::uint32_t nbins) {
    const __m128 inf = _mm_set1_ps(kInf), ninf = _mm_set1_ps(-kInf);
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t b = 0; b < nbins; ++b) lo[a][b] = inf, hi[a][b] = ninf, weight[a][b] = 0;
  }
  void add(const std::int32_t* bin, __m128 l, __m128 h, std::uint32_t w) {
    for (int a = 0; a < 3; ++a) {
      const std::int32_t b = bin[a];
      lo[a][b] = _mm_min_ps(lo[a][b], l);
      hi[a][b] = _mm_max_ps(hi[a][b], h);
      weight[a][b] += w;
    }
  }
  void merge(const Bins& o, std::uint32_t nbins) {
    for (int a = 0; a < 3; ++a)
      for (std::uint32_t b = 0; b < nbins; ++b) {
        lo[a][b] = _mm_min_ps(lo[a][b], o.lo[a][b]);
        hi[a][b] = _mm_max_ps(hi[a][b], o.hi[a][b]);
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
inline void rank_by_centroid(const Ref* r, std::uint32_t count, int a, std::uint8_t* order) {
  alignas(16) float cs[kSweepBelow];
  for (std::uint32_t i = 0; i < kSweepBelow; ++i) cs[i] = i < count ? r[i].c[a] : kInf;
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
}

}  // namespace

struct BuildWorkspace::Impl {
  std::vector<Ref, AlignedAllocator<Ref>> refs;
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
  for (std::uint32_t i = 0; i < n; ++i) {
    Ref& r = refs[i];
    const Box3f& b = in.boxes[i];
    const Vec3f& c = in.centroids[i];
    r = Ref{{b.lo[0], b.lo[1], b.lo[2]}, i, {b.hi[0], b.hi[1], b.hi[2]}, in.weights.empty() ? 1u : in.weights[i],
            {c[0], c[1], c[2]}, 0.0f};
    rlo = _mm_min_ps(rlo, load_lo(r)), rhi = _mm_max_ps(rhi, load_hi(r));
  }
  bvh.nodes.reserve(2 * static_cast<std::size_t>(n));
  CostAccumulator acc;
  std::vector<BinnedTask>& stack = w.stack;
  stack.clear();
  stack.push_back({0, n, kNone, to_box(rlo, rhi)});
  const __m128 inf = _mm_set1_ps(kInf), ninf = _mm_set1_ps(-kInf);

  while (!stack.empty()) {
    const BinnedTask task = stack.back();
    stack.pop_back();
    const auto idx = static_cast<std::uint32_t>(bvh.nodes.size());
    bvh.nodes.emplace_back();
    if (task.patch_parent != kNone) bvh.nodes[task.patch_parent].index = idx;
    bvh.nodes[idx].bounds = task.box;
    Ref* r = refs + task.begin;
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
    const bool must_split = count > cfg.max_leaf_size;
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
    int sweep_axis = -1;
    std::uint32_t sweep_k = 0;
    // Bins per axis: cfg.bins, but no more than count / 4 (at least 4) in nodes of few
    // primitives, where most of 16 bins would stay empty while costing a clear and a sweep step.
    const std::uint32_t nbins = std::min(cfg.bins, std::max(4u, count / 4));
    // Bin along every axis whose centroid extent is positive. (The centroid bounds are only
    // needed here, so they are gathered here rather than during the parent's partition.)
    Box3f cb;
    if (!small && !trivial && area > 0.0) {
      __m128 clo4 = inf, chi4 = ninf;
      for (std::uint32_t i = 0; i < count; ++i) {
        const __m128 c = _mm_load_ps(r[i].c);
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
    auto bin_of = [&](const Ref& x, std::int32_t* out) {  // the one bin formula (binning and partition)
      const __m128 c = _mm_load_ps(x.c);
      const __m128 f = _mm_min_ps(_mm_max_ps(_mm_mul_ps(_mm_sub_ps(c, clo), sc), _mm_setzero_ps()), maxbin);
      _mm_store_si128(reinterpret_cast<__m128i*>(out), _mm_cvttps_epi32(f));
    };
    Bins& b0 = w.bins[0];
    if (usable[0] || usable[1] || usable[2]) {
      // Two bin sets, for even and odd primitives: consecutive updates of the same bin would
      // otherwise wait for each other through memory.
      Bins& b1 = w.bins[1];
      b0.clear(nbins);
      b1.clear(nbins);
      std::uint32_t i = 0;
      for (; i + 1 < count; i += 2) {
        alignas(16) std::int32_t bi0[4], bi1[4];
        bin_of(r[i], bi0);
        bin_of(r[i + 1], bi1);
        b0.add(bi0, load_lo(r[i]), load_hi(r[i]), r[i].weight);
        b1.add(bi1, load_lo(r[i + 1]), load_hi(r[i + 1]), r[i + 1].weight);
        total_weight += r[i].weight + r[i + 1].weight;
      }
      if (i < count) {
        alignas(16) std::int32_t bi0[4];
        bin_of(r[i], bi0);
        b0.add(bi0, load_lo(r[i]), load_hi(r[i]), r[i].weight);
        total_weight += r[i].weight;
      }
      b0.merge(b1, nbins);
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
        __m128 lo = inf, hi = ninf;
        std::uint64_t wr = 0;
        for (std::uint32_t j = k; j-- > 1;) {  // right side = used[j .. k)
          const std::uint32_t b = used[j];
          lo = _mm_min_ps(lo, b0.lo[a][b]), hi = _mm_max_ps(hi, b0.hi[a][b]);
          wr += b0.weight[a][b];
          right_area[j] = half_area(lo, hi);
          right_weight[j] = static_cast<float>(wr);
        }
        lo = inf, hi = ninf;
        std::uint64_t wl = 0;
        for (std::uint32_t j = 1; j < k; ++j) {  // left = used[0 .. j), split before bin used[j]
          const std::uint32_t b = used[j - 1];
          lo = _mm_min_ps(lo, b0.lo[a][b]), hi = _mm_max_ps(hi, b0.hi[a][b]);
          wl += b0.weight[a][b];
          const float sum = half_area(lo, hi) * static_cast<float>(wl) + right_area[j] * right_weight[j];
          if (sum < best_sum) best_sum = sum, best_axis = a, best_split = used[j];
        }
      }
      if (best_axis >= 0) best_cost = m.traversal + m.intersection * 2.0 * static_cast<double>(best_sum) / area;
    } else {
      for (std::uint32_t i = 0; i < count; ++i) total_weight += r[i].weight;
      if (small && !trivial && area > 0.0) {
        float right_area[kSweepBelow], right_weight[kSweepBelow];
        float best_sum = std::numeric_limits<float>::infinity();
        int longest = 0;
        for (int a = 1; a < 3; ++a)
          if (task.box.hi[a] - task.box.lo[a] > task.box.hi[longest] - task.box.lo[longest]) longest = a;
        for (int a = 0; a < 3; ++a) {
          if (cfg.small_nodes_longest_axis && a != longest) continue;
          std::uint8_t* o = order[a];
          rank_by_centroid(r, count, a, o);
          __m128 lo = inf, hi = ninf;
          std::uint64_t wr = 0;
          for (std::uint32_t j = count; j-- > 1;) {
            lo = _mm_min_ps(lo, load_lo(r[o[j]])), hi = _mm_max_ps(hi, load_hi(r[o[j]]));
            wr += r[o[j]].weight;
            right_area[j] = half_area(lo, hi);
            right_weight[j] = static_cast<float>(wr);
          }
          lo = inf, hi = ninf;
          wr = 0;
          for (std::uint32_t j = 1; j < count; ++j) {
            lo = _mm_min_ps(lo, load_lo(r[o[j - 1]])), hi = _mm_max_ps(hi, load_hi(r[o[j - 1]]));
            wr += r[o[j - 1]].weight;
            const float sum = half_area(lo, hi) * static_cast<float>(wr) + right_area[j] * right_weight[j];
            if (sum < best_sum) best_sum = sum, sweep_axis = a, sweep_k = j;
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
    if (best_axis >= 0) {
      // The children's boxes are the unions of their bins (partition and binning use the same
      // bin formula); the partition is in place and branch-free (the side is a coin flip to the
      // branch predictor): [0, k) goes left, [k, i) right, and r[i] is swapped to position k.
      const int a = best_axis;
      for (std::uint32_t b = 0; b < nbins; ++b) {
        SideBounds& s = b < best_split ? left : right;
        s.lo = _mm_min_ps(s.lo, b0.lo[a][b]), s.hi = _mm_max_ps(s.hi, b0.hi[a][b]);
      }
      k = 0;
      for (std::uint32_t i = 0; i < count; ++i) {
        alignas(16) std::int32_t bi[4];
        bin_of(r[i], bi);
        const Ref x = r[i];
        r[i] = r[k];
        r[k] = x;
        k += static_cast<std::uint32_t>(bi[a]) < best_split;
      }
    } else {
      k = count / 2;
      if (sweep_axis >= 0) {
        Ref tmp[kSweepBelow];
        for (std::uint32_t i = 0; i < count; ++i) tmp[i] = r[order[sweep_axis][i]];
        for (std::uint32_t i = 0; i < count; ++i) r[i] = tmp[i];
        k = sweep_k;
      }
      for (std::uint32_t i = 0; i < k; ++i) left.add(r[i]);
      for (std::uint32_t i = k; i < count; ++i) right.add(r[i]);
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
    if (k == 1) {
      emit_leaf(task.begin, to_box(left.lo, left.hi));
      if (count - k == 1) {
        bvh.nodes[idx].index = idx + 2;
        emit_leaf(task.begin + 1, to_box(right.lo, right.hi));
      } else {
        stack.push_back({task.begin + k, task.end, idx, to_box(right.lo, right.hi)});
      }
      continue;
    }
    stack.push_back({task.begin + k, task.end, idx, to_box(right.lo, right.hi)});
    stack.push_back({task.begin, task.begin + k, kNone, to_box(left.lo, left.hi)});
  }
  bvh.prim_order.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) bvh.prim_order[i] = refs[i].id;
  bvh.cost = acc.total(bvh.nodes[0].bounds.surface_area());
}

}  // namespace ptc::bvh
