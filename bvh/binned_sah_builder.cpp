#include "bvh/binned_sah_builder.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "bvh/aligned.h"
#include "bvh/binning.h"
#include "bvh/box_simd.h"
#include "bvh/fragments.h"
#include "bvh/threads.h"
#include "bvh/top_down_builder.h"

// The binned builder on the top-down skeleton (top_down_builder.h). Its steps:
//   make_records        the input spans into 48-byte records (binning.h), root bounds, NaN check
//   make_group_records  two-level build: one record per group, the top task over them
// and per node (the skeleton's hooks):
//   open                a task of one group continues with the group's primitives
//   leaf_by_bound       the early leaf: the leaf is no dearer than a lower bound of every split
//   find_split          large nodes: bin_split (bin_grid, one binning pass, a sweep over the
//                       bins); small nodes: sweep_split (ranks by centroid, a right and a left
//                       sweep, or the object median); otherwise no split (the weight only)
//   apply               partition_by_bin (in place, children's boxes from the bins, centroid
//                       bounds on the way), the swept order, or the object median
namespace ptc::bvh {

namespace {

using namespace binned;

constexpr std::uint32_t kSweepBelow = 16;    // nodes of at most this many primitives are swept exactly
constexpr std::uint32_t kTwoSetsFrom = 256;  // binning into two bin sets from this many primitives up (below: one)
// The parallel build (build_parallel): from this many items at the root (primitives, or groups
// in a two-level build) and more than one thread in the arena; subtrees of at least
// max(kSmallestFragment, root items / (kFragmentsPerThread * threads)) items become fragments.
constexpr std::uint32_t kParallelFrom = 1u << 15;
constexpr std::uint32_t kSmallestFragment = 1u << 11;
constexpr std::uint32_t kFragmentsPerThread = 32;
constexpr std::uint32_t kRecordsPerTask = 1u << 15;  // records made per task

struct BinnedExtra {
  Box3f box;   // union of the primitive boxes
  Box3f cbox;  // bounds of the centroids, gathered by the parent's partition; empty: not known
  std::uint32_t groups = 0;  // 1: a range of group records (BuildInput::groups), 0: of primitives
};
using BinnedTask = TopDownTask<BinnedExtra>;

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
  // (all four rows, not only the q used ones: a loop of q loads was compiled into a memcpy call)
  for (std::uint32_t k = 0; k < kSweepBelow / 4; ++k)
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

// The root's bounds from the record pass.
struct RootBounds {
  __m128 lo, hi;    // union of the boxes
  __m128 clo, chi;  // bounds of the centroids
};

// The records of primitives [begin, end) of the input, in input order, and their bounds;
// `nan_seen` is set when a NaN was seen. Records are assembled in registers (store_record).
RootBounds make_records_range(const BuildInput& in, Ref* refs, std::uint32_t begin, std::uint32_t end, bool& nan_seen) {
  const auto n = static_cast<std::uint32_t>(in.boxes.size());
  static_assert(sizeof(Box3f) == 24 && sizeof(Vec3f) == 12);
  const float* cf = in.centroids.empty() ? nullptr : in.centroids[0].data();
  const __m128 mask = xyz_mask();
  RootBounds rb{_mm_set1_ps(kInf), _mm_set1_ps(-kInf), _mm_set1_ps(kInf), _mm_set1_ps(-kInf)};
  __m128 nan = _mm_setzero_ps();
  for (std::uint32_t i = begin; i < end; ++i) {
    __m128 l, h;
    simd::load_box(in.boxes[i], l, h);
    l = _mm_and_ps(l, mask), h = _mm_and_ps(h, mask);  // (lane 3 cleared)
    // Centroid: a 16-byte load reads one float past the element, allowed but for the last one.
    __m128 c;
    if (i + 1 < n) {
      c = _mm_and_ps(_mm_loadu_ps(cf + 3 * std::size_t(i)), mask);
    } else {
      const Vec3f& v = in.centroids[i];
      c = _mm_setr_ps(v[0], v[1], v[2], 0.0f);
    }
    const std::uint32_t wt = in.weights.empty() ? 1u : in.weights[i];
    store_record(refs[i], l, h, c, i, wt);
    rb.lo = _mm_min_ps(rb.lo, l), rb.hi = _mm_max_ps(rb.hi, h);
    rb.clo = _mm_min_ps(rb.clo, c), rb.chi = _mm_max_ps(rb.chi, c);
    nan = _mm_or_ps(nan, _mm_or_ps(_mm_cmpunord_ps(l, h), _mm_cmpunord_ps(c, c)));
  }
  nan_seen = _mm_movemask_ps(nan) != 0;
  return rb;
}

// The records of the input and the root's bounds, in pieces on `threads` threads from
// kParallelFrom primitives up. The pieces' bounds are merged in their order: _mm_min_ps and
// _mm_max_ps keep the later of two equal values (a +0 and a -0), as the one-piece loop does, so
// the bounds have the same bits. A NaN anywhere makes check_no_nan name the primitive.
RootBounds make_records(const BuildInput& in, Ref* refs, int threads) {
  const auto n = static_cast<std::uint32_t>(in.boxes.size());
  bool nan = false;
  RootBounds rb;
  if (threads <= 1 || n < kParallelFrom) {
    rb = make_records_range(in, refs, 0, n, nan);
  } else {
    const std::uint32_t pieces = (n + kRecordsPerTask - 1) / kRecordsPerTask;
    std::vector<RootBounds> piece_bounds(pieces);
    std::vector<char> piece_nan(pieces, 0);
    tbb::parallel_for(std::uint32_t{0}, pieces, [&](std::uint32_t k) {
      bool nk = false;
      piece_bounds[k] = make_records_range(in, refs, k * kRecordsPerTask, std::min(n, (k + 1) * kRecordsPerTask), nk);
      piece_nan[k] = nk;
    });
    rb = piece_bounds[0];
    nan = piece_nan[0];
    for (std::uint32_t k = 1; k < pieces; ++k) {
      const RootBounds& p = piece_bounds[k];
      rb.lo = _mm_min_ps(rb.lo, p.lo), rb.hi = _mm_max_ps(rb.hi, p.hi);
      rb.clo = _mm_min_ps(rb.clo, p.clo), rb.chi = _mm_max_ps(rb.chi, p.chi);
      nan = nan || piece_nan[k];
    }
  }
  if (nan) check_no_nan(in);
  return rb;
}

// Two-level build (BuildInput::groups): one record per group (the union of its primitives'
// boxes, the box centre, the summed weight; id = the group), into group_refs; returns the
// bounds of the group centres. Throws std::invalid_argument for an empty or decreasing group.
Box3f make_group_records(std::span<const std::uint32_t> groups, const Ref* refs, AlignedVector<Ref>& group_refs) {
  const std::size_t G = groups.size() - 1;
  const auto n = groups.back();
  const __m128 inf = _mm_set1_ps(kInf), ninf = _mm_set1_ps(-kInf);
  group_refs.resize(G);
  __m128 gclo = inf, gchi = ninf;
  for (std::size_t g = 0; g < G; ++g) {
    const std::uint32_t a = groups[g], e = groups[g + 1];
    if (e <= a || e > n) throw std::invalid_argument("build_binned_sah: empty or decreasing group " + std::to_string(g));
    __m128 lo = inf, hi = ninf;
    std::uint64_t wt = 0;
    for (std::uint32_t i = a; i < e; ++i) {
      lo = _mm_min_ps(lo, load_lo(refs[i])), hi = _mm_max_ps(hi, load_hi(refs[i]));
      wt += refs[i].weight;
    }
    const __m128 c = _mm_and_ps(_mm_mul_ps(_mm_set1_ps(0.5f), _mm_add_ps(lo, hi)), xyz_mask());
    store_record(group_refs[g], lo, hi, c, static_cast<std::uint32_t>(g), static_cast<std::uint32_t>(wt));
    gclo = _mm_min_ps(gclo, c), gchi = _mm_max_ps(gchi, c);
  }
  return to_box(gclo, gchi);
}

// What one thread of a build works in: the bins of the node at hand and the stack of pending
// subtrees.
struct Scratch {
  Bins bins[2];
  std::vector<BinnedTask> stack;
};

// A parallel build's piece of the tree (fragments.h): the subtree of a task built by one job,
// in pre-order with local indices.
using BinnedFragment = Fragment<BvhNode, BinnedTask>;

}  // namespace

struct BuildWorkspace::Impl {
  AlignedVector<Ref> refs;
  AlignedVector<Ref> group_refs;  // two-level build: one record per group
  Scratch scratch;                                       // the sequential build's
  // The parallel build's, per thread slot of the arena (tbb::this_task_arena::current_thread_index()
  // is below its max_concurrency(), which may exceed the threads the global limit lets run).
  std::vector<std::unique_ptr<Scratch>> thread_scratch;
  FragmentPool<BinnedFragment> fragments;  // kept from one build to the next (their node arrays too)
};

namespace {

// Per large node: one binning pass (which also stores each record's bins for the partition), a
// sweep over the bins, one partition pass (which also gathers the children's centroid bounds).
// Per small node: ranks by centroid (skipped when already in order), one right and one left
// sweep (which also give the records in order and the children's boxes), one copy back.
class BinnedBuilder {
 public:
  using Task = BinnedTask;
  // The best split of a node; the bins it was found in are bins_[0] until apply().
  struct Split {
    double cost = std::numeric_limits<double>::infinity();  // inf: none (leaf, or the object median)
    std::uint64_t weight = 0;                               // W(P)
    std::uint32_t nbins = 0;
    int bin_axis = -1;           // bin split: left = bins [0, bin_split) on bin_axis
    std::uint32_t bin_split = 0;
    int sweep_axis = -1;         // sweep split: left = the first sweep_k records in order[sweep_axis]
    std::uint32_t sweep_k = 0;
    SideBounds sweep_left, sweep_right;      // the children's boxes of the best sweep split
    bool sorted[3] = {false, false, false};  // order[a] is the identity
    std::uint8_t order[3][kSweepBelow];
    RefBits swept[3][kSweepBelow];           // the records in order[a]
  };

