// The binned SAH builder (Wald 2007), the one the scenes rebuild every frame with; its scratch
// memory (BuildWorkspace) is kept from one build to the next. One of the two builders behind
// sah_builder.h (which states the split rule both follow).
#pragma once

#include <memory>

#include "bvh/build_config.h"

namespace ptc::bvh {

/// Binned SAH (Wald 2007): centroids are binned into equal bins per axis of the node's
/// centroid bounds and the bins' boundaries are the candidate planes: cfg.bins bins, but at most
/// max(4, |P| / 4) in a node of |P| primitives (most of 16 bins would stay empty there). Nodes of
/// at most 16 primitives are split by the exact sweep instead (cheaper there, and exact; along
/// the longest axis only unless cfg.small_nodes_longest_axis is false); two
/// primitives that must be split are split without search; a node within max_leaf_size whose
/// leaf cost is below the lower bound traversal + intersection * sum_p A(p) w(p) / A(node) of
/// every split becomes a leaf without evaluating splits (the same decision, sooner).
/// O(n log n); on one core here about 0.11 s for 832k triangles and 3.6 ms for 27.6k clusters,
/// 1.75 ms with ClusterScene's groups of at most 8 clusters (bench/bvh_bench.cpp, --build-loop
/// for the build alone). From 2^15 items at the root (primitives, or groups) on more than one
/// thread of the caller's arena it runs in parallel: subtrees are built at once as fragments of
/// the tree and spliced in pre-order, and the tree, its node order, prim_order and the cost
/// (its terms summed in node order) are the sequential build's, bit for bit, at any thread count.
/// The binning loop has an AVX2 variant chosen at runtime (BuildConfig::allow_avx2); the tree
/// does not depend on it.
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
