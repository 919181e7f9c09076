// analyze_mesh against hand-counted answers on small meshes built for each defect.
#include "toolkit/mesh/mesh_report.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "toolkit/geometry/triangle.h"

#include <CGAL/Gmpq.h>

namespace ptc {
namespace {

Mesh unit_cube() {
  std::vector<Vec3> p;
  for (int i = 0; i < 8; ++i) p.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  std::vector<Tri> t{{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                     {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return Mesh(t, p);
}

TEST(MeshReport, SummaryOfEmptyAndOddEven) {
  EXPECT_EQ(summarize({}).count, 0u);
  std::vector<double> odd{3, 1, 2};
  auto s = summarize(odd);
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.max, 3);
  EXPECT_EQ(s.p50, 2);
  EXPECT_EQ(s.mean, 2);
  std::vector<double> even{4, 1, 3, 2};
  EXPECT_EQ(summarize(even).p50, 2.5);
  // 0..100: percentile p is exactly p (linear interpolation between order statistics).
  std::vector<double> hundred;
  for (int i = 100; i >= 0; --i) hundred.push_back(i);
  const auto h = summarize(hundred);
  EXPECT_EQ(h.p5, 5);
  EXPECT_EQ(h.p50, 50);
  EXPECT_EQ(h.p95, 95);
  EXPECT_EQ(h.mean, 50);
  std::vector<double> one{7};
  EXPECT_EQ(summarize(one).p5, 7);
  EXPECT_EQ(summarize(one).p95, 7);
}

TEST(MeshReport, ClosedCube) {
  const auto r = analyze_mesh(unit_cube());
  EXPECT_EQ(r.vertices, 8u);
  EXPECT_EQ(r.triangles, 12u);
  EXPECT_EQ(r.edges, 18u);
  EXPECT_EQ(r.boundary_edges, 0u);
  EXPECT_EQ(r.non_manifold_edges, 0u);
  EXPECT_EQ(r.non_manifold_vertices, 0u);
  EXPECT_TRUE(r.closed_manifold());
  EXPECT_EQ(r.euler_characteristic(), 2);
  EXPECT_DOUBLE_EQ(r.total_area, 6.0);
  EXPECT_DOUBLE_EQ(r.triangle_area.min, 0.5);
  EXPECT_DOUBLE_EQ(r.triangle_area.max, 0.5);
  EXPECT_DOUBLE_EQ(r.edge_length.min, 1.0);
  EXPECT_DOUBLE_EQ(r.edge_length.max, std::sqrt(2.0));
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.edge_components, 1u);
  EXPECT_EQ(r.bounds.lo, Vec3(0, 0, 0));
  EXPECT_EQ(r.bounds.hi, Vec3(1, 1, 1));
}

TEST(MeshReport, EveryDefectCountedOnce) {
  std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}, {0, 1, 0},   // 0-2 a triangle
                      {2, 0, 0},                          // 3 collinear with 0,1
                      {0, 0, 0},                          // 4 duplicate of vertex 0 (coordinates)
                      {-0.0, 1, 0},                       // 5 duplicate of vertex 2 (-0 == 0)
                      {9, 9, 9},                          // 6 unreferenced
                      {0, 0, 1}, {0, 0, 2}};              // 7,8 fan through edge (0,1)
  std::vector<Tri> t{{0, 1, 2},    // ok
                     {0, 1, 3},    // zero area (collinear)
                     {0, 0, 2},    // repeated index
                     {2, 1, 0},    // duplicate of triangle 0 (same vertex set)
                     {4, 5, 1},    // uses duplicate vertices: a separate vertex-component? shares vertex 1
                     {0, 1, 7}, {1, 0, 8}};  // edge (0,1) now has triangles 0,1,3,5,6 -> non-manifold
  const auto r = analyze_mesh(Mesh(t, p));
  EXPECT_EQ(r.triangles, 7u);
  EXPECT_EQ(r.unreferenced_vertices, 1u);
  EXPECT_EQ(r.zero_area_triangles, 1u);
  EXPECT_EQ(r.repeated_index_triangles, 1u);
  EXPECT_EQ(r.duplicate_triangles, 1u);
  EXPECT_EQ(r.duplicate_vertices, 2u);
  // (0,1) carries triangles 0,1,3,5,6 and (0,2) carries 0,2,3: both non-manifold.
  EXPECT_EQ(r.non_manifold_edges, 2u);
  EXPECT_FALSE(r.closed_manifold());
  EXPECT_EQ(r.bounds.hi, Vec3(2, 1, 2));  // the unreferenced vertex (9,9,9) is not in the box
  // Hand count of the edges: (0,1) (0,2) (1,2) (0,3) (1,3) (4,5) (1,5) (1,4) (0,7) (1,7) (0,8) (1,8).
  EXPECT_EQ(r.edges, 12u);
  // Valence 1: (1,2)? no: (1,2) carries 0 and 3. Boundary: (0,3) (1,3) (4,5) (1,5) (1,4) (0,7) (1,7) (0,8) (1,8).
  EXPECT_EQ(r.boundary_edges, 9u);
  // Vertex 1: triangle 4 {4,5,1} touches the rest only at vertex 1 -> a second fan.
  EXPECT_EQ(r.non_manifold_vertices, 1u);
  EXPECT_EQ(r.components, 1u);       // all share vertex 1 (or 0)
  EXPECT_EQ(r.edge_components, 2u);  // triangle 4 is edge-connected to nothing
  EXPECT_EQ(r.near_degenerate_triangles, 0u);
}

TEST(MeshReport, SliverIsNearDegenerateAndHugeCoordinatesStayFinite) {
  std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}, {0.5, 1e-14, 0}, {1e300, 0, 0}, {0, 1e300, 0}};
  const auto r = analyze_mesh(Mesh({{0, 1, 2}, {0, 3, 4}}, p));
  EXPECT_EQ(r.near_degenerate_triangles, 1u);  // sine of the largest angle ~4e-14 < 1e-12
  EXPECT_EQ(r.zero_area_triangles, 0u);
  EXPECT_EQ(r.edge_length.max, std::hypot(1e300, 1e300));  // no overflow in the length
  EXPECT_TRUE(std::isinf(r.total_area));                    // 5e599 is beyond double: inf, not 0
  // Right triangles of 1e-170 units: their area (5e-341) is below the double range, but their
  // sine is 1: not near-degenerate (they were counted so, by their area of 0). The sliver at that
  // scale still is.
  const double s = 1e-170;
  const std::vector<Vec3> q{{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {s, s, 0}, {0.5 * s, 1e-14 * s, 0}};
  const auto tiny = analyze_mesh(Mesh({{0, 1, 2}, {1, 3, 2}, {0, 1, 4}}, q));
  EXPECT_EQ(tiny.near_degenerate_triangles, 1u);
  EXPECT_EQ(tiny.zero_area_triangles, 0u);
}

