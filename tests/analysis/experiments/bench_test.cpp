// The Embree side-by-side benchmark on a small mesh: every configuration and frame present,
// zero mismatches of the closest triangle, summaries equal to medians recomputed from the rows,
// through the one frame loop over a scene (a deformer moving the mesh).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "analysis/experiments/bench.h"
#include "common/csv_rows.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/core/stats.h"
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

// The mesh under a deformer (deform_preset(kind) unless params are given), frames 0..59.
ptc::Scene scene_of(const Mesh& m, ptc::DeformKind kind = ptc::DeformKind::Twist,
                    std::optional<ptc::DeformParams> params = {}) {
  std::vector<ptc::ScenePart> parts;
  parts.push_back({"mesh", ptc::make_deformer(m, params ? *params : ptc::deform_preset(kind))});
  return ptc::Scene("test", std::move(parts), std::nullopt, std::nullopt, ptc::FrameRange{0, 59});
}

std::vector<std::string> names_of_configs() {
  std::vector<std::string> n;
  for (auto k : ptc::loop::kAllAccelKinds) n.emplace_back(ptc::loop::to_string(k));
  return n;
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
  cfg.frames = {0, 2};
  cfg.width = 40, cfg.height = 32;
  cfg.max_count = 20;
  ptc::Scene sc = scene_of(m);
  const ptc::PeerBenchResult r = ptc::run_peer_bench(sc, std::nullopt, cfg);
  const auto names = names_of_configs();
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
      EXPECT_EQ(row.agreement.mismatches(), 0u) << row.config << " frame " << f;
      EXPECT_EQ(row.agreement.rays, c == 0 ? 0u : r.rays);
      EXPECT_GT(row.times.build_ms, 0.0) << row.config;
      EXPECT_GE(row.times.update_ms, 0.0) << row.config;
      if (c < 2) EXPECT_GT(row.sah_cost, 0.0) << row.config;  // ours: the tree's SAH cost
      else EXPECT_TRUE(std::isnan(row.sah_cost)) << row.config;
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
    EXPECT_DOUBLE_EQ(r.summary[c].build_ms, 0.5 * (a.times.build_ms + b.times.build_ms));
    EXPECT_DOUBLE_EQ(r.summary[c].update_build_ms,
                     0.5 * (a.times.update_ms + a.times.build_ms + b.times.update_ms + b.times.build_ms));
  }
  // The CSVs: one row per frame and configuration; summary one per configuration with the ratios.
  const auto bench = split_lines(ptc::bench_table(r).csv.str());
  ASSERT_EQ(bench.size(), 1 + r.rows.size());
  EXPECT_EQ(bench[0].rfind("frame,config,update_ms,build_ms,", 0), 0u) << bench[0];
  std::set<std::string> seen;
  for (std::size_t i = 1; i < bench.size(); ++i) seen.insert(bench[i].substr(bench[i].find(',') + 1, bench[i].find(',', bench[i].find(',') + 1) - bench[i].find(',') - 1));
  EXPECT_EQ(seen, std::set<std::string>(names.begin(), names.end()));
  const auto summary = split_lines(ptc::bench_summary_table(r).csv.str());
  ASSERT_EQ(summary.size(), 1 + names.size());
  EXPECT_NE(summary[0].find("trace_speed_vs_embree_refit"), std::string::npos);
  const std::string table = ptc::bench_text(r);
  for (const auto& n : names) EXPECT_NE(table.find(n), std::string::npos);
  // The text table's hits and shadow_rays are medians over the frames, like its other columns
  // (they were the last frame's counts): against the rows, config by config.
  bool varies = false;  // (else the last frame's count would pass for the median)
  for (const auto& n : names) {
    std::vector<double> h, sh;
    for (const auto& row : r.rows)
      if (row.config == n && row.frame >= r.median_first_frame)
        h.push_back(static_cast<double>(row.hits)), sh.push_back(static_cast<double>(row.shadow_rays));
    varies = varies || h.front() != h.back() || sh.front() != sh.back();
    const std::string line_start = "\n" + n + " ";
    const auto at = table.find(line_start, table.find("update_ms"));  // the stage table's line of the config
    ASSERT_NE(at, std::string::npos) << n;
    std::istringstream line(table.substr(at + 1, table.find('\n', at + 1) - at - 1));
    std::vector<std::string> cells;
    for (std::string c; line >> c;) cells.push_back(c);
    ASSERT_EQ(cells.size(), 12u) << n;
    // Counts in full ("{:g}" printed 1048576 as 1.04858e+06); a median between two counts ends in .5.
    auto count = [](double v) { return v == std::floor(v) ? fmt::format("{:.0f}", v) : fmt::format("{:.1f}", v); };
    EXPECT_EQ(cells[6], count(ptc::median(h))) << n;
    EXPECT_EQ(cells[10], count(ptc::median(sh))) << n;
  }
  EXPECT_TRUE(varies) << "the frames' counts must differ for the medians to be tested";
}

