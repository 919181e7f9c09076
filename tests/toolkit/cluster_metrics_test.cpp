// Cluster quantities (docs/method.md "Quantities for a cluster") against independent answers:
// closed forms worked out by hand, CGAL's exact kernel, and brute-force recomputation.
// Degenerate cases first.
#include "toolkit/geometry/cluster_metrics.h"

#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <tuple>
#include <vector>

#include <Eigen/Geometry>

#include "toolkit/geometry/triangle.h"

namespace ptc {
namespace {

using std::numbers::pi;
const double kRegEquilateral = 3.0 * std::sqrt(3.0) / (4.0 * pi);

std::vector<std::uint32_t> all_ids(std::size_t n) {
  std::vector<std::uint32_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = static_cast<std::uint32_t>(i);
  return ids;
}

ClusterMetrics metrics_of(const Mesh& m, SphereMethod s = SphereMethod::Cgal) {
  return cluster_metrics(m, all_ids(m.triangle_count()), s);
}

Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::Quaterniond q(g(rng), g(rng), g(rng), g(rng));
  return q.normalized().toRotationMatrix();
}

Mesh transformed(const Mesh& m, const Eigen::Matrix3d& R, const Vec3& t) {
  std::vector<Vec3> p(m.positions().begin(), m.positions().end());
  for (Vec3& v : p) v = R * v + t;
  return m.with_positions(std::move(p));
}

// Regular n-gon fan of radius r in the plane z = 0: vertex 0 is the center, rim vertex i+1 at
// angle 2 pi i / n; triangles (0, i+1, i+2), counter-clockwise (normal +z).
Mesh fan(int n, double r = 1.0) {
  std::vector<Vec3> p{Vec3::Zero()};
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * pi * i / n;
    p.emplace_back(r * std::cos(a), r * std::sin(a), 0.0);
  }
  std::vector<Tri> t;
  for (int i = 0; i < n; ++i)
    t.push_back({0u, static_cast<std::uint32_t>(i + 1), static_cast<std::uint32_t>((i + 1) % n + 1)});
  return Mesh(std::move(t), std::move(p));
}

// Triangle strip of m quads (2m triangles) over 2(m+1) vertices in the plane z = 0.
Mesh strip(int m) {
  std::vector<Vec3> p;
  for (int i = 0; i <= m; ++i) {
    p.emplace_back(i, 0.0, 0.0);
    p.emplace_back(i, 1.0, 0.0);
  }
  std::vector<Tri> t;
  for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(m); ++i) {
    t.push_back({2 * i, 2 * i + 2, 2 * i + 1});
    t.push_back({2 * i + 1, 2 * i + 2, 2 * i + 3});
  }
  return Mesh(std::move(t), std::move(p));
}

// Sphere of radius R in latitude/longitude rings: polar angle theta_k = k * theta_max / rings
// (k = 0 is the north pole), `segments` longitudes. Triangles oriented outwards. With
// theta_max = pi the bottom ring collapses to the south pole (fan).
Mesh uv_cap(double R, double theta_max, int rings, int segments) {
  std::vector<Vec3> p{Vec3(0, 0, R)};
  const bool closed = theta_max == pi;
  const int last = closed ? rings - 1 : rings;
  for (int k = 1; k <= last; ++k) {
    const double th = theta_max * k / rings;
    for (int s = 0; s < segments; ++s) {
      const double ph = 2.0 * pi * s / segments;
      p.emplace_back(R * std::sin(th) * std::cos(ph), R * std::sin(th) * std::sin(ph), R * std::cos(th));
    }
  }
  auto ring = [&](int k, int s) { return static_cast<std::uint32_t>(1 + (k - 1) * segments + (s % segments)); };
  std::vector<Tri> t;
  for (int s = 0; s < segments; ++s) t.push_back({0u, ring(1, s), ring(1, s + 1)});
  for (int k = 1; k < last; ++k)
    for (int s = 0; s < segments; ++s) {
      t.push_back({ring(k, s), ring(k + 1, s), ring(k + 1, s + 1)});
      t.push_back({ring(k, s), ring(k + 1, s + 1), ring(k, s + 1)});
    }
  if (closed) {
    p.emplace_back(0, 0, -R);
    const auto south = static_cast<std::uint32_t>(p.size() - 1);
    for (int s = 0; s < segments; ++s) t.push_back({ring(last, s), south, ring(last, s + 1)});
  }
  return Mesh(std::move(t), std::move(p));
}

