#include "toolkit/clustering/sah_split.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

namespace ptc {

namespace {

/// Counts distinct vertices of successive triangle sets without clearing a V-sized array each
/// time: a vertex counts as seen when its stamp equals the current pass.
class VertexCounter {
 public:
  explicit VertexCounter(std::size_t vertex_count) : stamp_of_(vertex_count, 0) {}
  void new_pass() {
    if (++stamp_ == 0) {  // wrapped: forget all old stamps
      std::fill(stamp_of_.begin(), stamp_of_.end(), 0u);
      stamp_ = 1;
    }
    count_ = 0;
  }
  void add(const Tri& f) {
    for (const std::uint32_t v : f)
      if (stamp_of_[v] != stamp_) {
        stamp_of_[v] = stamp_;
        ++count_;
      }
  }
  [[nodiscard]] std::uint32_t count() const { return count_; }

 private:
  std::vector<std::uint32_t> stamp_of_;
  std::uint32_t stamp_ = 0, count_ = 0;
};

/// The fill term's rest (see the header): room left empty, in triangles, in the leaves a child of
/// n triangles and v distinct vertices needs at least.
double fill_rest(std::uint32_t n, std::uint32_t v, const ClusterLimits& lim) {
  const std::uint64_t leaves = std::max((std::uint64_t{n} + lim.max_triangles - 1) / lim.max_triangles,
                                        (std::uint64_t{v} + lim.max_vertices - 1) / lim.max_vertices);
  const double f = std::max(double(n) / lim.max_triangles, double(v) / lim.max_vertices);
  return (double(leaves) - f) * double(n) / f;
}

class SahSplitter {
 public:
  SahSplitter(const Mesh& mesh, const ClusterLimits& lim, const SahSplitOptions& opt)
      : tris_(mesh.triangles()), lim_(lim), opt_(opt), counter_(mesh.vertex_count()) {
    const std::size_t T = tris_.size();
    centroid_.resize(T);
    box_.resize(T);
    for (std::size_t t = 0; t < T; ++t) {
      const auto p = mesh.corners(t);
      centroid_[t] = (p[0] + p[1] + p[2]) / 3.0;
      for (const Vec3& q : p) box_[t].extend(q);
    }
    const std::size_t K = opt.bins;
    bin_box_.resize(K);
    bin_first_.resize(K + 1);
    left_box_.resize(K);
    right_box_.resize(K);
    left_n_.resize(K);
    right_n_.resize(K);
    left_v_.resize(K);
    right_v_.resize(K);
  }

  /// Leaf index per triangle.
  std::vector<std::uint32_t> run() {
    const auto T = static_cast<std::uint32_t>(tris_.size());
    std::vector<std::uint32_t> label(T, 0);
    order_.resize(T);
    std::iota(order_.begin(), order_.end(), 0u);
    scratch_.resize(T);
    bin_of_.resize(T);
    std::uint32_t leaves = 0;
    struct Range {
      std::uint32_t begin, end;
    };
    std::vector<Range> stack;
    if (T > 0) stack.push_back({0, T});
    while (!stack.empty()) {
      const Range r = stack.back();
      stack.pop_back();
      if (is_leaf(r.begin, r.end)) {
        for (std::uint32_t i = r.begin; i < r.end; ++i) label[order_[i]] = leaves;
        ++leaves;
        continue;
      }
      const std::uint32_t mid = split(r.begin, r.end);
      stack.push_back({mid, r.end});  // left child popped first: leaves numbered left to right
      stack.push_back({r.begin, mid});
    }
    return label;
  }

 private:
  bool is_leaf(std::uint32_t begin, std::uint32_t end) {
    if (end - begin > lim_.max_triangles) return false;
    counter_.new_pass();
    for (std::uint32_t i = begin; i < end; ++i) counter_.add(tris_[order_[i]]);
    return counter_.count() <= lim_.max_vertices;
  }

  /// Bin of a centroid coordinate x in [lo, lo + extent], extent > 0; NaN-safe, clamped.
  std::uint32_t bin_of(double x, double lo, double extent) const {
    const double K = opt_.bins;
    const double b = (x - lo) / extent * K;  // divide first: K / extent may overflow
    return b >= K ? opt_.bins - 1 : (b > 0 ? static_cast<std::uint32_t>(b) : 0u);
  }

