#include "analysis/experiments/experiments.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "analysis/experiments/accuracy.h"
#include "analysis/metrics/cluster_table.h"
#include "analysis/metrics/drift.h"
#include "analysis/metrics/epo.h"
#include "analysis/metrics/meshlet_stats.h"
#include "analysis/metrics/sah_overhead.h"
#include "analysis/metrics/sah_share.h"
#include "bvh/trace_scene.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/stats.h"
#include "toolkit/core/stopwatch.h"

namespace ptc {

const char* to_string(ExperimentKind k) {
  switch (k) {
    case ExperimentKind::Sweep: return "sweep";
    case ExperimentKind::Compare: return "compare";
    case ExperimentKind::Drift: return "drift";
    case ExperimentKind::Accuracy: return "accuracy";
  }
  return "?";
}

std::optional<ExperimentKind> parse_experiment_kind(std::string_view s) {
  for (ExperimentKind k : {ExperimentKind::Sweep, ExperimentKind::Compare, ExperimentKind::Drift, ExperimentKind::Accuracy})
    if (s == to_string(k)) return k;
  return std::nullopt;
}

std::vector<std::string> default_compare_configs(bool given) {
  std::vector<std::string> c;
  if (given) c.emplace_back("given");
  else c.insert(c.end(), {"acc_growth", "acc_contraction"});
  c.insert(c.end(), {"standard", "naive", "gwh01", "meshopt", "sah_split", "embree_low", "embree_refit", "embree_medium"});
  return c;
}

std::vector<std::string> default_drift_clusterings(bool given) {
  std::vector<std::string> c;
  if (given) c.emplace_back("given");
  else c.insert(c.end(), {"acc_growth", "acc_contraction"});
  c.insert(c.end(), {"naive", "gwh01", "meshopt", "sah_split"});
  return c;
}

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// |ln ratio| below this is rounding (the CGAL sphere and the box area are computed to about
/// 1e-15 relative): the drift correlations count it as no change (docs/experiments.md).
constexpr double kDriftNoise = 1e-12;

// The configuration a sweep value is: the user's method and objective with MaxCount = MaxSize =
// the value; 0 is one triangle per cluster (the paper's standard, any method; run as the triangle BVH).
ClusterConfig sweep_config(const ClusterConfig& base, std::uint32_t n) {
  ClusterConfig c = base;
  c.max_count = n;
  c.max_size = n;
  if (n == 0) c.method = ClusterMethod::Growth, c.objective = ObjectiveKind::Acc;
  return c;
}

// The parameters a configuration's per-cluster metrics use: its own clustering's, the given
// clustering's (from its manifest), else the user's.
ClusterConfig metric_config(const study::ConfigSpec& spec, const ExperimentParams& p) {
  if (spec.cluster) return *spec.cluster;
  if (spec.given && p.given_cluster) return *p.given_cluster;
  return p.cluster;
}

study::ConfigSpec spec_of(const std::string& name, const ExperimentParams& p) {
  study::ConfigSpec s;
  s.name = name;
  if (name == "given") {
    if (!p.given) throw std::invalid_argument("configuration 'given' needs a clustering (--clusters DIR)");
    s.given = p.given;
    if (p.given_cluster) s.given_adjacency = p.given_cluster->adjacency;
    return s;
  }
  if (name == "standard" || name == "triangles") {
    s.kind = loop::AccelKind::OursTriangles;
    return s;
  }
  for (loop::AccelKind k : {loop::AccelKind::EmbreeLow, loop::AccelKind::EmbreeRefit, loop::AccelKind::EmbreeMedium})
    if (name == loop::to_string(k)) {
      s.kind = k;
      return s;
    }
  s.cluster = study::clustering_config(name, p.cluster);
  if (!s.cluster) throw std::invalid_argument("'" + name + "' is not a configuration");
  if (const auto problem = check(*s.cluster))
    throw std::invalid_argument(fmt::format("{}: {} ({})", name, problem->reason, problem->parameter));
  return s;
}

// ---------------------------------------------------------------- rows shared by the kinds

struct ConfigRow {
  std::string scene, config, structure, method, objective;
  std::optional<std::int64_t> max_count = 0;  // none: a given clustering without a manifest (unknown)
  double max_size = 0;
  std::uint64_t clusters = 0, triangles = 0;
  double triangles_per_cluster = 0, cluster_ms = 0, setup_ms = 0;
  bool fused_vertex_pass = false;
};
void visit_config(const ConfigRow& r, Columns& col) {
  col("scene", r.scene);
  col("config", r.config);
  col("structure", r.structure);
  col("method", r.method);
  col("objective", r.objective);
  col("max_count", r.max_count ? CsvValue(*r.max_count) : CsvValue(std::string()));
  col("max_size", r.max_size);
  col("clusters", r.clusters);
  col("triangles", r.triangles);
  col("triangles_per_cluster", r.triangles_per_cluster);
  col("cluster_ms", r.cluster_ms);
  col("setup_ms", r.setup_ms);
  col("fused_vertex_pass", r.fused_vertex_pass);
}
// The parameters of a clustering as the row gives them (method, objective, MaxCount, MaxSize).
void cluster_parameters(const ClusterConfig& c, ConfigRow& r) {
  r.objective =
      c.method != ClusterMethod::Growth && c.method != ClusterMethod::Contraction ? "" : to_string(c.objective);
  r.max_count = c.max_count;
  // MaxSize only where the method reads it (Acc): nan for the others (naive, gwh01, meshopt,
  // sah-split), whose clusters it did not shape.
  const auto used = used_parameters(c);
  r.max_size = std::find(used.begin(), used.end(), "max_size") != used.end() ? c.max_size : kNaN;
}

// `given_cluster`: the given clustering's parameters, from its manifest (none without one).
ConfigRow config_row(const std::string& scene, const study::Prepared& p, const std::optional<ClusterConfig>& given_cluster) {
  ConfigRow r;
  r.scene = scene;
  r.config = p.spec.name;
  r.structure = std::string(loop::to_string(p.spec.kind));
  r.triangles = p.mesh.triangle_count();
  if (p.spec.cluster) {
    const ClusterConfig& c = *p.spec.cluster;
    const bool none = c.max_count == 0 && c.max_size == 0;
    r.method = none ? "none" : to_string(c.method);
    cluster_parameters(c, r);
    if (none) r.objective.clear();
  } else if (p.spec.given) {
    // Its own parameters where its manifest gave them (the method stays "given": the clusters
    // were read, not made), else unknown: MaxCount empty, MaxSize nan.
    r.method = "given";
    if (given_cluster) {
      cluster_parameters(*given_cluster, r);
    } else {
      r.max_count.reset();
      r.max_size = kNaN;
    }
  } else {
    r.method = "none";  // a structure over triangles (standard, Embree's): as sweep's MaxCount 0
  }
  if (p.has_clusters) {
    r.clusters = p.clustering.cluster_count();
    r.triangles_per_cluster = r.clusters ? double(r.triangles) / double(r.clusters) : 0.0;
    if (const auto* cs = loop::cluster_scene_of(*p.accel)) r.fused_vertex_pass = cs->fused_vertex_pass();
  }
  r.cluster_ms = p.cluster_ms;
  r.setup_ms = p.setup_ms;
  return r;
}

double per_ray(std::uint64_t n, std::uint64_t rays) { return rays ? double(n) / double(rays) : kNaN; }

// ---------------------------------------------------------------- sweep

const Schema kSweepSchema{"ptc-sweep", 2};
struct SweepRow {
  std::string scene;
  std::int64_t max_count = 0;
  double max_size = 0;
  std::uint64_t clusters = 0;
  std::int64_t frame = 0;
  bool warmup = false;
  std::uint64_t hits = 0;  // the frame's primary rays that hit (the same on its four stage rows)
  std::string stage;
  double ms = 0;
};
void visit_sweep(const SweepRow& r, Columns& col) {
  col("scene", r.scene);
  col("max_count", r.max_count);
  col("max_size", r.max_size);
  col("primitives", r.clusters);
  col("frame", r.frame);
  col("warmup", r.warmup);
  col("hits", r.hits);
  col("stage", r.stage);
  col("ms", r.ms);
}

// ---------------------------------------------------------------- compare

const Schema kCompareSchema{"ptc-compare", 1};
struct CompareRow {
  std::string scene;
  std::int64_t frame = 0;
  bool warmup = false;
  std::string config, structure;
  std::uint64_t clusters = 0;
  double update_ms = 0, build_ms = 0, trace_ms = 0, trace_primary_ms = 0, trace_shadow_ms = 0, total_ms = 0;
  double perf_factor = kNaN;  // filled by assemble()
  std::uint64_t rays = 0, shadow_rays = 0, hits = 0;
  double sah_cost = kNaN;
};
void visit_compare(const CompareRow& r, Columns& col) {
  col("scene", r.scene);
  col("frame", r.frame);
  col("warmup", r.warmup);
  col("config", r.config);
  col("structure", r.structure);
  col("clusters", r.clusters);
  col("update_ms", r.update_ms);
  col("build_ms", r.build_ms);
  col("trace_ms", r.trace_ms);
  col("trace_primary_ms", r.trace_primary_ms);
  col("trace_shadow_ms", r.trace_shadow_ms);
  col("total_ms", r.total_ms);
  col("perf_factor", r.perf_factor);
  col("rays", r.rays);
  col("shadow_rays", r.shadow_rays);
  col("hits", r.hits);
  col("sah_cost", r.sah_cost);
}

// ---------------------------------------------------------------- drift

const Schema kClustersFramesSchema{"ptc-drift-clusters", 1};
struct ClusterFrameRow {
  std::string clustering;
  std::int64_t frame = 0;
  std::uint32_t cluster_id = 0;
  std::uint64_t triangles = 0, vertices = 0;
  double connectivity = 0, reg = 0, acc = 0, reg_delta = 0, acc_delta = 0, sphere_radius = 0, sphere_radius_ratio = 0,
         sphere_radius_ratio_prev = 0, box_area = 0, box_area_ratio = 0, box_area_ratio_prev = 0, p_hit = 0, sah_share = 0;
  std::uint32_t boundary_vertices = 0, components = 0;
  bool not_full = false;
};
void visit_cluster_frame(const ClusterFrameRow& r, Columns& col) {
  col("clustering", r.clustering);
  col("frame", r.frame);
  col("cluster_id", r.cluster_id);
  col("triangles", r.triangles);
  col("vertices", r.vertices);
  col("connectivity", r.connectivity);
  col("reg", r.reg);
  col("acc", r.acc);
  col("reg_delta", r.reg_delta);
  col("acc_delta", r.acc_delta);
  col("sphere_radius", r.sphere_radius);
  col("sphere_radius_ratio", r.sphere_radius_ratio);
  col("sphere_radius_ratio_prev", r.sphere_radius_ratio_prev);
  col("box_area", r.box_area);
  col("box_area_ratio", r.box_area_ratio);
  col("box_area_ratio_prev", r.box_area_ratio_prev);
  col("p_hit", r.p_hit);
  col("sah_share", r.sah_share);
  col("boundary_vertices", r.boundary_vertices);
  col("components", r.components);
  col("not_full", r.not_full);
}

const Schema kFramesSchema{"ptc-drift-frames", 1};
struct DriftFrameRow {
  std::string scene, clustering;
  std::int64_t frame = 0;
  bool warmup = false;
  std::uint64_t clusters = 0;
  double sah_cost = 0, sah_cost_triangles = 0, sah_overhead = 0, epo = 0, nodes_per_ray = 0, triangles_per_ray = 0;
  double reg_mean = kNaN, acc_mean = kNaN, sphere_radius_ratio_max = kNaN, box_area_ratio_mean = kNaN,
         box_area_ratio_p50 = kNaN, box_area_ratio_p95 = kNaN, box_area_ratio_max = kNaN,
         box_area_ratio_prev_p95 = kNaN, box_area_ratio_prev_max = kNaN;
  std::string worst_clusters;
  double metrics_ms = 0;
};
void visit_drift_frame(const DriftFrameRow& r, Columns& col) {
  col("scene", r.scene);
  col("clustering", r.clustering);
  col("frame", r.frame);
  col("warmup", r.warmup);
  col("clusters", r.clusters);
  col("sah_cost", r.sah_cost);
  col("sah_cost_triangles", r.sah_cost_triangles);
  col("sah_overhead", r.sah_overhead);
  col("epo", r.epo);
  col("nodes_per_ray", r.nodes_per_ray);
  col("triangles_per_ray", r.triangles_per_ray);
  col("reg_mean", r.reg_mean);
  col("acc_mean", r.acc_mean);
  col("sphere_radius_ratio_max", r.sphere_radius_ratio_max);
  col("box_area_ratio_mean", r.box_area_ratio_mean);
  col("box_area_ratio_p50", r.box_area_ratio_p50);
  col("box_area_ratio_p95", r.box_area_ratio_p95);
  col("box_area_ratio_max", r.box_area_ratio_max);
  col("box_area_ratio_prev_p95", r.box_area_ratio_prev_p95);
  col("box_area_ratio_prev_max", r.box_area_ratio_prev_max);
  col("worst_clusters", r.worst_clusters);
  col("metrics_ms", r.metrics_ms);
}

const Schema kRaysSchema{"ptc-drift-rays", 1};
struct RayRow {
  std::string clustering;
  std::int64_t frame = 0;
  bool warmup = false;
  std::string ray_type;
  std::uint64_t rays = 0;
  double nodes_per_ray = 0, triangles_per_ray = 0, cost_per_ray = 0, sah_cost = 0, epo = 0, trace_ms = 0, ns_per_ray = 0;
};
void visit_ray(const RayRow& r, Columns& col) {
  col("clustering", r.clustering);
  col("frame", r.frame);
  col("warmup", r.warmup);
  col("ray_type", r.ray_type);
  col("rays", r.rays);
  col("nodes_per_ray", r.nodes_per_ray);
  col("triangles_per_ray", r.triangles_per_ray);
  col("cost_per_ray", r.cost_per_ray);
  col("sah_cost", r.sah_cost);
  col("epo", r.epo);
  col("trace_ms", r.trace_ms);
  col("ns_per_ray", r.ns_per_ray);
}

const Schema kCorrelationSchema{"ptc-drift-correlation", 1};
struct CorrelationRow {
  std::string scene, clustering, x, y;
  std::uint64_t clusters = 0, frames = 0;
  double spearman = kNaN, pearson = kNaN;
};
void visit_correlation(const CorrelationRow& r, Columns& col) {
  col("scene", r.scene);
  col("clustering", r.clustering);
  col("x", r.x);
  col("y", r.y);
  col("clusters", r.clusters);
  col("frames", r.frames);
  col("spearman", r.spearman);
  col("pearson", r.pearson);
}

const Schema kConfigsSchema{"ptc-experiment-configs", 1};

// The preparation (clusterings, renumbering, first builds) takes the first kPrepareShare of the
// progress bar: at 1M triangles six clusterings take minutes.
constexpr double kPrepareShare = 0.2;

std::vector<study::Prepared> prepare_all(const Scene& scene, const std::vector<study::ConfigSpec>& specs,
                                         const study::StudySetup& setup, const loop::AccelSetup& as,
                                         ExperimentRun& run, FileRows& configs, const std::string& scene_label,
                                         const std::optional<ClusterConfig>& given_cluster) {
  std::vector<study::Prepared> out;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    throw_if_cancelled();
    out.push_back(study::prepare(scene.rest(), specs[i], setup, as));
    const ConfigRow row = config_row(scene_label, out.back(), given_cluster);
    run.timings_ms["prepare_" + specs[i].name] = out.back().cluster_ms + out.back().setup_ms;
    std::vector<ConfigRow> one{row};
    add_item_rows(configs, run.done[i], tabulate(kConfigsSchema, one, visit_config));
    if (setup.progress) setup.progress(kPrepareShare * double(i + 1) / double(specs.size()));
  }
  return out;
}

