// Refit: keep a tree's topology, recompute every node box bottom-up from new primitive boxes
// (one reverse sweep: children have larger indices than their parents). The per-frame update
// scheme the rebuild is compared against.
#pragma once

#include <span>

#include "bvh/bvh.h"

namespace ptc::bvh {

/// Recomputes bvh.nodes[*].bounds from `boxes` (one per primitive id, same count as when the
/// tree was built). The reported cost is recomputed too (the SAH of the refitted tree), unless
/// model is null. Precondition: the tree is valid (validate()).
void refit(Bvh& bvh, std::span<const Box3f> boxes, std::span<const std::uint32_t> weights = {},
           const SahCostModel* model = nullptr);

}  // namespace ptc::bvh
