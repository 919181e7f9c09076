#include "analysis/experiments/bench.h"

#include "toolkit/core/memory.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "analysis/loop/frame_loop.h"
#include "bvh/camera.h"
#include "bvh/scene_tracer.h"
#include "render/rays.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/stats.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/core/strings.h"

namespace ptc {
namespace {

const BenchSummary* find(const std::vector<BenchSummary>& s, std::string_view name) {
  for (const auto& x : s)
    if (x.config == name) return &x;
  return nullptr;
}

constexpr loop::AccelKind kEmbree[3] = {loop::AccelKind::EmbreeMedium, loop::AccelKind::EmbreeLow,
                                        loop::AccelKind::EmbreeRefit};

double nan() { return std::numeric_limits<double>::quiet_NaN(); }

}  // namespace

const char* to_string(EmbreeShadowHint h) {
  return h == EmbreeShadowHint::Best ? "best" : h == EmbreeShadowHint::Coherent ? "coherent" : "incoherent";
}

std::optional<EmbreeShadowHint> parse_embree_shadow_hint(std::string_view s) {
  if (s == "best") return EmbreeShadowHint::Best;
  if (s == "coherent") return EmbreeShadowHint::Coherent;
  if (s == "incoherent") return EmbreeShadowHint::Incoherent;
  return std::nullopt;
}

std::vector<BenchSummary> summarize(const std::vector<BenchRow>& rows, int first_frame) {
  std::vector<BenchSummary> out;
  std::map<std::string, std::vector<const BenchRow*>> by;
  for (const auto& r : rows) {
    if (!by.count(r.config)) out.push_back(BenchSummary{r.config});
    by[r.config].push_back(&r);
  }
  for (auto& s : out) {
    std::vector<double> u, b, ub, t, m, sh, wf;
    for (const BenchRow* r : by[s.config]) {
      s.mismatches += r->agreement.mismatches();
      s.ties += r->agreement.ties;
      s.shadow_mismatches += r->shadow_mismatches;
      if (r->frame < first_frame) continue;
      u.push_back(r->times.update_ms), b.push_back(r->times.build_ms);
      ub.push_back(r->times.update_ms + r->times.build_ms);
      t.push_back(r->trace_ms), m.push_back(r->mrays_per_s);
      sh.push_back(r->shadow_ms), wf.push_back(r->whole_frame_ms());
    }
    s.update_ms = median(u), s.build_ms = median(b), s.update_build_ms = median(ub);
    s.trace_ms = median(t), s.mrays_per_s = median(m);
    s.shadow_ms = median(sh), s.whole_frame_ms = median(wf);
  }
  return out;
}

PeerBenchResult run_peer_bench(Scene& scene, std::optional<Clustering> clusters, const PeerBenchConfig& cfg) {
  if (cfg.frames.first < 0 || cfg.frames.count() < 1) throw std::invalid_argument("frames must be a range A:B, 0 <= A <= B");
  if (cfg.threads < 1) throw std::invalid_argument("threads must be >= 1");
  if (cfg.width < 1 || cfg.height < 1 || cfg.width > kMaxImageSide || cfg.height > kMaxImageSide)
    throw std::invalid_argument("image size must be 1..16384 per side");
  if (scene.rest().empty()) throw std::invalid_argument("the mesh has no triangles");
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, cfg.threads);

  PeerBenchResult res;
  res.triangles = scene.rest().triangle_count();
  res.vertices = scene.rest().vertex_count();
  const bool given = clusters.has_value();
  if (!given) {
    ClusterConfig cc;
    cc.method = ClusterMethod::Growth;
    cc.objective = ObjectiveKind::Acc;
    cc.max_count = cfg.max_count;
    cc.max_size = cfg.max_count;
    cc.adjacency = cfg.adjacency;
    Stopwatch sw;
    clusters = cluster_mesh(scene.rest(), cc, [](double) { throw_if_cancelled(); });  // Ctrl-C at the next step
    res.cluster_ms = sw.ms();
    const ClusterAdjacency used = resolve_adjacency(scene.rest(), cfg.adjacency);
    res.clustering =
        cfg.max_count == 0
            ? std::string("one triangle per cluster (MaxCount = MaxSize = 0)")
            : fmt::format("growth/acc MaxCount={} MaxSize={} adjacency={}{}", cfg.max_count, cfg.max_count,
                          to_string(used),
                          cfg.adjacency == ClusterAdjacency::Auto && used == ClusterAdjacency::Positions
                              ? " (auto: the rest pose is a triangle soup)"
                              : "");
  } else {
    res.clustering = "given";
  }
  res.clusters = clusters->cluster_count();

