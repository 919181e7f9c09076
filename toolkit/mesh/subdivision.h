// Uniform subdivision of a fixed triangle topology, built once and applied to every frame.
//
// The connectivity of an animated mesh never changes, so a subdivision scheme is a fixed LINEAR
// map from the old positions to the refined ones. `Subdivider::build` turns (triangles, scheme,
// levels) into that map: one sparse row per refined vertex (CSR; the per-level maps are composed
// into a single one, so a frame is one parallel sparse product) plus the refined triangle array.
// `apply` then maps any frame's positions; it allocates nothing and runs on oneTBB.
//
// Schemes
// - Midpoint: every triangle is split 1-to-4 at its edge midpoints. The refined surface is the
//   old one exactly (same point set, same area); works on any triangle array.
// - Loop: C. T. Loop, "Smooth Subdivision Surfaces Based on Triangles", M.S. thesis, University
//   of Utah, 1987, with the rules OpenMesh's Subdivider::Uniform::LoopT uses (bit-compatible
//   weights, so it serves as the test oracle):
//     interior edge (two triangles a b c, b a d):  3/8 (a + b) + 1/8 (c + d)
//     boundary edge (one triangle):                1/2 (a + b)
//     interior vertex of valence n:                (1 - alpha) v + alpha/n * sum of neighbours,
//                                                  alpha = (40 - (3 + 2 cos(2 pi / n))^2) / 64
//                                                  (= n * beta of Loop's thesis; any n, whereas
//                                                  OpenMesh's table stops at n = 49)
//     boundary vertex (one open fan):              3/4 v + 1/8 (l + r), l, r its two neighbours
//                                                  along the boundary
//   Choices beyond the standard rules (Hoppe et al., "Piecewise smooth surface reconstruction",
//   SIGGRAPH 1994, call a vertex with more than two crease/boundary edges a corner):
//     * a non-manifold vertex (its triangles form two or more edge-connected fans, e.g. two fans
//       touching at a point, or two closed surfaces sharing a vertex) is a CORNER: it keeps its
//       position at every level. Edges around it follow the edge rules above.
//     * orientation is not required: the rules only need each edge's (at most two) triangles and
//       each vertex's neighbours, so inconsistently oriented or non-orientable input is
//       subdivided; each child triangle keeps its parent's orientation.
//     * rejected with InputError (file "", location ""), checked in this order:
//       - an edge on three or more triangles (element "edge (a, b)", a < b): the edge rule has
//         no "two opposite vertices";
//       - a triangle with a repeated corner index (element "triangle t"): same reason;
//       - a triangle on the same three corners as an earlier one, either orientation (element
//         "triangle t", the later one): one level would be defined, but its children's inner
//         edges lie on four triangles, so the next level is not.
//
// Numbering (per level, and therefore for the composed map):
// - old vertices keep their indices 0 .. V-1, including unreferenced ones, which are carried
//   unchanged;
// - the new vertex of edge e is V + e, where edges are ordered as in EdgeMap (lexicographically
//   by (smaller endpoint, larger endpoint)); so one level maps V vertices to V + E;
// - triangle t (corners v0 v1 v2, side k joins corner k and k+1) becomes the four triangles
//     4t + 0: (v0, m0, m2)   4t + 1: (m0, v1, m1)   4t + 2: (m2, m1, v2)   4t + 3: (m0, m1, m2)
//   where mk is the new vertex of side k. Each child keeps the parent's orientation. A collapsed
//   side (two equal indices, Midpoint only) is no edge: its "midpoint" is that corner itself.
// After L levels triangle t's descendants are 4^L t .. 4^L (t + 1) - 1.
//
// Precision: a row stores an anchor column (its largest weight) first and is evaluated as
//   out = p[anchor] + sum_k w_k (p[c_k] - p[anchor]),
// which equals sum_k w_k p[c_k] because every row's weights sum to 1 (both schemes are affine),
// but keeps full precision for a mesh far from the origin: with offsets of 1e7 and features of
// 1e-3 the differences are exact and a midpoint is the correctly rounded 1/2 (a + b).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "toolkit/core/types.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

enum class SubdivisionScheme { Midpoint, Loop };