  BinnedBuilder(const BuildInput& in, const BuildConfig& cfg, Ref* refs, Ref* group_refs, Bins* bins)
      : in_(in), cfg_(cfg), refs_(refs), group_refs_(group_refs), bins_(bins), bin_range_(bin_range_for(cfg.allow_avx2)),
        w_(split_area_weights(cfg)),
        aw_(area_weights_of(w_)),
        has_eye_(cfg.area_eye.has_value()),
        eye_(cfg.area_eye ? _mm_setr_ps((*cfg.area_eye)[0], (*cfg.area_eye)[1], (*cfg.area_eye)[2], 0.0f) : _mm_setzero_ps()) {}

  // Half a box's area as the splits are priced (BuildConfig::area_weights, or area_eye).
  float split_area(__m128 lo, __m128 hi) const { return has_eye_ ? half_area_from(lo, hi, eye_) : half_area(lo, hi, aw_); }

  Box3f open(Task& t) const {
    if (t.extra.groups && t.size() == 1) {  // one group: continue with its primitives
      const std::uint32_t g = group_refs_[t.begin].id;
      t = {{t.extra.box, Box3f{}, 0}, in_.groups[g], in_.groups[g + 1], t.patch_parent};
    }
    return t.extra.box;
  }
  bool single_primitive(const Task& t) const { return !t.extra.groups && t.size() == 1; }
  bool must_split(const Task& t) const { return t.extra.groups != 0; }  // (a leaf holds primitives, not groups)
  double leaf_weight(const Task& t) const {
    const Ref* r = records(t);
    std::uint64_t wt = 0;
    for (std::uint32_t i = 0; i < t.size(); ++i) wt += r[i].weight;
    return static_cast<double>(wt);
  }

