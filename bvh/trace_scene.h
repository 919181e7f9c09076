// What the tracer reads, and the two scenes that make it (front door): a 4-wide BVH whose
// leaves refer to SIMD blocks of triangles, in one of two flavours that share every line of
// traversal code:
//   - TriangleScene (triangle_scene.h): a BVH over triangle boxes (the standard per-frame rebuild);
//   - ClusterScene (cluster_scene.h): a BVH over cluster boxes (Garanzha 2009): a leaf holds
//     whole clusters, whose triangles are either tested linearly four at a time
//     (ClusterLeaf::Linear, the paper's method) or through a small fixed-topology tree per
//     cluster over its blocks of four triangles, built once per clustering and refitted every
//     frame (ClusterLeaf::BlockTree: a two-level variant; the per-frame build still only sees
//     cluster boxes).
// Per frame (method.md, "The per-frame loop"): update(positions) converts the positions into
// the trace frame, recomputes the boxes (for a mesh renumbered once with cluster_vertex_order(),
// both in one pass over the input, see ClusterScene::fused_vertex_pass()), builds the SAH BVH,
// refreshes the leaf data (and, for BlockTree, refits the per-cluster trees); the time of every
// stage is kept.
//
// Precision: everything is in single precision in a *trace frame* centred at `origin` (double),
// see box.h. Rays come in world coordinates (double origins) and are moved into the frame.
//
//   trace_data.h      TraceData (what traversal reads), TriBlock, LeafRange, validate()
//   scene_config.h    SceneConfig, StageTimes, ClusterLeaf, the defaults, the trace frame's origin
//   triangle_scene.h  TriangleScene
//   cluster_scene.h   ClusterView, ClusterScene, cluster_visit_order, cluster_vertex_order
//   (internal: scene_frame.h, leaf_blocks.h; the vertex orders: vertex_order.h)
#pragma once

#include "bvh/cluster_scene.h"
#include "bvh/scene_config.h"
#include "bvh/trace_data.h"
#include "bvh/triangle_scene.h"
