// Every method through the front door (cluster_mesh) on the hard cases, checked item by item:
// validate() with the configured limits (validate itself is checked against brute force in
// clustering_result_test), the Standard baseline (MaxCount = MaxSize = 0: one triangle per
// cluster, recounted here), determinism (two runs bit-identical), and what cluster.h claims about
// invariance: growth (index start) and contraction with Acc or GWH01 under rigid motion; Naive
// (axis-aligned boxes), sah-split and meshopt (axis-aligned planes / kd-tree) under scaling by a
// power of two (exact in floating point) but not under rotation (a rotated mesh is still clustered
// validly).
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/geometry/sphere.h"
#include "toolkit/mesh/topology.h"
#include "test_meshes.h"

namespace ptc {
namespace {

using namespace test_meshes;

struct Case {
  ClusterMethod method;
  ObjectiveKind objective;
};

std::vector<Case> all_cases() {
  std::vector<Case> out;
  for (ClusterMethod m : {ClusterMethod::Growth, ClusterMethod::Contraction})
    for (ObjectiveKind o : {ObjectiveKind::Acc, ObjectiveKind::Naive, ObjectiveKind::Gwh01}) out.push_back({m, o});
  out.push_back({ClusterMethod::SahSplit, ObjectiveKind::Acc});
  out.push_back({ClusterMethod::Meshopt, ObjectiveKind::Acc});
  return out;
}

ClusterConfig config_of(const Case& c, std::uint32_t size) {
  ClusterConfig cfg;
  cfg.method = c.method;
  cfg.objective = c.objective;
  cfg.max_count = size;
  cfg.max_size = size;
  return cfg;
}

/// The limits validate() must see: a vertex limit for everything but Acc (whose bounds are soft).
ClusterLimits limits_of(const Case& c, std::uint32_t size) {
  ClusterLimits lim;
  if (c.objective != ObjectiveKind::Acc || c.method == ClusterMethod::SahSplit || c.method == ClusterMethod::Meshopt)
    lim.max_vertices = size;
  return lim;
}

std::string what(const Case& c, std::uint32_t size, const std::string& mesh) {
  return std::string(to_string(c.method)) + "/" + std::string(to_string(c.objective)) + " size " +
         std::to_string(size) + " on " + mesh;
}

void expect_same(const Clustering& a, const Clustering& b, const std::string& msg) {
  EXPECT_EQ(a.triangle_order, b.triangle_order) << msg;
  EXPECT_EQ(a.triangle_offsets, b.triangle_offsets) << msg;
  EXPECT_EQ(a.vertices, b.vertices) << msg;
  EXPECT_EQ(a.vertex_offsets, b.vertex_offsets) << msg;
}

Mesh moved(const Mesh& m, const Eigen::Matrix3d& r, const Vec3& t, double scale = 1.0) {
  std::vector<Vec3> p;
  for (const Vec3& x : m.positions()) p.push_back(scale * (r * x) + t);
  return m.with_positions(std::move(p));
}

/// The hard cases, unjittered (exact ties included) and jittered.
std::vector<Named> hard_meshes() {
  std::vector<Named> out{{"empty", Mesh()},
                         {"tetrahedron (closed: N_avg of the whole vanishes)", regular_tetrahedron()},
                         {"icosahedron (closed)", icosahedron()},
                         {"book (valence-4 edge)", book()},
                         {"closed fan", fan(9, true)},
                         {"degenerate mix", degenerate_mix()},
                         {"components", components()},
                         {"open cube", open_cube()}};
  // Many tiny components: 60 isolated triangles and 30 two-triangle pieces.
  Mesh tiny;
  for (int k = 0; k < 90; ++k) {
    Mesh piece = k < 60 ? Mesh(std::vector<Tri>{{0, 1, 2}}, std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}})
                        : grid(1, 1);
    piece = moved(piece, Eigen::Matrix3d::Identity(), Vec3(3.0 * k, 0.5 * (k % 7), 0.1 * (k % 3)));
    tiny = concat(tiny, piece);
  }
  out.push_back({"90 tiny components", tiny});
  // A non-manifold fan: 6 triangles on one edge, plus a repeated triangle and a (v, v, w) one.
  {
    std::vector<Vec3> p{{0, 0, 0}, {0, 0, 1}};
    std::vector<Tri> t;
    for (int i = 0; i < 6; ++i) {
      const double a = 2.0 * 3.14159265358979 * i / 6;
      p.emplace_back(std::cos(a), std::sin(a), 0.5);
      t.push_back({0, 1, static_cast<std::uint32_t>(2 + i)});
    }
    t.push_back({0, 1, 2});  // repeated triangle
    t.push_back({2, 2, 3});  // repeated index (zero area)
    out.push_back({"non-manifold fan with repeats", Mesh(std::move(t), std::move(p))});
  }
  return out;
}