  // One trace frame and one camera for every configuration (the rest bounds do not change with
  // the vertex numbering).
  const Box3 rest_bounds = scene.rest().referenced_bounds();
  loop::AccelSetup setup;
  setup.origin = rest_bounds.center();
  setup.cluster_leaf = cfg.cluster_leaf;
  setup.leaf_format = cfg.leaf_format;
  setup.cluster_group_size = cfg.cluster_group_size;
  setup.min_cluster_groups = cfg.min_cluster_groups;
  setup.group_trees = cfg.group_trees;
  setup.cluster_fallback = cfg.cluster_fallback;
  res.cluster_fallback = cfg.cluster_fallback;
  setup.fallback_refit = cfg.fallback_refit;
  res.fallback_refit = cfg.fallback_refit;
  setup.threads = cfg.threads;
  setup.embree_packet_width = cfg.embree_packet_width;
  const bvh::PinholeCamera cam =
      cfg.made_camera ? *cfg.made_camera : make_camera(cfg.camera, scene.rest().referenced_bounds(), cfg.width, cfg.height);
  res.fallback_sah = cfg.cluster_fallback > 0 ? cfg.fallback_sah : bvh::FallbackSah::Plain;
  if (res.fallback_sah == bvh::FallbackSah::Directions)
    setup.fallback_area_weights = bvh::direction_area_weights(cam, cfg.width, cfg.height);
  if (res.fallback_sah == bvh::FallbackSah::Eye) setup.fallback_area_eye = cam.eye;
  res.fallback_area_weights = setup.fallback_area_weights;
  res.fallback_area_eye = setup.fallback_area_eye;

  // The method's precomputation, once: vertices renumbered so that each cluster's own vertices
  // are consecutive; the scene renumbers its sources (or gathers, which it then says).
  res.vertex_order = to_string(cfg.vertex_order);
  if (cfg.vertex_order == bvh::VertexOrder::Clusters) {
    Stopwatch sw;
    bvh::renumber_by_clusters(scene, *clusters, loop::cluster_scene_config(setup));
    res.renumber_ms = sw.ms();
  }
  setup.clusters = &*clusters;
  const Mesh& mesh = scene.rest();

  const bvh::RayBatch rays = camera_rays(cam, cfg.width, cfg.height);
  res.rays = rays.size();

  std::vector<std::unique_ptr<loop::Accel>> accels;
  for (loop::AccelKind k : loop::kAllAccelKinds) {
    Stopwatch sw;
    accels.push_back(loop::make_accel(k, mesh, setup));
    if (k == loop::AccelKind::OursClusters) {
      res.cluster_scene_setup_ms = sw.ms();
      res.fused_vertex_pass = loop::cluster_scene_of(*accels.back())->fused_vertex_pass();
      res.cluster_leaves = bvh::leaf_shape(loop::cluster_scene_of(*accels.back())->cluster_data());
      res.cluster_leaf_estimate = loop::cluster_scene_of(*accels.back())->leaf_bytes_estimate();
      res.cluster_group_size = loop::cluster_scene_of(*accels.back())->group_size();
    }
  }
  res.group_trees = setup.group_trees;
  std::vector<loop::Accel*> order;
  for (auto& a : accels) order.push_back(a.get());

