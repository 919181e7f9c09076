#include "toolkit/mesh/mesh.h"

#include <stdexcept>
#include <string>

namespace ptc {

Mesh::Mesh(std::vector<Tri> triangles, std::vector<Vec3> positions) : pos_(std::move(positions)) {
  const std::size_t n = pos_.size();
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (std::uint32_t v : triangles[t])
      if (v >= n)
        throw std::invalid_argument("Mesh: triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                                    " of " + std::to_string(n));
  tris_ = std::make_shared<const std::vector<Tri>>(std::move(triangles));
}

void Mesh::set_positions(std::vector<Vec3> positions) {
  if (positions.size() != pos_.size())
    throw std::invalid_argument("Mesh::set_positions: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(pos_.size()) + " vertices");
  pos_ = std::move(positions);
}

Mesh Mesh::with_positions(std::vector<Vec3> positions) const {
  if (positions.size() != pos_.size())
    throw std::invalid_argument("Mesh::with_positions: " + std::to_string(positions.size()) + " positions for " +
                                std::to_string(pos_.size()) + " vertices");
  Mesh m;
  m.tris_ = tris_;
  m.pos_ = std::move(positions);
  return m;
}

Box3 Mesh::bounds() const {
  Box3 b;
  for (const Vec3& p : pos_) b.extend(p);
  return b;
}

}  // namespace ptc
