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

 private:
  std::shared_ptr<const std::vector<Tri>> tris_;
  SceneConfig cfg_;
  SceneFrame f_;
  WideWorkspace wide_ws_;                   // the parallel collapse's and regroup's scratch
  std::vector<std::uint32_t> first_block_;  // per wide node: its first leaf block (the leaf data's prefix sum)
};

}  // namespace ptc::bvh