  // Early leaf: every split costs at least traversal + intersection * sum_p A(p) w_p / A (each
  // primitive lies in a child whose area is at least its own), so a leaf that is no dearer than
  // that bound wins without evaluating any split.
  bool leaf_by_bound(const Task& t, double area) const {
    // (with area_eye the bound is approximate: a primitive stretched toward the point may price
    // above a node around it; kept, as the search it spares is most of a small node's build)
    if (!(area > 0.0)) return false;
    const Ref* r = records(t);
    double wt = 0.0, aw = 0.0;
    for (std::uint32_t i = 0; i < t.size(); ++i) {
      wt += r[i].weight;
      aw += 2.0 * static_cast<double>(split_area(load_lo(r[i]), load_hi(r[i]))) * r[i].weight;
    }
    const SahCostModel& m = cfg_.cost;
    return m.intersection * wt <= m.traversal + m.intersection * aw / area;
  }

  // Two primitives that must be split have one partition only: no search. Small nodes: exact
  // sweep over the primitives sorted by centroid (cheaper than clearing and sweeping bins, and
  // exact). Larger nodes: bins along every axis whose centroid extent is positive.
  Split find_split(const Task& t, double area, bool must_split) {
    Split s;
    Ref* r = records(t);
    const std::uint32_t count = t.size();
    const bool trivial = count == 2 && must_split;
    const bool small = count <= kSweepBelow;
    // Bins per axis: cfg.bins, but no more than count / 4 (at least 4) in nodes of few
    // primitives, where most of 16 bins would stay empty while costing a clear and a sweep step.
    s.nbins = std::min(cfg_.bins, std::max(4u, count / 4));
    if (!trivial && area > 0.0) {
      if (small) {
        sweep_split(t, r, area, must_split, s);
        return s;
      }
      const BinGrid grid = bin_grid(t, r, s.nbins);
      if (grid.usable[0] || grid.usable[1] || grid.usable[2]) {
        bin_split(r, count, grid, area, s);
        return s;
      }
    }
    for (std::uint32_t i = 0; i < count; ++i) s.weight += r[i].weight;
    return s;
  }

