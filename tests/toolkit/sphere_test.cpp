// Bounding spheres against independent answers: closed forms (cube, icosahedron, circles, lines),
// CGAL's Min_sphere_d (Gaertner's algorithm, a different code path than Min_sphere_of_spheres_d)
// with an exact rational kernel, rounded by MPFR here, and the exact path for everything else.
// Hard cases first; every method on every case must contain its points.
#include "toolkit/geometry/sphere.h"

#include <gtest/gtest.h>

#include <CGAL/Gmpq.h>
#include <CGAL/Min_sphere_annulus_d_traits_3.h>
#include <CGAL/Min_sphere_d.h>
#include <CGAL/Simple_cartesian.h>
#include <mpfr.h>

#include <bit>
#include <cfloat>
#include <cstring>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace ptc {
namespace {

constexpr double kEps = DBL_EPSILON;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr SphereMethod kApprox[] = {SphereMethod::Ritter, SphereMethod::Epos6, SphereMethod::Epos14, SphereMethod::Epos26};

// ---------------------------------------------------------------------------------------------
// Independent oracle: CGAL Min_sphere_d (exact rationals) gives the center and the squared
// radius as rationals; round them here with MPFR (center coordinate and sqrt of the squared
// radius, both correctly rounded at 53 bits).
struct OracleSphere {
  Vec3 center;
  double radius;
};

double mpfr_round_q(mpq_srcptr q, bool take_sqrt) {
  mpfr_t x;
  mpfr_init2(x, 53);
  if (take_sqrt) {
    mpfr_t y;
    mpfr_init2(y, 2048);
    mpfr_set_q(y, q, MPFR_RNDN);  // 2048 bits: the double rounding below cannot matter here
    mpfr_sqrt(x, y, MPFR_RNDN);
    mpfr_clear(y);
  } else {
    mpfr_set_q(x, q, MPFR_RNDN);
  }
  const double d = mpfr_get_d(x, MPFR_RNDN);
  mpfr_clear(x);
  return d;
}

OracleSphere oracle(const std::vector<Vec3>& pts) {
  using K = CGAL::Simple_cartesian<CGAL::Gmpq>;
  using MS = CGAL::Min_sphere_d<CGAL::Min_sphere_annulus_d_traits_3<K>>;
  std::vector<K::Point_3> kp;
  for (const Vec3& p : pts) kp.emplace_back(p.x(), p.y(), p.z());
  MS ms(kp.begin(), kp.end());
  const K::Point_3 c = ms.center();
  return {Vec3(mpfr_round_q(c.x().mpq(), false), mpfr_round_q(c.y().mpq(), false), mpfr_round_q(c.z().mpq(), false)),
          mpfr_round_q(ms.squared_radius().mpq(), true)};
}

double rel_err(double r, double ref) { return ref == 0.0 ? std::abs(r) : (r - ref) / ref; }

double max_abs_coord(const std::vector<Vec3>& pts) {
  double m = 0.0;
  for (const Vec3& p : pts) m = std::max(m, p.cwiseAbs().maxCoeff());
  return m;
}

/// The part of the radius error that a double center cannot avoid: its rounding moves it by up
/// to sqrt(3)/2 ulp of the coordinates, which is all of the error when features are tiny
/// against the offset (offset 1e7, features 1e-3: ~1e-6 relative).
double center_rounding_tol(const std::vector<Vec3>& pts, double r) {
  return r > 0.0 ? 2.0 * kEps * max_abs_coord(pts) / r : 0.0;
}

void expect_contains(SphereMethod m, const Sphere& s, const std::vector<Vec3>& pts, const std::string& what) {
  const double tol = m == SphereMethod::Exact ? exact_containment_tol(s, pts) : kSphereContainmentTol;
  EXPECT_TRUE(contains_all(s, pts, tol)) << what << " " << to_string(m) << " r=" << s.radius;
}

/// Every method on one point set: containment, the exact path against the oracle (bit for
/// bit), the working path minimal to 1e-12 (plus the center-rounding term), approximations
/// never below the minimal radius. Returns the exact sphere.
Sphere check_all_methods(const std::vector<Vec3>& pts, const std::string& what) {
  const Sphere ex = min_sphere_exact(pts);
  const OracleSphere orc = oracle(pts);
  EXPECT_EQ(ex.radius, orc.radius) << what;
  EXPECT_EQ(ex.center, orc.center) << what;
  const double tol = 1e-12 + center_rounding_tol(pts, ex.radius);
  for (SphereMethod m : kAllSphereMethods) {
    const Sphere s = bounding_sphere(m, pts);
    expect_contains(m, s, pts, what);
    const double err = rel_err(s.radius, ex.radius);
    EXPECT_GE(err, -1e-12) << what << " " << to_string(m);
    if (m == SphereMethod::Cgal) {
      EXPECT_LE(err, tol) << what;
      // The minimal sphere's squared radius is 2-strongly convex in the center, so a radius
      // within tol bounds the center error by r sqrt(2 tol); CGAL does far better.
      EXPECT_LE((s.center - ex.center).norm(), ex.radius * 1e-9 + 4.0 * kEps * max_abs_coord(pts)) << what;
    } else if (m != SphereMethod::Exact) {
      EXPECT_LE(err, 1.0) << what << " " << to_string(m);  // crude sanity: never twice the minimum
    }
  }
  return ex;
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  for (;;) {
    const Vec3 v(g(rng), g(rng), g(rng));
    if (v.norm() > 1e-3) return v.normalized();
  }
}

// ---------------------------------------------------------------------------------------------
// Degenerate inputs first.

TEST(SphereDegenerate, EmptyInputGivesEmptySphereForEveryMethod) {
  const std::vector<Vec3> none;
  for (SphereMethod m : kAllSphereMethods) {
    const Sphere s = bounding_sphere(m, none);
    EXPECT_TRUE(s.is_empty()) << to_string(m);
    EXPECT_EQ(s.radius, -1.0);
    EXPECT_EQ(s.surface_area(), 0.0);
    EXPECT_EQ(s.great_circle_area(), 0.0);
    EXPECT_TRUE(contains_all(s, none));
  }
  EXPECT_FALSE(contains_all(Sphere::empty(), std::vector<Vec3>{Vec3::Zero()}));
}

TEST(SphereDegenerate, NonFiniteInputGivesNanRadiusForEveryMethod) {
  for (double bad : {kNaN, kInf, -kInf}) {
    for (std::size_t n : {1u, 2u, 5u, 40u, 120u}) {
      for (std::size_t where : {std::size_t{0}, n / 2, n - 1}) {
        std::vector<Vec3> pts;
        for (std::size_t i = 0; i < n; ++i) pts.emplace_back(double(i), double(i * i % 7), 1.0);
        pts[where][where % 3] = bad;
        for (SphereMethod m : kAllSphereMethods) {
          const Sphere s = bounding_sphere(m, pts);
          EXPECT_TRUE(std::isnan(s.radius)) << to_string(m) << " n=" << n << " bad=" << bad;
          EXPECT_FALSE(contains_all(s, pts));
        }
      }
    }
  }
  EXPECT_TRUE(std::isnan(triangle_min_sphere(Vec3(kNaN, 0, 0), Vec3::Zero(), Vec3::UnitX()).radius));
  EXPECT_TRUE(std::isnan(triangle_min_sphere(Vec3::Zero(), Vec3(0, kInf, 0), Vec3::UnitX()).radius));
}

TEST(SphereDegenerate, SinglePointAndDuplicatesGiveRadiusZero) {
  const Vec3 p(1.5, -2.25, 1e7 + 0.125);
  for (std::size_t n : {1u, 2u, 7u, 100u}) {
    const std::vector<Vec3> pts(n, p);
    for (SphereMethod m : kAllSphereMethods) {
      const Sphere s = bounding_sphere(m, pts);
      EXPECT_EQ(s.radius, 0.0) << to_string(m) << " n=" << n;
      EXPECT_EQ(s.center, p) << to_string(m);
      EXPECT_TRUE(contains_all(s, pts));
    }
  }
  EXPECT_FALSE(contains_all(Sphere{p, 0.0}, std::vector<Vec3>{p + Vec3(0, 0, 1e-3)}));
}

TEST(SphereDegenerate, TwoPointsGiveHalfTheirDistance) {
  // Exact values: radius 2.5 and sqrt(3)/2 (= sqrt(0.75), correctly rounded by std::sqrt).
  const std::vector<Vec3> a{Vec3(0, 0, 0), Vec3(3, 4, 0)};
  const std::vector<Vec3> b{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  EXPECT_EQ(min_sphere_exact(a).radius, 2.5);
  EXPECT_EQ(min_sphere_exact(a).center, Vec3(1.5, 2, 0));
  EXPECT_EQ(min_sphere_exact(b).radius, std::sqrt(0.75));
  for (const auto& pts : {a, b}) {
    const Sphere ex = check_all_methods(pts, "two points");
    for (SphereMethod m : kAllSphereMethods)  // two points: every method is exact here
      EXPECT_NEAR(bounding_sphere(m, pts).radius, ex.radius, 2 * kEps * ex.radius) << to_string(m);
  }
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-100, 100);
  for (int i = 0; i < 200; ++i) {
    const std::vector<Vec3> pts{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng))};
    check_all_methods(pts, "random pair");
  }
}

