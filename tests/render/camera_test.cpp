// Cameras of `ptc trace`: vector parsing, every degenerate camera refused with an InputError
// naming the option, and the default camera framing every vertex for any aspect ratio.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "bvh/camera.h"
#include "render/camera.h"
#include "toolkit/core/error.h"

using ptc::Vec3;

namespace {

// Pixel coordinates of a world point (independent of primary_rays: the pinhole projection).
Eigen::Vector2d project(const ptc::bvh::PinholeCamera& c, const Vec3& p, int w, int h) {
  const Vec3 q = p - c.eye;
  const double z = q.dot(c.forward);
  const double th = std::tan(0.5 * c.fov_y_deg * M_PI / 180.0), tw = th * w / h;
  const double sx = q.dot(c.right) / z / tw, sy = q.dot(c.up) / z / th;  // in [-1, 1] inside
  return {0.5 * (sx + 1.0) * w, 0.5 * (1.0 - sy) * h};
}

std::string element_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ptc::InputError& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    return e.element();
  }
  return "(no error)";
}

}  // namespace

TEST(TraceCamera, DegenerateCamerasAreRefusedNamingTheOption) {
  ptc::Box3 b;
  b.extend(Vec3(-1, -1, -1));
  b.extend(Vec3(1, 1, 1));
  auto cam = [&](ptc::CameraSpec s) { return [s, &b] { (void)ptc::make_camera(s, b, 10, 10); }; };
  EXPECT_EQ(element_of(cam({Vec3(0, 0, 5), Vec3(0, 0, 5), {}, {}})), "--eye");             // eye == look-at
  EXPECT_EQ(element_of(cam({Vec3(0, 0, 5), {}, Vec3(0, 0, 0), {}})), "--up");              // zero up
  EXPECT_EQ(element_of(cam({Vec3(0, 0, 5), {}, Vec3(0, 0, -2), {}})), "--up");             // up parallel to view
  EXPECT_EQ(element_of(cam({Vec3(0, 0, 5), {}, Vec3(1e-9, 0, 1), {}})), "--up");           // almost parallel
  EXPECT_EQ(element_of(cam({{}, {}, {}, 0.0})), "--fov");
  EXPECT_EQ(element_of(cam({{}, {}, {}, 180.0})), "--fov");
  EXPECT_EQ(element_of(cam({{}, {}, {}, -5.0})), "--fov");
  EXPECT_EQ(element_of(cam({{}, {}, {}, std::nan("")})), "--fov");
  EXPECT_EQ(element_of(cam({Vec3(std::nan(""), 0, 0), {}, {}, {}})), "--eye");
  EXPECT_EQ(element_of(cam({{}, Vec3(0, INFINITY, 0), {}, {}})), "--look-at");
  // Without an eye the view is along -z; an up along z switches it to -y (a z-up mesh), not an error.
  const auto c = ptc::make_camera({{}, {}, Vec3(0, 0, 1), {}}, b, 10, 10);
  EXPECT_NEAR(c.forward.dot(Vec3(0, -1, 0)), 1.0, 1e-12);
  // An empty mesh cannot be framed.
  EXPECT_EQ(element_of([] { (void)ptc::make_camera({}, ptc::Box3{}, 10, 10); }), "--look-at");
}

TEST(TraceCamera, GivenCameraIsOrthonormalAndLooksAtTarget) {
  ptc::Box3 b;
  b.extend(Vec3(0, 0, 0));
  const auto c = ptc::make_camera({Vec3(3, 4, 5), Vec3(1, -2, 0.5), Vec3(0.2, 1, 0.1), 30.0}, b, 41, 41);
  EXPECT_EQ(c.eye, Vec3(3, 4, 5));
  EXPECT_NEAR(c.forward.dot((Vec3(1, -2, 0.5) - Vec3(3, 4, 5)).normalized()), 1.0, 1e-12);
  EXPECT_NEAR(c.forward.norm(), 1, 1e-12);
  EXPECT_NEAR(c.right.norm(), 1, 1e-12);
  EXPECT_NEAR(c.up.norm(), 1, 1e-12);
  EXPECT_NEAR(c.right.dot(c.forward), 0, 1e-12);
  EXPECT_NEAR(c.up.dot(c.forward), 0, 1e-12);
  EXPECT_GT(c.up.dot(Vec3(0.2, 1, 0.1)), 0.0);           // image up follows the hint
  EXPECT_NEAR(c.right.cross(c.up).dot(-c.forward), 1, 1e-12);  // right-handed: right x up = -forward
  // The centre pixel (odd size) looks exactly at the target.
  const auto rays = ptc::camera_rays(c, 41, 41);
  const std::size_t mid = 20 * 41 + 20;
  const Vec3 d(rays.dx[mid], rays.dy[mid], rays.dz[mid]);
  EXPECT_NEAR(d.normalized().dot(c.forward), 1.0, 1e-7);
  // Pixel (0, 0) is top-left: up and to the left of the centre.
  const Vec3 d0(rays.dx[0], rays.dy[0], rays.dz[0]);
  EXPECT_GT(d0.dot(c.up), 0);
  EXPECT_LT(d0.dot(c.right), 0);
}

