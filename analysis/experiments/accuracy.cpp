#include "analysis/experiments/accuracy.h"

#include <oneapi/tbb/global_control.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "analysis/metrics/cluster_table.h"
#include "analysis/metrics/reference_hits.h"
#include "bvh/trace_scene.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/geometry/sphere.h"

namespace ptc {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr SphereMethod kApprox[] = {SphereMethod::Ritter, SphereMethod::Epos6, SphereMethod::Epos14,
                                    SphereMethod::Epos26};
constexpr const char* kHitConfigs[] = {"ours_triangles", "ours_clusters", "embree_low", "embree_medium"};

struct AccuracyRow {
  std::string scene;
  std::int64_t frame = 0;
  std::string group, choice, reference;
  double time_ms = kNaN, reference_time_ms = kNaN, speedup = kNaN;
  std::string error;  ///< what error_mean / error_max measure
  double error_mean = kNaN, error_max = kNaN;
  double sah_cost = kNaN, reference_sah_cost = kNaN, trace_ms = kNaN, reference_trace_ms = kNaN;
  std::uint64_t count = 0;  ///< spheres, clusters or rays the row is over
  std::uint64_t mismatches = 0, ties = 0;
};
void visit_accuracy(const AccuracyRow& r, Columns& col) {
  col("scene", r.scene);
  col("frame", r.frame);
  col("group", r.group);
  col("choice", r.choice);
  col("reference", r.reference);
  col("time_ms", r.time_ms);
  col("reference_time_ms", r.reference_time_ms);
  col("speedup", r.speedup);
  col("error", r.error);
  col("error_mean", r.error_mean);
  col("error_max", r.error_max);
  col("sah_cost", r.sah_cost);
  col("reference_sah_cost", r.reference_sah_cost);
  col("trace_ms", r.trace_ms);
  col("reference_trace_ms", r.reference_trace_ms);
  col("count", r.count);
  col("mismatches", r.mismatches);
  col("ties", r.ties);
}
const Schema kAccuracySchema{"ptc-accuracy", 1};

double speedup_of(double ref, double t) { return t > 0 ? ref / t : kNaN; }

// The clustering the accuracy items measure: the given one, or acc_contraction with the user's
// parameters.
ClusterConfig method_config(const ExperimentParams& p) {
  if (p.given && p.given_cluster) return *p.given_cluster;  // the given clustering's own parameters
  ClusterConfig c = p.cluster;
  c.method = ClusterMethod::Contraction;
  c.objective = ObjectiveKind::Acc;
  return c;
}

double trace_primary_ms(const loop::Accel& a, const bvh::RayBatch& rays, unsigned threads, bvh::HitBatch* keep = nullptr) {
  bvh::TraceOptions o;
  o.threads = threads;
  bvh::HitBatch h;
  bvh::HitBatch& hits = keep ? *keep : h;
  hits.resize(rays.size());  // allocated and touched outside the timed trace
  a.check_rays(rays);        // (likewise)
  Stopwatch sw;
  (void)a.trace(rays, hits, o);
  return sw.ms();
}

}  // namespace

std::vector<std::string> accuracy_items(bool /*given*/) {
  std::vector<std::string> items;
  for (SphereMethod m : kApprox) items.push_back("sphere/" + std::string(to_string(m)));
  items.emplace_back("sphere/cgal");
  for (SphereMethod m : kApprox) items.push_back("sphere_in_loop/" + std::string(to_string(m)));
  items.emplace_back("builder/triangles");
  items.emplace_back("builder/clusters");
  items.emplace_back("groups/two_level");
  for (const char* c : kHitConfigs) items.push_back(std::string("hits/") + c);
  return items;
}

