// Clustering benchmark (issue 4's figures; not a unit test). Four sections (the last only when
// asked for), each a table on stdout and, with --out DIR, a CSV in DIR (written atomically with
// a JSON manifest):
//
//   speed.csv        time per method (growth, contraction, sah-split, meshopt) and objective (acc,
//                    naive, gwh01 where it applies) at MaxCount = MaxSize in --sizes, one thread;
//   spheres.csv      the sphere inside the Acc loop (exact, cgal, epos26/14/6, ritter): time, and
//                    the final clusters' mean reg / mean Acc recomputed with the EXACT sphere;
//   start_rules.csv  growth's start rule (index, spatial, fewest-free): clusters, mean reg / Acc,
//                    time;
//   stages.csv       growth and contraction (Acc, MaxCount = MaxSize = --sphere-size) stage by
//                    stage: the tables with AvgSA, the algorithm, the clusters from the labels (CPU
//                    time, median of --repeats; the stages of one `ptc cluster` cluster stage);
//   manifest.json    argv, the input mesh and its hash, parameters, versions, machine, timings.
//
//   clustering_bench [--mesh FILE] [--levels N] [--skip-large] [--quick] [--out DIR]
//                    [--methods growth,contraction,sah-split,meshopt] [--objectives acc,naive,gwh01]
//                    [--sizes 10,50,100] [--repeats N] [--sections speed,spheres,start,stages]
//                    [--sphere-size N] [--no-exact]
//
// Meshes: armadillo (52k triangles; --mesh, default ${PTC_DATA_DIR}/meshes/armadillo.off) and
// armadillo subdivided --levels times (default 2) with the midpoint scheme (832k; the same
// surface). --quick: the 52k mesh only, size 50, one repeat, no exact sphere in the loop (a smoke
// run of every section, ~10 s).
//
// Timing: every time is one run of the full pipeline that cluster_mesh performs (ClusterTables,
// objective, algorithm, clustering_from_labels) on one thread, repeated --repeats times (default
// 3); the MEDIAN of the process CPU time and of the wall time are reported (the machine is shared:
// the CPU time is the stable figure). Work counters (growth/contraction): exact_ev / bound_ev =
// objective evaluations that returned the exact score / an upper bound (objectives.h, "Lazy
// evaluation"); spheres = Acc spheres computed on a point set (the rest came from shortcuts).
// Quality columns (speed and start-rule tables): mean reg and mean Acc of the final clusters with
// the CGAL sphere, Acc with MaxCount = MaxSize = the row's size (also for naive, gwh01, sah-split
// and meshopt, so that the methods compare on Garanzha's measure); computed in parallel, not timed.
#include <oneapi/tbb/parallel_for.h>

#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/schema/manifest.h"
#include "analysis/schema/table.h"
#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/clustering/contraction.h"
#include "toolkit/clustering/growth.h"
#include "toolkit/clustering/objectives.h"
#include "toolkit/core/stats.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/geometry/cluster_metrics.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"
#include "toolkit/core/strings.h"