  // Puts the primitives in place (left child first) and gathers the children's bounds on the
  // way: an in-place partition by bin, the swept order, or (no plane separates the centroids:
  // all equal, a zero-area node, or two primitives) the object median of the current order.
  TopDownChildren<BinnedExtra> apply(const Task& t, const Split& s) {
    Ref* r = records(t);
    const std::uint32_t count = t.size();
    std::uint32_t k;
    SideBounds left, right;
    Box3f left_cb, right_cb;  // empty: not gathered
    if (s.bin_axis >= 0) {
      k = partition_by_bin(r, count, s, left, right, left_cb, right_cb);
    } else if (s.sweep_axis >= 0) {
      if (!s.sorted[s.sweep_axis])
        for (std::uint32_t i = 0; i < count; ++i) store_ref(r[i], s.swept[s.sweep_axis][i]);
      k = s.sweep_k;
      left = s.sweep_left, right = s.sweep_right;
    } else {
      k = count / 2;
      for (std::uint32_t i = 0; i < k; ++i) left.add(r[i]);
      for (std::uint32_t i = k; i < count; ++i) right.add(r[i]);
    }
    assert(k > 0 && k < count);
    return {k, {to_box(left.lo, left.hi), left_cb, t.extra.groups}, {to_box(right.lo, right.hi), right_cb, t.extra.groups}};
  }

 private:
  // Where a node's bins lie: clo + [0, nbins) / scale per axis (the bin formula of binning.h).
  struct BinGrid {
    BinParams params;
    bool usable[3];
  };

  Ref* records(const Task& t) const { return (t.extra.groups ? group_refs_ : refs_) + t.begin; }

  // The grid over the node's centroid bounds (gathered here when the parent's partition did
  // not: they are only needed here). An axis of zero extent, or of an extent below ~1e-38 (too
  // small to bin: the scale overflows), is not usable.
  static BinGrid bin_grid(const Task& t, const Ref* r, std::uint32_t nbins) {
    Box3f cb = t.extra.cbox;
    if (cb.empty()) {
      __m128 clo4 = _mm_set1_ps(kInf), chi4 = _mm_set1_ps(-kInf);
      for (std::uint32_t i = 0; i < t.size(); ++i) {
        const __m128 c = _mm_and_ps(_mm_load_ps(r[i].c), xyz_mask());
        clo4 = _mm_min_ps(clo4, c), chi4 = _mm_max_ps(chi4, c);
      }
      cb = to_box(clo4, chi4);
    }
    BinGrid g;
    float scale[3];
    for (int a = 0; a < 3; ++a) {
      const float ext = cb.hi[a] - cb.lo[a];
      // bins * (1 - 2^-20) / ext keeps the largest centroid inside the last bin; the clamp of
      // the bin formula catches what rounding still pushes out.
      g.usable[a] = ext > 0.0f;
      scale[a] = g.usable[a] ? static_cast<float>(nbins) * (1.0f - 1.0f / 1048576.0f) / ext : 0.0f;
      if (g.usable[a] && !std::isfinite(scale[a])) g.usable[a] = false;
    }
    g.params = {_mm_setr_ps(cb.lo[0], cb.lo[1], cb.lo[2], 0.0f), _mm_setr_ps(scale[0], scale[1], scale[2], 0.0f),
                _mm_set1_ps(static_cast<float>(nbins - 1))};
    return g;
  }