TEST(ClusterFrontDoor, HardCasesValidDeterministicForEveryMethod) {
  const auto meshes = hard_meshes();
  for (const Case& c : all_cases())
    for (std::uint32_t size : {3u, 10u, 50u}) {
      if (c.objective == ObjectiveKind::Acc && c.method != ClusterMethod::SahSplit &&
          c.method != ClusterMethod::Meshopt && size == 3)
        continue;  // Acc with MaxCount 3 is legal but adds nothing here
      for (const auto& [name, m] : meshes) {
        const std::string msg = what(c, size, name);
        const Clustering a = cluster_mesh(m, config_of(c, size));
        const auto issues = validate(a, m.triangles(), limits_of(c, size));
        EXPECT_TRUE(issues.empty()) << msg << ": " << joined(issues);
        EXPECT_EQ(a.triangle_order.size(), m.triangle_count()) << msg;
        if (m.empty()) {
          EXPECT_EQ(a.cluster_count(), 0u) << msg;
        }
        expect_same(a, cluster_mesh(m, config_of(c, size)), msg + " (second run)");
      }
    }
}

TEST(ClusterFrontDoor, ZeroLimitsMeanOneTrianglePerClusterForEveryMethod) {
  for (const auto& [name, m] : hard_meshes())
    for (const Case& c : all_cases()) {
      const Clustering a = cluster_mesh(m, config_of(c, 0));
      ASSERT_EQ(a.cluster_count(), m.triangle_count()) << what(c, 0, name);
      for (std::size_t k = 0; k < a.cluster_count(); ++k) {
        ASSERT_EQ(a.triangles_of(k).size(), 1u);
        EXPECT_EQ(a.triangles_of(k)[0], k) << what(c, 0, name);  // in input order
      }
      ClusterLimits lim;
      lim.max_triangles = 1;
      EXPECT_TRUE(validate(a, m.triangles(), lim).empty()) << what(c, 0, name);
    }
}

TEST(ClusterFrontDoor, RigidMotionInvarianceWhereClaimed) {
  const Mesh m = load("elephant.off");
  const Eigen::Matrix3d r = Eigen::Quaterniond(0.3, -0.5, 0.7, 0.2).normalized().toRotationMatrix();
  const Mesh mr = moved(m, r, Vec3(-2.5, 4.0, 1.25));
  const Mesh ms = moved(m, Eigen::Matrix3d::Identity(), Vec3::Zero(), 4.0);
  for (ObjectiveKind o : {ObjectiveKind::Acc, ObjectiveKind::Naive, ObjectiveKind::Gwh01}) {
    ClusterConfig cfg = config_of({ClusterMethod::Contraction, o}, 20);
    for (int method = 0; method < 2; ++method) {
      const std::string msg = std::string(method ? "growth/index " : "contraction ") + std::string(to_string(o));
      const Clustering a = cluster_mesh(m, cfg);
      // Naive scores axis-aligned boxes: invariant under scaling by powers of two, not rotation.
      if (o == ObjectiveKind::Naive) {
        expect_same(a, cluster_mesh(ms, cfg), msg + " scaled by 4");
      } else {
        expect_same(a, cluster_mesh(mr, cfg), msg + " rotated and translated");
      }
      cfg.method = ClusterMethod::Growth;
      cfg.start = StartRule::IndexOrder;
    }
  }
  // Naive is genuinely not rotation invariant (so the distinction above is not vacuous).
  const ClusterConfig naive = config_of({ClusterMethod::Contraction, ObjectiveKind::Naive}, 20);
  EXPECT_NE(cluster_mesh(m, naive).triangle_order, cluster_mesh(mr, naive).triangle_order);
}

