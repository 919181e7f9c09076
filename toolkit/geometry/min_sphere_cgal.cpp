// The two CGAL paths of sphere.h: the working path (Min_sphere_of_spheres_d on double) and the
// exact oracle (the same algorithm on an exact rational type). This is the only translation unit
// of the sphere code that includes CGAL (its headers are expensive to compile).
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Gmpq.h>
#include <CGAL/Min_sphere_of_spheres_d.h>
#include <CGAL/Min_sphere_of_spheres_d_traits_3.h>
#include <CGAL/Simple_cartesian.h>
#include <gmp.h>
#include <mpfr.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "toolkit/geometry/sphere.h"
#include "toolkit/core/isa.h"

namespace ptc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------------
// Working path: CGAL's default farthest-first heuristic and Use_square_roots = Tag_false. On
// armadillo patches (~65 points) the LP algorithm was ~3x slower; Tag_true (sqrt per distance)
// was indistinguishable from Tag_false within the noise; reusing one object per thread (clear()
// keeps the vectors' capacity) saved ~20%.
using KD = CGAL::Simple_cartesian<double>;
using TraitsD = CGAL::Min_sphere_of_spheres_d_traits_3<KD, double, CGAL::Tag_false>;
using MinSphereD = CGAL::Min_sphere_of_spheres_d<TraitsD>;

// ---------------------------------------------------------------------------------------------
// Exact path: Epeck's FT (Lazy_exact_nt over GMP rationals). Measured on the same patches
// against plain CGAL::Gmpq and mpq_class, including the exact evaluation of the results:
// ~2.5x faster, because most of the algorithm's comparisons are decided by the interval filter.
// Use_square_roots = Tag_false: results come as a + b*sqrt(t).
using FTQ = CGAL::Exact_predicates_exact_constructions_kernel::FT;
using KQ = CGAL::Simple_cartesian<FTQ>;
using TraitsQ = CGAL::Min_sphere_of_spheres_d_traits_3<KQ, FTQ, CGAL::Tag_false>;
using MinSphereQ = CGAL::Min_sphere_of_spheres_d<TraitsQ>;

// The GMP rational behind an exact value (Epeck_ft is mpq_class or Gmpq, depending on CGAL's
// configuration).
[[maybe_unused]] mpq_srcptr mpq_of(const CGAL::Gmpq& q) { return q.mpq(); }
#ifdef CGAL_USE_GMPXX
[[maybe_unused]] mpq_srcptr mpq_of(const mpq_class& q) { return q.get_mpq_t(); }
#endif
template <class ET>
mpq_srcptr mpq_of(const CGAL::Lazy_exact_nt<ET>& x) {
  return mpq_of(CGAL::exact(x));
}

/// Correctly rounded (to nearest, ties to even) double of the rational q.
double round_rational(mpq_srcptr q) {
  mpfr_t x;
  mpfr_init2(x, 53);
  mpfr_set_q(x, q, MPFR_RNDN);
  const double d = mpfr_get_d(x, MPFR_RNDN);
  mpfr_clear(x);
  return d;
}

/// Correctly rounded double of a + b*sqrt(t) (t >= 0).
/// - b = 0, t = 0 or t a perfect square: the value is rational and rounded once.
/// - otherwise the value is irrational, hence never a rounding tie, and a Ziv loop terminates:
///   at precision p every operation below rounds to nearest (relative error <= 2^-p each) and no
///   subtraction of like-signed approximations occurs, because when a and b*sqrt(t) have
///   opposite signs we evaluate (a^2 - b^2 t) / (a - b sqrt(t)) with the numerator exact.
///   The total relative error is below 8 * 2^-p, i.e. below 2^(EXP(x) - p + 3) absolutely;
///   we claim p - 8 correct bits and let mpfr_can_round decide (the RNDZ/prec+1 form is MPFR's
///   documented test for round-to-nearest of a value known not to be representable).
double round_sqrt_form(mpq_srcptr a, mpq_srcptr b, mpq_srcptr t) {
  if (mpq_sgn(b) == 0 || mpq_sgn(t) <= 0) return round_rational(a);
  if (mpz_perfect_square_p(mpq_numref(t)) && mpz_perfect_square_p(mpq_denref(t))) {
    mpq_t s;
    mpq_init(s);
    mpz_sqrt(mpq_numref(s), mpq_numref(t));  // canonical t: the roots stay coprime
    mpz_sqrt(mpq_denref(s), mpq_denref(t));
    mpq_mul(s, s, b);
    mpq_add(s, s, a);
    const double d = round_rational(s);
    mpq_clear(s);
    return d;
  }
  const bool opposite = mpq_sgn(a) * mpq_sgn(b) < 0;
  mpq_t num;
  mpq_init(num);
  if (opposite) {  // a^2 - b^2 t, exact
    mpq_t tmp;
    mpq_init(tmp);
    mpq_mul(num, a, a);
    mpq_mul(tmp, b, b);
    mpq_mul(tmp, tmp, t);
    mpq_sub(num, num, tmp);
    mpq_clear(tmp);
  }
  double result = kNaN;
  for (mpfr_prec_t prec = 256; prec <= 65536; prec *= 2) {
    mpfr_t x, y;
    mpfr_init2(x, prec);
    mpfr_init2(y, prec);
    mpfr_set_q(x, t, MPFR_RNDN);
    mpfr_sqrt(x, x, MPFR_RNDN);
    mpfr_set_q(y, b, MPFR_RNDN);
    mpfr_mul(x, x, y, MPFR_RNDN);  // b sqrt(t)
    mpfr_set_q(y, a, MPFR_RNDN);
    if (!opposite) {
      mpfr_add(x, y, x, MPFR_RNDN);
    } else {
      mpfr_sub(y, y, x, MPFR_RNDN);  // a - b sqrt(t): like-signed terms, no cancellation
      mpfr_set_q(x, num, MPFR_RNDN);
      mpfr_div(x, x, y, MPFR_RNDN);
    }
    const bool done = mpfr_zero_p(x) || mpfr_can_round(x, prec - 8, MPFR_RNDN, MPFR_RNDZ, 53 + 1);
    if (done) result = mpfr_get_d(x, MPFR_RNDN);
    mpfr_clear(x);
    mpfr_clear(y);
    if (done) break;
  }
  mpq_clear(num);
  return result;
}