  // One binning pass into bins_[0], then per usable axis a right and a left sweep over the
  // non-empty bins (a boundary next to an empty bin gives the same partition as the boundary
  // before it; small nodes, the majority, have few non-empty bins).
  void bin_split(Ref* r, std::uint32_t count, const BinGrid& grid, double area, Split& s) const {
    const std::uint32_t nbins = s.nbins;
    Bins& b0 = bins_[0];
    // Two bin sets (alternate primitives) hide the latency of consecutive updates of one bin;
    // in nodes of few primitives clearing and merging the second set costs more than it hides.
    if (count >= kTwoSetsFrom) {
      Bins& b1 = bins_[1];
      b0.clear(nbins);
      b1.clear(nbins);
      s.weight = bin_range_(r, count, grid.params, b0, b1);
      b0.merge(b1, nbins);
    } else {
      b0.clear(nbins);
      s.weight = bin_range_(r, count, grid.params, b0, b0);
    }
    const __m128 inf = _mm_set1_ps(kInf);
    float right_area[kMaxBins], right_weight[kMaxBins];
    std::uint32_t used[kMaxBins];
    float best_sum = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
      if (!grid.usable[a]) continue;
      std::uint32_t k = 0;
      for (std::uint32_t b = 0; b < nbins; ++b)
        if (b0.weight[a][b]) used[k++] = b;
      __m128 lo = inf, nhi = inf;
      std::uint64_t wr = 0;
      for (std::uint32_t j = k; j-- > 1;) {  // right side = used[j .. k)
        const std::uint32_t b = used[j];
        lo = _mm_min_ps(lo, b0.lo(a, b)), nhi = _mm_min_ps(nhi, b0.neg_hi(a, b));
        wr += b0.weight[a][b];
        right_area[j] = split_area(lo, negate(nhi));
        right_weight[j] = static_cast<float>(wr);
      }
      lo = inf, nhi = inf;
      std::uint64_t wl = 0;
      for (std::uint32_t j = 1; j < k; ++j) {  // left = used[0 .. j), split before bin used[j]
        const std::uint32_t b = used[j - 1];
        lo = _mm_min_ps(lo, b0.lo(a, b)), nhi = _mm_min_ps(nhi, b0.neg_hi(a, b));
        wl += b0.weight[a][b];
        const float sum = split_area(lo, negate(nhi)) * static_cast<float>(wl) + right_area[j] * right_weight[j];
        if (sum < best_sum) best_sum = sum, s.bin_axis = a, s.bin_split = used[j];
      }
    }
    if (s.bin_axis >= 0) s.cost = cost_of(best_sum, area);
  }

