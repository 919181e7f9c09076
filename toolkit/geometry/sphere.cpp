// Bounding spheres without CGAL: the approximations (Ritter, EPOS), the triangle closed form and
// the small helpers. The CGAL paths (min_sphere, min_sphere_exact) live in min_sphere_cgal.cpp.
#include "toolkit/geometry/sphere.h"
#include "toolkit/core/isa.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "toolkit/geometry/triangle.h"

namespace ptc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Sphere nan_sphere() { return {Vec3::Constant(kNaN), kNaN}; }

/// The containment pass shared by all approximations: for a fixed center the smallest radius
/// that contains every point is max |p - c|, computed exactly as contains_all computes it
/// (sqrt is monotone, so sqrt of the largest squared norm is the largest norm). This also
/// removes any overshoot of the growth passes. Non-finite input gives a NaN sphere (0 * x is 0
/// for finite x and NaN for +-inf and NaN, so one sum answers for all coordinates).
Sphere finish(const Vec3& c, std::span<const Vec3> points) {
  double m2 = 0.0, bad = 0.0;
  for (const Vec3& p : points) {
    m2 = std::max(m2, (p - c).squaredNorm());
    bad += 0.0 * p.x() + 0.0 * p.y() + 0.0 * p.z();
  }
  if (!(bad == 0.0) || !std::isfinite(m2) || !c.allFinite()) return nan_sphere();
  return {c, std::sqrt(m2)};
}

