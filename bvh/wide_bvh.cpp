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
    std::uint32_t kids[4] = {it.binary + 1, bvh.nodes[it.binary].index, 0, 0};
    int nk = 2;
    while (nk < 4) {
      int best = -1;
      double best_area = -1.0;
      for (int i = 0; i < nk; ++i) {
        const BvhNode& c = bvh.nodes[kids[i]];
        if (!c.is_leaf() && c.bounds.surface_area() > best_area) best = i, best_area = c.bounds.surface_area();
      }
      if (best < 0) break;
      const std::uint32_t b = kids[best];
      kids[best] = b + 1;  // keep the first child in place, the second at the end: order stays spatial
      kids[nk++] = bvh.nodes[b].index;
    }
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