TEST(TraceCamera, DefaultCameraFramesEveryCornerForAnyAspect) {
  ptc::Box3 b;
  b.extend(Vec3(-3, 10, 1e3));
  b.extend(Vec3(5, 11, 1e3 + 0.5));  // wide and flat, far from the origin
  for (auto [w, h] : {std::pair{100, 100}, std::pair{200, 50}, std::pair{50, 200}, std::pair{1, 1}}) {
    const auto c = ptc::make_camera({}, b, w, h);
    double margin = 1e9;
    for (int k = 0; k < 8; ++k) {
      const Vec3 q(k & 1 ? b.hi.x() : b.lo.x(), k & 2 ? b.hi.y() : b.lo.y(), k & 4 ? b.hi.z() : b.lo.z());
      const auto p = project(c, q, w, h);
      EXPECT_GE(p.x(), 0.0) << w << "x" << h;
      EXPECT_LE(p.x(), w) << w << "x" << h;
      EXPECT_GE(p.y(), 0.0);
      EXPECT_LE(p.y(), h);
      EXPECT_GT((q - c.eye).dot(c.forward), 0.0);  // in front of the camera
      margin = std::min({margin, p.x() / w, 1 - p.x() / w, p.y() / h, 1 - p.y() / h});
    }
    EXPECT_LT(margin, 0.05) << "the framing is not tight";  // a 5% margin on the tightest side
  }
  // A point-like mesh still gets a camera off the point.
  ptc::Box3 pt;
  pt.extend(Vec3(1, 2, 3));
  const auto c = ptc::make_camera({}, pt, 10, 10);
  EXPECT_GT((c.eye - Vec3(1, 2, 3)).norm(), 0.0);
}

// A flat mesh whose plane holds the default view direction (CGAL's ground plane y = 0, a wall
// x = 0) was seen edge-on: a line that no primary ray hit. The default camera looks at it from
// 45 degrees, framing every corner; a mesh with some depth keeps the straight view.
TEST(TraceCamera, DefaultCameraSeesAFlatMeshFromAbove) {
  for (int thin : {0, 1}) {
    ptc::Box3 b;
    Vec3 lo(-2, -1, -3), hi(2, 1, 3);
    lo[thin] = hi[thin] = 0.5;
    b.extend(lo);
    b.extend(hi);
    const auto c = ptc::make_camera({}, b, 64, 48);
    EXPECT_NEAR(std::abs(c.forward[thin]), std::sqrt(0.5), 1e-12) << thin;  // 45 degrees to the plane
    for (int k = 0; k < 8; ++k) {
      const Vec3 q(k & 1 ? b.hi.x() : b.lo.x(), k & 2 ? b.hi.y() : b.lo.y(), k & 4 ? b.hi.z() : b.lo.z());
      const auto p = project(c, q, 64, 48);
      EXPECT_GE(p.x(), 0.0);
      EXPECT_LE(p.x(), 64.0);
      EXPECT_GE(p.y(), 0.0);
      EXPECT_LE(p.y(), 48.0);
    }
  }
  ptc::Box3 deep;
  deep.extend(Vec3(-2, -0.01, -3));
  deep.extend(Vec3(2, 0.01, 3));  // thin, but not flat (1/300 of its length)
  EXPECT_EQ(ptc::make_camera({}, deep, 64, 48).forward, Vec3(0, 0, -1));
}