AccuracyRun run_accuracy(Scene& scene, const ExperimentParams& p, const study::StudySetup& setup,
                         const std::vector<std::string>& items, const std::vector<std::size_t>& done) {
  oneapi::tbb::global_control limit(oneapi::tbb::global_control::max_allowed_parallelism, setup.threads);
  AccuracyRun out;
  const Mesh& rest = scene.rest();
  const study::StudyRays rays = study::study_rays(rest, setup);
  out.rays = rays.primary.size();
  ClusterConfig mc = method_config(p);
  if (p.given) mc.adjacency = adjacency_on(rest, mc.adjacency);  // as drift and ptc viz read it
  FileRows file = file_rows("accuracy.csv", kAccuracySchema, columns_of<AccuracyRow>(visit_accuracy));
  if (done.empty()) {  // an empty shard: nothing to make
    out.files.push_back(std::move(file));
    return out;
  }
  // Ctrl-C stops a clustering at its next progress step (the loops run on this thread).
  const ProgressFn cancel = [](double) { throw_if_cancelled(); };
  Clustering method;
  if (p.given) method = *p.given;
  else method = cluster_mesh(rest, mc, cancel);

  loop::AccelSetup as = study::accel_setup(setup, rays.origin);
  as.clusters = &method;

  // Made once for the items that need them (they are updated per frame).
  const bool needs_loop_clusterings = [&] {
    for (std::size_t i : done)
      if (items[i].rfind("sphere_in_loop/", 0) == 0) return true;
    return false;
  }();
  std::vector<Clustering> in_loop;
  std::vector<double> in_loop_ms;
  Clustering cgal_loop;
  double cgal_loop_ms = 0;
  if (needs_loop_clusterings) {
    ClusterConfig c = mc;
    c.sphere = SphereMethod::Cgal;
    Stopwatch sw;
    cgal_loop = cluster_mesh(rest, c, cancel);
    cgal_loop_ms = sw.ms();
    for (SphereMethod m : kApprox) {
      throw_if_cancelled();
      c.sphere = m;
      sw.restart();
      in_loop.push_back(cluster_mesh(rest, c, cancel));
      in_loop_ms.push_back(sw.ms());
    }
  }
  const std::vector<std::size_t> sample = sample_rays(rays.primary.size(), p.reference_rays, 1);

  std::vector<std::vector<AccuracyRow>> rows(done.size());
  Mesh posed = rest;
  for (std::int64_t f = setup.frames.first; f <= setup.frames.last; ++f) {
    throw_if_cancelled();
    scene.positions(static_cast<double>(f), posed.positions());
    ReferenceHits ref;
    bool have_ref = false;
    double ref_ms = 0;
    for (std::size_t d = 0; d < done.size(); ++d) {
      throw_if_cancelled();
      const std::string& item = items[done[d]];
      AccuracyRow r;
      r.scene = p.scene;
      r.frame = f;
      r.group = item.substr(0, item.find('/'));
      r.choice = item.substr(item.find('/') + 1);
      if (r.group == "sphere") {
        const SphereMethod m = *parse_sphere_method(r.choice);
        r.reference = "exact";
        std::vector<std::vector<Vec3>> sets(method.cluster_count());
        for (std::size_t k = 0; k < sets.size(); ++k)
          for (std::uint32_t v : method.vertices_of(k)) sets[k].push_back(posed.positions()[v]);
        std::vector<double> got(sets.size()), exact(sets.size());
        Stopwatch sw;
        for (std::size_t k = 0; k < sets.size(); ++k) got[k] = bounding_sphere(m, sets[k]).radius;
        r.time_ms = sw.ms();
        sw.restart();
        for (std::size_t k = 0; k < sets.size(); ++k) exact[k] = bounding_sphere(SphereMethod::Exact, sets[k]).radius;
        r.reference_time_ms = sw.ms();
        std::vector<double> err;
        for (std::size_t k = 0; k < sets.size(); ++k)
          if (exact[k] > 0) err.push_back((got[k] - exact[k]) / exact[k]);
        const Summary s = summarize(err);
        r.error = "radius_rel_err";
        // Only the sets with a sphere to compare with (exact radius > 0) are measured: a frame that
        // collapses every cluster to a point measures none (nan, not a mean of 0 over nothing).
        r.error_mean = s.count ? s.mean : kNaN, r.error_max = s.count ? s.max : kNaN;
        r.count = s.count;
      } else if (r.group == "sphere_in_loop") {
        const std::size_t mi = static_cast<std::size_t>(
            std::find_if(std::begin(kApprox), std::end(kApprox), [&](SphereMethod m) { return to_string(m) == r.choice; }) -
            std::begin(kApprox));
        r.reference = "cgal";
        r.time_ms = in_loop_ms[mi];
        r.reference_time_ms = cgal_loop_ms;
        // Both clusterings scored by the same Acc (CGAL spheres) at the frame.
        auto mean_acc = [&](const Clustering& c) {
          double s = 0;
          std::size_t n = 0;
          for (const ClusterRow& row : cluster_rows(posed, c, mc))
            if (std::isfinite(row.acc)) s += row.acc, ++n;
          return n ? s / double(n) : kNaN;
        };
        const double a = mean_acc(in_loop[mi]), a0 = mean_acc(cgal_loop);
        r.error = "acc_mean_rel_diff";
        r.error_mean = r.error_max = a0 != 0 ? (a - a0) / std::abs(a0) : kNaN;
        r.count = in_loop[mi].cluster_count();
        loop::AccelSetup s1 = as, s0 = as;
        s1.clusters = &in_loop[mi];
        s0.clusters = &cgal_loop;
        auto a1 = loop::make_accel(loop::AccelKind::OursClusters, posed, s1);
        auto a0c = loop::make_accel(loop::AccelKind::OursClusters, posed, s0);
        r.sah_cost = a1->sah_cost().value_or(kNaN);
        r.reference_sah_cost = a0c->sah_cost().value_or(kNaN);
        r.trace_ms = trace_primary_ms(*a1, rays.primary, setup.threads);
        r.reference_trace_ms = trace_primary_ms(*a0c, rays.primary, setup.threads);
      } else if (r.group == "builder") {
        // Both builders on the same primitives at the frame, as the per-frame structures
        // (plain build: the sweep has no two-level one), then traced.
        const bool tris = r.choice == "triangles";
        const loop::AccelKind kind = tris ? loop::AccelKind::OursTriangles : loop::AccelKind::OursClusters;
        loop::AccelSetup binned = as, sweep = as;
        binned.cluster_group_size = sweep.cluster_group_size = 0;
        sweep.builder = bvh::SahBuilder::Sweep;
        auto af = loop::make_accel(kind, posed, sweep);
        auto ab = loop::make_accel(kind, posed, binned);
        af->update(posed.positions());  // timed on a second update (the first one builds the layout)
        ab->update(posed.positions());
        r.choice += "_sweep";
        r.reference = "binned";
        r.time_ms = af->last_update().stages.build_ms;
        r.reference_time_ms = ab->last_update().stages.build_ms;
        r.sah_cost = af->sah_cost().value_or(kNaN);
        r.reference_sah_cost = ab->sah_cost().value_or(kNaN);
        r.trace_ms = trace_primary_ms(*af, rays.primary, setup.threads);
        r.reference_trace_ms = trace_primary_ms(*ab, rays.primary, setup.threads);
        r.error = "sah_cost_rel_diff";
        r.error_mean = r.error_max =
            r.reference_sah_cost > 0 ? (r.sah_cost - r.reference_sah_cost) / r.reference_sah_cost : kNaN;
        r.count = tris ? posed.triangle_count() : method.cluster_count();
      } else if (r.group == "groups") {
        r.reference = "plain";
        loop::AccelSetup plain = as;
        plain.cluster_group_size = 0;
        loop::AccelSetup two = as;
        if (two.cluster_group_size == 0) two.cluster_group_size = bvh::cluster_scene_defaults().cluster_group_size;
        two.min_cluster_groups = 0;  // (the groups this row measures, whatever the mesh's size)
        auto a2 = loop::make_accel(loop::AccelKind::OursClusters, posed, two);
        auto a1 = loop::make_accel(loop::AccelKind::OursClusters, posed, plain);
        // Timed on a second update at the same positions (the first builds the layout).
        a2->update(posed.positions());
        a1->update(posed.positions());
        const auto t2 = a2->last_update(), t1 = a1->last_update();
        r.time_ms = t2.update_ms + t2.build_ms;
        r.reference_time_ms = t1.update_ms + t1.build_ms;
        r.sah_cost = a2->sah_cost().value_or(kNaN);
        r.reference_sah_cost = a1->sah_cost().value_or(kNaN);
        r.trace_ms = trace_primary_ms(*a2, rays.primary, setup.threads);
        r.reference_trace_ms = trace_primary_ms(*a1, rays.primary, setup.threads);
        r.error = "sah_cost_rel_diff";
        r.error_mean = r.error_max = r.reference_sah_cost > 0 ? (r.sah_cost - r.reference_sah_cost) / r.reference_sah_cost : kNaN;
        r.count = method.cluster_count();
      } else if (r.group == "hits") {
        r.reference = "double_brute_force";
        const loop::AccelKind k = *loop::parse_accel_kind(r.choice);
        auto a = loop::make_accel(k, posed, as);
        a->update(posed.positions());
        bvh::HitBatch hits;
        r.trace_ms = r.time_ms = trace_primary_ms(*a, rays.primary, setup.threads, &hits);
        if (!have_ref) {  // once per frame, for every configuration
          Stopwatch sw;
          ref = reference_hits(posed.triangles(), posed.positions(), rays.primary, sample);
          ref_ms = sw.ms();
          have_ref = true;
        }
        // The reference's time is for the sampled rays only: the speedup is per ray.
        r.reference_time_ms = ref_ms;
        r.speedup = r.time_ms > 0 && !sample.empty()
                        ? (ref_ms / double(sample.size())) / (r.time_ms / double(rays.primary.size()))
                        : kNaN;
        const HitErrors e = hit_errors(ref, hits, sample);
        r.error = "t_rel_err";
        r.error_mean = e.t_rel.count ? e.t_rel.mean : kNaN;
        r.error_max = e.t_rel.count ? e.t_rel.max : kNaN;
        r.count = e.rays;
        r.mismatches = e.mismatches();
        r.ties = e.ties;
      } else {
        throw std::invalid_argument("'" + item + "' is not an accuracy item");
      }
      if (std::isnan(r.speedup)) r.speedup = speedup_of(r.reference_time_ms, r.time_ms);
      rows[d].push_back(std::move(r));
      if (setup.progress)
        setup.progress(double((f - setup.frames.first) * std::int64_t(done.size()) + std::int64_t(d) + 1) /
                       double(setup.frames.count() * std::int64_t(done.size())));
    }
  }
  for (std::size_t d = 0; d < done.size(); ++d) add_item_rows(file, done[d], tabulate(kAccuracySchema, rows[d], visit_accuracy));
  out.files.push_back(std::move(file));
  return out;
}

