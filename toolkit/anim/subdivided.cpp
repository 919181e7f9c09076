#include "toolkit/anim/subdivided.h"

#include <stdexcept>

#include <fmt/format.h>

namespace ptc {

SubdividedAnimation::SubdividedAnimation(AnimationPtr source, SubdivisionScheme scheme, int levels)
    : source_(std::move(source)) {
  if (!source_) throw std::invalid_argument("SubdividedAnimation: null source");
  const Mesh& r = source_->rest();
  sub_ = Subdivider::build(r.triangles(), r.vertex_count(), scheme, levels);
  rest_ = sub_.apply(r);
  scratch_.resize(r.vertex_count());
}

void SubdividedAnimation::positions(double frame, std::span<Vec3> out) {
  if (out.size() != rest_.vertex_count())
    throw std::invalid_argument(
        fmt::format("positions: output holds {} vertices, the source has {}", out.size(), rest_.vertex_count()));
  source_->positions(frame, scratch_);
  sub_.apply(scratch_, out);
}

std::string SubdividedAnimation::describe() const {
  return fmt::format("{} x{} levels ({} triangles, {} vertices) of [{}]", to_string(sub_.scheme()), sub_.levels(),
                     rest_.triangle_count(), rest_.vertex_count(), source_->describe());
}

}  // namespace ptc