TEST(ClusterFrontDoor, BaselinesInvariantUnderPowerOfTwoScalingValidWhenRotated) {
  const Mesh m = load("elephant.off");
  const Eigen::Matrix3d r = Eigen::Quaterniond(0.3, -0.5, 0.7, 0.2).normalized().toRotationMatrix();
  for (ClusterMethod method : {ClusterMethod::SahSplit, ClusterMethod::Meshopt})
    for (std::uint32_t size : {10u, 64u}) {
      const Case c{method, ObjectiveKind::Acc};
      const ClusterConfig cfg = config_of(c, size);
      const Clustering a = cluster_mesh(m, cfg);
      for (double s : {0.25, 8.0, 1024.0})
        expect_same(a, cluster_mesh(moved(m, Eigen::Matrix3d::Identity(), Vec3::Zero(), s), cfg),
                    what(c, size, "elephant scaled by " + std::to_string(s)));
      const Clustering b = cluster_mesh(moved(m, r, Vec3(-2.5, 4.0, 1.25)), cfg);  // not invariant: only valid
      EXPECT_TRUE(validate(b, m.triangles(), limits_of(c, size)).empty()) << what(c, size, "rotated elephant");
    }
}

// Meshes of extreme scale (coordinates near 1e-301 or 1e301, where triangle areas underflow to 0
// or overflow) are clustered as the same mesh times a power of two: the same clusters as at unit
// scale, for every method and objective, and AvgSA in the mesh's own units. Before, the tiny
// elephant's growth gave one cluster per triangle ("every triangle collapses to a point").
TEST(ClusterFrontDoor, ExtremeScalesClusterAsTheUnitMesh) {
  const Mesh m = load("elephant.off");
  EXPECT_EQ(extreme_scale_exponent(m), 0);
  for (const int e : {-300, 300, -1000, 1000}) {
    const Mesh s = moved(m, Eigen::Matrix3d::Identity(), Vec3::Zero(), std::ldexp(1.0, e));
    EXPECT_NE(extreme_scale_exponent(s), 0) << e;
    EXPECT_EQ(extreme_scale_exponent(moved(m, Eigen::Matrix3d::Identity(), Vec3::Zero(), std::ldexp(1.0, e / 20))), 0) << e;
    // A stray unreferenced vertex far out does not scale the mesh (the triangles' extent does).
    std::vector<Vec3> stray(m.positions().begin(), m.positions().end());
    stray.push_back(Vec3(std::ldexp(1.0, 1000), 0, 0));
    EXPECT_EQ(extreme_scale_exponent(Mesh(std::vector<Tri>(m.triangles().begin(), m.triangles().end()), stray)), 0);
    for (const Case& c : all_cases()) {
      const ClusterConfig cfg = config_of(c, 24);
      double unit_sa = -1.0, scaled_sa = -1.0;
      const Clustering a = cluster_mesh(m, cfg, {}, std::nullopt, &unit_sa);
      const Clustering b = cluster_mesh(s, cfg, {}, std::nullopt, &scaled_sa);
      expect_same(a, b, what(c, 24, "elephant times 2^" + std::to_string(e)));
      // (at 2^+-300 the AvgSA is a finite double, at 2^+-1000 inf or 0)
      EXPECT_EQ(scaled_sa, unit_sa < 0 ? -1.0 : std::ldexp(unit_sa, 2 * e)) << what(c, 24, "AvgSA");
      if (std::abs(e) == 300 && unit_sa > 0) {
        EXPECT_TRUE(std::isfinite(scaled_sa) && scaled_sa > 0) << scaled_sa;
      }
    }
  }
}

