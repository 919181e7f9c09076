// The wide BVHs: a binary Bvh collapsed so that one node holds up to four children's boxes in
// SIMD order (WideNode, as Embree's BVH4: what the scenes build, link and refit), and that tree
// regrouped into nodes of up to eight (WideNode8, as Embree's BVH8: what the tracer walks).
//
// Collapse (the usual greedy rule): a wide node starts with its binary node's two children and
// repeatedly replaces the inner child of largest surface area by that child's two children
// until it has four children or only leaves. Leaves stay the binary tree's leaves.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "bvh/aligned.h"
#include "bvh/bvh.h"

namespace ptc::bvh {

/// A node of W children (WideNode: 4, 128 bytes, two cache lines; WideNode8: 8, 256 bytes).
/// Child i's box is (bounds[0][i], bounds[2][i], bounds[4][i]) .. (bounds[1][i], bounds[3][i],
/// bounds[5][i]): row 2a is lo on axis a, row 2a+1 hi on axis a, so a ray picks its near/far
/// rows by the sign of its direction once.
template <int W>
struct alignas(64) WideNodeOf {
  static constexpr int kWidth = W;
  float bounds[6][W];
  /// Inner child: node index, count = 0. Leaf child: `child` is the first item and `count`
  /// (> 0) the number of items of the leaf (collapse: a range of Bvh::prim_order; the tracer
  /// rebinds it to its own leaf table). Empty slot: empty box (+inf..-inf), count = 0,
  /// child = kEmptySlot.
  std::uint32_t child[W];
  std::uint32_t count[W];

