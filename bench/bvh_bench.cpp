// Side-by-side: our BVH over triangles and over clusters vs Embree 3, on the same mesh, the same
// trace frame and the same rays, in one process, by default on ONE thread.
//
//   build/bin/bvh_bench [MESH] [--levels 2] [--reps 5] [--size 1024] [--threads 1]
//                       [--clusters acc,meshopt] [--max-count 50] [--max-size 50]
//                       [--leaves linear,block-tree] [--leaf 8] [--ct 1] [--ci 0.3]
//                       [--isa auto|sse2|avx2] [--embree all|none] [--amplitude 0.01]
//                       [--clock wall|cpu] [--out DIR] [--build-loop N] [--median 4]
//                       [--vertex-order clusters|input] [--groups 8]
//
// MESH (default: armadillo) is subdivided `levels` times (midpoint; 2 -> 832k triangles for
// armadillo). Clusterings (comma list, made once from the rest pose):
//   acc      cluster_mesh(Growth, Acc, MaxCount = --max-count, MaxSize = --max-size): the method's
//   meshopt  meshoptimizer's meshlets made connected (max_count vertices), a modern baseline;
//   morton   Morton-ordered runs of 80 triangles (a spatial stand-in, not connected).
// --vertex-order clusters (default): after the first acc/meshopt clustering the mesh's vertices
// are renumbered once with cluster_vertex_order (every configuration then sees that mesh), so its
// cluster scene converts positions and computes boxes in one pass (stage 2; stage 1 is 0);
// input keeps the file's order and the cluster scenes gather (stage 1) before the boxes.
// Each clustering is traced with one cluster per leaf, tested linearly (the paper) or through a
// refitted block tree per cluster (see bvh/cluster_scene.h).
// Frames: repetition r animates the rest pose by a smooth non-rigid deformation of amplitude
// --amplitude * r (of the bounding box size), so Embree's refit and our rebuilds see real motion.
// Every configuration updates to frame r, then traces the same size x size primary rays
// (pinhole camera framing the rest pose, looking along -z); configurations are interleaved
// within a frame. Tables: median [min, max] over frames (the machine is noisy: read medians).
// Ratios: per-frame update times against each Embree mode's commit (build / refit), trace speed
// against each Embree mode's rtcIntersect1, measured in the same run.
// Mismatches (every frame, summed): rays whose closest triangle differs from our triangle BVH's
// (hit vs miss, or another triangle at a t differing by more than 1e-5 relative; "ties": another
// triangle at the same t within that tolerance, e.g. through a shared edge).
// --clock cpu times every stage, commit and trace with the calling thread's CPU time instead of
// the wall clock (bvh/stage_clock.h; one thread only): on a machine shared with other jobs the
// wall clock charges their time slices to whichever configuration was running.
// --groups N: SceneConfig::cluster_group_size of the cluster scenes (two-level build over fixed
// groups of at most N clusters; 0 = the plain build; default: cluster_scene_defaults()).
// --median N: BuildConfig::median_split_below of the cluster BVHs (default: cluster_scene_defaults()).
// --build-loop N: only the cluster build, N times over the first clustering's rest-pose boxes
// (median, and the tree's SAH cost), then exit; a target for perf (use with --embree none).
// --out DIR writes DIR/bvh_bench.csv (one row per frame and configuration) and
// DIR/manifest.json (analysis/schema/manifest.h).
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
#include <sstream>
#include <string>
#include <vector>

#include "analysis/schema/csv.h"
#include "analysis/schema/manifest.h"
#include "commands/output_dir.h"
#include "bvh/camera.h"
#include "bvh/embree_peer.h"
#include "toolkit/clustering/morton_runs.h"
#include "bvh/trace_scene.h"
#include "bvh/tracer.h"
#include "bvh/vertex_order.h"
#include "toolkit/clustering/cluster.h"
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
  if (v.empty()) return {};
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return {n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]), v.front(), v.back()};
}
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }
void row(const std::string& config, const std::string& what, const std::vector<double>& v) {
  const Stat s = stat_of(v);
  std::printf("%-30s %-28s %9.2f ms   [%.2f, %.2f]\n", config.c_str(), what.c_str(), s.median, s.min, s.max);
}