// The shadow pass. A convex ellipsoid under a rigid motion with the light outside it: a point
// facing the light sees it (nothing of a convex surface lies between), so no shadow ray of any
// configuration may be occluded, and every configuration traces the same batch (the points of
// ours_triangles' hits that face the light, counted here from the rows' primary hits).
TEST(PeerBench, ShadowRaysOfAConvexMeshAreNeverOccluded) {
  const Mesh m = sphere(4);
  ptc::PeerBenchConfig cfg;
  cfg.frames = {0, 2};
  cfg.width = 40, cfg.height = 32;
  cfg.max_count = 20;
  cfg.light = Vec3(3.0, 5.0, 4.0);
  ptc::Scene sc = scene_of(m, ptc::DeformKind::Rigid);
  const ptc::PeerBenchResult r = ptc::run_peer_bench(sc, std::nullopt, cfg);
  EXPECT_TRUE(r.shadows);
  const auto names = names_of_configs();
  ASSERT_EQ(r.rows.size(), 3u * names.size());
  for (int f = 0; f < 3; ++f) {
    const ptc::BenchRow& ref = r.rows[std::size_t(f) * names.size()];
    EXPECT_GT(ref.shadow_rays, 50u) << "frame " << f;
    EXPECT_LT(ref.shadow_rays, ref.hits) << "frame " << f;  // the far side of the ellipsoid faces away
    for (std::size_t c = 0; c < names.size(); ++c) {
      const ptc::BenchRow& row = r.rows[std::size_t(f) * names.size() + c];
      EXPECT_EQ(row.shadow_rays, ref.shadow_rays) << row.config << " frame " << f;
      EXPECT_EQ(row.shadow_occluded, 0u) << row.config << " frame " << f;
      EXPECT_EQ(row.shadow_mismatches, 0u) << row.config << " frame " << f;
      EXPECT_GT(row.shadow_ms, 0.0) << row.config;
      EXPECT_DOUBLE_EQ(row.whole_frame_ms(),
                       row.times.update_ms + row.times.build_ms + row.trace_ms + row.shadow_ms);
    }
  }
  for (std::size_t c = 0; c < names.size(); ++c) {
    const auto& a = r.rows[names.size() + c];
    const auto& b = r.rows[2 * names.size() + c];
    EXPECT_DOUBLE_EQ(r.summary[c].shadow_ms, 0.5 * (a.shadow_ms + b.shadow_ms));
    EXPECT_DOUBLE_EQ(r.summary[c].whole_frame_ms, 0.5 * (a.whole_frame_ms() + b.whole_frame_ms()));
  }
  const auto summary = split_lines(ptc::bench_summary_table(r).csv.str());
  EXPECT_NE(summary[0].find("whole_frame_speedup_vs_embree_refit"), std::string::npos);
  const std::string text = ptc::bench_text(r);
  EXPECT_LT(text.find("whole frame"), text.find("update_ms")) << "the whole frame is printed first";
}

