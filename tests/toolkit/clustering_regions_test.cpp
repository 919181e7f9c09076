// Clustering in regions (toolkit/clustering/regions.h), the parallel mode of growth and
// contraction:
// - the partition: Morton ranks cut into runs of equal size (+-1), against a sort done here;
// - an independent answer: on a mesh of separate blobs, one region per blob, the regions'
//   growth (Naive, index start rule) and contraction (Naive) equal the one run over the whole
//   mesh cluster by cluster (a cluster never leaves its blob, and within a blob the sub-mesh
//   keeps the relative order of ids, so every decision is the same);
// - determinism: the same clusters bit for bit at 1, 2 and 4 threads, for Acc and Naive, every
//   start rule;
// - validity: every cluster edge-connected, inside one region, and the clustering covers the
//   mesh (validate());
// - hard cases: more regions than triangles, one region, an empty mesh, degenerate triangles,
//   collapsed meshes (AvgSA 0), and the refusals (other methods, GWH01, a target cluster count).
#include <gtest/gtest.h>

#include <oneapi/tbb/global_control.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/clustering/regions.h"
#include "toolkit/core/cancel.h"
#include "toolkit/geometry/morton.h"
#include "toolkit/mesh/subdivision.h"
#include "toolkit/mesh/topology.h"
#include "test_meshes.h"

namespace ptc {
namespace {

using namespace test_meshes;

Clustering with_threads(int threads, const Mesh& m, const ClusterConfig& c) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  return cluster_mesh(m, c);
}

void expect_same(const Clustering& a, const Clustering& b, const std::string& what) {
  EXPECT_EQ(a.triangle_order, b.triangle_order) << what;
  EXPECT_EQ(a.triangle_offsets, b.triangle_offsets) << what;
  EXPECT_EQ(a.vertices, b.vertices) << what;
  EXPECT_EQ(a.vertex_offsets, b.vertex_offsets) << what;
}

ClusterConfig growth(ObjectiveKind o, std::uint32_t regions, StartRule start = StartRule::SpatialOrder,
                     ClusterMethod method = ClusterMethod::Growth) {
  ClusterConfig c;
  c.method = method;
  c.objective = o;
  c.max_count = 20;
  c.max_size = 20;
  c.start = start;
  c.regions = regions;
  return c;
}

Mesh armadillo_52k() { return load("armadillo.off"); }

TEST(Regions, PartitionCutsTheMortonOrderIntoEqualRuns) {
  const Mesh m = jittered(grid(40, 30), 0.2, 7);
  const std::vector<std::uint32_t> order = morton_order(m.positions(), m.triangles());
  for (std::uint32_t n : {1u, 2u, 3u, 7u, 64u}) {
    const std::vector<std::uint32_t> region = cluster_regions(m, n);
    ASSERT_EQ(region.size(), m.triangle_count());
    std::vector<std::size_t> size(n, 0);
    for (std::size_t rank = 0; rank < order.size(); ++rank) {
      const std::uint32_t r = region[order[rank]];
      ASSERT_LT(r, n);
      if (rank > 0) {
        EXPECT_GE(r, region[order[rank - 1]]) << "runs of the Morton order, n = " << n;
      }
      ++size[r];
    }
    const auto [lo, hi] = std::minmax_element(size.begin(), size.end());
    EXPECT_GE(*lo, 1u) << n;
    EXPECT_LE(*hi - *lo, 1u) << n;
  }
  // More regions than triangles: one triangle a region.
  const Mesh tiny = icosahedron();
  const std::vector<std::uint32_t> r = cluster_regions(tiny, 1000);
  EXPECT_EQ(std::set<std::uint32_t>(r.begin(), r.end()).size(), tiny.triangle_count());
  EXPECT_EQ(cluster_regions(Mesh{}, 4).size(), 0u);
}

TEST(Regions, SeparateBlobsGiveTheOneRunClusters) {
  // Four copies of a jittered sphere patch at the corners of a square, far apart: the Morton
  // order visits one blob after the other, so four regions are the four blobs.
  const Mesh blob = jittered(sphere_patch(14, 10), 0.05, 3);
  Mesh m = blob;
  for (int k = 1; k < 4; ++k) {
    std::vector<Vec3> p(blob.positions().begin(), blob.positions().end());
    for (Vec3& v : p) v += Vec3(k % 2 ? 100.0 : 0.0, k / 2 ? 100.0 : 0.0, 0.0);
    m = concat(m, blob.with_positions(std::move(p)));
  }
  const std::vector<std::uint32_t> region = cluster_regions(m, 4);
  const std::size_t per = blob.triangle_count();
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    // each blob is one region (which one depends on the Morton order of the corners)
    EXPECT_EQ(region[t], region[(t / per) * per]) << t;
  }
  // (The spatial and fewest-free start rules order by the Morton code in the region's own box,
  // so they start clusters in another order than one run over the whole mesh.)
  const Clustering one = cluster_mesh(m, growth(ObjectiveKind::Naive, 0, StartRule::IndexOrder));
  const Clustering four = cluster_mesh(m, growth(ObjectiveKind::Naive, 4, StartRule::IndexOrder));
  expect_same(four, one, "index start rule");
  EXPECT_GT(one.cluster_count(), 4u * 5u);
  const auto contraction = growth(ObjectiveKind::Naive, 0, StartRule::IndexOrder, ClusterMethod::Contraction);
  auto contraction4 = contraction;
  contraction4.regions = 4;
  expect_same(cluster_mesh(m, contraction4), cluster_mesh(m, contraction), "contraction");
}