struct Mismatch {
  std::size_t hit_miss = 0, other_triangle = 0, ties = 0;
  void add(const HitBatch& ref, const HitBatch& got) {
    for (std::size_t i = 0; i < ref.size(); ++i) {
      const bool a = ref.triangle[i] != kNoTriangle, b = got.triangle[i] != kNoTriangle;
      if (a != b) {
        ++hit_miss;
      } else if (a && ref.triangle[i] != got.triangle[i]) {
        if (std::abs(ref.t[i] - got.t[i]) <= 1e-5f * std::abs(ref.t[i])) ++ties;
        else ++other_triangle;
      }
    }
  }
};

// One configuration: how to update it for a frame, how to trace, and its per-stage times.
struct Config {
  std::string name;
  bool embree = false;
  EmbreeMode embree_mode{};
  std::function<void(std::span<const Vec3>)> update;
  std::function<TraceTotals(HitBatch&)> trace;
  std::function<std::vector<std::pair<std::string, double>>()> stages;
  std::function<double()> sah;  // SAH cost of the last build (ours only)
  std::map<std::string, std::vector<double>> times;
  std::vector<double> trace_ms, box_build_ms, total_ms;
  std::vector<TraceTotals> totals;
  std::vector<Mismatch> mismatch;  // per frame
};

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