// Two ellipsoids, the second between the light of occluder_bench_config() and the first.
Mesh ellipsoid_and_occluder() {
  const Mesh a = sphere(4);
  std::vector<Vec3> p(a.positions().begin(), a.positions().end());
  std::vector<ptc::Tri> t(a.triangles().begin(), a.triangles().end());
  const auto n = static_cast<std::uint32_t>(p.size());
  for (const Vec3& v : a.positions()) p.push_back(0.5 * v + Vec3(0.8, 2.5, 1.2));
  for (const ptc::Tri& tri : a.triangles()) t.push_back({tri[0] + n, tri[1] + n, tri[2] + n});
  return Mesh(std::move(t), std::move(p));
}

ptc::PeerBenchConfig occluder_bench_config() {
  ptc::PeerBenchConfig cfg;
  cfg.frames = {0, 1};
  cfg.width = cfg.height = 48;
  cfg.max_count = 20;
  cfg.light = Vec3(1.6, 5.0, 2.4);
  return cfg;
}

// Occluders: two ellipsoids, the second between the light and the first. The shadow rays of
// the first one's lit-side points end on the second; every configuration agrees with
// ours_triangles point by point, and the occluded count is the same everywhere.
TEST(PeerBench, ShadowRaysAgreeAcrossConfigurationsWithOccluders) {
  const Mesh m = ellipsoid_and_occluder();
  ptc::PeerBenchConfig cfg = occluder_bench_config();
  ptc::Scene sc = scene_of(m, ptc::DeformKind::Rigid);
  const ptc::PeerBenchResult r = ptc::run_peer_bench(sc, std::nullopt, cfg);
  // Packets on both sides (ours: 8 lanes; Embree: rtcIntersect8 / rtcOccluded8): the same hits
  // and the same occluded points as single rays, configuration by configuration.
  cfg.packets = true;
  ptc::Scene sc2 = scene_of(m, ptc::DeformKind::Rigid);
  const ptc::PeerBenchResult rp = ptc::run_peer_bench(sc2, std::nullopt, cfg);
  const auto names = names_of_configs();
  ASSERT_EQ(rp.rows.size(), r.rows.size());
  for (int f = 0; f < 2; ++f) {
    const ptc::BenchRow& ref = r.rows[std::size_t(f) * names.size()];
    EXPECT_GT(ref.shadow_occluded, 10u) << "frame " << f;
    for (std::size_t c = 0; c < names.size(); ++c) {
      const ptc::BenchRow& row = r.rows[std::size_t(f) * names.size() + c];
      const ptc::BenchRow& packed = rp.rows[std::size_t(f) * names.size() + c];
      EXPECT_EQ(row.shadow_rays, ref.shadow_rays) << row.config;
      EXPECT_EQ(row.shadow_occluded, ref.shadow_occluded) << row.config;
      EXPECT_EQ(row.shadow_mismatches, 0u) << row.config;
      EXPECT_EQ(packed.hits, row.hits) << "packets " << row.config;
      EXPECT_EQ(packed.agreement.mismatches(), 0u) << "packets " << row.config;
      EXPECT_EQ(packed.shadow_rays, row.shadow_rays) << "packets " << row.config;
      EXPECT_EQ(packed.shadow_occluded, row.shadow_occluded) << "packets " << row.config;
      EXPECT_EQ(packed.shadow_mismatches, 0u) << "packets " << row.config;
    }
  }
  // Embree's shadow packets: by default (Best) each frame timed with both context flags, the
  // faster counted and the other kept; with one flag, that flag alone. The same occluded points
  // with every flag; ours and single rays have no flag.
  const bool embree_row[] = {false, false, true, true, true};
  ASSERT_EQ(names.size(), std::size(embree_row));
  for (const ptc::EmbreeShadowHint hint :
       {ptc::EmbreeShadowHint::Best, ptc::EmbreeShadowHint::Coherent, ptc::EmbreeShadowHint::Incoherent}) {
    cfg.embree_shadow_hint = hint;
    ptc::Scene sc3 = scene_of(m, ptc::DeformKind::Rigid);
    const ptc::PeerBenchResult rh = ptc::run_peer_bench(sc3, std::nullopt, cfg);
    ASSERT_EQ(rh.rows.size(), r.rows.size());
    for (std::size_t i = 0; i < rh.rows.size(); ++i) {
      const ptc::BenchRow& row = rh.rows[i];
      const ptc::BenchRow& single = r.rows[i];
      const std::string at = std::string(ptc::to_string(hint)) + " " + row.config + " frame " + std::to_string(row.frame);
      EXPECT_TRUE(single.shadow_hint.empty()) << at;
      EXPECT_TRUE(std::isnan(single.shadow_other_ms)) << at;
      EXPECT_EQ(row.shadow_occluded, single.shadow_occluded) << at;
      EXPECT_EQ(row.shadow_mismatches, 0u) << at;
      if (!embree_row[i % names.size()]) {
        EXPECT_TRUE(row.shadow_hint.empty()) << at;
        EXPECT_TRUE(std::isnan(row.shadow_other_ms)) << at;
      } else if (hint == ptc::EmbreeShadowHint::Best) {
        EXPECT_TRUE(row.shadow_hint == "coherent" || row.shadow_hint == "incoherent") << at << ": " << row.shadow_hint;
        EXPECT_GE(row.shadow_other_ms, row.shadow_ms) << at;  // (the faster counts)
      } else {
        EXPECT_EQ(row.shadow_hint, ptc::to_string(hint)) << at;
        EXPECT_TRUE(std::isnan(row.shadow_other_ms)) << at;
      }
    }
    const std::string text = ptc::bench_text(rh);
    EXPECT_EQ(text.find("Embree's shadow packets, the faster flag per frame") != std::string::npos,
              hint == ptc::EmbreeShadowHint::Best)
        << text;
  }
}