TEST(SphereDegenerate, CollinearSetsGiveTheSegmentSphere) {
  std::mt19937_64 rng(12);
  std::uniform_int_distribution<int> di(-9, 9), ti(-50, 50);
  for (int trial = 0; trial < 60; ++trial) {
    // Integer direction and parameters: exactly collinear, extreme points known exactly.
    const Vec3 o(di(rng), di(rng), di(rng));
    Vec3 d(di(rng), di(rng), di(rng));
    if (d.isZero()) d = Vec3(1, 2, 3);
    std::vector<Vec3> pts;
    int tmin = 1000, tmax = -1000;
    for (int i = 0; i < 3 + trial; ++i) {
      const int t = ti(rng);
      tmin = std::min(tmin, t), tmax = std::max(tmax, t);
      pts.push_back(o + t * d);
    }
    const Sphere ex = check_all_methods(pts, "collinear");
    EXPECT_NEAR(ex.radius, 0.5 * (tmax - tmin) * d.norm(), 4 * kEps * ex.radius);
  }
}

TEST(SphereDegenerate, CoplanarCircleGivesTheCircle) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> ang(0, 2 * std::numbers::pi);
  for (int trial = 0; trial < 40; ++trial) {
    const Vec3 n = random_unit(rng);
    const Vec3 e1 = n.unitOrthogonal(), e2 = n.cross(e1);
    const Vec3 c(3.0 * trial, -1.0, 0.5);
    const double R = 0.5 + trial;
    std::vector<Vec3> pts;
    // Angles spread around the full circle (one per sector), so the circle is minimal.
    for (int k = 0; k < 6 + trial; ++k) {
      const double a = (k + 0.9 * ang(rng) / (2 * std::numbers::pi)) * 2 * std::numbers::pi / (6 + trial);
      pts.push_back(c + R * (std::cos(a) * e1 + std::sin(a) * e2));
    }
    const Sphere ex = check_all_methods(pts, "circle");
    EXPECT_NEAR(ex.radius, R, 1e-14 * R);
    EXPECT_LE((ex.center - c).norm(), 1e-13 * R);
  }
}