// Regular tetrahedron (edge 2 sqrt2), outward faces: face 0 = (v0 v1 v2) is opposite v3 with
// normal -v3/sqrt3 = (1,1,-1)/sqrt3; faces 1, 2, 3 are opposite v0, v1, v2 (normal -v/sqrt3).
Mesh tetrahedron() {
  std::vector<Vec3> v{{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  std::vector<Tri> t{{0, 1, 2}, {1, 3, 2}, {0, 2, 3}, {0, 3, 1}};
  return Mesh(std::move(t), std::move(v));
}

// Independent single-triangle reg for an ACUTE triangle with CGAL's exact kernel:
// reg = Area / (pi R^2) with R the circumradius (the minimal sphere of an acute triangle).
double exact_reg_acute(const Vec3& a, const Vec3& b, const Vec3& c) {
  using K = CGAL::Exact_predicates_exact_constructions_kernel;
  const K::Point_3 pa(a.x(), a.y(), a.z()), pb(b.x(), b.y(), b.z()), pc(c.x(), c.y(), c.z());
  const double area2 = CGAL::to_double(CGAL::squared_area(pa, pb, pc));
  const double r2 = CGAL::to_double(CGAL::squared_radius(pa, pb, pc));
  return std::sqrt(area2) / (pi * r2);
}

// ---------------------------------------------------------------------------------------------
// triangle.h helpers

TEST(ClusterMetricsTriangle, ZeroAreaAndRepeatedCornersGiveZero) {
  const Vec3 a(0.1, 0.2, 0.3), b(1.7, -2.0, 5.0);
  for (const auto& g : {triangle_geometry(a, a, b), triangle_geometry(a, b, a), triangle_geometry(b, a, a),
                        triangle_geometry(a, a, a), triangle_geometry(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(3, 3, 3)),
                        triangle_geometry(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), Vec3(0.3, 0.3, 0.3))}) {
    EXPECT_EQ(g.area, 0.0);
    EXPECT_EQ(g.normal, Vec3::Zero());
  }
}

TEST(ClusterMetricsTriangle, RightTriangleAreaNormalPerimeterCentroid) {
  const Vec3 a(0, 0, 0), b(3, 0, 0), c(0, 4, 0);
  for (const auto& g : {triangle_geometry(a, b, c), triangle_geometry(b, c, a), triangle_geometry(c, a, b)}) {
    EXPECT_EQ(g.area, 6.0);
    EXPECT_EQ(g.normal, Vec3(0, 0, 1));
  }
  EXPECT_EQ(triangle_normal(a, c, b), Vec3(0, 0, -1));
  EXPECT_EQ(triangle_area(a, c, b), 6.0);
  EXPECT_EQ(triangle_perimeter(a, b, c), 12.0);
  EXPECT_EQ(triangle_centroid(a, b, c), Vec3(1, 4.0 / 3.0, 0));
}

TEST(ClusterMetricsTriangle, SliverAboveThresholdKeepsItsNormalBelowIsDegenerate) {
  std::mt19937_64 rng(7);
  for (int rep = 0; rep < 20; ++rep) {
    const Eigen::Matrix3d R = random_rotation(rng);
    const Vec3 t(0.3, -1.1, 2.5);
    // Cap-shaped sliver: largest angle pi - 4e-9, sine ~4e-9 > kDegenerateSine.
    const Vec3 a = R * Vec3(0, 0, 0) + t, b = R * Vec3(1, 0, 0) + t, c = R * Vec3(0.5, 1e-9, 0) + t;
    const TriangleGeometry g = triangle_geometry(a, b, c);
    EXPECT_NEAR(g.area, 0.5e-9, 0.5e-9 * 1e-5);
    EXPECT_LT((g.normal - R * Vec3::UnitZ()).norm(), 1e-5);
    // Needle (one short side): well conditioned although thin.
    const TriangleGeometry needle = triangle_geometry(R * Vec3(0, 0, 0) + t, R * Vec3(1, 0, 0) + t,
                                                      R * Vec3(0, 1e-9, 0) + t);
    EXPECT_NEAR(needle.area, 0.5e-9, 0.5e-9 * 1e-6);
    EXPECT_LT((needle.normal - R * Vec3::UnitZ()).norm(), 1e-6);
  }
  // Sine ~4e-14 < 1e-12: degenerate, area and normal zero together.
  const TriangleGeometry g = triangle_geometry(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 1e-14, 0));
  EXPECT_EQ(g.area, 0.0);
  EXPECT_EQ(g.normal, Vec3::Zero());
}

