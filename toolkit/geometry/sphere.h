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
[[nodiscard]] Sphere min_sphere(std::span<const Vec3> points);

/// The exact minimal sphere computed with an exact number type. CGAL returns the center and
/// radius as a + b*sqrt(t) with rational a, b, t; they are rounded to double here (radius to
/// nearest, via MPFR), so `radius` is within 1 ulp of the true minimal radius.
/// Containment is NOT re-inflated: this is the reference value.
[[nodiscard]] Sphere min_sphere_exact(std::span<const Vec3> points);

[[nodiscard]] Sphere ritter_sphere(std::span<const Vec3> points);
/// directions: 3, 7 or 13 (EPOS-6, -14, -26); other values throw std::invalid_argument.
[[nodiscard]] Sphere epos_sphere(std::span<const Vec3> points, int directions);

/// Minimal sphere of a triangle in closed form: the circumsphere when the triangle is acute
/// (center in the plane), otherwise the sphere over the longest edge; degenerate triangles
/// (collinear or repeated corners) give the sphere over the two farthest corners.
[[nodiscard]] Sphere triangle_min_sphere(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace ptc
