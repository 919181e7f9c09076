#include "bvh/wide_bvh.h"

#include "bvh/fragments.h"
#include "bvh/threads.h"
#include "bvh/top_down_builder.h"

#include <algorithm>
#include <map>
#include <memory>
#include <type_traits>
#include <utility>

namespace ptc::bvh {

namespace {

WideNode empty_node() {
  WideNode n;
  const Box3f e;
  for (int i = 0; i < 4; ++i) {
    n.set_child_box(i, e);
    n.child[i] = WideNode::kEmptySlot;
    n.count[i] = 0;
  }
  return n;
}

// Both walks below allocate a node's inner children (consecutive indices, in slot order) when
// they open the node, and open nodes last-in first-out: a node, then its children, then the
// descendants of its last child, ..., of its first. So their parallel forms are fragments.h's:
// the tree cut at a fixed level (LevelCut, through the walks' `defer` hook), the fragments walked
// at once and spliced; the same nodes in the same order as the sequential walk.

struct CollapseItem {
  std::uint32_t binary, wide, depth;  // binary node to expand, wide node to fill, its level
};
struct RegroupItem {
  std::uint32_t node4, node8, depth;
};
inline std::uint32_t local_of(const CollapseItem& it) { return it.wide; }  // (the node to fill)
inline std::uint32_t local_of(const RegroupItem& it) { return it.node8; }

// The collapse from `root` (its wide node already in `nodes`); raises depth, adds to leaves.
template <class Nodes, class Defer>
void collapse_walk(const Bvh& bvh, CollapseItem root, Nodes& nodes, std::vector<CollapseItem>& stack,
                   std::uint32_t& depth, std::uint32_t& leaves, Defer& defer) {
  stack.clear();
  stack.push_back(root);
  bool at_root = true;
  while (!stack.empty()) {
    const CollapseItem it = stack.back();
    stack.pop_back();
    if (!at_root && defer.wants(it)) {
      defer.take(static_cast<std::uint32_t>(nodes.size()), it);  // (the nodes allocated by now)
      continue;
    }
    at_root = false;
    depth = std::max(depth, it.depth);
    std::uint32_t kids[4];
    const int nk = wide_children(bvh, it.binary, kids);
    for (int i = 0; i < nk; ++i) {
      const BvhNode& c = bvh.nodes[kids[i]];
      WideNode& dst = nodes[it.wide];
      dst.set_child_box(i, c.bounds);
      if (c.is_leaf()) {
        dst.child[i] = c.index;
        dst.count[i] = c.count;
        ++leaves;
      } else {
        const auto idx = static_cast<std::uint32_t>(nodes.size());
        nodes[it.wide].child[i] = idx;  // (dst may dangle after the push_back below)
        nodes[it.wide].count[i] = 0;
        nodes.push_back(empty_node());
        stack.push_back({kids[i], idx, it.depth + 1});
      }
    }
  }
}

// regroup_subtree's walk from `root` (its 8-wide node already in `out`).
template <class Nodes, class Defer>
void regroup_walk(std::span<const WideNode> w4, RegroupItem root, Nodes& out,
                  std::vector<RegroupItem>& stack, std::uint32_t& depth, std::uint32_t linked_below,
                  std::span<const std::uint32_t> linked8, std::vector<SlotSource>* sources, Defer& defer) {
  // A slot of the 8-wide node being filled; an inner one keeps its area and its node's number of
  // live children, computed once when it enters (the choice below reads them up to seven times).
  struct Slot {
    Box3f box;
    std::uint32_t child, count;
    SlotSource from;
    int live;  // an inner child that may be opened: live children of w4[child]; otherwise 9
    float area;
  };
  auto slot_of = [&](std::uint32_t n4, int j) {
    const WideNode& n = w4[n4];
    Slot s{n.child_box(j), n.child[j], n.count[j], {n4, static_cast<std::uint32_t>(j)}, 9, 0.0f};
    if (s.count == 0 && s.child >= linked_below) {
      const WideNode& c = w4[s.child];
      s.live = 0;
      for (int k = 0; k < 4; ++k) s.live += !c.is_empty(k);
      if (s.live == 0) s.live = 9;  // (a node without children: nothing to open; the builds make none)
      s.area = static_cast<float>(s.box.surface_area());
    }
    return s;
  };
  stack.clear();
  stack.push_back(root);
  bool at_root = true;
  while (!stack.empty()) {
    const RegroupItem it = stack.back();
    stack.pop_back();
    if (!at_root && defer.wants(it)) {
      defer.take(static_cast<std::uint32_t>(out.size()), it);
      continue;
    }
    at_root = false;
    depth = std::max(depth, it.depth);
    if (sources) sources->resize(8 * std::size_t{out.size()});  // (room for it.node8's slots)
    Slot s[8];
    int ns = 0;
    for (int j = 0; j < 4; ++j)
      if (!w4[it.node4].is_empty(j)) s[ns++] = slot_of(it.node4, j);
    for (;;) {  // open the inner child of largest area whose children fit
      int best = -1;
      float best_area = -1.0f;
      for (int i = 0; i < ns; ++i)
        if (ns - 1 + s[i].live <= 8 && s[i].area > best_area) best = i, best_area = s[i].area;
      if (best < 0) break;
      const std::uint32_t c = s[best].child;
      int j = 0;
      while (w4[c].is_empty(j)) ++j;  // the first live child takes the opened slot, the others go last
      s[best] = slot_of(c, j);
      for (++j; j < 4; ++j)
        if (!w4[c].is_empty(j)) s[ns++] = slot_of(c, j);
    }
    for (int i = 0; i < 8; ++i) {
      std::uint32_t child = WideNode::kEmptySlot, count = 0;
      Box3f box;
      SlotSource from{WideNode::kEmptySlot, 0};
      if (i < ns) {
        box = s[i].box, count = s[i].count, from = s[i].from;
        if (count != 0) {
          child = s[i].child;
        } else if (s[i].child < linked_below) {
          child = linked8[s[i].child];
        } else {
          child = static_cast<std::uint32_t>(out.size());
          out.emplace_back();
          stack.push_back({s[i].child, child, it.depth + 1});
        }
      }
      WideNode8& dst = out[it.node8];
      dst.set_child_box(i, box);
      dst.child[i] = child, dst.count[i] = count;
      if (sources) (*sources)[8 * std::size_t{it.node8} + i] = from;
    }
  }
}

// Defers the items at one level of the walk to fragments of their own (fragments.h).
template <class Frag>
struct LevelCut {
  std::uint32_t level;
  FragmentFeed<Frag>& feed;
  template <class Item>
  bool wants(const Item& it) const { return it.depth == level; }
  template <class Item>
  void take(std::uint32_t allocated, const Item& it) { feed.add(local_of(it), allocated, it); }
};

// A wide node's inner children through the fragment's final positions.
constexpr auto kRemapWideChildren = [](auto& nd, const auto& f) {
  for (int k = 0; k < std::remove_reference_t<decltype(nd)>::kWidth; ++k)
    if (nd.count[k] == 0 && nd.child[k] != WideNode::kEmptySlot) nd.child[k] = static_cast<std::uint32_t>(f.position(nd.child[k]));
};

// The parallel forms: from these many nodes (binary ones for the collapse, 4-wide ones for the
// regroup) on more than one thread, cut at this level (at most 4^3 and 8^2 fragments below the
// top one).
constexpr std::size_t kParallelCollapseFrom = std::size_t{1} << 16;
constexpr std::uint32_t kCollapseCutDepth = 4;
constexpr std::size_t kParallelRegroupFrom = std::size_t{1} << 14;
constexpr std::uint32_t kRegroupCutDepth = 3;

}  // namespace

struct WideWorkspace::Impl {
  std::vector<CollapseItem> collapse_stack;  // the sequential walks' work lists
  std::vector<RegroupItem> regroup_stack;
  FragmentPool<Fragment<WideNode, CollapseItem>> collapse_fragments;  // the parallel walks'
  FragmentPool<Fragment<WideNode8, RegroupItem>> regroup_fragments;   // (their work lists: thread_local)
};

WideWorkspace::WideWorkspace() : impl_(std::make_unique<Impl>()) {}
WideWorkspace::~WideWorkspace() = default;
WideWorkspace::WideWorkspace(const WideWorkspace&) : impl_(std::make_unique<Impl>()) {}
WideWorkspace& WideWorkspace::operator=(const WideWorkspace&) { return *this; }
WideWorkspace::WideWorkspace(WideWorkspace&&) noexcept = default;
WideWorkspace& WideWorkspace::operator=(WideWorkspace&&) noexcept = default;

namespace {

bool collapse_in_parallel(const Bvh& bvh) { return bvh.nodes.size() >= kParallelCollapseFrom && usable_threads() >= 2; }
bool regroup_in_parallel(const WideBvh& w4) { return w4.nodes.size() >= kParallelRegroupFrom && usable_threads() >= 2; }

// Both collapses: the root's fields, then the walk (sequential with `stack`, or in fragments).
void collapse(const Bvh& bvh, WideBvh& w, std::vector<CollapseItem>* stack, WideWorkspace::Impl* wk) {
  w.nodes.clear();
  w.root = 0, w.bounds = Box3f{}, w.depth = 0, w.leaves = 0;
  if (bvh.nodes.empty()) return;
  w.bounds = bvh.nodes[0].bounds;
  if (bvh.nodes[0].is_leaf()) {
    w.nodes.push_back(empty_node());
    w.nodes[0].set_child_box(0, bvh.nodes[0].bounds);
    w.nodes[0].child[0] = bvh.nodes[0].index;
    w.nodes[0].count[0] = bvh.nodes[0].count;
    w.depth = 1, w.leaves = 1;
    return;
  }
  if (stack) {
    w.nodes.reserve(bvh.nodes.size() / 2 + 1);
    w.nodes.push_back(empty_node());
    BuildEverything none;
    collapse_walk(bvh, {0, 0, 1}, w.nodes, *stack, w.depth, w.leaves, none);
    return;
  }
  using Frag = Fragment<WideNode, CollapseItem>;
  auto& pool = wk->collapse_fragments;
  walk_fragments(pool, CollapseItem{0, 0, 1}, [&](Frag& f, FragmentFeed<Frag>& feed) {
    thread_local std::vector<CollapseItem> local_stack;
    LevelCut<Frag> cut{kCollapseCutDepth, feed};
    f.nodes.push_back(empty_node());
    collapse_walk(bvh, {f.root.binary, 0, f.root.depth}, f.nodes, local_stack, f.depth, f.leaves, cut);
  });
  splice_fragments(pool, w.nodes, 0, kRemapWideChildren);
  for (std::size_t i = 0; i < pool.used; ++i) w.depth = std::max(w.depth, pool.all[i]->depth), w.leaves += pool.all[i]->leaves;
}

void regroup(const WideBvh& w4, WideBvh8& out, std::vector<RegroupItem>* stack, WideWorkspace::Impl* wk) {
  out.nodes.clear();
  out.root = 0, out.depth = 0;
  if (w4.nodes.empty()) return;
  if (stack) {
    out.nodes.reserve(w4.nodes.size());  // at least one 4-wide node per 8-wide one
    out.nodes.emplace_back();
    BuildEverything none;
    regroup_walk(w4.nodes, {w4.root, 0, 1}, out.nodes, *stack, out.depth, 0, {}, nullptr, none);
    return;
  }
  using Frag = Fragment<WideNode8, RegroupItem>;
  auto& pool = wk->regroup_fragments;
  const std::span<const WideNode> nodes4(w4.nodes);
  walk_fragments(pool, RegroupItem{w4.root, 0, 1}, [&](Frag& f, FragmentFeed<Frag>& feed) {
    thread_local std::vector<RegroupItem> local_stack;
    LevelCut<Frag> cut{kRegroupCutDepth, feed};
    f.nodes.emplace_back();
    regroup_walk(nodes4, {f.root.node4, 0, f.root.depth}, f.nodes, local_stack, f.depth, 0, {}, nullptr, cut);
  });
  splice_fragments(pool, out.nodes, 0, kRemapWideChildren);
  for (std::size_t i = 0; i < pool.used; ++i) out.depth = std::max(out.depth, pool.all[i]->depth);
}

}  // namespace

WideBvh collapse_to_wide(const Bvh& bvh) {
  WideBvh w;
  collapse_to_wide(bvh, w);
  return w;
}

void collapse_to_wide(const Bvh& bvh, WideBvh& w) {
  WideWorkspace ws;  // (one allocation: its work lists and fragments start empty)
  collapse_to_wide(bvh, w, ws);
}

void collapse_to_wide(const Bvh& bvh, WideBvh& w, WideWorkspace& ws) {
  if (!ws.impl_) ws.impl_ = std::make_unique<WideWorkspace::Impl>();  // (a moved-from workspace)
  if (collapse_in_parallel(bvh)) collapse(bvh, w, nullptr, ws.impl_.get());
  else collapse(bvh, w, &ws.impl_->collapse_stack, nullptr);
}

std::uint32_t regroup_subtree(std::span<const WideNode> w4, std::uint32_t root4, AlignedVector<WideNode8>& out,
                              std::uint32_t& depth, std::uint32_t linked_below, std::span<const std::uint32_t> linked8,
                              std::vector<SlotSource>* sources) {
  std::vector<RegroupItem> stack;
  stack.reserve(64);
  const auto root8 = static_cast<std::uint32_t>(out.size());
  out.emplace_back();
  BuildEverything none;
  regroup_walk(w4, {root4, root8, 1}, out, stack, depth, linked_below, linked8, sources, none);
  return root8;
}

void regroup_to_8(const WideBvh& w4, WideBvh8& out) {
  WideWorkspace ws;
  regroup_to_8(w4, out, ws);
}

void regroup_to_8(const WideBvh& w4, WideBvh8& out, WideWorkspace& ws) {
  if (!ws.impl_) ws.impl_ = std::make_unique<WideWorkspace::Impl>();
  if (regroup_in_parallel(w4)) regroup(w4, out, nullptr, ws.impl_.get());
  else regroup(w4, out, &ws.impl_->regroup_stack, nullptr);
}

std::vector<std::string> validate_wide(const WideBvh& wide, const Bvh& bvh) {
  std::vector<std::string> issues;
  auto fail = [&](std::string s) {
    if (issues.size() < 20) issues.push_back(std::move(s));
  };
  if (bvh.nodes.empty() != wide.nodes.empty()) {
    fail("empty binary tree and non-empty wide tree, or the reverse");
    return issues;
  }
  // Binary leaves by their first prim_order position.
  std::map<std::uint32_t, const BvhNode*> leaves;
  for (const BvhNode& n : bvh.nodes)
    if (n.is_leaf()) leaves[n.index] = &n;
  std::vector<std::uint8_t> reached(wide.nodes.size(), 0);
  std::size_t leaf_children = 0;
  if (!wide.nodes.empty()) reached[0] = 1;
  for (std::uint32_t i = 0; i < wide.nodes.size(); ++i) {
    const WideNode& n = wide.nodes[i];
    for (int k = 0; k < 4; ++k) {
      const Box3f b = n.child_box(k);
      if (n.is_leaf(k)) {
        ++leaf_children;
        auto it = leaves.find(n.child[k]);
        if (it == leaves.end() || it->second->count != n.count[k]) {
          fail("node " + std::to_string(i) + " child " + std::to_string(k) + ": no binary leaf with this range");
        } else {
          if (!(it->second->bounds == b)) fail("node " + std::to_string(i) + " child " + std::to_string(k) + ": leaf box differs");
          leaves.erase(it);
        }
      } else if (n.is_empty(k)) {
        if (!b.empty()) fail("node " + std::to_string(i) + " empty slot " + std::to_string(k) + " has a box");
      } else {
        const std::uint32_t c = n.child[k];
        if (c <= i || c >= wide.nodes.size()) {
          fail("node " + std::to_string(i) + " child index " + std::to_string(c) + " not after its parent");
          continue;
        }
        if (reached[c]++) fail("node " + std::to_string(c) + " has two parents");
        Box3f u;
        for (int j = 0; j < 4; ++j) u.extend(wide.nodes[c].child_box(j));
        if (!(u == b)) fail("node " + std::to_string(i) + " child " + std::to_string(k) + ": box is not the union of its children");
      }
    }
  }
  for (std::size_t i = 0; i < reached.size(); ++i)
    if (!reached[i]) fail("wide node " + std::to_string(i) + " is unreachable");
  if (!leaves.empty()) fail(std::to_string(leaves.size()) + " binary leaves are missing from the wide tree");
  if (leaf_children != wide.leaves) fail("leaf count " + std::to_string(wide.leaves) + " but " + std::to_string(leaf_children) + " leaf children");
  return issues;
}

}  // namespace ptc::bvh
