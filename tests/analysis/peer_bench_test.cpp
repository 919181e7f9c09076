// The Embree side-by-side benchmark on a small mesh: every configuration and frame present,
// zero mismatches of the closest triangle, summaries equal to medians recomputed from the rows,
// and the deformations checked against their definitions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "analysis/peer_bench.h"
#include "analysis/trace_deform.h"
#include "toolkit/mesh/subdivision.h"

using ptc::Mesh;
using ptc::Vec3;

namespace {

Mesh sphere(int levels) {
  std::vector<Vec3> p{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<ptc::Tri> t{{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  Mesh m = ptc::subdivide(Mesh(std::move(t), std::move(p)), ptc::SubdivisionScheme::Midpoint, levels);
  std::vector<Vec3> q;
  for (const Vec3& v : m.positions()) q.push_back(Vec3(v.normalized().cwiseProduct(Vec3(1.0, 2.0, 0.7))));
  return m.with_positions(std::move(q));
}

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

}  // namespace

TEST(PeerBench, SmallMeshAllConfigurationsNoMismatches) {
  const Mesh m = sphere(4);  // 2048 triangles
  ptc::PeerBenchConfig cfg;
  cfg.frames = 3;
  cfg.width = 40, cfg.height = 32;
  cfg.max_count = 20;
  const ptc::PeerBenchResult r = ptc::run_peer_bench(m, nullptr, cfg);
  const auto& names = ptc::peer_bench_configs();
  ASSERT_EQ(r.rows.size(), 3u * names.size());
  EXPECT_EQ(r.rays, 40u * 32u);
  EXPECT_GT(r.clusters, 20u);
  for (int f = 0; f < 3; ++f) {
    std::uint64_t hits = 0;
    for (std::size_t c = 0; c < names.size(); ++c) {
      const ptc::BenchRow& row = r.rows[std::size_t(f) * names.size() + c];
      EXPECT_EQ(row.frame, f);
      EXPECT_EQ(row.config, names[c]);
      EXPECT_EQ(row.rays, r.rays);
      EXPECT_EQ(row.mismatches, 0u) << row.config << " frame " << f;
      EXPECT_EQ(row.hit_miss + row.other_triangle, row.mismatches);
      EXPECT_GT(row.build_ms, 0.0) << row.config;
      EXPECT_GE(row.update_ms, 0.0) << row.config;
      EXPECT_GT(row.trace_ms, 0.0) << row.config;
      if (c == 0) hits = row.hits;
      EXPECT_EQ(row.hits, hits) << row.config << " frame " << f;
    }
    EXPECT_GT(hits, 200u);
  }
  // Summaries: medians over frames 1..2 (frame 0 skipped), recomputed here from the rows.
  EXPECT_EQ(r.median_first_frame, 1);
  ASSERT_EQ(r.summary.size(), names.size());
  for (std::size_t c = 0; c < names.size(); ++c) {
    const auto& a = r.rows[names.size() + c];
    const auto& b = r.rows[2 * names.size() + c];
    EXPECT_EQ(r.summary[c].config, names[c]);
    EXPECT_DOUBLE_EQ(r.summary[c].trace_ms, 0.5 * (a.trace_ms + b.trace_ms));
    EXPECT_DOUBLE_EQ(r.summary[c].build_ms, 0.5 * (a.build_ms + b.build_ms));
    EXPECT_DOUBLE_EQ(r.summary[c].update_build_ms, 0.5 * (a.update_ms + a.build_ms + b.update_ms + b.build_ms));
  }
  // The CSVs: one row per frame and configuration; summary one per configuration with the ratios.
  const auto bench = split_lines(ptc::bench_csv(r).str());
  ASSERT_EQ(bench.size(), 1 + r.rows.size());
  EXPECT_EQ(bench[0].rfind("frame,config,update_ms,build_ms,", 0), 0u) << bench[0];
  std::set<std::string> seen;
  for (std::size_t i = 1; i < bench.size(); ++i) seen.insert(bench[i].substr(bench[i].find(',') + 1, bench[i].find(',', bench[i].find(',') + 1) - bench[i].find(',') - 1));
  EXPECT_EQ(seen, std::set<std::string>(names.begin(), names.end()));
  const auto summary = split_lines(ptc::bench_summary_csv(r).str());
  ASSERT_EQ(summary.size(), 1 + names.size());
  EXPECT_NE(summary[0].find("trace_speed_vs_embree_refit"), std::string::npos);
  const std::string table = ptc::bench_table(r);
  for (const auto& n : names) EXPECT_NE(table.find(n), std::string::npos);
}

TEST(PeerBench, GivenClusteringAndLinearLeavesAlsoMatch) {
  const Mesh m = sphere(3);
  // Clusters: the 8 octants of the octahedron (each connected).
  std::vector<std::uint32_t> label(m.triangle_count());
  for (std::size_t t = 0; t < m.triangle_count(); ++t) label[t] = std::uint32_t(t / (m.triangle_count() / 8));
  const ptc::Clustering c = ptc::clustering_from_labels(label, m.triangles());
  ptc::PeerBenchConfig cfg;
  cfg.frames = 2;
  cfg.width = cfg.height = 24;
  cfg.deformation = ptc::Deformation::Wave;
  cfg.cluster_leaf = ptc::bvh::ClusterLeaf::Linear;
  cfg.threads = 2;
  const auto r = ptc::run_peer_bench(m, &c, cfg);
  EXPECT_EQ(r.clusters, 8u);
  for (const auto& row : r.rows) EXPECT_EQ(row.mismatches, 0u) << row.config << " frame " << row.frame;
  EXPECT_THROW((void)ptc::run_peer_bench(m, &c, [&] { auto x = cfg; x.frames = 0; return x; }()), std::invalid_argument);
}

TEST(PeerBench, MedianAndSummarize) {
  EXPECT_EQ(ptc::median({}), 0.0);
  EXPECT_EQ(ptc::median({3}), 3.0);
  EXPECT_EQ(ptc::median({4, 1, 3}), 3.0);
  EXPECT_EQ(ptc::median({4, 1, 3, 10}), 3.5);
  std::vector<ptc::BenchRow> rows;
  for (int f = 0; f < 4; ++f) {
    ptc::BenchRow r;
    r.frame = f;
    r.config = "x";
    r.trace_ms = f == 0 ? 1000.0 : double(f);  // a slow first frame must not count
    r.mismatches = f == 0 ? 2 : 0;
    rows.push_back(r);
  }
  const auto s = ptc::summarize(rows, 1);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].trace_ms, 2.0);
  EXPECT_EQ(s[0].mismatches, 2u);  // mismatches are summed over every frame
}

TEST(TraceDeform, TwistWaveAndNoneFollowTheirDefinitions) {
  const Mesh m = sphere(2);
  const ptc::Box3 b = m.bounds();
  const auto rest = m.positions();
  std::vector<Vec3> out(rest.size());
  // Frame 0 (and whole periods) is the rest pose, for every kind.
  for (auto kind : {ptc::Deformation::None, ptc::Deformation::Twist, ptc::Deformation::Wave})
    for (int f : {0, ptc::kDeformPeriod, 2 * ptc::kDeformPeriod}) {
      ptc::deform(rest, b, kind, f, out);
      for (std::size_t v = 0; v < rest.size(); ++v) ASSERT_EQ(out[v], rest[v]);
    }
  const Vec3 c = b.center();
  ptc::deform(rest, b, ptc::Deformation::Twist, 6, out);  // a quarter period: amplitude 1
  std::size_t moved = 0;
  for (std::size_t v = 0; v < rest.size(); ++v) {
    EXPECT_EQ(out[v].y(), rest[v].y());
    const double r0 = std::hypot(rest[v].x() - c.x(), rest[v].z() - c.z());
    const double r1 = std::hypot(out[v].x() - c.x(), out[v].z() - c.z());
    EXPECT_NEAR(r0, r1, 1e-12);
    // The rotation angle grows linearly with height: 0.6 rad at the top.
    if (r0 > 0.1) {
      const double a0 = std::atan2(rest[v].z() - c.z(), rest[v].x() - c.x());
      const double a1 = std::atan2(out[v].z() - c.z(), out[v].x() - c.x());
      const double expect = 0.6 * (rest[v].y() - b.lo.y()) / (b.hi.y() - b.lo.y());
      EXPECT_NEAR(std::remainder(a0 - a1, 2 * M_PI), expect, 1e-9);
      moved += expect > 0.01;
    }
  }
  EXPECT_GT(moved, 10u);
  ptc::deform(rest, b, ptc::Deformation::Wave, 3, out);
  for (std::size_t v = 0; v < rest.size(); ++v) {
    EXPECT_EQ(out[v].x(), rest[v].x());
    EXPECT_EQ(out[v].y(), rest[v].y());
    EXPECT_LE(std::abs(out[v].z() - rest[v].z()), 0.05 * (b.hi - b.lo).norm() + 1e-12);
  }
  EXPECT_EQ(ptc::parse_deformation("wave"), ptc::Deformation::Wave);
  EXPECT_FALSE(ptc::parse_deformation("Twist"));
  std::vector<Vec3> wrong(3);
  EXPECT_THROW(ptc::deform(rest, b, ptc::Deformation::Twist, 1, wrong), std::invalid_argument);
}

// Frames from a scene's positions (a FramePositions callback) instead of the stand-in
// deformation: the callback is asked for scene frames first_frame .. first_frame + frames - 1 in
// order, rows carry them as scene_frame, and every configuration sees those positions (the hits
// follow a mesh that moves out of the view: fewer hits each frame, all configurations agreeing).
TEST(PeerBench, ScenePositionsDriveTheFrames) {
  const Mesh m = sphere(3);
  ptc::PeerBenchConfig cfg;
  cfg.frames = 3;
  cfg.first_frame = 4;
  cfg.width = cfg.height = 24;
  cfg.max_count = 16;
  std::vector<std::int64_t> asked;
  std::vector<Vec3> rest(m.positions().begin(), m.positions().end());
  cfg.positions = [&](std::int64_t f, std::span<Vec3> out) {
    asked.push_back(f);
    for (std::size_t v = 0; v < out.size(); ++v) out[v] = rest[v] + Vec3(3.0 * double(f - 4), 0, 0);
  };
  // The benchmark renumbers the vertices once (cluster order): the frame source follows.
  EXPECT_THROW((void)ptc::run_peer_bench(m, nullptr, cfg), std::invalid_argument);  // no renumber_positions
  int renumbered = 0;
  cfg.renumber_positions = [&](std::span<const std::uint32_t> to_old) {
    ++renumbered;
    std::vector<Vec3> r2(rest.size());
    for (std::size_t i = 0; i < r2.size(); ++i) r2[i] = rest[to_old[i]];
    rest = std::move(r2);
  };
  const auto r = ptc::run_peer_bench(m, nullptr, cfg);
  EXPECT_EQ(renumbered, 1);
  EXPECT_EQ(r.vertex_order, "clusters");
  EXPECT_TRUE(r.fused_vertex_pass);
  EXPECT_EQ(asked, (std::vector<std::int64_t>{4, 5, 6}));
  const std::size_t nc = ptc::peer_bench_configs().size();
  ASSERT_EQ(r.rows.size(), 3 * nc);
  for (const auto& row : r.rows) {
    EXPECT_EQ(row.scene_frame, 4 + row.frame);
    EXPECT_EQ(row.mismatches, 0u) << row.config << " frame " << row.frame;
  }
  EXPECT_GT(r.rows[0].hits, r.rows[nc].hits);
  EXPECT_GT(r.rows[nc].hits, r.rows[2 * nc].hits);
  const auto bench = split_lines(ptc::bench_csv(r).str());
  EXPECT_NE(bench[0].find(",scene_frame,source_ms"), std::string::npos);

  // The file's vertex order: the cluster path gathers; the same hits, frame by frame.
  rest.assign(m.positions().begin(), m.positions().end());
  asked.clear();
  cfg.cluster_vertex_order = false;
  const auto ri = ptc::run_peer_bench(m, nullptr, cfg);
  EXPECT_EQ(renumbered, 1);
  EXPECT_EQ(ri.vertex_order, "input");
  EXPECT_FALSE(ri.fused_vertex_pass);
  ASSERT_EQ(ri.rows.size(), r.rows.size());
  for (std::size_t i = 0; i < r.rows.size(); ++i) {
    EXPECT_EQ(ri.rows[i].hits, r.rows[i].hits) << r.rows[i].config;
    EXPECT_EQ(ri.rows[i].mismatches, 0u);
  }
}