  // The exact sweep of a small node (count <= kSweepBelow) along its longest axis (all three
  // unless cfg.small_nodes_longest_axis); a node that must be split and has at most
  // cfg.median_split_below primitives is split at the object median of that order instead.
  void sweep_split(const Task& t, const Ref* r, double area, bool must_split, Split& s) const {
    const std::uint32_t count = t.size();
    const __m128 inf = _mm_set1_ps(kInf), ninf = _mm_set1_ps(-kInf);
    float right_area[kSweepBelow], right_weight[kSweepBelow];
    __m128 suffix_lo[kSweepBelow], suffix_hi[kSweepBelow];
    const __m128 mask3 = xyz_mask();
    float best_sum = std::numeric_limits<float>::infinity();
    // The longest axis, each extent over its area weight: the axis whose faces' weighted area
    // w_a * (product of the other extents) is the least, so a cut across it shrinks the most of
    // the weighted area (with the plain weights simply the longest extent).
    std::array<float, 3> w = w_;
    if (cfg_.area_eye) {  // (the faces' weights in area_from: |v_a| / D + kEyeAreaIsotropic)
      float v[3], d2 = 0.0f, r2 = 0.0f;
      for (int a = 0; a < 3; ++a) {
        v[a] = 0.5f * (t.extra.box.lo[a] + t.extra.box.hi[a]) - (*cfg_.area_eye)[a];
        const float e = t.extra.box.hi[a] - t.extra.box.lo[a];
        d2 += v[a] * v[a], r2 += 0.25f * e * e;
      }
      const float D = std::sqrt(std::max(d2, r2));
      for (int a = 0; a < 3; ++a) w[a] = (D > 0.0f ? std::abs(v[a]) / D : 0.0f) + static_cast<float>(kEyeAreaIsotropic);
    }
    auto reach = [&](int a) { return (t.extra.box.hi[a] - t.extra.box.lo[a]) / w[a]; };
    int longest = 0;
    for (int a = 1; a < 3; ++a)
      if (reach(a) > reach(longest)) longest = a;
    for (int a = 0; a < 3; ++a) {
      if (cfg_.small_nodes_longest_axis && a != longest) continue;
      std::uint8_t* o = s.order[a];
      s.sorted[a] = rank_by_centroid(r, count, a, o);
      // Right sweep down to position 0 (the total weight), keeping the suffix boxes (the
      // right child's box) and the records in sweep order (the reordering); the left sweep
      // keeps the best split's prefix box (the left child's box). No other pass over the
      // node: each variable-length loop costs a mispredicted exit, and small nodes are many.
      __m128 lo = inf, hi = ninf;
      std::uint64_t wr = 0;
      for (std::uint32_t j = count; j-- > 0;) {
        const RefBits x = load_ref(r[o[j]]);
        s.swept[a][j] = x;
        lo = _mm_min_ps(lo, _mm_and_ps(x.a, mask3)), hi = _mm_max_ps(hi, _mm_and_ps(x.b, mask3));
        wr += r[o[j]].weight;
        suffix_lo[j] = lo, suffix_hi[j] = hi;
        right_area[j] = split_area(lo, hi);
        right_weight[j] = static_cast<float>(wr);
      }
      s.weight = wr;
      lo = inf, hi = ninf;
      wr = 0;
      if (must_split && count <= cfg_.median_split_below) {
        const std::uint32_t j = count / 2;
        for (std::uint32_t i = 0; i < j; ++i) {
          lo = _mm_min_ps(lo, _mm_and_ps(s.swept[a][i].a, mask3));
          hi = _mm_max_ps(hi, _mm_and_ps(s.swept[a][i].b, mask3));
          wr += r[o[i]].weight;
        }
        const float sum = split_area(lo, hi) * static_cast<float>(wr) + right_area[j] * right_weight[j];
        if (sum < best_sum) {
          best_sum = sum, s.sweep_axis = a, s.sweep_k = j;
          s.sweep_left = {lo, hi}, s.sweep_right = {suffix_lo[j], suffix_hi[j]};
        }
        continue;
      }
      for (std::uint32_t j = 1; j < count; ++j) {
        lo = _mm_min_ps(lo, _mm_and_ps(s.swept[a][j - 1].a, mask3));
        hi = _mm_max_ps(hi, _mm_and_ps(s.swept[a][j - 1].b, mask3));
        wr += r[o[j - 1]].weight;
        const float sum = split_area(lo, hi) * static_cast<float>(wr) + right_area[j] * right_weight[j];
        if (sum < best_sum) {
          best_sum = sum, s.sweep_axis = a, s.sweep_k = j;
          s.sweep_left = {lo, hi}, s.sweep_right = {suffix_lo[j], suffix_hi[j]};
        }
      }
    }
    if (s.sweep_axis >= 0) s.cost = cost_of(best_sum, area);
  }

  // The SAH split cost from the best sum of half areas times weights (both children).
  double cost_of(float best_sum, double area) const {
    return cfg_.cost.traversal + cfg_.cost.intersection * 2.0 * static_cast<double>(best_sum) / area;
  }

