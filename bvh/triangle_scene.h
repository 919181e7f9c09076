// The standard per-frame rebuild: a BVH over triangle boxes, leaves of a few triangles whose
// SIMD blocks are laid out in leaf order (see trace_scene.h for the per-frame loop).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "bvh/scene_config.h"
#include "bvh/scene_frame.h"
#include "bvh/wide_bvh.h"

namespace ptc::bvh {

/// Triangle BVH: one box per triangle; a leaf is a range of triangles whose blocks are laid out
/// in leaf order (each leaf starts a new block).
class TriangleScene {
 public:
  /// Keeps the topology (shared, not copied) and builds the first frame.
  explicit TriangleScene(const Mesh& mesh, const SceneConfig& cfg = triangle_scene_defaults());
  /// One frame: new positions (same vertex count).
  void update(std::span<const Vec3> positions);

  [[nodiscard]] const TraceData& data() const { return f_.data; }
  [[nodiscard]] const Bvh& bvh() const { return f_.bvh; }
  [[nodiscard]] std::span<const Box3f> boxes() const { return f_.boxes; }
  [[nodiscard]] const StageTimes& times() const { return f_.times; }
  /// Whether the last update refitted the tree instead of rebuilding it (SceneConfig::refit_growth);
  /// bvh() and boxes() are then those of the last build.
  [[nodiscard]] bool refitted() const { return refitted_; }
  /// Whether the last update tried the refit (refitted(), or rejected and then rebuilt).
  [[nodiscard]] bool refit_tried() const { return refit_tried_; }
  /// wide_sah_cost of the traced tree now, and right after its last build (both 0 without
  /// SceneConfig::refit_growth, which alone computes them).
  [[nodiscard]] double wide_cost() const { return wide_cost_; }
  [[nodiscard]] double built_wide_cost() const { return built_wide_cost_; }

 private:
  std::shared_ptr<const std::vector<Tri>> tris_;
  SceneConfig cfg_;
  SceneFrame f_;
  WideWorkspace wide_ws_;                   // the parallel collapse's and regroup's scratch
  std::vector<std::uint32_t> first_block_;  // per wide node: its first leaf block (the leaf data's prefix sum)
  AlignedVector<Box3f> block_boxes_;        // refit frames: each block's box
  bool refitted_ = false, refit_tried_ = false;
  double wide_cost_ = 0.0, built_wide_cost_ = 0.0;
  std::uint32_t age_ = 0;   // frames refitted since the last build
  bool refit_due_ = true;   // the next update tries the refit first
  std::uint32_t skip_ = 0, backoff_ = 1;  // rebuilds left without a refit attempt; the next such pause

  // fp: the frame positions without the sentinel (which follows them in f_.fpos).
  bool try_refit(std::span<const Vec3f> fp, std::span<const Tri> tris);
  void rebuild(std::span<const Vec3f> fp, std::span<const Tri> tris);
};

}  // namespace ptc::bvh
