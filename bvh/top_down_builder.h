// The top-down skeleton both SAH builders share (the model: madmann91/bvh v2's
// top_down_sah_builder.h). The skeleton owns the stack of pending subtrees, the emission of
// nodes in depth-first pre-order (bvh.h's layout), the leaf decision and the SAH cost sum; a
// builder supplies only how a node's split is found and applied. Internal to bvh/ (included by
// sweep_sah_builder.cpp and binned_sah_builder.cpp, and by its test).
//
//   stack = {root}
//   while the stack is not empty:
//     task = pop;  box = builder.open(task)                 (the builder may rewrite the task)
//     emit node `box` (pre-order: the first child follows its parent; a second child's index is
//                      patched into its parent when the child is emitted)
//     if |P| = 1: leaf
//     must_split = |P| > max_leaf_size or builder.must_split(task)
//     if not must_split and builder.leaf_by_bound(task, A): leaf   (a cheap bound says so)
//     split = builder.find_split(task, A, must_split)           -> split.cost (inf: none), split.weight = W(P)
//     if not must_split and intersection * W(P) <= split.cost: leaf
//     k, first, second = builder.apply(task, split)             (primitives put in place)
//     inner node; a child of one primitive is emitted as a leaf at once when it is next in
//     pre-order (the first child, then the second when the first was one), else pushed.
// A is the node's area as the splits are priced: its surface area, with
// BuildConfig::area_weights its weighted area (Box3f::weighted_area), or with
// BuildConfig::area_eye the solid angle it shows that point (Box3f::area_from); the builders'
// half areas alike. A leaf costs intersection * W(P) * S, an inner node traversal * S, S the
// surface area, whatever the weights (CostAccumulator); their sum over S(root) is Bvh::cost
// (sah_cost.h's formula).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <optional>
#include <cstdint>
#include <vector>

#include "bvh/build_config.h"

