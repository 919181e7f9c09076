// Skeletal animation: a node hierarchy with keyframed TRS channels, bone palettes and per-vertex
// weights, evaluated by linear blend skinning (LBS). Plain data (SkinRig) filled by a loader
// (assimp_source.h) or by hand; SkinnedAnimation evaluates it per frame.
//
// Per frame (time t in frames -> ticks = t / fps * ticks_per_second):
//   1. local[n] = T(t) * R(t) * S(t) for animated nodes (keys interpolated: lerp for T and S,
//      slerp for R; before the first / after the last key the nearest key holds), else the
//      node's rest transform;
//   2. global[n] = global[parent[n]] * local[n]   (nodes stored parents first);
//   3. palette[j] = global[palette_node[j]] * offset[j]   (offset = inverse bind matrix);
//   4. p'[v] = sum_i w_i * palette[j_i] * p[v]    (weights of a vertex normalised to sum 1).
// Vertices of meshes without bones use one palette entry (their node, identity offset), so rigid
// node animation is the same computation. Steps 1-3 are serial (nodes are few); step 4 runs
// in parallel over vertices (TBB). All scratch space is allocated at construction: positions()
// does not allocate.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "toolkit/anim/animation.h"

namespace ptc {

using Affine3 = Eigen::Transform<double, 3, Eigen::Affine>;

/// Keyframes of one node (times in ticks, increasing). Empty key lists fall back to the rest
/// transform's decomposition (rest_t/rest_r/rest_s).
struct NodeTrack {
  std::vector<double> t_times, r_times, s_times;
  std::vector<Vec3> t_keys, s_keys;
  std::vector<Eigen::Quaterniond> r_keys;
  Vec3 rest_t = Vec3::Zero(), rest_s = Vec3::Ones();
  Eigen::Quaterniond rest_r = Eigen::Quaterniond::Identity();
};

struct SkeletonNode {
  std::string name;
  std::int32_t parent = -1;  ///< index of the parent (< own index) or -1 for the root
  Affine3 rest = Affine3::Identity();  ///< local transform without animation
  std::int32_t track = -1;   ///< index into SkinRig::tracks or -1
};

struct SkinInfluence {
  std::uint32_t palette = 0;
  double weight = 0.0;
};

struct SkinRig {
  std::vector<SkeletonNode> nodes;
  std::vector<NodeTrack> tracks;
  double duration_ticks = 0.0;     ///< length of the animation
  double ticks_per_second = 25.0;  ///< > 0
  std::vector<std::uint32_t> palette_node;  ///< palette entry -> node
  std::vector<Affine3> palette_offset;      ///< palette entry -> offset (inverse bind) matrix
  std::vector<Vec3> bind_positions;         ///< per vertex, in its mesh's space
  std::vector<std::uint32_t> influence_begin;  ///< per vertex + 1 (CSR offsets into influences)
  std::vector<SkinInfluence> influences;
  std::vector<Tri> triangles;
};

/// Checks a rig's internal consistency (parents before children, indices in range, weights
/// finite and >= 0 with a positive sum, keys sorted); std::invalid_argument naming the item.
void validate(const SkinRig& rig);

struct SkinOptions {
  double fps = 30.0;  ///< sampling rate: frame f is at f / fps seconds (> 0)
  /// Weld vertices whose bind position and influence list are equal (they coincide in every
  /// frame, since LBS is a deterministic function of both): undoes texture-seam splits and the
  /// soups some importers produce.
  bool weld = true;
};

class SkinnedAnimation final : public Animation {
 public:
  /// Validates the rig (std::invalid_argument) and welds if asked.
  SkinnedAnimation(SkinRig rig, const SkinOptions& opt, std::string label);

  [[nodiscard]] const Mesh& rest() const override { return rest_; }
  /// floor(duration in seconds * fps) + 1 samples; 1 for a rig without animation.
  [[nodiscard]] std::size_t frame_count() const override { return frames_; }
  [[nodiscard]] double frames_per_second() const override { return opt_.fps; }
  void positions(double frame, std::span<Vec3> out) override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool is_static() const override { return rig_.tracks.empty() || frames_ <= 1; }

  /// Positions at a time in ticks (no range check: keys hold before the first / after the last;
  /// a one-frame rig always gives rest()).
  void positions_at_ticks(double ticks, std::span<Vec3> out);
  [[nodiscard]] std::size_t merged_vertices() const { return merged_; }
  [[nodiscard]] const SkinRig& rig() const { return rig_; }

 private:
  void pose(double ticks, bool animated);  // fills global_ and palette_
  void skin(std::span<Vec3> out) const;

  SkinRig rig_;
  SkinOptions opt_;
  std::string label_;
  Mesh rest_;
  std::size_t frames_ = 1, merged_ = 0;
  std::vector<Affine3> global_;
  std::vector<Eigen::Matrix<double, 3, 4>> palette_;
};

}  // namespace ptc
