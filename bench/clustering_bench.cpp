// Clustering speed (growth and contraction, per objective and MaxCount = MaxSize) and the sphere
// inside the Acc loop: speed against error. Plain tables on stdout; not a unit test.
//
//   clustering_bench [--mesh FILE] [--levels N] [--skip-large] [--only growth|contraction]
//                    [--objectives acc,naive,gwh01] [--sizes 10,50,100] [--repeats N]
//                    [--no-spheres] [--no-speed]
//
// Meshes: armadillo (52k triangles) and armadillo subdivided twice with the midpoint scheme
// (832k; the same surface). Every time is one run of the full pipeline cluster_mesh performs
// (ClusterTables, objective, algorithm, clustering_from_labels) on one thread; each run is repeated
// --repeats times (default 3) and the fastest is printed (wall clock and this process's CPU time;
// on a shared machine the minimum is the least disturbed measurement).
// Work counters: exact_ev / bound_ev = objective evaluations that returned the exact score / an
// upper bound (objectives.h, "Lazy evaluation"); spheres = Acc spheres computed on a point set
// (CGAL or the chosen method), the rest came from the shortcuts (acc.h).
// Sphere table: Acc at MaxCount = MaxSize = 50 with each SphereMethod inside the loop; the final
// clusters' mean reg and mean Acc are then recomputed with the EXACT sphere (cluster_metrics with
// SphereMethod::Exact, in parallel; not timed), so the columns show what the cheaper sphere costs
// in cluster quality. Exact inside the loop only on the 52k mesh (it is ~200x slower).
#include <oneapi/tbb/parallel_for.h>

#include <time.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/clustering/contraction.h"
#include "toolkit/clustering/growth.h"
#include "toolkit/clustering/objectives.h"
#include "toolkit/geometry/cluster_metrics.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"