/// "midpoint" or "loop" (ASCII case-insensitive); nullopt for anything else.
[[nodiscard]] std::optional<SubdivisionScheme> parse_subdivision_scheme(std::string_view name);
/// "midpoint" or "loop".
[[nodiscard]] std::string_view to_string(SubdivisionScheme scheme);

class Subdivider {
 public:
  /// The map of `levels` subdivision steps of `triangles` over `vertex_count` vertices.
  /// - levels: number of 1-to-4 steps, >= 0 (0 = identity); InputError (element "levels") when
  ///   negative or when the result would not fit 32-bit indices.
  /// - every index must be < vertex_count (std::invalid_argument otherwise, as for Mesh).
  /// - Loop: InputError for a non-manifold edge, a triangle with a repeated index or two
  ///   triangles on the same corners, whatever `levels` > 0 (see the file comment); Midpoint
  ///   accepts any triangle array.
  /// Cost: O(result size) time and memory. The composed map has at most 3 entries per refined
  /// vertex for Midpoint; for Loop about 4.7, 8.1, 10.2 (max 12, 17, 19) at 1, 2, 3 levels on
  /// armadillo, bounded because a Loop vertex depends on a 2-ring of the input. Armadillo (52k
  /// triangles) to 832k triangles (2 levels), Release, 2 shared cores: build 0.25-0.5 s (Loop) /
  /// 0.05-0.1 s (Midpoint), apply 3-20 ms / 1.5-9 ms.
  [[nodiscard]] static Subdivider build(std::span<const Tri> triangles, std::size_t vertex_count,
                                        SubdivisionScheme scheme, int levels);

  /// Identity map of an empty mesh.
  Subdivider();

  [[nodiscard]] SubdivisionScheme scheme() const { return scheme_; }
  [[nodiscard]] int levels() const { return levels_; }
  /// Vertex count of the input positions `apply` expects.
  [[nodiscard]] std::size_t source_vertex_count() const { return source_vertex_count_; }
  /// The refined topology (4^levels triangles per input triangle, numbered as in the file comment).
  [[nodiscard]] std::span<const Tri> triangles() const { return refined_.triangles(); }
  /// Refined vertex count.
  [[nodiscard]] std::size_t vertex_count() const { return refined_.vertex_count(); }

  /// One row of the linear map: refined vertex = sum_k weights[k] * old[columns[k]]. The first
  /// entry is the anchor (largest weight); columns are distinct; weights are >= 0 and sum to 1.
  struct Row {
    std::span<const std::uint32_t> columns;
    std::span<const double> weights;
  };
  [[nodiscard]] Row row(std::size_t refined_vertex) const {
    const std::size_t b = row_offsets_[refined_vertex], e = row_offsets_[refined_vertex + 1];
    return {{columns_.data() + b, e - b}, {weights_.data() + b, e - b}};
  }
  /// Stored entries over all rows (the map's memory is about 12 bytes per entry).
  [[nodiscard]] std::size_t nonzero_count() const { return columns_.size(); }

  /// out[i] = refined position i of the frame `in`. Multithreaded (oneTBB), allocates nothing,
  /// safe to call concurrently. std::invalid_argument unless in.size() == source_vertex_count(),
  /// out.size() == vertex_count() and the two spans do not overlap.
  void apply(std::span<const Vec3> in, std::span<Vec3> out) const;

  /// The refined mesh of frame `m`. Its triangle array is shared (not copied) by every mesh this
  /// returns. std::invalid_argument unless m has the topology the map was built for.
  [[nodiscard]] Mesh apply(const Mesh& m) const;

 private:
  SubdivisionScheme scheme_ = SubdivisionScheme::Midpoint;
  int levels_ = 0;
  std::size_t source_vertex_count_ = 0;
  std::vector<Tri> source_triangles_;      // to check apply(Mesh)'s topology
  Mesh refined_;                           // refined triangles + placeholder positions (shared by results)
  std::vector<std::size_t> row_offsets_;   // vertex_count() + 1
  std::vector<std::uint32_t> columns_;
  std::vector<double> weights_;
};

/// Subdivider::build(m.triangles(), m.vertex_count(), scheme, levels).apply(m).
[[nodiscard]] Mesh subdivide(const Mesh& m, SubdivisionScheme scheme, int levels);

}  // namespace ptc
