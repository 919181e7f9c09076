// SAH BVH builders (front door): pure functions from primitive boxes, centroids and weights to a
// Bvh. The same builder serves triangles (weight 1) and clusters (weight = triangles in the
// cluster; a leaf then holds whole clusters).
//
//   Bvh b = build_binned_sah({boxes, centroids, weights}, BuildConfig{});
//
// Both builders split top-down on one skeleton (top_down_builder.h) and differ only in how a
// node's split is found. At a node with primitives P, box B and weight W(P):
//   leaf cost  = intersection * W(P)
//   split cost = traversal + intersection * (A(L) W(L) + A(R) W(R)) / A(B)
// and the node becomes a leaf when |P| <= max_leaf_size and leaf cost <= best split cost, or
// when |P| = 1. Above max_leaf_size a split is forced: the SAH-best one, or, when every centroid
// is equal (no plane separates them), the object median in the current order.
// The reported Bvh::cost is the tree's SAH cost (sah_cost() recomputes it independently).
// Deterministic: the same input gives the same tree on every run and thread count.
//
//   build_config.h       BuildInput, BuildConfig (what both take)
//   sweep_sah_builder.h  build_sweep_sah: exact sweep, the quality reference
//   binned_sah_builder.h build_binned_sah, BuildWorkspace: binned (Wald 2007), the per-frame one
#pragma once

#include "bvh/binned_sah_builder.h"
#include "bvh/build_config.h"
#include "bvh/sweep_sah_builder.h"
