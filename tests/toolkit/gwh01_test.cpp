// GWH01 terms (docs/method.md, baseline 3) against closed forms worked out by hand, item by item.
// Point sets are built so that the stored doubles are exactly what the hand answer assumes
// (small integers times powers of two, integer offsets), so tolerances measure our arithmetic.
#include "toolkit/geometry/gwh01.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

namespace ptc {
namespace {

using std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<std::uint32_t> all_ids(std::size_t n) {
  std::vector<std::uint32_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = static_cast<std::uint32_t>(i);
  return ids;
}

Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized().toRotationMatrix();
}

Quadric quadric_of(const std::vector<Vec3>& pts) {
  Quadric q;
  for (const Vec3& p : pts) q.add(p);
  return q;
}

// Covariance of a point set computed the slow, obvious way: two passes, centered, after moving
// the points next to the origin (exact differences for nearby doubles).
Eigen::Matrix3d covariance(const std::vector<Vec3>& pts) {
  std::vector<Vec3> q;
  for (const Vec3& p : pts) q.push_back(p - pts[0]);
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : q) mean += p;
  mean /= static_cast<double>(q.size());
  Eigen::Matrix3d Z = Eigen::Matrix3d::Zero();
  for (const Vec3& p : q) Z += (p - mean) * (p - mean).transpose();
  return Z;
}

// Regular n-gon fan of radius r in z = 0 (center vertex 0), counter-clockwise (normal +z).
Mesh fan(int n, double r = 1.0) {
  std::vector<Vec3> p{Vec3::Zero()};
  for (int i = 0; i < n; ++i) p.emplace_back(r * std::cos(2 * pi * i / n), r * std::sin(2 * pi * i / n), 0.0);
  std::vector<Tri> t;
  for (int i = 0; i < n; ++i)
    t.push_back({0u, static_cast<std::uint32_t>(i + 1), static_cast<std::uint32_t>((i + 1) % n + 1)});
  return Mesh(std::move(t), std::move(p));
}

// ---------------------------------------------------------------------------------------------
// Quadric and plane fit

TEST(GwhFit, EmptySingleAndCollinearPoints) {
  const PlaneFit e = fit_plane(Quadric());
  EXPECT_EQ(e.normal, Vec3::UnitZ());
  EXPECT_EQ(e.offset, 0.0);
  EXPECT_EQ(e.e_fit, 0.0);

  Quadric one;
  one.add(Vec3(3, 4, 5));
  const PlaneFit f1 = fit_plane(one);
  EXPECT_EQ(f1.e_fit, 0.0);
  EXPECT_NEAR(f1.normal.norm(), 1.0, 1e-15);
  EXPECT_EQ(f1.centroid, Vec3(3, 4, 5));
  EXPECT_NEAR(f1.normal.dot(f1.centroid) + f1.offset, 0.0, 1e-14);

  // Points on the line through (1,2,3) with direction (1,1,0): e_fit 0, normal orthogonal to it.
  std::vector<Vec3> line;
  for (int i = -3; i <= 5; ++i) line.push_back(Vec3(1, 2, 3) + 0.25 * i * Vec3(1, 1, 0));
  const PlaneFit fl = fit_plane(quadric_of(line));
  EXPECT_LT(fl.e_fit, 1e-30);
  EXPECT_NEAR(fl.normal.norm(), 1.0, 1e-15);
  EXPECT_NEAR(fl.normal.dot(Vec3(1, 1, 0)), 0.0, 1e-15);
}

