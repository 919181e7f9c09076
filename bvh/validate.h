// Self-checks of a BVH (style.md point 7): tests call them on every tree they build; they also
// run on deliberately corrupted trees to show that they can fail.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "bvh/bvh.h"

namespace ptc::bvh {

/// What validate() checks besides the structure; weights/model only matter for the cost check.
struct ValidateOptions {
  std::span<const std::uint32_t> weights;  ///< as given to the builder (empty: 1 each)
  SahCostModel model{};                    ///< as given to the builder
  bool check_cost = true;                  ///< compare bvh.cost with sah_cost() (relative 1e-9)
  std::size_t max_issues = 20;             ///< stop after this many messages
};

/// Checks, returning one line per violation (empty = valid):
/// - prim_order is a permutation of 0 .. boxes.size()-1;
/// - the node graph is a tree in the documented layout (pre-order, first child = i + 1, second
///   child index in (i + 1, nodes.size())), reaching every node once, with no cycle;
/// - every leaf range lies inside prim_order, leaves' ranges are disjoint and cover it, so every
///   primitive is reachable exactly once;
/// - every child box lies inside its parent's box; every leaf box contains its primitives' boxes;
///   (exact float comparisons: boxes are unions of primitive boxes, no rounding is involved)
/// - bvh.cost equals sah_cost(bvh, boxes, weights, model) within a relative 1e-9 (the two
///   sum the same terms in a different order) when opt.check_cost.
/// Never crashes on a corrupted tree (indices out of range, cycles, overlapping leaves).
[[nodiscard]] std::vector<std::string> validate(const Bvh& bvh, std::span<const Box3f> boxes,
                                                const ValidateOptions& opt = {});

}  // namespace ptc::bvh
