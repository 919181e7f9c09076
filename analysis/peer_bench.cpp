#include "analysis/peer_bench.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "bvh/box.h"
#include "bvh/embree_peer.h"
#include "bvh/tracer.h"
#include "toolkit/clustering/cluster.h"

namespace ptc {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct Config {
  std::string name;
  std::function<void(std::span<const Vec3>)> update;         // new positions
  std::function<std::pair<double, double>()> stage_ms;       // (update_ms, build_ms) of the last update
  std::function<bvh::TraceTotals(bvh::HitBatch&)> trace;
};

void compare(const bvh::HitBatch& ref, const bvh::HitBatch& got, double tie_rel, BenchRow& row) {
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const bool a = ref.triangle[i] != bvh::kNoTriangle, b = got.triangle[i] != bvh::kNoTriangle;
    if (a != b) {
      ++row.hit_miss;
    } else if (a && ref.triangle[i] != got.triangle[i]) {
      if (std::abs(double(ref.t[i]) - double(got.t[i])) <= tie_rel * std::abs(double(ref.t[i])))
        ++row.ties;
      else
        ++row.other_triangle;
    }
  }
  row.mismatches = row.hit_miss + row.other_triangle;
}

std::pair<double, double> scene_stages(const bvh::StageTimes& t) {
  return {t.vertices_ms + t.boxes_ms, t.build_ms + t.collapse_ms + t.leaf_data_ms + t.refit_ms};
}

const BenchSummary* find(const std::vector<BenchSummary>& s, const std::string& name) {
  for (const auto& x : s)
    if (x.config == name) return &x;
  return nullptr;
}

const char* kEmbree[3] = {"embree_medium", "embree_low", "embree_refit"};

}  // namespace