  // The children's boxes are the unions of their bins (partition and binning use the same bin
  // formula); the partition is in place and branch-free (the side is a coin flip to the branch
  // predictor): [0, k) goes left, [k, i) right, and r[i] is swapped to position k. The
  // children's centroid bounds are gathered on the way (their binning needs them, and a
  // separate pass would read the records once more): the centroid, or NaN on the other side,
  // which _mm_min_ps / _mm_max_ps (second operand returned on NaN) ignore. Lane 3 holds
  // Ref::bins and is never read from these bounds. Returns k.
  std::uint32_t partition_by_bin(Ref* r, std::uint32_t count, const Split& s, SideBounds& left, SideBounds& right,
                                 Box3f& left_cb, Box3f& right_cb) const {
    const Bins& b0 = bins_[0];
    const int a = s.bin_axis;
    for (std::uint32_t b = 0; b < s.nbins; ++b) {
      SideBounds& side = b < s.bin_split ? left : right;
      side.lo = _mm_min_ps(side.lo, b0.lo(a, b)), side.hi = _mm_max_ps(side.hi, negate(b0.neg_hi(a, b)));
    }
    std::uint32_t k = 0;
    const unsigned shift = 8u * static_cast<unsigned>(a);
    const __m128 ones = _mm_castsi128_ps(_mm_set1_epi32(-1));
    const __m128 inf = _mm_set1_ps(kInf), ninf = _mm_set1_ps(-kInf);
    __m128 lcl = inf, lch = ninf, rcl = inf, rch = ninf;
    for (std::uint32_t i = 0; i < count; ++i) {
      const std::uint32_t bin = (r[i].bins >> shift) & 0xffu;
      const RefBits x = load_ref(r[i]);
      store_ref(r[i], load_ref(r[k]));
      store_ref(r[k], x);
      const std::uint32_t goes_left = bin < s.bin_split;
      const __m128 mk = _mm_castsi128_ps(_mm_set1_epi32(-static_cast<std::int32_t>(goes_left)));
      const __m128 cl = _mm_or_ps(x.c, _mm_xor_ps(mk, ones)), cr = _mm_or_ps(x.c, mk);
      lcl = _mm_min_ps(cl, lcl), lch = _mm_max_ps(cl, lch), rcl = _mm_min_ps(cr, rcl), rch = _mm_max_ps(cr, rch);
      k += goes_left;
    }
    left_cb = to_box(lcl, lch), right_cb = to_box(rcl, rch);
    return k;
  }

  const BuildInput& in_;
  const BuildConfig& cfg_;
  Ref* const refs_;
  Ref* const group_refs_;
  Bins* const bins_;  // two bin sets
  const BinRangeFn bin_range_;
  const std::array<float, 3> w_;  // split_area_weights(cfg)
  const __m128 aw_;               // the same in half_area's lanes
  const bool has_eye_;  // BuildConfig::area_eye given: half_area_from(eye_) instead
  const __m128 eye_;
};

}  // namespace

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

