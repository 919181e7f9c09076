// Side-by-side: our BVH over triangles and over clusters vs Embree 3, on the same mesh, the same
// trace frame and the same rays, in one process, by default on ONE thread.
//
//   build-bvh/bin/bvh_bench [MESH] [--levels 2] [--reps 7] [--size 1024] [--run 80]
//                           [--leaf 8] [--threads 1] [--ct 1] [--ci 0.3] [--meshopt 50]
//
// MESH (default: armadillo) is subdivided `levels` times (midpoint; 2 -> 832k triangles for
// armadillo). Clusters: Morton-ordered runs of `run` triangles (a stand-in until the clustering
// code is used) and, unless --meshopt 0, meshoptimizer's meshlets made connected
// (toolkit/clustering/meshopt.h, max_count vertices): compact clusters, as the method expects.
// One cluster per leaf, tested linearly (the paper) or through a refitted block tree per
// cluster (see bvh/trace_scene.h). Rays: size x size primary rays of a pinhole camera
// framing the mesh (looking along -z). Every stage is run `reps` times, configurations
// interleaved; the table shows median [min, max] (the machine is noisy: read medians).
// Mismatches: rays whose closest triangle differs from our triangle BVH's (hit vs miss, or
// another triangle at a t differing by more than 1e-5 relative; "ties": another triangle at the
// same t within that tolerance, e.g. through a shared edge).
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "bvh/camera.h"
#include "bvh/embree_peer.h"
#include "bvh/morton_runs.h"
#include "bvh/trace_scene.h"
#include "bvh/tracer.h"
#include "toolkit/clustering/meshopt.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"

namespace {

using namespace ptc;
using namespace ptc::bvh;
using Clock = std::chrono::steady_clock;

struct Stat {
  double median = 0, min = 0, max = 0;
};
Stat stat_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return {n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]), v.front(), v.back()};
}
double time_ms(const std::function<void()>& f) {
  const auto t0 = Clock::now();
  f();
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
void row(const std::string& config, const std::string& what, const std::vector<double>& v) {
  const Stat s = stat_of(v);
  std::printf("%-30s %-28s %9.2f ms   [%.2f, %.2f]\n", config.c_str(), what.c_str(), s.median, s.min, s.max);
}

struct Mismatch {
  std::size_t hit_miss = 0, other_triangle = 0, ties = 0;
};
Mismatch compare(const HitBatch& ref, const HitBatch& got) {
  Mismatch m;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const bool a = ref.triangle[i] != kNoTriangle, b = got.triangle[i] != kNoTriangle;
    if (a != b) {
      ++m.hit_miss;
    } else if (a && ref.triangle[i] != got.triangle[i]) {
      if (std::abs(ref.t[i] - got.t[i]) <= 1e-5f * std::abs(ref.t[i])) ++m.ties;
      else ++m.other_triangle;
    }
  }
  return m;
}

// One configuration: how to update it for a frame, how to trace, and its per-stage times.
struct Config {
  std::string name;
  std::function<void()> update;
  std::function<TraceTotals(HitBatch&)> trace;
  std::function<std::vector<std::pair<std::string, double>>()> stages;
  std::map<std::string, std::vector<double>> times;
  std::vector<double> trace_ms;
  TraceTotals totals;
  Mismatch mismatch;
};

}  // namespace