// The shadow batch in Morton order: the same occluded points in every configuration as in pixel
// order, the ordering's time once a frame in every row of the frame and in its whole frame.
TEST(PeerBench, ShadowRaysInMortonOrderLightTheSamePoints) {
  const Mesh m = ellipsoid_and_occluder();
  ptc::PeerBenchConfig cfg = occluder_bench_config();
  cfg.packets = true;
  const auto names = names_of_configs();
  ptc::Scene s1 = scene_of(m, ptc::DeformKind::Rigid);
  const ptc::PeerBenchResult pixel = ptc::run_peer_bench(s1, std::nullopt, cfg);
  cfg.shadow_morton = true;
  ptc::Scene s2 = scene_of(m, ptc::DeformKind::Rigid);
  const ptc::PeerBenchResult morton = ptc::run_peer_bench(s2, std::nullopt, cfg);
  ASSERT_EQ(pixel.rows.size(), morton.rows.size());
  for (std::size_t i = 0; i < pixel.rows.size(); ++i) {
    const ptc::BenchRow &x = pixel.rows[i], &y = morton.rows[i];
    const std::string at = y.config + " frame " + std::to_string(y.frame);
    EXPECT_EQ(y.shadow_rays, x.shadow_rays) << at;
    EXPECT_EQ(y.shadow_occluded, x.shadow_occluded) << at;
    EXPECT_GT(y.shadow_occluded, 10u) << at;
    EXPECT_EQ(y.shadow_mismatches, 0u) << at;
    EXPECT_EQ(x.shadow_order_ms, 0.0) << at;
    EXPECT_GT(y.shadow_order_ms, 0.0) << at;
    EXPECT_EQ(y.shadow_order_ms, morton.rows[i - i % names.size()].shadow_order_ms) << at;  // (once a frame)
    EXPECT_DOUBLE_EQ(y.whole_frame_ms(),
                     y.times.update_ms + y.times.build_ms + y.trace_ms + y.shadow_order_ms + y.shadow_ms) << at;
  }
  EXPECT_NE(ptc::bench_text(morton).find("shadow rays in the Morton order of their hit points"), std::string::npos);
  EXPECT_EQ(ptc::bench_text(pixel).find("Morton order"), std::string::npos);
}