bool all_finite(std::span<const Vec3> points) {
  for (const Vec3& p : points) {
    if (!p.allFinite()) return false;
  }
  return true;
}

}  // namespace

// Flattened: CGAL's solver is inlined, so that each instruction-set clone has its own copy.
[[gnu::flatten]] PTC_ISA_CLONES
Sphere min_sphere(std::span<const Vec3> points) {
  if (points.empty()) return Sphere::empty();
  Box3 box;
  for (const Vec3& p : points) box.extend(p);
  if (!all_finite(points)) return {Vec3::Constant(kNaN), kNaN};
  // Normalise: translate to the box center, scale by 2^-e so that |coordinates| <= 1. CGAL's
  // double path rejects support points by absolute thresholds (SqrOfEps = 1e-32 against squared
  // radii, Min_float = 1e-120), so at extents beyond ~1e70 or below ~1e-70 it silently returns
  // a wrong (zero) radius. Halves are taken before subtracting so that +-DBL_MAX does not
  // overflow; scaling by a power of two is exact.
  const Vec3 mid = 0.5 * box.lo + 0.5 * box.hi;
  const double half_extent = (0.5 * box.hi - 0.5 * box.lo).maxCoeff();
  if (!(half_extent > 0.0)) return {points[0], 0.0};  // all points coincide
  int e = 0;
  (void)std::frexp(half_extent, &e);  // half_extent = f * 2^e, f in [0.5, 1)
  const double down = std::ldexp(1.0, 1 - e);  // (p - mid) * 2^-e = (p/2 - mid/2) * 2^(1-e)

  thread_local MinSphereD ms;  // reused: clear() keeps the vectors' capacity
  ms.clear();
  for (const Vec3& p : points) {
    const Vec3 q = (0.5 * p - 0.5 * mid) * down;
    ms.insert(TraitsD::Sphere(KD::Point_3(q.x(), q.y(), q.z()), 0.0));
  }
  const double* c = ms.center_cartesian_begin();
  const double up = std::ldexp(1.0, e);
  const Vec3 center = mid + Vec3(c[0], c[1], c[2]) * up;
  // Containment: the radius is the largest center-point distance, computed as contains_all does.
  double m2 = 0.0;
  for (const Vec3& p : points) m2 = std::max(m2, (p - center).squaredNorm());
  return {center, std::sqrt(m2)};
}

Sphere min_sphere_exact(std::span<const Vec3> points) {
  if (points.empty()) return Sphere::empty();
  if (!all_finite(points)) return {Vec3::Constant(kNaN), kNaN};
  std::vector<TraitsQ::Sphere> balls;
  balls.reserve(points.size());
  for (const Vec3& p : points) balls.emplace_back(KQ::Point_3(p.x(), p.y(), p.z()), FTQ(0));
  MinSphereQ ms(balls.begin(), balls.end());
  // For points (radius-0 balls) CGAL returns a rational center (b = 0) and the radius as
  // 0 + b sqrt(t), but the rounding below handles the general form.
  const FTQ& t = ms.discriminant();
  const auto* c = ms.center_cartesian_begin();
  Sphere s;
  for (int j = 0; j < 3; ++j) s.center[j] = round_sqrt_form(mpq_of(c[j].first), mpq_of(c[j].second), mpq_of(t));
  s.radius = round_sqrt_form(mpq_of(ms.radius().first), mpq_of(ms.radius().second), mpq_of(t));
  return s;
}

double detail::round_sqrt_form(std::string_view a, std::string_view b, std::string_view t) {
  mpq_t q[3];
  const std::string_view text[3] = {a, b, t};
  bool ok = true;
  for (int i = 0; i < 3; ++i) {
    mpq_init(q[i]);
    ok = ok && mpq_set_str(q[i], std::string(text[i]).c_str(), 10) == 0 && mpz_sgn(mpq_denref(q[i])) != 0;
    if (ok) mpq_canonicalize(q[i]);
  }
  ok = ok && mpq_sgn(q[2]) >= 0;
  const double d = ok ? ptc::round_sqrt_form(q[0], q[1], q[2]) : 0.0;
  for (auto& x : q) mpq_clear(x);
  if (!ok) throw std::invalid_argument("round_sqrt_form: bad rational");
  return d;
}

}  // namespace ptc