  bvh::TraceOptions opt;
  opt.threads = cfg.threads;
  opt.counters = false;
  opt.packets = cfg.packets;
  opt.isa = cfg.isa;
  bvh::AlignedVector<Vec3> pos(mesh.positions().begin(), mesh.positions().end());
  bvh::HitBatch ref, hits, counted;
  // The shadow pass: one batch per frame, made from ours_triangles' primary hits on the frame's
  // positions (the first configuration of the loop), traced by every configuration.
  res.shadows = cfg.light.has_value();
  res.packets = cfg.packets;
  res.embree_packet_width = cfg.embree_packet_width;
  res.embree_shadow_hint = cfg.embree_shadow_hint;
  res.shadow_morton = cfg.shadow_morton;
  std::vector<std::uint32_t> shadow_order;  // the frame's (with shadow_morton)
  double shadow_order_ms = 0;
  res.isa = bvh::resolve(cfg.isa);
  std::optional<Mesh> frame_mesh;  // only with a light: the frame's positions on the mesh's triangles
  SurfaceHits surface;
  Box3 frame_bounds;
  std::vector<std::uint8_t> ref_lit;
  loop::LoopOptions lo;
  lo.frames = cfg.frames;
  loop::run_frame_loop(scene, pos, order, lo, [&](const loop::FrameRecord& fr, loop::Accel& a, std::span<const Vec3> positions) {
    BenchRow row;
    row.frame = fr.index;
    row.scene_frame = fr.frame;
    row.config = std::string(a.name());
    row.source_ms = fr.source_ms;
    row.frame_ms = fr.update_wall_ms;
    row.times = fr.times;
    row.sah_cost = a.sah_cost().value_or(nan());
    if (const bvh::ClusterScene* cs = loop::cluster_scene_of(a)) {
      row.swelling = cs->swelling();
      row.fallback = cs->fallback_active() ? 1 : 0;
      row.fallback_refit = cs->fallback_active() && cs->fallback_scene()->refitted() ? 1 : 0;
    } else {
      row.swelling = nan();
    }
    bvh::HitBatch& h = fr.accel == 0 ? ref : hits;
    if (fr.index == 0) a.check_rays(rays);  // (the same rays every frame; outside the timed trace)
    Stopwatch sw;
    const bvh::TraceTotals tt = a.trace(rays, h, opt);
    row.trace_ms = sw.ms();
    row.rays = tt.rays;
    row.hits = tt.hits;
    row.mrays_per_s = row.trace_ms > 0 ? double(tt.rays) / (row.trace_ms * 1e3) : 0.0;
    if (fr.accel > 0) row.agreement = compare_hits(ref, hits, cfg.tie);
    if (cfg.light) {
      if (fr.accel == 0) {
        if (!frame_mesh) frame_mesh = mesh;
        frame_mesh->set_positions(std::vector<Vec3>(positions.begin(), positions.end()));
        surface = surface_hits(*frame_mesh, rays, ref);
        frame_bounds = frame_mesh->referenced_bounds();  // (ray offsets: of the surface, not of an unused vertex)
        if (cfg.shadow_morton) {
          Stopwatch order_sw;
          shadow_order = morton_order(surface, frame_bounds);
          shadow_order_ms = order_sw.ms();
        }
      }
      const TraceTarget target = with_isa(target_of(a), cfg.isa);
      auto shadows = [&](bool coherent) {
        return trace_shadows(with_coherence(target, coherent), surface, *cfg.light, RayFrame{frame_bounds, a.origin()},
                             cfg.threads, cfg.packets, shadow_order);
      };
      // Points lit otherwise than ours_triangles' (the reference, fr.accel 0).
      auto mismatches = [&](const ShadowResult& x) {
        std::uint64_t m = 0;
        for (std::size_t i = 0; i < x.lit.size() && i < ref_lit.size(); ++i) m += x.lit[i] != ref_lit[i];
        return m;
      };
      ShadowResult sr;
      if (cfg.packets && loop::is_embree(loop::kAllAccelKinds[fr.accel])) {
        bool coherent = cfg.embree_shadow_hint != EmbreeShadowHint::Incoherent;
        if (cfg.embree_shadow_hint == EmbreeShadowHint::Best) {
          // Both flags, first one then the other, the order alternating with the frame (so that
          // neither always finds the caches warm); the faster counts.
          const bool first = fr.index % 2 == 0;
          ShadowResult one = shadows(first), two = shadows(!first);
          ShadowResult& with_coherent = first ? one : two;
          ShadowResult& with_incoherent = first ? two : one;
          coherent = with_coherent.stats.trace_ms <= with_incoherent.stats.trace_ms;
          row.shadow_other_ms = coherent ? with_incoherent.stats.trace_ms : with_coherent.stats.trace_ms;
          // The other flag's lit points are checked too: shadow_mismatches counts the worse pass.
          row.shadow_mismatches = mismatches(coherent ? with_incoherent : with_coherent);
          sr = std::move(coherent ? with_coherent : with_incoherent);
        } else {
          sr = shadows(coherent);
        }
        row.shadow_hint = coherent ? "coherent" : "incoherent";
      } else {
        sr = shadows(true);
      }
      row.shadow_rays = sr.stats.rays, row.shadow_occluded = sr.stats.hits, row.shadow_ms = sr.stats.trace_ms;
      row.shadow_order_ms = shadow_order_ms;
      if (fr.accel == 0) ref_lit = sr.lit;
      else row.shadow_mismatches = std::max(row.shadow_mismatches, mismatches(sr));
    }
    if (!loop::is_embree(loop::kAllAccelKinds[fr.accel])) {  // ours: the counters, from an untimed trace with them on
      bvh::TraceOptions with = opt;
      with.counters = true;
      const bvh::TraceTotals c = a.trace(rays, counted, with);
      row.nodes_per_ray = c.rays ? double(c.nodes_visited) / double(c.rays) : 0.0;
      row.triangles_per_ray = c.rays ? double(c.triangles_tested) / double(c.rays) : 0.0;
    } else {
      row.nodes_per_ray = row.triangles_per_ray = nan();
    }
    const RssSample mem = rss_sample();
    row.rss_mb = mem.rss_mb;
    row.peak_rss_mb = mem.peak_mb;
    res.rows.push_back(std::move(row));
  });
  res.median_first_frame = cfg.frames.count() > 1 ? 1 : 0;
  res.summary = summarize(res.rows, res.median_first_frame);
  return res;
}

