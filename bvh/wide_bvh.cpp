#include "bvh/wide_bvh.h"

#include <algorithm>
#include <map>
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

}  // namespace

WideBvh collapse_to_wide(const Bvh& bvh) {
  WideBvh w;
  collapse_to_wide(bvh, w);
  return w;
}

void collapse_to_wide(const Bvh& bvh, WideBvh& w) {
  w.nodes.clear();
  w.root = 0, w.bounds = Box3f{}, w.depth = 0, w.leaves = 0;
  if (bvh.nodes.empty()) return;
  w.bounds = bvh.nodes[0].bounds;
  w.nodes.reserve(bvh.nodes.size() / 2 + 1);
  // Work list of (binary node to expand, wide node to fill, depth); children after parents
  // because a wide node is allocated before it is filled, and filled after its parent.
  struct Item {
    std::uint32_t binary, wide, depth;
  };
  std::vector<Item> stack;
  w.nodes.push_back(empty_node());
  if (bvh.nodes[0].is_leaf()) {
    w.nodes[0].set_child_box(0, bvh.nodes[0].bounds);
    w.nodes[0].child[0] = bvh.nodes[0].index;
    w.nodes[0].count[0] = bvh.nodes[0].count;
    w.depth = 1, w.leaves = 1;
    return;
  }
  stack.push_back({0, 0, 1});
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    w.depth = std::max(w.depth, it.depth);
    std::uint32_t kids[4];
    const int nk = wide_children(bvh, it.binary, kids);
    for (int i = 0; i < nk; ++i) {
      const BvhNode& c = bvh.nodes[kids[i]];
      WideNode& dst = w.nodes[it.wide];
      dst.set_child_box(i, c.bounds);
      if (c.is_leaf()) {
        dst.child[i] = c.index;
        dst.count[i] = c.count;
        ++w.leaves;
      } else {
        const auto idx = static_cast<std::uint32_t>(w.nodes.size());
        w.nodes[it.wide].child[i] = idx;  // (dst may dangle after the push_back below)
        w.nodes[it.wide].count[i] = 0;
        w.nodes.push_back(empty_node());
        stack.push_back({kids[i], idx, it.depth + 1});
      }
    }
  }
}

std::uint32_t regroup_subtree(std::span<const WideNode> w4, std::uint32_t root4, AlignedVector<WideNode8>& out,
                              std::uint32_t& depth, std::uint32_t linked_below, std::span<const std::uint32_t> linked8,
                              std::vector<SlotSource>* sources) {
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
  struct Item {
    std::uint32_t node4, node8, depth;
  };
  std::vector<Item> stack;
  stack.reserve(64);
  const auto root8 = static_cast<std::uint32_t>(out.size());
  out.emplace_back();
  stack.push_back({root4, root8, 1});
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
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
  return root8;
}

void regroup_to_8(const WideBvh& w4, WideBvh8& out) {
  out.nodes.clear();
  out.root = 0, out.depth = 0;
  if (w4.nodes.empty()) return;
  out.nodes.reserve(w4.nodes.size());  // at least one 4-wide node per 8-wide one
  out.root = regroup_subtree(w4.nodes, w4.root, out.nodes, out.depth, 0, {}, nullptr);
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