// ---------------------------------------------------------------------------------------------
// Cospherical points: the minimal sphere is known in closed form.

TEST(SphereCospherical, CubeCornersGiveHalfTheDiagonal) {
  const Vec3 c(1, 2, 3);
  std::vector<Vec3> pts;
  for (int i = 0; i < 8; ++i) pts.push_back(c + Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
  const Sphere ex = check_all_methods(pts, "cube");
  EXPECT_EQ(ex.radius, std::sqrt(3.0));  // exact value sqrt(3), correctly rounded
  EXPECT_EQ(ex.center, c);
  // EPOS-14/26 solve sets of at most 14/26 points directly; Ritter and EPOS-6 meet ties of the
  // axis extremes here (each extreme is a face of 4 corners) and need not be minimal.
  for (SphereMethod m : {SphereMethod::Cgal, SphereMethod::Epos14, SphereMethod::Epos26})
    EXPECT_NEAR(bounding_sphere(m, pts).radius, std::sqrt(3.0), 4 * kEps) << to_string(m);
}

TEST(SphereCospherical, IcosahedronGivesItsCircumradius) {
  // Vertices (0, +-1, +-phi) and cyclic permutations: edge 2, circumradius sqrt(10 + 2 sqrt 5) / 2
  // = sqrt(1 + phi^2). phi is rounded, but the 12 rounded points are still exactly cospherical
  // (center 0, squared radius 1 + phi_d^2), so the exact radius is that value rounded once.
  const double phi = std::numbers::phi;
  std::vector<Vec3> pts;
  for (double s1 : {-1.0, 1.0})
    for (double s2 : {-phi, phi}) {
      pts.emplace_back(0, s1, s2);
      pts.emplace_back(s1, s2, 0);
      pts.emplace_back(s2, 0, s1);
    }
  const Sphere ex = check_all_methods(pts, "icosahedron");
  mpfr_t x;
  mpfr_init2(x, 300);
  mpfr_set_d(x, phi, MPFR_RNDN);
  mpfr_sqr(x, x, MPFR_RNDN);
  mpfr_add_ui(x, x, 1, MPFR_RNDN);
  mpfr_sqrt(x, x, MPFR_RNDN);
  const double expected = mpfr_get_d(x, MPFR_RNDN);
  mpfr_clear(x);
  EXPECT_EQ(ex.radius, expected);
  EXPECT_NEAR(ex.radius, std::sqrt(10 + 2 * std::sqrt(5.0)) / 2, 2 * kEps * ex.radius);
  EXPECT_EQ(ex.center, Vec3::Zero());
  for (SphereMethod m : {SphereMethod::Cgal, SphereMethod::Epos14, SphereMethod::Epos26})  // at most 14 points
    EXPECT_NEAR(bounding_sphere(m, pts).radius, expected, 8 * kEps * expected) << to_string(m);
}

TEST(SphereCospherical, RandomPointsOnAKnownSphere) {
  std::mt19937_64 rng(14);
  for (int trial = 0; trial < 30; ++trial) {
    const Vec3 c(trial - 7.5, 0.25 * trial, -3.0);
    const double R = 0.1 + 0.7 * trial;
    std::vector<Vec3> pts;
    for (int k = 0; k < 60; ++k) pts.push_back(c + R * random_unit(rng));  // not in a hemisphere (p ~ 1e-15)
    const Sphere ex = check_all_methods(pts, "on sphere");
    EXPECT_NEAR(ex.radius, R, 8 * kEps * (R + c.norm()));
    EXPECT_LE((ex.center - c).norm(), 1e-12 * (R + c.norm()));
  }
}

// ---------------------------------------------------------------------------------------------
// Scale and offset: the working path normalises, so it stays minimal where raw CGAL double
// silently fails (beyond ~1e70, below ~1e-70).

std::vector<Vec3> random_cloud(std::mt19937_64& rng, std::size_t n, double scale, const Vec3& offset) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> pts;
  for (std::size_t i = 0; i < n; ++i) pts.push_back(offset + scale * Vec3(u(rng), 0.6 * u(rng), 0.3 * u(rng)));
  return pts;
}

