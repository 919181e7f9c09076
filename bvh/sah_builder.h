// SAH BVH builders: pure functions from primitive boxes, centroids and weights to a Bvh.
// The same builder serves triangles (weight 1) and clusters (weight = triangles in the cluster;
// a leaf then holds whole clusters).
//
//   Bvh b = build_binned_sah({boxes, centroids, weights}, BuildConfig{});
//
// Both builders split top-down. At a node with primitives P, box B and weight W(P):
//   leaf cost  = intersection * W(P)
//   split cost = traversal + intersection * (A(L) W(L) + A(R) W(R)) / A(B)
// and the node becomes a leaf when |P| <= max_leaf_size and leaf cost <= best split cost, or
// when |P| = 1. Above max_leaf_size a split is forced: the SAH-best one, or, when every centroid
// is equal (no plane separates them), the object median in the current order.
// The reported Bvh::cost is the tree's SAH cost (sah_cost() recomputes it independently).
// Deterministic: the same input gives the same tree on every run and thread count.
#pragma once

#include <cstdint>
#include <memory>
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
  /// only, instead of all three. Measured on 28k Acc clusters of armadillo x2: build 20% faster,
  /// SAH cost 0.4% higher, trace speed unchanged within noise (bench/bvh_bench.cpp).
  bool small_nodes_longest_axis = true;
  /// Binned builder: a node of at most this many primitives that must be split (more than
  /// max_leaf_size) is split at the object median of its primitives sorted by centroid along
  /// the swept axis, without evaluating the other positions (0, the default: always the
  /// SAH-best position). Meant for single-cluster leaves (cluster_scene_defaults() sets 4):
  /// measured on 27.6k Acc clusters of armadillo x2, build 6% faster, SAH cost 0.3% higher.
  std::uint32_t median_split_below = 0;
  /// Binned builder: use the AVX2 binning loop when the CPU has it (runtime check). Both loops
  /// compute the same bins, so the tree is the same either way (tests compare them).
  bool allow_avx2 = true;
};

/// Exact SAH: at every node every axis is sorted by centroid (ties by primitive id) and all
/// |P| - 1 split positions are evaluated. O(n log^2 n); the quality reference.
[[nodiscard]] Bvh build_sweep_sah(const BuildInput& in, const BuildConfig& cfg = {});

/// Binned SAH (Wald 2007): centroids are binned into equal bins per axis of the node's
/// centroid bounds and the bins' boundaries are the candidate planes: cfg.bins bins, but at most
/// max(4, |P| / 4) in a node of |P| primitives (most of 16 bins would stay empty there). Nodes of
/// at most 16 primitives are split by the exact sweep instead (cheaper there, and exact; along
/// the longest axis only unless cfg.small_nodes_longest_axis is false); two
/// primitives that must be split are split without search; a node within max_leaf_size whose
/// leaf cost is below the lower bound traversal + intersection * sum_p A(p) w(p) / A(node) of
/// every split becomes a leaf without evaluating splits (the same decision, sooner).
/// Sequential, O(n log n); on one core here about 0.11 s for 832k triangles and 3.6 ms for
/// 27.6k clusters, 1.75 ms with ClusterScene's groups of at most 8 clusters (bench/bvh_bench.cpp,
/// --build-loop for the build alone). The binning loop has
/// an AVX2 variant chosen at runtime (BuildConfig::allow_avx2); the tree does not depend on it.
[[nodiscard]] Bvh build_binned_sah(const BuildInput& in, const BuildConfig& cfg = {});

/// Scratch memory of the binned builder, kept from one build to the next: a per-frame rebuild
/// into the same `out` with the same workspace allocates nothing once both have grown to size.
/// One workspace per thread. A copy is a fresh workspace (scratch content is never shared), so
/// the objects holding one stay copyable.
class BuildWorkspace {
 public:
  BuildWorkspace();
  ~BuildWorkspace();
  BuildWorkspace(const BuildWorkspace&);
  BuildWorkspace& operator=(const BuildWorkspace&);
  BuildWorkspace(BuildWorkspace&&) noexcept;
  BuildWorkspace& operator=(BuildWorkspace&&) noexcept;
  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
  friend void build_binned_sah(const BuildInput&, const BuildConfig&, Bvh&, BuildWorkspace&);
};

/// The same tree as build_binned_sah(in, cfg), written into `out` (its previous content is
/// replaced, its capacity reused).
void build_binned_sah(const BuildInput& in, const BuildConfig& cfg, Bvh& out, BuildWorkspace& ws);

}  // namespace ptc::bvh