// The study loop with the progress of the loop mapped after the preparation's share.
study::StudySetup loop_setup(const study::StudySetup& setup) {
  study::StudySetup s = setup;
  if (setup.progress) s.progress = [f = setup.progress](double x) { f(kPrepareShare + (1.0 - kPrepareShare) * x); };
  return s;
}

struct Context {
  Scene& scene;
  const ExperimentParams& p;
  const study::StudySetup& setup;
  const study::StudyRays& rays;
  const loop::AccelSetup& as;  ///< the trace frame and settings every structure shares
  ExperimentRun& run;
  std::vector<study::Prepared>& prepared;
};

void run_sweep(Context& x) {
  study::PassOptions timed;
  timed.threads = x.setup.threads;
  FileRows f = file_rows("sweep.csv", kSweepSchema, columns_of<SweepRow>(visit_sweep));
  std::vector<std::vector<SweepRow>> rows(x.prepared.size());
  study::run_study(x.scene, x.prepared, loop_setup(x.setup), [&](const study::StudyFrame& sf, std::size_t c, study::Prepared& pr) {
    const study::Passes ps = study::trace_passes(pr, x.rays, x.setup.light, timed);
    const double trace = ps.primary.trace_ms + ps.shadow.trace_ms;
    SweepRow r;
    r.scene = x.p.scene;
    r.max_count = pr.spec.cluster->max_count;
    r.max_size = pr.spec.cluster->max_size;
    r.clusters = pr.has_clusters ? pr.clustering.cluster_count() : pr.mesh.triangle_count();
    r.frame = sf.frame;
    r.warmup = sf.warmup;
    r.hits = ps.primary.hits;
    const std::pair<const char*, double> stages[] = {{"update", sf.times.update_ms},
                                                     {"build", sf.times.build_ms},
                                                     {"trace", trace},
                                                     {"total", sf.times.update_ms + sf.times.build_ms + trace}};
    for (const auto& [stage, ms] : stages) {
      r.stage = stage;
      r.ms = ms;
      rows[c].push_back(r);
    }
  });
  for (std::size_t c = 0; c < x.prepared.size(); ++c) add_item_rows(f, x.run.done[c], tabulate(kSweepSchema, rows[c], visit_sweep));
  x.run.files.push_back(std::move(f));
}