namespace {

using namespace ptc;

/// CPU time of this process (the timed code is single-threaded).
double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Result {
  Clustering clustering;
  ClusterRun run;  // counters (growth/contraction only)
  double seconds = 0;
  double cpu = 0;
  std::uint64_t spheres = 0;  // Acc: spheres computed from scratch
};

struct Job {
  ClusterMethod method = ClusterMethod::Growth;
  ObjectiveKind objective = ObjectiveKind::Acc;
  std::uint32_t size = 50;
  SphereMethod sphere = SphereMethod::Cgal;
  StartRule start = StartRule::SpatialOrder;
};

bool uses_objective(ClusterMethod m) { return m == ClusterMethod::Growth || m == ClusterMethod::Contraction; }

/// Acc's parameters at MaxCount = MaxSize = size, with the mesh's AvgSA.
ClusterParams acc_params(const Mesh& mesh, std::uint32_t size, SphereMethod sphere) {
  ClusterParams p;
  p.max_count = size;
  p.max_size = size;
  p.avg_sa = average_triangle_sphere_area(mesh.positions(), mesh.triangles());
  p.sphere = sphere;
  return p;
}

/// The Acc accelerations cluster_mesh picks for the method.
AccTuning acc_tuning(ClusterMethod m) {
  return m == ClusterMethod::Growth ? AccTuning::for_growth() : AccTuning::for_contraction();
}

/// The same clusters in the same order (the determinism check of the repeats).
bool same_clustering(const Clustering& a, const Clustering& b) {
  return a.triangle_order == b.triangle_order && a.triangle_offsets == b.triangle_offsets;
}

[[noreturn]] void non_deterministic(ClusterMethod m) {
  std::fprintf(stderr, "NON-DETERMINISTIC clustering (%s)\n", std::string(to_string(m)).c_str());
  std::exit(3);
}

template <class O>
void run_algorithm(const Mesh& mesh, const ClusterTables& tables, O& objective, const Job& job, Result& r) {
  if (job.method == ClusterMethod::Growth) {
    GrowthOptions o;
    o.start = job.start;
    r.run = grow_clusters(tables, objective, o);
  } else {
    r.run = contract_clusters(tables, objective, ContractionOptions{});
  }
  r.clustering = clustering_from_labels(r.run.labels, mesh.triangles());
}

/// One timed run of the pipeline cluster_mesh performs (see the file comment).
Result cluster_once(const Mesh& mesh, const Job& job) {
  Result r;
  const Stopwatch wall;
  const double c0 = cpu_seconds();
  if (!uses_objective(job.method)) {
    ClusterConfig cfg;
    cfg.method = job.method;
    cfg.max_count = job.size;
    cfg.max_size = job.size;
    r.clustering = cluster_mesh(mesh, cfg);
  } else {
    const ClusterTables tables = ClusterTables::build(mesh, /*with_edges=*/job.objective == ObjectiveKind::Gwh01);
    switch (job.objective) {
      case ObjectiveKind::Acc: {
        AccObjective o(tables, acc_params(mesh, job.size, job.sphere), acc_tuning(job.method));
        run_algorithm(mesh, tables, o, job, r);
        r.spheres = o.sphere_computations();
        break;
      }
      case ObjectiveKind::Naive: {
        NaiveObjective o(tables, job.size);
        run_algorithm(mesh, tables, o, job, r);
        break;
      }
      case ObjectiveKind::Gwh01: {
        Gwh01Objective o(tables, job.size, GwhParams{});
        run_algorithm(mesh, tables, o, job, r);
        break;
      }
    }
  }
  r.seconds = wall.ms() * 1e-3;
  r.cpu = cpu_seconds() - c0;
  r.run.labels.clear();
  r.run.labels.shrink_to_fit();
  return r;
}

/// `repeats` runs; the last run's result with the median wall and CPU times. Every run must give
/// the same clustering (determinism; the bench stops otherwise).
Result cluster_timed(const Mesh& mesh, const Job& job, int repeats) {
  std::vector<double> wall, cpu;
  Result r;
  for (int i = 0; i < repeats; ++i) {
    Result again = cluster_once(mesh, job);
    if (i > 0 && !same_clustering(again.clustering, r.clustering)) non_deterministic(job.method);
    wall.push_back(again.seconds);
    cpu.push_back(again.cpu);
    r = std::move(again);
  }
  r.seconds = median(wall);
  r.cpu = median(cpu);
  return r;
}

struct Quality {
  double mean_reg = 0, mean_acc = 0, mean_triangles = 0;
};

/// Mean reg and Acc (MaxCount = MaxSize = size) of the clusters with sphere `sm` (parallel).
Quality quality(const Mesh& mesh, const Clustering& c, std::uint32_t size, SphereMethod sm) {
  const ClusterParams p = acc_params(mesh, size, sm);
  const std::size_t n = c.cluster_count();
  if (n == 0) return {};
  std::vector<double> reg(n), acc(n);
  oneapi::tbb::parallel_for(std::size_t{0}, n, [&](std::size_t k) {
    const ClusterMetrics m = cluster_metrics(mesh, c.triangles_of(k), sm);
    reg[k] = m.reg;
    acc[k] = cluster_acc(m, p);
  });
  const double dn = static_cast<double>(n);
  return {std::accumulate(reg.begin(), reg.end(), 0.0) / dn, std::accumulate(acc.begin(), acc.end(), 0.0) / dn,
          static_cast<double>(mesh.triangle_count()) / dn};
}

// The three tables (schemas ptc-clustering-speed/1, ptc-clustering-spheres/1,
// ptc-clustering-start-rules/1): one row type and one visitor each, over shared column groups.
struct Timed {
  double wall_s = 0, cpu_s = 0;
  std::uint64_t clusters = 0;
};
Timed timed(const Result& r) { return {r.seconds, r.cpu, r.clustering.cluster_count()}; }
void visit_timed(const Timed& t, Columns& col) {
  col("wall_s", t.wall_s);
  col("cpu_s", t.cpu_s);
  col("clusters", t.clusters);
}
void visit_quality(const Quality& q, Columns& col) {
  col("triangles_per_cluster", q.mean_triangles);
  col("mean_reg", q.mean_reg);
  col("mean_acc", q.mean_acc);
}

struct SpeedRow {
  std::string mesh;
  std::uint64_t triangles = 0;
  std::string method, objective;
  std::uint64_t size = 0;
  Timed t;
  Quality q;
  std::uint64_t exact_evaluations = 0, bound_evaluations = 0, spheres = 0;
};
void visit_speed(const SpeedRow& r, Columns& col) {
  col("mesh", r.mesh);
  col("triangles", r.triangles);
  col("method", r.method);
  col("objective", r.objective);
  col("size", r.size);
  visit_timed(r.t, col);
  visit_quality(r.q, col);
  col("exact_evaluations", r.exact_evaluations);
  col("bound_evaluations", r.bound_evaluations);
  col("sphere_computations", r.spheres);
}

struct SphereRow {
  std::string mesh;
  std::uint64_t triangles = 0;
  std::string method;
  std::uint64_t size = 0;
  std::string sphere;
  Timed t;
  Quality q;  // with the exact sphere
  double d_reg_vs_cgal = 0, d_acc_vs_cgal = 0, d_reg_vs_exact = 0, d_acc_vs_exact = 0, time_ratio_vs_cgal = 0;
};
void visit_sphere(const SphereRow& r, Columns& col) {
  col("mesh", r.mesh);
  col("triangles", r.triangles);
  col("method", r.method);
  col("size", r.size);
  col("sphere", r.sphere);
  visit_timed(r.t, col);
  col("mean_reg_exact", r.q.mean_reg);
  col("mean_acc_exact", r.q.mean_acc);
  col("d_reg_vs_cgal", r.d_reg_vs_cgal);
  col("d_acc_vs_cgal", r.d_acc_vs_cgal);
  col("d_reg_vs_exact", r.d_reg_vs_exact);
  col("d_acc_vs_exact", r.d_acc_vs_exact);
  col("time_ratio_vs_cgal", r.time_ratio_vs_cgal);
}

struct StartRow {
  std::string mesh;
  std::uint64_t triangles = 0;
  std::string objective;
  std::uint64_t size = 0;
  std::string start;
  Timed t;
  Quality q;
};
void visit_start(const StartRow& r, Columns& col) {
  col("mesh", r.mesh);
  col("triangles", r.triangles);
  col("objective", r.objective);
  col("size", r.size);
  col("start", r.start);
  visit_timed(r.t, col);
  visit_quality(r.q, col);
}

struct StageRow {
  std::string mesh;
  std::uint64_t triangles = 0;
  std::string method;
  std::uint64_t size = 0;
  double tables_s = 0, algorithm_s = 0, from_labels_s = 0, total_s = 0;
  std::uint64_t clusters = 0;
};
void visit_stage(const StageRow& r, Columns& col) {
  col("mesh", r.mesh);
  col("triangles", r.triangles);
  col("method", r.method);
  col("size", r.size);
  col("tables_cpu_s", r.tables_s);
  col("algorithm_cpu_s", r.algorithm_s);
  col("from_labels_cpu_s", r.from_labels_s);
  col("total_cpu_s", r.total_s);
  col("clusters", r.clusters);
}

/// The stages of cluster_mesh's growth / contraction with Acc (cgal sphere), each timed in CPU
/// seconds, medians of `repeats`; every repeat must give the same clustering.
StageRow stages_timed(const std::string& name, const Mesh& mesh, ClusterMethod method, std::uint32_t size, int repeats) {
  std::vector<double> tab, alg, lab, tot;
  Clustering first;
  for (int i = 0; i < repeats; ++i) {
    double c = cpu_seconds();
    auto lap = [&] {
      const double now = cpu_seconds(), d = now - c;
      c = now;
      return d;
    };
    // cluster_mesh's one pass: the tables with AvgSA and the centroids' box (with_sums)
    const ClusterTables tables = ClusterTables::build(mesh, /*with_edges=*/false, /*with_sums=*/true);
    const double avg_sa = tables.avg_sphere_area;
    tab.push_back(lap());
    ClusterConfig cfg;  // Acc, cgal sphere: cluster_mesh's own objective and loop
    cfg.method = method;
    cfg.max_count = size;
    cfg.max_size = size;
    const ClusterRun run = detail::run_objective(tables, cfg, avg_sa, {});
    alg.push_back(lap());
    Clustering cl = clustering_from_labels(run.labels, mesh.triangles());
    lab.push_back(lap());
    tot.push_back(tab.back() + alg.back() + lab.back());
    if (i > 0 && !same_clustering(cl, first)) non_deterministic(method);
    if (i == 0) first = std::move(cl);
  }
  return {name, mesh.triangle_count(), std::string(to_string(method)), size, median(tab), median(alg), median(lab),
          median(tot), first.cluster_count()};
}

[[noreturn]] void usage_error(const std::string& msg) {
  std::fprintf(stderr, "clustering_bench: %s\n", msg.c_str());
  std::exit(2);
}

/// Every non-empty item of a comma list through `parse` (which exits with a usage error for a bad one).
template <class F>
auto parse_each(const std::string& list, F parse) {
  std::vector<decltype(parse(list))> out;
  for (const std::string& item : split_list(list)) out.push_back(parse(item));
  return out;
}

/// A parse_* of an enum name as a `parse_each` item parser; `what` names the kind in the error.
template <class Parse>
auto named(Parse parse, const char* what) {
  return [parse, what](const std::string& s) {
    const auto v = parse(s);
    if (!v) usage_error(std::string("unknown ") + what + " " + s);
    return *v;
  };
}

std::string str(std::string_view s) { return std::string(s); }

}  // namespace

