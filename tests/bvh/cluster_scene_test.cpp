// The cluster scene's layout, against answers computed here: Linear leaves keep each cluster's
// triangles in Morton order of their rest-pose centroids (10-bit cells over the cluster's
// centroid box, interleaved bit by bit in this file, ties by triangle id); the scene's cluster
// order is cluster_visit_order. And the trace frame's origin rule of both scenes.
#include "bvh/cluster_scene.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cstring>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <utility>
#include <vector>

#include "toolkit/clustering/morton_runs.h"
#include "bvh/scene_config.h"
#include "test_util.h"

namespace ptc::bvh {
namespace {

// The expected order of one cluster's triangles: (code, id) sorted, code = the cell indices'
// bits interleaved x y z from the top bit down (x most significant).
std::vector<std::uint32_t> expected_cluster_order(const Mesh& m, std::vector<std::uint32_t> ids) {
  std::vector<Vec3> cen;
  Box3 box;
  for (std::uint32_t t : ids) {
    const auto c = m.corners(t);
    cen.push_back((c[0] + c[1] + c[2]) / 3.0);
    box.extend(cen.back());
  }
  const double e = (box.hi - box.lo).maxCoeff();
  const double scale = e > 0 ? 1023.0 / e : 0.0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> keyed;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const Vec3 q = (cen[i] - box.lo) * scale;
    const std::uint32_t cell[3] = {static_cast<std::uint32_t>(q.x()), static_cast<std::uint32_t>(q.y()),
                                   static_cast<std::uint32_t>(q.z())};
    std::uint32_t code = 0;
    for (int bit = 9; bit >= 0; --bit)
      for (int a = 0; a < 3; ++a) code = (code << 1) | ((cell[a] >> bit) & 1u);
    keyed.push_back({code, ids[i]});
  }
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = keyed[i].second;
  return ids;
}

TEST(ClusterScene, LinearLeavesAreInMortonOrderOfRestCentroids) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Mesh moved = test::deformed(m, 0.05);  // the order is the rest pose's, whatever the frame
  for (std::uint32_t run : {7u, 37u, 200u}) {
    const Clustering runs = ptc::morton_runs(m, run);
    for (std::uint32_t groups : {0u, 8u}) {
      SceneConfig cfg = cluster_scene_defaults();
      cfg.cluster_group_size = groups;
      ClusterScene s(m, view_of(runs), cfg);
      s.update(moved.positions());
      const std::vector<std::uint32_t> visit = cluster_visit_order(m, view_of(runs), cfg);
      EXPECT_EQ(s.cluster_ids(), visit);
      // The BVH's primitive i is scene cluster prim_order[i], traced through ranges[i].
      const TraceData& d = s.data();
      ASSERT_EQ(d.ranges.size(), runs.cluster_count());
      for (std::size_t i = 0; i < d.ranges.size(); ++i) {
        const std::uint32_t c = s.cluster_ids()[s.bvh().prim_order[i]];
        const std::vector<std::uint32_t> members(runs.triangle_order.begin() + runs.triangle_offsets[c],
                                                 runs.triangle_order.begin() + runs.triangle_offsets[c + 1]);
        const LeafRange r = d.ranges[i];
        ASSERT_EQ(r.triangle_count, members.size());
        const std::vector<std::uint32_t> got(d.triangle_ids.begin() + 4 * std::size_t(r.first_block),
                                             d.triangle_ids.begin() + 4 * std::size_t(r.first_block) + members.size());
        EXPECT_EQ(got, expected_cluster_order(m, members)) << "run " << run << " cluster " << c;
      }
    }
  }
}