const std::vector<std::string>& peer_bench_configs() {
  static const std::vector<std::string> names{"ours_triangles", "ours_clusters", "embree_medium", "embree_low",
                                              "embree_refit"};
  return names;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::vector<BenchSummary> summarize(const std::vector<BenchRow>& rows, int first_frame) {
  std::vector<BenchSummary> out;
  std::map<std::string, std::vector<const BenchRow*>> by;
  for (const auto& r : rows) {
    if (!by.count(r.config)) out.push_back(BenchSummary{r.config});
    by[r.config].push_back(&r);
  }
  for (auto& s : out) {
    std::vector<double> u, b, ub, t, m;
    for (const BenchRow* r : by[s.config]) {
      s.mismatches += r->mismatches;
      s.ties += r->ties;
      if (r->frame < first_frame) continue;
      u.push_back(r->update_ms), b.push_back(r->build_ms), ub.push_back(r->update_ms + r->build_ms);
      t.push_back(r->trace_ms), m.push_back(r->mrays_per_s);
    }
    s.update_ms = median(u), s.build_ms = median(b), s.update_build_ms = median(ub);
    s.trace_ms = median(t), s.mrays_per_s = median(m);
  }
  return out;
}

PeerBenchResult run_peer_bench(const Mesh& mesh, const Clustering* clusters, const PeerBenchConfig& cfg) {
  if (cfg.frames < 1) throw std::invalid_argument("frames must be >= 1");
  if (cfg.first_frame < 0 || cfg.first_frame > (std::int64_t(1) << 40)) throw std::invalid_argument("first_frame must be >= 0");
  if (cfg.threads < 1) throw std::invalid_argument("threads must be >= 1");
  if (cfg.width < 1 || cfg.height < 1 || cfg.width > 16384 || cfg.height > 16384)
    throw std::invalid_argument("image size must be 1..16384 per side");
  if (mesh.empty()) throw std::invalid_argument("the mesh has no triangles");
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, cfg.threads);

  PeerBenchResult res;
  res.triangles = mesh.triangle_count();
  res.vertices = mesh.vertex_count();
  Clustering own;
  if (!clusters) {
    ClusterConfig cc;
    cc.method = ClusterMethod::Growth;
    cc.objective = ObjectiveKind::Acc;
    cc.max_count = cfg.max_count;
    cc.max_size = cfg.max_count;
    const auto t0 = Clock::now();
    own = cluster_mesh(mesh, cc);
    res.cluster_ms = ms_since(t0);
    res.clustering = fmt::format("growth/acc MaxCount={} MaxSize={}", cfg.max_count, cfg.max_count);
    clusters = &own;
  } else {
    res.clustering = "given";
  }
  res.clusters = clusters->cluster_count();

  // One trace frame and one cluster-scene configuration for everything below (the rest bounds do
  // not change with the vertex numbering).
  const Box3 rest_bounds = mesh.bounds();
  const Vec3 origin = rest_bounds.center();
  bvh::SceneConfig ccfg = bvh::cluster_scene_defaults();
  ccfg.origin = origin;
  ccfg.cluster_leaf = cfg.cluster_leaf;
  ccfg.cluster_group_size = cfg.cluster_group_size;

  // The method's precomputation, once: vertices renumbered so that each cluster's own vertices
  // are consecutive; the frame source renumbers its own data (or gathers, which it then says).
  Mesh renumbered;
  Clustering renumbered_clusters;
  const Mesh* bm = &mesh;
  res.vertex_order = cfg.cluster_vertex_order ? "clusters" : "input";
  if (cfg.cluster_vertex_order) {
    if (cfg.positions && !cfg.renumber_positions)
      throw std::invalid_argument("cluster_vertex_order with scene positions needs renumber_positions");
    const auto t1 = Clock::now();
    const std::vector<std::uint32_t> to_old =
        bvh::cluster_vertex_order(mesh, bvh::view_of(*clusters), cfg.part_offsets, ccfg);
    renumbered = renumber_vertices(mesh, to_old);
    renumbered_clusters = renumber_vertices(*clusters, inverse_permutation(to_old));
    if (cfg.positions) cfg.renumber_positions(to_old);  // (may change `mesh`, a caller's scene rest)
    res.renumber_ms = ms_since(t1);
    bm = &renumbered;
    clusters = &renumbered_clusters;
  }
  const Mesh& mesh_b = *bm;

  const bvh::PinholeCamera cam = make_camera(cfg.camera, rest_bounds, cfg.width, cfg.height);
  const bvh::RayBatch rays = camera_rays(cam, cfg.width, cfg.height);
  res.rays = rays.size();

  bvh::TraceOptions opt;
  opt.threads = cfg.threads;
  opt.counters = false;
  bvh::SceneConfig tcfg = bvh::triangle_scene_defaults();
  tcfg.origin = origin;
  auto ts = std::make_shared<bvh::TriangleScene>(mesh_b, tcfg);
  const auto t0 = Clock::now();
  auto cs = std::make_shared<bvh::ClusterScene>(mesh_b, bvh::view_of(*clusters), ccfg);
  res.cluster_scene_setup_ms = ms_since(t0);
  res.fused_vertex_pass = cs->fused_vertex_pass();
  res.cluster_group_size = ccfg.cluster_group_size;

  std::vector<Config> configs;
  configs.push_back({"ours_triangles", [ts](std::span<const Vec3> p) { ts->update(p); },
                     [ts] { return scene_stages(ts->times()); },
                     [ts, &rays, opt](bvh::HitBatch& h) { return bvh::trace(ts->data(), rays, h, opt); }});
  configs.push_back({"ours_clusters", [cs](std::span<const Vec3> p) { cs->update(p); },
                     [cs] { return scene_stages(cs->times()); },
                     [cs, &rays, opt](bvh::HitBatch& h) { return bvh::trace(cs->data(), rays, h, opt); }});
  const bvh::EmbreeMode modes[3] = {bvh::EmbreeMode::StaticMedium, bvh::EmbreeMode::DynamicLow,
                                    bvh::EmbreeMode::DynamicRefit};
  for (int k = 0; k < 3; ++k) {
    auto es = std::make_shared<bvh::EmbreeScene>(mesh_b, origin, bvh::EmbreeConfig{modes[k], cfg.threads, ""});
    const unsigned th = cfg.threads;
    configs.push_back({kEmbree[k], [es](std::span<const Vec3> p) { es->update(p); },
                       [es] { return std::pair{es->last_vertex_ms(), es->last_commit_ms()}; },
                       [es, &rays, th](bvh::HitBatch& h) { return es->trace(rays, h, bvh::HitMode::Closest, th); }});
  }

  const auto rest = mesh_b.positions();
  std::vector<Vec3> pos(rest.begin(), rest.end()), fresh(pos.size());
  bvh::HitBatch ref, hits;
  for (int f = 0; f < cfg.frames; ++f) {
    const auto ts0 = Clock::now();
    if (cfg.positions)
      cfg.positions(cfg.first_frame + f, pos);
    else
      deform(rest, rest_bounds, cfg.deformation, static_cast<int>(cfg.first_frame + f), pos);
    const double source_ms = ms_since(ts0);
    for (std::size_t c = 0; c < configs.size(); ++c) {
      BenchRow row;
      row.frame = f;
      row.scene_frame = cfg.first_frame + f;
      row.config = configs[c].name;
      row.source_ms = source_ms;
      // Every configuration reads positions just written (as right after an animation step),
      // not whatever the configurations before it left in the caches (untimed copy).
      std::copy(pos.begin(), pos.end(), fresh.begin());
      auto t1 = Clock::now();
      configs[c].update(fresh);
      row.frame_ms = ms_since(t1);
      std::tie(row.update_ms, row.build_ms) = configs[c].stage_ms();
      bvh::HitBatch& h = c == 0 ? ref : hits;
      t1 = Clock::now();
      const bvh::TraceTotals tt = configs[c].trace(h);
      row.trace_ms = ms_since(t1);
      row.rays = tt.rays;
      row.hits = tt.hits;
      row.mrays_per_s = row.trace_ms > 0 ? double(tt.rays) / (row.trace_ms * 1e3) : 0.0;
      if (c > 0) compare(ref, hits, cfg.tie_rel, row);
      res.rows.push_back(std::move(row));
    }
  }
  res.median_first_frame = cfg.frames > 1 ? 1 : 0;
  res.summary = summarize(res.rows, res.median_first_frame);
  return res;
}

