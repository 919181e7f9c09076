#include "bvh/wide_bvh.h"

#include "bvh/threads.h"

#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <utility>

#include <tbb/parallel_for.h>
#include <tbb/parallel_for_each.h>
#include <tbb/task_arena.h>

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

}  // namespace

namespace {

// Both walks below allocate a node's inner children (consecutive indices, in slot order) when
// they open the node, and open nodes last-in first-out: a node, then its children, then the
// descendants of its last child, ..., of its first. So the descendants of a node (without the
// node itself) are contiguous, and a walk over a subtree alone, its root at 0, numbers them in
// the same order. The parallel forms cut the tree at a fixed depth into fragments walked at once
// (the `defer` hook of the walks: an item at that depth is not opened; its node stays a
// placeholder) and splice them (splice_fragments): a fragment's local node i > 0 lands at
// desc_start + i - 1 plus the nodes of the deferred subtrees opened before it was allocated.
// The same nodes in the same order as the sequential walk, at any thread count.

struct NoDefer {
  template <class Item>
  bool wants(const Item&) const { return false; }
  template <class Item>
  void take(const Item&, std::uint32_t) {}
};

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
      defer.take(it, static_cast<std::uint32_t>(nodes.size()));
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
      defer.take(it, static_cast<std::uint32_t>(out.size()));
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

// A piece of a walk (see above): the subtree of `root` walked alone, its nodes numbered from 0
// (the root). `holes` are the items deferred to other fragments, in the order the walk met
// them: the placeholder's local index and the number of local nodes allocated by then.
template <class Node, class Item>
struct WalkFragment {
  Item root{};
  std::vector<Node> nodes;  // (not an AlignedVector, which puts arrays of 256 KiB or more on whole 2 MiB pages)
  struct Hole {
    std::uint32_t local, cut;
    WalkFragment* child;
  };
  std::vector<Hole> holes;
  std::vector<std::uint32_t> hole_locals;  // sorted: the placeholders, which the splice skips
  std::vector<std::uint64_t> shift;        // shift[h]: nodes the holes before h add (size - 1 each)
  std::uint64_t size = 0, root_pos = 0, desc_start = 0;
  std::uint32_t depth = 0, leaves = 0;