TEST(GwhFit, PlanePointsGiveExactNormalAtAnyOffset) {
  // The plane x + 2y + 3z = const contains the directions e1 = (2,-1,0), e2 = (3,0,-1).
  // Points O + h (u e1 + v e2) for small integers u, v are exact doubles for O integer and
  // h = 2^-k, including O ~ 1e7 with h = 2^-12 (features ~1e-3).
  const Vec3 n_exact = Vec3(1, 2, 3).normalized();
  const Vec3 e1(2, -1, 0), e2(3, 0, -1);
  std::mt19937_64 rng(41);
  std::uniform_int_distribution<int> ui(-6, 6);
  for (const auto& [O, h] : std::vector<std::pair<Vec3, double>>{{Vec3::Zero(), 1.0},
                                                                  {Vec3(1e7, 1e7, 1e7), std::ldexp(1.0, -12)},
                                                                  {Vec3(-1e7, 3e7, 2e7), std::ldexp(1.0, -12)},
                                                                  {Vec3(0, 0, 0), std::ldexp(1.0, -100)}}) {
    std::vector<Vec3> pts;
    for (int i = 0; i < 40; ++i) pts.push_back(O + h * (ui(rng) * e1 + ui(rng) * e2));
    const Eigen::Matrix3d Z = covariance(pts);
    const double spread = Z.trace() / static_cast<double>(pts.size());  // mean squared distance to the centroid
    for (const Quadric& q : {quadric_of(pts), [&] {
                               Quadric r(pts[7]);  // explicit origin inside the cluster
                               for (const Vec3& p : pts) r.add(p);
                               return r;
                             }()}) {
      const PlaneFit f = fit_plane(q, Vec3(1, 2, 3));
      EXPECT_LT((f.normal - n_exact).norm(), 1e-13) << "offset " << O.transpose();
      EXPECT_LE(f.e_fit, 1e-15 * spread);
      // The centroid is rounded to absolute coordinates: ulp/2 per coordinate.
      EXPECT_NEAR(f.normal.dot(pts[3] - f.centroid), 0.0, 1e-13 * std::sqrt(spread) + 4e-16 * O.lpNorm<1>());
    }
  }
}

TEST(GwhFit, KnownSpreadGivesExactEFit) {
  // Corners (+-a, +-b, +-h), a > b > h: covariance diag(a^2, b^2, h^2) * 8, E_fit = h^2, normal z.
  const double a = 3, b = 2, h = 0.5;
  std::vector<Vec3> box;
  for (int i = 0; i < 8; ++i) box.emplace_back(i & 1 ? a : -a, i & 2 ? b : -b, i & 4 ? h : -h);
  const PlaneFit f = fit_plane(quadric_of(box), Vec3::UnitZ());
  EXPECT_NEAR(f.e_fit, h * h, 1e-15);
  EXPECT_LT((f.normal - Vec3::UnitZ()).norm(), 1e-15);
  EXPECT_NEAR(f.offset, 0.0, 1e-15);
  // Rotated and translated: same E_fit, rotated normal.
  std::mt19937_64 rng(43);
  for (int rep = 0; rep < 30; ++rep) {
    const Eigen::Matrix3d R = random_rotation(rng);
    const Vec3 t = 100.0 * Vec3::Random();
    std::vector<Vec3> moved;
    for (const Vec3& p : box) moved.push_back(R * p + t);
    const PlaneFit g = fit_plane(quadric_of(moved), R * Vec3::UnitZ());
    EXPECT_NEAR(g.e_fit / (h * h), 1.0, 1e-12);
    EXPECT_LT((g.normal - R * Vec3::UnitZ()).norm(), 1e-13);
    EXPECT_NEAR(g.normal.dot(t) + g.offset, 0.0, 1e-12);  // the centroid t lies on the plane
  }
  // At a 1e7 offset with features 2^-12 (exact corners): E_fit = (h 2^-12)^2 to 1e-12.
  const double s = std::ldexp(1.0, -12);
  std::vector<Vec3> far;
  for (const Vec3& p : box) far.push_back(Vec3(1e7, -2e7, 3e7) + s * p);
  const PlaneFit ff = fit_plane(quadric_of(far), Vec3::UnitZ());
  EXPECT_NEAR(ff.e_fit / (h * h * s * s), 1.0, 1e-12);
  EXPECT_LT((ff.normal - Vec3::UnitZ()).norm(), 1e-13);
}