namespace ptc::bvh {

/// Sum of a tree's SAH terms (see sah_cost.h), divided by A(root) at the end.
struct CostAccumulator {
  double area_terms = 0.0;   ///< sum traversal * A(inner) + intersection * W * A(leaf)
  double count_terms = 0.0;  ///< the same sum with every A = 1 (used when A(root) = 0)
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

/// The weight of a primitive (BuildInput::weights, or 1).
[[nodiscard]] inline double weight_of(const BuildInput& in, std::uint32_t prim) {
  return in.weights.empty() ? 1.0 : in.weights[prim];
}

/// The preconditions of BuildInput and BuildConfig (assertions: programmer errors).
void check_input(const BuildInput& in, const BuildConfig& cfg);

/// BuildConfig::area_weights not all finite and above 0: std::invalid_argument naming the axis.
void check_area_weights(const BuildConfig& cfg);

/// BuildConfig::area_eye not finite: std::invalid_argument naming the axis.
void check_area_eye(const BuildConfig& cfg);

/// `cfg` as the builders use it for a tree whose root box is `root`: a BuildConfig::area_eye
/// farther than 2^20 root diagonals from the root's centre is moved toward it, along the same
/// direction, to that distance (it prices every box alike but for a factor, and the float
/// solid angles stay in range).
[[nodiscard]] inline BuildConfig with_near_area_eye(BuildConfig cfg, const Box3f& root) {
  if (!cfg.area_eye || root.empty()) return cfg;
  double v[3], d2 = 0.0, diag2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    v[a] = double((*cfg.area_eye)[a]) - 0.5 * (double(root.lo[a]) + root.hi[a]);
    d2 += v[a] * v[a], diag2 += (double(root.hi[a]) - root.lo[a]) * (double(root.hi[a]) - root.lo[a]);
  }
  const double far = 1048576.0 * std::sqrt(diag2), d = std::sqrt(d2);
  if (!(far > 0.0) || d <= far) return cfg;
  for (int a = 0; a < 3; ++a) (*cfg.area_eye)[a] = static_cast<float>(0.5 * (double(root.lo[a]) + root.hi[a]) + v[a] * (far / d));
  return cfg;
}

/// The area weights the splits are priced with: BuildConfig::area_weights over the largest of
/// them (only their ratios matter; so the float half areas stay in range whatever their scale).
/// (1, 1, 1) stays (1, 1, 1), the same bits as the plain surface area.
[[nodiscard]] inline std::array<float, 3> split_area_weights(const BuildConfig& cfg) {
  const auto& w = cfg.area_weights;
  const float top = std::max(w[0], std::max(w[1], w[2]));
  return {w[0] / top, w[1] / top, w[2] / top};
}

/// NaN in a box or centroid (comparisons with NaN break every ordering the builders rely on):
/// std::invalid_argument naming the first such primitive.
void check_no_nan(const BuildInput& in);

inline constexpr std::uint32_t kNoParent = 0xffffffffu;

/// A pending subtree: what the builder carries along, the items [begin, end) (primitives, or a
/// builder's own kind, such as the binned builder's groups), and the node whose `index`
/// receives the subtree's root (kNoParent for a first child, which is its parent + 1). `extra`
/// comes first: a box at its start then lies on the task's 16-byte boundaries, so that reading
/// it from a task just copied is forwarded from the copy's stores (a box at offset 12 made the
/// binned build 5% slower: store-to-load forwarding failed at every node).
template <class Extra>
struct TopDownTask {
  Extra extra{};
  std::uint32_t begin = 0, end = 0;
  std::uint32_t patch_parent = kNoParent;
  [[nodiscard]] std::uint32_t size() const { return end - begin; }
};

/// What a builder's apply() returns: the first child holds items [begin, begin + k), the
/// second [begin + k, end), 0 < k < size.
template <class Extra>
struct TopDownChildren {
  std::uint32_t k = 0;
  Extra first{}, second{};
};

/// What a builder supplies (see the file comment; Split has at least `cost` and `weight`).
template <class B>
concept TopDownBuilder = requires(B& b, typename B::Task& task, const typename B::Task& ct,
                                  const typename B::Split& split, double area, bool must_split) {
  { b.open(task) } -> std::same_as<Box3f>;  // the node's box (union of its primitives' boxes)
  { b.single_primitive(ct) } -> std::same_as<bool>;  // a task of one primitive (a leaf)
  { b.must_split(ct) } -> std::same_as<bool>;        // beyond |P| > max_leaf_size
  { b.leaf_by_bound(ct, area) } -> std::same_as<bool>;
  { b.leaf_weight(ct) } -> std::same_as<double>;  // W(P) of a leaf made before find_split
  { b.find_split(ct, area, must_split) } -> std::same_as<typename B::Split>;
  { split.cost } -> std::convertible_to<double>;
  { split.weight } -> std::convertible_to<double>;
  { b.apply(ct, split) } -> std::same_as<TopDownChildren<decltype(ct.extra)>>;
};

/// The default of build_top_down's `defer` (and the sequential wide walks', wide_bvh.cpp): every
/// task is built here. The parallel forms defer through fragments.h.
struct BuildEverything {
  template <class Task>
  bool wants(const Task&) const { return false; }
  template <class Task>
  void take(std::uint32_t, const Task&) {}
};

/// Builds the tree of `root` into bvh.nodes (appended; the caller clears and reserves them)
/// and sets bvh.cost. bvh.prim_order is the builder's business.
///
/// `defer` lets a parallel build cut the tree into fragments: a task other than the root for
/// which defer.wants(task) holds is not opened here; a placeholder node (empty box, index and
/// count 0, its parent patched as for any node) is emitted in its place and defer.take(index,
/// task) is told, and the subtree is someone else's (the same skeleton over that task as its
/// root builds it, node for node, as it would have been built here). Splicing each fragment in
/// at its placeholder gives the tree built without deferring, in the same pre-order; bvh.cost
/// then counts only the nodes built here.
/// (`Tree`: a Bvh, or anything with `nodes`, a vector of BvhNode, and `cost`.)
template <TopDownBuilder B, class Tree = Bvh, class Defer = BuildEverything>
void build_top_down(B& builder, const BuildConfig& cfg, const typename B::Task& root,
                    std::vector<typename B::Task>& stack, Tree& bvh, Defer&& defer = {}) {
  using Task = typename B::Task;
  const SahCostModel& m = cfg.cost;
  const std::array<float, 3> aw = split_area_weights(cfg);
  CostAccumulator acc;
  // A node for `task` (already opened, with its box), its parent patched.
  auto emit = [&](const Task& task, const Box3f& box) {
    const auto idx = static_cast<std::uint32_t>(bvh.nodes.size());
    bvh.nodes.emplace_back().bounds = box;
    if (task.patch_parent != kNoParent) bvh.nodes[task.patch_parent].index = idx;
    return idx;
  };
  auto make_leaf = [&](std::uint32_t idx, const Task& task, double area, double weight) {
    bvh.nodes[idx].index = task.begin;
    bvh.nodes[idx].count = task.size();
    acc.leaf(m, area, weight);
  };
  auto emit_leaf = [&](Task task) {
    const Box3f box = builder.open(task);
    make_leaf(emit(task, box), task, box.surface_area(), builder.leaf_weight(task));
  };
  stack.clear();
  stack.push_back(root);
  bool at_root = true;
  while (!stack.empty()) {
    Task task = stack.back();
    stack.pop_back();
    if (!at_root && defer.wants(task)) {
      defer.take(emit(task, Box3f{}), task);
      continue;
    }
    at_root = false;
    const Box3f box = builder.open(task);
    const std::uint32_t idx = emit(task, box);
    const double area = box.surface_area();  // (the cost's; the splits are chosen by `chooser`)
    if (task.size() == 1) {
      make_leaf(idx, task, area, builder.leaf_weight(task));
      continue;
    }
    const double chooser = cfg.area_eye ? box.area_from(*cfg.area_eye) : box.weighted_area(aw);
    const bool must_split = task.size() > cfg.max_leaf_size || builder.must_split(task);
    if (!must_split && builder.leaf_by_bound(task, chooser)) {
      make_leaf(idx, task, area, builder.leaf_weight(task));
      continue;
    }
    const typename B::Split split = builder.find_split(task, chooser, must_split);
    const double weight = static_cast<double>(split.weight);
    if (!must_split && m.intersection * weight <= split.cost) {
      make_leaf(idx, task, area, weight);
      continue;
    }
    const auto children = builder.apply(task, split);
    acc.inner(m, area);
    const Task first{children.first, task.begin, task.begin + children.k, kNoParent};
    const Task second{children.second, task.begin + children.k, task.end, idx};
    if (builder.single_primitive(first)) {
      emit_leaf(first);
      if (builder.single_primitive(second)) emit_leaf(second);
      else stack.push_back(second);
      continue;
    }
    stack.push_back(second);
    stack.push_back(first);
  }
  bvh.cost = acc.total(bvh.nodes[0].bounds.surface_area());
}

}  // namespace ptc::bvh
