// The scalar watertight test against an independent double-precision computation, and its
// defining property: no ray passes between two triangles that share an edge.
#include "bvh/watertight.h"

#include <gtest/gtest.h>

#include <random>

namespace ptc::bvh {
namespace {

// Double-precision Moeller-Trumbore: t and barycentrics of the ray/plane hit, no tolerance.
struct Ref {
  bool hit;
  double t, u, v;
  double sine;  // |det| / (|D| |e1| |e2|): small for grazing rays and slivers (ill-conditioned)
};
Ref reference(const Vec3f& o, const Vec3f& d, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const Vec3 O(o[0], o[1], o[2]), D(d[0], d[1], d[2]), A(a[0], a[1], a[2]), B(b[0], b[1], b[2]), C(c[0], c[1], c[2]);
  const Vec3 e1 = B - A, e2 = C - A, p = D.cross(e2);
  const double det = e1.dot(p);
  if (det == 0.0) return {false, 0, 0, 0, 0};
  const Vec3 s = O - A;
  const double u = s.dot(p) / det;
  const Vec3 q = s.cross(e1);
  const double v = D.dot(q) / det, t = e2.dot(q) / det;
  return {u >= 0 && v >= 0 && u + v <= 1 && t > 0, t, u, v, std::abs(det) / (D.norm() * e1.norm() * e2.norm())};
}

Vec3f rnd(std::mt19937& g, float lo, float hi) {
  std::uniform_real_distribution<float> U(lo, hi);
  return {U(g), U(g), U(g)};
}

TEST(Watertight, AgreesWithDoublePrecisionAwayFromEdges) {
  std::mt19937 g(7);
  int hits = 0, checked = 0;
  for (int i = 0; i < 200000; ++i) {
    const Vec3f a = rnd(g, -1, 1), b = rnd(g, -1, 1), c = rnd(g, -1, 1), o = rnd(g, -3, 3);
    Vec3f d = rnd(g, -1, 1);
    if (i % 2) {  // half the rays aimed at a point of the triangle's plane near it
      const Vec3f w = rnd(g, -0.2f, 1.0f);
      for (int k = 0; k < 3; ++k) d[k] = (w[0] * a[k] + w[1] * b[k] + w[2] * c[k]) / (w[0] + w[1] + w[2]) - o[k];
    }
    if (d[0] == 0 && d[1] == 0 && d[2] == 0) continue;
    const Ref ref = reference(o, d, a, b, c);
    const double w0 = 1.0 - ref.u - ref.v;
    // Only rays whose hit point is clearly inside or clearly outside are comparable.
    const double margin = std::min({std::abs(ref.u), std::abs(ref.v), std::abs(w0)});
    if (margin < 1e-4 || std::abs(ref.t) < 1e-4 || ref.sine < 0.05) continue;
    ++checked;
    const auto h = intersect_triangle(make_watertight_ray(o, d), a, b, c, 0.0f, kInf);
    ASSERT_EQ(h.has_value(), ref.hit) << i;
    if (h) {
      ++hits;
      EXPECT_NEAR(h->t, ref.t, 1e-4 * std::max(1.0, ref.t));
      EXPECT_NEAR(h->u, ref.u, 1e-4);
      EXPECT_NEAR(h->v, ref.v, 1e-4);
    }
  }
  EXPECT_GT(checked, 100000);
  EXPECT_GT(hits, 5000);
}

TEST(Watertight, NoRayPassesBetweenTrianglesSharingAnEdge) {
  // Two triangles (a, b, c) and (b, a, d) share edge ab; rays aimed at points of the edge
  // (rounded to float, so exactly on it or an ulp to either side) from random origins hit at
  // least one of them, unless the edge is a silhouette seen from the origin (c and d on the same
  // side of the plane through the ray and the edge): then grazing rays may pass legitimately.
  std::mt19937 g(11);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  int both = 0, tested = 0;
  for (int i = 0; i < 100000; ++i) {
    const Vec3f a = rnd(g, -1, 1), b = rnd(g, -1, 1);
    Vec3f c = rnd(g, -1, 1), d;
    // d on the other side of edge ab, roughly in the same plane (a folded pair)
    const float s = U(g);
    for (int k = 0; k < 3; ++k) d[k] = a[k] + b[k] - c[k] + 0.3f * (U(g) - 0.5f);
    Vec3f target;
    for (int k = 0; k < 3; ++k) target[k] = a[k] + s * (b[k] - a[k]);
    const Vec3f o = rnd(g, -5, 5);
    const Vec3f dir = {target[0] - o[0], target[1] - o[1], target[2] - o[2]};
    auto v3 = [](const Vec3f& x) { return Vec3(x[0], x[1], x[2]); };
    const Vec3 n = (v3(b) - v3(a)).cross(v3(dir));
    const double sc = (v3(c) - v3(a)).dot(n), sd = (v3(d) - v3(a)).dot(n);
    if (!(sc * sd < 0.0) || std::min(std::abs(sc), std::abs(sd)) < 1e-3 * n.norm()) continue;
    ++tested;
    const WatertightRay r = make_watertight_ray(o, dir);
    const auto h1 = intersect_triangle(r, a, b, c, 0.0f, kInf);
    const auto h2 = intersect_triangle(r, b, a, d, 0.0f, kInf);
    // A ray grazing the pair's common plane may miss both legitimately only if it is parallel
    // to both triangles (det = 0 in both), which random data does not produce.
    ASSERT_TRUE(h1 || h2) << "ray " << i << " leaks through the shared edge";
    both += h1 && h2;
  }
  EXPECT_GT(tested, 30000);
  (void)both;
  // A ray exactly through the edge: both triangles report the hit (the double recomputation
  // gives U = 0 exactly in both).
  const Vec3f a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0}, d{1, -1, 0.25f};
  const auto r = make_watertight_ray({0.5f, 0.0f, 1.0f}, {0.0f, 0.0f, -1.0f});
  EXPECT_TRUE(intersect_triangle(r, a, b, c, 0.0f, kInf));
  EXPECT_TRUE(intersect_triangle(r, b, a, d, 0.0f, kInf));
  const auto r2 = make_watertight_ray({0.3f, 0.7f, 1.0f}, {0.1f, -0.35f, -0.5f});  // through (0.5, 0, 0)
  EXPECT_TRUE(intersect_triangle(r2, a, b, c, 0.0f, kInf) || intersect_triangle(r2, b, a, d, 0.0f, kInf));
}

TEST(Watertight, ThroughASharedVertexHitsAtLeastOneOfTheFan) {
  // A fan of 6 triangles around the origin vertex in the z = 0 plane; rays through the vertex
  // from random origins above or below.
  std::mt19937 g(3);
  const Vec3f center{0.25f, -0.5f, 0.125f};
  Vec3f ring[6];
  for (int k = 0; k < 6; ++k) {
    const double ang = k * M_PI / 3.0 + 0.1;
    ring[k] = {center[0] + float(std::cos(ang)), center[1] + float(std::sin(ang)), center[2]};
  }
  for (int i = 0; i < 20000; ++i) {
    Vec3f o = rnd(g, -3, 3);
    if (o[2] == center[2]) continue;
    const Vec3f dir = {center[0] - o[0], center[1] - o[1], center[2] - o[2]};
    const WatertightRay r = make_watertight_ray(o, dir);
    int n = 0;
    for (int k = 0; k < 6; ++k) n += intersect_triangle(r, center, ring[k], ring[(k + 1) % 6], 0.0f, kInf).has_value();
    ASSERT_GE(n, 1) << i;
  }
}

TEST(Watertight, AxisAlignedAndDegenerate) {
  const Vec3f a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  // Straight down the z axis through the interior, an edge and a vertex.
  EXPECT_TRUE(intersect_triangle(make_watertight_ray({0.25f, 0.25f, 1}, {0, 0, -1}), a, b, c, 0, kInf));
  EXPECT_TRUE(intersect_triangle(make_watertight_ray({0.5f, 0.0f, 1}, {0, 0, -1}), a, b, c, 0, kInf));
  EXPECT_TRUE(intersect_triangle(make_watertight_ray({0.0f, 0.0f, -1}, {0, 0, 1}), a, b, c, 0, kInf));
  EXPECT_FALSE(intersect_triangle(make_watertight_ray({0.75f, 0.75f, 1}, {0, 0, -1}), a, b, c, 0, kInf));
  // Negative zero components.
  EXPECT_TRUE(intersect_triangle(make_watertight_ray({0.25f, 0.25f, 1}, {-0.0f, -0.0f, -1}), a, b, c, 0, kInf));
  // Parallel ray in the triangle's plane: det = 0, no hit.
  EXPECT_FALSE(intersect_triangle(make_watertight_ray({-1, 0.25f, 0}, {1, 0, 0}), a, b, c, 0, kInf));
  // Degenerate triangles (repeated corner, collinear) are never hit.
  EXPECT_FALSE(intersect_triangle(make_watertight_ray({0.0f, 0.0f, 1}, {0, 0, -1}), a, a, c, 0, kInf));
  EXPECT_FALSE(intersect_triangle(make_watertight_ray({0.5f, 0.0f, 1}, {0, 0, -1}), a, b, {2, 0, 0}, 0, kInf));
  // Interval: t = 1 exactly; (tmin, tmax] is half open.
  const auto r = make_watertight_ray({0.25f, 0.25f, 1}, {0, 0, -1});
  EXPECT_TRUE(intersect_triangle(r, a, b, c, 0.0f, 1.0f));
  EXPECT_FALSE(intersect_triangle(r, a, b, c, 1.0f, 2.0f));
  EXPECT_FALSE(intersect_triangle(r, a, b, c, 0.0f, 0.999f));
  const auto h = intersect_triangle(r, a, b, c, 0.0f, kInf);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->t, 1.0f);
  EXPECT_FLOAT_EQ(h->u, 0.25f);
  EXPECT_FLOAT_EQ(h->v, 0.25f);
}

}  // namespace
}  // namespace ptc::bvh
