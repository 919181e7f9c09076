#include "bvh/trace_data.h"

#include <cmath>
#include <type_traits>
#include <utility>

namespace ptc::bvh {

namespace {

// The checks of validate() on one of the trees (WideBvh or WideBvh8); `tree_name` names it in
// the messages ("" or "8-wide ").
template <class Tree>
void validate_tree(const TraceData& d, const Tree& tree, std::size_t triangle_count, bool exact_unions,
                   const std::string& tree_name, std::vector<std::string>& issues) {
  auto fail = [&](std::string s) {
    if (issues.size() < 20) issues.push_back(tree_name + std::move(s));
  };
  const auto& nodes = tree.nodes;
  constexpr int kWidth = std::remove_cvref_t<decltype(nodes[0])>::kWidth;
  if (nodes.empty()) {
    if (triangle_count != 0) fail("no nodes for " + std::to_string(triangle_count) + " triangles");
    return;
  }
  if (tree.root >= nodes.size()) {
    fail("root out of range");
    return;
  }
  std::vector<std::uint8_t> reached(nodes.size(), 0), tri_seen(triangle_count, 0), lane_used(d.triangle_ids.size(), 0);
  // (node, its level: the root's is 1); no level beyond tree.depth, which sizes the walks' stacks
  std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{tree.root, 1}};
  reached[tree.root] = 1;
  bool too_deep = false;
  while (!stack.empty()) {
    const auto [i, level] = stack.back();
    stack.pop_back();
    if (level > tree.depth && !too_deep) {
      fail("node " + std::to_string(i) + " at level " + std::to_string(level) + ", deeper than the tree's depth " +
           std::to_string(tree.depth));
      too_deep = true;
    }
    const auto& n = nodes[i];
    for (int k = 0; k < kWidth; ++k) {
      const Box3f box = n.child_box(k);
      const std::string where = "node " + std::to_string(i) + " child " + std::to_string(k);
      if (n.is_empty(k)) {
        if (!box.empty()) fail(where + ": empty slot with a box");
        continue;
      }
      if (!n.is_leaf(k)) {
        const std::uint32_t c = n.child[k];
        if (c >= nodes.size()) {
          fail(where + ": child index " + std::to_string(c) + " out of range");
          continue;
        }
        if (reached[c]++) {
          fail("node " + std::to_string(c) + " is reached twice");
          continue;
        }
        stack.push_back({c, level + 1});
        Box3f u;
        for (int j = 0; j < kWidth; ++j) u.extend(nodes[c].child_box(j));
        if (exact_unions ? !(u == box) : !box.contains(u))
          fail(where + ": box is not the union of (does not contain) its children's boxes");
        continue;
      }
      std::vector<LeafRange> leaf_ranges;
      if (n.count[k] & kIndirectLeaf) {
        const std::uint32_t nr = n.count[k] & ~kIndirectLeaf;
        if (static_cast<std::uint64_t>(n.child[k]) + nr > d.ranges.size()) {
          fail(where + ": ranges out of bounds");
          continue;
        }
        leaf_ranges.assign(d.ranges.begin() + n.child[k], d.ranges.begin() + n.child[k] + nr);
      } else {
        leaf_ranges.push_back({n.child[k], (n.count[k] + 3) / 4, n.count[k]});
      }
      for (std::size_t r = 0; r < leaf_ranges.size(); ++r) {
        const LeafRange lr = leaf_ranges[r];
        const std::uint64_t nb = lr.block_count;
        if (lr.triangle_count == 0 || lr.triangle_count > 4 * nb || lr.first_block + nb > d.blocks.size()) {
          fail(where + ": range " + std::to_string(r) + " empty or past the blocks");
          continue;
        }
        std::uint32_t real = 0;
        for (std::uint32_t j = 0; j < 4 * nb; ++j) {
          const std::size_t lane = 4 * std::size_t(lr.first_block) + j;
          const TriBlock& blk = d.blocks[lane / 4];
          const std::uint32_t id = d.triangle_ids[lane];
          if (lane_used[lane]++) fail(where + ": lane " + std::to_string(lane) + " referenced twice");
          if (id == kNoTriangle) {
            if (!std::isnan(blk.v[0][0][lane % 4])) fail(where + ": padding lane not padded");
            continue;
          }
          ++real;
          if (id >= triangle_count) {
            fail(where + ": triangle id " + std::to_string(id) + " out of range");
            continue;
          }
          if (tri_seen[id]++) fail("triangle " + std::to_string(id) + " appears twice");
          for (int c = 0; c < 3; ++c) {
            Box3f pb;
            pb.extend(Vec3f{blk.v[c][0][lane % 4], blk.v[c][1][lane % 4], blk.v[c][2][lane % 4]});
            if (!box.contains(pb)) fail(where + ": triangle " + std::to_string(id) + " corner outside the leaf box");
          }
        }
        if (real != lr.triangle_count) fail(where + ": range " + std::to_string(r) + " holds " + std::to_string(real) +
                                            " triangles, not " + std::to_string(lr.triangle_count));
      }
    }
  }
  for (std::size_t i = 0; i < nodes.size(); ++i)
    if (!reached[i]) {
      fail("node " + std::to_string(i) + " is unreachable");
      break;
    }
  for (std::size_t t = 0; t < triangle_count; ++t)
    if (!tri_seen[t]) {
      fail("triangle " + std::to_string(t) + " is in no leaf");
      break;
    }
}

}  // namespace

std::vector<std::string> validate(const TraceData& d, std::size_t triangle_count, bool exact_unions) {
  std::vector<std::string> issues;
  if (d.triangle_ids.size() != 4 * d.blocks.size()) issues.push_back("triangle_ids size is not 4 per block");
  validate_tree(d, d.wide, triangle_count, exact_unions, "", issues);
  if (d.wide8.nodes.empty() != d.wide.nodes.empty()) {
    issues.push_back(d.wide8.nodes.empty() ? "no 8-wide nodes beside the 4-wide tree"
                                           : "8-wide nodes without a 4-wide tree");
  } else {
    validate_tree(d, d.wide8, triangle_count, exact_unions, "8-wide ", issues);
  }
  return issues;
}

}  // namespace ptc::bvh