TEST(Regions, SameClustersAtAnyThreadCount) {
  const Mesh m = armadillo_52k();
  struct Run {
    ObjectiveKind o;
    StartRule s;
    ClusterMethod method;
  };
  std::vector<Run> runs;
  for (ObjectiveKind o : {ObjectiveKind::Acc, ObjectiveKind::Naive}) {
    for (StartRule s : {StartRule::SpatialOrder, StartRule::IndexOrder, StartRule::FewestFree})
      runs.push_back({o, s, ClusterMethod::Growth});
    runs.push_back({o, StartRule::SpatialOrder, ClusterMethod::Contraction});
  }
  for (const Run& run : runs) {
      const ClusterConfig c = growth(run.o, 8, run.s, run.method);
      const Clustering t1 = with_threads(1, m, c);
      const std::string what = std::string(to_string(run.method)) + " " + std::string(to_string(run.o)) + " " +
                               std::string(to_string(run.s));
      expect_same(with_threads(2, m, c), t1, what + ", 2 threads");
      expect_same(with_threads(4, m, c), t1, what + ", 4 threads");
      EXPECT_GT(t1.cluster_count(), m.triangle_count() / 60) << what;
    }
}

TEST(Regions, ClustersAreConnectedAndStayInTheirRegion) {
  for (const Mesh& m : {armadillo_52k(), jittered(grid(30, 30), 0.1, 2), degenerate_mix(), components()})
    for (ClusterMethod method : {ClusterMethod::Growth, ClusterMethod::Contraction})
    for (std::uint32_t n : {2u, 5u, 16u}) {
      const ClusterConfig c = growth(ObjectiveKind::Acc, n, StartRule::SpatialOrder, method);
      const Clustering cl = cluster_mesh(m, c);
      const std::vector<std::string> issues = validate(cl, m.triangles(), limits_of(c));
      EXPECT_TRUE(issues.empty()) << issues.front();
      const std::vector<std::uint32_t> region = cluster_regions(m, n);
      for (std::size_t k = 0; k < cl.cluster_count(); ++k) {
        const auto tris = cl.triangles_of(k);
        for (std::uint32_t t : tris) EXPECT_EQ(region[t], region[tris[0]]) << "cluster " << k << " crosses a border";
      }
    }
}