namespace {

// What a fragment's job hands on: a task of at least `cutoff` items (never its own root) becomes
// a new fragment. In pre-order the deferred subtree's nodes follow its placeholder at once: its
// cut is the placeholder's index + 1.
struct Deferrer {
  std::uint32_t cutoff;
  FragmentFeed<BinnedFragment>& feed;
  bool wants(const BinnedTask& t) const { return t.size() >= cutoff; }
  void take(std::uint32_t idx, BinnedTask t) {
    t.patch_parent = kNoParent;  // (its root is its own node 0; the placeholder was patched)
    feed.add(idx, idx + 1, t);
  }
};

// The SAH cost of a finished tree, its terms summed in node order: the order in which the
// sequential build adds them (top_down_builder.h), so the same bits. A leaf weighs its records'
// weights (their count when every primitive weighs 1).
double tree_cost(const SahCostModel& m, const AlignedVector<BvhNode>& nodes, const Ref* refs, bool weighted) {
  CostAccumulator acc;
  for (const BvhNode& nd : nodes) {
    const double area = nd.bounds.surface_area();
    if (!nd.is_leaf()) {
      acc.inner(m, area);
      continue;
    }
    std::uint64_t wt = nd.count;
    if (weighted) {
      wt = 0;
      for (std::uint32_t i = nd.index; i < nd.index + nd.count; ++i) wt += refs[i].weight;
    }
    acc.leaf(m, area, static_cast<double>(wt));
  }
  return acc.total(nodes[0].bounds.surface_area());
}

// The parallel build: the tree is cut into fragments, subtrees of at least `cutoff` items,
// each built by one job on the skeleton (its deferred subtrees become new jobs), then spliced at
// their placeholders in pre-order and their local indices moved to the final ones. Every
// subtree is built from the same records by the same decisions as in the sequential build, so
// the tree, its node order, the records' order and the cost are the sequential build's, at any
// thread count.
void build_parallel(const BuildInput& in, const BuildConfig& cfg, const BinnedTask& root, int threads,
                    BuildWorkspace::Impl& w, Bvh& bvh) {
  const std::uint32_t cutoff = std::max(kSmallestFragment, root.size() / (kFragmentsPerThread * static_cast<std::uint32_t>(threads)));
  const auto slots = static_cast<std::size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
  if (w.thread_scratch.size() < slots) w.thread_scratch.resize(slots);
  walk_fragments(w.fragments, root, [&](BinnedFragment& f, FragmentFeed<BinnedFragment>& feed) {
    const int t = tbb::this_task_arena::current_thread_index();
    std::unique_ptr<Scratch>& sc = w.thread_scratch[static_cast<std::size_t>(t)];
    if (!sc) sc = std::make_unique<Scratch>();
    BinnedBuilder builder(in, cfg, w.refs.data(), w.group_refs.data(), sc->bins);
    build_top_down(builder, cfg, f.root, sc->stack, f, Deferrer{cutoff, feed});
  });
  // An inner node's index is its second child.
  splice_fragments(w.fragments, bvh.nodes, 0, [](BvhNode& nd, const BinnedFragment& f) {
    if (!nd.is_leaf()) nd.index = static_cast<std::uint32_t>(f.position(nd.index));
  });
  bvh.cost = tree_cost(cfg.cost, bvh.nodes, w.refs.data(), !in.weights.empty());
}

}  // namespace

void build_binned_sah(const BuildInput& in, const BuildConfig& cfg, Bvh& bvh, BuildWorkspace& ws) {
  check_input(in, cfg);
  check_area_weights(cfg);
  check_area_eye(cfg);
  bvh.nodes.clear();
  bvh.prim_order.clear();
  bvh.cost = 0.0;
  const auto n = static_cast<std::uint32_t>(in.boxes.size());
  if (n == 0) return;
  if (!ws.impl_) ws.impl_ = std::make_unique<BuildWorkspace::Impl>();  // (a moved-from workspace)
  BuildWorkspace::Impl& w = *ws.impl_;
  const int threads = usable_threads();
  w.refs.resize(n);
  const RootBounds rb = make_records(in, w.refs.data(), threads);
  // The root: the group records when there are two groups or more (the top levels split
  // groups, and a node of one group continues with the group's primitives, contiguous in the
  // records), else the primitives.
  const std::size_t G = in.groups.empty() ? 0 : in.groups.size() - 1;
  if (!in.groups.empty() && (G == 0 || in.groups.front() != 0 || in.groups.back() != n))
    throw std::invalid_argument("build_binned_sah: group offsets do not span the " + std::to_string(n) + " primitives");
  BinnedTask root{{to_box(rb.lo, rb.hi), to_box(rb.clo, rb.chi), 0}, 0, n};
  const BuildConfig use = with_near_area_eye(cfg, root.extra.box);
  if (G > 1) root = {{root.extra.box, make_group_records(in.groups, w.refs.data(), w.group_refs), 1}, 0, static_cast<std::uint32_t>(G)};
  if (threads > 1 && root.size() >= kParallelFrom) {
    build_parallel(in, use, root, threads, w, bvh);
    bvh.prim_order.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n, kRecordsPerTask), [&](const tbb::blocked_range<std::uint32_t>& r) {
      for (std::uint32_t i = r.begin(); i < r.end(); ++i) bvh.prim_order[i] = w.refs[i].id;
    });
    return;
  }
  bvh.nodes.reserve(2 * static_cast<std::size_t>(n));
  BinnedBuilder builder(in, use, w.refs.data(), w.group_refs.data(), w.scratch.bins);
  build_top_down(builder, use, root, w.scratch.stack, bvh);
  bvh.prim_order.resize(n);
  for (std::uint32_t i = 0; i < n; ++i) bvh.prim_order[i] = w.refs[i].id;
}

}  // namespace ptc::bvh