namespace {

using namespace ptc;
using Clock = std::chrono::steady_clock;

/// CPU time of this process (the timed code is single-threaded; on a loaded machine this is the
/// stable number, wall clock is printed next to it).
double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Result {
  Clustering clustering;
  ClusterRun run;  // labels moved out; counters kept
  double seconds = 0;
  double cpu = 0;
  std::uint64_t spheres = 0;  // Acc: spheres computed from scratch
};

template <class O>
Result run_algorithm(const Mesh& mesh, const ClusterTables& tables, O& objective, ClusterMethod method,
                     Clock::time_point t0, double c0) {
  Result r;
  if (method == ClusterMethod::Growth) {
    GrowthOptions o;
    o.start = StartRule::SpatialOrder;
    r.run = grow_clusters(tables, objective, o);
  } else {
    r.run = contract_clusters(tables, objective, ContractionOptions{});
  }
  r.clustering = clustering_from_labels(r.run.labels, mesh.triangles());
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  r.cpu = cpu_seconds() - c0;
  return r;
}

Result cluster_timed(const Mesh& mesh, ClusterMethod method, ObjectiveKind objective, std::uint32_t size,
                     SphereMethod sphere = SphereMethod::Cgal) {
  const auto t0 = Clock::now();
  const double c0 = cpu_seconds();
  const ClusterTables tables = ClusterTables::build(mesh, /*edge_lengths=*/objective == ObjectiveKind::Gwh01);
  switch (objective) {
    case ObjectiveKind::Acc: {
      ClusterParams p;
      p.max_count = size;
      p.max_size = size;
      p.avg_sa = average_triangle_sphere_area(mesh.positions(), mesh.triangles());
      p.sphere = sphere;
      AccObjective o(tables, p, method == ClusterMethod::Growth ? AccTuning::for_growth() : AccTuning::for_contraction());
      Result r = run_algorithm(mesh, tables, o, method, t0, c0);
      r.spheres = o.sphere_computations();
      return r;
    }
    case ObjectiveKind::Naive: {
      NaiveObjective o(tables, size);
      return run_algorithm(mesh, tables, o, method, t0, c0);
    }
    case ObjectiveKind::Gwh01: {
      Gwh01Objective o(tables, size, GwhParams{});
      return run_algorithm(mesh, tables, o, method, t0, c0);
    }
  }
  return {};
}

struct Quality {
  double mean_reg = 0, mean_acc = 0;
};

/// Mean reg and Acc of the clusters, recomputed with the exact sphere (parallel).
Quality exact_quality(const Mesh& mesh, const Clustering& c, std::uint32_t size) {
  ClusterParams p;
  p.max_count = size;
  p.max_size = size;
  p.avg_sa = average_triangle_sphere_area(mesh.positions(), mesh.triangles());
  std::vector<double> reg(c.cluster_count()), acc(c.cluster_count());
  oneapi::tbb::parallel_for(std::size_t{0}, c.cluster_count(), [&](std::size_t k) {
    const ClusterMetrics m = cluster_metrics(mesh, c.triangles_of(k), SphereMethod::Exact);
    reg[k] = m.reg;
    acc[k] = cluster_acc(m, p);
  });
  const double n = static_cast<double>(c.cluster_count());
  return {std::accumulate(reg.begin(), reg.end(), 0.0) / n, std::accumulate(acc.begin(), acc.end(), 0.0) / n};
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');) out.push_back(item);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string mesh_path = std::string(PTC_TEST_DATA) + "/meshes/armadillo.off";
  int levels = 2;
  int repeats = 3;
  bool skip_large = false, spheres = true, speed = true;
  std::vector<ClusterMethod> methods{ClusterMethod::Growth, ClusterMethod::Contraction};
  std::vector<ObjectiveKind> objectives{ObjectiveKind::Acc, ObjectiveKind::Naive, ObjectiveKind::Gwh01};
  std::vector<std::uint32_t> sizes{10, 50, 100};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--mesh") {
      mesh_path = value();
    } else if (a == "--levels") {
      levels = std::stoi(value());
    } else if (a == "--repeats") {
      repeats = std::max(1, std::stoi(value()));
    } else if (a == "--skip-large") {
      skip_large = true;
    } else if (a == "--no-spheres") {
      spheres = false;
    } else if (a == "--no-speed") {
      speed = false;
    } else if (a == "--only") {
      const auto m = parse_cluster_method(value());
      if (!m) return 2;
      methods = {*m};
    } else if (a == "--objectives") {
      objectives.clear();
      for (const auto& s : split(value())) {
        const auto o = parse_objective(s);
        if (!o) return 2;
        objectives.push_back(*o);
      }
    } else if (a == "--sizes") {
      sizes.clear();
      for (const auto& s : split(value())) sizes.push_back(static_cast<std::uint32_t>(std::stoul(s)));
    } else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }

  std::vector<std::pair<std::string, Mesh>> meshes;
  meshes.emplace_back("armadillo", read_mesh(mesh_path).mesh);
  if (!skip_large)
    meshes.emplace_back("armadillo/mid" + std::to_string(levels),
                        subdivide(meshes.front().second, SubdivisionScheme::Midpoint, levels));

  if (speed) {
    std::printf("# clustering time, one thread (full cluster_mesh pipeline; start rule spatial for growth)\n");
    std::printf("%-16s %9s %-12s %-6s %5s %8s %8s %9s %8s %10s %10s %10s\n", "mesh", "triangles", "method", "obj",
                "size", "wall_s", "cpu_s", "clusters", "tri/cl", "exact_ev", "bound_ev", "spheres");
    for (const auto& [name, mesh] : meshes)
      for (ClusterMethod m : methods)
        for (ObjectiveKind o : objectives)
          for (std::uint32_t s : sizes) {
            Result r = cluster_timed(mesh, m, o, s);
            for (int rep = 1; rep < repeats; ++rep) {
              Result again = cluster_timed(mesh, m, o, s);
              if (again.cpu < r.cpu) r = std::move(again);
            }
            std::printf("%-16s %9zu %-12s %-6s %5u %8.3f %8.3f %9zu %8.2f %10llu %10llu %10llu\n", name.c_str(),
                        mesh.triangle_count(), std::string(to_string(m)).c_str(), std::string(to_string(o)).c_str(),
                        s, r.seconds, r.cpu, r.clustering.cluster_count(),
                        double(mesh.triangle_count()) / double(r.clustering.cluster_count()),
                        static_cast<unsigned long long>(r.run.exact_evaluations),
                        static_cast<unsigned long long>(r.run.bound_evaluations),
                        static_cast<unsigned long long>(r.spheres));
            std::fflush(stdout);
          }
  }

  if (spheres) {
    const std::uint32_t size = 50;
    std::printf("\n# sphere inside the Acc loop (MaxCount = MaxSize = %u): time, and the final clusters' mean reg /\n"
                "# mean Acc recomputed with the exact sphere; d_reg, d_acc = difference to the Cgal run\n",
                size);
    std::printf("%-16s %-12s %-7s %8s %8s %9s %12s %12s %11s %11s\n", "mesh", "method", "sphere", "wall_s", "cpu_s",
                "clusters",
                "mean_reg", "mean_acc", "d_reg", "d_acc");
    for (const auto& [name, mesh] : meshes)
      for (ClusterMethod m : methods) {
        std::vector<SphereMethod> list{SphereMethod::Cgal, SphereMethod::Epos26, SphereMethod::Epos14,
                                       SphereMethod::Epos6, SphereMethod::Ritter};
        if (mesh.triangle_count() < 100000) list.push_back(SphereMethod::Exact);
        Quality ref;
        for (SphereMethod sm : list) {
          const Result r = cluster_timed(mesh, m, ObjectiveKind::Acc, size, sm);
          const Quality q = exact_quality(mesh, r.clustering, size);
          if (sm == SphereMethod::Cgal) ref = q;
          std::printf("%-16s %-12s %-7s %8.3f %8.3f %9zu %12.6f %12.6f %11.2e %11.2e\n", name.c_str(),
                      std::string(to_string(m)).c_str(), std::string(to_string(sm)).c_str(), r.seconds, r.cpu,
                      r.clustering.cluster_count(), q.mean_reg, q.mean_acc, q.mean_reg - ref.mean_reg,
                      q.mean_acc - ref.mean_acc);
          std::fflush(stdout);
        }
      }
  }
  return 0;
}