void run_compare(Context& x) {
  study::PassOptions timed;
  timed.threads = x.setup.threads;
  FileRows f = file_rows("compare.csv", kCompareSchema, columns_of<CompareRow>(visit_compare));
  std::vector<std::vector<CompareRow>> rows(x.prepared.size());
  study::run_study(x.scene, x.prepared, loop_setup(x.setup), [&](const study::StudyFrame& sf, std::size_t c, study::Prepared& pr) {
    const study::Passes ps = study::trace_passes(pr, x.rays, x.setup.light, timed);
    CompareRow r;
    r.scene = x.p.scene;
    r.frame = sf.frame;
    r.warmup = sf.warmup;
    r.config = pr.spec.name;
    r.structure = std::string(loop::to_string(pr.spec.kind));
    r.clusters = pr.has_clusters ? pr.clustering.cluster_count() : 0;
    r.update_ms = sf.times.update_ms;
    r.build_ms = sf.times.build_ms;
    r.trace_primary_ms = ps.primary.trace_ms;
    r.trace_shadow_ms = ps.shadow.trace_ms;
    r.trace_ms = r.trace_primary_ms + r.trace_shadow_ms;
    r.total_ms = r.update_ms + r.build_ms + r.trace_ms;
    r.rays = ps.primary.rays;
    r.shadow_rays = ps.shadow.rays;
    r.hits = ps.primary.hits;
    r.sah_cost = x.prepared[c].accel->sah_cost().value_or(kNaN);
    rows[c].push_back(r);
  });
  for (std::size_t c = 0; c < x.prepared.size(); ++c)
    add_item_rows(f, x.run.done[c], tabulate(kCompareSchema, rows[c], visit_compare));
  x.run.files.push_back(std::move(f));
}

