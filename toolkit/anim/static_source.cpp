#include "toolkit/anim/static_source.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace ptc {

StaticSource::StaticSource(Mesh mesh, std::string label) : mesh_(std::move(mesh)), label_(std::move(label)) {}

void StaticSource::positions(double frame, std::span<Vec3> out) {
  if (!std::isfinite(frame)) throw std::invalid_argument("positions: frame time is not finite");
  if (out.size() != mesh_.vertex_count())
    throw std::invalid_argument(
        fmt::format("positions: output holds {} vertices, the source has {}", out.size(), mesh_.vertex_count()));
  std::ranges::copy(mesh_.positions(), out.begin());
}

bool StaticSource::renumber_vertices_in_place(std::span<const std::uint32_t> to_old) {
  mesh_.renumber_vertices(to_old);  // in place
  return true;
}

std::string StaticSource::describe() const {
  return fmt::format("static {} ({} triangles, {} vertices)", label_, mesh_.triangle_count(), mesh_.vertex_count());
}

}  // namespace ptc
