// Per-sphere time of every bounding-sphere method on cluster-like point sets of a real mesh:
// armadillo's triangles in Morton order cut into runs of 64-128 (the same point sets as
// `ptc spheres`, see analysis/metrics/sphere_accuracy.h). Each benchmark also reports the radius error
// against the exact minimal sphere over all point sets (counters rel_err_mean / rel_err_max,
// (r - r_exact) / r_exact) and how many spheres miss a point (not_containing, must be 0).
//
//   build/bin/spheres_bench [MESH] [--benchmark_filter=...]   ("s_per_sphere" is the per-sphere time)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

#include "analysis/metrics/sphere_accuracy.h"
#include "toolkit/io/mesh_io.h"

namespace {

std::string g_mesh = std::string(PTC_TEST_DATA) + "/meshes/armadillo.off";

struct Data {
  std::vector<std::vector<ptc::Vec3>> sets;
  std::vector<double> exact;
};

const Data& data() {
  static const Data d = [] {
    Data r;
    r.sets = ptc::morton_point_sets(ptc::read_mesh(g_mesh).mesh, ptc::SphereReportConfig{});
    for (const auto& s : r.sets) r.exact.push_back(ptc::min_sphere_exact(s).radius);
    return r;
  }();
  return d;
}

void BM_Sphere(benchmark::State& state, ptc::SphereMethod method) {
  const Data& d = data();
  for (auto _ : state)
    for (const auto& s : d.sets) benchmark::DoNotOptimize(ptc::bounding_sphere(method, s));
  double err_sum = 0.0, err_max = 0.0;
  std::size_t points = 0, not_containing = 0;
  for (std::size_t i = 0; i < d.sets.size(); ++i) {
    const ptc::Sphere s = ptc::bounding_sphere(method, d.sets[i]);
    const double err = (s.radius - d.exact[i]) / d.exact[i];
    err_sum += err;
    err_max = std::max(err_max, std::abs(err));
    points += d.sets[i].size();
    const double tol = method == ptc::SphereMethod::Exact ? ptc::exact_containment_tol(s, d.sets[i])
                                                          : ptc::kSphereContainmentTol;
    not_containing += !ptc::contains_all(s, d.sets[i], tol);
  }
  const auto n = static_cast<double>(d.sets.size());
  state.counters["s_per_sphere"] =
      benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["sets"] = n;
  state.counters["points_mean"] = static_cast<double>(points) / n;
  state.counters["rel_err_mean"] = err_sum / n;
  state.counters["rel_err_max"] = err_max;
  state.counters["not_containing"] = static_cast<double>(not_containing);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);  // takes Google Benchmark's own flags (--help lists them)
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.empty() || a[0] == '-' || i > 1) {
      std::cerr << "spheres_bench: " << a << ": " << (i > 1 ? "one mesh at most" : "unknown option")
                << " (usage: spheres_bench [MESH] [Google Benchmark flags, e.g. --benchmark_filter=REGEX])\n";
      return 2;
    }
    g_mesh = a;
  }
  try {
    (void)data();
  } catch (const std::exception& e) {
    std::cerr << "spheres_bench: " << e.what() << "\n";
    return 1;
  }
  for (ptc::SphereMethod m : ptc::kAllSphereMethods)
    benchmark::RegisterBenchmark(("BM_Sphere/" + std::string(ptc::to_string(m))).c_str(), BM_Sphere, m)
        ->Unit(benchmark::kMillisecond);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
