#include "bvh/sweep_sah_builder.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <vector>

#include "bvh/top_down_builder.h"

namespace ptc::bvh {

namespace {

// The full sweep as a top-down builder: primitives are permuted in place in bvh.prim_order; a
// node's box and weight are recomputed from its primitives (the reference favours plainness).
class SweepBuilder {
 public:
  struct NoExtra {};
  using Task = TopDownTask<NoExtra>;
  struct Split {
    double cost = std::numeric_limits<double>::infinity();  // inf: no usable plane
    double weight = 0.0;                                    // W(P)
    int axis = -1;                                          // -1: object median in the current order
    std::uint32_t k = 0;                                    // split after position k of the sorted order
  };

  SweepBuilder(const BuildInput& in, const BuildConfig& cfg, AlignedVector<std::uint32_t>& prim_order)
      : in_(in), cfg_(cfg), aw_(split_area_weights(cfg)), prims_(prim_order), order_(prim_order.size()), suffix_area_(prim_order.size() + 1),
        suffix_weight_(prim_order.size() + 1) {}

  Box3f open(Task& t) const {
    Box3f box;
    for (std::uint32_t i = t.begin; i < t.end; ++i) box.extend(in_.boxes[prims_[i]]);
    return box;
  }
  bool single_primitive(const Task& t) const { return t.size() == 1; }
  // A box's area as the splits are priced (BuildConfig::area_weights, or area_eye).
  double split_area(const Box3f& b) const { return cfg_.area_eye ? b.area_from(*cfg_.area_eye) : b.weighted_area(aw_); }
  bool must_split(const Task&) const { return false; }
  bool leaf_by_bound(const Task&, double) const { return false; }
  double leaf_weight(const Task& t) const {
    double w = 0.0;
    for (std::uint32_t i = t.begin; i < t.end; ++i) w += weight_of(in_, prims_[i]);
    return w;
  }

  // Best split over all axes and positions: each axis sorted by centroid (ties by id), the
  // right sides' areas and weights from a backward pass, the left sides' from a forward one.
  Split find_split(const Task& t, double area, bool) {
    Split s;
    s.weight = leaf_weight(t);
    if (area <= 0.0) return s;
    const SahCostModel& m = cfg_.cost;
    const std::uint32_t* prims = prims_.data() + t.begin;
    const std::uint32_t count = t.size();
    for (int axis = 0; axis < 3; ++axis) {
      std::copy(prims, prims + count, order_.begin());
      sort_by_centroid(order_.data(), count, axis);
      Box3f right;
      double wr = 0.0;
      for (std::uint32_t i = count; i-- > 0;) {
        right.extend(in_.boxes[order_[i]]);
        wr += weight_of(in_, order_[i]);
        suffix_area_[i] = split_area(right);
        suffix_weight_[i] = wr;
      }
      Box3f left;
      double wl = 0.0;
      for (std::uint32_t k = 1; k < count; ++k) {  // left = order[0, k), right = order[k, count)
        left.extend(in_.boxes[order_[k - 1]]);
        wl += weight_of(in_, order_[k - 1]);
        const double c =
            m.traversal + m.intersection * (split_area(left) * wl + suffix_area_[k] * suffix_weight_[k]) / area;
        if (c < s.cost) s.cost = c, s.axis = axis, s.k = k;
      }
    }
    return s;
  }

  TopDownChildren<NoExtra> apply(const Task& t, const Split& s) {
    if (s.axis < 0) return {t.size() / 2};  // no usable plane (zero-area node): object median
    sort_by_centroid(prims_.data() + t.begin, t.size(), s.axis);
    return {s.k};
  }

 private:
  void sort_by_centroid(std::uint32_t* p, std::uint32_t count, int axis) const {
    std::sort(p, p + count, [&](std::uint32_t a, std::uint32_t b) {
      const float ca = in_.centroids[a][axis], cb = in_.centroids[b][axis];
      return ca != cb ? ca < cb : a < b;
    });
  }

  const BuildInput& in_;
  const BuildConfig& cfg_;
  const std::array<float, 3> aw_;  // split_area_weights(cfg)
  AlignedVector<std::uint32_t>& prims_;
  std::vector<std::uint32_t> order_;
  std::vector<double> suffix_area_, suffix_weight_;
};

}  // namespace

Bvh build_sweep_sah(const BuildInput& in, const BuildConfig& cfg) {
  check_input(in, cfg);
  check_area_weights(cfg);
  check_area_eye(cfg);
  check_no_nan(in);
  Bvh bvh;
  const auto n = static_cast<std::uint32_t>(in.boxes.size());
  if (n == 0) return bvh;
  bvh.prim_order.resize(n);
  std::iota(bvh.prim_order.begin(), bvh.prim_order.end(), 0u);
  bvh.nodes.reserve(2 * static_cast<std::size_t>(n));
  Box3f root;
  if (cfg.area_eye)
    for (const Box3f& b : in.boxes) root.extend(b);
  const BuildConfig use = with_near_area_eye(cfg, root);
  SweepBuilder builder(in, use, bvh.prim_order);
  std::vector<SweepBuilder::Task> stack;
  build_top_down(builder, use, {{}, 0, n}, stack, bvh);
  return bvh;
}

}  // namespace ptc::bvh
