// Welding of vertices that coincide in every frame of an animation (issue 6): assimp hands MD2,
// MD3 and most skinned assets over as triangle soups or with vertices split at texture seams;
// without welding the mesh has no shared edges, and clustering (which grows clusters over shared
// edges) degenerates to one triangle per cluster.
//
// Rule: vertices a and b merge iff their positions are exactly equal (==, so -0.0 equals +0.0;
// a NaN never equals anything) in EVERY frame fed to the welder. Coincidence in one frame is not
// enough: two vertices that touch at rest and separate later are different vertices.
//
// Algorithm: partition refinement, one frame at a time, so a long sequence never has to be in
// memory at once. Classes start as "all vertices"; each frame splits every class by the exact
// position of its members (hash map keyed by (class, position bits) -> new class, O(V) per frame).
// The result is deterministic: new vertex ids follow the first occurrence of each class in the
// input order, and each class is represented by its first (lowest-index) member.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "toolkit/core/types.h"

namespace ptc {

/// The outcome of welding: an index map from input vertices to welded vertices.
struct WeldMap {
  std::vector<std::uint32_t> remap;           ///< input vertex -> welded vertex (size = input count)
  std::vector<std::uint32_t> representative;  ///< welded vertex -> its first input vertex
  [[nodiscard]] std::size_t input_count() const { return remap.size(); }
  [[nodiscard]] std::size_t welded_count() const { return representative.size(); }
  /// Vertices removed by welding (input - welded).
  [[nodiscard]] std::size_t merged() const { return remap.size() - representative.size(); }
  /// Whether nothing was merged (the map is the identity).
  [[nodiscard]] bool identity() const { return merged() == 0; }

  /// Triangles with their corners renumbered (same order; triangles that become degenerate are
  /// kept, so triangle ids still follow the input).
  [[nodiscard]] std::vector<Tri> apply(std::span<const Tri> triangles) const;
  /// Welded positions of one frame: out[w] = in[representative[w]] (out.size() = welded_count()).
  void gather(std::span<const Vec3> in, std::span<Vec3> out) const;
  [[nodiscard]] std::vector<Vec3> gather(std::span<const Vec3> in) const;
};

/// Streaming welder: feed every frame (all of the same size), then finish().
class VertexWelder {
 public:
  explicit VertexWelder(std::size_t vertex_count);
  /// Refines the classes by one frame's positions (size must equal vertex_count, else
  /// std::invalid_argument).
  void add_frame(std::span<const Vec3> positions);
  [[nodiscard]] std::size_t frames() const { return frames_; }
  /// The map after the frames seen so far (at least one frame is required: std::logic_error
  /// otherwise, since with no frame every vertex would "coincide").
  [[nodiscard]] WeldMap finish() const;

 private:
  std::vector<std::uint32_t> cls_;  // class per input vertex
  std::uint32_t classes_ = 1;
  std::size_t frames_ = 0;
};

/// Convenience: weld over a list of frames (each of the same size).
[[nodiscard]] WeldMap weld_frames(std::span<const std::vector<Vec3>> frames);

}  // namespace ptc
