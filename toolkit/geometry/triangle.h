// Per-triangle geometry: area, unit normal, edge lengths, perimeter, centroid. Inline, pure.
//
// Degeneracy rule (one rule for area and normal, so that they never disagree):
//   the cross product is formed at the corner between the two SHORTEST sides e1, e2 (the largest
//   angle), which minimises its rounding error; the triangle is DEGENERATE when
//       |e1 x e2| <= kDegenerateSine * |e1| * |e2|
//   i.e. when the sine of its largest angle is below kDegenerateSine (this includes repeated
//   corners, where |e1| = 0, and exactly collinear corners). A degenerate triangle has area 0 and
//   the zero normal, and so contributes nothing to area sums or area-weighted normal sums.
// Why 1e-12: every component of the computed cross product carries an absolute rounding error of
// about 3 eps |e1| |e2| (eps = 2.2e-16), so its direction is only known to ~6 eps / sine radians.
// Above 1e-12 a normal is right to ~1.3e-3 rad even for the worst accepted sliver (to ~1e-15 rad
// for well-shaped triangles); below it the direction is noise, while the area dropped is at most
// 5e-13 |e1| |e2| (far below anything a metric can see).
//
// Range: lengths use std::hypot (no overflow/underflow in the squares); the cross product's
// components are products of two coordinate differences, so side lengths must lie in about
// [1e-150, 1e150] (scales 1e-30 and 1e+30, offsets of 1e7 with features of 1e-3 are fine: the
// differences of nearby doubles are exact, so a far offset costs nothing beyond the rounding of
// the input coordinates themselves).
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "toolkit/core/types.h"

