#include "bvh/trace_data.h"

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <utility>

namespace ptc::bvh {

namespace {

// The checks of one leaf of a LeafFormat::Tables scene: its ranges of groups (every range whole
// clusters: only its last group marked last), each group's counts and slot mask, corner slots
// (in use, and in their test's chunk pair) and ids, every triangle once, its corners (finite)
// inside the leaf's box, unused slots NaN.
template <class Fail>
void validate_table_leaf(const TraceData& d, const std::vector<LeafRange>& leaf_ranges, const Box3f& box,
                         std::size_t triangle_count, const std::string& where, std::vector<std::uint8_t>& tri_seen,
                         std::vector<std::uint8_t>& slot_used, Fail&& fail) {
  for (std::size_t r = 0; r < leaf_ranges.size(); ++r) {
    const LeafRange lr = leaf_ranges[r];
    const std::string rw = where + ": range " + std::to_string(r);
    if (lr.block_count == 0 || std::uint64_t{lr.first_block} + lr.block_count > d.tables.size()) {
      fail(rw + " empty or past the tables");
      continue;
    }
    std::uint32_t real = 0;
    for (std::uint32_t g = lr.first_block; g < lr.first_block + lr.block_count; ++g) {
      const TableGroup& t = d.tables[g];
      const std::string gw = rw + " group " + std::to_string(g);
      if ((t.last != 0) != (g + 1 == lr.first_block + lr.block_count)) fail(gw + ": marked last " + std::to_string(t.last));
      if (t.count < 1 || t.count > kTableSlots || t.vertices < 1 || t.vertices > kTableSlots ||
          static_cast<std::uint32_t>(__builtin_popcount(t.slot_mask)) != t.vertices) {
        fail(gw + ": " + std::to_string(t.count) + " triangles on " + std::to_string(t.vertices) + " vertices (" +
             std::to_string(__builtin_popcount(t.slot_mask)) + " slots marked)");
        continue;
      }
      for (std::uint32_t s = 0; s < kTableSlots; ++s)
        if (!(t.slot_mask >> s & 1) && (!std::isnan(t.v[0][s]) || !std::isnan(t.v[1][s]) || !std::isnan(t.v[2][s])))
          fail(gw + ": unused slot " + std::to_string(s) + " not NaN");
      for (std::uint32_t i = 0; i < kTableSlots; ++i) {
        const std::size_t slot = std::size_t{kTableSlots} * g + i;
        if (slot_used[slot]++) fail(gw + ": slot " + std::to_string(i) + " referenced twice");
        const std::uint32_t id = d.triangle_ids[slot];
        if (i >= t.count) {
          if (id != kNoTriangle) fail(gw + ": slot " + std::to_string(i) + " beyond the count holds a triangle");
          continue;
        }
        ++real;
        if (id >= triangle_count) {
          fail(gw + ": triangle id " + std::to_string(id) + " out of range");
          continue;
        }
        if (tri_seen[id]++) fail("triangle " + std::to_string(id) + " appears twice");
        const std::uint8_t pair = t.pair[i / 8];
        if (i == 0 && pair != 0) fail(gw + ": test 0 not on chunks 0 and 1 (pair code " + std::to_string(pair) + ")");
        for (int c = 0; c < 3; ++c) {
          const std::uint32_t v = t.corner[c][i];
          if (v >= kTableSlots || !(t.slot_mask >> v & 1)) {
            fail(gw + ": triangle " + std::to_string(id) + " corner slot " + std::to_string(v) + " unused");
            continue;
          }
          const int chunk = static_cast<int>(v) & ~7;
          if (pair > 3 || (chunk != table_even_chunk(pair) && chunk != table_odd_chunk(pair)))
            fail(gw + ": triangle " + std::to_string(id) + " corner slot " + std::to_string(v) + " outside its test's chunks");
          Box3f pb;
          pb.extend(Vec3f{t.v[0][v], t.v[1][v], t.v[2][v]});
          if (!box.contains(pb)) fail(where + ": triangle " + std::to_string(id) + " corner outside the leaf box");
        }
      }
    }
    if (real != lr.triangle_count)
      fail(rw + " holds " + std::to_string(real) + " triangles, not " + std::to_string(lr.triangle_count));
  }
}

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
      } else if (d.format == LeafFormat::Tables) {  // the groups up to the first marked last
        std::uint32_t g = n.child[k];
        while (g < d.tables.size() && !d.tables[g].last) ++g;
        if (g >= d.tables.size()) {
          fail(where + ": a direct leaf's groups run past the tables");
          continue;
        }
        leaf_ranges.push_back({n.child[k], g + 1 - n.child[k], n.count[k]});
      } else {
        leaf_ranges.push_back({n.child[k], (n.count[k] + 3) / 4, n.count[k]});
      }
      if (d.format == LeafFormat::Tables) {
        validate_table_leaf(d, leaf_ranges, box, triangle_count, where, tri_seen, lane_used, fail);
        continue;
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

LeafShape leaf_shape(const TraceData& d) {
  LeafShape s;
  s.format = d.format;
  if (d.format == LeafFormat::Tables) {
    s.units = d.tables.size();
    for (const TableGroup& g : d.tables) s.triangles += g.count, s.vertices += g.vertices, s.lanes += 8 * ((g.count + 7) / 8);
    return s;
  }
  s.units = d.blocks.size();
  s.lanes = 4 * s.units;
  s.triangles = static_cast<std::size_t>(
      std::count_if(d.triangle_ids.begin(), d.triangle_ids.end(), [](std::uint32_t id) { return id != kNoTriangle; }));
  return s;
}

std::vector<std::string> validate(const TraceData& d, std::size_t triangle_count, bool exact_unions) {
  std::vector<std::string> issues;
  if (d.format == LeafFormat::Tables) {
    if (!d.blocks.empty()) issues.push_back("blocks beside the tables");
    if (d.triangle_ids.size() != std::size_t{kTableSlots} * d.tables.size())
      issues.push_back("triangle_ids size is not " + std::to_string(kTableSlots) + " per group");
  } else if (d.triangle_ids.size() != 4 * d.blocks.size()) {
    issues.push_back("triangle_ids size is not 4 per block");
  }
  if (!issues.empty()) return issues;  // (the walks below index the ids by group or block)
  // (A cluster scene's data has no 4-wide tree: `wide` is then empty.)
  if (!d.wide.nodes.empty()) validate_tree(d, d.wide, triangle_count, exact_unions, "", issues);
  if (d.wide8.nodes.empty() && !d.wide.nodes.empty()) issues.push_back("no 8-wide nodes beside the 4-wide tree");
  else validate_tree(d, d.wide8, triangle_count, exact_unions, "8-wide ", issues);
  return issues;
}

}  // namespace ptc::bvh
