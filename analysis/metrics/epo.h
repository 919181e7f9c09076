// End-point overlap (EPO; Aila, Karras & Laine 2013, "On quality metrics of bounding volume
// hierarchies", HPG): how much geometry OUTSIDE a node's subtree lies inside the node's box, the
// part of the traversal cost that SAH does not see (rays that end on that geometry still have to
// enter the node):
//   EPO = sum over nodes n of C_n * A(T \ subtree(n), box(n)) / A(T)
// with C_n = the traversal cost for inner nodes and the intersection cost times the leaf's
// triangle count for leaves (a ray that ends in a leaf's box tests all of its triangles; the
// weights of the SAH cost model, bvh/sah_cost.h), A(S, box) the area of the triangles S
// clipped to the box (toolkit/geometry/clip.h) and A(T) the scene's triangle area. The overlap
// query runs on the BVH itself (a node's subtree is skipped, every other subtree whose box misses
// the node's box is pruned), not over all pairs.
//
// Primitives of the BVH are triangles, or clusters of triangles (a cluster BVH): primitive p
// holds the triangles prim_triangles[prim_offsets[p] .. prim_offsets[p + 1]) (both empty:
// primitive p is triangle p). Node boxes are recomputed in double from the triangles' corners.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "bvh/bvh.h"
#include "toolkit/core/types.h"

namespace ptc {

struct EpoResult {
  double epo = 0;                   ///< the sum above (dimensionless)
  double total_area = 0;            ///< A(T)
  std::vector<double> node_overlap;  ///< per node: A(T \ subtree(n), box(n)), mesh units squared
};

/// Precondition: a valid tree (bvh::validate) whose primitives are the clusters described by the
/// offsets (or the triangles). Triangles are `tris` over `positions`.
[[nodiscard]] EpoResult end_point_overlap(const bvh::Bvh& bvh, std::span<const Tri> tris, std::span<const Vec3> positions,
                                          std::span<const std::uint32_t> prim_offsets,
                                          std::span<const std::uint32_t> prim_triangles, const bvh::SahCostModel& model);

}  // namespace ptc