Table bench_table(const PeerBenchResult& r) {
  return tabulate(Schema{"ptc-bench", 8}, r.rows, [](const BenchRow& x, Columns& col) {
    col("frame", x.frame);
    col("config", x.config);
    col("update_ms", x.times.update_ms);
    col("build_ms", x.times.build_ms);
    col("update_build_ms", x.times.update_ms + x.times.build_ms);
    col("frame_ms", x.frame_ms);
    col("trace_ms", x.trace_ms);
    col("mrays_per_s", x.mrays_per_s);
    col("rays", x.rays);
    col("hits", x.hits);
    col("mismatches", x.agreement.mismatches());
    col("mismatch_hit_miss", x.agreement.hit_miss);
    col("mismatch_other_triangle", x.agreement.other_triangle);
    col("ties", x.agreement.ties);
    col("scene_frame", x.scene_frame);
    col("source_ms", x.source_ms);
    col("vertices_ms", x.times.stages.vertices_ms);
    col("boxes_ms", x.times.stages.boxes_ms);
    col("sah_build_ms", x.times.stages.build_ms);
    col("collapse_ms", x.times.stages.collapse_ms);
    col("leaf_data_ms", x.times.stages.leaf_data_ms);
    col("refit_ms", x.times.stages.refit_ms);
    col("overlap_ms", x.times.stages.overlap_ms);
    col("sah_cost", x.sah_cost);
    col("nodes_per_ray", x.nodes_per_ray);
    col("triangles_per_ray", x.triangles_per_ray);
    col("rss_mb", x.rss_mb);
    col("peak_rss_mb", x.peak_rss_mb);
    col("shadow_rays", x.shadow_rays);
    col("shadow_occluded", x.shadow_occluded);
    col("shadow_ms", x.shadow_ms);
    col("shadow_mismatches", x.shadow_mismatches);
    col("whole_frame_ms", x.whole_frame_ms());
    col("fallback_ms", x.times.stages.fallback_ms);
    col("swelling", x.swelling);
    col("fallback", x.fallback);
    col("fallback_refit", x.fallback_refit);
    col("shadow_hint", x.shadow_hint);
    col("shadow_other_ms", x.shadow_other_ms);
    col("shadow_order_ms", x.shadow_order_ms);
  });
}