  [[nodiscard]] Box3f child_box(int i) const {
    return {{bounds[0][i], bounds[2][i], bounds[4][i]}, {bounds[1][i], bounds[3][i], bounds[5][i]}};
  }
  void set_child_box(int i, const Box3f& b) {
    for (int a = 0; a < 3; ++a) bounds[2 * a][i] = b.lo[a], bounds[2 * a + 1][i] = b.hi[a];
  }
  [[nodiscard]] bool is_leaf(int i) const { return count[i] != 0; }
  static constexpr std::uint32_t kEmptySlot = 0xffffffffu;
  [[nodiscard]] bool is_empty(int i) const { return count[i] == 0 && child[i] == kEmptySlot; }
};
/// The nodes the builds make, link and refit (as Embree's BVH4).
using WideNode = WideNodeOf<4>;
static_assert(sizeof(WideNode) == 128);

/// Nodes (an empty tree has none) and the root's index; collapse_to_wide puts the root first and
/// children after parents (a ClusterScene appends per-cluster subtrees, see cluster_scene.h).
/// `depth`: the number of wide levels (the traversal stack needs at most 3 * depth + 1 entries).
struct WideBvh {
  AlignedVector<WideNode> nodes;
  std::uint32_t root = 0;
  Box3f bounds;
  std::uint32_t depth = 0;
  std::uint32_t leaves = 0;
};

/// The nodes the tracer walks, single rays and packets (one 8-lane slab test a node, or two
/// 4-lane ones on SSE2), made from the 4-wide tree by regroup_to_8 (as Embree's BVH8).
struct WideNode8 : WideNodeOf<8> {
  /// Uninitialised (regroup_to_8 writes every field; value-initialising 256 bytes per node took
  /// a tenth of its time).
  WideNode8() {}  // NOLINT: not = default, which would zero the node in emplace_back()
};
static_assert(sizeof(WideNode8) == 256);

/// 8-wide nodes (regroup_to_8: root first, children after parents; a ClusterScene puts its
/// fixed subtrees first and the top after them, see cluster_scene.h). `depth`: the number of
/// 8-wide levels (the traversal stack needs at most 7 * depth + 1 entries).
struct WideBvh8 {
  AlignedVector<WideNode8> nodes;
  std::uint32_t root = 0;
  std::uint32_t depth = 0;
};

/// What the collapse and the regroup keep from one frame to the next (below): the sequential
/// walks' work lists, and the parallel walks' fragments with their node arrays (each thread's
/// work list there is its own). One per scene, used by one call at a time. A copy is a fresh
/// workspace.
class WideWorkspace {
 public:
  WideWorkspace();
  ~WideWorkspace();
  WideWorkspace(const WideWorkspace&);
  WideWorkspace& operator=(const WideWorkspace&);
  WideWorkspace(WideWorkspace&&) noexcept;
  WideWorkspace& operator=(WideWorkspace&&) noexcept;
  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
  friend void collapse_to_wide(const Bvh&, WideBvh&, WideWorkspace&);
  friend void regroup_to_8(const WideBvh&, WideBvh8&, WideWorkspace&);
};

/// Regroups a 4-wide tree into 8-wide nodes with the same leaf children (the same child, count
/// and box: leaf references are copied, not interpreted) and the same boxes. An 8-wide node
/// starts with its 4-wide node's children and repeatedly replaces the inner child of largest
/// surface area whose children still fit (at most 8 in all) by those children. About two thirds
/// of the dependent node visits a ray makes on the way down (log8 against log4 levels).
/// O(nodes); `out` keeps its capacity (per frame only a temporary workspace is allocated, and
/// above the parallel threshold below its fragments: pass a kept one).
void regroup_to_8(const WideBvh& w4, WideBvh8& out);
/// The same with kept scratch: on the caller's threads from 2^14 4-wide nodes up (the tree cut
/// into fragments regrouped at once and spliced), the same nodes in the same order at any
/// thread count.
void regroup_to_8(const WideBvh& w4, WideBvh8& out, WideWorkspace& ws);

/// Where an 8-wide slot's box comes from: slot `slot` of 4-wide node `node` (node kEmptySlot:
/// an empty slot).
struct SlotSource {
  std::uint32_t node, slot;
};
/// regroup_to_8 of the subtree of `w4` rooted at `root4`, appended to `out` (its root first; the
/// root's index is returned; `depth` is raised to the subtree's 8-wide levels). An inner child
/// below `linked_below` is a link into fixed subtrees regrouped before: it is never opened and
/// becomes a link to linked8[child], their 8-wide root. With `sources`, slot i of the node made
/// at index n records where its box came from in sources[8 n + i] (so that refits of the 4-wide
/// subtree can write the 8-wide boxes too; ClusterScene).
std::uint32_t regroup_subtree(std::span<const WideNode> w4, std::uint32_t root4, AlignedVector<WideNode8>& out,
                              std::uint32_t& depth, std::uint32_t linked_below, std::span<const std::uint32_t> linked8,
                              std::vector<SlotSource>* sources);

/// The children of binary inner node `b` that its 4-wide node gets (collapse_to_wide, in slot
/// order): b's two children, then the inner one of largest surface area replaced by its two (the
/// first in place, the second at the end) until there are four or only leaves. Returns their
/// number, 2 to 4.
inline int wide_children(const Bvh& bvh, std::uint32_t b, std::uint32_t (&kids)[4]) {
  kids[0] = b + 1, kids[1] = bvh.nodes[b].index;
  int nk = 2;
  while (nk < 4) {
    int best = -1;
    double best_area = -1.0;
    for (int i = 0; i < nk; ++i) {
      const BvhNode& c = bvh.nodes[kids[i]];
      if (!c.is_leaf() && c.bounds.surface_area() > best_area) best = i, best_area = c.bounds.surface_area();
    }
    if (best < 0) break;
    const std::uint32_t c = kids[best];
    kids[best] = c + 1;  // keep the first child in place, the second at the end: order stays spatial
    kids[nk++] = bvh.nodes[c].index;
  }
  return nk;
}

/// Collapses a binary tree (validate()d) into a 4-wide one with the same leaves. A binary tree
/// that is a single leaf becomes one wide node with one leaf child. O(nodes).
[[nodiscard]] WideBvh collapse_to_wide(const Bvh& bvh);
/// The same into `out`, whose node array keeps its capacity (a per-frame rebuild then allocates
/// only a temporary workspace, and above the parallel threshold below its fragments: pass a kept
/// one; fresh pages cost more than the collapse itself).
void collapse_to_wide(const Bvh& bvh, WideBvh& out);
/// The same with kept scratch: on the caller's threads from 2^16 binary nodes up (the tree cut
/// into fragments collapsed at once and spliced), the same nodes in the same order at any
/// thread count.
void collapse_to_wide(const Bvh& bvh, WideBvh& out, WideWorkspace& ws);

/// Checks of a collapsed tree against its binary source before rebinding: every binary leaf
/// appears exactly once as a wide leaf child with the same range and box; every inner child's
/// box equals the union of its node's child boxes; children after parents; empty slots empty.
[[nodiscard]] std::vector<std::string> validate_wide(const WideBvh& wide, const Bvh& bvh);

}  // namespace ptc::bvh