TEST(GwhFit, RepeatedEigenvaluesOnACircleAreStable) {
  // n points on a circle: eigenvalues (0, c r^2/2, c r^2/2). The two large ones are repeated;
  // the normal (simple eigenvalue 0) must still come out to ~1e-15 (computeDirect: ~5e-9).
  std::mt19937_64 rng(47);
  double worst = 0;
  for (int rep = 0; rep < 200; ++rep) {
    const Eigen::Matrix3d R = random_rotation(rng);
    const Vec3 t = 10.0 * Vec3::Random();
    const int n = 3 + rep % 13;
    std::vector<Vec3> pts;
    for (int i = 0; i < n; ++i) pts.push_back(R * Vec3(std::cos(2 * pi * i / n), std::sin(2 * pi * i / n), 0) + t);
    const PlaneFit f = fit_plane(quadric_of(pts), R.col(2));
    worst = std::max(worst, (f.normal - R.col(2)).norm());
    // The eigenvalue 0 is computed to ~eps * |Z|: E_fit within a few eps of the spread r^2/2.
    EXPECT_LE(f.e_fit, 1e-15);
  }
  EXPECT_LT(worst, 1e-13);
}

TEST(GwhFit, AllEigenvaluesEqualOnSymmetricSets) {
  // Octahedron (+-e_i) and icosahedron ((0, +-1, +-phi) cyclic) vertices: covariance = lambda I
  // (both are spherical 2-designs), so E_fit = |v|^2 / 3 exactly and any unit normal is valid.
  const double phi = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> octa, ico;
  for (int a = 0; a < 3; ++a)
    for (double s : {-1.0, 1.0}) octa.push_back(s * Vec3::Unit(a));
  for (double s1 : {-1.0, 1.0})
    for (double s2 : {-1.0, 1.0}) {
      ico.emplace_back(0, s1, s2 * phi);
      ico.emplace_back(s1, s2 * phi, 0);
      ico.emplace_back(s2 * phi, 0, s1);
    }
  std::mt19937_64 rng(53);
  for (const auto& [set, r2] : std::vector<std::pair<std::vector<Vec3>, double>>{{octa, 1.0}, {ico, 1 + phi * phi}}) {
    for (int rep = 0; rep < 20; ++rep) {
      const Eigen::Matrix3d R = random_rotation(rng);
      const Vec3 t = Vec3::Random();
      std::vector<Vec3> pts;
      for (const Vec3& p : set) pts.push_back(R * p + t);
      const PlaneFit f = fit_plane(quadric_of(pts));
      EXPECT_NEAR(f.e_fit / (r2 / 3), 1.0, 1e-13);
      EXPECT_NEAR(f.normal.norm(), 1.0, 1e-15);
      const Eigen::Matrix3d Z = covariance(pts);
      const double lambda = r2 / 3 * static_cast<double>(pts.size());
      EXPECT_LT((Z * f.normal - lambda * f.normal).norm(), 1e-12 * lambda);
    }
  }
}