FrameRatioRange whole_frame_ratio_range(const PeerBenchResult& r, std::string_view config, std::string_view peer) {
  struct At {
    double ms;
    std::int64_t scene_frame;
  };
  std::map<int, At> ours;
  std::map<int, double> theirs;  // benchmark frame -> whole frame ms
  for (const auto& row : r.rows) {
    if (row.frame < r.median_first_frame) continue;
    if (row.config == config) ours[row.frame] = {row.whole_frame_ms(), row.scene_frame};
    if (row.config == peer) theirs[row.frame] = row.whole_frame_ms();
  }
  FrameRatioRange out;
  for (const auto& [f, at] : ours) {
    const auto it = theirs.find(f);
    if (it == theirs.end() || !(at.ms > 0.0) || !(it->second > 0.0)) continue;  // (NaN too)
    const double q = it->second / at.ms;
    if (!std::isfinite(q)) continue;
    const bool first = out.lowest_frame < 0;
    if (first || q < out.lowest) out.lowest = q, out.lowest_frame = f, out.lowest_scene_frame = at.scene_frame;
    out.highest = first ? q : std::max(out.highest, q);
  }
  return out;
}

namespace {
struct SummaryRow {
  const BenchSummary* s = nullptr;
  const PeerBenchResult* r = nullptr;
};
}  // namespace

Table bench_summary_table(const PeerBenchResult& r) {
  std::vector<SummaryRow> rows;
  for (const auto& s : r.summary) rows.push_back({&s, &r});
  const int frames = r.rows.empty() ? 0 : r.rows.back().frame + 1;
  return tabulate(Schema{"ptc-bench-summary", 3}, rows, [frames](const SummaryRow& x, Columns& col) {
    static const BenchSummary none;
    const BenchSummary& s = x.s ? *x.s : none;
    col("config", s.config);
    col("frames_in_median", frames - (x.r ? x.r->median_first_frame : 0));
    col("update_ms", s.update_ms);
    col("build_ms", s.build_ms);
    col("update_build_ms", s.update_build_ms);
    col("trace_ms", s.trace_ms);
    col("mrays_per_s", s.mrays_per_s);
    col("mismatches", s.mismatches);
    col("ties", s.ties);
    col("shadow_ms", s.shadow_ms);
    col("shadow_mismatches", s.shadow_mismatches);
    col("whole_frame_ms", s.whole_frame_ms);
    for (loop::AccelKind e : kEmbree) {
      const BenchSummary* p = x.r ? find(x.r->summary, to_string(e)) : nullptr;
      col(std::string("whole_frame_speedup_vs_") + std::string(to_string(e)),
          p && s.whole_frame_ms > 0 ? p->whole_frame_ms / s.whole_frame_ms : nan());
    }
    for (loop::AccelKind e : kEmbree) {  // the range of the per-frame ratios behind the median
      const FrameRatioRange q = x.r ? whole_frame_ratio_range(*x.r, s.config, to_string(e)) : FrameRatioRange{};
      const std::string peer(to_string(e));
      col("whole_frame_speedup_lowest_vs_" + peer, q.lowest);
      col("whole_frame_speedup_lowest_scene_frame_vs_" + peer, q.lowest_scene_frame);
      col("whole_frame_speedup_highest_vs_" + peer, q.highest);
    }
    for (loop::AccelKind e : kEmbree) {
      const BenchSummary* p = x.r ? find(x.r->summary, to_string(e)) : nullptr;
      col(std::string("update_build_speedup_vs_") + std::string(to_string(e)),
          p && s.update_build_ms > 0 ? p->update_build_ms / s.update_build_ms : nan());
    }
    for (loop::AccelKind e : kEmbree) {
      const BenchSummary* p = x.r ? find(x.r->summary, to_string(e)) : nullptr;
      col(std::string("trace_speed_vs_") + std::string(to_string(e)),
          p && p->mrays_per_s > 0 ? s.mrays_per_s / p->mrays_per_s : nan());
    }
  });
}