int main(int argc, char** argv) {
  std::string mesh_path = std::string(PTC_TEST_DATA) + "/meshes/armadillo.off";
  int levels = 2, reps = 7, size = 1024;
  unsigned run = 80, threads = 1, meshopt_count = 50;
  SceneConfig tcfg = triangle_scene_defaults(), ccfg = cluster_scene_defaults();
  for (int i = 1; i < argc; ++i) {
    auto value = [&](const char* what) {
      if (i + 1 >= argc) {
        std::cerr << "bvh_bench: " << what << " needs a value\n";
        std::exit(2);
      }
      return std::atof(argv[++i]);
    };
    if (!std::strcmp(argv[i], "--levels")) levels = static_cast<int>(value("--levels"));
    else if (!std::strcmp(argv[i], "--reps")) reps = static_cast<int>(value("--reps"));
    else if (!std::strcmp(argv[i], "--size")) size = static_cast<int>(value("--size"));
    else if (!std::strcmp(argv[i], "--run")) run = static_cast<unsigned>(value("--run"));
    else if (!std::strcmp(argv[i], "--leaf")) tcfg.build.max_leaf_size = static_cast<unsigned>(value("--leaf"));
    else if (!std::strcmp(argv[i], "--threads")) threads = static_cast<unsigned>(value("--threads"));
    else if (!std::strcmp(argv[i], "--meshopt")) meshopt_count = static_cast<unsigned>(value("--meshopt"));
    else if (!std::strcmp(argv[i], "--ci")) tcfg.build.cost.intersection = ccfg.build.cost.intersection = value("--ci");
    else if (!std::strcmp(argv[i], "--ct")) tcfg.build.cost.traversal = ccfg.build.cost.traversal = value("--ct");
    else if (argv[i][0] != '-') mesh_path = argv[i];
    else {
      std::cerr << "bvh_bench: unknown option " << argv[i] << "\n";
      return 2;
    }
  }
  if (reps < 1 || size < 1 || run < 1 || threads < 1 || tcfg.build.max_leaf_size < 1) {
    std::cerr << "bvh_bench: counts must be >= 1\n";
    return 2;
  }
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);

  Mesh mesh;
  try {
    mesh = read_mesh(mesh_path).mesh;
  } catch (const std::exception& e) {
    std::cerr << "bvh_bench: " << e.what() << "\n";
    return 1;
  }
  if (levels > 0) mesh = subdivide(mesh, SubdivisionScheme::Midpoint, levels);
  const MortonRuns runs = morton_runs(mesh, run);
  Clustering meshlets;
  if (meshopt_count) {
    ClusterConfig mc;
    mc.max_count = meshopt_count;
    meshlets = meshopt_clusters(mesh, mc);
  }
  const Vec3 origin = mesh.bounds().center();
  tcfg.origin = ccfg.origin = origin;
  const RayBatch rays = primary_rays(frame_box(mesh.bounds()), size, size);
  std::printf("mesh %s, %d subdivision levels: %zu triangles, %zu vertices; %zu clusters (Morton runs of %u), "
              "%zu meshopt clusters (max %u vertices); "
              "%zu rays; %u thread(s); %d reps; SAH traversal %.2f intersection %.2f, triangle leaves <= %u\n\n",
              mesh_path.c_str(), levels, mesh.triangle_count(), mesh.vertex_count(), runs.cluster_count(), run,
              meshlets.cluster_count(), meshopt_count,
              rays.size(), threads, reps, tcfg.build.cost.traversal, tcfg.build.cost.intersection,
              tcfg.build.max_leaf_size);
  const auto pos = mesh.positions();
  TraceOptions opt;
  opt.threads = threads;

  std::vector<std::unique_ptr<Config>> configs;
  auto ts = std::make_shared<TriangleScene>(mesh, tcfg);
  auto scene_stages = [](const StageTimes& t) {
    return std::vector<std::pair<std::string, double>>{
        {"1 vertices to frame", t.vertices_ms}, {"2 boxes", t.boxes_ms},         {"3 SAH build", t.build_ms},
        {"4 collapse+link", t.collapse_ms},      {"5 leaf data", t.leaf_data_ms}, {"6 block-tree refit", t.refit_ms},
        {"= boxes+build (2+3)", t.boxes_ms + t.build_ms},
        {"= per-frame total", t.total_ms()}};
  };
  configs.push_back(std::make_unique<Config>(Config{
      "ours_triangles", [=] { ts->update(pos); }, [=, &rays](HitBatch& h) { return trace(ts->data(), rays, h, opt); },
      [=] { return scene_stages(ts->times()); }, {}, {}, {}, {}}));
  std::vector<std::pair<std::string, ClusterView>> clusterings{{"morton" + std::to_string(run), runs.view()}};
  if (meshopt_count) clusterings.push_back({"meshopt" + std::to_string(meshopt_count), view_of(meshlets)});
  for (const auto& [cname, view] : clusterings)
    for (ClusterLeaf mode : {ClusterLeaf::Linear, ClusterLeaf::BlockTree}) {
      SceneConfig c = ccfg;
      c.cluster_leaf = mode;
      auto cs = std::make_shared<ClusterScene>(mesh, view, c);
      configs.push_back(std::make_unique<Config>(Config{
          "ours_" + cname + "_" + to_string(mode), [=] { cs->update(pos); },
          [=, &rays](HitBatch& h) { return trace(cs->data(), rays, h, opt); },
          [=] { return scene_stages(cs->times()); }, {}, {}, {}, {}}));
    }
  struct EmbreeRun {
    EmbreeMode mode;
    std::string isa;
  };
  for (const EmbreeRun& er : {EmbreeRun{EmbreeMode::StaticMedium, ""}, EmbreeRun{EmbreeMode::DynamicLow, ""},
                              EmbreeRun{EmbreeMode::DynamicRefit, ""}, EmbreeRun{EmbreeMode::StaticMedium, "sse2"}}) {
    const EmbreeMode mode = er.mode;
    const std::string ename = std::string(to_string(mode)) + (er.isa.empty() ? "" : "_" + er.isa);
    auto es = std::make_shared<EmbreeScene>(mesh, origin, EmbreeConfig{mode, threads, er.isa});
    if (mode == EmbreeMode::DynamicRefit)
      std::printf("%-30s %-28s %9.2f ms   (first commit, once)\n", to_string(mode), "build", es->last_commit_ms());
    configs.push_back(std::make_unique<Config>(Config{
        ename, [=] { es->update(pos); },
        [=, &rays](HitBatch& h) { return es->trace(rays, h, HitMode::Closest, threads); },
        [=] {
          return std::vector<std::pair<std::string, double>>{
              {"1 vertices to frame", es->last_vertex_ms()},
              {mode == EmbreeMode::DynamicRefit ? "3 refit commit" : "3 build commit", es->last_commit_ms()},
              {"= per-frame total", es->last_vertex_ms() + es->last_commit_ms()}};
        },
        {}, {}, {}, {}}));
  }

  // Interleaved repetitions: per-frame update, then trace.
  HitBatch ref, hits;
  for (int r = 0; r < reps; ++r)
    for (auto& c : configs) {
      c->update();
      for (const auto& [k, v] : c->stages()) c->times[k].push_back(v);
      HitBatch& h = c.get() == configs[0].get() ? ref : hits;
      c->trace_ms.push_back(time_ms([&] { c->totals = c->trace(h); }));
      if (c.get() != configs[0].get() && r == 0) c->mismatch = compare(ref, hits);
    }

  for (auto& c : configs) {
    for (const auto& [k, v] : c->times) row(c->name, k, v);
    std::printf("\n");
  }
  const double ours = stat_of(configs[0]->trace_ms).median;
  for (auto& c : configs) {
    std::vector<double> mr;
    for (double m : c->trace_ms) mr.push_back(static_cast<double>(rays.size()) / (m * 1e3));
    const Stat s = stat_of(mr);
    std::printf("%-30s trace closest %7.2f Mrays/s [%.2f, %.2f]  %.2fx ours_triangles", c->name.c_str(), s.median,
                s.min, s.max, ours / stat_of(c->trace_ms).median);
    if (c->totals.nodes_visited)
      std::printf("  nodes/ray %.2f tris/ray %.2f", double(c->totals.nodes_visited) / double(rays.size()),
                  double(c->totals.triangles_tested) / double(rays.size()));
    std::printf("  hits %llu", (unsigned long long)c->totals.hits);
    if (c.get() != configs[0].get())
      std::printf("  mismatches: hit/miss %zu, other triangle %zu, ties %zu", c->mismatch.hit_miss,
                  c->mismatch.other_triangle, c->mismatch.ties);
    std::printf("\n");
  }
  return 0;
}