// Corners near +-1e308 (whose differences overflow: the box's extent is inf) are scaled like
// any extreme mesh: two triangles sharing an edge cluster as the same two at unit size (one
// cluster), every method and objective. Before, the extent's overflow left the mesh unscaled,
// its areas inf and NaN, and growth made two clusters (found by a new user's sweep).
TEST(ClusterFrontDoor, CornersWhoseDifferencesOverflowAreScaled) {
  const std::vector<Tri> t{{0, 1, 2}, {1, 3, 2}};
  const std::vector<Vec3> unit{{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}, {1, 1, 0}};
  std::vector<Vec3> huge;
  for (const Vec3& p : unit) huge.push_back(1e308 * p);
  const Mesh a(t, unit), b(t, huge);
  EXPECT_NE(extreme_scale_exponent(b), 0);
  for (const Case& c : all_cases()) {
    const ClusterConfig cfg = config_of(c, 24);
    expect_same(cluster_mesh(a, cfg), cluster_mesh(b, cfg), what(c, 24, "two triangles at +-1e308"));
  }
}

// cluster_mesh's avg_sa_used (ptc cluster's AvgSA for the metrics) is the separate pass's value
// bit for bit on every path that runs Acc: the whole mesh (the tables' pass), regions (the
// separate pass), a soup clustered over its weld, and a given value; it is left alone by the
// methods without Acc. Meshes with degenerate triangles, an offset far from the origin, a tiny
// scale.
TEST(ClusterFrontDoor, AvgSaUsedIsTheSeparatePassBitForBit) {
  const Mesh e = load("elephant.off");
  const std::vector<Named> meshes{{"elephant", e},
                                  {"elephant moved by 3e6", moved(e, Eigen::Matrix3d::Identity(), Vec3(3e6, -3e6, 1e6))},
                                  {"elephant scaled by 1e-30", moved(e, Eigen::Matrix3d::Identity(), Vec3::Zero(), 1e-30)},
                                  {"degenerate mix", degenerate_mix()},
                                  {"elephant as a soup", soup_of(e)}};
  for (const Named& nm : meshes) {
    const double expected = average_triangle_sphere_area(nm.mesh.positions(), nm.mesh.triangles());
    for (ClusterMethod method : {ClusterMethod::Growth, ClusterMethod::Contraction})
      for (std::uint32_t regions : {0u, 4u}) {
        ClusterConfig cfg = config_of({method, ObjectiveKind::Acc}, 20);
        cfg.regions = regions;
        double used = -1.0;
        (void)cluster_mesh(nm.mesh, cfg, {}, std::nullopt, &used);
        EXPECT_EQ(std::bit_cast<std::uint64_t>(used), std::bit_cast<std::uint64_t>(expected))
            << what({method, ObjectiveKind::Acc}, 20, nm.name) << " regions " << regions << ": " << used << " vs "
            << expected;
        double given = -1.0;
        (void)cluster_mesh(nm.mesh, cfg, {}, 0.75 * expected, &given);
        EXPECT_EQ(given, 0.75 * expected) << nm.name << ": a given AvgSA is the one used";
      }
    for (const Case& c : {Case{ClusterMethod::Growth, ObjectiveKind::Naive}, Case{ClusterMethod::SahSplit, ObjectiveKind::Acc},
                          Case{ClusterMethod::Meshopt, ObjectiveKind::Acc}}) {
      double used = -1.0;
      (void)cluster_mesh(nm.mesh, config_of(c, 20), {}, std::nullopt, &used);
      EXPECT_EQ(used, -1.0) << what(c, 20, nm.name) << ": no Acc objective ran";
    }
  }
}

}  // namespace
}  // namespace ptc