/// Ritter's growth step (Ritter 1990, pass 2; also EPOS's last pass, Larsson 2008 Sec. 3):
/// a point outside the current sphere moves the center toward it so that the new sphere
/// touches it and still contains the old one.
void grow(Vec3& c, double& r, std::span<const Vec3> points) {
  double r2 = r * r;
  for (const Vec3& p : points) {
    const Vec3 d = p - c;
    const double d2 = d.squaredNorm();
    if (d2 > r2) {
      const double dist = std::sqrt(d2);
      const double r_new = 0.5 * (r + dist);
      c += ((r_new - r) / dist) * d;
      r = r_new;
      r2 = r * r;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// A small minimal-sphere solver for EPOS's extremal points (at most 26): Welzl's move-to-front
// recursion (Welzl 1991; Gaertner 1999, "Fast and robust smallest enclosing balls") in double, on
// coordinates translated to one of the points and scaled by a power of two to unit extent.
// Degenerate supports (collinear triples, coplanar quadruples) fall back to the smallest sphere
// of a subset; a slightly non-minimal sphere only costs tightness, never containment, because
// EPOS grows the result over all points and finish() sets the final radius.

struct Ball {
  Vec3 c = Vec3::Zero();
  double r2 = -1.0;
  [[nodiscard]] bool outside(const Vec3& p) const { return (p - c).squaredNorm() > r2 * (1.0 + 1e-12) + 1e-30; }
};

Ball ball_over(const Vec3& a, const Vec3& b) { return {0.5 * (a + b), 0.25 * (b - a).squaredNorm()}; }

double max_dist2(const Vec3& c, const Vec3* s, int k) {
  double m = 0.0;
  for (int i = 0; i < k; ++i) m = std::max(m, (s[i] - c).squaredNorm());
  return m;
}

/// Smallest sphere of three points (the triangle closed form on unit-scale data).
Ball ball3_min(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Sphere s = triangle_min_sphere(a, b, c);
  return {s.center, s.radius * s.radius};
}

/// The smallest sphere with the k <= 4 support points on its boundary (center in their affine
/// hull), or a fallback for degenerate supports.
Ball ball_of_support(const Vec3* s, int k) {
  switch (k) {
    case 0: return {};
    case 1: return {s[0], 0.0};
    case 2: return ball_over(s[0], s[1]);
    case 3: {
      const Vec3 u = s[1] - s[0], v = s[2] - s[0];
      const Vec3 n = u.cross(v);
      const double n2 = n.squaredNorm();
      if (!(n2 > 1e-20 * u.squaredNorm() * v.squaredNorm())) return ball3_min(s[0], s[1], s[2]);
      const Vec3 c = s[0] + (u.squaredNorm() * v - v.squaredNorm() * u).cross(n) / (2.0 * n2);
      return {c, max_dist2(c, s, 3)};
    }
    default: {
      const Vec3 u = s[1] - s[0], v = s[2] - s[0], w = s[3] - s[0];
      const Vec3 vw = v.cross(w), wu = w.cross(u), uv = u.cross(v);
      const double det = u.dot(vw);
      if (!(std::abs(det) > 1e-10 * u.norm() * v.norm() * w.norm())) {
        // Coplanar: the smallest of the triangle spheres that contains the fourth point.
        Ball best;
        best.r2 = std::numeric_limits<double>::infinity();
        constexpr int kSkip[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
        for (int skip = 0; skip < 4; ++skip) {
          const auto& t = kSkip[skip];
          Ball b = ball3_min(s[t[0]], s[t[1]], s[t[2]]);
          b.r2 = max_dist2(b.c, s, 4);
          if (b.r2 < best.r2) best = b;
        }
        return best;
      }
      const Vec3 c = s[0] + (u.squaredNorm() * vw + v.squaredNorm() * wu + w.squaredNorm() * uv) / (2.0 * det);
      return {c, max_dist2(c, s, 4)};
    }
  }
}

/// Welzl with move-to-front on pts[0, end): the minimal ball of those points with the k points
/// of `support` on the boundary.
Ball mtf_ball(Vec3* pts, int end, Vec3* support, int k) {
  Ball ball = ball_of_support(support, k);
  if (k == 4) return ball;
  for (int i = 0; i < end; ++i) {
    if (ball.outside(pts[i])) {
      support[k] = pts[i];
      ball = mtf_ball(pts, i, support, k + 1);
      std::rotate(pts, pts + i, pts + i + 1);  // move to front
    }
  }
  return ball;
}

/// Minimal sphere (up to rounding) of at most a few dozen points; the radius is not yet the
/// containment radius (EPOS calls finish() on the full set).
Sphere small_min_sphere(Vec3* pts, int n) {
  if (n == 0) return Sphere::empty();
  const Vec3 origin = pts[0];
  double extent = 0.0;
  for (int i = 0; i < n; ++i) extent = std::max(extent, (pts[i] - origin).cwiseAbs().maxCoeff());
  if (!(extent > 0.0) || !std::isfinite(extent)) return {origin, 0.0};
  int e = 0;
  (void)std::frexp(extent, &e);  // extent = f * 2^e, f in [0.5, 1)
  const double down = std::ldexp(1.0, -e), up = std::ldexp(1.0, e);
  for (int i = 0; i < n; ++i) pts[i] = (pts[i] - origin) * down;
  Vec3 support[4];
  const Ball b = mtf_ball(pts, n, support, 0);
  return {origin + b.c * up, std::sqrt(std::max(b.r2, 0.0)) * up};
}

// EPOS direction sets (Larsson 2008, Table 1): the 3 axes, then the 4 cube diagonals, then the
// 6 edge directions of the cube, unnormalised (only the order of projections matters), so every
// projection is a sum or difference of coordinates. Directions 0..S-1 are used for EPOS-2S.
inline void epos_projections(const Vec3& p, double* d) {
  const double x = p.x(), y = p.y(), z = p.z(), xpy = x + y, xmy = x - y;
  d[0] = x, d[1] = y, d[2] = z;                                               // EPOS-6
  d[3] = xpy + z, d[4] = xpy - z, d[5] = xmy + z, d[6] = xmy - z;             // EPOS-14
  d[7] = xpy, d[8] = xmy, d[9] = x + z, d[10] = x - z, d[11] = y + z, d[12] = y - z;  // EPOS-26
}

template <int S>
Sphere epos_impl(std::span<const Vec3> points) {
  constexpr int kMaxSmall = 2 * S;
  Vec3 pts[kMaxSmall];
  int m = 0;
  if (points.size() <= static_cast<std::size_t>(kMaxSmall)) {
    // Larsson's small-input rule: the exact (here: double) minimal sphere of all points.
    for (const Vec3& p : points) pts[m++] = p;
  } else {
    // Extremal points along the S directions in two branch-light passes: the extreme values
    // (min/max), then the first point attaining each one (the projections are recomputed by the
    // same code, so equality is exact). On armadillo patches this was ~35% faster for EPOS-6
    // than one pass tracking indices with branches (index updates mispredict) and on par for
    // EPOS-26, where 4S running values no longer fit in registers either way.
    alignas(16) double d[14], lo[14], hi[14];
    d[13] = 0.0;
    epos_projections(points[0], d);
    for (int j = 0; j < 14; ++j) lo[j] = hi[j] = d[j];
    for (const Vec3& p : points) {
      epos_projections(p, d);
      for (int j = 0; j < S; ++j) {
        lo[j] = d[j] < lo[j] ? d[j] : lo[j];
        hi[j] = d[j] > hi[j] ? d[j] : hi[j];
      }
    }
    std::size_t ilo[S], ihi[S];
    int missing = 2 * S;
    for (int j = 0; j < S; ++j) ilo[j] = ihi[j] = points.size();
    for (std::size_t i = 0; i < points.size() && missing > 0; ++i) {
      epos_projections(points[i], d);
      bool hit = false;
      for (int j = 0; j < S; ++j) hit |= (d[j] == lo[j]) | (d[j] == hi[j]);
      if (!hit) continue;
      for (int j = 0; j < S; ++j) {
        if (d[j] == lo[j] && ilo[j] == points.size()) ilo[j] = i, --missing;
        if (d[j] == hi[j] && ihi[j] == points.size()) ihi[j] = i, --missing;
      }
    }
    // Distinct extremal points only (a point is often extreme along several directions).
    std::size_t ids[kMaxSmall];
    for (int j = 0; j < S; ++j) ids[2 * j] = ilo[j], ids[2 * j + 1] = ihi[j];
    std::sort(ids, ids + kMaxSmall);
    for (int k = 0; k < kMaxSmall; ++k)
      if ((k == 0 || ids[k] != ids[k - 1]) && ids[k] < points.size()) pts[m++] = points[ids[k]];
  }
  Sphere s = small_min_sphere(pts, m);
  grow(s.center, s.radius, points);
  return finish(s.center, points);
}

}  // namespace

double Sphere::surface_area() const { return is_empty() ? 0.0 : 4.0 * std::numbers::pi * radius * radius; }
double Sphere::great_circle_area() const { return is_empty() ? 0.0 : std::numbers::pi * radius * radius; }

bool contains_all(const Sphere& s, std::span<const Vec3> points, double rel_tol) {
  if (std::isnan(s.radius)) return false;
  if (points.empty()) return true;
  if (s.is_empty()) return false;
  double limit = s.radius * (1.0 + rel_tol);
  if (s.radius == 0.0) {
    double m = s.center.cwiseAbs().maxCoeff();
    for (const Vec3& p : points) m = std::max(m, p.cwiseAbs().maxCoeff());
    limit = m > 0.0 ? rel_tol * m : 0.0;  // (every point at the origin: on the centre, exactly; not inf x 0)
  }
  for (const Vec3& p : points) {
    if (!((p - s.center).norm() <= limit)) return false;
  }
  return true;
}

double exact_containment_tol(const Sphere& exact, std::span<const Vec3> points) {
  if (!(exact.radius > 0.0)) return std::numeric_limits<double>::infinity();
  double m = exact.center.cwiseAbs().maxCoeff();
  for (const Vec3& p : points) m = std::max(m, p.cwiseAbs().maxCoeff());
  return kSphereContainmentTol + 4.0 * DBL_EPSILON * m / exact.radius;
}

std::string_view to_string(SphereMethod m) {
  switch (m) {
    case SphereMethod::Exact: return "exact";
    case SphereMethod::Cgal: return "cgal";
    case SphereMethod::Ritter: return "ritter";
    case SphereMethod::Epos6: return "epos6";
    case SphereMethod::Epos14: return "epos14";
    case SphereMethod::Epos26: return "epos26";
  }
  return "unknown";
}

std::optional<SphereMethod> parse_sphere_method(std::string_view s) {
  for (SphereMethod m : kAllSphereMethods) {
    if (to_string(m) == s) return m;
  }
  return std::nullopt;
}

Sphere bounding_sphere(SphereMethod m, std::span<const Vec3> points) {
  switch (m) {
    case SphereMethod::Exact: return min_sphere_exact(points);
    case SphereMethod::Cgal: return min_sphere(points);
    case SphereMethod::Ritter: return ritter_sphere(points);
    case SphereMethod::Epos6: return epos_sphere(points, 3);
    case SphereMethod::Epos14: return epos_sphere(points, 7);
    case SphereMethod::Epos26: return epos_sphere(points, 13);
  }
  throw std::invalid_argument("bounding_sphere: unknown method");
}

Sphere ritter_sphere(std::span<const Vec3> points) {
  if (points.empty()) return Sphere::empty();
  // Pass 1 (Ritter 1990): the points of smallest and largest x, y and z; the farthest of the
  // three pairs spans the initial sphere.
  std::size_t lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (std::size_t i = 1; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (points[i][k] < points[lo[k]][k]) lo[k] = i;
      if (points[i][k] > points[hi[k]][k]) hi[k] = i;
    }
  }
  int best = 0;
  double best_d2 = -1.0;
  for (int k = 0; k < 3; ++k) {
    const double d2 = (points[hi[k]] - points[lo[k]]).squaredNorm();
    if (d2 > best_d2) best_d2 = d2, best = k;
  }
  const Vec3& a = points[lo[best]];
  const Vec3& b = points[hi[best]];
  Vec3 c = 0.5 * a + 0.5 * b;
  double r = 0.5 * (b - a).norm();
  // Pass 2: growth; then the containment pass.
  grow(c, r, points);
  return finish(c, points);
}

Sphere epos_sphere(std::span<const Vec3> points, int directions) {
  switch (directions) {
    case 3: return points.empty() ? Sphere::empty() : epos_impl<3>(points);
    case 7: return points.empty() ? Sphere::empty() : epos_impl<7>(points);
    case 13: return points.empty() ? Sphere::empty() : epos_impl<13>(points);
    default: throw std::invalid_argument("epos_sphere: directions must be 3, 7 or 13, got " + std::to_string(directions));
  }
}

PTC_ISA_CLONES
Sphere triangle_min_sphere(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 corners[3] = {a, b, c};
  if (!a.allFinite() || !b.allFinite() || !c.allFinite()) return nan_sphere();
  // Edge i is opposite corner i (e[i] runs between the two corners other than i); len2[i] its
  // squared length. The products below are of fifth degree in the edges, so unscaled they under-
  // or overflow for triangles smaller than ~1e-62 or larger than ~1e61: outside squared lengths of
  // 2^-240 .. 2^240 the edges are scaled by the power of two 2^-k that brings their longest
  // coordinate to [1, 2). Scaling by a power of two is exact and every operation here commutes
  // with it, so the bits are those of the unscaled formulas wherever those neither under- nor
  // overflow (k = 0 in range: the common case costs two comparisons).
  Vec3 e[3] = {c - b, a - c, b - a};
  double len2[3] = {e[0].squaredNorm(), e[1].squaredNorm(), e[2].squaredNorm()};
  int k = 0;
  if (const double l2 = std::max({len2[0], len2[1], len2[2]}); !(l2 >= 0x1p-240 && l2 <= 0x1p+240)) {
    const double extent = std::max({e[0].cwiseAbs().maxCoeff(), e[1].cwiseAbs().maxCoeff(), e[2].cwiseAbs().maxCoeff()});
    if (extent > 0.0 && std::isfinite(extent)) {
      k = exponent_of(extent);
      for (int i = 0; i < 3; ++i) {
        e[i] = times_pow2(e[i], -k);
        len2[i] = e[i].squaredNorm();
      }
    }
  }
  // The dot product of the two edges at corner i (> 0 iff the angle there is acute).
  const double dots[3] = {-e[2].dot(e[1]), -e[0].dot(e[2]), -e[1].dot(e[0])};
  int longest = 0;
  if (len2[1] > len2[longest]) longest = 1;
  if (len2[2] > len2[longest]) longest = 2;
  Vec3 center;
  if (dots[0] > 0.0 && dots[1] > 0.0 && dots[2] > 0.0) {
    // Acute: the circumcenter, relative to the corner of the largest angle (opposite the
    // longest edge, >= 60 degrees), so the cross product of the two shorter edges is well
    // conditioned: center = o + ((|u|^2 v - |v|^2 u) x n) / (2 |n|^2), n = u x v, with
    // u = corner(l+1) - o and v = corner(l+2) - o the scaled edges (e[l+2] and -e[l+1]).
    const Vec3& o = corners[longest];
    const Vec3 u = e[(longest + 2) % 3], v = -e[(longest + 1) % 3];
    const Vec3 n = u.cross(v);
    const double n2 = n.squaredNorm();
    if (n2 > 0.0) {
      const Vec3 off = (u.squaredNorm() * v - v.squaredNorm() * u).cross(n) / (2.0 * n2);
      center = o + (k == 0 ? off : times_pow2(off, k));
    } else {
      center = 0.5 * corners[(longest + 1) % 3] + 0.5 * corners[(longest + 2) % 3];
    }
  } else {
    // Right, obtuse or degenerate: the sphere over the longest edge (for collinear corners the
    // longest edge joins the two farthest ones; repeated corners give a 0 dot product).
    center = 0.5 * corners[(longest + 1) % 3] + 0.5 * corners[(longest + 2) % 3];
  }
  double m2 = 0.0;  // of the scaled distances
  for (const Vec3& p : corners) m2 = std::max(m2, (k == 0 ? Vec3(p - center) : times_pow2(p - center, -k)).squaredNorm());
  if (!std::isfinite(m2)) return nan_sphere();
  return {center, k == 0 ? std::sqrt(m2) : times_pow2(std::sqrt(m2), k)};
}

double average_triangle_sphere_area(std::span<const Vec3> positions, std::span<const Tri> triangles) {
  if (triangles.empty()) return 0.0;
  // Fixed chunks summed in parallel, then the chunks' sums in order: one value at any thread
  // count (and the one-pass sum for meshes of one chunk).
  constexpr std::size_t kChunk = kAvgSaChunk;
  const std::size_t chunks = (triangles.size() + kChunk - 1) / kChunk;
  std::vector<double> sums(chunks, 0.0);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    double s = 0.0;
    const std::size_t end = std::min(triangles.size(), (c + 1) * kChunk);
    for (std::size_t i = c * kChunk; i < end; ++i) {
      if (i + kCornerPrefetchAhead < end) prefetch_corners(positions.data(), triangles[i + kCornerPrefetchAhead]);
      const Tri& t = triangles[i];
      assert(t[0] < positions.size() && t[1] < positions.size() && t[2] < positions.size());
      s += triangle_sphere_area(positions[t[0]], positions[t[1]], positions[t[2]]);
    }
    sums[c] = s;
  });
  double sum = 0.0;
  for (const double s : sums) sum += s;
  return sum / static_cast<double>(triangles.size());
}

}  // namespace ptc
