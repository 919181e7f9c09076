#include "analysis/metrics/sphere_accuracy.h"

#include <cmath>
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "toolkit/geometry/morton.h"

namespace ptc {
namespace {

Mesh random_surface(std::size_t n, std::uint64_t seed) {
  // A bumpy height field: realistic, spatially coherent triangles.
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-0.05, 0.05);
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (std::size_t j = 0; j <= n; ++j)
    for (std::size_t i = 0; i <= n; ++i)
      p.emplace_back(double(i), double(j), std::sin(0.3 * double(i)) * std::cos(0.2 * double(j)) + U(rng));
  auto id = [&](std::size_t i, std::size_t j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t i = 0; i < n; ++i) {
      t.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      t.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return Mesh(t, p);
}

TEST(SphereReport, EmptyMeshGivesEmptyReport) {
  const auto r = run_sphere_report(Mesh(), {});
  EXPECT_TRUE(r.exact_radius.empty());
  EXPECT_EQ(sphere_methods_table(r).csv.rows(), r.methods.size());
}

TEST(SphereReport, RejectsBadConfig) {
  SphereReportConfig c;
  c.min_run = 10;
  c.max_run = 5;
  EXPECT_THROW((void)run_sphere_report(random_surface(4, 1), c), std::invalid_argument);
  c = {};
  c.repeats = 0;
  EXPECT_THROW((void)run_sphere_report(random_surface(4, 1), c), std::invalid_argument);
}

TEST(SphereReport, SetsAndErrorsAgainstIndependentRecomputation) {
  const Mesh m = random_surface(20, 2);  // 800 triangles
  SphereReportConfig c;
  c.min_run = c.max_run = 64;
  c.repeats = 1;
  const auto r = run_sphere_report(m, c);
  ASSERT_EQ(r.exact_radius.size(), (800 + 63) / 64);
  // Recompute each set's points from the Morton order and its exact sphere.
  const auto order = morton_order(m.positions(), m.triangles());
  for (std::size_t s = 0; s < r.exact_radius.size(); ++s) {
    std::set<std::uint32_t> verts;
    for (std::uint32_t i = r.run_first[s]; i < r.run_first[s + 1]; ++i)
      for (auto v : m.triangle(order[i])) verts.insert(v);
    std::vector<Vec3> pts;
    for (auto v : verts) pts.push_back(m.position(v));
    EXPECT_EQ(r.run_points[s], pts.size());
    EXPECT_EQ(r.exact_radius[s], min_sphere_exact(pts).radius);
  }
  for (std::size_t mi = 0; mi < r.methods.size(); ++mi) {
    const auto& s = r.methods[mi];
    // Errors recomputed independently from the per-set radii, set by set.
    double mean = 0, mx = -1e300;
    for (std::size_t k = 0; k < r.exact_radius.size(); ++k) {
      const double err = (r.radius[mi][k] - r.exact_radius[k]) / r.exact_radius[k];
      EXPECT_GE(err, -1e-12) << to_string(s.method) << " set " << k;  // never below the minimal radius
      mean += err;
      mx = std::max(mx, err);
    }
    EXPECT_DOUBLE_EQ(s.rel_err_mean, mean / double(r.exact_radius.size())) << to_string(s.method);
    EXPECT_EQ(s.rel_err_max, mx) << to_string(s.method);
    EXPECT_EQ(s.not_containing, 0u) << to_string(s.method);
    EXPECT_GE(s.rel_err_mean, -1e-12) << to_string(s.method);  // nothing beats the minimal sphere
    if (s.method == SphereMethod::Exact) {
      EXPECT_EQ(s.rel_err_max, 0.0);
    }
    if (s.method == SphereMethod::Cgal) {
      EXPECT_LT(s.rel_err_max, 1e-12);
    }
    EXPECT_GT(s.ns_per_sphere_median, 0.0);
  }
  const auto csv = sphere_sets_table(r).csv;
  EXPECT_EQ(csv.rows(), r.methods.size() * r.exact_radius.size());
}

// Far from the origin the sets are measured on local coordinates, as the clustering measures its
// spheres: CGAL's error stays that of the routine (in world coordinates it grew with the offset,
// 1.5e-9 at 2^20 and 5e-6 at 2^32), and the exact radii do not move (an exact translation).
TEST(SphereReport, FarFromTheOriginTheErrorsAreTheRoutines) {
  const Mesh base = random_surface(20, 2);
  std::vector<Vec3> p(base.positions().begin(), base.positions().end());
  for (Vec3& q : p)  // on a 2^-20 grid, so that adding 2^32 is exact
    for (int a = 0; a < 3; ++a) q[a] = std::ldexp(std::round(std::ldexp(q[a], 20)), -20);
  const Mesh near = base.with_positions(p);
  for (Vec3& q : p) q += Vec3(0x1p32, -0x1p32, 0x1p32);
  const Mesh far = base.with_positions(p);
  SphereReportConfig c;
  c.min_run = c.max_run = 64;
  c.repeats = 1;
  const auto rn = run_sphere_report(near, c), rf = run_sphere_report(far, c);
  ASSERT_EQ(rn.exact_radius.size(), rf.exact_radius.size());
  for (std::size_t s = 0; s < rn.exact_radius.size(); ++s) EXPECT_EQ(rf.exact_radius[s], rn.exact_radius[s]) << s;
  for (const auto& m : rf.methods)
    if (m.method == SphereMethod::Cgal) {
      EXPECT_LT(m.rel_err_max, 1e-12);
      EXPECT_EQ(m.not_containing, 0u);
    }
}

// At any scale the report is the unit scale's: every method's radius times the scale (a power
// of two: exactly), the same errors, every sphere containing its points. CGAL answered radius 0
// below ~1e-70 and beyond ~1e70, and at 1e-300 the containment test passed those zero radii
// (distances underflowed). And a set of one repeated point: contained by its radius-0 sphere.
TEST(SphereReport, TinyAndHugeScalesGiveTheUnitScalesReport) {
  const Mesh base = random_surface(12, 5);
  SphereReportConfig c;
  c.min_run = c.max_run = 16;
  c.repeats = 1;
  const auto unit = run_sphere_report(base, c);
  for (const int k : {-1000, -250, 250, 900}) {
    std::vector<Vec3> p(base.positions().begin(), base.positions().end());
    for (Vec3& q : p) q = Vec3(std::ldexp(q.x(), k), std::ldexp(q.y(), k), std::ldexp(q.z(), k));
    const auto r = run_sphere_report(base.with_positions(p), c);
    ASSERT_EQ(r.exact_radius.size(), unit.exact_radius.size());
    for (std::size_t s = 0; s < r.exact_radius.size(); ++s)
      EXPECT_EQ(r.exact_radius[s], std::ldexp(unit.exact_radius[s], k)) << "2^" << k << " set " << s;
    ASSERT_EQ(r.methods.size(), unit.methods.size());
    for (std::size_t m = 0; m < r.methods.size(); ++m) {
      EXPECT_EQ(r.methods[m].rel_err_max, unit.methods[m].rel_err_max) << to_string(r.methods[m].method) << " 2^" << k;
      EXPECT_EQ(r.methods[m].not_containing, 0u) << to_string(r.methods[m].method) << " 2^" << k;
      for (std::size_t s = 0; s < r.exact_radius.size(); ++s)
        EXPECT_EQ(r.radius[m][s], std::ldexp(unit.radius[m][s], k)) << to_string(r.methods[m].method);
    }
  }
  const Mesh point(std::vector<Tri>{{0, 1, 2}}, std::vector<Vec3>{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}});
  for (const auto& m : run_sphere_report(point, c).methods) EXPECT_EQ(m.not_containing, 0u) << to_string(m.method);
}

}  // namespace
}  // namespace ptc
