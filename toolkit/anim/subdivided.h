// Scale-up: an animated source subdivided while it moves (issue 6, "a real skinned character
// reaches 250k-1.3M triangles with its real motion").
//
// Subdivision of a fixed topology is a fixed linear map (toolkit/mesh/subdivision.h): the
// Subdivider stencil is built ONCE from the source's topology, and each frame is
//   refined positions = stencil applied to the source's positions of that frame,
// one parallel sparse product into caller storage. What this carries:
// - keyframes (frame files, MD2/MD3 vertex animation, simulations, deformers): exactly the
//   subdivided keyframes, and since the map is linear, interpolating between keyframes and then
//   subdividing equals subdividing the keyframes and interpolating (for midpoint this is
//   "new vertex = linear interpolation of its parents' keyframe positions");
// - skinned sources: the refined vertices follow the skinned positions of their parents (the
//   surface of the posed mesh is refined). This is NOT the same as giving each new vertex
//   interpolated skinning weights and skinning it: linear blend skinning is not linear in
//   (weights, rest position) jointly, so the two differ by a second-order term wherever a new
//   vertex's parents have different weights. Refining the posed surface keeps the new vertices
//   on the (midpoint) posed surface, which is what a consumer of positions sees.
#pragma once

#include <vector>

#include "toolkit/anim/animation.h"
#include "toolkit/mesh/subdivision.h"

namespace ptc {

class SubdividedAnimation final : public Animation {
 public:
  /// Builds the stencil of `levels` steps of `scheme` over the source's topology (cost: see
  /// Subdivider::build; InputError from it, e.g. Loop on a non-manifold edge). source != null.
  SubdividedAnimation(AnimationPtr source, SubdivisionScheme scheme, int levels);

  /// Refined topology; rest positions = the stencil applied to the source's rest positions.
  [[nodiscard]] const Mesh& rest() const override { return rest_; }
  [[nodiscard]] std::size_t frame_count() const override { return source_->frame_count(); }
  [[nodiscard]] double frames_per_second() const override { return source_->frames_per_second(); }
  /// The source's positions at `frame` (into scratch space kept from construction), refined
  /// into out. Allocates nothing; the sparse product runs on oneTBB.
  void positions(double frame, std::span<Vec3> out) override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool is_static() const override { return source_->is_static(); }

  [[nodiscard]] const Animation& source() const { return *source_; }
  [[nodiscard]] const Subdivider& stencil() const { return sub_; }

 private:
  AnimationPtr source_;
  Subdivider sub_;
  Mesh rest_;
  std::vector<Vec3> scratch_;
};

}  // namespace ptc
