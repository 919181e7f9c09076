// What `ptc info` reports about a mesh: counts, extent, area and edge statistics, and every
// kind of defect the degenerate-input policy (docs/mesh_policy.md) counts instead of rejecting.
#pragma once

#include <cstddef>
#include <span>

#include "toolkit/core/types.h"
#include "toolkit/mesh/mesh.h"
#include "toolkit/core/stats.h"
#include "toolkit/mesh/topology.h"

namespace ptc {

struct MeshReport {
  std::size_t vertices = 0;              ///< positions in the mesh
  std::size_t triangles = 0;
  std::size_t unreferenced_vertices = 0; ///< vertices used by no triangle
  Box3 bounds;                           ///< over referenced vertices only
  double total_area = 0;                 ///< sum of triangle areas (one side; geometry/triangle.h, so
                                         ///< degenerate ones count 0); inf if beyond the double range
  Summary triangle_area;                 ///< per triangle
  Summary edge_length;                   ///< per unique edge (collapsed sides excluded)

  // Defects, counted (never repaired) — see docs/mesh_policy.md.
  std::size_t repeated_index_triangles = 0;  ///< a corner index appears twice or three times
  std::size_t zero_area_triangles = 0;       ///< distinct indices but collinear corners (exact predicate)
  /// Not zero-area, but the sine of the largest angle is below kDegenerateSine (1e-12): every
  /// cluster metric treats these as degenerate too (area 0, no normal; geometry/triangle.h).
  std::size_t near_degenerate_triangles = 0;
  std::size_t duplicate_vertices = 0;        ///< vertices whose coordinates equal an earlier vertex's (-0 == 0)
  std::size_t duplicate_triangles = 0;       ///< triangles with the same vertex set as an earlier one
  std::size_t edges = 0;                     ///< unique undirected edges
  std::size_t boundary_edges = 0;            ///< edges with one incident triangle
  std::size_t non_manifold_edges = 0;        ///< edges with three or more incident triangles
  std::size_t non_manifold_vertices = 0;     ///< vertices whose incident triangles form two or more edge-connected fans
  std::size_t components = 0;                ///< connected through shared vertices
  std::size_t edge_components = 0;           ///< connected through shared edges (dual-graph components)

  /// Closed 2-manifold: no boundary, non-manifold edge or vertex, and no triangle collapsed to an
  /// edge or a point by a repeated corner index (such a face has no edges to close, so a mesh of
  /// only such faces would otherwise pass).
  [[nodiscard]] bool closed_manifold() const {
    return boundary_edges == 0 && non_manifold_edges == 0 && non_manifold_vertices == 0 && triangles > 0 &&
           repeated_index_triangles == 0;
  }
  /// V - E + F over referenced vertices.
  [[nodiscard]] long long euler_characteristic() const {
    return static_cast<long long>(vertices - unreferenced_vertices) - static_cast<long long>(edges) +
           static_cast<long long>(triangles);
  }
};

[[nodiscard]] MeshReport analyze_mesh(const Mesh& mesh, const EdgeMap& edges);
[[nodiscard]] MeshReport analyze_mesh(const Mesh& mesh);

/// Exact orientation predicate: true when a, b, c are collinear (including coincident points).
/// Uses CGAL's filtered exact predicates, so the answer is exact for all finite doubles.
[[nodiscard]] bool collinear_exact(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace ptc
