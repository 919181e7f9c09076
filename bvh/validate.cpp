#include "bvh/validate.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "bvh/sah_cost.h"

namespace ptc::bvh {

namespace {

std::string box_str(const Box3f& b) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "[%g %g %g | %g %g %g]", b.lo[0], b.lo[1], b.lo[2], b.hi[0], b.hi[1], b.hi[2]);
  return buf;
}

}  // namespace

std::vector<std::string> validate(const Bvh& bvh, std::span<const Box3f> boxes, const ValidateOptions& opt) {
  std::vector<std::string> issues;
  auto fail = [&](std::string s) {
    if (issues.size() < opt.max_issues) issues.push_back(std::move(s));
  };
  const std::size_t n = boxes.size();
  if (bvh.prim_order.size() != n)
    fail("prim_order has " + std::to_string(bvh.prim_order.size()) + " entries for " + std::to_string(n) + " boxes");
  if (n == 0 || bvh.nodes.empty()) {
    if (!bvh.nodes.empty()) fail("no primitives but " + std::to_string(bvh.nodes.size()) + " nodes");
    if (n != 0) fail(std::to_string(n) + " primitives but no nodes");
    if (bvh.cost != 0.0) fail("empty tree with cost " + std::to_string(bvh.cost));
    return issues;
  }
  // Permutation.
  std::vector<std::uint8_t> seen(n, 0);
  bool perm_ok = bvh.prim_order.size() == n;
  for (std::size_t i = 0; i < bvh.prim_order.size(); ++i) {
    const std::uint32_t p = bvh.prim_order[i];
    if (p >= n) {
      fail("prim_order[" + std::to_string(i) + "] = " + std::to_string(p) + " is out of range");
      perm_ok = false;
    } else if (seen[p]++) {
      fail("primitive " + std::to_string(p) + " appears twice in prim_order");
      perm_ok = false;
    }
  }
  // Walk the tree from the root; every node must be reached exactly once, every prim_order
  // position covered by exactly one leaf.
  const std::size_t nn = bvh.nodes.size();
  std::vector<std::uint8_t> visited(nn, 0);
  std::vector<std::uint8_t> covered(bvh.prim_order.size(), 0);
  std::vector<std::uint32_t> stack{0};
  bool tree_ok = true;
  while (!stack.empty()) {
    const std::uint32_t i = stack.back();
    stack.pop_back();
    if (visited[i]++) {
      fail("node " + std::to_string(i) + " is reached twice");
      tree_ok = false;
      continue;
    }
    const BvhNode& nd = bvh.nodes[i];
    if (nd.is_leaf()) {
      if (static_cast<std::uint64_t>(nd.index) + nd.count > bvh.prim_order.size()) {
        fail("leaf " + std::to_string(i) + " range [" + std::to_string(nd.index) + ", +" + std::to_string(nd.count) +
             ") runs past prim_order");
        tree_ok = false;
        continue;
      }
      for (std::uint32_t k = nd.index; k < nd.index + nd.count; ++k) {
        if (covered[k]++) {
          fail("prim_order position " + std::to_string(k) + " is in two leaves (second: node " + std::to_string(i) + ")");
          tree_ok = false;
        }
        const std::uint32_t p = bvh.prim_order[k];
        if (p < n && !nd.bounds.contains(boxes[p]))
          fail("leaf " + std::to_string(i) + " box " + box_str(nd.bounds) + " does not contain primitive " +
               std::to_string(p) + " " + box_str(boxes[p]));
      }
      continue;
    }
    const std::uint32_t kids[2] = {i + 1, nd.index};
    if (i + 1 >= nn || nd.index <= i + 1 || nd.index >= nn) {
      fail("inner node " + std::to_string(i) + " has children " + std::to_string(i + 1) + ", " +
           std::to_string(nd.index) + " (need i+1 < second < " + std::to_string(nn) + ")");
      tree_ok = false;
      continue;
    }
    for (std::uint32_t c : kids) {
      if (!nd.bounds.contains(bvh.nodes[c].bounds))
        fail("child " + std::to_string(c) + " box " + box_str(bvh.nodes[c].bounds) + " is not inside parent " +
             std::to_string(i) + " box " + box_str(nd.bounds));
      stack.push_back(c);
    }
  }
  for (std::size_t i = 0; i < nn; ++i)
    if (!visited[i]) {
      fail("node " + std::to_string(i) + " is unreachable");
      tree_ok = false;
      break;
    }
  for (std::size_t k = 0; k < covered.size(); ++k)
    if (!covered[k]) {
      fail("prim_order position " + std::to_string(k) + " is in no leaf");
      tree_ok = false;
      break;
    }
  if (opt.check_cost && tree_ok && perm_ok) {
    const double c = sah_cost(bvh, boxes, opt.weights, opt.model);
    if (!(std::abs(c - bvh.cost) <= 1e-9 * std::abs(c)))
      fail("reported SAH cost " + std::to_string(bvh.cost) + " differs from recomputed " + std::to_string(c));
  }
  return issues;
}

}  // namespace ptc::bvh
