// Drift of cluster quality (analysis/metrics/drift.h): zero under rigid motion for the
// rotation-invariant metrics, box areas as the rotated boxes predict (computed here from the
// rotation matrix), and drift that grows with the angle of a twist.
#include <gtest/gtest.h>

#include <cmath>

#include <Eigen/Geometry>

#include "analysis/metrics/drift.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/scene.h"
#include "toolkit/clustering/cluster.h"

namespace ptc {
namespace {

struct Fixture {
  Mesh rest;
  ClusterConfig cfg;
  Clustering clusters;
  std::vector<ClusterRow> rows0;
  Fixture() : rest(make_sphere_mesh(Vec3(0.3, -0.2, 0.1), 1.0, 3)) {
    // An ellipsoid, so that clusters differ in shape.
    std::vector<Vec3> p(rest.positions().begin(), rest.positions().end());
    for (Vec3& v : p) v = Vec3(2.0 * v.x(), v.y(), 0.5 * v.z());
    rest = rest.with_positions(std::move(p));
    cfg.method = ClusterMethod::Growth;
    cfg.max_count = 30;
    cfg.max_size = 30;
    clusters = cluster_mesh(rest, cfg);
    rows0 = cluster_rows(rest, clusters, cfg);
  }
};

TEST(Drift, RigidMotionMovesOnlyTheBoxes) {
  const Fixture f;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 t(1e3, -5.0, 20.0);
  std::vector<Vec3> p;
  for (const Vec3& v : f.rest.positions()) p.push_back(R * v + t);
  const Mesh moved = f.rest.with_positions(p);
  const auto rows = cluster_rows(moved, f.clusters, f.cfg);
  const auto d = cluster_drift(f.rows0, rows);
  ASSERT_EQ(d.size(), f.clusters.cluster_count());
  int box_changed = 0;
  for (std::size_t k = 0; k < d.size(); ++k) {
    EXPECT_NEAR(d[k].reg_delta, 0.0, 1e-9) << k;
    EXPECT_NEAR(d[k].acc_delta, 0.0, 1e-9) << k;
    EXPECT_NEAR(d[k].sphere_radius_ratio, 1.0, 1e-9) << k;
    // The box the rotation predicts: the axis-aligned box of the rotated rest vertices.
    Box3 b;
    for (std::uint32_t v : f.clusters.vertices_of(k)) b.extend(R * f.rest.position(v) + t);
    EXPECT_NEAR(d[k].box_area_ratio, b.surface_area() / f.rows0[k].m.box.surface_area(), 1e-9) << k;
    box_changed += std::abs(d[k].box_area_ratio - 1.0) > 1e-3;
  }
  EXPECT_GT(box_changed, int(d.size()) / 2);  // a rotation does change axis-aligned boxes
  const DriftSummary s = summarize_drift(d, 3);
  EXPECT_EQ(s.box_area_ratio.count, d.size());
  EXPECT_NEAR(s.sphere_radius_ratio.max, 1.0, 1e-9);
  ASSERT_EQ(s.worst_box_area.size(), 3u);
  // Worst first: no other cluster changed its box more than the first named one.
  const double worst = std::abs(std::log(d[s.worst_box_area[0]].box_area_ratio));
  for (const auto& x : d) EXPECT_LE(std::abs(std::log(x.box_area_ratio)), worst + 1e-15);
}

TEST(Drift, GrowsWithTheAngleOfATwist) {
  const Fixture f;
  double last_mean = 0, last_max = 0;
  for (double angle : {0.2, 0.5, 1.0, 1.5}) {
    DeformParams tw = deform_preset(DeformKind::Twist);
    tw.amplitude = angle;
    tw.axis = 0;  // along the ellipsoid's long axis
    AnimationPtr a = make_deformer(f.rest, tw);
    std::vector<Vec3> p(f.rest.vertex_count());
    a->positions(tw.period / 4, p);  // the quarter period: the full angle
    const auto d = cluster_drift(f.rows0, cluster_rows(f.rest.with_positions(p), f.clusters, f.cfg));
    std::vector<double> reg;
    for (const auto& x : d) reg.push_back(std::abs(x.reg_delta));
    const DriftSummary s = summarize_drift(d);
    const double mean = summarize(reg).mean;
    EXPECT_GT(mean, last_mean) << angle;
    EXPECT_GT(s.box_area_ratio.max, 1.0) << angle;
    EXPECT_GE(s.box_area_ratio.max, last_max) << angle;
    last_mean = mean, last_max = s.box_area_ratio.max;
  }
}

TEST(Drift, OtherClusteringsAreRefused) {
  const Fixture f;
  auto fewer = f.rows0;
  fewer.pop_back();
  EXPECT_THROW((void)cluster_drift(f.rows0, fewer), std::invalid_argument);
  auto changed = f.rows0;
  changed[0].m.vertices += 1;
  EXPECT_THROW((void)cluster_drift(f.rows0, changed), std::invalid_argument);
  EXPECT_EQ(summarize_drift({}).box_area_ratio.count, 0u);
}

}  // namespace
}  // namespace ptc
