// Bounding spheres of point sets: the exact minimal sphere (CGAL Min_sphere_of_spheres_d),
// its fast working path, and fast approximations, all behind one method enum so that the
// speed-against-error report can compare them item by item.
//
// Conventions (contract for every function below):
// - The empty point set gives Sphere::empty(): center 0, radius -1 (contains nothing).
// - Points must be finite (loaders reject NaN/Inf). Non-finite input gives a NaN radius.
// - Every returned sphere contains all its points: |p - c| <= r * (1 + 8 eps) for every p
//   (eps = DBL_EPSILON); `contains_all` checks this and tests call it.
#pragma once

#include <algorithm>
#include <cstddef>
#include <optional>
#include <span>
#include <string_view>

#include "toolkit/core/types.h"

namespace ptc {

struct Sphere {
  Vec3 center = Vec3::Zero();
  double radius = -1.0;

  [[nodiscard]] static Sphere empty() { return {}; }
  [[nodiscard]] bool is_empty() const { return radius < 0.0; }
  /// Surface area 4 pi r^2 (0 for the empty sphere).
  [[nodiscard]] double surface_area() const;
  /// Great-circle area pi r^2 (AreaC in method.md; 0 for the empty sphere).
  [[nodiscard]] double great_circle_area() const;
};

/// Relative tolerance of the containment guarantee above.
inline constexpr double kSphereContainmentTol = 8.0 * 2.220446049250313e-16;

/// True when |p - center| <= radius * (1 + rel_tol) for every point (relative to the radius;
/// for radius 0 the points must coincide with the center up to rel_tol times the largest
/// coordinate magnitude).
[[nodiscard]] bool contains_all(const Sphere& s, std::span<const Vec3> points, double rel_tol = kSphereContainmentTol);

enum class SphereMethod {
  Exact,   ///< CGAL with an exact number type: the oracle (slow, ~300x the working path).
  Cgal,    ///< CGAL with double on normalised coordinates: the working path (minimal to ~1e-15).
  Ritter,  ///< Ritter 1990: two passes, typically 5-20% larger than minimal.
  Epos6,   ///< Larsson 2008 EPOS with 3 directions (6 extremal points), then Ritter growth.
  Epos14,  ///< EPOS with 7 directions (14 points).
  Epos26,  ///< EPOS with 13 directions (26 points).
};
inline constexpr SphereMethod kAllSphereMethods[] = {SphereMethod::Exact,  SphereMethod::Cgal,   SphereMethod::Ritter,
                                                    SphereMethod::Epos6,  SphereMethod::Epos14, SphereMethod::Epos26};
[[nodiscard]] std::string_view to_string(SphereMethod m);
/// "exact", "cgal", "ritter", "epos6", "epos14", "epos26"; nullopt otherwise.
[[nodiscard]] std::optional<SphereMethod> parse_sphere_method(std::string_view s);

/// Dispatches to the functions below.
[[nodiscard]] Sphere bounding_sphere(SphereMethod m, std::span<const Vec3> points);

/// Working path: CGAL Min_sphere_of_spheres_d<double> on coordinates translated to the box
/// center and scaled by a power of two to unit extent (exact operations), mapped back; the
/// radius is then raised to the largest center-point distance so that containment holds.
/// Precision: the radius is minimal to ~1e-15 of the set's extent PLUS ~1 ulp of the largest
/// coordinate magnitude, because the center is rounded in absolute coordinates before the
/// radius is raised (offset 1e7, features 1e-3: ~2e-9 absolute, ~1e-6 relative). Callers that
/// need the radius of a small set far from the origin pass coordinates relative to a local
/// origin (cluster_metrics does).
[[nodiscard]] Sphere min_sphere(std::span<const Vec3> points);

/// The exact minimal sphere computed with an exact number type. CGAL returns the center and
/// radius as a + b*sqrt(t) with rational a, b, t; they are rounded to double here (radius to
/// nearest, via MPFR), so `radius` is within 1 ulp of the true minimal radius.
/// Containment is NOT re-inflated: this is the reference value.
/// Guarantee (stronger than the line above): every center coordinate and the radius are the
/// correctly rounded (to nearest, ties to even) doubles of the exact values. Cancellation in
/// a + b*sqrt(t) is avoided by evaluating (a^2 - b^2 t) / (a - b sqrt(t)) when the terms have
/// opposite signs, with a Ziv loop (mpfr_can_round) that raises the precision from 256 bits
/// until the rounding is decided; a rational value (b = 0 or t a perfect square) is rounded
/// directly. Because the center is rounded, |p - center| computed in double may exceed `radius`
/// by up to ~2 ulp of the largest coordinate magnitude (see exact_containment_tol).
[[nodiscard]] Sphere min_sphere_exact(std::span<const Vec3> points);

/// The relative tolerance under which contains_all holds for min_sphere_exact's result: the
/// rounding of the center to double displaces it by up to sqrt(3)/2 ulp of the largest
/// coordinate magnitude M, so tol = kSphereContainmentTol + 4 eps M / radius (infinite for a
/// radius of 0, where contains_all uses its own absolute rule).
[[nodiscard]] double exact_containment_tol(const Sphere& exact, std::span<const Vec3> points);

/// Ritter 1990: pass 1 finds the points of extreme x, y, z and spans the initial sphere over the
/// farthest of the three pairs; pass 2 grows the sphere over every outside point (center moved
/// toward it, new radius (r + d) / 2). Like every approximation below, a last pass sets the
/// radius to the largest center-point distance: that is what makes containment hold under
/// rounding, and it removes the growth passes' overshoot (never larger than Ritter's radius).
[[nodiscard]] Sphere ritter_sphere(std::span<const Vec3> points);
/// EPOS-2s (Larsson 2008): the points of extreme projection onto s fixed directions (axes, cube
/// diagonals, cube edge directions), their minimal sphere (Welzl's move-to-front in double on
/// normalised coordinates; duplicates removed first), then Ritter's growth pass over all points
/// and the containment pass. Sets of at most 2s points are solved directly (Larsson's rule).
/// directions: 3, 7 or 13 (EPOS-6, -14, -26); other values throw std::invalid_argument.
/// Cost is O(s n): on cluster-sized sets (~65 points) EPOS-14/-26 are slower than min_sphere.
[[nodiscard]] Sphere epos_sphere(std::span<const Vec3> points, int directions);

/// Minimal sphere of a triangle in closed form: the circumsphere when the triangle is acute
/// (center in the plane), otherwise the sphere over the longest edge; degenerate triangles
/// (collinear or repeated corners) give the sphere over the two farthest corners.
/// The acute case is computed relative to the corner with the largest angle (the cross
/// product is then well conditioned), the others from the longest edge's midpoint; the radius
/// is finally raised to the largest center-corner distance (containment, as above). On edges
/// scaled by a power of two to unit size: scaling the corners by 2^k scales the result by 2^k
/// bit for bit over the whole double range (the unscaled fifth powers under- or overflow beyond
/// ~1e+-62).
[[nodiscard]] Sphere triangle_min_sphere(const Vec3& a, const Vec3& b, const Vec3& c);

/// SA = 4 pi R^2 of triangle_min_sphere, on the triangle's local coordinates p - o (o = the
/// per-axis minimum of its corners, whatever their order), so that it does not depend on where
/// the triangle sits: an exact translation leaves p - o, and so the bits, unchanged. In world
/// coordinates the center was rounded to ulp(|center|) and the radius, the largest
/// |p - center|, with it: at an exact offset of 2^32 a mesh's AvgSA moved by 7e-6 relative.
/// AvgSA's term.
[[nodiscard]] inline double triangle_sphere_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 o(std::min({a.x(), b.x(), c.x()}), std::min({a.y(), b.y(), c.y()}), std::min({a.z(), b.z(), c.z()}));
  return triangle_min_sphere(a - o, b - o, c - o).surface_area();
}

/// The chunk of average_triangle_sphere_area's sums (ClusterTables' one-pass AvgSA uses it too).
inline constexpr std::size_t kAvgSaChunk = 65536;

/// AvgSA of method.md: the mean surface area 4 pi R^2 of the minimal spheres of the single
/// triangles (triangle_sphere_area); 0 for no triangles. Indices must be < positions.size()
/// (asserted). Summed in parallel in fixed chunks of kAvgSaChunk triangles, added in order: the same
/// value at any thread count.
[[nodiscard]] double average_triangle_sphere_area(std::span<const Vec3> positions, std::span<const Tri> triangles);

namespace detail {
/// The rounding behind min_sphere_exact, exposed for tests: the correctly rounded (to nearest,
/// ties to even) double of a + b*sqrt(t) for rationals written "p/q" or "p" (base 10, t >= 0).
/// Throws std::invalid_argument on malformed text.
[[nodiscard]] double round_sqrt_form(std::string_view a, std::string_view b, std::string_view t);
}  // namespace detail

}  // namespace ptc