TEST(PeerBench, EmbreeShadowHintNamesParse) {
  for (const ptc::EmbreeShadowHint h :
       {ptc::EmbreeShadowHint::Best, ptc::EmbreeShadowHint::Coherent, ptc::EmbreeShadowHint::Incoherent})
    EXPECT_EQ(ptc::parse_embree_shadow_hint(ptc::to_string(h)), h);
  EXPECT_FALSE(ptc::parse_embree_shadow_hint("Coherent"));
  EXPECT_FALSE(ptc::parse_embree_shadow_hint(""));
}

TEST(PeerBench, GivenClusteringAndLinearLeavesAlsoMatch) {
  const Mesh m = sphere(3);
  // Clusters: the 8 octants of the octahedron (each connected).
  std::vector<std::uint32_t> label(m.triangle_count());
  for (std::size_t t = 0; t < m.triangle_count(); ++t) label[t] = std::uint32_t(t / (m.triangle_count() / 8));
  const ptc::Clustering c = ptc::clustering_from_labels(label, m.triangles());
  ptc::PeerBenchConfig cfg;
  cfg.frames = {0, 1};
  cfg.width = cfg.height = 24;
  cfg.cluster_leaf = ptc::bvh::ClusterLeaf::Linear;
  cfg.threads = 2;
  ptc::Scene sc = scene_of(m, ptc::DeformKind::Wave);
  const auto r = ptc::run_peer_bench(sc, c, cfg);
  EXPECT_EQ(r.clusters, 8u);
  for (const auto& row : r.rows) EXPECT_EQ(row.agreement.mismatches(), 0u) << row.config << " frame " << row.frame;
  ptc::Scene sc2 = scene_of(m, ptc::DeformKind::Wave);
  EXPECT_THROW((void)ptc::run_peer_bench(sc2, c, [&] { auto x = cfg; x.frames = {3, 2}; return x; }()),
               std::invalid_argument);
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
    r.agreement.hit_miss = f == 0 ? 2 : 0;
    rows.push_back(r);
  }
  const auto s = ptc::summarize(rows, 1);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].trace_ms, 2.0);
  EXPECT_EQ(s[0].mismatches, 2u);  // mismatches are summed over every frame
}

// Frames from a scene: rows carry the scene frames of the range, and every configuration sees
// the scene's positions (a rigid motion carries the mesh out of the view: fewer hits each frame,
// all configurations agreeing). The vertex renumbering and the file's order give the same hits.
TEST(PeerBench, ScenePositionsDriveTheFrames) {
  const Mesh m = sphere(3);
  ptc::PeerBenchConfig cfg;
  cfg.frames = {4, 6};
  cfg.width = cfg.height = 24;
  cfg.max_count = 16;
  ptc::DeformParams rigid = ptc::deform_preset(ptc::DeformKind::Rigid);
  rigid.amplitude = 0.0;                  // no turn
  rigid.velocity = Vec3(0.07, 0.0, 0.0);  // 7% of the diagonal per frame along x
  ptc::Scene sc = scene_of(m, ptc::DeformKind::Rigid, rigid);
  // The camera frames the rest pose (scene frame 0), so the moving mesh leaves the view.
  const auto r = ptc::run_peer_bench(sc, std::nullopt, cfg);
  EXPECT_EQ(r.vertex_order, "clusters");
  EXPECT_TRUE(r.fused_vertex_pass);
  const std::size_t nc = names_of_configs().size();
  ASSERT_EQ(r.rows.size(), 3 * nc);
  for (const auto& row : r.rows) {
    EXPECT_EQ(row.scene_frame, 4 + row.frame);
    EXPECT_EQ(row.agreement.mismatches(), 0u) << row.config << " frame " << row.frame;
  }
  EXPECT_GT(r.rows[0].hits, r.rows[nc].hits);
  EXPECT_GT(r.rows[nc].hits, r.rows[2 * nc].hits);
  const auto bench = split_lines(ptc::bench_table(r).csv.str());
  EXPECT_NE(bench[0].find(",scene_frame,source_ms"), std::string::npos);

  // The file's vertex order: the cluster path gathers; the same hits, frame by frame.
  cfg.vertex_order = ptc::bvh::VertexOrder::Input;
  ptc::Scene sc2 = scene_of(m, ptc::DeformKind::Rigid, rigid);
  const auto ri = ptc::run_peer_bench(sc2, std::nullopt, cfg);
  EXPECT_EQ(ri.vertex_order, "input");
  EXPECT_FALSE(ri.fused_vertex_pass);
  ASSERT_EQ(ri.rows.size(), r.rows.size());
  for (std::size_t i = 0; i < r.rows.size(); ++i) {
    EXPECT_EQ(ri.rows[i].hits, r.rows[i].hits) << r.rows[i].config;
    EXPECT_EQ(ri.rows[i].agreement.mismatches(), 0u);
  }
}