TEST(SphereScale, TinyAndHugeCoordinatesStayMinimal) {
  std::mt19937_64 rng(15);
  for (double scale : {1e-100, 1e-75, 1e-30, 1e30, 1e75, 1e100}) {
    for (int trial = 0; trial < 10; ++trial) {
      const auto pts = random_cloud(rng, 20 + 9 * trial, scale, Vec3(scale, 0, -0.5 * scale));
      const Sphere ex = check_all_methods(pts, "scale " + std::to_string(scale));
      EXPECT_GT(ex.radius, 0.3 * scale);
      EXPECT_LE(std::abs(rel_err(min_sphere(pts).radius, ex.radius)), 1e-12);
    }
  }
}

TEST(SphereScale, LargeOffsetWithTinyFeatures) {
  std::mt19937_64 rng(16);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 offset(1e7, -1e7 + 3.0 * trial, 5e6);
    const auto pts = random_cloud(rng, 30 + 5 * trial, 1e-3, offset);
    const Sphere ex = check_all_methods(pts, "offset");
    const Sphere w = min_sphere(pts);
    // A double center is off by up to ~1e-9 here (ulp(1e7) = 1.9e-9), i.e. ~1e-6 of the radius.
    EXPECT_LE(rel_err(w.radius, ex.radius), 1e-12 + center_rounding_tol(pts, ex.radius));
    EXPECT_LE(center_rounding_tol(pts, ex.radius), 1e-5);
  }
}

// ---------------------------------------------------------------------------------------------
// Random clouds: working path against exact, approximations against the minimal radius.

