// The per-cluster quantities of the method (docs/method.md, "Quantities for a cluster k"), as pure
// functions over a set of triangles of a mesh: reg, regBound, sizeBound, Acc, N_avg, AreaP,
// AreaC, connectivity, Naive(k) and the SAH hit probability.
//
// Units: lengths in mesh units L, areas in L^2; reg, regBound, sizeBound, Acc, connectivity,
// Naive and P_hit are dimensionless.
//
// Surface-area convention: the SAH "surface area" SA of a triangle (or of a flat surface) counts
// BOTH sides, SA = 2 * Area. This is what makes the paper's statements true: a triangle inside its
// box has P_hit in (0, 0.5] (exactly 0.5 for a right triangle in an axis plane), a disc >= pi/12
// (the geometry gives more: pi/4 axis-aligned down to pi/8 for the normal (1,1,1)/sqrt3; the
// paper's pi/12 is the bound from the disc's box lying inside its sphere's cube).
// For a closed sphere (one-sided SA 4 pi R^2) the paper's pi/6 is the probability that a random
// line through the box hits it; sum 2*Area_i / SA(box) is then pi/3: the EXPECTED NUMBER of
// crossings (Cauchy-Crofton), twice the probability, because every hitting line crosses twice.
// Naive(k) and p_hit below are that sum; they equal the hit probability exactly when no line can
// cross the cluster twice (a single triangle, a flat convex patch), and bound it from above
// otherwise.
#pragma once

#include <optional>
#include <string_view>
#include <cstddef>
#include <cstdint>
#include <span>

#include "toolkit/core/types.h"
#include "toolkit/geometry/sphere.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

/// Which reading of the paper's sizeBound (method.md): `Max` = max(1, SA(S)/(MaxSize*AvgSA)) as
/// printed (flat 1 until the sphere outgrows MaxSize times the average, then growing; default);
/// `Min` = min(1, ...) as the write-up's "(0, 1]" suggests. Both kept so the difference is measured.
enum class SizeBoundMode { Max, Min };
/// "max", "min".
[[nodiscard]] std::string_view to_string(SizeBoundMode m);
[[nodiscard]] std::optional<SizeBoundMode> parse_size_bound_mode(std::string_view s);

/// The free parameters of the objective Acc(k) (Garanzha 2009 as restated in method.md).
/// The functions here require max_count > 0, max_size > 0, avg_sa > 0 and throw
/// std::invalid_argument otherwise; "MaxCount = MaxSize = 0 means one triangle per cluster" is a
/// rule of the clustering algorithms, which must not call these functions in that case.
struct ClusterParams {
  double max_count = 50;  ///< MaxCount: vertex count at which regBound reaches 1; > 0. Paper sweep {10, 50, 100}, 50 best on Dragon.
  double max_size = 50;   ///< MaxSize: sphere SA, in units of AvgSA, beyond which sizeBound grows; > 0. Same sweep.
  double avg_sa = 0;      ///< AvgSA: mean SA 4 pi R^2 of the scene's per-triangle minimal spheres (L^2); > 0.
                          ///< Scene-dependent, so no usable default: 0 makes the functions throw until it is set.
  SizeBoundMode size_bound_mode = SizeBoundMode::Max;  ///< see SizeBoundMode
  SphereMethod sphere = SphereMethod::Cgal;             ///< bounding sphere used for R(k) (method.md: CGAL)
};

/// regBound(k) = VertexCount(k) / MaxCount (method.md). Range [0, inf). Throws
/// std::invalid_argument unless max_count > 0 (and finite).
[[nodiscard]] double reg_bound(std::size_t vertex_count, double max_count);

/// sizeBound(k) = max(1, SA(S(k)) / (MaxSize * AvgSA)) (mode Max; range [1, inf)) or
/// min(1, ...) (mode Min; range [0, 1]), with SA(S) = 4 pi R^2 the sphere's surface area (L^2,
/// >= 0). Throws std::invalid_argument unless max_size > 0, avg_sa > 0 (finite) and
/// sphere_surface_area >= 0.
[[nodiscard]] double size_bound(double sphere_surface_area, double max_size, double avg_sa,
                                SizeBoundMode mode = SizeBoundMode::Max);

/// Acc(k) = reg(k) - regBound(k) * sizeBound(k) (method.md "Objective"); larger is better.
[[nodiscard]] inline double acc(double reg, double reg_bound_value, double size_bound_value) {
  return reg - reg_bound_value * size_bound_value;
}

/// Result of average_normal: a unit vector, and whether the fallback rule chose it.
struct NormalAverage {
  Vec3 n = Vec3::UnitZ();
  bool fallback = true;
};

/// Relative threshold of the fallback: the normal sum is "numerically zero" when
///   |sum n_i| <= kNormalSumZeroTol * m,  m = number of non-zero normals.
/// Why: each unit normal carries a rounding error of a few eps (~1e-15 for well-shaped
/// triangles), so the computed sum of m of them is off by at most ~1e-15 m. A sum above 1e-9 m is
/// six orders of magnitude above that noise, so the direction of every non-fallback N_avg is
/// right to ~1e-6 rad at worst (to ~1e-15 rad when the sum is of order m); at or below it the
/// direction is rounding noise (a closed tetrahedron's sum is ~1e-16).
inline constexpr double kNormalSumZeroTol = 1e-9;
/// Areas within this relative distance of the largest count as tied for the fallback rule, so
/// that equal-area faces (regular tetrahedron) stay tied after a rotation's rounding.
inline constexpr double kFallbackAreaTieTol = 1e-12;