// Clusters that come apart: the explode deformer (every triangle of the sphere flies off along
// its normal, 4% of the diagonal a frame) swells ours_clusters' boxes frame by frame. With a
// threshold the bench traces exactly the frames whose swelling is above it on the triangle
// fallback (its build in fallback_ms and build_ms), with zero mismatches on every frame; the
// CSV carries swelling, fallback and fallback_ms as the rows hold them, and the text names the
// threshold, the count and the scene frames. Off (0), no frame falls back.
TEST(PeerBench, SwollenClustersTraceOnTheTriangleFallback) {
  const Mesh m = sphere(4);
  ptc::DeformParams ex = ptc::deform_preset(ptc::DeformKind::Explode);
  ex.amplitude = 0.04;
  for (double threshold : {0.0, 12.0}) {
    ptc::PeerBenchConfig cfg;
    cfg.frames = {0, 5};
    cfg.width = 40, cfg.height = 32;
    cfg.max_count = 20;
    cfg.cluster_fallback = threshold;
    ptc::Scene sc = scene_of(m, ptc::DeformKind::Explode, ex);
    const ptc::PeerBenchResult r = ptc::run_peer_bench(sc, std::nullopt, cfg);
    EXPECT_EQ(r.cluster_fallback, threshold);
    std::vector<const ptc::BenchRow*> ours;
    for (const auto& row : r.rows) {
      EXPECT_EQ(row.agreement.mismatches(), 0u) << row.config << " frame " << row.frame;
      if (row.config == "ours_clusters") ours.push_back(&row);
      else EXPECT_TRUE(std::isnan(row.swelling) && row.fallback == 0) << row.config;
    }
    ASSERT_EQ(ours.size(), 6u);
    std::vector<std::int64_t> fell;
    for (std::size_t i = 0; i < ours.size(); ++i) {
      const ptc::BenchRow& row = *ours[i];
      if (i > 0) {
        EXPECT_GT(row.swelling, ours[i - 1]->swelling) << "frame " << i;
      }
      const bool above = threshold > 0 && row.swelling > threshold;
      EXPECT_EQ(row.fallback, above ? 1 : 0) << "frame " << i << " swelling " << row.swelling;
      if (above) {
        fell.push_back(row.scene_frame);
        EXPECT_GT(row.times.stages.fallback_ms, 0.0);
        EXPECT_GE(row.times.build_ms, row.times.stages.fallback_ms);
      } else {
        EXPECT_EQ(row.times.stages.fallback_ms, 0.0);
      }
    }
    EXPECT_LT(ours.front()->swelling, 12.0);
    EXPECT_GT(ours.back()->swelling, 12.0);
    const auto csv = ptc::test::csv_rows(ptc::bench_table(r).csv.str());
    ASSERT_EQ(csv.size(), r.rows.size());
    for (std::size_t i = 0; i < csv.size(); ++i) {
      const ptc::BenchRow& row = r.rows[i];
      EXPECT_EQ(csv[i].at("fallback"), std::to_string(row.fallback));
      if (row.config == "ours_clusters") {
        EXPECT_NEAR(std::stod(csv[i].at("swelling")), row.swelling, 1e-6 * row.swelling);
        EXPECT_NEAR(std::stod(csv[i].at("fallback_ms")), row.times.stages.fallback_ms, 1e-6 + 1e-6 * row.times.stages.fallback_ms);
      }
    }
    const std::string text = ptc::bench_text(r);
    if (threshold > 0) {
      ASSERT_GE(fell.size(), 2u);
      for (std::size_t i = 1; i < fell.size(); ++i) ASSERT_EQ(fell[i], fell[i - 1] + 1);  // (one run: A-B)
      const std::string want = fmt::format("triangle fallback above 12: {} of 6 frames (scene frames {}-{})", fell.size(),
                                           fell.front(), fell.back());
      EXPECT_NE(text.find(want), std::string::npos) << want << "\n" << text;
    } else {
      EXPECT_TRUE(fell.empty());
      EXPECT_NE(text.find("triangle fallback off"), std::string::npos) << text;
    }
  }
}