// The rest pose deformed by a smooth non-rigid field of amplitude a (relative to the box size).
std::vector<Vec3> frame_positions_at(const Mesh& m, double a) {
  std::vector<Vec3> p(m.positions().begin(), m.positions().end());
  if (a == 0.0) return p;
  const Box3 b = m.bounds();
  const double s = (b.hi - b.lo).maxCoeff();
  for (Vec3& q : p) {
    const Vec3 u = (q - b.lo) / s;
    q += a * s * Vec3(std::sin(3.0 * u.y()), std::sin(3.0 * u.z() + 1.0), std::sin(3.0 * u.x() + 2.0));
  }
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  std::string mesh_path = std::string(PTC_TEST_DATA) + "/meshes/armadillo.off";
  int levels = 2, reps = 5, size = 1024, build_loop = 0;
  unsigned threads = 1, max_count = 50;
  double max_size = 50, amplitude = 0.01;
  std::string vertex_order_arg = "clusters";
  std::string clusters_arg = "acc,meshopt", leaves_arg = "linear,block-tree", isa_arg = "auto", embree_arg = "all",
              clock_arg = "wall", out_dir;
  SceneConfig tcfg = triangle_scene_defaults(), ccfg = cluster_scene_defaults();
  std::vector<std::string> args(argv, argv + argc);
  for (int i = 1; i < argc; ++i) {
    auto text = [&](const char* what) -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "bvh_bench: " << what << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    auto value = [&](const char* what) {
      const std::string t = text(what);
      char* end = nullptr;
      const double v = std::strtod(t.c_str(), &end);
      if (end == t.c_str() || *end != '\0' || !std::isfinite(v)) {
        std::cerr << "bvh_bench: " << what << ": not a number: " << t << "\n";
        std::exit(2);
      }
      return v;
    };
    const std::string a = argv[i];
    if (a == "--levels") levels = static_cast<int>(value("--levels"));
    else if (a == "--reps") reps = static_cast<int>(value("--reps"));
    else if (a == "--build-loop") build_loop = static_cast<int>(value("--build-loop"));
    else if (a == "--size") size = static_cast<int>(value("--size"));
    else if (a == "--leaf") tcfg.build.max_leaf_size = static_cast<unsigned>(value("--leaf"));
    else if (a == "--threads") threads = static_cast<unsigned>(value("--threads"));
    else if (a == "--max-count") max_count = static_cast<unsigned>(value("--max-count"));
    else if (a == "--max-size") max_size = value("--max-size");
    else if (a == "--amplitude") amplitude = value("--amplitude");
    else if (a == "--clusters") clusters_arg = text("--clusters");
    else if (a == "--vertex-order") vertex_order_arg = text("--vertex-order");
    else if (a == "--leaves") leaves_arg = text("--leaves");
    else if (a == "--isa") isa_arg = text("--isa");
    else if (a == "--embree") embree_arg = text("--embree");
    else if (a == "--out") out_dir = text("--out");
    else if (a == "--clock") clock_arg = text("--clock");
    else if (a == "--ci") tcfg.build.cost.intersection = ccfg.build.cost.intersection = value("--ci");
    else if (a == "--groups") ccfg.cluster_group_size = static_cast<unsigned>(value("--groups"));
    else if (a == "--median") ccfg.build.median_split_below = static_cast<unsigned>(value("--median"));
    else if (a == "--ct") tcfg.build.cost.traversal = ccfg.build.cost.traversal = value("--ct");
    else if (a[0] != '-') mesh_path = a;
    else {
      std::cerr << "bvh_bench: unknown option " << a << "\n";
      return 2;
    }
  }
  if (reps < 1 || size < 1 || threads < 1 || tcfg.build.max_leaf_size < 1 || max_count < 1 || levels < 0) {
    std::cerr << "bvh_bench: counts must be >= 1 (levels >= 0)\n";
    return 2;
  }
  TraceIsa isa = TraceIsa::Auto;
  if (isa_arg == "sse2") isa = TraceIsa::Sse2;
  else if (isa_arg == "avx2") isa = TraceIsa::Avx2;
  else if (isa_arg != "auto") {
    std::cerr << "bvh_bench: --isa must be auto, sse2 or avx2\n";
    return 2;
  }
  if (embree_arg != "all" && embree_arg != "none") {
    std::cerr << "bvh_bench: --embree must be all or none\n";
    return 2;
  }
  if (!parse_vertex_order(vertex_order_arg)) {
    std::cerr << "bvh_bench: --vertex-order must be clusters or input\n";
    return 2;
  }
  if (clock_arg != "wall" && clock_arg != "cpu") {
    std::cerr << "bvh_bench: --clock must be wall or cpu\n";
    return 2;
  }
  const StageClock clock = clock_arg == "cpu" ? StageClock::ThreadCpu : StageClock::Wall;
  if (clock == StageClock::ThreadCpu && threads != 1) {
    std::cerr << "bvh_bench: --clock cpu needs --threads 1\n";
    return 2;
  }
  tcfg.clock = ccfg.clock = clock;
  std::vector<ClusterLeaf> leaf_modes;
  for (const std::string& l : split_list(leaves_arg)) {
    if (const auto m = parse_cluster_leaf(l)) leaf_modes.push_back(*m);
    else {
      std::cerr << "bvh_bench: --leaves: unknown leaf mode " << l << " (linear, block-tree)\n";
      return 2;
    }
  }
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);

  RunManifest manifest("bvh_bench", args);
  Mesh mesh;
  try {
    mesh = read_mesh(mesh_path).mesh;
    manifest.add_input(mesh_path);
  } catch (const std::exception& e) {
    std::cerr << "bvh_bench: " << e.what() << "\n";
    return 1;
  }
  if (levels > 0) mesh = subdivide(mesh, SubdivisionScheme::Midpoint, levels);

  // Clusterings, made once from the rest pose.
  std::vector<std::pair<std::string, Clustering>> clusterings;
  std::unique_ptr<Clustering> runs;
  std::vector<std::pair<std::string, ClusterView>> views;
  bool renumbered = false, want_morton = false;
  for (const std::string& c : split_list(clusters_arg)) {
    const auto t0 = Clock::now();
    if (c == "acc") {
      ClusterConfig cc;
      cc.method = ClusterMethod::Growth;
      cc.objective = ObjectiveKind::Acc;
      cc.max_count = max_count;
      cc.max_size = max_size;
      clusterings.push_back({"acc" + std::to_string(max_count), cluster_mesh(mesh, cc)});
    } else if (c == "meshopt") {
      ClusterConfig mc;
      mc.max_count = max_count;
      clusterings.push_back({"meshopt" + std::to_string(max_count), meshopt_clusters(mesh, mc)});
    } else if (c == "morton") {
      want_morton = true;  // made after the loop, on the final (possibly renumbered) mesh
      continue;
    } else {
      std::cerr << "bvh_bench: --clusters: unknown clustering " << c << " (acc, meshopt, morton)\n";
      return 2;
    }
    const double ms = ms_since(t0);
    manifest.add_timing_ms("clustering_" + c, ms);
    std::printf("clustering %-8s %9.0f ms (once, rest pose)\n", c.c_str(), ms);
    // --vertex-order clusters: the mesh renumbered once after the first clustering, so that its
    // clusters own consecutive vertices (the fused conversion + box pass); later clusterings are
    // made on the renumbered mesh (their scenes gather unless their order happens to match).
    if (parse_vertex_order(vertex_order_arg) == VertexOrder::Clusters && clusterings.size() == 1 && !renumbered) {
      const auto t1 = Clock::now();
      Clustering& c0 = clusterings.front().second;
      const std::vector<std::uint32_t> to_old = cluster_vertex_order(mesh, view_of(c0), {}, ccfg);
      mesh = renumber_vertices(mesh, to_old);
      c0 = renumber_vertices(c0, inverse_permutation(to_old));
      renumbered = true;
      std::printf("vertices renumbered in %s's cluster order %9.0f ms (once)\n", clusterings.front().first.c_str(),
                  ms_since(t1));
    }
  }
  if (want_morton) {
    const auto t0 = Clock::now();
    runs = std::make_unique<Clustering>(ptc::morton_runs(mesh, 80));
    manifest.add_timing_ms("clustering_morton", ms_since(t0));
  }
  for (const auto& [name, cl] : clusterings) views.push_back({name, view_of(cl)});
  if (runs) views.push_back({"morton80", view_of(*runs)});

  const Vec3 origin = mesh.bounds().center();
  tcfg.origin = ccfg.origin = origin;
  const RayBatch rays = primary_rays(frame_box(mesh.bounds()), size, size);
  std::printf("mesh %s, %d subdivision levels: %zu triangles, %zu vertices; %zu rays; %u thread(s); %d frames "
              "(amplitude %.3g per frame); SAH traversal %.2f intersection %.2f, triangle leaves <= %u; "
              "tracer isa %s; %s clock\n",
              mesh_path.c_str(), levels, mesh.triangle_count(), mesh.vertex_count(), rays.size(), threads, reps,
              amplitude, tcfg.build.cost.traversal, tcfg.build.cost.intersection, tcfg.build.max_leaf_size,
              to_string(resolve(isa)), clock_arg.c_str());
  for (const auto& [name, v] : views)
    std::printf("  clustering %s: %zu clusters, mean %.1f triangles\n", name.c_str(), v.triangle_offsets.size() - 1,
                double(mesh.triangle_count()) / double(v.triangle_offsets.size() - 1));
  std::printf("\n");
  TraceOptions opt;
  opt.threads = threads;
  opt.isa = isa;

  std::vector<std::unique_ptr<Config>> configs;
  std::shared_ptr<ClusterScene> first_cluster_scene;
  auto scene_stages = [](const StageTimes& t) {
    return std::vector<std::pair<std::string, double>>{
        {"1 vertices to frame", t.vertices_ms}, {"2 boxes", t.boxes_ms},         {"3 SAH build", t.build_ms},
        {"4 collapse+link", t.collapse_ms},      {"5 leaf data", t.leaf_data_ms}, {"6 block-tree refit", t.refit_ms}};
  };
  auto ts = std::make_shared<TriangleScene>(mesh, tcfg);
  {
    auto c = std::make_unique<Config>();
    c->name = "ours_triangles";
    c->update = [=](std::span<const Vec3> p) { ts->update(p); };
    c->trace = [=, &rays](HitBatch& h) { return trace(ts->data(), rays, h, opt); };
    c->stages = [=] { return scene_stages(ts->times()); };
    c->sah = [=] { return ts->bvh().cost; };
    configs.push_back(std::move(c));
  }
  for (const auto& [cname, view] : views)
    for (ClusterLeaf mode : leaf_modes) {
      SceneConfig sc = ccfg;
      sc.cluster_leaf = mode;
      auto cs = std::make_shared<ClusterScene>(mesh, view, sc);
      if (!first_cluster_scene) first_cluster_scene = cs;
      auto c = std::make_unique<Config>();
      c->name = "ours_" + cname + "_" + to_string(mode);
      c->update = [=](std::span<const Vec3> p) { cs->update(p); };
      c->trace = [=, &rays](HitBatch& h) { return trace(cs->data(), rays, h, opt); };
      c->stages = [=] { return scene_stages(cs->times()); };
      c->sah = [=] { return cs->bvh().cost; };
      configs.push_back(std::move(c));
    }
  if (embree_arg == "all")
    for (const EmbreeMode mode : {EmbreeMode::StaticMedium, EmbreeMode::DynamicLow, EmbreeMode::DynamicRefit}) {
      auto es = std::make_shared<EmbreeScene>(mesh, origin, EmbreeConfig{mode, threads, "", clock});
      if (mode == EmbreeMode::DynamicRefit)
        std::printf("%-30s %-28s %9.2f ms   (first commit, once)\n\n", to_string(mode), "build", es->last_commit_ms());
      auto c = std::make_unique<Config>();
      c->name = to_string(mode);
      c->embree = true;
      c->embree_mode = mode;
      c->update = [=](std::span<const Vec3> p) { es->update(p); };
      c->trace = [=, &rays](HitBatch& h) { return es->trace(rays, h, HitMode::Closest, threads); };
      c->stages = [=] {
        return std::vector<std::pair<std::string, double>>{
            {"1 vertices to frame", es->last_vertex_ms()},
            {mode == EmbreeMode::DynamicRefit ? "3 refit commit" : "3 build commit", es->last_commit_ms()}};
      };
      configs.push_back(std::move(c));
    }

  // --build-loop N: the binned SAH build alone, N times over the first cluster scene's rest-pose
  // boxes (centroids = box centres, as in the scene), then exit: a profiling target.
  if (build_loop > 0) {
    if (!first_cluster_scene) {
      std::cerr << "bvh_bench: --build-loop needs a clustering\n";
      return 2;
    }
    const std::vector<Box3f>& boxes = first_cluster_scene->boxes();
    const std::vector<Vec3f> centers = box_centers(boxes);
    const std::vector<std::uint32_t>& groups = first_cluster_scene->group_offsets();  // the scene's own groups
    Bvh b;
    BuildWorkspace ws;
    std::vector<double> ms;
    for (int i = 0; i < build_loop; ++i) {
      const double t0 = clock_ms(clock);
      build_binned_sah({boxes, centers, first_cluster_scene->weights(), groups}, ccfg.build, b, ws);
      ms.push_back(clock_ms(clock) - t0);
    }
    row("build loop " + std::to_string(boxes.size()) + " clusters", "3 SAH build", ms);
    // The box stage alone on the same clustering (rest pose).
    std::vector<Vec3f> fp;
    frame_positions(mesh.positions(), origin, fp);
    std::vector<Box3f> bx;
    std::vector<Vec3f> cx;
    ms.clear();
    for (int i = 0; i < build_loop; ++i) {
      frame_positions(mesh.positions(), origin, fp);  // as in the scene: fresh positions first
      const double t0 = clock_ms(clock);
      point_group_boxes(fp, views.front().second.vertex_offsets, views.front().second.vertices, bx, cx);
      ms.push_back(clock_ms(clock) - t0);
    }
    row("build loop " + std::to_string(boxes.size()) + " clusters", "2 boxes", ms);
    // The same with the vertices renumbered in first-touch order (as ClusterScene does).
    const GroupVertexOrder vo = first_touch_order(mesh.vertex_count(), views.front().second.vertex_offsets,
                                                  views.front().second.vertices);
    std::vector<double> ms_conv;
    ms.clear();
    for (int i = 0; i < build_loop; ++i) {
      double t0 = clock_ms(clock);
      frame_positions(mesh.positions(), vo.to_old, origin, fp);
      ms_conv.push_back(clock_ms(clock) - t0);
      t0 = clock_ms(clock);
      point_group_boxes(fp, vo, bx, cx);
      ms.push_back(clock_ms(clock) - t0);
    }
    row("build loop " + std::to_string(boxes.size()) + " clusters", "1 vertices (first-touch)", ms_conv);
    row("build loop " + std::to_string(boxes.size()) + " clusters", "2 boxes (first-touch)", ms);
    // The fused pass on the mesh renumbered once in that order (ClusterScene::fused_vertex_pass).
    {
      const Mesh rm = renumber_vertices(mesh, vo.to_old);
      const ClusterView& v0 = views.front().second;
      std::vector<std::uint32_t> rv(v0.vertices.size());
      for (std::size_t k = 0; k < rv.size(); ++k) rv[k] = vo.to_new[v0.vertices[k]];
      const auto fused_runs = group_runs(first_touch_order(rm.vertex_count(), v0.vertex_offsets, rv));
      if (!fused_runs) {
        std::fprintf(stderr, "bvh_bench: renumbered mesh has no runs\n");
        return 1;
      }
      std::vector<Vec3f> fpr(rm.vertex_count() + 2);
      ms.clear();
      for (int i = 0; i < build_loop; ++i) {
        const double t0 = clock_ms(clock);
        frame_positions_and_boxes(rm.positions(), origin, *fused_runs, fpr, bx, cx);
        ms.push_back(clock_ms(clock) - t0);
      }
      row("build loop " + std::to_string(boxes.size()) + " clusters", "1+2 fused (renumbered mesh)", ms);
    }
    std::printf("first-touch order: %zu shared of %zu listed vertices\n", vo.shared.size(),
                views.front().second.vertices.size());
    std::printf("SAH cost %.6f, %zu nodes\n", b.cost, b.nodes.size());
    return 0;
  }

  // Frames: every configuration updates to frame r, then traces; mismatches against the first.
  HitBatch ref, hits;
  for (int r = 0; r < reps; ++r) {
    const std::vector<Vec3> pos = frame_positions_at(mesh, amplitude * r);
    std::vector<Vec3> fresh(pos.size());
    for (auto& c : configs) {
      // Every configuration reads positions just written (as right after an animation step),
      // not whatever the configurations before it left in the caches (untimed copy).
      std::copy(pos.begin(), pos.end(), fresh.begin());
      c->update(fresh);
      double box_build = 0, total = 0;
      for (const auto& [k, v] : c->stages()) {
        c->times[k].push_back(v);
        total += v;
        if (k == "2 boxes" || k == "3 SAH build" || k.find("commit") != std::string::npos) box_build += v;
      }
      c->box_build_ms.push_back(box_build);
      c->total_ms.push_back(total);
      const bool first = c.get() == configs[0].get();
      HitBatch& h = first ? ref : hits;
      const double t0 = clock_ms(clock);
      c->totals.push_back(c->trace(h));
      c->trace_ms.push_back(clock_ms(clock) - t0);
      c->mismatch.emplace_back();
      if (!first) c->mismatch.back().add(ref, hits);
    }
  }

  for (auto& c : configs) {
    for (const auto& [k, v] : c->times) row(c->name, k, v);
    row(c->name, c->embree ? "= commit (build or refit)" : "= boxes+build (2+3)", c->box_build_ms);
    row(c->name, "= per-frame total", c->total_ms);
    std::printf("\n");
  }
  // Peers for the ratios.
  std::map<std::string, double> embree_update, embree_trace;
  for (auto& c : configs)
    if (c->embree) {
      embree_update[to_string(c->embree_mode)] = stat_of(c->box_build_ms).median;
      embree_trace[to_string(c->embree_mode)] = stat_of(c->trace_ms).median;
    }
  const double ours = stat_of(configs[0]->trace_ms).median;
  std::printf("%-30s %-13s %8s %8s | %-22s %-22s | %-30s\n", "configuration", "update", "box+bld", "total",
              "x faster than REFIT", "x faster than LOW", "trace speed vs rtcIntersect1");
  std::printf("%-30s %-13s %8s %8s | %-22s %-22s | %-30s\n", "", "", "ms", "ms", "box+bld  total", "box+bld  total",
              "MEDIUM  LOW  REFIT");
  for (auto& c : configs) {
    const double bb = stat_of(c->box_build_ms).median, tot = stat_of(c->total_ms).median,
                 tr = stat_of(c->trace_ms).median;
    std::printf("%-30s %-13s %8.2f %8.2f |", c->name.c_str(), c->embree ? "commit" : "ours", bb, tot);
    const char* peers[2] = {"embree_dynamic_refit", "embree_dynamic_low"};
    for (const char* p : peers) {
      if (embree_update.count(p)) std::printf(" %7.1fx %7.1fx      |", embree_update[p] / bb, embree_update[p] / tot);
      else std::printf(" %-21s|", " -");
    }
    for (const char* p : {"embree_static_medium", "embree_dynamic_low", "embree_dynamic_refit"}) {
      if (embree_trace.count(p)) std::printf(" %5.2fx", embree_trace[p] / tr);
    }
    std::printf("\n");
  }
  std::printf("\n");
  for (auto& c : configs) {
    std::vector<double> mr;
    for (double m : c->trace_ms) mr.push_back(static_cast<double>(rays.size()) / (m * 1e3));
    const Stat s = stat_of(mr);
    Mismatch mm;
    for (const Mismatch& m : c->mismatch)
      mm.hit_miss += m.hit_miss, mm.other_triangle += m.other_triangle, mm.ties += m.ties;
    const TraceTotals& t = c->totals.back();
    std::printf("%-30s trace closest %7.2f Mrays/s [%.2f, %.2f]  %.2fx ours_triangles", c->name.c_str(), s.median,
                s.min, s.max, ours / stat_of(c->trace_ms).median);
    if (t.nodes_visited)
      std::printf("  nodes/ray %.2f tris/ray %.2f", double(t.nodes_visited) / double(rays.size()),
                  double(t.triangles_tested) / double(rays.size()));
    std::printf("  hits %llu", (unsigned long long)t.hits);
    if (c->sah) std::printf("  SAH %.4f", c->sah());
    if (c.get() != configs[0].get())
      std::printf("  mismatches (all frames): hit/miss %zu, other triangle %zu, ties %zu", mm.hit_miss,
                  mm.other_triangle, mm.ties);
    std::printf("\n");
  }

  if (!out_dir.empty()) {
    try {
      CsvTable csv({"config", "frame", "vertices_ms", "boxes_ms", "build_ms", "collapse_ms", "leaf_data_ms",
                    "refit_ms", "box_build_ms", "update_ms", "trace_ms", "mrays_per_s", "rays", "hits",
                    "nodes_visited", "triangles_tested", "mismatch_hit_miss", "mismatch_other_triangle",
                    "mismatch_ties"});
      for (auto& c : configs)
        for (int r = 0; r < reps; ++r) {
          auto at = [&](const char* k) {
            for (const auto& [key, v] : c->times)
              if (key.find(k) != std::string::npos) return v[r];
            return 0.0;
          };
          const TraceTotals& t = c->totals[r];
          const Mismatch& m = c->mismatch[r];
          csv.add_row({c->name, std::int64_t(r), at("vertices"), at("boxes"),
                       c->embree ? at("commit") : at("SAH build"), at("collapse"), at("leaf data"), at("block-tree"),
                       c->box_build_ms[r], c->total_ms[r], c->trace_ms[r],
                       static_cast<double>(rays.size()) / (c->trace_ms[r] * 1e3), std::uint64_t(t.rays),
                       std::uint64_t(t.hits), std::uint64_t(t.nodes_visited), std::uint64_t(t.triangles_tested),
                       std::uint64_t(m.hit_miss), std::uint64_t(m.other_triangle), std::uint64_t(m.ties)});
        }
      manifest.set_parameter("levels", levels);
      manifest.set_parameter("frames", reps);
      manifest.set_parameter("size", size);
      manifest.set_parameter("threads", threads);
      manifest.set_parameter("clusters", clusters_arg);
      manifest.set_parameter("max_count", max_count);
      manifest.set_parameter("max_size", max_size);
      manifest.set_parameter("leaves", leaves_arg);
      manifest.set_parameter("amplitude", amplitude);
      manifest.set_parameter("isa", to_string(resolve(isa)));
      manifest.set_parameter("clock", clock_arg);
      manifest.set_parameter("sah_traversal", tcfg.build.cost.traversal);
      manifest.set_parameter("sah_intersection", tcfg.build.cost.intersection);
      manifest.set_parameter("triangle_leaf", tcfg.build.max_leaf_size);
      manifest.set_result("triangles", mesh.triangle_count());
      manifest.set_result("rays", rays.size());
      OutputDir dir(out_dir);
      dir.write("bvh_bench.csv", csv.str());
      manifest.add_output("bvh_bench.csv");
      manifest.add_output("manifest.json");
      dir.write("manifest.json", dump_json(manifest.to_json()));
      dir.commit();
      std::printf("\nwrote %s/{bvh_bench.csv,manifest.json}\n", out_dir.c_str());
    } catch (const std::exception& e) {
      std::cerr << "bvh_bench: " << e.what() << "\n";
      return 1;
    }
  }
  return 0;
}
