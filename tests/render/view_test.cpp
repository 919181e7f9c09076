// Rendered views against analytic answers: a plane filling the view (every pixel hit, depth =
// plane distance along the ray), a finely tessellated sphere (normals and hit/miss against the
// analytic sphere), the cluster BVH giving the same hit triangle per pixel as the triangle BVH,
// and the colour maps of the images.
#include <gtest/gtest.h>

#include <cmath>

#include "render/camera.h"
#include "render/view.h"
#include "bvh/trace_scene.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"

using ptc::Mesh;
using ptc::Tri;
using ptc::Vec3;
namespace bvh = ptc::bvh;

namespace {

// Octahedron subdivided `levels` times with every vertex pushed onto the sphere of radius r.
Mesh sphere(int levels, double r = 1.0, const Vec3& c = Vec3::Zero()) {
  std::vector<Vec3> p{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<Tri> t{{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  Mesh m = ptc::subdivide(Mesh(std::move(t), std::move(p)), ptc::SubdivisionScheme::Midpoint, levels);
  std::vector<Vec3> q;
  for (const Vec3& v : m.positions()) q.push_back(c + r * v.normalized());
  return m.with_positions(std::move(q));
}

Mesh quad(double half) {
  return Mesh({{0, 1, 2}, {0, 2, 3}}, {Vec3(-half, -half, 0), Vec3(half, -half, 0), Vec3(half, half, 0), Vec3(-half, half, 0)});
}

}  // namespace

TEST(TraceRender, PlaneFillingTheViewEveryPixelHitDepthIsAnalytic) {
  const Mesh m = quad(1000);
  const bvh::TriangleScene scene(m);
  ptc::Box3 b = m.bounds();
  struct View {
    Vec3 eye, look;
  };
  for (const View& v : {View{Vec3(0.3, -0.2, 5), Vec3(0.3, -0.2, 0)}, View{Vec3(3, 2, 5), Vec3(0, 0, 0)},
                        View{Vec3(0, 0, 1e-3), Vec3(0, 0, 0)}}) {
    ptc::RenderConfig rc;
    rc.width = 37, rc.height = 23;
    const auto cam = ptc::make_camera({v.eye, v.look, Vec3(0, 1, 0), 60.0}, b, rc.width, rc.height);
    const ptc::Render r = ptc::render_view(scene.data(), m, cam, rc);
    ASSERT_EQ(r.primary_stats.hits, 37u * 23u);
    ptc::ColorLegend dl;
    const ptc::RgbImage depth = ptc::depth_image(r, dl);
    const ptc::RgbImage normal = ptc::normal_image(r);
    for (std::size_t i = 0; i < r.rays.size(); ++i) {
      ASSERT_TRUE(r.surface.hit[i]);
      const Vec3 d(r.rays.dx[i], r.rays.dy[i], r.rays.dz[i]);
      const double t_plane = -v.eye.z() / d.z() * d.norm();  // distance to z = 0 along the ray
      // Float vertices (|coordinates| <= 1000) and float t: a few units in the last place of the
      // largest magnitude involved.
      EXPECT_NEAR(r.primary.t[i], t_plane, 8.0 * 0x1p-24 * (1000.0 + t_plane)) << "pixel " << i;
      EXPECT_NEAR(r.surface.point[i].z(), 0.0, 1e-12);
      EXPECT_EQ(r.surface.normal[i], Vec3(0, 0, 1));
      EXPECT_EQ(normal.at(int(i % 37), int(i / 37)), (ptc::Rgb8{128, 128, 255}));
      // Depth grey: 255 at the legend min, 40 at the max, linear in between.
      const double f = dl.max > dl.min ? (r.primary.t[i] - dl.min) / (dl.max - dl.min) : 0.0;
      EXPECT_NEAR(depth.at(int(i % 37), int(i / 37))[0], 255.0 - 215.0 * f, 0.51);
    }
    EXPECT_EQ(dl.quantity, "depth");
    EXPECT_LE(dl.min, dl.max);
  }
}

TEST(TraceRender, SphereNormalsAndSilhouetteMatchTheAnalyticSphere) {
  const Mesh m = sphere(5, 1.0, Vec3(0.2, -0.1, 0.3));  // 8192 triangles, facets ~ 2.8 degrees
  const bvh::TriangleScene scene(m);
  ptc::RenderConfig rc;
  rc.width = 64, rc.height = 48;
  const Vec3 c(0.2, -0.1, 0.3);
  const auto cam = ptc::make_camera({Vec3(1, 2, 4), c, Vec3(0, 1, 0), 40.0}, m.bounds(), rc.width, rc.height);
  const ptc::Render r = ptc::render_view(scene.data(), m, cam, rc);
  const ptc::RgbImage nimg = ptc::normal_image(r);
  std::size_t checked = 0;
  for (std::size_t i = 0; i < r.rays.size(); ++i) {
    const Vec3 d = Vec3(r.rays.dx[i], r.rays.dy[i], r.rays.dz[i]).normalized();
    const Vec3 o = cam.eye - c;
    const double b = o.dot(d), dist2 = (o - b * d).squaredNorm();  // squared distance of the line to the centre
    if (dist2 > 1.0) {
      EXPECT_FALSE(r.surface.hit[i]) << "pixel " << i << " misses the sphere but hit the mesh";
      continue;
    }
    if (dist2 > 0.9 * 0.9) continue;  // near the silhouette the inscribed mesh may miss
    ASSERT_TRUE(r.surface.hit[i]) << "pixel " << i;
    ++checked;
    const double t = -b - std::sqrt(1.0 - dist2);
    const Vec3 n_exact = (o + t * d).normalized();
    EXPECT_GT(r.surface.normal[i].dot(n_exact), std::cos(4.0 * M_PI / 180.0)) << "pixel " << i;
    // Facets lie within ~5e-4 of the sphere; along a ray at up to 64 degrees from the normal
    // (line distance 0.9) that is ~1.1e-3 of t.
    EXPECT_NEAR(r.primary.t[i], t, 0.005) << "pixel " << i;
    const ptc::Rgb8 px = nimg.at(int(i % 64), int(i / 64));
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(px[a] / 255.0 * 2.0 - 1.0, r.surface.normal[i][a], 1.0 / 255.0 + 1e-9);
  }
  EXPECT_GT(checked, 500u);
}

TEST(TraceRender, ClusterBvhHitsTheSameTrianglePerPixelAsTheTriangleBvh) {
  const Mesh m = ptc::read_mesh(std::string(PTC_TEST_DATA) + "/meshes/armadillo.off").mesh;
  ptc::ClusterConfig cc;
  cc.method = ptc::ClusterMethod::Growth;
  cc.objective = ptc::ObjectiveKind::Acc;
  const ptc::Clustering cl = ptc::cluster_mesh(m, cc);
  const bvh::TriangleScene ts(m);
  ptc::RenderConfig rc;
  rc.width = 96, rc.height = 80;
  rc.shadows = true;
  rc.ao_samples = 2;
  const auto cam = ptc::make_camera({}, m.bounds(), rc.width, rc.height);
  const ptc::Render a = ptc::render_view(ts.data(), m, cam, rc);
  ASSERT_GT(a.primary_stats.hits, 1000u);
  for (bvh::ClusterLeaf leaf : {bvh::ClusterLeaf::Linear, bvh::ClusterLeaf::BlockTree}) {
    bvh::SceneConfig sc = bvh::cluster_scene_defaults();
    sc.cluster_leaf = leaf;
    const bvh::ClusterScene cs(m, bvh::view_of(cl), sc);
    const ptc::Render b = ptc::render_view(cs.data(), m, cam, rc);
    std::size_t diff = 0;
    for (std::size_t i = 0; i < a.rays.size(); ++i) {
      diff += a.primary.triangle[i] != b.primary.triangle[i] || a.primary.t[i] != b.primary.t[i];
    }
    EXPECT_EQ(diff, 0u) << bvh::to_string(leaf);
    EXPECT_EQ(a.lit, b.lit) << bvh::to_string(leaf);
    EXPECT_EQ(a.ao, b.ao) << bvh::to_string(leaf);
    EXPECT_EQ(ptc::shaded_image(a).rgb, ptc::shaded_image(b).rgb);
  }
}

TEST(TraceRender, HeatmapWithAFixedRangeCountsWhatFallsOutside) {
  const std::vector<std::uint32_t> counts{0, 5, 10, 20};
  ptc::ColorLegend l;
  const ptc::RgbImage img = ptc::cost_heatmap(counts, 4, 1, l, std::pair{5.0, 15.0});
  EXPECT_EQ(l.min, 5.0);
  EXPECT_EQ(l.max, 15.0);
  EXPECT_EQ(img.at(0, 0), ptc::viridis(0.0));
  EXPECT_EQ(img.at(1, 0), ptc::viridis(0.0));
  EXPECT_EQ(img.at(2, 0), ptc::viridis(0.5));
  EXPECT_EQ(img.at(3, 0), ptc::viridis(1.0));
  EXPECT_NE(l.note.find("1 pixels below the range"), std::string::npos) << l.note;
  EXPECT_NE(l.note.find("1 pixels above the range"), std::string::npos) << l.note;
  EXPECT_THROW((void)ptc::cost_heatmap(counts, 4, 1, l, std::pair{3.0, 3.0}), std::invalid_argument);
}

TEST(TraceRender, HeatmapLegendAndColourMap) {
  // Counts 0, 5, 10 on a 3x1 image: legend 0..10, ends of viridis, middle its midpoint.
  const std::vector<std::uint32_t> counts{0, 5, 10};
  ptc::ColorLegend l;
  const ptc::RgbImage img = ptc::cost_heatmap(counts, 3, 1, l);
  EXPECT_EQ(l.min, 0.0);
  EXPECT_EQ(l.max, 10.0);
  EXPECT_EQ(img.at(0, 0), (ptc::Rgb8{68, 1, 84}));     // #440154
  EXPECT_EQ(img.at(1, 0), (ptc::Rgb8{33, 145, 140}));  // #21918c
  EXPECT_EQ(img.at(2, 0), (ptc::Rgb8{253, 231, 37}));  // #fde725
  // All zero: no division by zero, everything at the low end.
  const std::vector<std::uint32_t> zeros(4, 0);
  const ptc::RgbImage z = ptc::cost_heatmap(zeros, 2, 2, l);
  EXPECT_EQ(l.max, 0.0);
  EXPECT_EQ(z.at(1, 1), (ptc::Rgb8{68, 1, 84}));
  EXPECT_THROW((void)ptc::cost_heatmap(zeros, 3, 2, l), std::invalid_argument);
  // The map is monotone in lightness-ish: green grows over the whole range.
  for (int k = 1; k <= 100; ++k) EXPECT_GE(ptc::viridis(k / 100.0)[1], ptc::viridis((k - 1) / 100.0)[1]);
  EXPECT_EQ(ptc::viridis(std::nan("")), ptc::viridis(0.0));
  EXPECT_EQ(ptc::viridis(7.0), ptc::viridis(1.0));
  EXPECT_EQ(ptc::to_u8(0.5), 128);
  EXPECT_EQ(ptc::to_u8(-1), 0);
  EXPECT_EQ(ptc::to_u8(2), 255);
}

TEST(TraceRender, MissedPixelsAndShadingTerms) {
  // A quad seen from its back side (normal turned to the viewer), with the light behind the eye.
  const Mesh m = quad(1);
  const bvh::TriangleScene scene(m);
  ptc::RenderConfig rc;
  rc.width = 20, rc.height = 20;
  rc.shadows = true;
  const auto cam = ptc::make_camera({Vec3(0, 0, -3), Vec3(0, 0, 0), Vec3(0, 1, 0), 60.0}, m.bounds(), 20, 20);
  rc.light = Vec3(0, 0, -10);
  const ptc::Render r = ptc::render_view(scene.data(), m, cam, rc);
  const ptc::RgbImage img = ptc::shaded_image(r);
  std::size_t hits = 0;
  for (std::size_t i = 0; i < r.rays.size(); ++i) {
    const ptc::Rgb8 px = img.at(int(i % 20), int(i / 20));
    if (!r.surface.hit[i]) {
      EXPECT_EQ(px, (ptc::Rgb8{32, 32, 40}));
      continue;
    }
    ++hits;
    EXPECT_EQ(r.surface.normal[i], Vec3(0, 0, -1));
    EXPECT_EQ(r.lit[i], 1);
    // 0.9 * (0.2 + 0.8 * cos) with cos the angle to the light.
    const Vec3 l = (rc.light.value() - r.surface.point[i]).normalized();
    EXPECT_NEAR(px[0], 255.0 * 0.9 * (0.2 + 0.8 * l.dot(Vec3(0, 0, -1))), 0.51);
  }
  EXPECT_GT(hits, 50u);
  EXPECT_LT(hits, 400u);

  // The light's intensity scales the diffuse term (a scene file's light.intensity; it changed
  // nothing once): 0 leaves the ambient term, 0.5 half the diffuse, 3 saturates near the centre.
  for (const double intensity : {0.0, 0.5, 3.0}) {
    rc.light_intensity = intensity;
    const ptc::Render ri = ptc::render_view(scene.data(), m, cam, rc);
    const ptc::RgbImage li = ptc::shaded_image(ri);
    for (std::size_t i = 0; i < ri.rays.size(); ++i) {
      if (!ri.surface.hit[i]) continue;
      const Vec3 l = (rc.light.value() - ri.surface.point[i]).normalized();
      const double v = 255.0 * 0.9 * (0.2 + 0.8 * intensity * l.dot(Vec3(0, 0, -1)));
      EXPECT_NEAR(li.at(int(i % 20), int(i / 20))[0], std::min(v, 255.0), 0.51) << intensity;
    }
  }
  for (const double bad : {-1.0, std::nan(""), HUGE_VAL}) {
    rc.light_intensity = bad;
    EXPECT_THROW((void)ptc::render_view(scene.data(), m, cam, rc), std::invalid_argument);
  }
}