// direction_area_weights: rays along one axis weight only the faces across it (the others at the
// floor, 1/64 of it); zero and NaN directions are left out; none left gives the plain SAH's
// (1, 1, 1); directions spread evenly over the sphere give about (1, 1, 1) (a box's mean
// projected area is a quarter of its surface area).
TEST(TraceCamera, DirectionAreaWeights) {
  using ptc::bvh::RayBatch;
  using ptc::bvh::direction_area_weights;
  auto batch = [](const std::vector<ptc::bvh::Vec3f>& dirs) {
    RayBatch r;
    r.resize(dirs.size());
    for (std::size_t i = 0; i < dirs.size(); ++i) r.set(i, Vec3(1e6, -3, 2), dirs[i]);
    return r;
  };
  const float nan = std::nanf("");
  EXPECT_EQ(direction_area_weights(RayBatch{}), (std::array<float, 3>{1, 1, 1}));
  EXPECT_EQ(direction_area_weights(batch({{0, 0, 0}, {nan, 1, 0}})), (std::array<float, 3>{1, 1, 1}));
  EXPECT_EQ(direction_area_weights(batch({{0, 0, -1}, {0, 0, 0}, {0, 0, 7}, {nan, 0, 1}})),
            (std::array<float, 3>{2.0f / 64, 2.0f / 64, 2.0f}));
  const auto w = direction_area_weights(batch({{3, 4, 0}, {-0.3f, 0.4f, 0}}));  // (unit: 0.6, 0.8, 0)
  EXPECT_NEAR(w[0], 1.2f, 1e-6f);
  EXPECT_NEAR(w[1], 1.6f, 1e-6f);
  EXPECT_FLOAT_EQ(w[2], 1.6f / 64);
  std::vector<ptc::bvh::Vec3f> sphere;  // Fibonacci points: evenly spread unit directions
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n, r = std::sqrt(1.0 - z * z), phi = i * M_PI * (3.0 - std::sqrt(5.0));
    sphere.push_back({static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)), static_cast<float>(z)});
  }
  for (const float x : direction_area_weights(batch(sphere))) EXPECT_NEAR(x, 1.0f, 2e-3f);
  // A camera's weights without its rays: those of its primary rays, bit for bit.
  const ptc::bvh::PinholeCamera cam = ptc::bvh::frame_box(ptc::Box3(Vec3(-1, 0, 2), Vec3(3, 2, 5)), Vec3(0.2, -0.5, -1.0));
  EXPECT_EQ(direction_area_weights(cam, 37, 23), direction_area_weights(ptc::bvh::primary_rays(cam, 37, 23)));
}

// What the weights are for: with those of parallel rays along d, a quarter of a box's weighted
// area is its area projected across d, the share of those rays it meets. Counted by brute force:
// a fine grid of parallel rays over the box's shadow, each tested against the box's slabs.
TEST(TraceCamera, DirectionAreaWeightsGiveTheProjectedArea) {
  const Vec3 d = Vec3(0.36, -0.48, 0.8).normalized();
  ptc::bvh::RayBatch one;
  one.resize(1);
  one.set(0, Vec3::Zero(), {static_cast<float>(d.x()), static_cast<float>(d.y()), static_cast<float>(d.z())});
  const auto w = ptc::bvh::direction_area_weights(one);
  const ptc::bvh::Box3f box{{-1.0f, 0.5f, 2.0f}, {2.0f, 1.0f, 4.5f}};
  // A plane across d, spanned by u and v, far behind the box; cells of h x h.
  const Vec3 u = d.cross(Vec3(0, 0, 1)).normalized(), v = d.cross(u);
  const Vec3 centre(0.5, 0.75, 3.25);
  const double h = 0.004;
  std::size_t hits = 0;
  for (double s = -3.0; s < 3.0; s += h)
    for (double t = -3.0; t < 3.0; t += h) {
      const Vec3 o = centre - 10.0 * d + s * u + t * v;
      double t0 = -1e300, t1 = 1e300;
      for (int a = 0; a < 3; ++a) {
        const double ta = (box.lo[a] - o[a]) / d[a], tb = (box.hi[a] - o[a]) / d[a];
        t0 = std::max(t0, std::min(ta, tb)), t1 = std::min(t1, std::max(ta, tb));
      }
      hits += t0 <= t1 ? 1 : 0;
    }
  const double counted = static_cast<double>(hits) * h * h;
  EXPECT_NEAR(box.weighted_area(w) / 4.0, counted, 0.005 * counted);
}