// What drift keeps per configuration over the frames.
struct Track {
  std::vector<ClusterRow> first, prev;
  std::vector<MeshletShape> shapes;
  std::vector<double> drift_sum;   // per cluster: sum over the frames after the first of |ln box_area_ratio|
  std::vector<double> radius_sum;  // the same of the sphere radius
  std::size_t frames_summed = 0;
  std::vector<ClusterFrameRow> cluster_rows;
  std::vector<DriftFrameRow> frame_rows;
  std::vector<RayRow> ray_rows;
  /// A clustering's triangle BVH of the same frame: one structure updated per frame, in the
  /// study's trace frame, as the triangles item's own.
  std::unique_ptr<loop::Accel> triangles;
};

// The cluster BVH's metrics at the frame: SAH shares per cluster id, EPO, meshoptimizer's SAH
// overhead, every cluster's row (against the first and the previous frame) and the frame's
// summaries.
void drift_clusters(const ExperimentParams& p, const study::StudyFrame& sf, study::Prepared& pr, Track& tr,
                    const bvh::SahCostModel& cost, DriftFrameRow& d) {
  const Mesh& m = pr.mesh;
  const bvh::ClusterScene* cs = loop::cluster_scene_of(*pr.accel);
  d.clusters = pr.clustering.cluster_count();
  const bvh::Bvh tree = cs->cluster_tree();  // over the clusters (bvh() is over the groups with fixed group trees)
  d.sah_cost = tree.cost;
  const SahShares shares = sah_shares(tree, cs->boxes(), cs->weights(), cost);
  std::vector<double> share(pr.clustering.cluster_count(), 0.0);
  std::vector<std::uint32_t> offsets{0}, ids;
  for (std::size_t i = 0; i < cs->cluster_ids().size(); ++i) {
    const std::uint32_t k = cs->cluster_ids()[i];
    share[k] = shares.share[i];
    const auto t = pr.clustering.triangles_of(k);
    ids.insert(ids.end(), t.begin(), t.end());
    offsets.push_back(static_cast<std::uint32_t>(ids.size()));
  }
  d.epo = end_point_overlap(tree, m.triangles(), m.positions(), offsets, ids, cost).epo;
  d.sah_overhead = sah_overhead(m, pr.clustering).overhead;
  const ClusterConfig mc = metric_config(pr.spec, p);
  const std::vector<ClusterRow> rows = cluster_rows(m, pr.clustering, mc, std::nullopt, pr.adjacency);
  if (tr.first.empty()) {
    tr.first = rows, tr.prev = rows;
    tr.drift_sum.assign(rows.size(), 0.0), tr.radius_sum.assign(rows.size(), 0.0);
  }
  const std::vector<ClusterDrift> dr = cluster_drift(tr.first, rows), dp = cluster_drift(tr.prev, rows);
  if (sf.index > 0) {
    // A change below kDriftNoise is rounding, not motion (a cluster carried rigidly by a bone
    // gets ratios 1 +- a few ulps, whose ranks would decide the Spearman of such clusters): 0.
    auto moved = [](double ratio) {
      const double v = std::abs(std::log(ratio));
      return v < kDriftNoise ? 0.0 : v;
    };
    for (std::size_t k = 0; k < rows.size(); ++k) {
      tr.drift_sum[k] += moved(dr[k].box_area_ratio);
      tr.radius_sum[k] += moved(dr[k].sphere_radius_ratio);
    }
    ++tr.frames_summed;
  }
  const DriftSummary ds = summarize_drift(dr, 5);
  std::vector<double> reg, acc;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    ClusterFrameRow r;
    r.clustering = pr.spec.name;
    r.frame = sf.frame;
    r.cluster_id = static_cast<std::uint32_t>(k);
    r.triangles = rows[k].m.triangles;
    r.vertices = rows[k].m.vertices;
    r.connectivity = rows[k].m.connectivity;
    r.reg = rows[k].m.reg;
    r.acc = rows[k].acc;
    r.reg_delta = dr[k].reg_delta;
    r.acc_delta = dr[k].acc_delta;
    r.sphere_radius = rows[k].m.sphere.radius;
    r.sphere_radius_ratio = dr[k].sphere_radius_ratio;
    r.sphere_radius_ratio_prev = dp[k].sphere_radius_ratio;
    r.box_area = rows[k].m.box.surface_area();
    r.box_area_ratio = dr[k].box_area_ratio;
    r.box_area_ratio_prev = dp[k].box_area_ratio;
    r.p_hit = rows[k].m.p_hit;
    r.sah_share = share[k];
    r.boundary_vertices = tr.shapes[k].boundary_vertices;
    r.components = tr.shapes[k].components;
    r.not_full = tr.shapes[k].not_full;
    tr.cluster_rows.push_back(r);
    reg.push_back(rows[k].m.reg);
    if (std::isfinite(rows[k].acc)) acc.push_back(rows[k].acc);
  }
  d.reg_mean = summarize(reg).mean;
  d.acc_mean = acc.empty() ? kNaN : summarize(acc).mean;
  d.sphere_radius_ratio_max = ds.sphere_radius_ratio.count ? ds.sphere_radius_ratio.max : kNaN;
  if (ds.box_area_ratio.count) {
    d.box_area_ratio_mean = ds.box_area_ratio.mean;
    d.box_area_ratio_p50 = ds.box_area_ratio.p50;
    d.box_area_ratio_p95 = ds.box_area_ratio.p95;
    d.box_area_ratio_max = ds.box_area_ratio.max;
  }
  if (const DriftSummary dps = summarize_drift(dp, 0); dps.box_area_ratio.count) {
    d.box_area_ratio_prev_p95 = dps.box_area_ratio.p95;
    d.box_area_ratio_prev_max = dps.box_area_ratio.max;
  }
  for (std::uint32_t w : ds.worst_box_area) d.worst_clusters += (d.worst_clusters.empty() ? "" : ";") + std::to_string(w);
  tr.prev = rows;
}