namespace ptc {

/// Threshold on the sine of a triangle's largest angle below which it is degenerate (see above).
inline constexpr double kDegenerateSine = 1e-12;

/// Euclidean length without overflow or underflow of the squares.
[[nodiscard]] inline double safe_norm(const Vec3& v) { return std::hypot(v.x(), v.y(), v.z()); }

/// std::ilogb(x) for a finite x != 0, read off the exponent field where x is normal (no libm call
/// in the per-triangle loop; docs/scale.md has the figures); subnormals go to std::ilogb.
[[nodiscard]] inline int exponent_of(double x) {
  const int field = static_cast<int>((std::bit_cast<std::uint64_t>(x) >> 52) & 0x7ff);
  return field != 0 ? field - 1023 : std::ilogb(x);
}

/// std::ldexp(x, k), exactly: x times the double 2^k where that is a normal double (one rounding,
/// to nearest, as ldexp's), else std::ldexp itself.
[[nodiscard]] inline double times_pow2(double x, int k) {
  if (k < -1022 || k > 1023) return std::ldexp(x, k);
  return x * std::bit_cast<double>(static_cast<std::uint64_t>(k + 1023) << 52);
}
/// times_pow2 of every coordinate.
[[nodiscard]] inline Vec3 times_pow2(const Vec3& v, int k) {
  return {times_pow2(v.x(), k), times_pow2(v.y(), k), times_pow2(v.z(), k)};
}

/// Area (one side, unit length^2) and unit normal (right-handed in corner order a, b, c) of a
/// triangle; degenerate triangles (see the file comment) give area 0 and normal (0, 0, 0).
struct TriangleGeometry {
  double area = 0;
  Vec3 normal = Vec3::Zero();
};

// Always inlined: the tables' pass calls it from an instruction-set clone (toolkit/core/isa.h).
[[nodiscard]] [[gnu::always_inline]] inline
TriangleGeometry triangle_geometry(const Vec3& a, const Vec3& b, const Vec3& c) {
  // Sides opposite each corner; the corner between the two shortest sides is the one opposite
  // the longest side. (b-a) x (c-a) = (c-b) x (a-b) = (a-c) x (b-c): same orientation.
  // Scale the sides by a power of two (exact) so that the cross product neither overflows
  // (coordinates ~1e300) nor underflows (~1e-300); the area is scaled back at the end.
  Vec3 ab = b - a, bc = c - b, ca = a - c;
  double big = std::max({ab.cwiseAbs().maxCoeff(), bc.cwiseAbs().maxCoeff(), ca.cwiseAbs().maxCoeff()});
  int e = 0;
  if (!std::isfinite(big) && a.allFinite() && b.allFinite() && c.allFinite()) [[unlikely]] {
    // A side beyond double's range between finite corners (signs opposite, near 1e308): the sides
    // of the same triangle at a quarter of its size (exact), and two more binary orders in e.
    const Vec3 qa = 0.25 * a, qb = 0.25 * b, qc = 0.25 * c;
    ab = qb - qa, bc = qc - qb, ca = qa - qc;
    big = std::max({ab.cwiseAbs().maxCoeff(), bc.cwiseAbs().maxCoeff(), ca.cwiseAbs().maxCoeff()});
    e = 2;
  }
  if (big > 0 && std::isfinite(big)) {
    const int k = exponent_of(big);
    if (k >= -1023) {
      const double scale = times_pow2(1.0, -k);
      ab = ab * scale, bc = bc * scale, ca = ca * scale;
    } else {  // (subnormal sides: 2^-k is beyond double, so each coordinate is scaled alone)
      ab = times_pow2(ab, -k), bc = times_pow2(bc, -k), ca = times_pow2(ca, -k);
    }
    e += k;
  }
  const double lab = safe_norm(ab), lbc = safe_norm(bc), lca = safe_norm(ca);
  Vec3 cr;
  double l1, l2;
  if (lbc >= lab && lbc >= lca) {  // longest side bc: corner a, sides ab and ac
    cr = ab.cross(-ca);
    l1 = lab, l2 = lca;
  } else if (lca >= lab) {  // longest side ca: corner b, sides bc and ba
    cr = bc.cross(-ab);
    l1 = lbc, l2 = lab;
  } else {  // longest side ab: corner c, sides ca and cb
    cr = ca.cross(-bc);
    l1 = lca, l2 = lbc;
  }
  const double n = safe_norm(cr);
  TriangleGeometry g;
  if (!(n > kDegenerateSine * l1 * l2)) return g;  // also catches n == 0 and NaN
  g.area = times_pow2(0.5 * n, 2 * e);  // inf only when the true area exceeds the double range
  g.normal = cr / n;
  return g;
}

/// v / |v| for a finite v != 0 whose length may be beyond double (|(1e308, 1.5e308, 0)|): v over
/// its largest coordinate first. (Eigen's stableNormalized() divides by the length itself, which
/// overflows there, and returns 0.)
[[nodiscard]] inline Vec3 unit_vector(const Vec3& v) {
  const Vec3 s = v / v.cwiseAbs().maxCoeff();
  return s / s.norm();
}

/// |q - p| for finite points, inf only when the distance itself is beyond double's range (the
/// difference of coordinates near 1e308 of opposite signs overflows: then four times the
/// distance of the quartered points, exact); NaN for a non-finite point.
[[nodiscard]] inline double safe_distance(const Vec3& p, const Vec3& q) {
  const Vec3 d = q - p;
  if (d.allFinite() || !p.allFinite() || !q.allFinite()) return safe_norm(d);
  return 4.0 * safe_norm(0.25 * q - 0.25 * p);
}

/// Area of one side (unit length^2); 0 for degenerate triangles.
[[nodiscard]] inline double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c) {
  return triangle_geometry(a, b, c).area;
}

/// Unit normal, right-handed in corner order; the zero vector for degenerate triangles.
[[nodiscard]] inline Vec3 triangle_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  return triangle_geometry(a, b, c).normal;
}

/// Sum of the three side lengths (unit length). Collapsed sides have length 0.
[[nodiscard]] inline double triangle_perimeter(const Vec3& a, const Vec3& b, const Vec3& c) {
  return safe_norm(b - a) + safe_norm(c - b) + safe_norm(a - c);
}

/// Arithmetic mean of the corners, computed as (a + b + c) / 3.
[[nodiscard]] inline Vec3 triangle_centroid(const Vec3& a, const Vec3& b, const Vec3& c) { return (a + b + c) / 3.0; }

/// A pass over a large mesh's triangles reads each triangle's three corners; when the vertex
/// numbers are far from the triangle order (a subdivided mesh numbers its new vertices by edge),
/// those reads miss the cache one after the other. Such a pass asks for the corners of the
/// triangle kCornerPrefetchAhead places ahead (docs/scale.md, "Open (issue 15)").
inline constexpr std::size_t kCornerPrefetchAhead = 8;
inline void prefetch_corners(const Vec3* positions, const Tri& f) {
  for (const std::uint32_t v : f) __builtin_prefetch(positions + v);
}

}  // namespace ptc