CsvTable bench_csv(const PeerBenchResult& r) {
  CsvTable t({"frame", "config", "update_ms", "build_ms", "update_build_ms", "frame_ms", "trace_ms", "mrays_per_s",
              "rays", "hits", "mismatches", "mismatch_hit_miss", "mismatch_other_triangle", "ties", "scene_frame",
              "source_ms"});
  for (const auto& x : r.rows)
    t.add_row({std::int64_t(x.frame), x.config, x.update_ms, x.build_ms, x.update_ms + x.build_ms, x.frame_ms,
               x.trace_ms, x.mrays_per_s, x.rays, x.hits, x.mismatches, x.hit_miss, x.other_triangle, x.ties,
               x.scene_frame, x.source_ms});
  return t;
}

CsvTable bench_summary_csv(const PeerBenchResult& r) {
  std::vector<std::string> cols{"config", "frames_in_median", "update_ms", "build_ms", "update_build_ms", "trace_ms",
                                "mrays_per_s", "mismatches", "ties"};
  for (const char* e : kEmbree) cols.push_back(std::string("update_build_speedup_vs_") + e);
  for (const char* e : kEmbree) cols.push_back(std::string("trace_speed_vs_") + e);
  CsvTable t(cols);
  const int frames = r.rows.empty() ? 0 : r.rows.back().frame + 1;
  for (const auto& s : r.summary) {
    std::vector<CsvValue> row{s.config,   std::int64_t(frames - r.median_first_frame), s.update_ms, s.build_ms,
                              s.update_build_ms, s.trace_ms, s.mrays_per_s, s.mismatches, s.ties};
    for (const char* e : kEmbree) {
      const BenchSummary* p = find(r.summary, e);
      row.push_back(p && s.update_build_ms > 0 ? p->update_build_ms / s.update_build_ms : std::nan(""));
    }
    for (const char* e : kEmbree) {
      const BenchSummary* p = find(r.summary, e);
      row.push_back(p && p->mrays_per_s > 0 ? s.mrays_per_s / p->mrays_per_s : std::nan(""));
    }
    t.add_row(std::move(row));
  }
  return t;
}

std::string bench_table(const PeerBenchResult& r) {
  const int frames = r.rows.empty() ? 0 : r.rows.back().frame + 1;
  std::string s = fmt::format("medians over frames {}..{} ({} frames), {} rays\n", r.median_first_frame, frames - 1,
                              frames - r.median_first_frame, r.rays);
  s += fmt::format("{:<16} {:>10} {:>10} {:>13} {:>10} {:>10} {:>10} {:>8} {:>8}\n", "config", "update_ms",
                   "build_ms", "upd+build_ms", "trace_ms", "Mrays/s", "hits", "mismatch", "ties");
  for (const auto& x : r.summary) {
    std::uint64_t hits = 0;
    for (const auto& row : r.rows)
      if (row.config == x.config) hits = row.hits;
    s += fmt::format("{:<16} {:>10.2f} {:>10.2f} {:>13.2f} {:>10.2f} {:>10.2f} {:>10} {:>8} {:>8}\n", x.config,
                     x.update_ms, x.build_ms, x.update_build_ms, x.trace_ms, x.mrays_per_s, hits, x.mismatches, x.ties);
  }
  std::vector<double> src;
  for (const auto& row : r.rows)
    if (row.frame >= r.median_first_frame && row.config == r.rows.front().config) src.push_back(row.source_ms);
  s += fmt::format("frame source (positions of a frame, outside every configuration): median {:.2f} ms; vertex order: "
                   "{}{}; cluster BVH: {}\n",
                   median(src), r.vertex_order,
                   r.fused_vertex_pass ? " (cluster path: conversion and boxes in one pass)"
                                       : " (cluster path: positions gathered per frame)",
                   r.cluster_group_size > 1 ? fmt::format("two-level, groups of <= {} clusters", r.cluster_group_size)
                                            : std::string("plain SAH build over all cluster boxes"));
  s += "\nratios (> 1: the row is faster): update+build = Embree's time / the row's; trace = the row's Mrays/s / Embree's\n";
  s += fmt::format("{:<16}", "config");
  for (const char* e : kEmbree) s += fmt::format(" {:>19}", std::string("upd+build vs ") + (e + 7));
  for (const char* e : kEmbree) s += fmt::format(" {:>15}", std::string("trace vs ") + (e + 7));
  s += "\n";
  for (const auto& x : r.summary) {
    s += fmt::format("{:<16}", x.config);
    for (const char* e : kEmbree) {
      const BenchSummary* p = find(r.summary, e);
      s += fmt::format(" {:>18.2f}x", p && x.update_build_ms > 0 ? p->update_build_ms / x.update_build_ms : 0.0);
    }
    for (const char* e : kEmbree) {
      const BenchSummary* p = find(r.summary, e);
      s += fmt::format(" {:>14.2f}x", p && p->mrays_per_s > 0 ? x.mrays_per_s / p->mrays_per_s : 0.0);
    }
    s += "\n";
  }
  return s;
}

}  // namespace ptc