  // Final position of local node i.
  [[nodiscard]] std::uint64_t position(std::uint32_t i) const {
    if (i == 0) return root_pos;
    std::size_t h = 0;  // (holes before i: their cut is at most i; cuts ascend)
    while (h < holes.size() && holes[h].cut <= i) ++h;
    return desc_start + (i - 1) + shift[h];
  }
};

// Fragments kept from one walk to the next (their node arrays too), handed out under a lock.
template <class Frag>
struct FragmentPool {
  std::vector<std::unique_ptr<Frag>> all;
  std::size_t used = 0;
  std::mutex mutex;
  Frag* take() {
    const std::lock_guard<std::mutex> lock(mutex);
    if (used == all.size()) all.push_back(std::make_unique<Frag>());
    Frag* f = all[used++].get();
    f->nodes.clear(), f->holes.clear(), f->hole_locals.clear(), f->shift.clear();
    f->depth = 0, f->leaves = 0;
    return f;
  }
};

// Runs walk(fragment, defer) over the fragment of `root` and every fragment deferred from it, on
// the caller's threads; items for which cut(item) holds (never a fragment's root) are deferred.
template <class Frag, class Item, class Cut, class Walk>
void walk_fragments(FragmentPool<Frag>& pool, const Item& root, const Cut& cut, const Walk& walk) {
  pool.used = 0;
  Frag* top = pool.take();
  top->root = root;
  Frag* const start[1] = {top};
  tbb::parallel_for_each(start, start + 1, [&](Frag* f, tbb::feeder<Frag*>& feeder) {
    struct Deferrer {
      FragmentPool<Frag>& pool;
      Frag& f;
      tbb::feeder<Frag*>& feeder;
      const Cut& cut;
      bool wants(const Item& it) const { return cut(it); }
      void take(const Item& it, std::uint32_t allocated) {
        Frag* c = pool.take();
        c->root = it;
        f.holes.push_back({local_of(it), allocated, c});
        feeder.add(c);
      }
    } defer{pool, *f, feeder, cut};
    walk(*f, defer);
  });
}

// The fragments spliced into out[base ..), their inner children's indices made final; returns
// the nodes written. Fragments were handed out parents first.
template <class Frag, class Node>
std::uint64_t splice_fragments(FragmentPool<Frag>& pool, AlignedVector<Node>& out, std::uint64_t base) {
  const std::size_t F = pool.used;
  for (std::size_t i = F; i-- > 0;) {  // sizes, children first
    Frag& f = *pool.all[i];
    f.size = f.nodes.size();
    f.shift.assign(f.holes.size() + 1, 0);
    f.hole_locals.clear();
    for (std::size_t h = 0; h < f.holes.size(); ++h) {
      f.size += f.holes[h].child->size - 1;
      f.shift[h + 1] = f.shift[h] + f.holes[h].child->size - 1;
      f.hole_locals.push_back(f.holes[h].local);
    }
    std::sort(f.hole_locals.begin(), f.hole_locals.end());
  }
  Frag& top = *pool.all[0];
  top.root_pos = base, top.desc_start = base + 1;
  for (std::size_t i = 0; i < F; ++i) {  // positions, parents first
    const Frag& f = *pool.all[i];
    for (std::size_t h = 0; h < f.holes.size(); ++h) {
      Frag& c = *f.holes[h].child;
      c.root_pos = f.position(f.holes[h].local);
      c.desc_start = f.desc_start + (f.holes[h].cut - 1) + f.shift[h];
    }
  }
  out.resize(base + top.size);
  tbb::parallel_for(std::size_t{0}, F, [&](std::size_t i) {
    const Frag& f = *pool.all[i];
    std::size_t skip = 0;
    for (std::uint32_t j = 0; j < f.nodes.size(); ++j) {
      if (skip < f.hole_locals.size() && f.hole_locals[skip] == j) {  // (its subtree's fragment writes it)
        ++skip;
        continue;
      }
      Node nd = f.nodes[j];
      for (int k = 0; k < Node::kWidth; ++k)
        if (nd.count[k] == 0 && nd.child[k] != Node::kEmptySlot) nd.child[k] = static_cast<std::uint32_t>(f.position(nd.child[k]));
      out[f.position(j)] = nd;
    }
  });
  return top.size;
}

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
  FragmentPool<WalkFragment<WideNode, CollapseItem>> collapse_fragments;  // the parallel walks'
  FragmentPool<WalkFragment<WideNode8, RegroupItem>> regroup_fragments;   // (their work lists: thread_local)
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
    NoDefer none;
    collapse_walk(bvh, {0, 0, 1}, w.nodes, *stack, w.depth, w.leaves, none);
    return;
  }
  using Frag = WalkFragment<WideNode, CollapseItem>;
  auto& pool = wk->collapse_fragments;
  walk_fragments(pool, CollapseItem{0, 0, 1}, [](const CollapseItem& it) { return it.depth == kCollapseCutDepth; },
                 [&](Frag& f, auto& defer) {
                   thread_local std::vector<CollapseItem> local_stack;
                   f.nodes.push_back(empty_node());
                   collapse_walk(bvh, {f.root.binary, 0, f.root.depth}, f.nodes, local_stack, f.depth, f.leaves, defer);
                 });
  splice_fragments(pool, w.nodes, 0);
  for (std::size_t i = 0; i < pool.used; ++i) w.depth = std::max(w.depth, pool.all[i]->depth), w.leaves += pool.all[i]->leaves;
}

void regroup(const WideBvh& w4, WideBvh8& out, std::vector<RegroupItem>* stack, WideWorkspace::Impl* wk) {
  out.nodes.clear();
  out.root = 0, out.depth = 0;
  if (w4.nodes.empty()) return;
  if (stack) {
    out.nodes.reserve(w4.nodes.size());  // at least one 4-wide node per 8-wide one
    out.nodes.emplace_back();
    NoDefer none;
    regroup_walk(w4.nodes, {w4.root, 0, 1}, out.nodes, *stack, out.depth, 0, {}, nullptr, none);
    return;
  }
  using Frag = WalkFragment<WideNode8, RegroupItem>;
  auto& pool = wk->regroup_fragments;
  const std::span<const WideNode> nodes4(w4.nodes);
  walk_fragments(pool, RegroupItem{w4.root, 0, 1}, [](const RegroupItem& it) { return it.depth == kRegroupCutDepth; },
                 [&](Frag& f, auto& defer) {
                   thread_local std::vector<RegroupItem> local_stack;
                   f.nodes.emplace_back();
                   regroup_walk(nodes4, {f.root.node4, 0, f.root.depth}, f.nodes, local_stack, f.depth, 0, {}, nullptr, defer);
                 });
  splice_fragments(pool, out.nodes, 0);
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
  NoDefer none;
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