/// N_avg(k) = sum n_i / |sum n_i| over the unit normals n_i of the cluster's triangles
/// (method.md). Zero normals (degenerate triangles) contribute nothing.
/// Fallback (sum numerically zero, see kNormalSumZeroTol; e.g. a regular tetrahedron or a cube —
/// note that only the AREA-weighted normal sum vanishes on every closed surface, the plain sum
/// of unit normals vanishes only on symmetric ones): N_avg is
/// undefined, and this returns, deterministically, the unit normal of the largest-area triangle
/// (the lowest index among those within kFallbackAreaTieTol of the largest area) — a choice that
/// rotates with the cluster; if every normal is zero (or the input is empty), (0, 0, 1).
/// `fallback` is true in both cases. `areas` is used only by the fallback.
/// Throws std::invalid_argument if the spans differ in size.
[[nodiscard]] NormalAverage average_normal(std::span<const Vec3> unit_normals, std::span<const double> areas);

/// Every quantity of one cluster k (method.md). The empty cluster gives the value-initialised
/// result below (the "empty" result): counts 0, Sphere::empty(), all areas and ratios 0,
/// n_avg = (0,0,1) with n_avg_fallback = true, an empty box.
struct ClusterMetrics {
  std::size_t triangles = 0;  ///< N_T: triangles in k
  std::size_t vertices = 0;   ///< N_V = VertexCount(k): distinct vertex indices used by k
  Sphere sphere;              ///< S(k): bounding sphere of the distinct vertices (method chosen by the caller),
                              ///< computed in a cluster-local frame (see cluster_metrics); the center is then
                              ///< translated back, so it is rounded to ulp(|center|) in absolute coordinates
  double area = 0;            ///< sum_i Area_i (one side, L^2); degenerate triangles count 0
  double area_c = 0;          ///< AreaC(k) = pi R(k)^2 (L^2)
  double area_p = 0;          ///< AreaP(k) = sum_i Area_i |N_avg . n_i| (L^2)
  double reg = 0;             ///< reg(k) = AreaP/AreaC, in [0, ~1] for flat patches, can exceed 1 when curved; 0 when AreaC = 0
  Vec3 n_avg = Vec3::UnitZ(); ///< N_avg(k), see average_normal
  bool n_avg_fallback = true; ///< N_avg came from the fallback rule
  double connectivity = 0;    ///< N_T / N_V (method.md "Connectivity"); 0 for the empty cluster
  Box3 box;                   ///< axis-aligned box of the distinct vertices
  double naive = 0;           ///< Naive(k) = sum_i 2 Area_i / SA(box); 0 when SA(box) = 0 (then the area is 0 too)
  double p_hit = 0;           ///< SAH hit probability of the surface inside its box (same value as naive; see file comment)
};

/// Computes ClusterMetrics for the triangles `triangle_ids` of `mesh` (a set: ids must be distinct
/// and < mesh.triangle_count(), otherwise std::invalid_argument). The sphere is taken over the
/// cluster's distinct vertices with `sphere_method`, on coordinates relative to a local origin o
/// (per axis: 0 if the cluster's box touches or straddles 0, else the box minimum), so that the
/// differences p - o are exact for far-away clusters and R, AreaC, reg and Acc are translation
/// invariant to ~1e-15 relative (a 1e7 offset with 1e-3 features costs nothing). With
/// SphereMethod::Exact, R is then the exact minimal radius of the points p - o (exact differences
/// in the far-away case, correctly rounded ones otherwise). Cost O(k log k) plus the sphere.
/// Triangles need not be connected; degenerate and repeated-index triangles are allowed (they
/// count in N_T, their distinct vertices in N_V, and contribute zero area and no normal).
/// `vertices`: the triangles' distinct vertex ids, ascending, when the caller has them
/// (Clustering::vertices_of); empty: computed here (the same list).
[[nodiscard]] ClusterMetrics cluster_metrics(const Mesh& mesh, std::span<const std::uint32_t> triangle_ids,
                                             SphereMethod sphere_method = SphereMethod::Cgal,
                                             std::span<const std::uint32_t> vertices = {});

/// Acc(k) = reg - regBound(N_V, MaxCount) * sizeBound(SA(S), MaxSize, AvgSA, mode) of already
/// computed metrics (params.sphere is not used: the sphere is in `m`). Empty cluster: 0.
[[nodiscard]] double cluster_acc(const ClusterMetrics& m, const ClusterParams& params);

/// Convenience: cluster_acc(cluster_metrics(mesh, ids, params.sphere), params).
[[nodiscard]] double cluster_acc(const Mesh& mesh, std::span<const std::uint32_t> triangle_ids,
                                 const ClusterParams& params);

}  // namespace ptc