// Corners near 1e308 of opposite signs: their differences overflow while the corners are finite.
// The triangle is a right isosceles one (legs sqrt(2) 1e308, area 1e616: inf), not degenerate,
// and its edge lengths are sqrt(2) 1e308 (twice) and 2e308 (inf), never NaN.
TEST(MeshReport, CornersWhoseDifferencesOverflow) {
  const std::vector<Vec3> p{{1e308, 0, 0}, {-1e308, 0, 0}, {0, 1e308, 0}};
  const auto r = analyze_mesh(Mesh({{0, 1, 2}}, p));
  EXPECT_EQ(r.near_degenerate_triangles, 0u);
  EXPECT_EQ(r.zero_area_triangles, 0u);
  EXPECT_TRUE(std::isinf(r.total_area) && r.total_area > 0) << r.total_area;
  EXPECT_EQ(r.edge_length.min, std::hypot(1e308, 1e308));
  EXPECT_TRUE(std::isinf(r.edge_length.max));
  EXPECT_FALSE(std::isnan(r.edge_length.mean) || std::isnan(r.edge_length.p5) || std::isnan(r.edge_length.p50));
  // The geometry itself: the normal of the triangle at a quarter of the size, -z ((b - a) x (c - a)
  // = (-2, 0, 0) x (-1, 1, 0) times 1e308^2).
  const TriangleGeometry g = triangle_geometry(p[0], p[1], p[2]);
  EXPECT_EQ(g.normal, Vec3(0, 0, -1));
  EXPECT_TRUE(std::isinf(g.area));
  // At 2^-600 of the size (exact) the area is finite: base 2e308 s, height 1e308 s.
  const double s = std::ldexp(1.0, -600);
  const TriangleGeometry small = triangle_geometry(s * p[0], s * p[1], s * p[2]);
  EXPECT_DOUBLE_EQ(small.area, 0.5 * (2.0 * (1e308 * s)) * (1e308 * s));
  EXPECT_EQ(small.normal, Vec3(0, 0, -1));
  EXPECT_EQ(safe_distance(p[0], p[1]), std::numeric_limits<double>::infinity());
  EXPECT_EQ(safe_distance(p[0], p[2]), std::hypot(1e308, 1e308));
  EXPECT_EQ(safe_distance(Vec3(1, 2, 3), Vec3(4, 6, 3)), 5.0);
  EXPECT_TRUE(std::isnan(safe_distance(Vec3(std::nan(""), 0, 0), Vec3(1e308, 0, 0))));
}