// Spearman (and Pearson) over the clusters of connectivity against the mean drift over the frames
// after the first; NaN drifts (a cluster of zero box area at the first frame) are left out.
std::vector<CorrelationRow> drift_correlations(const ExperimentParams& p, const study::Prepared& pr, const Track& tr) {
  std::vector<CorrelationRow> corr;
  if (!pr.has_clusters) return corr;
  const double n = tr.frames_summed ? double(tr.frames_summed) : kNaN;
  for (const auto& [sums, name] : {std::pair{&tr.drift_sum, "box_area_drift"}, std::pair{&tr.radius_sum, "sphere_radius_drift"}}) {
    std::vector<double> xs, ys;
    for (std::size_t k = 0; k < tr.first.size(); ++k) {
      const double y = (*sums)[k] / n;
      if (std::isfinite(y)) xs.push_back(tr.first[k].m.connectivity), ys.push_back(y);
    }
    CorrelationRow r;
    r.scene = p.scene;
    r.clustering = pr.spec.name;
    r.x = "connectivity";
    r.y = name;
    r.clusters = xs.size();
    r.frames = tr.frames_summed;
    if (xs.size() >= 3) r.spearman = spearman(xs, ys), r.pearson = pearson(xs, ys);
    corr.push_back(r);
  }
  return corr;
}

