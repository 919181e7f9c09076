// meshoptimizer's SAH overhead (analysis/metrics/sah_overhead.h): exactly 1 for the two
// clusterings that add no level (one triangle per cluster, one cluster of everything), and the
// composition of the formula checked on a two-cluster split against its pieces.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/metrics/sah_overhead.h"
#include "toolkit/anim/scene.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/morton_runs.h"

namespace ptc {
namespace {

TEST(SahOverhead, IdentitiesAndOrder) {
  const Mesh m = make_sphere_mesh(Vec3(0.2, 0.0, -0.1), 1.0, 3);  // 1280 triangles
  std::vector<std::uint32_t> each(m.triangle_count()), all(m.triangle_count(), 0);
  for (std::uint32_t t = 0; t < m.triangle_count(); ++t) each[t] = t;
  const SahOverhead singles = sah_overhead(m, clustering_from_labels(each, m.triangles()));
  EXPECT_NEAR(singles.overhead, 1.0, 1e-6);  // the top tree is the triangle tree
  const SahOverhead whole = sah_overhead(m, clustering_from_labels(all, m.triangles()));
  EXPECT_NEAR(whole.overhead, 1.0, 1e-6);  // one cluster: its tree is the triangle tree
  EXPECT_GT(whole.triangles, 0.0);
  // A real clustering costs something, within a small factor.
  ClusterConfig cc;
  cc.method = ClusterMethod::Growth;
  cc.max_count = 40;
  cc.max_size = 40;
  const SahOverhead acc = sah_overhead(m, cluster_mesh(m, cc));
  EXPECT_GT(acc.overhead, 1.0);
  EXPECT_LT(acc.overhead, 3.0);
  EXPECT_EQ(sah_overhead(Mesh{}, Clustering{}).overhead, 0.0);
}

TEST(SahOverhead, DoesNotDependOnWhereTheMeshLies) {
  // The same clustering of a sphere at the origin, 1e7 away and scaled by 2^-20: the same
  // overhead (in world floats the far one's boxes were rounded to whole units: 0.8 against 1.03),
  // and absolute costs in the mesh's units (a 2^-20 scale: areas times 2^-40).
  const Mesh m = make_sphere_mesh(Vec3(0.2, 0.0, -0.1), 1.0, 3);
  ClusterConfig cc;
  cc.method = ClusterMethod::Growth;
  cc.max_count = 20;
  cc.max_size = 20;
  const Clustering c = cluster_mesh(m, cc);
  const SahOverhead here = sah_overhead(m, c);
  auto moved = [&](double scale, const Vec3& offset) {
    std::vector<Vec3> p(m.positions().begin(), m.positions().end());
    for (Vec3& q : p) q = q * scale + offset;
    return Mesh(std::vector<Tri>(m.triangles().begin(), m.triangles().end()), p);
  };
  const SahOverhead far = sah_overhead(moved(1.0, Vec3(1e7, -3e7, 2e7)), c);
  EXPECT_NEAR(far.overhead, here.overhead, 1e-6 * here.overhead);
  const double s = std::ldexp(1.0, -20);
  const SahOverhead tiny = sah_overhead(moved(s, Vec3(0, 0, 0)), c);
  EXPECT_NEAR(tiny.overhead, here.overhead, 1e-6 * here.overhead);
  EXPECT_NEAR(tiny.triangles, here.triangles * s * s, 1e-6 * here.triangles * s * s);
  // No box has area (triangles on an axis): the ratio is undefined.
  const Mesh flat({{0, 1, 2}, {1, 2, 3}}, std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}});  // boxes of no area
  EXPECT_TRUE(std::isnan(sah_overhead(flat, clustering_from_labels(std::vector<std::uint32_t>{0, 1}, flat.triangles())).overhead));
}

TEST(SahOverhead, TwoClustersComposeFromTheirPieces) {
  // Two far-apart spheres, one cluster each: the top tree has one inner node over two leaves,
  // so clustered = [A(top) + A(b0) + A(b1)] + sum_k (SAH(k) - A(b_k)) = A(top) + SAH(0) + SAH(1),
  // and the triangle tree's best first split separates the spheres the same way.
  Mesh a = make_sphere_mesh(Vec3(-10, 0, 0), 1.0, 2), b = make_sphere_mesh(Vec3(10, 0, 0), 1.0, 2);
  std::vector<Tri> tris(a.triangles().begin(), a.triangles().end());
  std::vector<Vec3> pos(a.positions().begin(), a.positions().end());
  const auto off = static_cast<std::uint32_t>(pos.size());
  for (const Tri& t : b.triangles()) tris.push_back({t[0] + off, t[1] + off, t[2] + off});
  pos.insert(pos.end(), b.positions().begin(), b.positions().end());
  const Mesh m(tris, pos);
  std::vector<std::uint32_t> label(m.triangle_count());
  for (std::size_t t = 0; t < label.size(); ++t) label[t] = t < a.triangle_count() ? 0 : 1;
  const SahOverhead two = sah_overhead(m, clustering_from_labels(label, m.triangles()));
  EXPECT_NEAR(two.overhead, 1.0, 1e-6);
  const SahOverhead sa = sah_overhead(a, clustering_from_labels(std::vector<std::uint32_t>(a.triangle_count(), 0), a.triangles()));
  const SahOverhead sb = sah_overhead(b, clustering_from_labels(std::vector<std::uint32_t>(b.triangle_count(), 0), b.triangles()));
  Box3 top;
  for (const Vec3& p : pos) top.extend(p);
  const double area_top = 2 * (top.extent().x() * top.extent().y() + top.extent().x() * top.extent().z() +
                               top.extent().y() * top.extent().z());
  EXPECT_NEAR(two.clustered, area_top + sa.triangles + sb.triangles, 1e-4 * two.clustered);
}

}  // namespace
}  // namespace ptc