TEST(SphereRandom, WorkingPathMatchesExactAndApproximationsAreTight) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> g;
  double epos26_max = 0, epos26_sum = 0, ritter_max = 0;
  int count = 0;
  for (int trial = 0; trial < 150; ++trial) {
    const std::size_t n = 5 + trial;
    std::vector<Vec3> pts;
    for (std::size_t i = 0; i < n; ++i) {
      switch (trial % 3) {
        case 0: pts.emplace_back(u(rng), u(rng), u(rng)); break;                 // box
        case 1: pts.emplace_back(g(rng), 0.5 * g(rng), 0.1 * g(rng)); break;     // flat gaussian
        default: pts.push_back(Vec3(3, 1, 0.5).cwiseProduct(random_unit(rng))); // ellipsoid shell
      }
    }
    const Sphere ex = check_all_methods(pts, "random " + std::to_string(trial));
    const double e26 = rel_err(epos_sphere(pts, 13).radius, ex.radius);
    epos26_max = std::max(epos26_max, e26);
    epos26_sum += e26;
    ritter_max = std::max(ritter_max, rel_err(ritter_sphere(pts).radius, ex.radius));
    ++count;
  }
  // Measured here: EPOS-26 mean ~1e-5, max 0.4%; Ritter max ~22% (Larsson 2008 reports
  // EPOS-26 within ~1% of minimal, Ritter 5-20% above).
  EXPECT_LE(epos26_sum / count, 0.005);
  EXPECT_LE(epos26_max, 0.02);
  EXPECT_LE(ritter_max, 0.35);
}

TEST(SphereRandom, ThreadsGiveTheSerialResults) {
  // min_sphere reuses one CGAL object per thread; the exact path uses lazy exact numbers.
  std::mt19937_64 rng(21);
  std::vector<std::vector<Vec3>> sets;
  for (int i = 0; i < 40; ++i) sets.push_back(random_cloud(rng, 10 + i, 1.0 + i, Vec3(i, -i, 2 * i)));
  std::vector<Sphere> serial_w, serial_e;
  for (const auto& pts : sets) serial_w.push_back(min_sphere(pts)), serial_e.push_back(min_sphere_exact(pts));
  std::vector<std::vector<Sphere>> w(4), e(4);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (int rep = 0; rep < 3; ++rep) {
        w[t].clear(), e[t].clear();
        for (std::size_t i = 0; i < sets.size(); ++i) {
          const auto& pts = sets[(i + t) % sets.size()];
          w[t].push_back(min_sphere(pts)), e[t].push_back(min_sphere_exact(pts));
        }
      }
    });
  for (auto& th : threads) th.join();
  for (int t = 0; t < 4; ++t)
    for (std::size_t i = 0; i < sets.size(); ++i) {
      const std::size_t k = (i + t) % sets.size();
      EXPECT_EQ(w[t][i].radius, serial_w[k].radius);
      EXPECT_EQ(w[t][i].center, serial_w[k].center);
      EXPECT_EQ(e[t][i].radius, serial_e[k].radius);
      EXPECT_EQ(e[t][i].center, serial_e[k].center);
    }
}

TEST(SphereRandom, FuzzSmallIntegerGridSets) {
  // Small grids are full of degeneracies: repeated, collinear, coplanar and cospherical points.
  std::mt19937_64 rng(18);
  std::uniform_int_distribution<int> c(-2, 2);
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<Vec3> pts;
    const int n = 1 + trial % 40;
    for (int i = 0; i < n; ++i) pts.emplace_back(c(rng), c(rng), trial % 4 == 0 ? 0 : c(rng));
    check_all_methods(pts, "grid " + std::to_string(trial));
  }
}

// ---------------------------------------------------------------------------------------------
// Triangles.

void check_triangle(const Vec3& a, const Vec3& b, const Vec3& c, const std::string& what) {
  const std::vector<Vec3> pts{a, b, c};
  const Sphere t = triangle_min_sphere(a, b, c);
  const OracleSphere orc = oracle(pts);
  const double tol = 1e-12 + center_rounding_tol(pts, orc.radius);
  EXPECT_TRUE(contains_all(t, pts)) << what;
  EXPECT_LE(std::abs(rel_err(t.radius, orc.radius)), tol) << what << " r=" << t.radius << " exact=" << orc.radius;
  EXPECT_LE((t.center - orc.center).norm(), tol * orc.radius + 4 * kEps * max_abs_coord(pts)) << what;
}

TEST(SphereTriangle, EquilateralGivesSideOverSqrt3) {
  // (1,0,0), (0,1,0), (0,0,1): exactly equilateral, side sqrt 2, center (1/3, 1/3, 1/3).
  const Sphere s = triangle_min_sphere(Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ());
  EXPECT_NEAR(s.radius, std::sqrt(2.0) / std::sqrt(3.0), 2 * kEps);
  EXPECT_NEAR((s.center - Vec3::Constant(1.0 / 3.0)).norm(), 0.0, 2 * kEps);
  std::mt19937_64 rng(19);
  for (int trial = 0; trial < 50; ++trial) {
    const double side = std::ldexp(1.0, trial - 25);
    const Vec3 e1 = random_unit(rng), e2 = e1.cross(random_unit(rng)).normalized();
    const Vec3 a = Vec3(1, 2, 3) * side;
    const Vec3 b = a + side * e1, c = a + side * (0.5 * e1 + std::sqrt(0.75) * e2);
    EXPECT_NEAR(triangle_min_sphere(a, b, c).radius, side / std::sqrt(3.0), 1e-14 * side);
    check_triangle(a, b, c, "equilateral");
  }
}