TEST(GwhFit, OrientationFollowsReferenceOrCanonicalSign) {
  const std::vector<Vec3> pts{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  EXPECT_LT((fit_plane(quadric_of(pts), Vec3(0.1, 0.2, 1)).normal - Vec3::UnitZ()).norm(), 1e-15);
  EXPECT_LT((fit_plane(quadric_of(pts), Vec3(5, 5, -1e-3)).normal + Vec3::UnitZ()).norm(), 1e-15);
  // No reference, or one (numerically) orthogonal: the largest component is made positive.
  EXPECT_LT((fit_plane(quadric_of(pts)).normal - Vec3::UnitZ()).norm(), 1e-15);
  EXPECT_LT((fit_plane(quadric_of(pts), Vec3(1, 0, 0)).normal - Vec3::UnitZ()).norm(), 1e-15);
  EXPECT_LT((fit_plane(quadric_of(pts), Vec3(1, 0, -1e-14)).normal - Vec3::UnitZ()).norm(), 1e-15);
  // Plane spanned by (1,0,0) and (0,1,2): normal +-(0,-2,1)/sqrt5, |y| largest -> (0,2,-1)/sqrt5.
  const std::vector<Vec3> tilted{{0, 0, 0}, {2, 0, 0}, {0, 1, 2}, {2, 1, 2}};
  EXPECT_LT((fit_plane(quadric_of(tilted)).normal - Vec3(0, 2, -1) / std::sqrt(5.0)).norm(), 1e-15);
  EXPECT_LT((fit_plane(quadric_of(tilted), Vec3(0, 0, 1)).normal - Vec3(0, -2, 1) / std::sqrt(5.0)).norm(), 1e-15);
}

TEST(GwhQuadric, MergeEqualsUnionWhateverTheOrigins) {
  std::mt19937_64 rng(59);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const Vec3& O : {Vec3(0, 0, 0), Vec3(1e7, -1e7, 5e6)}) {
    const double s = O.isZero() ? 1.0 : 1e-3;
    std::vector<Vec3> p1, p2, all;
    for (int i = 0; i < 30; ++i) p1.push_back(O + s * Vec3(u(rng), u(rng), 0.1 * u(rng)));
    for (int i = 0; i < 20; ++i) p2.push_back(O + s * Vec3(1.5 + u(rng), u(rng), 0.1 * u(rng)));
    all = p1;
    all.insert(all.end(), p2.begin(), p2.end());
    Quadric q1 = quadric_of(p1);  // origin p1[0]
    const Quadric q2 = quadric_of(p2);  // origin p2[0]
    ASSERT_NE(q1.origin, q2.origin);
    q1 += q2;
    EXPECT_EQ(q1.c, 50.0);
    const PlaneFit fm = fit_plane(q1, Vec3::UnitZ()), fa = fit_plane(quadric_of(all), Vec3::UnitZ());
    EXPECT_NEAR(fm.e_fit / fa.e_fit, 1.0, 1e-12);
    EXPECT_LT((fm.normal - fa.normal).norm(), 1e-12);
    EXPECT_LT((fm.centroid - fa.centroid).norm(), 1e-12 * s + 1e-15 * O.norm());
    // Independent: E_fit = smallest eigenvalue of the centered covariance / count.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(covariance(all));
    EXPECT_NEAR(fa.e_fit / (es.eigenvalues()[0] / 50.0), 1.0, 1e-12);
  }
  // Empty quadrics: adopting and ignoring.
  Quadric empty;
  Quadric q;
  q.add(Vec3(1, 2, 3));
  q.add(Vec3(2, 2, 3));
  empty += q;
  EXPECT_EQ(empty.origin, Vec3(1, 2, 3));
  EXPECT_EQ(empty.c, 2.0);
  q += Quadric();
  EXPECT_EQ(q.c, 2.0);
  // shifted() is the same point set.
  const Quadric sh = q.shifted(Vec3(-4, 0, 9));
  EXPECT_EQ(sh.origin, Vec3(-4, 0, 9));
  EXPECT_LT((fit_plane(sh).centroid - Vec3(1.5, 2, 3)).norm(), 1e-14);
}

TEST(GwhQuadric, WeightsEqualRepetition) {
  std::vector<Vec3> pts{{0, 0, 0}, {2, 0, 1}, {0, 3, -1}, {1, 1, 2}};
  Quadric w, rep;
  const double weights[4] = {1, 3, 2, 1};
  for (int i = 0; i < 4; ++i) {
    w.add(pts[i], weights[i]);
    for (int k = 0; k < static_cast<int>(weights[i]); ++k) rep.add(pts[i]);
  }
  EXPECT_EQ(w.c, rep.c);
  EXPECT_LT((w.A - rep.A).norm(), 1e-14);
  EXPECT_LT((w.b - rep.b).norm(), 1e-14);
  EXPECT_NEAR(fit_plane(w).e_fit, fit_plane(rep).e_fit, 1e-14);
}

// ---------------------------------------------------------------------------------------------
// E_dir, irregularity, E_shape

