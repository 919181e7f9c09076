// The per-frame cluster metrics of the pictures, checked against facts that do not depend on how
// they are computed: a translated frame changes no metric; a frame scaled by s about any point
// has every box area s^2 and every sphere radius s times the reference's, reg and Acc unchanged;
// the SAH shares sum to 1; triangle counts sum to the mesh's; the columns are in
// clusters_frames.csv's order.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "analysis/metrics/cluster_frame.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/test_meshes.h"

namespace ptc {
namespace {

struct Fixture {
  Mesh mesh = read_mesh(std::string(PTC_TEST_DATA) + "/meshes/bunny00.off").mesh;
  ClusterConfig cfg;
  Clustering c;
  Fixture() {
    cfg.method = ClusterMethod::Growth;
    c = cluster_mesh(mesh, cfg);
  }
  Mesh moved(const Vec3& shift, double scale) const {
    Mesh m = mesh;
    std::vector<Vec3> p(m.positions().begin(), m.positions().end());
    const Vec3 pivot(0.3, -0.2, 0.1);
    for (auto& q : p) q = pivot + scale * (q - pivot) + shift;
    m.set_positions(std::move(p));
    return m;
  }
};

TEST(ClusterFrame, NamesFollowTheDriftTable) {
  const std::vector<std::string> want = {"triangles", "vertices", "connectivity", "reg", "acc", "reg_delta", "acc_delta",
                                         "sphere_radius", "sphere_radius_ratio", "sphere_radius_ratio_prev", "box_area",
                                         "box_area_ratio", "box_area_ratio_prev", "p_hit", "sah_share",
                                         "boundary_vertices", "components", "not_full"};
  ASSERT_EQ(cluster_metric_infos().size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_EQ(cluster_metric_infos()[i].name, want[i]);
  EXPECT_TRUE(find_cluster_metric("box_area_ratio")->diverging);
  EXPECT_EQ(find_cluster_metric("box_area_ratio")->centre, 1.0);
  EXPECT_TRUE(find_cluster_metric("acc_delta")->diverging);
  EXPECT_FALSE(find_cluster_metric("reg")->diverging);
  EXPECT_FALSE(find_cluster_metric("nodes_visited"));
}

TEST(ClusterFrame, ScaledFrameScalesBoxesAndSpheresAndKeepsShapes) {
  const Fixture f;
  const ClusterFrameMetrics ref = cluster_frame_metrics(f.mesh, f.c, f.cfg, {}, {});
  const std::size_t n = f.c.cluster_count();
  for (std::size_t k = 0; k < n; ++k) {
    EXPECT_EQ(ref.of("box_area_ratio")[k], 1.0);
    EXPECT_EQ(ref.of("reg_delta")[k], 0.0);
  }
  const double tris = std::accumulate(ref.of("triangles").begin(), ref.of("triangles").end(), 0.0);
  EXPECT_EQ(tris, double(f.mesh.triangle_count()));
  const double shares = std::accumulate(ref.of("sah_share").begin(), ref.of("sah_share").end(), 0.0);
  EXPECT_NEAR(shares, 1.0, 1e-9);
  for (std::size_t k = 0; k < n; ++k) EXPECT_GT(ref.of("sah_share")[k], 0.0) << k;  // every cluster is a leaf

  const Mesh big = f.moved(Vec3(5, -3, 2), 2.0);
  const ClusterFrameMetrics m = cluster_frame_metrics(big, f.c, f.cfg, ref.rows, ref.rows);
  for (std::size_t k = 0; k < n; ++k) {
    EXPECT_NEAR(m.of("box_area_ratio")[k], 4.0, 1e-9) << k;
    EXPECT_NEAR(m.of("box_area_ratio_prev")[k], 4.0, 1e-9) << k;
    EXPECT_NEAR(m.of("sphere_radius_ratio")[k], 2.0, 1e-9) << k;
    EXPECT_NEAR(m.of("box_area")[k], 4.0 * ref.of("box_area")[k], 1e-9 * ref.of("box_area")[k]) << k;
    EXPECT_NEAR(m.of("reg_delta")[k], 0.0, 1e-9) << k;
    EXPECT_NEAR(m.of("reg")[k], ref.of("reg")[k], 1e-9) << k;
    EXPECT_EQ(m.of("triangles")[k], ref.of("triangles")[k]);
    EXPECT_EQ(m.of("components")[k], ref.of("components")[k]);
  }
  // Only translated: the shares of the SAH cost stay (the tree is built over the same shapes).
  const ClusterFrameMetrics t = cluster_frame_metrics(f.moved(Vec3(1e3, 0, 0), 1.0), f.c, f.cfg, ref.rows, ref.rows);
  for (std::size_t k = 0; k < n; ++k) {
    EXPECT_NEAR(t.of("box_area_ratio")[k], 1.0, 1e-6) << k;
    EXPECT_NEAR(t.of("sah_share")[k], ref.of("sah_share")[k], 1e-6) << k;
  }
}

TEST(ClusterFrame, AnotherClusteringAsReferenceIsRefused) {
  const Fixture f;
  ClusterConfig other = f.cfg;
  other.max_count = 10, other.max_size = 10;
  const Clustering c2 = cluster_mesh(f.mesh, other);
  const ClusterFrameMetrics ref = cluster_frame_metrics(f.mesh, c2, other, {}, {});
  EXPECT_THROW((void)cluster_frame_metrics(f.mesh, f.c, f.cfg, ref.rows, {}), std::invalid_argument);
  EXPECT_THROW((void)ref.of("nodes_visited"), std::invalid_argument);
}

}  // namespace
}  // namespace ptc

namespace ptc {
namespace {

TEST(ClusterFrame, ASoupWithItsRestAdjacencyCountsRestPositions) {
  // The bunny as a soup whose triangles then fly apart (each moved by its own offset): with the
  // rest pose's adjacency, every frame's vertices / connectivity / Acc count the rest positions
  // (equal to the connected mesh's at rest, and the same in every frame: topology does not move),
  // while the positions of the frame give the boxes.
  const Mesh soup = test_meshes::soup_of(test_meshes::load("bunny00.off"));
  ClusterConfig cfg;
  cfg.method = ClusterMethod::Growth;
  const Clustering c = cluster_mesh(soup, cfg);
  const std::vector<Tri> adj = adjacency_triangles(soup, ClusterAdjacency::Auto);
  ASSERT_FALSE(adj.empty());
  const ClusterFrameMetrics rest = cluster_frame_metrics(soup, c, cfg, {}, {}, adj);
  std::vector<Vec3> flown(soup.positions().begin(), soup.positions().end());
  for (std::size_t i = 0; i < flown.size(); ++i) flown[i] += Vec3(0.01 * double(i / 3 % 7), 0, 0);
  Mesh moved = soup;
  moved.set_positions(flown);
  const ClusterFrameMetrics later = cluster_frame_metrics(moved, c, cfg, rest.rows, rest.rows, adj);
  const ClusterFrameMetrics by_ids = cluster_frame_metrics(moved, c, cfg, {}, {});
  ASSERT_EQ(rest.rows.size(), c.cluster_count());
  std::size_t welded_total = 0, boxes_moved = 0;
  for (std::size_t k = 0; k < c.cluster_count(); ++k) {
    EXPECT_EQ(later.rows[k].m.vertices, rest.rows[k].m.vertices) << k;
    EXPECT_LT(rest.rows[k].m.vertices, 3 * rest.rows[k].m.triangles + (rest.rows[k].m.triangles == 1 ? 1 : 0)) << k;
    EXPECT_EQ(by_ids.rows[k].m.vertices, 3 * by_ids.rows[k].m.triangles) << k;
    // The geometry is the frame's own: box, sphere, areas as without the adjacency.
    EXPECT_EQ(later.rows[k].m.box.lo, by_ids.rows[k].m.box.lo) << k;
    EXPECT_EQ(later.rows[k].m.box.hi, by_ids.rows[k].m.box.hi) << k;
    EXPECT_EQ(later.rows[k].m.sphere.radius, by_ids.rows[k].m.sphere.radius) << k;
    EXPECT_EQ(later.rows[k].m.area_p, by_ids.rows[k].m.area_p) << k;
    EXPECT_EQ(later.rows[k].m.reg, by_ids.rows[k].m.reg) << k;
    boxes_moved += later.rows[k].m.box.hi != rest.rows[k].m.box.hi;
    welded_total += rest.rows[k].m.vertices;
  }
  EXPECT_LT(welded_total, soup.vertex_count());
  EXPECT_GT(boxes_moved, c.cluster_count() / 2);  // the triangles did move apart
}

}  // namespace
}  // namespace ptc
