// A scene part that does not move: positions() returns the rest positions at every frame time,
// and is_static() is true, so consumers keep its BVH across frames (issue 6: "static meshes keep
// their BVH across frames, only moving meshes are updated").
#pragma once

#include "toolkit/anim/animation.h"

namespace ptc {

class StaticSource final : public Animation {
 public:
  /// `label` names the source in describe() (a file name, "sphere", "floor").
  explicit StaticSource(Mesh mesh, std::string label = "mesh");

  [[nodiscard]] const Mesh& rest() const override { return mesh_; }
  /// 0: any frame time is valid (the same positions at every one).
  [[nodiscard]] std::size_t frame_count() const override { return 0; }
  /// Copies the rest positions (std::invalid_argument for a wrong out size or a non-finite time).
  void positions(double frame, std::span<Vec3> out) override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool is_static() const override { return true; }
  bool renumber_vertices_in_place(std::span<const std::uint32_t> to_old) override;

 private:
  Mesh mesh_;
  std::string label_;
};

}  // namespace ptc