TEST(ClusterMetricsTriangle, AreaMatchesExactKernelAtOffsetsAndScales) {
  using K = CGAL::Exact_predicates_exact_constructions_kernel;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const auto& [scale, offset] : std::vector<std::pair<double, Vec3>>{
           {1.0, Vec3::Zero()}, {1e-3, Vec3(1e7, -1e7, 3e6)}, {1e-30, Vec3::Zero()}, {1e30, Vec3(1e31, 0, 0)}}) {
    for (int rep = 0; rep < 200; ++rep) {
      Vec3 p[3];
      for (Vec3& q : p) q = offset + scale * Vec3(u(rng), u(rng), u(rng));
      const K::Point_3 a(p[0].x(), p[0].y(), p[0].z()), b(p[1].x(), p[1].y(), p[1].z()),
          c(p[2].x(), p[2].y(), p[2].z());
      const double exact = std::sqrt(CGAL::to_double(CGAL::squared_area(a, b, c)));
      const TriangleGeometry g = triangle_geometry(p[0], p[1], p[2]);
      // Error bound ~6 eps |e1||e2| absolute; random triangles are rarely thinner than sine 1e-3.
      const double e1e2 = std::min({(p[1] - p[0]).norm() * (p[2] - p[0]).norm(),
                                    (p[2] - p[1]).norm() * (p[0] - p[1]).norm(),
                                    (p[0] - p[2]).norm() * (p[1] - p[2]).norm()});
      EXPECT_NEAR(g.area, exact, 8 * 2.3e-16 * e1e2) << "scale " << scale << " rep " << rep;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// average_normal

// exponent_of and times_pow2 stand in for std::ilogb and std::ldexp inside triangle_geometry;
// they must give the same values bit for bit everywhere: normal and subnormal x, both signs,
// the ends of the exponent range, results that overflow or become subnormal, and random ones.
TEST(ClusterMetricsTriangle, ExponentHelpersEqualIlogbAndLdexpBitForBit) {
  std::vector<double> xs{1.0, -1.0, 0.75, 3.0, std::numeric_limits<double>::max(), std::numeric_limits<double>::min(),
                         std::numeric_limits<double>::denorm_min(), -std::numeric_limits<double>::denorm_min(),
                         std::numeric_limits<double>::min() / 3.0, 1e-310, -2.5e-320, 1e300, -1e-300, 0.1, 1.0 / 3.0};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> mant(0.5, 1.0);
  std::uniform_int_distribution<int> ex(-1080, 1030);
  for (int i = 0; i < 2000; ++i) xs.push_back((i % 2 ? -1.0 : 1.0) * std::ldexp(mant(rng), ex(rng)));
  std::vector<int> ks{-2200, -1075, -1074, -1023, -1022, -1021, -1, 0, 1, 1022, 1023, 1024, 2200};
  for (int i = 0; i < 200; ++i) ks.push_back(ex(rng));
  for (double x : xs) {
    if (x == 0.0) continue;
    if (std::isfinite(x)) {
      ASSERT_EQ(exponent_of(x), std::ilogb(x)) << x;  // its contract: finite x != 0
    }
    for (int k : ks) {
      const double want = std::ldexp(x, k), got = times_pow2(x, k);
      ASSERT_EQ(std::bit_cast<std::uint64_t>(got), std::bit_cast<std::uint64_t>(want)) << x << " * 2^" << k;
    }
  }
}

TEST(ClusterMetricsNormal, EmptyAndAllZeroGiveUnitZFallback) {
  const NormalAverage e = average_normal({}, {});
  EXPECT_TRUE(e.fallback);
  EXPECT_EQ(e.n, Vec3::UnitZ());
  const std::vector<Vec3> zeros(3, Vec3::Zero());
  const std::vector<double> areas(3, 0.0);
  const NormalAverage z = average_normal(zeros, areas);
  EXPECT_TRUE(z.fallback);
  EXPECT_EQ(z.n, Vec3::UnitZ());
}

TEST(ClusterMetricsNormal, SizeMismatchThrows) {
  const std::vector<Vec3> n{Vec3::UnitX()};
  const std::vector<double> a{1.0, 2.0};
  EXPECT_THROW((void)average_normal(n, a), std::invalid_argument);
}

TEST(ClusterMetricsNormal, CancellingNormalsPickLargestAreaLowestIndex) {
  // Sum vanishes exactly; largest area 5 at indices 2 and 3 -> index 2 (+y).
  const std::vector<Vec3> n{Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  const std::vector<double> a{1, 1, 5, 5, 2, 2};
  const NormalAverage r = average_normal(n, a);
  EXPECT_TRUE(r.fallback);
  EXPECT_EQ(r.n, Vec3::UnitY());
  // Areas within 1e-12 relative are tied: index 0 wins although index 1 is larger by 1e-14.
  const std::vector<double> b{5 * (1 - 1e-14), 5, 1, 1, 1, 1};
  EXPECT_EQ(average_normal(n, b).n, Vec3::UnitX());
  // Zero normals do not count even with a large area.
  std::vector<Vec3> n2 = n;
  n2.push_back(Vec3::Zero());
  std::vector<double> a2 = a;
  a2.push_back(100);
  EXPECT_EQ(average_normal(n2, a2).n, Vec3::UnitY());
}

TEST(ClusterMetricsNormal, NonCancellingSumIsNormalised) {
  const std::vector<Vec3> n{Vec3::UnitX(), Vec3::UnitY(), Vec3::Zero()};
  const std::vector<double> a{1, 7, 0};
  const NormalAverage r = average_normal(n, a);
  EXPECT_FALSE(r.fallback);
  EXPECT_NEAR((r.n - Vec3(1, 1, 0) / std::sqrt(2.0)).norm(), 0.0, 1e-16);
  // Just above the threshold (|sum| = 2e-9 for m = 1... use two nearly opposite normals).
  const Vec3 e = Vec3(1, 3e-9, 0).normalized(), f = Vec3(-1, 3e-9, 0).normalized();
  const std::vector<Vec3> nn{e, f};
  const std::vector<double> aa{1, 1};
  const NormalAverage s = average_normal(nn, aa);  // |sum| ~ 6e-9 > 2e-9
  EXPECT_FALSE(s.fallback);
  EXPECT_NEAR((s.n - Vec3::UnitY()).norm(), 0.0, 1e-6);
  const Vec3 g = Vec3(1, 5e-10, 0).normalized(), h = Vec3(-1, 5e-10, 0).normalized();
  const std::vector<Vec3> n3{g, h};
  EXPECT_TRUE(average_normal(n3, aa).fallback);  // |sum| ~ 1e-9 <= 2e-9
}

// ---------------------------------------------------------------------------------------------
// Degenerate clusters

TEST(ClusterMetricsEmpty, EmptyClusterGivesDocumentedEmptyResult) {
  const Mesh m = fan(6);
  const ClusterMetrics e = cluster_metrics(m, {});
  EXPECT_EQ(e.triangles, 0u);
  EXPECT_EQ(e.vertices, 0u);
  EXPECT_TRUE(e.sphere.is_empty());
  EXPECT_EQ(e.area, 0.0);
  EXPECT_EQ(e.area_c, 0.0);
  EXPECT_EQ(e.area_p, 0.0);
  EXPECT_EQ(e.reg, 0.0);
  EXPECT_EQ(e.n_avg, Vec3::UnitZ());
  EXPECT_TRUE(e.n_avg_fallback);
  EXPECT_EQ(e.connectivity, 0.0);
  EXPECT_TRUE(e.box.empty());
  EXPECT_EQ(e.naive, 0.0);
  EXPECT_EQ(e.p_hit, 0.0);
  const ClusterParams p{.max_count = 10, .max_size = 2, .avg_sa = 1};
  EXPECT_EQ(cluster_acc(e, p), 0.0);
  EXPECT_EQ(cluster_acc(Mesh(), {}, p), 0.0);
}

TEST(ClusterMetricsEmpty, BadIdsThrow) {
  const Mesh m = fan(4);
  const std::vector<std::uint32_t> out{0, 4};
  const std::vector<std::uint32_t> dup{1, 2, 1};
  EXPECT_THROW((void)cluster_metrics(m, out), std::invalid_argument);
  EXPECT_THROW((void)cluster_metrics(m, dup), std::invalid_argument);
}

TEST(ClusterMetricsDegenerate, SliverZeroAreaAndRepeatedIndexInOneCluster) {
  // good: right angle at (0,1,0) on the hypotenuse (-1,0,0)-(1,0,0): minimal sphere center 0, R 1.
  // zero-area: (-1,0,0) (1,0,0) (0,0,0) collinear; repeated index (3,3,1);
  // sliver: (-1,0,0) (1,0,0) (0,0,1e-9), normal -y, area 1e-9 (largest-angle sine ~2e-9: kept).
  const std::vector<Vec3> p{{-1, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {0, 0, 1e-9}};
  const Mesh m({{0, 1, 2}, {0, 1, 3}, {3, 3, 1}, {0, 1, 4}}, p);
  for (SphereMethod s : {SphereMethod::Cgal, SphereMethod::Exact}) {
    const ClusterMetrics c = metrics_of(m, s);
    EXPECT_EQ(c.triangles, 4u);
    EXPECT_EQ(c.vertices, 5u);
    EXPECT_DOUBLE_EQ(c.connectivity, 0.8);
    EXPECT_NEAR(c.sphere.radius, 1.0, 1e-14);
    EXPECT_NEAR(c.area, 1.0 + 1e-9, 1e-15);
    // The sliver's unit normal counts fully in N_avg (method.md: unweighted sum of unit normals).
    EXPECT_FALSE(c.n_avg_fallback);
    EXPECT_NEAR((c.n_avg - Vec3(0, -1, 1) / std::sqrt(2.0)).norm(), 0.0, 1e-7);
    const double area_p = (1.0 + 1e-9) / std::sqrt(2.0);
    EXPECT_NEAR(c.area_p, area_p, 1e-8);
    EXPECT_NEAR(c.reg, area_p / pi, 1e-8);
    // box [-1,1] x [0,1] x [0,1e-9]: SA = 2 (2 + 1e-9 + 2e-9)
    EXPECT_NEAR(c.naive, 2.0 * (1.0 + 1e-9) / (2.0 * (2.0 + 3e-9)), 1e-15);
    EXPECT_EQ(c.p_hit, c.naive);
  }
}

TEST(ClusterMetricsDegenerate, OnlyDegenerateTrianglesGiveZerosNotNaN) {
  // Collinear along x: box is a segment (SA 0), every area 0, sphere radius 1.5.
  const std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}, {3, 0, 0}};
  const Mesh m({{0, 1, 2}, {0, 0, 2}, {1, 1, 1}}, p);
  const ClusterMetrics c = metrics_of(m);
  EXPECT_EQ(c.vertices, 3u);
  EXPECT_EQ(c.area, 0.0);
  EXPECT_EQ(c.area_p, 0.0);
  EXPECT_EQ(c.reg, 0.0);
  EXPECT_TRUE(c.n_avg_fallback);
  EXPECT_EQ(c.n_avg, Vec3::UnitZ());
  EXPECT_NEAR(c.sphere.radius, 1.5, 1e-15);
  EXPECT_EQ(c.naive, 0.0);
  EXPECT_EQ(c.p_hit, 0.0);
  // All three corners identical: sphere radius 0, AreaC 0 -> reg 0, box SA 0 -> naive 0.
  const Mesh pt({{0, 1, 2}}, {Vec3(2, 3, 4), Vec3(2, 3, 4), Vec3(2, 3, 4)});
  const ClusterMetrics d = metrics_of(pt);
  EXPECT_EQ(d.vertices, 3u);  // distinct indices, not distinct positions
  EXPECT_EQ(d.area_c, 0.0);
  EXPECT_EQ(d.reg, 0.0);
  EXPECT_EQ(d.naive, 0.0);
  EXPECT_EQ(d.p_hit, 0.0);
}

// ---------------------------------------------------------------------------------------------
// reg

TEST(ClusterMetricsReg, EquilateralTriangleAtManyPosesAndScales) {
  // (1,0,0) (0,1,0) (0,0,1) is exactly equilateral (side sqrt 2) in double; power-of-two scales
  // and integer offsets keep it exact, so the answer is the closed form to rounding.
  const Vec3 base[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  struct Pose {
    double scale;
    Vec3 offset;
  };
  const std::vector<Pose> poses{{1.0, Vec3::Zero()},
                                {std::ldexp(1.0, -100), Vec3::Zero()},  // ~7.9e-31
                                {1e-30, Vec3::Zero()},
                                {1e30, Vec3::Zero()},
                                {std::ldexp(1.0, 100), Vec3::Zero()},  // ~1.3e30
                                {std::ldexp(1.0, -10), Vec3(1e7, 1e7, 1e7)},  // 1e7 offset, ~1.4e-3 sides
                                {std::ldexp(1.0, -10), Vec3(-1e7, 3e7, 5e6)},
                                {1e30, Vec3(1e31, -1e31, 0)}};
  // Orientations that keep the corners exact: axis permutations with sign flips.
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const Pose& pose : poses)
    for (const auto& perm : perms)
      for (int signs = 0; signs < 8; ++signs) {
        std::vector<Vec3> p;
        for (const Vec3& b : base) {
          Vec3 q;
          for (int a = 0; a < 3; ++a) q[a] = ((signs >> a) & 1 ? -1.0 : 1.0) * b[perm[a]];
          p.push_back(pose.offset + pose.scale * q);
        }
        const Mesh m({{0, 1, 2}}, p);
        for (SphereMethod s : {SphereMethod::Cgal, SphereMethod::Exact}) {
          const ClusterMetrics c = metrics_of(m, s);
          EXPECT_NEAR(c.reg / kRegEquilateral, 1.0, 1e-12) << "scale " << pose.scale << " offset "
                                                           << pose.offset.transpose() << " method " << to_string(s);
          EXPECT_FALSE(c.n_avg_fallback);
        }
      }
  // Generic rotations (inexact corners): against the exact-kernel oracle of the rounded corners.
  std::mt19937_64 rng(3);
  for (int rep = 0; rep < 50; ++rep) {
    const Eigen::Matrix3d R = random_rotation(rng);
    const Vec3 t = 5.0 * Vec3::Random();
    std::vector<Vec3> p;
    for (const Vec3& b : base) p.push_back(R * b + t);
    const Mesh m({{0, 1, 2}}, p);
    const ClusterMetrics c = metrics_of(m);
    EXPECT_NEAR(c.reg / exact_reg_acute(p[0], p[1], p[2]), 1.0, 1e-12);
    EXPECT_NEAR(c.reg / kRegEquilateral, 1.0, 1e-12);
  }
}

TEST(ClusterMetricsReg, RandomAcuteTrianglesMatchExactKernel) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int tested = 0;
  while (tested < 300) {
    Vec3 p[3];
    for (Vec3& q : p) q = Vec3(u(rng), u(rng), u(rng));
    // keep clearly acute triangles (the oracle is the circumsphere)
    bool acute = true;
    for (int i = 0; i < 3; ++i)
      acute = acute && (p[(i + 1) % 3] - p[i]).dot(p[(i + 2) % 3] - p[i]) >
                           0.05 * (p[(i + 1) % 3] - p[i]).norm() * (p[(i + 2) % 3] - p[i]).norm();
    if (!acute) continue;
    ++tested;
    const Vec3 off = tested % 2 ? Vec3(1e7, -2e7, 4e6) : Vec3::Zero();
    const double sc = tested % 2 ? 1e-3 : 1.0;
    std::vector<Vec3> pts{off + sc * p[0], off + sc * p[1], off + sc * p[2]};
    const Mesh m({{0, 1, 2}}, pts);
    EXPECT_NEAR(metrics_of(m).reg / exact_reg_acute(pts[0], pts[1], pts[2]), 1.0, 1e-12) << tested;
  }
}

TEST(ClusterMetricsReg, ClosedTetrahedronTakesTheFallback) {
  // Sum of the four unit normals vanishes -> fallback: normal of the largest-area triangle,
  // all four tie -> face 0 -> (1,1,-1)/sqrt3. Then AreaP = A (1 + 3 * 1/3) = 2A with
  // A = 2 sqrt3 (edge 2 sqrt2), R = sqrt3, AreaC = 3 pi: reg = 4 sqrt3 / (3 pi).
  const Mesh m = tetrahedron();
  const double reg = 4.0 * std::sqrt(3.0) / (3.0 * pi);
  const Vec3 n0 = Vec3(1, 1, -1) / std::sqrt(3.0);
  const ClusterMetrics c = metrics_of(m);
  EXPECT_TRUE(c.n_avg_fallback);
  EXPECT_LT((c.n_avg - n0).norm(), 1e-15);
  EXPECT_NEAR(c.area, 8.0 * std::sqrt(3.0), 1e-13);
  EXPECT_NEAR(c.area_p, 4.0 * std::sqrt(3.0), 1e-13);
  EXPECT_NEAR(c.reg, reg, 1e-14);
  EXPECT_DOUBLE_EQ(c.connectivity, 1.0);
  // Deterministic: the same input twice gives bit-identical output.
  const ClusterMetrics c2 = metrics_of(m);
  EXPECT_EQ(c2.n_avg, c.n_avg);
  EXPECT_EQ(c2.reg, c.reg);
  // The rule follows the cluster's order of triangles: listing face 2 first picks face 2's normal.
  const std::vector<std::uint32_t> order{2, 0, 1, 3};
  EXPECT_LT((cluster_metrics(m, order).n_avg - Vec3(-1, 1, 1) / std::sqrt(3.0)).norm(), 1e-15);
  // Rotation-equivariant: rotated tetrahedra give the rotated face-0 normal and the same reg.
  std::mt19937_64 rng(17);
  for (int rep = 0; rep < 30; ++rep) {
    const Eigen::Matrix3d R = random_rotation(rng);
    const Vec3 t = 10.0 * Vec3::Random();
    const ClusterMetrics r = metrics_of(transformed(m, R, t));
    EXPECT_TRUE(r.n_avg_fallback);
    EXPECT_LT((r.n_avg - R * n0).norm(), 1e-12);
    EXPECT_NEAR(r.reg / reg, 1.0, 1e-12);
  }
}

TEST(ClusterMetricsReg, ClosedCuboidFallbackPicksLargestFace) {
  // Box 1 x 2 x 3: opposite faces cancel; the largest triangles (area 3) lie on the two 2 x 3 faces
  // (x = 0 listed first, outward -x).
  const std::vector<Vec3> v{{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {1, 2, 0}, {0, 0, 3}, {1, 0, 3}, {0, 2, 3}, {1, 2, 3}};
  const std::vector<Tri> t{{0, 2, 1}, {1, 2, 3},   // z = 0, -z, area 1 each
                           {0, 1, 4}, {1, 5, 4},   // y = 0, -y, area 1.5
                           {0, 4, 2}, {2, 4, 6},   // x = 0, -x, area 3
                           {4, 5, 6}, {5, 7, 6},   // z = 3, +z
                           {2, 6, 3}, {3, 6, 7},   // y = 2, +y
                           {1, 3, 5}, {3, 7, 5}};  // x = 1, +x
  const Mesh m(t, v);
  const ClusterMetrics c = metrics_of(m);
  EXPECT_TRUE(c.n_avg_fallback);
  EXPECT_EQ(c.n_avg, Vec3(-1, 0, 0));
  // AreaP = the two x faces (2*6); R = sqrt(14)/2; reg = 12 / (pi 14/4).
  EXPECT_NEAR(c.area_p, 12.0, 1e-14);
  EXPECT_NEAR(c.reg, 12.0 / (pi * 3.5), 1e-14);
  EXPECT_NEAR(c.naive, 2.0 * 22.0 / 22.0, 1e-15);  // closed box: every line crosses twice
}

TEST(ClusterMetricsReg, FlatFanApproachesOne) {
  // Regular n-gon of radius r: AreaP = Area = (n/2) r^2 sin(2 pi / n), R = r (circumcircle; the
  // center lies inside), so reg = n sin(2 pi / n) / (2 pi) -> 1 from below, 1 - reg ~ (2 pi/n)^2 / 6.
  double prev = 0;
  std::mt19937_64 rng(23);
  for (int n : {3, 4, 5, 8, 64, 1024, 4096}) {
    const double expected = n * std::sin(2.0 * pi / n) / (2.0 * pi);
    const Mesh m = transformed(fan(n, 2.5), random_rotation(rng), Vec3(3, -4, 5));
    const ClusterMetrics c = metrics_of(m);
    EXPECT_FALSE(c.n_avg_fallback);
    EXPECT_NEAR(c.reg / expected, 1.0, 1e-12) << n;
    EXPECT_GT(c.reg, prev);
    EXPECT_LT(c.reg, 1.0);
    prev = c.reg;
  }
  EXPECT_NEAR(prev, 1.0, 1e-6);  // n = 4096: 1 - reg = 3.9e-7
  // n = 3 is the single equilateral triangle's value.
  EXPECT_NEAR(metrics_of(fan(3)).reg / kRegEquilateral, 1.0, 1e-12);
}

TEST(ClusterMetricsReg, CurvedCapsExceedOne) {
  // Caps of a sphere of radius R with an equator ring (antipodal points): minimal sphere = R.
  // N_avg = +z by symmetry, so AreaP = sum Area_i |n_i.z| = the projected areas: the hemisphere
  // projects to a disc (reg -> 1 from below); a cap to 135 degrees adds the annulus below the
  // equator, pi R^2 (1 - sin^2 45) = pi R^2 / 2: reg -> 1.5 (> 1).
  const double R = 1.7;
  for (const auto& [theta, rings, limit] : std::vector<std::tuple<double, int, double>>{
           {pi / 2, 32, 1.0}, {3 * pi / 4, 48, 1.5}}) {
    const Mesh m = uv_cap(R, theta, rings, 128);
    const ClusterMetrics c = metrics_of(m);
    EXPECT_FALSE(c.n_avg_fallback);
    EXPECT_LT((c.n_avg - Vec3::UnitZ()).norm(), 1e-14);
    EXPECT_NEAR(c.sphere.radius, R, 1e-14);
    double projected = 0;  // independent: |z| of the cross products
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const auto q = m.corners(t);
      projected += 0.5 * std::abs((q[1] - q[0]).cross(q[2] - q[0]).z());
    }
    EXPECT_NEAR(c.area_p / projected, 1.0, 1e-12);
    EXPECT_NEAR(c.reg / (projected / (pi * R * R)), 1.0, 1e-12);
    EXPECT_LT(c.reg, limit);
    EXPECT_GT(c.reg, limit - 0.01);
  }
  EXPECT_GT(metrics_of(uv_cap(R, 3 * pi / 4, 48, 128)).reg, 1.0);
}

TEST(ClusterMetricsReg, RigidMotionInvariance) {
  // Random height-field patch, 8 x 8 quads, rotated and translated: every invariant equal to
  // 1e-12 relative, N_avg rotated.
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<Vec3> p;
  for (int j = 0; j <= 8; ++j)
    for (int i = 0; i <= 8; ++i) p.emplace_back(i + 0.2 * u(rng), j + 0.2 * u(rng), u(rng));
  std::vector<Tri> t;
  for (std::uint32_t j = 0; j < 8; ++j)
    for (std::uint32_t i = 0; i < 8; ++i) {
      const std::uint32_t a = j * 9 + i;
      t.push_back({a, a + 1, a + 10});
      t.push_back({a, a + 10, a + 9});
    }
  const Mesh m(t, p);
  const ClusterParams params{.max_count = 60, .max_size = 3, .avg_sa = 5};
  std::vector<std::uint32_t> ids;  // a sub-patch
  for (std::uint32_t i = 0; i < t.size(); i += 1)
    if (i % 16 < 10) ids.push_back(i);
  const ClusterMetrics c0 = cluster_metrics(m, ids);
  for (int rep = 0; rep < 20; ++rep) {
    const Eigen::Matrix3d R = random_rotation(rng);
    const Vec3 tr(17.0 * u(rng), -23.0 * u(rng), 31.0 * u(rng));
    const Mesh mt = transformed(m, R, tr);
    const ClusterMetrics c = cluster_metrics(mt, ids);
    EXPECT_EQ(c.vertices, c0.vertices);
    EXPECT_NEAR(c.area / c0.area, 1.0, 1e-12);
    EXPECT_NEAR(c.area_p / c0.area_p, 1.0, 1e-12);
    EXPECT_NEAR(c.sphere.radius / c0.sphere.radius, 1.0, 1e-12);
    EXPECT_NEAR(c.reg / c0.reg, 1.0, 1e-12);
    EXPECT_LT((c.n_avg - R * c0.n_avg).norm(), 1e-12);
    EXPECT_NEAR(cluster_acc(c, params) / cluster_acc(c0, params), 1.0, 1e-12);
    for (SizeBoundMode mode : {SizeBoundMode::Max, SizeBoundMode::Min}) {
      ClusterParams pm = params;
      pm.size_bound_mode = mode;
      EXPECT_NEAR(cluster_acc(mt, ids, pm) / cluster_acc(m, ids, pm), 1.0, 1e-12);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Connectivity

TEST(ClusterMetricsConnectivity, FanStripAndSubsetsByHand) {
  EXPECT_DOUBLE_EQ(metrics_of(fan(6)).connectivity, 6.0 / 7.0);
  EXPECT_DOUBLE_EQ(metrics_of(fan(20)).connectivity, 20.0 / 21.0);
  const Mesh s = strip(5);  // 10 triangles, 12 vertices
  EXPECT_EQ(metrics_of(s).triangles, 10u);
  EXPECT_EQ(metrics_of(s).vertices, 12u);
  EXPECT_DOUBLE_EQ(metrics_of(s).connectivity, 10.0 / 12.0);
  // First three triangles of the strip: vertices 0..4 -> 3/5.
  const std::vector<std::uint32_t> first3{0, 1, 2};
  EXPECT_DOUBLE_EQ(cluster_metrics(s, first3).connectivity, 3.0 / 5.0);
  // Two disjoint triangles of the fan share the center: 2 triangles, 5 vertices.
  const std::vector<std::uint32_t> apart{0, 3};
  EXPECT_DOUBLE_EQ(cluster_metrics(fan(6), apart).connectivity, 2.0 / 5.0);
}

// ---------------------------------------------------------------------------------------------
// regBound, sizeBound, Acc

TEST(ClusterMetricsBounds, SmallFunctionsByHand) {
  EXPECT_DOUBLE_EQ(reg_bound(30, 50), 0.6);
  EXPECT_EQ(reg_bound(0, 10), 0.0);
  // SA = 12, MaxSize 2, AvgSA 3: ratio 2.
  EXPECT_EQ(size_bound(12, 2, 3, SizeBoundMode::Max), 2.0);
  EXPECT_EQ(size_bound(12, 2, 3, SizeBoundMode::Min), 1.0);
  // SA = 3: ratio 0.5.
  EXPECT_EQ(size_bound(3, 2, 3, SizeBoundMode::Max), 1.0);
  EXPECT_EQ(size_bound(3, 2, 3, SizeBoundMode::Min), 0.5);
  EXPECT_EQ(size_bound(3, 2, 3), 1.0);  // default Max as printed in the paper
  EXPECT_EQ(size_bound(0, 2, 3, SizeBoundMode::Min), 0.0);
  EXPECT_DOUBLE_EQ(acc(0.8, 0.6, 2.0), -0.4);
  EXPECT_DOUBLE_EQ(acc(0.8, 0.6, 0.5), 0.5);
}

TEST(ClusterMetricsBounds, NonPositiveParametersThrow) {
  const double nan = std::nan("");
  for (double bad : {0.0, -1.0, nan, std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW((void)reg_bound(3, bad), std::invalid_argument);
    EXPECT_THROW((void)size_bound(1, bad, 1), std::invalid_argument);
    EXPECT_THROW((void)size_bound(1, 1, bad), std::invalid_argument);
  }
  EXPECT_THROW((void)size_bound(-1, 1, 1), std::invalid_argument);
  EXPECT_THROW((void)size_bound(nan, 1, 1), std::invalid_argument);
  const Mesh m = fan(3);
  const ClusterMetrics c = metrics_of(m);
  EXPECT_THROW((void)cluster_acc(c, ClusterParams{.max_count = 0, .max_size = 1, .avg_sa = 1}), std::invalid_argument);
  EXPECT_THROW((void)cluster_acc(c, ClusterParams{.max_count = 1, .max_size = 0, .avg_sa = 1}), std::invalid_argument);
  EXPECT_THROW((void)cluster_acc(c, ClusterParams{.max_count = 1, .max_size = 1}), std::invalid_argument);  // avg_sa unset
}

TEST(ClusterMetricsBounds, ClusterAccOfEquilateralTriangleByHand) {
  // Side s: R = s / sqrt3, SA = 4 pi s^2 / 3; reg = 3 sqrt3 / (4 pi); 3 vertices.
  const double s = std::sqrt(2.0);
  const Mesh m({{0, 1, 2}}, {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)});
  const ClusterMetrics c = metrics_of(m);
  const double sa = 4.0 * pi * s * s / 3.0;
  EXPECT_NEAR(c.sphere.radius, s / std::sqrt(3.0), 1e-15);
  // MaxCount 10 -> regBound 0.3. AvgSA = SA, MaxSize 2 -> ratio 0.5.
  ClusterParams p{.max_count = 10, .max_size = 2, .avg_sa = sa};
  EXPECT_NEAR(cluster_acc(c, p), kRegEquilateral - 0.3 * 1.0, 1e-14);
  p.size_bound_mode = SizeBoundMode::Min;
  EXPECT_NEAR(cluster_acc(c, p), kRegEquilateral - 0.3 * 0.5, 1e-14);
  // AvgSA = SA / 4 -> ratio 2.
  p.avg_sa = sa / 4;
  EXPECT_NEAR(cluster_acc(c, p), kRegEquilateral - 0.3 * 1.0, 1e-14);
  p.size_bound_mode = SizeBoundMode::Max;
  EXPECT_NEAR(cluster_acc(c, p), kRegEquilateral - 0.3 * 2.0, 1e-14);
  p.sphere = SphereMethod::Exact;
  EXPECT_NEAR(cluster_acc(m, all_ids(1), p), kRegEquilateral - 0.6, 1e-14);
}

// ---------------------------------------------------------------------------------------------
// Naive(k) / P_hit

TEST(ClusterMetricsNaive, RightTriangleInAxisPlaneIsExactlyHalf) {
  // legs 3 and 7: 2 * 10.5 / (2 * 21) = 0.5, exactly in double.
  for (int axis = 0; axis < 3; ++axis) {
    Vec3 a = Vec3::Zero(), b = Vec3::Zero(), c = Vec3::Zero();
    b[(axis + 1) % 3] = 3;
    c[(axis + 2) % 3] = 7;
    a[axis] = b[axis] = c[axis] = 5;  // in the plane coordinate = 5
    const ClusterMetrics m = metrics_of(Mesh({{0, 1, 2}}, {a, b, c}));
    EXPECT_EQ(m.naive, 0.5);
    EXPECT_EQ(m.p_hit, 0.5);
  }
}

TEST(ClusterMetricsNaive, AnyTriangleInItsBoxIsInZeroHalf) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0;
  for (int rep = 0; rep < 2000; ++rep) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const ClusterMetrics m = metrics_of(Mesh({{0, 1, 2}}, {a, b, c}));
    Box3 box;
    box.extend(a), box.extend(b), box.extend(c);
    const double expected = (b - a).cross(c - a).norm() / box.surface_area();  // 2 * Area / SA
    EXPECT_NEAR(m.p_hit, expected, 1e-14);
    EXPECT_GT(m.p_hit, 0.0);
    EXPECT_LE(m.p_hit, 0.5);
    worst = std::max(worst, m.p_hit);
  }
  EXPECT_GT(worst, 0.3);  // the sample reaches into the range
}

TEST(ClusterMetricsNaive, DiscBetweenPiOver8AndPiOver4) {
  // The paper's "disc: >= pi/12" is the bound from the disc's box lying inside the cube of its
  // sphere (2 pi r^2 / 24 r^2). The geometry gives more: an axis-aligned disc has a flat 2r x 2r
  // box, P = 2 pi r^2 / 8 r^2 = pi/4; the worst tilt, normal (1,1,1)/sqrt3, has extents
  // 2r sqrt(2/3) on every axis, box SA 16 r^2, P = pi/8. Never pi/12.
  // Axis-aligned regular 4k-gon (vertices on the axes): P = n sin(2 pi/n) / 8, exactly.
  for (int n : {4, 8, 64, 4096}) {
    const ClusterMetrics m = metrics_of(fan(n));
    EXPECT_NEAR(m.p_hit / (n * std::sin(2 * pi / n) / 8.0), 1.0, 1e-13) << n;
  }
  EXPECT_NEAR(metrics_of(fan(4096)).p_hit, pi / 4, 1e-6);
  // Tilted to normal (1,1,1)/sqrt3.
  const Eigen::Matrix3d tilt = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), Vec3(1, 1, 1)).toRotationMatrix();
  EXPECT_NEAR(metrics_of(transformed(fan(4096), tilt, Vec3(1, 2, 3))).p_hit, pi / 8, 1e-5);
  // Random orientations stay in [pi/8, pi/4] up to the polygon's deficit.
  std::mt19937_64 rng(37);
  const Mesh disc = fan(1024);
  for (int rep = 0; rep < 200; ++rep) {
    const double p = metrics_of(transformed(disc, random_rotation(rng), Vec3::Zero())).p_hit;
    EXPECT_GE(p, pi / 8 - 1e-4);
    EXPECT_LE(p, pi / 4);
    EXPECT_GT(p, pi / 12);
  }
}

TEST(ClusterMetricsNaive, ClosedSphereCountsBothCrossings) {
  // The paper's sphere pi/6 is the probability of a hit; sum 2 Area_i / SA(box) of a closed
  // tessellated sphere tends to 2 * 4 pi R^2 / 24 R^2 = pi/3, the expected number of crossings.
  const double R = 2.0;
  const Mesh m = uv_cap(R, pi, 128, 256);  // equator ring and poles on the axes: box = cube 2R
  const ClusterMetrics c = metrics_of(m);
  EXPECT_NEAR(c.box.surface_area(), 24 * R * R, 1e-12);
  EXPECT_NEAR(c.naive, 2 * c.area / (24 * R * R), 1e-15);
  EXPECT_NEAR(c.naive, pi / 3, 1e-3);
  EXPECT_LT(c.naive, pi / 3);
  EXPECT_EQ(c.p_hit, c.naive);
}

}  // namespace
}  // namespace ptc