// Scaled by 2^k, the sphere scales by 2^k bit for bit, from 2^-900 to 2^900: the closed form's
// fifth-degree products neither under- nor overflow (unscaled, the circumcenter of a triangle of
// 1e-65 was off and its radius too large). Acute, right, obtuse, thin and degenerate shapes,
// at the origin and moved off it by a multiple of their size.
TEST(SphereTriangle, ScaledByAPowerOfTwoBitForBit) {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  int acute = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Vec3 p[3];
    for (Vec3& q : p) q = Vec3(u(rng), u(rng), u(rng));
    if (trial % 5 == 1) p[2] = 0.5 * (p[0] + p[1]);                    // collinear
    if (trial % 5 == 2) p[2] = p[0];                                   // repeated corner
    if (trial % 5 == 3) p[2] = p[0] + 1e-6 * (p[1] - p[0]).cross(Vec3(u(rng), u(rng), u(rng)));  // thin
    const Vec3 shift = trial % 2 == 0 ? Vec3::Zero() : Vec3(3, -5, 7);
    const Sphere ref = triangle_min_sphere(p[0] + shift, p[1] + shift, p[2] + shift);
    ASSERT_TRUE(std::isfinite(ref.radius));
    acute += (p[1] - p[0]).dot(p[2] - p[0]) > 0 && (p[0] - p[1]).dot(p[2] - p[1]) > 0 && (p[0] - p[2]).dot(p[1] - p[2]) > 0;
    for (int k = -900; k <= 900; k += 25) {
      auto scale = [k](const Vec3& v) { return Vec3(std::ldexp(v.x(), k), std::ldexp(v.y(), k), std::ldexp(v.z(), k)); };
      const Sphere s = triangle_min_sphere(scale(p[0] + shift), scale(p[1] + shift), scale(p[2] + shift));
      const std::string what = "trial " + std::to_string(trial) + ", 2^" + std::to_string(k);
      ASSERT_EQ(bits(s.radius), bits(std::ldexp(ref.radius, k))) << what;
      for (int d = 0; d < 3; ++d) ASSERT_EQ(bits(s.center[d]), bits(std::ldexp(ref.center[d], k))) << what;
    }
  }
  EXPECT_GT(acute, 50);  // the circumcenter branch ran
}

TEST(SphereTriangle, RandomTrianglesOfEveryShapeMatchExact) {
  std::mt19937_64 rng(20);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int> ii(-20, 20);
  auto rv = [&] { return Vec3(u(rng), u(rng), u(rng)); };
  auto iv = [&] { return Vec3(ii(rng), ii(rng), ii(rng)); };
  int acute = 0, obtuse = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 a = rv(), b = rv(), c = rv();
    const double da = (b - a).dot(c - a), db = (a - b).dot(c - b), dc = (a - c).dot(b - c);
    (da > 0 && db > 0 && dc > 0 ? acute : obtuse)++;
    check_triangle(a, b, c, "random");
  }
  EXPECT_GT(acute, 100);
  EXPECT_GT(obtuse, 100);
  for (int trial = 0; trial < 300; ++trial) {
    // Exactly right angles: integer legs u and v = u x w are exactly orthogonal.
    const Vec3 o = iv(), uu = iv(), v = uu.cross(iv());
    if (uu.isZero() || v.isZero()) continue;
    check_triangle(o, o + uu, o + v, "right");
    check_triangle(o + uu, o + v, o, "right rotated");
    // Exactly collinear and repeated corners.
    check_triangle(o, o + 3 * uu, o - 2 * uu, "collinear");
    check_triangle(o, o + uu, o + uu, "repeated");
    check_triangle(o, o, o, "single");
    // Slivers: a corner 1e-9 off the middle of the opposite edge (obtuse, ~180 degrees), and a
    // needle with an apex angle of ~1e-6 (acute, base angles just below 90 degrees).
    const Vec3 n = uu.cross(v).normalized();
    check_triangle(o, o + uu, o + 0.5 * uu + 1e-9 * n, "flat sliver");
    check_triangle(o, o + uu * 1e-6, o + 0.5e-6 * uu + v.normalized() * uu.norm(), "needle");
    // Huge offset, tiny features.
    const Vec3 off(1e7, 2e7, -3e7);
    check_triangle(off + 1e-4 * uu, off + 1e-4 * v, off + 1e-4 * rv(), "offset");
  }
}

