// The binary BVH as plain data: what every builder returns, what validate/refit/sah_cost read,
// and what the tracer's 4-wide BVH is collapsed from.
//
// Layout (pbrt's "linear BVH"): nodes in depth-first pre-order; the first child of inner node i
// is node i + 1, the second child is node `index` (> i + 1). A leaf covers the primitives
// prim_order[index .. index + count). So every child has a larger index than its parent (refit
// is one reverse sweep), and the left spine is contiguous in memory.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "bvh/box.h"

namespace ptc::bvh {

/// 32 bytes: two nodes per 64-byte cache line.
struct BvhNode {
  Box3f bounds;             ///< union of the primitive boxes below this node
  std::uint32_t index = 0;  ///< inner: second child; leaf: first position in Bvh::prim_order
  std::uint32_t count = 0;  ///< 0: inner node; > 0: leaf with this many primitives

  [[nodiscard]] bool is_leaf() const { return count != 0; }
};
static_assert(sizeof(BvhNode) == 32);

/// The surface area heuristic's cost model (MacDonald & Booth 1990; Wald 2007 for binning):
///   cost(leaf)  = intersection * W(leaf)
///   cost(inner) = traversal + (A(left) cost(left) + A(right) cost(right)) / A(inner)
/// with A the box surface area and W the summed primitive weight (1 per triangle; the triangle
/// count of a cluster when the primitives are clusters, so that a leaf of clusters costs the sum
/// of their triangles, as the rays test them linearly). Unitless: only the ratio matters. The
/// defaults (1, 1) are the textbook choice; the tracer's scenes use (1, 0.3) (scene_config.h):
/// one 4-wide node test costs about as much as testing a block of four triangles, i.e. about
/// three triangle tests' worth per triangle (measured on armadillo x2: 10-15% faster tracing
/// than (1, 1), and bigger leaves make the build faster; measured when the tracer walked the
/// 4-wide nodes, not measured again since it walks their 8-wide regrouping).
struct SahCostModel {
  double traversal = 1.0;     ///< cost of visiting an inner node, > 0
  double intersection = 1.0;  ///< cost of one ray/triangle test (per unit of weight), > 0
};

/// The tree: nodes, the primitive order the leaves refer to, and the SAH cost the builder
/// computed for it (see sah_cost() for the formula; 0 for an empty tree).
struct Bvh {
  AlignedVector<BvhNode> nodes;             ///< empty iff there are no primitives; root = nodes[0]
  AlignedVector<std::uint32_t> prim_order;  ///< a permutation of the primitive ids 0 .. n-1
  double cost = 0.0;                      ///< SAH cost as reported by the builder

  [[nodiscard]] bool empty() const { return nodes.empty(); }
  [[nodiscard]] std::size_t primitive_count() const { return prim_order.size(); }
};

/// Counts of a tree (for reports).
struct BvhStats {
  std::size_t inner = 0, leaves = 0, max_depth = 0, max_leaf_size = 0;
  double mean_leaf_size = 0.0;
};
[[nodiscard]] BvhStats stats(const Bvh& bvh);

}  // namespace ptc::bvh