TEST(Regions, HardCasesAndRefusals) {
  // One region is the one-run growth; more regions than triangles: one triangle a cluster.
  const Mesh m = jittered(grid(12, 9), 0.1, 5);
  expect_same(cluster_mesh(m, growth(ObjectiveKind::Acc, 1)), cluster_mesh(m, growth(ObjectiveKind::Acc, 0)), "1 region");
  const Clustering many = cluster_mesh(m, growth(ObjectiveKind::Acc, 100000));
  EXPECT_EQ(many.cluster_count(), m.triangle_count());
  EXPECT_EQ(cluster_mesh(Mesh{}, growth(ObjectiveKind::Acc, 4)).cluster_count(), 0u);
  // Every triangle collapsed to one point (AvgSA = 0): one triangle a cluster, as in one run.
  std::vector<Vec3> same(m.vertex_count(), Vec3(1, 2, 3));
  const Mesh collapsed = m.with_positions(std::move(same));
  expect_same(cluster_mesh(collapsed, growth(ObjectiveKind::Acc, 4)), cluster_mesh(collapsed, growth(ObjectiveKind::Acc, 0)),
              "collapsed");
  // Regions are a mode of growth and contraction with Acc or Naive, without a target count.
  ClusterConfig c = growth(ObjectiveKind::Acc, 4);
  c.method = ClusterMethod::SahSplit;
  EXPECT_THROW((void)cluster_in_regions(m, c, 1.0), std::invalid_argument);
  c = growth(ObjectiveKind::Gwh01, 4);
  EXPECT_THROW((void)cluster_in_regions(m, c, 1.0), std::invalid_argument);
  c = growth(ObjectiveKind::Naive, 4, StartRule::SpatialOrder, ClusterMethod::Contraction);
  c.target_clusters = 10;
  EXPECT_THROW((void)cluster_in_regions(m, c, 1.0), std::invalid_argument);
  ASSERT_TRUE(check(c).has_value());
  EXPECT_EQ(check(c)->parameter, "regions");
  for (ClusterConfig bad : {growth(ObjectiveKind::Gwh01, 4), growth(ObjectiveKind::Acc, 4, StartRule::SpatialOrder,
                                                                     ClusterMethod::SahSplit)}) {
    ASSERT_TRUE(check(bad).has_value());
    EXPECT_EQ(check(bad)->parameter, "regions");
  }
  EXPECT_FALSE(check(growth(ObjectiveKind::Naive, 4, StartRule::SpatialOrder, ClusterMethod::Contraction)).has_value());
  const auto used = used_parameters(growth(ObjectiveKind::Acc, 4));
  EXPECT_NE(std::find(used.begin(), used.end(), "regions"), used.end());
  const auto used_gwh = used_parameters(growth(ObjectiveKind::Gwh01, 4));
  EXPECT_EQ(std::find(used_gwh.begin(), used_gwh.end(), "regions"), used_gwh.end());
  const auto used_c = used_parameters(growth(ObjectiveKind::Acc, 4, StartRule::SpatialOrder, ClusterMethod::Contraction));
  EXPECT_NE(std::find(used_c.begin(), used_c.end(), "regions"), used_c.end());
}

// A stop request ends a clustering in regions with ptc::Interrupted (every region polls it when
// it reports progress, on any thread), and progress is only reported on the caller's thread.
TEST(Regions, StopsOnRequestAndReportsOnTheCallersThread) {
  const Mesh m = armadillo_52k();
  const std::thread::id caller = std::this_thread::get_id();
  std::size_t calls = 0, foreign = 0;
  double last = 0.0;
  bool monotonic = true;
  const Clustering c = cluster_mesh(m, growth(ObjectiveKind::Acc, 8), [&](double f) {
    ++calls;
    foreign += std::this_thread::get_id() != caller;
    monotonic = monotonic && f >= last;
    last = f;
  });
  EXPECT_GT(calls, 2u);
  EXPECT_EQ(foreign, 0u);
  EXPECT_TRUE(monotonic);
  EXPECT_EQ(last, 1.0);
  EXPECT_GT(c.cluster_count(), 0u);
  request_cancel();
  EXPECT_THROW((void)cluster_mesh(m, growth(ObjectiveKind::Acc, 8)), Interrupted);
  EXPECT_THROW((void)cluster_mesh(m, growth(ObjectiveKind::Naive, 8, StartRule::SpatialOrder, ClusterMethod::Contraction)),
               Interrupted);
  reset_cancel();
  expect_same(cluster_mesh(m, growth(ObjectiveKind::Acc, 8)), c, "after the reset");
}

}  // namespace
}  // namespace ptc