namespace {
// The cluster BVH's swelling over the frames and the frames traced on its triangle fallback
// (scene frames, runs of consecutive ones as A-B); empty without ours_clusters rows.
std::string fallback_text(const PeerBenchResult& r) {
  std::vector<const BenchRow*> rows;
  for (const auto& row : r.rows)
    if (row.config == loop::to_string(loop::AccelKind::OursClusters)) rows.push_back(&row);
  if (rows.empty()) return {};
  double high = rows.front()->swelling;
  std::vector<std::int64_t> fell;
  for (const BenchRow* row : rows) {
    if (row->swelling > high) high = row->swelling;
    if (row->fallback) fell.push_back(row->scene_frame);
  }
  std::string s = fmt::format("cluster swelling (box area / triangle area): {:.2f} at scene frame {}, {:.2f} at {}, "
                              "highest {:.2f}; ",
                              rows.front()->swelling, rows.front()->scene_frame, rows.back()->swelling,
                              rows.back()->scene_frame, high);
  if (!(r.cluster_fallback > 0)) return s + "triangle fallback off\n";
  s += fmt::format("triangle fallback above {:g}: {} of {} frames", r.cluster_fallback, fell.size(), rows.size());
  std::size_t kept = 0;
  for (const BenchRow* row : rows) kept += row->fallback_refit ? 1 : 0;
  const std::string tree = r.fallback_refit > 0 ? fmt::format("; its tree refitted on {} of them (cost growth at most {:g})",
                                                              kept, r.fallback_refit)
                                                : std::string("; its tree rebuilt on each");
  const auto& w = r.fallback_area_weights;
  const std::string sah =
      r.fallback_sah == bvh::FallbackSah::Plain ? std::string("; plain SAH")
      : r.fallback_sah == bvh::FallbackSah::Eye
          ? std::string("; SAH for rays from the camera's eye")
          : fmt::format("; SAH for the camera's ray directions (area weights {:.3g} {:.3g} {:.3g})", w[0], w[1], w[2]);
  std::string runs;
  for (std::size_t i = 0; i < fell.size();) {
    std::size_t j = i;
    while (j + 1 < fell.size() && fell[j + 1] == fell[j] + 1) ++j;
    runs += (runs.empty() ? "" : ", ") +
            (j == i ? fmt::format("{}", fell[i]) : fmt::format("{}-{}", fell[i], fell[j]));
    i = j + 1;
  }
  return s + (runs.empty() ? std::string() : " (scene frames " + runs + ")") + (fell.empty() ? std::string() : tree + sah) + "\n";
}
// With EmbreeShadowHint::Best: per Embree configuration, the frames of the medians on which each
// context flag was the faster for the shadow packets; empty otherwise.
std::string shadow_hint_text(const PeerBenchResult& r) {
  if (!r.packets || !r.shadows || r.embree_shadow_hint != EmbreeShadowHint::Best) return {};
  std::string s;
  for (loop::AccelKind e : kEmbree) {
    int coherent = 0, incoherent = 0;
    for (const auto& row : r.rows)
      if (row.config == to_string(e) && row.frame >= r.median_first_frame)
        coherent += row.shadow_hint == "coherent", incoherent += row.shadow_hint == "incoherent";
    if (coherent + incoherent == 0) continue;
    s += fmt::format("{}{} coherent on {}, incoherent on {}", s.empty() ? "" : "; ", to_string(e), coherent, incoherent);
  }
  return s.empty() ? s
                   : "Embree's shadow packets, the faster flag per frame (frames of the medians; bench.csv shadow_hint, "
                     "shadow_other_ms): " + s + "\n";
}
}  // namespace