TEST(GwhDir, HandComputedBothWeights) {
  // n = z; n_i = z, x, (0, 0.6, 0.8); areas 1, 4, 9:
  //   Area:     (1*0 + 4*1 + 9*0.2^2) / 14 = 4.36 / 14
  //   SqrtArea: (1*0 + 2*1 + 3*0.2^2) / 14 = 2.12 / 14
  const std::vector<Vec3> n{Vec3::UnitZ(), Vec3::UnitX(), Vec3(0, 0.6, 0.8)};
  const std::vector<double> a{1, 4, 9};
  EXPECT_NEAR(e_dir(Vec3::UnitZ(), n, a, GwhWeight::Area), 4.36 / 14, 1e-15);
  EXPECT_NEAR(e_dir(Vec3::UnitZ(), n, a, GwhWeight::SqrtArea), 2.12 / 14, 1e-15);
  // Opposite normal: (1 - (-1))^2 = 4, the maximum.
  const std::vector<Vec3> down{-Vec3::UnitZ()};
  const std::vector<double> one{2.5};
  EXPECT_EQ(e_dir(Vec3::UnitZ(), down, one), 4.0);
  // Zero-area (zero-normal) triangles weigh nothing; all-zero area gives 0.
  const std::vector<Vec3> nz{Vec3::UnitZ(), Vec3::Zero()};
  const std::vector<double> az{2, 0};
  EXPECT_EQ(e_dir(Vec3::UnitZ(), nz, az, GwhWeight::SqrtArea), 0.0);
  const std::vector<Vec3> z0{Vec3::Zero()};
  const std::vector<double> a0{0};
  EXPECT_EQ(e_dir(Vec3::UnitZ(), z0, a0), 0.0);
  EXPECT_EQ(e_dir(Vec3::UnitZ(), {}, {}), 0.0);
  EXPECT_THROW((void)e_dir(Vec3::UnitZ(), n, one), std::invalid_argument);
}

TEST(GwhShape, IrregularityByHand) {
  EXPECT_DOUBLE_EQ(irregularity(4.0, 1.0), 4.0 / pi);  // unit square
  EXPECT_DOUBLE_EQ(irregularity(2 * pi * 3, pi * 9), 1.0);  // disc of radius 3
  EXPECT_EQ(irregularity(5.0, 0.0), kInf);
  EXPECT_EQ(irregularity(0.0, 0.0), kInf);
  EXPECT_EQ(irregularity(0.0, 2.0), 0.0);  // closed surface
}

TEST(GwhShape, ShapeCostByHand) {
  EXPECT_DOUBLE_EQ(shape_cost(2.0, 1.0, 1.5), 0.25);
  EXPECT_DOUBLE_EQ(shape_cost(2.0, 1.5, 1.0), 0.25);
  EXPECT_EQ(shape_cost(1.0, 2.0, 3.0), 0.0);  // an improvement costs nothing
  EXPECT_EQ(shape_cost(3.0, 2.0, 3.0), 0.0);
  EXPECT_EQ(shape_cost(0.0, 0.0, 0.0), 0.0);
  EXPECT_EQ(shape_cost(kInf, 1.0, 2.0), 1.0);
  EXPECT_EQ(shape_cost(kInf, kInf, 2.0), 0.0);
  EXPECT_EQ(shape_cost(5.0, kInf, 2.0), 0.0);
  EXPECT_TRUE(std::isnan(shape_cost(std::nan(""), 1.0, 1.0)));
  EXPECT_TRUE(std::isnan(shape_cost(1.0, std::nan(""), 1.0)));
}

// ---------------------------------------------------------------------------------------------
// gwh_terms on meshes

TEST(GwhTerms, EmptyClusterAndBadIds) {
  const Mesh m = fan(4);
  const GwhTerms t = gwh_terms(m, {});
  EXPECT_EQ(t.area, 0.0);
  EXPECT_EQ(t.perimeter, 0.0);
  EXPECT_EQ(t.e_dir, 0.0);
  EXPECT_EQ(t.fit.e_fit, 0.0);
  EXPECT_EQ(t.gamma, kInf);
  const std::vector<std::uint32_t> out{4}, dup{0, 0};
  EXPECT_THROW((void)gwh_terms(m, out), std::invalid_argument);
  EXPECT_THROW((void)gwh_terms(m, dup), std::invalid_argument);
}