// A triangle collapsed by a repeated corner index has no edges: a mesh of only such faces is
// not a closed manifold (it was reported as one: no boundary edge), nor is a closed cube with one.
TEST(MeshReport, CollapsedTrianglesAreNotAClosedManifold) {
  const std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const auto r = analyze_mesh(Mesh({{0, 0, 0}}, p));
  EXPECT_EQ(r.edges, 0u);
  EXPECT_EQ(r.repeated_index_triangles, 1u);
  EXPECT_FALSE(r.closed_manifold());
  Mesh cube = unit_cube();
  std::vector<Tri> t(cube.triangles().begin(), cube.triangles().end());
  t.push_back({1, 1, 1});  // (collapsed to a point: no side at all, so no edge changes)
  const auto with = analyze_mesh(Mesh(t, std::vector<Vec3>(cube.positions().begin(), cube.positions().end())));
  EXPECT_EQ(with.boundary_edges, 0u);
  EXPECT_FALSE(with.closed_manifold());
  EXPECT_TRUE(analyze_mesh(cube).closed_manifold());
}

TEST(MeshReport, BookOfManyPagesIsFast) {
  // 20000 triangles on one edge: counting non-manifold vertices must not be quadratic.
  std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}};
  std::vector<Tri> t;
  for (std::uint32_t i = 0; i < 20000; ++i) {
    p.emplace_back(0.5, std::cos(i * 1e-4), std::sin(i * 1e-4));
    t.push_back({0, 1, i + 2});
  }
  const auto r = analyze_mesh(Mesh(t, p));
  EXPECT_EQ(r.non_manifold_edges, 1u);
  EXPECT_EQ(r.non_manifold_vertices, 0u);  // every page is linked through the shared edge
  EXPECT_EQ(r.boundary_edges, 40000u);
}

TEST(MeshReport, BowTieIsANonManifoldVertex) {
  std::vector<Vec3> p{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  std::vector<Tri> t{{0, 1, 2}, {0, 3, 4}};
  const auto r = analyze_mesh(Mesh(t, p));
  EXPECT_EQ(r.non_manifold_vertices, 1u);
  EXPECT_EQ(r.non_manifold_edges, 0u);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.edge_components, 2u);
  EXPECT_EQ(r.boundary_edges, 6u);
}

TEST(MeshReport, ExactCollinearityAtHugeOffsetAndTinyScale) {
  // Collinear in exact arithmetic although the double cross product is not exactly zero...
  const Vec3 a(1e7, 1e7, 1e7), d(1e-3, 3e-3, 7e-3);
  const Vec3 b = a + d, c = a + 2 * d;
  EXPECT_TRUE(collinear_exact(a, a, b));
  // ... and b, c may be rounded off the line: the predicate decides on the stored doubles.
  // Oracle: the cross product in exact rational arithmetic (GMP).
  auto exact_collinear = [](const Vec3& p, const Vec3& q, const Vec3& r) {
    using Q = CGAL::Gmpq;
    const Q ux = Q(q.x()) - Q(p.x()), uy = Q(q.y()) - Q(p.y()), uz = Q(q.z()) - Q(p.z());
    const Q vx = Q(r.x()) - Q(p.x()), vy = Q(r.y()) - Q(p.y()), vz = Q(r.z()) - Q(p.z());
    return uy * vz - uz * vy == 0 && uz * vx - ux * vz == 0 && ux * vy - uy * vx == 0;
  };
  EXPECT_EQ(collinear_exact(a, b, c), exact_collinear(a, b, c));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> U(-1, 1);
  for (int i = 0; i < 2000; ++i) {
    // Points on a line through a huge offset, rounded to double: sometimes collinear, sometimes not.
    const Vec3 o(1e7 * U(rng), 1e7 * U(rng), 1e7 * U(rng)), dir(U(rng), U(rng), U(rng));
    const Vec3 p = o + 1e-3 * dir, q = o + 2e-3 * (i % 3 ? dir : Vec3(U(rng), U(rng), U(rng)));
    ASSERT_EQ(collinear_exact(o, p, q), exact_collinear(o, p, q)) << i;
  }
  // A sliver that is not collinear is never reported as zero area.
  EXPECT_FALSE(collinear_exact(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 1e-300, 0)));
  // Tiny scale: exact multiples (power-of-two scaling keeps them exact) are collinear; 1e-30
  // times 3 is not 3e-30 in double, so those stored points are not.
  const double s = std::ldexp(1.0, -100);
  EXPECT_TRUE(collinear_exact(Vec3(1, 2, 3) * s, Vec3(2, 4, 6) * s, Vec3(3, 6, 9) * s));
  EXPECT_EQ(collinear_exact(Vec3(1e-30, 2e-30, 3e-30), Vec3(2e-30, 4e-30, 6e-30), Vec3(3e-30, 6e-30, 9e-30)),
            exact_collinear(Vec3(1e-30, 2e-30, 3e-30), Vec3(2e-30, 4e-30, 6e-30), Vec3(3e-30, 6e-30, 9e-30)));
}

}  // namespace
}  // namespace ptc