TEST(SphereTriangle, AverageTriangleSphereArea) {
  const std::vector<Vec3> pos{Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(10, 10, 10), Vec3(14, 10, 10)};
  const std::vector<Tri> tris{{0, 1, 2}, {3, 4, 3}, {0, 1, 2}};
  // Right triangle: radius sqrt 2 (area 8 pi); degenerate edge of length 4: radius 2 (16 pi).
  EXPECT_NEAR(average_triangle_sphere_area(pos, tris), (8 + 16 + 8) * std::numbers::pi / 3, 1e-12);
  EXPECT_EQ(average_triangle_sphere_area(pos, {}), 0.0);
}

// AvgSA does not depend on where the mesh sits, nor on the corners' order: random triangles on a
// 2^-20 grid (so that adding 2^32 is exact), translated, and with their corners rotated, give the
// same bits. (In world coordinates the minimal sphere's center was rounded to ulp(|center|) and
// the radius with it: 7e-6 relative at 2^32 on a mesh of such triangles.)
TEST(SphereTriangle, AverageTriangleSphereAreaIsTranslationInvariant) {
  std::mt19937 g(5);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  auto grid = [](double x) { return std::ldexp(std::round(std::ldexp(x, 20)), -20); };
  std::vector<Vec3> pos;
  std::vector<Tri> tris, rotated;
  for (std::uint32_t t = 0; t < 3000; ++t) {
    const Vec3 c(grid(U(g)), grid(U(g)), grid(U(g)));
    for (int k = 0; k < 3; ++k) pos.push_back(c + Vec3(grid(1e-3 * U(g)), grid(1e-3 * U(g)), grid(1e-3 * U(g))));
    tris.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    rotated.push_back({3 * t + 1, 3 * t + 2, 3 * t});
  }
  const double base = average_triangle_sphere_area(pos, tris);
  ASSERT_GT(base, 0.0);
  EXPECT_EQ(average_triangle_sphere_area(pos, rotated), base);
  for (const Vec3& off : {Vec3(0x1p32, -0x1p32, 0x1p32), Vec3(-0x1p20, 0x1p12, 3.0)}) {
    std::vector<Vec3> moved = pos;
    for (Vec3& p : moved) p += off;
    EXPECT_EQ(average_triangle_sphere_area(moved, tris), base) << off.transpose();
  }
}

// ---------------------------------------------------------------------------------------------
// Rounding of a + b sqrt(t) (the exact path's last step), against MPFR at 8192 bits.

double reference_round(const std::string& a, const std::string& b, const std::string& t) {
  mpq_t qa, qb, qt;
  mpq_inits(qa, qb, qt, nullptr);
  mpq_set_str(qa, a.c_str(), 10), mpq_set_str(qb, b.c_str(), 10), mpq_set_str(qt, t.c_str(), 10);
  mpq_canonicalize(qa), mpq_canonicalize(qb), mpq_canonicalize(qt);
  mpfr_t x, y;
  mpfr_init2(x, 8192), mpfr_init2(y, 8192);
  mpfr_set_q(x, qt, MPFR_RNDN);
  mpfr_sqrt(x, x, MPFR_RNDN);
  mpfr_mul_q(x, x, qb, MPFR_RNDN);
  mpfr_add_q(x, x, qa, MPFR_RNDN);
  const double d = mpfr_get_d(x, MPFR_RNDN);
  mpfr_clears(x, y, nullptr);
  mpq_clears(qa, qb, qt, nullptr);
  return d;
}