// The per-frame range behind the whole-frame medians, on rows made by hand: the ratio of the
// peer's whole frame to the row's, frame by frame, over the frames of the medians only, skipping
// frames where either side is missing, 0 ms or not finite; the lowest's frame (benchmark and
// scene frame) is the first of equal lowest ratios. The summary table and the text carry the
// same values, each in its peer's column.
TEST(PeerBench, WholeFrameRatioRangeOverTheFrames) {
  ptc::PeerBenchResult r;
  r.median_first_frame = 1;
  auto row = [&](int frame, const std::string& config, double update, double build, double trace, double shadow) {
    ptc::BenchRow b;
    b.frame = frame, b.scene_frame = 40 + frame, b.config = config;
    b.times.update_ms = update, b.times.build_ms = build, b.trace_ms = trace, b.shadow_ms = shadow;
    r.rows.push_back(b);
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // ours: whole frames 10, 20, 10, 40, 8, ... (frame 0 is left out of the medians; frame 4 has no
  // Embree row); refit: 100, 30, 40, 20; frames 5-8 are skipped (0 ms, NaN, Embree's 0 ms and NaN).
  row(0, "ours_clusters", 1, 2, 3, 4), row(0, "embree_refit", 50, 0, 50, 0);
  row(1, "ours_clusters", 1, 1, 10, 8), row(1, "embree_refit", 10, 0, 20, 0);
  row(2, "ours_clusters", 0, 2, 5, 3), row(2, "embree_refit", 20, 0, 20, 0);
  row(3, "ours_clusters", 10, 10, 10, 10), row(3, "embree_refit", 10, 0, 10, 0);
  row(4, "ours_clusters", 2, 2, 2, 2);
  row(5, "ours_clusters", 0, 0, 0, 0), row(5, "embree_refit", 10, 0, 0, 0);
  row(6, "ours_clusters", nan, 0, 1, 0), row(6, "embree_refit", 1000, 0, 0, 0);
  row(7, "ours_clusters", 1, 0, 0, 0), row(7, "embree_refit", 0, 0, 0, 0);
  row(8, "ours_clusters", 1, 0, 0, 0), row(8, "embree_refit", nan, 0, 0, 0);
  r.summary = ptc::summarize(r.rows, r.median_first_frame);
  const ptc::FrameRatioRange q = ptc::whole_frame_ratio_range(r, "ours_clusters", "embree_refit");
  EXPECT_DOUBLE_EQ(q.lowest, 0.5);  // frame 3: 20 / 40
  EXPECT_EQ(q.lowest_frame, 3);
  EXPECT_EQ(q.lowest_scene_frame, 43);
  EXPECT_DOUBLE_EQ(q.highest, 4.0);  // frame 2: 40 / 10 (frame 0's 100 / 10 is not a median frame)
  const ptc::FrameRatioRange self = ptc::whole_frame_ratio_range(r, "embree_refit", "embree_refit");
  EXPECT_DOUBLE_EQ(self.lowest, 1.0);
  EXPECT_DOUBLE_EQ(self.highest, 1.0);
  EXPECT_EQ(self.lowest_frame, 1);  // the first of equal ratios
  const ptc::FrameRatioRange none = ptc::whole_frame_ratio_range(r, "ours_clusters", "embree_low");
  EXPECT_TRUE(std::isnan(none.lowest) && std::isnan(none.highest));
  EXPECT_EQ(none.lowest_frame, -1);
  EXPECT_EQ(none.lowest_scene_frame, -1);
  // Ties at the lowest: the earlier frame; the highest may come first or after a skipped frame.
  ptc::PeerBenchResult t;
  for (int f = 0; f < 4; ++f) {
    ptc::BenchRow a, b;
    a.frame = b.frame = f, a.scene_frame = b.scene_frame = f, a.config = "ours_clusters", b.config = "embree_low";
    a.trace_ms = 10, b.trace_ms = f == 0 ? 30 : f == 1 ? nan : 20;
    t.rows.push_back(a), t.rows.push_back(b);
  }
  const ptc::FrameRatioRange tie = ptc::whole_frame_ratio_range(t, "ours_clusters", "embree_low");
  EXPECT_EQ(tie.lowest_frame, 2);
  EXPECT_DOUBLE_EQ(tie.lowest, 2.0);
  EXPECT_DOUBLE_EQ(tie.highest, 3.0);

  const auto rows = ptc::test::csv_rows(ptc::bench_summary_table(r).csv.str());
  ASSERT_EQ(rows.size(), 2u);
  const auto& ours = rows[0];
  EXPECT_EQ(ours.at("config"), "ours_clusters");
  EXPECT_EQ(ours.at("whole_frame_speedup_lowest_vs_embree_refit"), "0.5");
  EXPECT_EQ(ours.at("whole_frame_speedup_lowest_scene_frame_vs_embree_refit"), "43");
  EXPECT_EQ(ours.at("whole_frame_speedup_highest_vs_embree_refit"), "4");
  EXPECT_EQ(ours.at("whole_frame_speedup_lowest_scene_frame_vs_embree_low"), "-1");
  EXPECT_EQ(ours.at("whole_frame_speedup_highest_vs_embree_low"), "nan");
  // The text: the block after the whole-frame table, ours' line, its cell under each peer.
  const std::string text = ptc::bench_text(r);
  const auto block = text.find("per frame (the same frames)");
  ASSERT_NE(block, std::string::npos) << text;
  EXPECT_LT(block, text.find("update_ms")) << text;
  const auto at = text.find("\nours_clusters", block);
  ASSERT_NE(at, std::string::npos) << text;
  std::istringstream line(text.substr(at + 1, text.find('\n', at + 1) - at - 1));
  std::vector<std::string> cells;
  for (std::string c; line >> c;) cells.push_back(c);
  // config, then per peer (medium, low, refit) "-" or "lo-hix" "@frame"
  ASSERT_EQ(cells.size(), 5u) << text;
  EXPECT_EQ(cells[1], "-");  // no medium rows
  EXPECT_EQ(cells[2], "-");  // no low rows
  EXPECT_EQ(cells[3], "0.50-4.00x");
  EXPECT_EQ(cells[4], "@43");
  const auto self_at = text.find("\nembree_refit", block);
  ASSERT_NE(self_at, std::string::npos);
  EXPECT_EQ(text.substr(self_at + 1, text.find('\n', self_at + 1) - self_at - 1).find("1.00-1.00x"), std::string::npos)
      << "a configuration against itself prints -";
}