void run_drift(Context& x) {
  FileRows fc = file_rows("clusters_frames.csv", kClustersFramesSchema, columns_of<ClusterFrameRow>(visit_cluster_frame));
  FileRows ff = file_rows("frames.csv", kFramesSchema, columns_of<DriftFrameRow>(visit_drift_frame));
  FileRows fr = file_rows("rays.csv", kRaysSchema, columns_of<RayRow>(visit_ray));
  FileRows fk = file_rows("correlation.csv", kCorrelationSchema, columns_of<CorrelationRow>(visit_correlation));
  study::PassOptions counted;
  counted.threads = x.setup.threads;
  counted.counters = true;
  counted.ao_samples = x.p.ao_samples;
  const bvh::SahCostModel cost = bvh::cluster_scene_defaults().build.cost;
  std::vector<Track> tracks(x.prepared.size());
  for (std::size_t c = 0; c < x.prepared.size(); ++c)
    if (x.prepared[c].has_clusters) {
      const ClusterConfig mc = metric_config(x.prepared[c].spec, x.p);
      tracks[c].shapes = meshlet_shapes(x.prepared[c].clustering, x.prepared[c].mesh.triangles(),
                                        x.prepared[c].mesh.vertex_count(), std::max<std::uint32_t>(mc.max_count, 1));
    }
  study::run_study(x.scene, x.prepared, loop_setup(x.setup), [&](const study::StudyFrame& sf, std::size_t c, study::Prepared& pr) {
    Stopwatch sw;
    Track& tr = tracks[c];
    const study::Passes ps = study::trace_passes(pr, x.rays, x.setup.light, counted);
    DriftFrameRow d;
    d.scene = x.p.scene;
    d.clustering = pr.spec.name;
    d.frame = sf.frame;
    d.warmup = sf.warmup;
    // The triangle BVH of the same frame (its own structure, or one kept beside a clustering).
    const bvh::TriangleScene* ts = loop::triangle_scene_of(*pr.accel);
    if (!ts) {
      if (!tr.triangles) tr.triangles = loop::make_accel(loop::AccelKind::OursTriangles, pr.mesh, x.as);
      else tr.triangles->update(pr.mesh.positions());
      ts = loop::triangle_scene_of(*tr.triangles);
    }
    d.sah_cost_triangles = ts->bvh().cost;
    if (pr.has_clusters) {
      drift_clusters(x.p, sf, pr, tr, cost, d);
    } else {
      d.sah_cost = d.sah_cost_triangles;
      d.sah_overhead = 1.0;
      d.epo = end_point_overlap(ts->bvh(), pr.mesh.triangles(), pr.mesh.positions(), {}, {}, cost).epo;
    }
    d.nodes_per_ray = per_ray(ps.primary.nodes_visited, ps.primary.rays);
    d.triangles_per_ray = per_ray(ps.primary.triangles_tested, ps.primary.rays);
    const std::pair<const char*, const PassStats*> passes[] = {{"primary", &ps.primary}, {"shadow", &ps.shadow}, {"ao", &ps.ao}};
    for (const auto& [type, st] : passes) {
      if (st->rays == 0) continue;
      RayRow r;
      r.clustering = pr.spec.name;
      r.frame = sf.frame;
      r.warmup = sf.warmup;
      r.ray_type = type;
      r.rays = st->rays;
      r.nodes_per_ray = per_ray(st->nodes_visited, st->rays);
      r.triangles_per_ray = per_ray(st->triangles_tested, st->rays);
      r.cost_per_ray = cost.traversal * r.nodes_per_ray + cost.intersection * r.triangles_per_ray;
      r.sah_cost = d.sah_cost;
      r.epo = d.epo;
      r.trace_ms = st->trace_ms;
      r.ns_per_ray = st->trace_ms * 1e6 / double(st->rays);
      tr.ray_rows.push_back(r);
    }
    d.metrics_ms = sw.ms();
    tr.frame_rows.push_back(d);
  });
  for (std::size_t c = 0; c < x.prepared.size(); ++c) {
    const std::size_t item = x.run.done[c];
    const Track& tr = tracks[c];
    add_item_rows(fc, item, tabulate(kClustersFramesSchema, tr.cluster_rows, visit_cluster_frame));
    add_item_rows(ff, item, tabulate(kFramesSchema, tr.frame_rows, visit_drift_frame));
    add_item_rows(fr, item, tabulate(kRaysSchema, tr.ray_rows, visit_ray));
    add_item_rows(fk, item, tabulate(kCorrelationSchema, drift_correlations(x.p, x.prepared[c], tr), visit_correlation));
  }
  for (FileRows* f : {&fc, &ff, &fr, &fk}) x.run.files.push_back(std::move(*f));
}

}  // namespace