// With more than one thread the leaf data is written while the tree is built and linked: the
// flat data must be the same bytes at 1, 2 and 4 threads, frame after frame, and the stage times
// must add up to no more than the update's wall time (overlap_ms = what two stages shared; 0 on
// one thread).
TEST(ClusterScene, SameDataAtAnyThreadCountAndStagesAddUpToTheWallTime) {
  const Mesh m = test::load_mesh("armadillo.off");  // 13k blocks: more than one fill chunk
  const Clustering runs = ptc::morton_runs(m, 37);
  const std::vector<Mesh> frames{test::deformed(m, 0.02), test::deformed(m, 0.06)};
  for (ClusterLeaf leaf : {ClusterLeaf::Linear, ClusterLeaf::BlockTree}) {
    std::vector<TraceData> want;
    for (int threads : {1, 2, 4}) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
      SceneConfig cfg = cluster_scene_defaults();
      cfg.cluster_leaf = leaf;
      ClusterScene s(m, view_of(runs), cfg);
      for (std::size_t f = 0; f < frames.size(); ++f) {
        const auto t0 = std::chrono::steady_clock::now();
        s.update(frames[f].positions());
        const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        const std::string what = std::string(to_string(leaf)) + " threads " + std::to_string(threads) + " frame " +
                                 std::to_string(f);
        const StageTimes& t = s.times();
        EXPECT_GE(t.overlap_ms, 0.0) << what;
        if (threads == 1) {
          EXPECT_EQ(t.overlap_ms, 0.0) << what;
        }
        EXPECT_LE(t.overlap_ms, std::min(t.leaf_data_ms, t.build_ms + t.collapse_ms) + 1e-9) << what;
        EXPECT_LE(t.total_ms(), wall + 1e-6) << what;
        const TraceData& d = s.data();
        ASSERT_TRUE(validate(d, m.triangle_count(), false).empty()) << what << test::joined(validate(d, m.triangle_count(), false));
        if (threads == 1) {
          want.push_back(d);
          continue;
        }
        const TraceData& w = want[f];
        ASSERT_EQ(d.wide.nodes.size(), w.wide.nodes.size()) << what;
        EXPECT_EQ(std::memcmp(d.wide.nodes.data(), w.wide.nodes.data(), w.wide.nodes.size() * sizeof(WideNode)), 0) << what;
        ASSERT_EQ(d.blocks.size(), w.blocks.size()) << what;
        EXPECT_EQ(std::memcmp(d.blocks.data(), w.blocks.data(), w.blocks.size() * sizeof(TriBlock)), 0) << what;
        EXPECT_TRUE(std::equal(d.triangle_ids.begin(), d.triangle_ids.end(), w.triangle_ids.begin(), w.triangle_ids.end()))
            << what;
        ASSERT_EQ(d.ranges.size(), w.ranges.size()) << what;
        for (std::size_t i = 0; i < w.ranges.size(); ++i)
          ASSERT_TRUE(d.ranges[i].first_block == w.ranges[i].first_block &&
                      d.ranges[i].block_count == w.ranges[i].block_count &&
                      d.ranges[i].triangle_count == w.ranges[i].triangle_count)
              << what << " range " << i;
        EXPECT_EQ(d.wide.root, w.wide.root) << what;
      }
    }
  }
}

TEST(ClusterScene, TheSweepBuilderHasNoTwoLevelBuild) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Clustering runs = ptc::morton_runs(m, 20);
  SceneConfig cfg = cluster_scene_defaults();
  cfg.builder = SahBuilder::Sweep;
  cfg.cluster_group_size = 8;
  EXPECT_THROW(ClusterScene(m, view_of(runs), cfg), std::invalid_argument);
  cfg.cluster_group_size = 0;
  const ClusterScene s(m, view_of(runs), cfg);
  EXPECT_EQ(s.data().ranges.size(), runs.cluster_count());
  EXPECT_STREQ(to_string(SahBuilder::Sweep), "sweep");
  EXPECT_STREQ(to_string(SahBuilder::Binned), "binned");
}

TEST(SceneConfig, TraceFrameOrigin) {
  EXPECT_EQ(trace_frame_origin(Mesh(), SceneConfig{}), Vec3::Zero());
  const Mesh m = test::grid_cube(2, 1.0, Vec3(10, 20, 30));
  EXPECT_EQ(trace_frame_origin(m, SceneConfig{}), Vec3(10, 20, 30));  // the bounds' centre
  SceneConfig at;
  at.origin = Vec3(1, 2, 3);
  EXPECT_EQ(trace_frame_origin(m, at), Vec3(1, 2, 3));
  at.origin = Vec3(1, std::numeric_limits<double>::infinity(), 3);
  EXPECT_THROW((void)trace_frame_origin(m, at), std::invalid_argument);
  std::vector<Vec3> p(m.positions().begin(), m.positions().end());
  p[5].y() = std::numeric_limits<double>::quiet_NaN();
  try {
    (void)trace_frame_origin(m.with_positions(std::move(p)), SceneConfig{});
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 5"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ptc::bvh
