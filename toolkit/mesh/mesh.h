// A triangle mesh whose connectivity is fixed for a whole animation while its vertex positions
// change per frame. The triangle index array is shared (immutable, reference counted) between
// all copies of a mesh and all frames; a frame only owns its positions.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "toolkit/core/types.h"

namespace ptc {

class Mesh {
 public:
  Mesh() = default;
  /// Takes ownership of the triangles and positions. Every index must be < positions.size()
  /// (loaders check this and report the element; here a violation is a programmer error and
  /// throws std::invalid_argument).
  Mesh(std::vector<Tri> triangles, std::vector<Vec3> positions);
  /// A mesh sharing a triangle array another holds (shared_triangles(); no copy; null: no
  /// triangles), with these positions; indices checked as by the constructor.
  [[nodiscard]] static Mesh sharing(std::shared_ptr<const std::vector<Tri>> triangles, std::vector<Vec3> positions);

  [[nodiscard]] std::size_t triangle_count() const { return tris_ ? tris_->size() : 0; }
  [[nodiscard]] std::size_t vertex_count() const { return pos_.size(); }
  [[nodiscard]] bool empty() const { return triangle_count() == 0; }

  [[nodiscard]] std::span<const Tri> triangles() const {
    return tris_ ? std::span<const Tri>(*tris_) : std::span<const Tri>();
  }
  [[nodiscard]] const Tri& triangle(std::size_t t) const { return (*tris_)[t]; }
  [[nodiscard]] std::span<const Vec3> positions() const { return pos_; }
  [[nodiscard]] std::span<Vec3> positions() { return pos_; }
  [[nodiscard]] const Vec3& position(std::size_t v) const { return pos_[v]; }

  /// The three corner positions of triangle t.
  [[nodiscard]] std::array<Vec3, 3> corners(std::size_t t) const {
    const Tri& f = (*tris_)[t];
    return {pos_[f[0]], pos_[f[1]], pos_[f[2]]};
  }

  /// Replace the positions of the current frame (same vertex count; otherwise invalid_argument).
  void set_positions(std::vector<Vec3> positions);

  /// The shared, immutable triangle array (the topology every frame refers to).
  [[nodiscard]] std::shared_ptr<const std::vector<Tri>> shared_triangles() const { return tris_; }

  /// Renumbers the vertices in place: new vertex i is old vertex to_old[i] (positions moved,
  /// triangle corners renamed, the triangle order kept). The triangle array is renamed where it
  /// is (no copy) when no other mesh shares it, else this mesh gets a renamed copy; the positions
  /// are gathered into a new array. Throws std::invalid_argument, before anything changes, unless
  /// to_old is a permutation of 0 .. vertex_count-1.
  void renumber_vertices(std::span<const std::uint32_t> to_old);

  /// Same topology, new positions (no copy of the triangle array).
  [[nodiscard]] Mesh with_positions(std::vector<Vec3> positions) const;

  /// Axis-aligned bounding box of the referenced and unreferenced vertices alike.
  [[nodiscard]] Box3 bounds() const;
  /// Bounding box of the vertices some triangle uses: the shape the default camera and light
  /// frame (an unreferenced vertex far away would leave the mesh a dot in the image).
  [[nodiscard]] Box3 referenced_bounds() const;

 private:
  // std::invalid_argument naming the first triangle that refers to a vertex at or past n.
  static void check_indices(std::span<const Tri> triangles, std::size_t n);

  std::shared_ptr<std::vector<Tri>> tris_;  // never changed while shared (see renumber_vertices)
  std::vector<Vec3> pos_;
};

/// The inverse of a vertex renumbering: to_new[to_old[i]] = i. Throws std::invalid_argument
/// unless to_old is a permutation of 0 .. n-1 (n = to_old.size()), naming the first bad entry.
/// Mesh::referenced_bounds of these triangles over these positions (indices past the positions ignored).
[[nodiscard]] Box3 referenced_bounds(std::span<const Tri> triangles, std::span<const Vec3> positions);

[[nodiscard]] std::vector<std::uint32_t> inverse_permutation(std::span<const std::uint32_t> to_old);

/// Throws the same std::invalid_argument as inverse_permutation unless to_old is a permutation
/// of 0 .. n-1, with one bit of memory an entry.
void check_permutation(std::span<const std::uint32_t> to_old);

/// The mesh with its vertices renumbered: new vertex i is old vertex to_old[i] (positions moved,
/// triangle corners renamed; the triangle order is kept, so triangle ids stay valid). Throws
/// std::invalid_argument unless to_old is a permutation of 0 .. vertex_count-1.
[[nodiscard]] Mesh renumber_vertices(const Mesh& mesh, std::span<const std::uint32_t> to_old);

}  // namespace ptc