std::string bench_text(const PeerBenchResult& r) {
  const int frames = r.rows.empty() ? 0 : r.rows.back().frame + 1;
  // Named by their scene frames (the table's "@F"), not by their place in the run.
  std::int64_t first = r.median_first_frame, last = frames - 1;
  for (const auto& row : r.rows) {
    if (row.frame == r.median_first_frame) first = row.scene_frame;
    if (row.frame == frames - 1) last = row.scene_frame;
  }
  const int counted_frames = frames - r.median_first_frame;
  std::string s = fmt::format("medians over {} ({}), {} primary rays{}\n",
                              first == last ? fmt::format("frame {}", first) : fmt::format("frames {}..{}", first, last),
                              counted(counted_frames, "frame"), r.rays,
                              r.shadows ? " and shadow rays to the light" : " (no shadow rays)");
  // The whole frame first: what the method is for.
  s += fmt::format("whole frame = update + build + primary{} (> 1: the row is faster; Embree's frame / the row's){}\n",
                   r.shadows ? " + shadow rays" : "",
                   r.packets ? fmt::format("; rays in packets (ours: 8, one per AVX2 lane; Embree: {0}, "
                                           "rtcIntersect{0} coherent{1})",
                                           r.embree_packet_width,
                                           !r.shadows ? std::string()
                                           : r.embree_shadow_hint == EmbreeShadowHint::Best
                                               ? fmt::format(", rtcOccluded{} with the faster of its coherent and incoherent "
                                                             "flags each frame", r.embree_packet_width)
                                               : fmt::format(", rtcOccluded{} {}", r.embree_packet_width,
                                                             to_string(r.embree_shadow_hint)))
                             : std::string());
  s += fmt::format("{:<16} {:>10}", "config", "whole_ms");  // (summary.csv's whole_frame_ms)
  for (loop::AccelKind e : kEmbree) s += fmt::format(" {:>15}", "vs " + std::string(to_string(e)));
  s += "\n";
  for (const auto& x : r.summary) {
    s += fmt::format("{:<16} {:>10.2f}", x.config, x.whole_frame_ms);
    for (loop::AccelKind e : kEmbree) {
      const BenchSummary* p = find(r.summary, to_string(e));
      s += fmt::format(" {:>14.2f}x", p && x.whole_frame_ms > 0 ? p->whole_frame_ms / x.whole_frame_ms : 0.0);
    }
    s += "\n";
  }
  // The medians hide how the ratio moves over the animation (clusters swell, a scene drapes): per
  // frame, the lowest and highest ratio, and the scene frame of the lowest.
  s += fmt::format("per frame (the same frames): lowest-highest of Embree's whole frame / the row's, @ the scene frame of "
                   "the lowest\n");
  s += fmt::format("{:<16}", "config");
  for (loop::AccelKind e : kEmbree) s += fmt::format(" {:>22}", "vs " + std::string(to_string(e)));
  s += "\n";
  for (const auto& x : r.summary) {
    s += fmt::format("{:<16}", x.config);
    for (loop::AccelKind e : kEmbree) {
      const FrameRatioRange q = whole_frame_ratio_range(r, x.config, to_string(e));
      s += x.config == to_string(e) || q.lowest_frame < 0
               ? fmt::format(" {:>22}", "-")
               : fmt::format(" {:>22}", fmt::format("{:.2f}-{:.2f}x @{}", q.lowest, q.highest, q.lowest_scene_frame));
    }
    s += "\n";
  }
  s += "\n";
  // (the names of summary.csv's columns; hits and shadow_rays are medians of bench.csv's)
  s += fmt::format("{:<16} {:>10} {:>10} {:>13} {:>10} {:>10} {:>10} {:>10} {:>8} {:>10} {:>11} {:>17}\n", "config",
                   "update_ms", "build_ms", "upd+build_ms", "trace_ms", "Mrays/s", "hits", "mismatches", "ties",
                   "shadow_ms", "shadow_rays", "shadow_mismatches");
  // A median count in full ("{:g}" would print 1048576 as 1.04858e+06; between two counts it ends in .5).
  auto count = [](const std::vector<double>& v) {
    if (v.empty()) return std::string("-");
    const double m = median(v);
    return m == std::floor(m) ? fmt::format("{:.0f}", m) : fmt::format("{:.1f}", m);
  };
  for (const auto& x : r.summary) {
    // Medians over the frames, like the other columns.
    std::vector<double> hv, sv;
    for (const auto& row : r.rows)
      if (row.config == x.config && row.frame >= r.median_first_frame)
        hv.push_back(static_cast<double>(row.hits)), sv.push_back(static_cast<double>(row.shadow_rays));
    const std::string hits = count(hv), shadow_rays = count(sv);
    s += fmt::format("{:<16} {:>10.2f} {:>10.2f} {:>13.2f} {:>10.2f} {:>10.2f} {:>10} {:>10} {:>8} {:>10.2f} {:>11} {:>17}\n",
                     x.config, x.update_ms, x.build_ms, x.update_build_ms, x.trace_ms, x.mrays_per_s, hits,
                     x.mismatches, x.ties, x.shadow_ms, shadow_rays, x.shadow_mismatches);
  }
  std::vector<double> src;
  for (const auto& row : r.rows)
    if (row.frame >= r.median_first_frame && row.config == r.rows.front().config) src.push_back(row.source_ms);
  s += fmt::format("frame source (positions of a frame, outside every configuration): median {:.2f} ms; vertex order: "
                   "{}{}; cluster BVH: {}\n",
                   median(src), r.vertex_order,
                   r.fused_vertex_pass ? " (cluster path: conversion and boxes in one pass)"
                                       : " (cluster path: positions gathered per frame)",
                   r.cluster_group_size > 1 ? fmt::format("two-level, groups of <= {} clusters, {}", r.cluster_group_size,
                                                                         r.group_trees == bvh::GroupTrees::Refit
                                                                             ? "each group's tree fixed and refitted"
                                                                             : "each group's tree rebuilt")
                                            : std::string("plain SAH build over all cluster boxes"));
  const bvh::LeafShape& ls = r.cluster_leaves;
  if (ls.units > 0) {
    const double u = static_cast<double>(ls.units), tris = static_cast<double>(ls.triangles);
    const double used = 100.0 * tris / static_cast<double>(ls.lanes);
    s += ls.format == bvh::LeafFormat::Tables
             ? fmt::format("cluster leaves: tables, {} groups of {:.2f} triangles on {:.2f} vertices ({:.1f}% of the "
                           "tests' lanes used)\n",
                           ls.units, tris / u, static_cast<double>(ls.vertices) / u, used)
             : fmt::format("cluster leaves: blocks, {} blocks of four lanes ({:.1f}% used)\n", ls.units, used);
    const bvh::LeafBytes& e = r.cluster_leaf_estimate;
    if (e.blocks > 0)
      s += fmt::format("  (estimated bytes: tables {:.2f} of the blocks' {:.1f} MB; --leaf-format auto takes the tables "
                       "at {:.2f} or less)\n",
                       static_cast<double>(e.tables) / static_cast<double>(e.blocks), static_cast<double>(e.blocks) / 1e6,
                       bvh::kAutoTablesMaxShare);
  }
  s += fallback_text(r);
  s += shadow_hint_text(r);
  if (r.shadows && r.shadow_morton)
    s += "shadow rays in the Morton order of their hit points (made once a frame, bench.csv shadow_order_ms, counted "
         "in every configuration's whole frame)\n";
  s += "\nratios (> 1: the row is faster): update+build = Embree's time / the row's; trace = the row's Mrays/s / Embree's\n";
  s += fmt::format("{:<16}", "config");
  for (loop::AccelKind e : kEmbree) s += fmt::format(" {:>19}", "upd+build vs " + std::string(to_string(e).substr(7)));
  for (loop::AccelKind e : kEmbree) s += fmt::format(" {:>15}", "trace vs " + std::string(to_string(e).substr(7)));
  s += "\n";
  for (const auto& x : r.summary) {
    s += fmt::format("{:<16}", x.config);
    for (loop::AccelKind e : kEmbree) {
      const BenchSummary* p = find(r.summary, to_string(e));
      s += fmt::format(" {:>18.2f}x", p && x.update_build_ms > 0 ? p->update_build_ms / x.update_build_ms : 0.0);
    }
    for (loop::AccelKind e : kEmbree) {
      const BenchSummary* p = find(r.summary, to_string(e));
      s += fmt::format(" {:>14.2f}x", p && p->mrays_per_s > 0 ? x.mrays_per_s / p->mrays_per_s : 0.0);
    }
    s += "\n";
  }
  return s;
}

}  // namespace ptc