TEST(GwhTerms, SquareOfTwoTrianglesAndEquilateralTriangle) {
  // Unit square at a far offset: perimeter 4, area 1, gamma 4/pi, flat, normal +z (CCW).
  const Vec3 O(1e7, 2e7, -3e7);
  const double s = std::ldexp(1.0, -10);
  const Mesh sq({{0, 1, 2}, {0, 2, 3}}, {O, O + s * Vec3(1, 0, 0), O + s * Vec3(1, 1, 0), O + s * Vec3(0, 1, 0)});
  const GwhTerms t = gwh_terms(sq, all_ids(2));
  EXPECT_NEAR(t.perimeter, 4 * s, 1e-15 * s);
  EXPECT_NEAR(t.area, s * s, 1e-15 * s * s);
  EXPECT_NEAR(t.gamma, 4 / pi, 1e-14);
  EXPECT_LE(t.fit.e_fit, 1e-30 * s * s);
  EXPECT_EQ(t.fit.normal, Vec3::UnitZ());
  EXPECT_EQ(t.e_dir, 0.0);
  // Reversed orientation: the reference flips the normal too; e_dir stays 0.
  const Mesh rev({{0, 2, 1}, {0, 3, 2}}, {O, O + s * Vec3(1, 0, 0), O + s * Vec3(1, 1, 0), O + s * Vec3(0, 1, 0)});
  EXPECT_EQ(gwh_terms(rev, all_ids(2)).fit.normal, -Vec3::UnitZ());
  EXPECT_EQ(gwh_terms(rev, all_ids(2)).e_dir, 0.0);
  // Equilateral triangle (side sqrt2): gamma = (3 sqrt2)^2 / (4 pi sqrt3/2) = 9 / (pi sqrt3).
  const Mesh tri({{0, 1, 2}}, {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)});
  const GwhTerms e = gwh_terms(tri, all_ids(1));
  EXPECT_NEAR(e.gamma, 9 / (pi * std::sqrt(3.0)), 1e-14);
  EXPECT_LT((e.fit.normal - Vec3(1, 1, 1) / std::sqrt(3.0)).norm(), 1e-15);
  EXPECT_LT(e.e_dir, 1e-30);
  EXPECT_LE(e.fit.e_fit, 1e-15);  // eps * spread (spread 2/3): the eigenvalue's rounding
}

TEST(GwhTerms, RoofOfTwoTrianglesByHand) {
  // P1 = (0,-1,0), P2 = (0,1,0), P3 = (1,0,t), P4 = (-1,0,t); triangles (P1 P3 P2), (P1 P2 P4).
  // Covariance diag(2, 2, t^2) (t < sqrt2): normal z, E_fit = t^2 / 4.
  // Normals (-t,0,1)/sqrt(1+t^2) and (t,0,1)/sqrt(1+t^2), areas sqrt(1+t^2):
  //   E_dir(Area) = (1 - 1/sqrt(1+t^2))^2, E_dir(SqrtArea) = that / (1+t^2)^(1/4).
  // Boundary: 4 edges of length sqrt(2+t^2) (P1P2 is interior).
  const double t = 0.5;
  const Mesh roof({{0, 2, 1}, {0, 1, 3}}, {Vec3(0, -1, 0), Vec3(0, 1, 0), Vec3(1, 0, t), Vec3(-1, 0, t)});
  const double d = 1 - 1 / std::sqrt(1 + t * t);
  for (GwhWeight w : {GwhWeight::Area, GwhWeight::SqrtArea}) {
    const GwhTerms g = gwh_terms(roof, all_ids(2), w);
    EXPECT_LT((g.fit.normal - Vec3::UnitZ()).norm(), 1e-15);
    EXPECT_NEAR(g.fit.e_fit, t * t / 4, 1e-15);
    EXPECT_NEAR(g.fit.offset, -t / 2, 1e-15);
    const double expected = w == GwhWeight::Area ? d * d : d * d / std::pow(1 + t * t, 0.25);
    EXPECT_NEAR(g.e_dir, expected, 1e-15);
    EXPECT_NEAR(g.area, 2 * std::sqrt(1 + t * t), 1e-15);
    EXPECT_NEAR(g.perimeter, 4 * std::sqrt(2 + t * t), 1e-14);
    EXPECT_NEAR(g.gamma, 16 * (2 + t * t) / (4 * pi * 2 * std::sqrt(1 + t * t)), 1e-14);
  }
  // gwh_cost with the paper's weights a1 = 0.2, a2 = 2, merging the two single triangles.
  const GwhTerms merged = gwh_terms(roof, all_ids(2));
  const std::vector<std::uint32_t> first{0}, second{1};
  const GwhTerms g1 = gwh_terms(roof, first), g2 = gwh_terms(roof, second);
  const GwhParams params;
  EXPECT_EQ(params.a1, 0.2);
  EXPECT_EQ(params.a2, 2.0);
  const double shape = std::max(0.0, (merged.gamma - std::max(g1.gamma, g2.gamma)) / merged.gamma);
  EXPECT_DOUBLE_EQ(gwh_cost(merged, g1, g2), t * t / 4 + 0.2 * d * d + 2 * shape);
  EXPECT_DOUBLE_EQ(gwh_cost(merged, g1, g2, GwhParams{.a1 = 1, .a2 = 0}), t * t / 4 + d * d);
}