  /// Partitions order_[begin, end) and returns the split position (begin < mid < end).
  std::uint32_t split(std::uint32_t begin, std::uint32_t end) {
    const std::uint32_t K = opt_.bins;
    Box3 cbox, node_box;
    for (std::uint32_t i = begin; i < end; ++i) {
      cbox.extend(centroid_[order_[i]]);
      node_box.extend(box_[order_[i]]);
    }
    const bool flat = !(node_box.surface_area() > 0);  // a line or a point: count cost only
    auto area = [&](const Box3& b) { return flat ? 1.0 : b.surface_area(); };

    double best_cost = std::numeric_limits<double>::infinity();
    int best_axis = -1;
    std::uint32_t best_plane = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double lo = cbox.lo[axis], extent = cbox.hi[axis] - cbox.lo[axis];
      if (!(extent > 0)) continue;
      // Counting sort of the node's triangles into bins (stable: triangle order within a bin).
      std::fill(bin_first_.begin(), bin_first_.end(), 0u);
      std::fill(bin_box_.begin(), bin_box_.end(), Box3{});
      for (std::uint32_t i = begin; i < end; ++i) {
        const std::uint32_t t = order_[i];
        const std::uint32_t b = bin_of(centroid_[t][axis], lo, extent);
        bin_of_[i] = b;
        ++bin_first_[b + 1];
        bin_box_[b].extend(box_[t]);
      }
      std::partial_sum(bin_first_.begin(), bin_first_.end(), bin_first_.begin());
      {
        std::vector<std::uint32_t> fill(bin_first_.begin(), bin_first_.end() - 1);
        for (std::uint32_t i = begin; i < end; ++i) scratch_[begin + fill[bin_of_[i]]++] = order_[i];
      }
      // Sweeps: left_*[b] over bins 0..b, right_*[b] over bins b..K-1.
      Box3 acc;
      counter_.new_pass();
      for (std::uint32_t b = 0; b < K; ++b) {
        acc.extend(bin_box_[b]);
        for (std::uint32_t i = bin_first_[b]; i < bin_first_[b + 1]; ++i) counter_.add(tris_[scratch_[begin + i]]);
        left_box_[b] = acc;
        left_n_[b] = bin_first_[b + 1];
        left_v_[b] = counter_.count();
      }
      acc = Box3{};
      counter_.new_pass();
      for (std::uint32_t b = K; b-- > 0;) {
        acc.extend(bin_box_[b]);
        for (std::uint32_t i = bin_first_[b]; i < bin_first_[b + 1]; ++i) counter_.add(tris_[scratch_[begin + i]]);
        right_box_[b] = acc;
        right_n_[b] = (end - begin) - bin_first_[b];
        right_v_[b] = counter_.count();
      }
      for (std::uint32_t b = 0; b + 1 < K; ++b) {
        const std::uint32_t nl = left_n_[b], nr = right_n_[b + 1];
        if (nl == 0 || nr == 0) continue;
        const double al = area(left_box_[b]), ar = area(right_box_[b + 1]);
        const double cost = al * nl + ar * nr +
                            opt_.fill_weight * (al * fill_rest(nl, left_v_[b], lim_) +
                                                ar * fill_rest(nr, right_v_[b + 1], lim_));
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = axis;
          best_plane = b;
        }
      }
    }

    if (best_axis < 0) {  // no plane (all centroids equal, or NaN costs): index-order median
      std::sort(order_.begin() + begin, order_.begin() + end);
      return begin + (end - begin) / 2;
    }
    // Stable partition by the chosen plane (bins recomputed exactly as above).
    const double lo = cbox.lo[best_axis], extent = cbox.hi[best_axis] - cbox.lo[best_axis];
    std::uint32_t l = begin;
    std::uint32_t nr = 0;
    for (std::uint32_t i = begin; i < end; ++i) {
      const std::uint32_t t = order_[i];
      if (bin_of(centroid_[t][best_axis], lo, extent) <= best_plane)
        order_[l++] = t;
      else
        scratch_[nr++] = t;
    }
    std::copy(scratch_.begin(), scratch_.begin() + nr, order_.begin() + l);
    return l;
  }

  std::span<const Tri> tris_;
  ClusterLimits lim_;
  SahSplitOptions opt_;
  VertexCounter counter_;
  std::vector<Vec3> centroid_;
  std::vector<Box3> box_;
  std::vector<std::uint32_t> order_, scratch_, bin_of_;
  std::vector<Box3> bin_box_, left_box_, right_box_;
  std::vector<std::uint32_t> bin_first_, left_n_, right_n_, left_v_, right_v_;
};

}  // namespace

ClusterLimits sah_split_limits(const ClusterConfig& config) {
  if (config.max_count < 3)
    throw std::invalid_argument(fmt::format(
        "SAH split: max_count (vertices per cluster) must be >= 3 so that any triangle fits, got {}", config.max_count));
  ClusterLimits lim;
  lim.max_vertices = config.max_count;
  lim.max_triangles =
      config.max_triangles != 0
          ? config.max_triangles
          : static_cast<std::uint32_t>(std::min<std::uint64_t>(2 * std::uint64_t{config.max_count}, 0xffffffffu));
  return lim;
}

Clustering sah_split_leaves(const Mesh& mesh, const ClusterConfig& config, const SahSplitOptions& options) {
  const ClusterLimits lim = sah_split_limits(config);
  if (options.bins < 2 || options.bins > 1024)
    throw std::invalid_argument(fmt::format("SAH split: bins must be in [2, 1024], got {}", options.bins));
  if (!(options.fill_weight >= 0) || !std::isfinite(options.fill_weight))
    throw std::invalid_argument(fmt::format("SAH split: fill_weight must be finite and >= 0, got {}", options.fill_weight));
  if (mesh.triangle_count() >= 0xffffffffu) throw std::invalid_argument("SAH split: more than 2^32 - 2 triangles");
  SahSplitter s(mesh, lim, options);
  const std::vector<std::uint32_t> label = s.run();
  return clustering_from_labels(label, mesh.triangles());
}

Clustering sah_split_clusters(const Mesh& mesh, const ClusterConfig& config, const SahSplitOptions& options) {
  Clustering leaves = sah_split_leaves(mesh, config, options);
  return split_disconnected(leaves, mesh.triangles());
}

}  // namespace ptc