FileRows file_rows(std::string file, Schema schema, std::vector<std::string> header) {
  FileRows f;
  f.file = std::move(file);
  f.schema = std::move(schema);
  f.rows.header = std::move(header);
  return f;
}

void add_item_rows(FileRows& f, std::size_t item, const Table& t) {
  CsvText c = parse_csv(t.csv.str());
  if (c.header != f.rows.header) throw std::logic_error(f.file + ": an item's columns differ from the file's");
  f.item_rows.emplace_back(item, c.rows.size());
  for (auto& r : c.rows) f.rows.rows.push_back(std::move(r));
}

std::vector<std::string> experiment_items(const ExperimentParams& p) {
  std::vector<std::string> items;
  switch (p.kind) {
    case ExperimentKind::Sweep:
      for (std::uint32_t n : p.max_counts) items.push_back(fmt::format("max_count={}", n));
      break;
    case ExperimentKind::Compare:
      items = p.configs.empty() ? default_compare_configs(p.has_given()) : p.configs;
      break;
    case ExperimentKind::Drift:
      items.emplace_back("triangles");
      for (const auto& c : p.clusterings.empty() ? default_drift_clusterings(p.has_given()) : p.clusterings)
        items.push_back(c);
      break;
    case ExperimentKind::Accuracy: items = accuracy_items(p.has_given()); break;
  }
  return items;
}