TEST(GwhTerms, FanPerimeterAndIrregularityApproachDisc) {
  // Regular n-gon: P = 2 n r sin(pi/n), A = (n/2) r^2 sin(2 pi/n): gamma -> 1 from above.
  double prev = kInf;
  for (int n : {3, 4, 6, 16, 256, 4096}) {
    const double r = 1.75;
    const GwhTerms g = gwh_terms(fan(n, r), all_ids(static_cast<std::size_t>(n)));
    const double P = 2 * n * r * std::sin(pi / n), A = 0.5 * n * r * r * std::sin(2 * pi / n);
    EXPECT_NEAR(g.perimeter / P, 1.0, 1e-13) << n;
    EXPECT_NEAR(g.area / A, 1.0, 1e-13) << n;
    EXPECT_NEAR(g.gamma / (P * P / (4 * pi * A)), 1.0, 1e-12) << n;
    EXPECT_LT(g.gamma, prev);
    EXPECT_GT(g.gamma, 1.0);
    prev = g.gamma;
  }
  EXPECT_NEAR(prev, 1.0, 1e-6);
  EXPECT_NEAR(gwh_terms(fan(4, 1.0), all_ids(4)).gamma, 4 / pi, 1e-14);  // the square
}

TEST(GwhTerms, BoundaryEdgePolicy) {
  // Three triangles on edge {0,1} (non-manifold): not boundary; the 6 other edges are.
  const std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  const Mesh nm({{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}, p);
  const double r2 = std::sqrt(2.0);
  EXPECT_NEAR(gwh_terms(nm, all_ids(3)).perimeter, 3 * (1 + r2), 1e-15);
  // Two of them share {0,1} as a manifold edge: boundary is the other 4 edges.
  const std::vector<std::uint32_t> two{0, 1};
  EXPECT_NEAR(gwh_terms(nm, two).perimeter, 2 * (1 + r2), 1e-15);
  // Repeated-index triangles: (0,0,1) and (0,1,0) use {0,1} once each; alone each has perimeter
  // |p0 p1| = 1 (collapsed side ignored) and area 0 -> gamma +inf.
  for (const Tri& tri : {Tri{0, 0, 1}, Tri{0, 1, 0}, Tri{1, 0, 0}}) {
    const Mesh d({tri}, p);
    const GwhTerms g = gwh_terms(d, all_ids(1));
    EXPECT_EQ(g.perimeter, 1.0);
    EXPECT_EQ(g.area, 0.0);
    EXPECT_EQ(g.gamma, kInf);
  }
  // A degenerate triangle glued along {0,1} to a proper one: {0,1} is used twice -> interior.
  const Mesh glued({{0, 1, 2}, {0, 1, 0}}, p);
  EXPECT_NEAR(gwh_terms(glued, all_ids(2)).perimeter, 1 + r2, 1e-15);
  // (3,3,3) contributes no edge at all.
  const Mesh point({{0, 1, 2}, {3, 3, 3}}, p);
  EXPECT_NEAR(gwh_terms(point, all_ids(2)).perimeter, 2 + r2, 1e-15);
}

}  // namespace
}  // namespace ptc