int main(int argc, char** argv) {
  const char* data_env = std::getenv("PTC_DATA_DIR");
  std::string mesh_path = std::string(data_env && *data_env ? data_env : PTC_TEST_DATA) + "/meshes/armadillo.off";
  int levels = 2;
  int repeats = 3;
  bool skip_large = false, quick = false, with_exact = true;
  std::uint32_t sphere_size = 50;
  std::string out_dir;
  std::vector<std::string> sections{"speed", "spheres", "start"};
  std::vector<ClusterMethod> methods{ClusterMethod::Growth, ClusterMethod::Contraction, ClusterMethod::SahSplit,
                                     ClusterMethod::Meshopt};
  std::vector<ObjectiveKind> objectives{ObjectiveKind::Acc, ObjectiveKind::Naive, ObjectiveKind::Gwh01};
  std::vector<std::uint32_t> sizes{10, 50, 100};
  bool sizes_given = false, repeats_given = false;
  const std::vector<std::string> args(argv, argv + argc);
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage_error(a + " needs a value");
      return argv[++i];
    };
    auto number = [&](const std::string& s) -> unsigned long {
      try {
        std::size_t used = 0;
        const unsigned long v = std::stoul(s, &used);
        if (used != s.size()) throw std::invalid_argument(s);
        return v;
      } catch (const std::exception&) {
        usage_error(a + ": not a number: " + s);
      }
    };
    if (a == "--help" || a == "-h") {
      std::printf(
          "usage: clustering_bench [--mesh FILE] [--levels N] [--skip-large] [--quick] [--out DIR]\n"
          "                        [--methods growth,contraction,sah-split,meshopt] [--objectives acc,naive,gwh01]\n"
          "                        [--sizes 10,50,100] [--repeats N] [--sections speed,spheres,start,stages]\n"
          "                        [--sphere-size N] [--no-exact]\n"
          "(the sections and their CSV files: the comment at the top of bench/clustering_bench.cpp, docs/tables.md)\n");
      return 0;
    }
    if (a == "--mesh") {
      mesh_path = value();
    } else if (a == "--levels") {
      levels = static_cast<int>(number(value()));
    } else if (a == "--repeats") {
      repeats = std::max(1, static_cast<int>(number(value())));
      repeats_given = true;
    } else if (a == "--skip-large") {
      skip_large = true;
    } else if (a == "--quick") {
      quick = true;
    } else if (a == "--no-exact") {
      with_exact = false;
    } else if (a == "--out") {
      out_dir = value();
    } else if (a == "--sphere-size") {
      sphere_size = static_cast<std::uint32_t>(number(value()));
    } else if (a == "--sections") {
      sections = parse_each(value(), named([](const std::string& s) {
        return s == "speed" || s == "spheres" || s == "start" || s == "stages" ? std::optional(s) : std::nullopt;
      }, "section"));
    } else if (a == "--methods" || a == "--only") {
      methods = parse_each(value(), named([](const std::string& s) { return parse_cluster_method(s); }, "method"));
    } else if (a == "--objectives") {
      objectives = parse_each(value(), named([](const std::string& s) { return parse_objective(s); }, "objective"));
    } else if (a == "--sizes") {
      sizes = parse_each(value(), [&](const std::string& s) { return static_cast<std::uint32_t>(number(s)); });
      sizes_given = true;
    } else {
      usage_error("unknown argument " + a);
    }
  }
  if (quick) {
    skip_large = true;
    with_exact = false;
    if (!sizes_given) sizes = {50};
    if (!repeats_given) repeats = 1;
  }
  auto has_section = [&](const char* s) { return std::find(sections.begin(), sections.end(), s) != sections.end(); };

  RunManifest manifest("clustering_bench", args);
  manifest.set_parameter("levels", skip_large ? 0 : levels);
  manifest.set_parameter("repeats", repeats);
  manifest.set_parameter("quick", quick);
  manifest.set_parameter("threads", 1);
  manifest.set_parameter("sizes", sizes);
  manifest.set_parameter("sphere_size", sphere_size);
  manifest.set_parameter("sections", sections);
  manifest.set_parameter("timing", "median of repeats; cpu_s = process CPU time, wall_s = wall clock");

  std::vector<std::pair<std::string, Mesh>> meshes;
  const Stopwatch t_load;
  try {
    meshes.emplace_back(std::filesystem::path(mesh_path).stem().string(), read_mesh(mesh_path).mesh);  // its file's name
    record_input(manifest, mesh_path);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "clustering_bench: %s\n", e.what());
    return 1;
  }
  if (!skip_large)
    meshes.emplace_back(meshes.front().first + "/mid" + std::to_string(levels),
                        subdivide(meshes.front().second, SubdivisionScheme::Midpoint, levels));
  manifest.add_timing_ms("load_and_subdivide", t_load.ms());

  std::vector<SpeedRow> speed_rows;
  std::vector<SphereRow> sphere_rows;
  std::vector<StartRow> start_rows;
  std::vector<StageRow> stage_rows;

  if (has_section("speed")) {
    std::printf("# clustering time, one thread, median of %d (growth: spatial start rule; sphere: cgal)\n", repeats);
    std::printf("%-15s %8s %-11s %-6s %5s %8s %8s %8s %7s %9s %9s %10s %10s %9s\n", "mesh", "tris", "method", "obj",
                "size", "wall_s", "cpu_s", "clusters", "tri/cl", "mean_reg", "mean_acc", "exact_ev", "bound_ev",
                "spheres");
    for (const auto& [name, mesh] : meshes)
      for (ClusterMethod m : methods) {
        std::vector<ObjectiveKind> objs = objectives;
        if (!uses_objective(m)) objs = {ObjectiveKind::Acc};  // unused; one row
        for (ObjectiveKind o : objs)
          for (std::uint32_t s : sizes) {
            Job job;
            job.method = m;
            job.objective = o;
            job.size = s;
            const Result r = cluster_timed(mesh, job, repeats);
            const Quality q = quality(mesh, r.clustering, s, SphereMethod::Cgal);
            const std::string obj = uses_objective(m) ? str(to_string(o)) : "-";
            std::printf("%-15s %8zu %-11s %-6s %5u %8.3f %8.3f %8zu %7.2f %9.5f %9.5f %10llu %10llu %9llu\n",
                        name.c_str(), mesh.triangle_count(), str(to_string(m)).c_str(), obj.c_str(), s, r.seconds,
                        r.cpu, r.clustering.cluster_count(), q.mean_triangles, q.mean_reg, q.mean_acc,
                        static_cast<unsigned long long>(r.run.exact_evaluations),
                        static_cast<unsigned long long>(r.run.bound_evaluations),
                        static_cast<unsigned long long>(r.spheres));
            std::fflush(stdout);
            speed_rows.push_back({name, mesh.triangle_count(), str(to_string(m)), obj, s, timed(r), q,
                                  r.run.exact_evaluations, r.run.bound_evaluations, r.spheres});
          }
      }
  }

  if (has_section("spheres")) {
    const std::uint32_t size = sphere_size;
    std::printf("\n# sphere inside the Acc loop (MaxCount = MaxSize = %u), median of %d: time, and the final\n"
                "# clusters' mean reg / mean Acc recomputed with the EXACT sphere; d_* = difference to the cgal\n"
                "# run and to the exact-in-loop run (exact in the loop only on meshes < 100k triangles)\n",
                size, repeats);
    std::printf("%-15s %-11s %-7s %8s %8s %7s %8s %11s %11s %10s %10s %10s %10s\n", "mesh", "method", "sphere",
                "wall_s", "cpu_s", "x_cgal", "clusters", "mean_reg", "mean_acc", "d_reg_cg", "d_acc_cg", "d_reg_ex",
                "d_acc_ex");
    for (const auto& [name, mesh] : meshes)
      for (ClusterMethod m : methods) {
        if (!uses_objective(m)) continue;
        std::vector<SphereMethod> list{SphereMethod::Cgal, SphereMethod::Epos26, SphereMethod::Epos14,
                                       SphereMethod::Epos6, SphereMethod::Ritter};
        if (with_exact && mesh.triangle_count() < 100000) list.insert(list.begin(), SphereMethod::Exact);
        Quality ref_cgal, ref_exact;
        double cgal_cpu = 0;
        bool have_exact = false;
        for (SphereMethod sm : list) {
          Job job;
          job.method = m;
          job.objective = ObjectiveKind::Acc;
          job.size = size;
          job.sphere = sm;
          const Result r = cluster_timed(mesh, job, sm == SphereMethod::Exact ? 1 : repeats);
          const Quality q = quality(mesh, r.clustering, size, SphereMethod::Exact);
          if (sm == SphereMethod::Exact) {
            ref_exact = q;
            have_exact = true;
          }
          if (sm == SphereMethod::Cgal) {
            ref_cgal = q;
            cgal_cpu = r.cpu;
          }
          const double nan = std::numeric_limits<double>::quiet_NaN();
          const double dre = have_exact ? q.mean_reg - ref_exact.mean_reg : nan;
          const double dae = have_exact ? q.mean_acc - ref_exact.mean_acc : nan;
          // Exact runs before Cgal: its d_*_cg is filled in once Cgal has run (the CSV keeps NaN).
          const bool cg = sm != SphereMethod::Exact;
          const double drc = cg ? q.mean_reg - ref_cgal.mean_reg : nan, dac = cg ? q.mean_acc - ref_cgal.mean_acc : nan;
          const double ratio = cg && cgal_cpu > 0 ? r.cpu / cgal_cpu : nan;
          std::printf("%-15s %-11s %-7s %8.3f %8.3f %7.2f %8zu %11.6f %11.6f %10.2e %10.2e %10.2e %10.2e\n",
                      name.c_str(), str(to_string(m)).c_str(), str(to_string(sm)).c_str(), r.seconds, r.cpu, ratio,
                      r.clustering.cluster_count(), q.mean_reg, q.mean_acc, drc, dac, dre, dae);
          std::fflush(stdout);
          sphere_rows.push_back({name, mesh.triangle_count(), str(to_string(m)), size, str(to_string(sm)), timed(r), q,
                                 drc, dac, dre, dae, ratio});
        }
      }
  }

  if (has_section("start")) {
    const std::uint32_t size = sphere_size;
    std::printf("\n# growth start rule (MaxCount = MaxSize = %u), median of %d; mean reg / Acc with the cgal sphere\n",
                size, repeats);
    std::printf("%-15s %-6s %-12s %8s %8s %8s %7s %9s %9s\n", "mesh", "obj", "start", "wall_s", "cpu_s", "clusters",
                "tri/cl", "mean_reg", "mean_acc");
    for (const auto& [name, mesh] : meshes)
      for (ObjectiveKind o : objectives)
        for (StartRule rule : {StartRule::IndexOrder, StartRule::SpatialOrder, StartRule::FewestFree}) {
          Job job;
          job.method = ClusterMethod::Growth;
          job.objective = o;
          job.size = size;
          job.start = rule;
          const Result r = cluster_timed(mesh, job, repeats);
          const Quality q = quality(mesh, r.clustering, size, SphereMethod::Cgal);
          std::printf("%-15s %-6s %-12s %8.3f %8.3f %8zu %7.2f %9.5f %9.5f\n", name.c_str(),
                      str(to_string(o)).c_str(), str(to_string(rule)).c_str(), r.seconds, r.cpu,
                      r.clustering.cluster_count(), q.mean_triangles, q.mean_reg, q.mean_acc);
          std::fflush(stdout);
          start_rows.push_back(
              {name, mesh.triangle_count(), str(to_string(o)), size, str(to_string(rule)), timed(r), q});
        }
  }

  if (has_section("stages")) {
    const std::uint32_t size = sphere_size;
    std::printf("\n# stages of growth / contraction (acc, cgal sphere, MaxCount = MaxSize = %u), CPU s, median of %d\n",
                size, repeats);
    std::printf("%-15s %9s %-11s %8s %9s %11s %8s %8s\n", "mesh", "tris", "method", "tables", "algorithm", "from_labels",
                "total", "clusters");
    for (const auto& [name, mesh] : meshes)
      for (ClusterMethod m : methods) {
        if (!uses_objective(m)) continue;
        const StageRow r = stages_timed(name, mesh, m, size, repeats);
        std::printf("%-15s %9llu %-11s %8.3f %9.3f %11.3f %8.3f %8llu\n", name.c_str(),
                    static_cast<unsigned long long>(r.triangles), r.method.c_str(), r.tables_s, r.algorithm_s,
                    r.from_labels_s, r.total_s, static_cast<unsigned long long>(r.clusters));
        std::fflush(stdout);
        stage_rows.push_back(r);
      }
  }

  if (!out_dir.empty()) {
    OutputDir dir{std::filesystem::path(out_dir)};
    std::vector<std::string> written;
    auto write = [&](const char* section, const std::string& file, const Table& t) {
      if (!has_section(section)) return;
      dir.write(file, t.csv.str());
      manifest.add_output(file, t.schema.id());
      written.push_back(file);
    };
    write("speed", "speed.csv", tabulate(Schema{"ptc-clustering-speed", 1}, speed_rows, visit_speed));
    write("spheres", "spheres.csv", tabulate(Schema{"ptc-clustering-spheres", 1}, sphere_rows, visit_sphere));
    write("start", "start_rules.csv", tabulate(Schema{"ptc-clustering-start-rules", 1}, start_rows, visit_start));
    write("stages", "stages.csv", tabulate(Schema{"ptc-clustering-stages", 2}, stage_rows, visit_stage));
    manifest.add_output("manifest.json");
    nlohmann::json meshes_json = nlohmann::json::array();
    for (const auto& [name, mesh] : meshes)
      meshes_json.push_back({{"name", name}, {"triangles", mesh.triangle_count()}, {"vertices", mesh.vertex_count()}});
    manifest.set_result("meshes", meshes_json);
    manifest.set_result("rows", {{"speed", speed_rows.size()}, {"spheres", sphere_rows.size()},
                                 {"start_rules", start_rows.size()}, {"stages", stage_rows.size()}});
    dir.write("manifest.json", dump_json(manifest.to_json()));
    dir.commit();
    std::printf("\nwrote %s/{%smanifest.json}\n", out_dir.c_str(), [&] {
      std::string s;
      for (const auto& f : written) s += f + ",";
      return s;
    }().c_str());
  }
  return 0;
}