std::string accuracy_text(const CsvText& a) {
  std::string s = "accuracy: speed against error of each approximation (speedup = reference time / time)\n";
  s += fmt::format("{:>5} {:<15} {:<16} {:<19} {:>10} {:>10} {:>8} {:<18} {:>11} {:>11} {:>6}\n", "frame", "group",
                   "choice", "reference", "time_ms", "ref_ms", "speedup", "error", "mean", "max", "mism.");
  const std::size_t fr = a.column("frame"), g = a.column("group"), c = a.column("choice"), r = a.column("reference"),
                    t = a.column("time_ms"), rt = a.column("reference_time_ms"), sp = a.column("speedup"),
                    e = a.column("error"), em = a.column("error_mean"), ex = a.column("error_max"),
                    mm = a.column("mismatches");
  for (std::size_t i = 0; i < a.rows.size(); ++i) {
    const auto& row = a.rows[i];
    s += fmt::format("{:>5} {:<15} {:<16} {:<19} {:>10.2f} {:>10.2f} {:>8.2f} {:<18} {:>11.3g} {:>11.3g} {:>6}\n", row[fr],
                     row[g], row[c], row[r], a.number(i, t), a.number(i, rt), a.number(i, sp), row[e], a.number(i, em),
                     a.number(i, ex), row[mm]);
  }
  return s;
}

}  // namespace ptc
