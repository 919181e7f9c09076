// meshoptimizer's SAH overhead of a clustering (its nanite demo's definition, read from its
// source): the SAH cost of a two-level structure, a BVH over the cluster boxes on top of one BVH
// per cluster over its triangles, relative to one BVH over all triangles,
//   overhead = [SAH(BVH over cluster boxes) + sum_k (SAH(BVH of k) - A(box_k))] / SAH(BVH over all triangles),
// each SAH in absolute area units with traversal 1 and intersection 1 per triangle and
// single-primitive leaves (A(box_k) is subtracted because the cluster's box is already a leaf
// of the top tree). 1 means clustering costs nothing; meshoptimizer reports it per LOD level.
// The trees here are ptc's binned SAH builds (bvh/binned_sah_builder.h) rather than
// meshoptimizer's own 15-bin sweep, so values agree with that library's to the builders'
// difference, not bit for bit. The boxes are the BVHs' floats in the mesh's trace frame (its box
// centre and power-of-two scale, bvh/scene_config.h), so the value does not depend on where the
// mesh lies; the absolute costs are given in the mesh's units.
#pragma once

#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

struct SahOverhead {
  double clustered = 0;  ///< SAH(top) + sum_k (SAH(k) - A(box_k)), absolute
  double triangles = 0;  ///< SAH(BVH over all triangles), absolute
  double overhead = 0;   ///< clustered / triangles (0 for an empty mesh, NaN when no triangle has area)
};

[[nodiscard]] SahOverhead sah_overhead(const Mesh& mesh, const Clustering& clusters);

}  // namespace ptc