std::vector<std::string> primary_files(ExperimentKind kind) {
  switch (kind) {
    case ExperimentKind::Sweep: return {"configs.csv", "sweep.csv"};
    case ExperimentKind::Compare: return {"configs.csv", "compare.csv"};
    case ExperimentKind::Drift: return {"configs.csv", "clusters_frames.csv", "frames.csv", "rays.csv", "correlation.csv"};
    case ExperimentKind::Accuracy: return {"accuracy.csv"};
  }
  return {};
}

ExperimentRun run_experiment(Scene& scene, const ExperimentParams& p, const study::StudySetup& setup) {
  if (scene.rest().empty()) throw std::invalid_argument("the mesh has no triangles");
  if (setup.shard.count < 1 || setup.shard.index >= setup.shard.count) throw std::invalid_argument("bad shard");
  ExperimentRun run;
  run.items = experiment_items(p);
  {
    std::set<std::string> seen;
    for (const auto& i : run.items)
      if (!seen.insert(i).second) throw std::invalid_argument("'" + i + "' is listed twice");
  }
  for (std::size_t i = 0; i < run.items.size(); ++i)
    if (setup.shard.has(i)) run.done.push_back(i);
  run.triangles = scene.rest().triangle_count();
  run.vertices = scene.rest().vertex_count();

  if (p.kind == ExperimentKind::Accuracy) {
    AccuracyRun a = run_accuracy(scene, p, setup, run.items, run.done);
    run.files = std::move(a.files);
    run.rays = a.rays;
    return run;
  }

  const study::StudyRays rays = study::study_rays(scene.rest(), setup);
  run.rays = rays.primary.size();
  const loop::AccelSetup as = study::accel_setup(setup, rays.origin);

  // The shard's configurations.
  std::vector<study::ConfigSpec> specs;
  for (std::size_t i : run.done) {
    const std::string& name = run.items[i];
    if (p.kind == ExperimentKind::Sweep) {
      study::ConfigSpec s;
      s.name = name;
      s.cluster = sweep_config(p.cluster, p.max_counts[i]);
      // MaxCount = MaxSize = 0 is the paper's standard: the triangle BVH (ours_triangles), not
      // the cluster path over one-triangle clusters.
      if (p.max_counts[i] == 0) s.kind = loop::AccelKind::OursTriangles;
      if (const auto problem = check(*s.cluster))
        throw std::invalid_argument(fmt::format("MaxCount {}: {}", p.max_counts[i], problem->reason));
      specs.push_back(s);
    } else {
      specs.push_back(spec_of(name, p));
    }
  }
  FileRows configs = file_rows("configs.csv", kConfigsSchema, columns_of<ConfigRow>(visit_config));
  std::vector<study::Prepared> prepared = prepare_all(scene, specs, setup, as, run, configs, p.scene, p.given_cluster);
  run.files.push_back(std::move(configs));
  Context x{scene, p, setup, rays, as, run, prepared};
  if (p.kind == ExperimentKind::Sweep) run_sweep(x);
  else if (p.kind == ExperimentKind::Compare) run_compare(x);
  else run_drift(x);
  return run;
}

}  // namespace ptc
