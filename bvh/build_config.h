// What both SAH builders take: the input spans (BuildInput) and the settings (BuildConfig).
// The builders themselves: sweep_sah_builder.h, binned_sah_builder.h (front door: sah_builder.h).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>

#include "bvh/bvh.h"

namespace ptc::bvh {

/// Input spans (not owned; all of the same length n, except weights). A NaN in a box or a
/// centroid makes both builders throw std::invalid_argument naming the primitive.
struct BuildInput {
  std::span<const Box3f> boxes;
  std::span<const Vec3f> centroids;        ///< a point inside (or at the centre of) each box
  std::span<const std::uint32_t> weights;  ///< empty: every primitive weighs 1; else n entries >= 1, sum < 2^32
  /// Optional two-level build (binned builder only): offsets of G groups of consecutive
  /// primitives (G + 1 entries, ascending from 0 to n, no empty group). The top of the tree is
  /// built over the groups (one record each: the union of its primitives' boxes, its centre, the
  /// summed weight), and a node holding one group is built on over the group's primitives; a
  /// leaf never holds primitives of two groups. Empty (or one group): the plain build.
  std::span<const std::uint32_t> groups = {};
};

struct BuildConfig {
  SahCostModel cost{};              ///< SAH constants (see SahCostModel)
  std::uint32_t max_leaf_size = 8;  ///< most primitives in a leaf, >= 1 (triangles: 4-16; clusters: 1-4)
  std::uint32_t bins = 16;          ///< binned builder: bins per axis, in [2, 256] (Wald 2007 uses 16)
  /// Binned builder: nodes of at most 16 primitives are swept along the longest axis of their box
  /// only, instead of all three (with area_weights: the largest extent over its weight, the axis
  /// a cut across which shrinks the weighted area the most; with area_eye, the weights of the
  /// node's faces in Box3f::area_from). Measured on 28k Acc clusters of armadillo x2: build 20% faster,
  /// SAH cost 0.4% higher, trace speed unchanged within noise (bench/bvh_bench.cpp).
  bool small_nodes_longest_axis = true;
  /// Binned builder: a node of at most this many primitives that must be split (more than
  /// max_leaf_size) is split at the object median of its primitives sorted by centroid along
  /// the swept axis, without evaluating the other positions (0, the default: always the
  /// SAH-best position). Meant for single-cluster leaves (cluster_scene_defaults() sets 4):
  /// measured on 27.6k Acc clusters of armadillo x2, build 6% faster, SAH cost 0.3% higher.
  std::uint32_t median_split_below = 0;
  /// Use the AVX2 loops when the CPU has them (runtime check): the binned builder's binning, and a
  /// scene's per-frame loops built on this config (conversion, fills, the cluster scene's 8-wide
  /// refit). Both variants of each compute the same bits, so the tree and the trace data are the
  /// same either way (tests compare them).
  bool allow_avx2 = true;
  /// The areas the splits are chosen by: the faces across x, y and z weighted by these
  /// (Box3f::weighted_area; each finite and > 0, else both builders throw
  /// std::invalid_argument; only their ratios matter). (1, 1, 1), the default: the surface
  /// area, the plain SAH, which prices every ray direction alike. With twice the mean |d| of a
  /// ray set's unit directions d (direction_area_weights, camera.h) the weighted area is four
  /// times that set's mean projected area, so a child's share of its parent's is the share of
  /// those rays through the parent that meet the child when they come from afar: a tree for
  /// those rays (docs/tracing.md, "The fallback built for the camera's rays"). Uniform
  /// directions give equal weights, the plain SAH (Cauchy's formula). Only the binary splits
  /// change: Bvh::cost stays the plain SAH cost of the tree, and the collapse to 4- and 8-wide
  /// nodes (wide_bvh.h) still opens children by their plain area (weighting it too changed
  /// nothing measurable on the explode scene: 28.34 against 28.39 nodes a primary ray).
  std::array<float, 3> area_weights = {1.0f, 1.0f, 1.0f};
  /// The point the rays leave from (a pinhole camera's eye), in the coordinates of the boxes
  /// (a scene's trace frame), or none. Given, the splits are chosen by the solid angle a box
  /// shows that point instead of by area_weights (Box3f::area_from: its faces' areas, each times
  /// the cosine toward the point, over the squared distance; D = max(distance to the centre,
  /// half the diagonal), so a box around the point counts as seen from its surface), plus
  /// kEyeAreaIsotropic of its surface area over D^2 (so a face seen edge-on keeps some). A tree
  /// for rays from that point: boxes near it meet more of them than the same boxes far off
  /// (docs/tracing.md, "The fallback built for the camera's eye"). Must be finite (else
  /// std::invalid_argument); a point farther than 2^20 root diagonals from the root is moved in
  /// along its direction (with_near_area_eye). The price is not monotone (a box stretched toward the
  /// point may price below one inside it), so the binned builder's early-leaf bound is only
  /// approximate with it. As with area_weights, Bvh::cost stays the plain SAH cost.
  std::optional<Vec3f> area_eye;
};

}  // namespace ptc::bvh