TEST(SphereRounding, SqrtFormIsCorrectlyRounded) {
  using detail::round_sqrt_form;
  const std::string p60 = "1152921504606846976";  // 2^60
  // Cancellation: 1 - sqrt(1 + 2^-60) = -2^-61 (1 - 2^-62 + ...); naive double evaluation gives 0.
  EXPECT_EQ(round_sqrt_form("1", "-1", "1152921504606846977/" + p60), reference_round("1", "-1", "1152921504606846977/" + p60));
  EXPECT_NEAR(round_sqrt_form("1", "-1", "1152921504606846977/" + p60), -std::ldexp(1.0, -61), std::ldexp(1.0, -120));
  EXPECT_EQ(round_sqrt_form("-3", "1", "9000000000000000000000001/1000000000000000000000000"),
            reference_round("-3", "1", "9000000000000000000000001/1000000000000000000000000"));
  // Rational values: perfect-square t, b = 0, t = 0; ties go to even.
  EXPECT_EQ(round_sqrt_form("1/3", "1", "4/9"), 1.0);
  EXPECT_EQ(round_sqrt_form("7/2", "0", "2"), 3.5);
  EXPECT_EQ(round_sqrt_form("7/2", "5", "0"), 3.5);
  const std::string p53 = "9007199254740992";  // 2^53: 1 + 2^-53 is the tie between 1 and 1 + 2^-52
  EXPECT_EQ(round_sqrt_form("1", "1/" + p53, "1"), 1.0);
  EXPECT_EQ(round_sqrt_form("1", "3/" + p53, "1"), 1.0 + std::ldexp(1.0, -51));
  EXPECT_EQ(round_sqrt_form("1", "1/" + p53, "1/4"), 1.0);  // 1 + 2^-54: below the tie
  EXPECT_EQ(round_sqrt_form("0", "1/4", "2"), std::sqrt(2.0) / 4);
  EXPECT_THROW((void)round_sqrt_form("1/0", "1", "2"), std::invalid_argument);
  EXPECT_THROW((void)round_sqrt_form("x", "1", "2"), std::invalid_argument);
  EXPECT_THROW((void)round_sqrt_form("1", "1", "-2"), std::invalid_argument);
  // Random rationals of mixed signs, many close to cancellation.
  std::mt19937_64 rng(22);
  std::uniform_int_distribution<std::uint64_t> big(1, std::uint64_t{1} << 62);
  for (int i = 0; i < 2000; ++i) {
    const std::uint64_t s = big(rng) >> (i % 40), d = big(rng);
    const std::string t = std::to_string(s) + "/" + std::to_string(d);
    // a ~ -b sqrt(t): a = -b * (rounded sqrt(t)) as an exact rational of the double.
    const double approx = std::sqrt(double(s) / double(d)) * (i % 3 == 0 ? 1.0 : 1.0 + 1e-9 * (i % 7));
    mpq_t q;
    mpq_init(q);
    mpq_set_d(q, -approx);
    char* buf = mpq_get_str(nullptr, 10, q);
    const std::string a = buf;
    void (*freefunc)(void*, size_t);
    mp_get_memory_functions(nullptr, nullptr, &freefunc);
    freefunc(buf, std::strlen(buf) + 1);
    mpq_clear(q);
    const std::string b = i % 2 ? "1" : "-3/7";
    EXPECT_EQ(round_sqrt_form(a, b, t), reference_round(a, b, t)) << a << " + " << b << " sqrt(" << t << ")";
  }
}

// ---------------------------------------------------------------------------------------------
// Small interface pieces.

TEST(SphereInterface, NamesRoundTripAndBadValuesAreRejected) {
  for (SphereMethod m : kAllSphereMethods) EXPECT_EQ(parse_sphere_method(to_string(m)), m);
  EXPECT_EQ(to_string(SphereMethod::Epos26), "epos26");
  EXPECT_EQ(parse_sphere_method("EXACT"), std::nullopt);
  EXPECT_EQ(parse_sphere_method(""), std::nullopt);
  EXPECT_EQ(parse_sphere_method("epos"), std::nullopt);
  const std::vector<Vec3> pts{Vec3::Zero(), Vec3::UnitX()};
  EXPECT_THROW((void)epos_sphere(pts, 6), std::invalid_argument);
  EXPECT_THROW((void)epos_sphere(pts, 0), std::invalid_argument);
}

TEST(SphereInterface, AreasAndContainment) {
  const Sphere s{Vec3(1, 1, 1), 2.0};
  EXPECT_DOUBLE_EQ(s.surface_area(), 16 * std::numbers::pi);
  EXPECT_DOUBLE_EQ(s.great_circle_area(), 4 * std::numbers::pi);
  const std::vector<Vec3> on{Vec3(3, 1, 1), Vec3(1, -1, 1)};
  EXPECT_TRUE(contains_all(s, on));
  EXPECT_TRUE(contains_all(s, std::vector<Vec3>{Vec3(3 + 4 * 2 * kEps, 1, 1)}));
  EXPECT_FALSE(contains_all(s, std::vector<Vec3>{Vec3(3 + 1e-12, 1, 1)}));
  EXPECT_FALSE(contains_all(Sphere{Vec3::Zero(), kNaN}, on));
}

}  // namespace
}  // namespace ptc
