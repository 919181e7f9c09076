// Side-by-side: our BVH over triangles and over clusters vs Embree 3, on the same mesh, the same
// trace frame and the same rays, in one process, by default on ONE thread.
//
//   build/bin/bvh_bench [MESH] [--levels 2] [--reps 5] [--size 1024] [--threads 1]
//                       [--clusters acc,meshopt] [--max-count 50] [--max-size 50]
//                       [--leaves linear,block-tree] [--leaf-formats blocks,tables] [--leaf 8] [--ct 1] [--ci 0.3]
//                       [--isa auto|sse2|avx2|avx512vl|avx512] [--embree all|none] [--deform twist] [--amplitude A]
//                       [--clock wall|cpu] [--out DIR] [--build-loop N] [--update-loop N] [--median 4]
//                       [--vertex-order clusters|input] [--groups 8] [--packets] [--no-counters]
//
// MESH (default: armadillo) is subdivided `levels` times (midpoint; 2 -> 832k triangles for
// armadillo). Clusterings (comma list, made once from the rest pose):
//   acc      cluster_mesh(Growth, Acc, MaxCount = --max-count, MaxSize = --max-size): the method's
//   meshopt  meshoptimizer's meshlets made connected (max_count vertices), a modern baseline;
//   morton   Morton-ordered runs of 80 triangles (a spatial stand-in, not connected).
// --vertex-order clusters (default): after the first acc/meshopt clustering the mesh's vertices
// are renumbered once with cluster_vertex_order (every configuration then sees that mesh; later
// clusterings are made on it), so its cluster scene converts positions and computes boxes in one
// pass (stage 2; stage 1 is 0); input keeps the file's order and the cluster scenes gather
// (stage 1) before the boxes. Each clustering is traced with one cluster per leaf, tested
// linearly (the paper) or through a refitted block tree per cluster (bvh/cluster_scene.h).
// --leaf-formats blocks,tables: the linear leaves' formats (bvh::LeafFormat; default blocks),
// each its own configuration (ours_NAME_linear for blocks, ours_NAME_tables).
//
// Motion: frames 0 .. reps-1 of a deformer of the rest pose (toolkit/anim/deformers.h, as the
// one part of a Scene): --deform twist (default), bend, wave or rigid with deform_preset's
// parameters, the motion of `ptc bench` and peer_bench (twist: about y, the ends turning by
// pi/2 sin(2 pi f / 60) radians at frame f); --amplitude replaces the preset's amplitude, in the
// deformer's unit (twist, bend: radians; wave: fraction of the box diagonal; rigid: turns per
// period). Twist, bend and rigid leave frame 0 at the rest pose. (Before the port: a private
// sine field of 0.01 r box sizes at frame r.) Not explode: its rest mesh is a triangle soup,
// which clusterings of the input mesh do not index.
//
// Loop: the configurations are analysis/loop/accel.h's (ours_triangles, one ours_clusters per
// clustering and leaf mode, embree_medium / embree_low / embree_refit), run by the one frame loop
// (analysis/loop/frame_loop.h): per frame the positions are made once (untimed by the
// configurations), each configuration updates from a fresh copy, then traces the same size x size
// primary rays (pinhole camera framing the rest pose, looking along -z), interleaved within the
// frame. --clock cpu, --leaf, --ct, --ci and --median reach the configurations through
// loop::AccelSetup (its stage clock and builder settings).
// Tables: median [min, max] over frames (the machine is noisy: read medians). Ratios: per-frame
// update times against each Embree mode's commit (build / refit), trace speed against each Embree
// mode's rtcIntersect1, measured in the same run. Mismatches (every frame, summed): rays whose
// closest triangle differs from our triangle BVH's (analysis/metrics/hit_agreement.h, default
// tie rule: "ties" are other triangles at a t within 1e-5 relative, e.g. through a shared edge).
// --clock cpu times every stage, commit and trace with the calling thread's CPU time instead of
// the wall clock (bvh/stage_clock.h; one thread only): on a machine shared with other jobs the
// wall clock charges their time slices to whichever configuration was running.
// --groups N: SceneConfig::cluster_group_size of the cluster scenes (two-level build over fixed
// groups of at most N clusters; 0 = the plain build; default: cluster_scene_defaults()).
// --group-trees rebuild|refit: SceneConfig::group_trees (default: cluster_scene_defaults()).
// --median N: BuildConfig::median_split_below of the cluster BVHs (default: cluster_scene_defaults()).
// --update-loop N: only the first cluster configuration's update, N times over frames 1 ..
// reps - 1 (positions made once), and exit: the median per stage; a target for perf.
// --build-loop N: only the cluster build, N times over the first clustering's rest-pose boxes
// (median, and the tree's SAH cost; the two-level build as --group-trees rebuild runs it, whatever
// --group-trees says), then the box passes alone, and exit; a target for perf (use
// with --embree none). It stays outside the frame loop: it times the builder and the box passes
// in isolation, with no frames, update() or trace, which whole per-frame updates cannot give.
// --packets: the rays traced in packets of eight (TraceOptions::packets; Embree's rtcIntersect of
// its packet width, coherent) instead of one by one, still interleaved within each frame: the
// in-process ratio of two leaf formats' packet walks (--leaf-formats blocks,tables).
// --no-counters: no per-ray node and triangle counts (TraceOptions::counters off, as `ptc bench`
// traces); the tables then print 0 nodes and triangles a ray.
// --out DIR writes DIR/bvh_bench.csv (schema ptc-bvh-bench/2, columns in visit_row: one row per
// frame and configuration) and DIR/manifest.json (analysis/schema/manifest.h).
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <ranges>
#include <string>
#include <vector>

#include "analysis/loop/frame_loop.h"
#include "analysis/metrics/hit_agreement.h"
#include "analysis/schema/manifest.h"
#include "analysis/schema/table.h"
#include "bvh/camera.h"
#include "bvh/embree_peer.h"
#include "bvh/vertex_order.h"
#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/meshopt.h"
#include "toolkit/clustering/morton_runs.h"
#include "toolkit/core/stats.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"
#include "toolkit/core/strings.h"

namespace {

using namespace ptc;
using namespace ptc::bvh;
using loop::AccelKind;

[[noreturn]] void usage(const std::string& msg) {
  std::cerr << "bvh_bench: " << msg << "\n";
  std::exit(2);
}

void row(const std::string& config, const std::string& what, const std::vector<double>& v) {
  const Summary s = summarize(v);
  std::printf("%-30s %-28s %9.2f ms   [%.2f, %.2f]\n", config.c_str(), what.c_str(), s.p50, s.min, s.max);
}

struct Options {
  std::string mesh_path = std::string(PTC_TEST_DATA) + "/meshes/armadillo.off";
  int levels = 2, reps = 5, size = 1024, build_loop = 0, update_loop = 0;
  unsigned threads = 1, max_count = 50;
  double max_size = 50;
  DeformParams deform = deform_preset(DeformKind::Twist);
  std::vector<std::string> clusterings{"acc", "meshopt"};
  std::vector<ClusterLeaf> leaves{ClusterLeaf::Linear, ClusterLeaf::BlockTree};
  std::vector<bvh::LeafFormat> formats{bvh::LeafFormat::Blocks};  // of the linear leaves
  VertexOrder vertex_order = VertexOrder::Clusters;
  TraceIsa isa = TraceIsa::Auto;
  bool embree = true;
  bool packets = false, counters = true;
  StageClock clock = StageClock::Wall;
  std::string out_dir;
  SceneConfig tcfg = triangle_scene_defaults(), ccfg = cluster_scene_defaults();
};

// Comma list -> values; usage error naming the flag for an unknown item.
template <class T, class Parse>
std::vector<T> parse_list(const std::string& text, const char* flag, const char* choices, Parse parse) {
  std::vector<T> out;
  for (const std::string& item : split_list(text)) {
    const std::optional<T> v = parse(item);
    if (!v) usage(std::string(flag) + ": unknown value " + item + " (" + choices + ")");
    out.push_back(*v);
  }
  return out;
}

Options parse_options(int argc, char** argv) {
  Options o;
  std::string clock_arg = "wall";
  DeformKind deform = DeformKind::Twist;
  std::optional<double> amplitude;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto text = [&]() -> std::string {
      if (i + 1 >= argc) usage(a + " needs a value");
      return argv[++i];
    };
    auto value = [&]() {
      const std::string t = text();
      char* end = nullptr;
      const double v = std::strtod(t.c_str(), &end);
      if (end == t.c_str() || *end != '\0' || !std::isfinite(v)) usage(a + ": not a number: " + t);
      return v;
    };
    if (a == "--help" || a == "-h") {
      std::printf(
          "usage: bvh_bench [MESH] [--levels 2] [--reps 5] [--size 1024] [--threads 1] [--clusters acc,meshopt,morton]\n"
          "                 [--max-count 50] [--max-size 50] [--leaves linear,block-tree] [--leaf-formats blocks,tables]\n"
          "                 [--leaf 8] [--ct 1] [--ci 0.3] [--isa auto|sse2|avx2|avx512vl|avx512] [--embree all|none]\n"
          "                 [--deform twist|bend|wave|rigid] [--amplitude A] [--clock wall|cpu] [--out DIR]\n"
          "                 [--build-loop N] [--update-loop N] [--median 4] [--vertex-order clusters|input]\n"
          "                 [--groups 8] [--group-trees rebuild|refit] [--packets] [--no-counters]\n"
          "(what each measures: the comment at the top of bench/bvh_bench.cpp; CSV columns: docs/tables.md)\n");
      std::exit(0);
    }
    if (a == "--levels") o.levels = static_cast<int>(value());
    else if (a == "--reps") o.reps = static_cast<int>(value());
    else if (a == "--build-loop") o.build_loop = static_cast<int>(value());
    else if (a == "--update-loop") o.update_loop = static_cast<int>(value());
    else if (a == "--size") o.size = static_cast<int>(value());
    else if (a == "--leaf") o.tcfg.build.max_leaf_size = static_cast<unsigned>(value());
    else if (a == "--threads") o.threads = static_cast<unsigned>(value());
    else if (a == "--max-count") o.max_count = static_cast<unsigned>(value());
    else if (a == "--max-size") o.max_size = value();
    else if (a == "--amplitude") amplitude = value();
    else if (a == "--deform") {
      const auto k = parse_deform_kind(text());
      if (!k || *k == DeformKind::Explode) usage("--deform must be twist, bend, wave or rigid");
      deform = *k;
    } else if (a == "--clusters") {
      o.clusterings = parse_list<std::string>(text(), "--clusters", "acc, meshopt, morton", [](const std::string& s) {
        return s == "acc" || s == "meshopt" || s == "morton" ? std::optional(s) : std::nullopt;
      });
    } else if (a == "--vertex-order") {
      const auto v = parse_vertex_order(text());
      if (!v) usage("--vertex-order must be clusters or input");
      o.vertex_order = *v;
    } else if (a == "--leaves") {
      o.leaves = parse_list<ClusterLeaf>(text(), "--leaves", "linear, block-tree",
                                         [](const std::string& s) { return parse_cluster_leaf(s); });
    } else if (a == "--leaf-formats") {
      o.formats = parse_list<bvh::LeafFormat>(text(), "--leaf-formats", "blocks, tables",
                                              [](const std::string& s) { return bvh::parse_leaf_format(s); });
    } else if (a == "--isa") {
      const std::string s = text();
      const auto isa = parse_trace_isa(s);
      if (!isa) usage("--isa must be auto, sse2, avx2, avx512vl or avx512");
      o.isa = *isa;
    } else if (a == "--embree") {
      const std::string s = text();
      if (s != "all" && s != "none") usage("--embree must be all or none");
      o.embree = s == "all";
    } else if (a == "--out") o.out_dir = text();
    else if (a == "--packets") o.packets = true;
    else if (a == "--no-counters") o.counters = false;
    else if (a == "--clock") clock_arg = text();
    else if (a == "--ci") o.tcfg.build.cost.intersection = o.ccfg.build.cost.intersection = value();
    else if (a == "--groups") o.ccfg.cluster_group_size = static_cast<unsigned>(value());
    else if (a == "--group-trees") {
      const auto g = bvh::parse_group_trees(text());
      if (!g) usage("--group-trees must be rebuild or refit");
      o.ccfg.group_trees = *g;
    }
    else if (a == "--median") o.ccfg.build.median_split_below = static_cast<unsigned>(value());
    else if (a == "--ct") o.tcfg.build.cost.traversal = o.ccfg.build.cost.traversal = value();
    else if (a[0] != '-') o.mesh_path = a;
    else usage("unknown option " + a);
  }
  if (o.reps < 1 || o.size < 1 || o.threads < 1 || o.tcfg.build.max_leaf_size < 1 || o.max_count < 1 || o.levels < 0)
    usage("counts must be >= 1 (levels >= 0)");
  if (clock_arg != "wall" && clock_arg != "cpu") usage("--clock must be wall or cpu");
  if (clock_arg == "cpu") {
    if (o.threads != 1) usage("--clock cpu needs --threads 1");
    o.clock = StageClock::ThreadCpu;
  }
  o.tcfg.clock = o.ccfg.clock = o.clock;
  o.deform = deform_preset(deform);
  if (amplitude) o.deform.amplitude = *amplitude;
  if (const std::string why = check(o.deform); !why.empty()) usage("--deform/--amplitude: " + why);
  return o;
}

// The scene setting that asks for format f (never auto: each configuration is one format).
bvh::LeafFormatChoice explicit_format(bvh::LeafFormat f) {
  return f == bvh::LeafFormat::Tables ? bvh::LeafFormatChoice::Tables : bvh::LeafFormatChoice::Blocks;
}

// Every configuration through loop::make_accel, with the bench's own builder settings and clock.
std::unique_ptr<loop::Accel> make_config(AccelKind kind, const Mesh& mesh, loop::AccelSetup s, const Options& o) {
  s.clock = o.clock;
  s.triangle_build = o.tcfg.build;
  s.cluster_build = o.ccfg.build;
  return loop::make_accel(kind, mesh, s);
}

struct Config {
  std::string name;
  AccelKind kind = AccelKind::OursTriangles;
  std::unique_ptr<loop::Accel> accel;
  [[nodiscard]] bool embree() const { return loop::is_embree(kind); }
};

// One frame of one configuration.
struct Row {
  int frame = 0;
  std::size_t config = 0;
  std::string name;
  bool embree = false;
  loop::UpdateTimes times;        // Embree: update_ms = vertex buffer, build_ms = commit
  double frame_ms = 0, source_ms = 0, trace_ms = 0;  // frame_ms: the whole update() call, wall clock
  TraceTotals totals;
  HitAgreement agreement;         // against ours_triangles of the same frame (zero for itself)
  double sah_cost = std::numeric_limits<double>::quiet_NaN();
  // Ours: stages 2 + 3; Embree: the commit (build or refit).
  [[nodiscard]] double box_build_ms() const {
    return embree ? times.build_ms : times.stages.boxes_ms + times.stages.build_ms;
  }
  [[nodiscard]] double total_ms() const { return times.update_ms + times.build_ms; }
  [[nodiscard]] double mrays_per_s() const { return trace_ms > 0 ? double(totals.rays) / (trace_ms * 1e3) : 0.0; }
};

void visit_row(const Row& r, Columns& col) {
  const StageTimes& s = r.times.stages;
  col("frame", r.frame);
  col("config", r.name);
  col("vertices_ms", r.embree ? r.times.update_ms : s.vertices_ms);
  col("boxes_ms", s.boxes_ms);
  col("sah_build_ms", s.build_ms);
  col("collapse_ms", s.collapse_ms);
  col("leaf_data_ms", s.leaf_data_ms);
  col("refit_ms", s.refit_ms);
  col("overlap_ms", s.overlap_ms);
  col("commit_ms", r.embree ? r.times.build_ms : 0.0);
  col("box_build_ms", r.box_build_ms());
  col("total_ms", r.total_ms());
  col("frame_ms", r.frame_ms);
  col("source_ms", r.source_ms);
  col("trace_ms", r.trace_ms);
  col("mrays_per_s", r.mrays_per_s());
  col("rays", r.totals.rays);
  col("hits", r.totals.hits);
  col("nodes_visited", r.totals.nodes_visited);
  col("triangles_tested", r.totals.triangles_tested);
  col("sah_cost", r.sah_cost);
  col("mismatches", r.agreement.mismatches());
  col("mismatch_hit_miss", r.agreement.hit_miss);
  col("mismatch_other_triangle", r.agreement.other_triangle);
  col("ties", r.agreement.ties);
}

template <class F>
std::vector<double> series(const std::vector<Row>& rows, std::size_t config, F f) {
  std::vector<double> v;
  for (const Row& r : rows)
    if (r.config == config) v.push_back(f(r));
  return v;
}

// --build-loop N: the binned SAH build alone, N times over the first cluster scene's rest-pose
// boxes (centroids = box centres, as in the scene), then the box passes alone: a profiling target.
// --update-loop N: the first cluster configuration (first clustering, leaf mode and format)
// updated N times from frames 1 .. reps - 1 in turn (positions made once, outside the timing):
// the median of every stage and of the whole update. A target for perf: no Embree, no triangle
// BVH, no trace.
int run_update_loop(loop::Accel& accel, Scene& scene, const Options& o) {
  const std::size_t F = o.reps > 1 ? static_cast<std::size_t>(o.reps - 1) : 1;
  std::vector<AlignedVector<Vec3>> frames(F, AlignedVector<Vec3>(scene.rest().vertex_count()));
  for (std::size_t f = 0; f < F; ++f) scene.positions(static_cast<double>(o.reps > 1 ? f + 1 : 0), frames[f]);
  std::vector<double> st[7];
  for (int i = 0; i < o.update_loop; ++i) {
    accel.update(frames[static_cast<std::size_t>(i) % F]);
    const bvh::StageTimes t = accel.last_update().stages;
    const double v[7] = {t.vertices_ms, t.boxes_ms, t.build_ms, t.collapse_ms, t.leaf_data_ms, t.refit_ms, t.total_ms()};
    for (int k = 0; k < 7; ++k) st[k].push_back(v[k]);
  }
  const char* names[7] = {"1 vertices to frame", "2 boxes", "3 SAH build", "4 collapse+link", "5 leaf data",
                          "6 block-tree refit", "= per-frame total"};
  const std::string label = "update loop " + std::string(accel.name());
  for (int k = 0; k < 7; ++k) row(label, names[k], st[k]);
  return 0;
}

int run_build_loop(const ClusterScene& cs, const Mesh& mesh, const ClusterView& v0, const Vec3& origin,
                   const Options& o) {
  const StageClock clock = o.clock;
  const std::span<const Box3f> boxes = cs.boxes();
  const std::vector<Vec3f> centers = box_centers(boxes);
  const std::string label = "build loop " + std::to_string(boxes.size()) + " clusters";
  Bvh b;
  BuildWorkspace ws;
  std::vector<double> ms;
  for (int i = 0; i < o.build_loop; ++i) {
    const double t0 = clock_ms(clock);
    build_binned_sah({boxes, centers, cs.weights(), cs.group_offsets()}, o.ccfg.build, b, ws);
    ms.push_back(clock_ms(clock) - t0);
  }
  row(label, "3 SAH build", ms);
  // The box stage alone on the same clustering (rest pose).
  AlignedVector<Vec3f> fp;
  AlignedVector<Box3f> bx;
  AlignedVector<Vec3f> cx;
  ms.clear();
  for (int i = 0; i < o.build_loop; ++i) {
    frame_positions(mesh.positions(), origin, fp);  // as in the scene: fresh positions first
    const double t0 = clock_ms(clock);
    point_group_boxes(fp, v0.vertex_offsets, v0.vertices, bx, cx);
    ms.push_back(clock_ms(clock) - t0);
  }
  row(label, "2 boxes", ms);
  // The same with the vertices renumbered in first-touch order (as ClusterScene does).
  const GroupVertexOrder vo = first_touch_order(mesh.vertex_count(), v0.vertex_offsets, v0.vertices);
  std::vector<double> ms_conv;
  ms.clear();
  for (int i = 0; i < o.build_loop; ++i) {
    double t0 = clock_ms(clock);
    frame_positions(mesh.positions(), vo.to_old, origin, fp);
    ms_conv.push_back(clock_ms(clock) - t0);
    t0 = clock_ms(clock);
    point_group_boxes(fp, vo, bx, cx);
    ms.push_back(clock_ms(clock) - t0);
  }
  row(label, "1 vertices (first-touch)", ms_conv);
  row(label, "2 boxes (first-touch)", ms);
  // The fused pass on the mesh renumbered once in that order (ClusterScene::fused_vertex_pass).
  const Mesh rm = renumber_vertices(mesh, vo.to_old);
  std::vector<std::uint32_t> rv(v0.vertices.size());
  for (std::size_t k = 0; k < rv.size(); ++k) rv[k] = vo.to_new[v0.vertices[k]];
  const auto fused_runs = group_runs(first_touch_order(rm.vertex_count(), v0.vertex_offsets, rv));
  if (!fused_runs) {
    std::fprintf(stderr, "bvh_bench: renumbered mesh has no runs\n");
    return 1;
  }
  AlignedVector<Vec3f> fpr(rm.vertex_count() + 2);
  ms.clear();
  for (int i = 0; i < o.build_loop; ++i) {
    const double t0 = clock_ms(clock);
    frame_positions_and_boxes(rm.positions(), origin, *fused_runs, fpr, bx, cx);
    ms.push_back(clock_ms(clock) - t0);
  }
  row(label, "1+2 fused (renumbered mesh)", ms);
  std::printf("first-touch order: %zu shared of %zu listed vertices\n", vo.shared.size(), v0.vertices.size());
  std::printf("SAH cost %.6f, %zu nodes\n", b.cost, b.nodes.size());
  return 0;
}

void print_tables(const std::vector<Config>& configs, const std::vector<Row>& rows, std::size_t ray_count) {
  auto med = [&](std::size_t c, auto f) { return median(series(rows, c, f)); };
  auto box_build = [](const Row& r) { return r.box_build_ms(); };
  auto total = [](const Row& r) { return r.total_ms(); };
  auto trace_ms = [](const Row& r) { return r.trace_ms; };
  const std::pair<const char*, double StageTimes::*> stages[] = {
      {"1 vertices to frame", &StageTimes::vertices_ms}, {"2 boxes", &StageTimes::boxes_ms},
      {"3 SAH build", &StageTimes::build_ms},            {"4 collapse+link", &StageTimes::collapse_ms},
      {"5 leaf data", &StageTimes::leaf_data_ms},        {"6 block-tree refit", &StageTimes::refit_ms}};
  // (A cluster scene on one thread over renumbered vertices makes its boxes in stage 5: stage 2 is
  // then 0, and boxes+build leaves them out; the per-frame total counts every stage.)
  std::map<AccelKind, double> embree_update, embree_trace;  // the peers of the ratios
  for (std::size_t c = 0; c < configs.size(); ++c) {
    const std::string& n = configs[c].name;
    if (configs[c].embree()) {
      row(n, "1 vertices to frame", series(rows, c, [](const Row& r) { return r.times.update_ms; }));
      row(n, configs[c].kind == AccelKind::EmbreeRefit ? "3 refit commit" : "3 build commit",
          series(rows, c, [](const Row& r) { return r.times.build_ms; }));
      embree_update[configs[c].kind] = med(c, box_build);
      embree_trace[configs[c].kind] = med(c, trace_ms);
    } else {
      for (const auto& [what, m] : stages)
        row(n, what, series(rows, c, [m](const Row& r) { return r.times.stages.*m; }));
    }
    row(n, configs[c].embree() ? "= commit (build or refit)" : "= boxes+build (2+3)", series(rows, c, box_build));
    row(n, "= per-frame total", series(rows, c, total));
    std::printf("\n");
  }
  std::printf("%-30s %-13s %8s %8s | %-22s %-22s | %-30s\n", "configuration", "update", "box+bld", "total",
              "x faster than REFIT", "x faster than LOW", "trace speed vs rtcIntersect1");
  std::printf("%-30s %-13s %8s %8s | %-22s %-22s | %-30s\n", "", "", "ms", "ms", "box+bld  total", "box+bld  total",
              "MEDIUM  LOW  REFIT");
  for (std::size_t c = 0; c < configs.size(); ++c) {
    const double bb = med(c, box_build), tot = med(c, total), tr = med(c, trace_ms);
    std::printf("%-30s %-13s %8.2f %8.2f |", configs[c].name.c_str(), configs[c].embree() ? "commit" : "ours", bb, tot);
    for (AccelKind p : {AccelKind::EmbreeRefit, AccelKind::EmbreeLow}) {
      if (embree_update.count(p)) std::printf(" %7.1fx %7.1fx      |", embree_update[p] / bb, embree_update[p] / tot);
      else std::printf(" %-21s|", " -");
    }
    for (AccelKind p : {AccelKind::EmbreeMedium, AccelKind::EmbreeLow, AccelKind::EmbreeRefit})
      if (embree_trace.count(p)) std::printf(" %5.2fx", embree_trace[p] / tr);
    std::printf("\n");
  }
  std::printf("\n");
  for (std::size_t c = 0; c < configs.size(); ++c) {
    const Summary s = summarize(series(rows, c, [](const Row& r) { return r.mrays_per_s(); }));
    HitAgreement mm;
    const Row* last = nullptr;
    for (const Row& r : rows)
      if (r.config == c) {
        mm.hit_miss += r.agreement.hit_miss, mm.other_triangle += r.agreement.other_triangle;
        mm.ties += r.agreement.ties, last = &r;
      }
    const TraceTotals& t = last->totals;
    std::printf("%-30s trace closest %7.2f Mrays/s [%.2f, %.2f]  %.2fx ours_triangles", configs[c].name.c_str(), s.p50,
                s.min, s.max, med(0, trace_ms) / med(c, trace_ms));
    if (t.nodes_visited)
      std::printf("  nodes/ray %.2f tris/ray %.2f", double(t.nodes_visited) / double(ray_count),
                  double(t.triangles_tested) / double(ray_count));
    std::printf("  hits %llu", (unsigned long long)t.hits);
    if (!std::isnan(last->sah_cost)) std::printf("  SAH %.4f", last->sah_cost);
    if (c > 0)
      std::printf("  mismatches (all frames): hit/miss %llu, other triangle %llu, ties %llu",
                  (unsigned long long)mm.hit_miss, (unsigned long long)mm.other_triangle, (unsigned long long)mm.ties);
    std::printf("\n");
  }
  std::printf("frame source (deformer positions, outside every configuration): median %.2f ms\n",
              med(0, [](const Row& r) { return r.source_ms; }));
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse_options(argc, argv);
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, o.threads);

  RunManifest manifest("bvh_bench", std::vector<std::string>(argv, argv + argc));
  Mesh mesh;
  try {
    mesh = read_mesh(o.mesh_path).mesh;
    record_input(manifest, o.mesh_path);
  } catch (const std::exception& e) {
    std::cerr << "bvh_bench: " << e.what() << "\n";
    return 1;
  }
  if (o.levels > 0) mesh = subdivide(mesh, SubdivisionScheme::Midpoint, o.levels);

  // Clusterings, made once from the rest pose.
  std::vector<std::pair<std::string, Clustering>> clusterings;
  bool renumbered = false, want_morton = false;
  for (const std::string& c : o.clusterings) {
    Stopwatch sw;
    if (c == "acc") {
      ClusterConfig cc;
      cc.method = ClusterMethod::Growth;
      cc.objective = ObjectiveKind::Acc;
      cc.max_count = o.max_count;
      cc.max_size = o.max_size;
      clusterings.push_back({"acc" + std::to_string(o.max_count), cluster_mesh(mesh, cc)});
    } else if (c == "meshopt") {
      ClusterConfig mc;
      mc.max_count = o.max_count;
      clusterings.push_back({"meshopt" + std::to_string(o.max_count), meshopt_clusters(mesh, mc)});
    } else {
      want_morton = true;  // made after the loop, on the final (possibly renumbered) mesh
      continue;
    }
    const double ms = sw.ms();
    manifest.add_timing_ms("clustering_" + c, ms);
    std::printf("clustering %-8s %9.0f ms (once, rest pose)\n", c.c_str(), ms);
    if (o.vertex_order == VertexOrder::Clusters && clusterings.size() == 1 && !renumbered) {
      sw.restart();
      Clustering& c0 = clusterings.front().second;
      const std::vector<std::uint32_t> to_old = cluster_vertex_order(mesh, view_of(c0), {}, o.ccfg);
      mesh = renumber_vertices(mesh, to_old);
      c0 = renumber_vertices(c0, inverse_permutation(to_old));
      renumbered = true;
      std::printf("vertices renumbered in %s's cluster order %9.0f ms (once)\n", clusterings.front().first.c_str(),
                  sw.ms());
    }
  }
  if (want_morton) {
    Stopwatch sw;
    clusterings.push_back({"morton80", ptc::morton_runs(mesh, 80)});
    manifest.add_timing_ms("clustering_morton", sw.ms());
  }

  // The motion: the (final) mesh as one part moved by the deformer.
  std::vector<ScenePart> parts;
  parts.push_back({"mesh", make_deformer(mesh, o.deform)});
  Scene scene("bvh_bench", std::move(parts), std::nullopt, std::nullopt, FrameRange{0, o.reps - 1});

  loop::AccelSetup setup;
  setup.origin = mesh.referenced_bounds().center();
  setup.cluster_group_size = o.ccfg.cluster_group_size;
  setup.group_trees = o.ccfg.group_trees;
  setup.threads = o.threads;
  const RayBatch rays = primary_rays(frame_box(mesh.referenced_bounds()), o.size, o.size);
  std::printf("mesh %s, %d subdivision levels: %zu triangles, %zu vertices; %zu rays; %u thread(s); %d frames "
              "of the %s deformer (amplitude %.3g, period %.3g); SAH traversal %.2f intersection %.2f, triangle "
              "leaves <= %u; tracer isa %s%s; %s clock\n",
              o.mesh_path.c_str(), o.levels, mesh.triangle_count(), mesh.vertex_count(), rays.size(), o.threads, o.reps,
              std::string(to_string(o.deform.kind)).c_str(), o.deform.amplitude, o.deform.period,
              o.tcfg.build.cost.traversal, o.tcfg.build.cost.intersection, o.tcfg.build.max_leaf_size,
              to_string(resolve(o.isa)), o.packets ? ", packets" : "", o.clock == StageClock::ThreadCpu ? "cpu" : "wall");
  for (const auto& [name, cl] : clusterings)
    std::printf("  clustering %s: %zu clusters, mean %.1f triangles\n", name.c_str(), cl.cluster_count(),
                double(mesh.triangle_count()) / double(cl.cluster_count()));
  std::printf("\n");

  if (o.build_loop > 0) {  // the first clustering's scene as the first cluster configuration has it
    if (clusterings.empty() || o.leaves.empty()) usage("--build-loop needs a clustering");
    SceneConfig c = o.ccfg;
    c.origin = setup.origin;
    c.cluster_leaf = o.leaves.front();
    const ClusterView v0 = view_of(clusterings.front().second);
    return run_build_loop(ClusterScene(mesh, v0, c), mesh, v0, setup.origin, o);
  }

  if (o.update_loop > 0) {  // the first cluster configuration's whole update, nothing else
    if (clusterings.empty() || o.leaves.empty() || o.formats.empty()) usage("--update-loop needs a clustering");
    setup.clusters = &clusterings.front().second;
    setup.cluster_leaf = o.leaves.front();
    setup.leaf_format = explicit_format(o.leaves.front() == ClusterLeaf::Linear ? o.formats.front() : bvh::LeafFormat::Blocks);
    return run_update_loop(*make_config(AccelKind::OursClusters, mesh, setup, o), scene, o);
  }

  // Configurations: ours_triangles first (the reference of the mismatches), then every clustering
  // in every leaf mode, then Embree.
  std::vector<Config> configs;
  try {
    configs.push_back(
        {"ours_triangles", AccelKind::OursTriangles, make_config(AccelKind::OursTriangles, mesh, setup, o)});
    for (const auto& [cname, cl] : clusterings)
      for (ClusterLeaf mode : o.leaves)
        for (bvh::LeafFormat f : o.formats) {
          if (mode != ClusterLeaf::Linear && f != bvh::LeafFormat::Blocks) continue;  // (tables: linear leaves only)
          setup.clusters = &cl;
          setup.cluster_leaf = mode;
          setup.leaf_format = explicit_format(f);
          const bool tables = f == bvh::LeafFormat::Tables;
          configs.push_back({"ours_" + cname + "_" + (tables ? std::string("tables") : to_string(mode)),
                             AccelKind::OursClusters, make_config(AccelKind::OursClusters, mesh, setup, o)});
        }
    if (o.embree)
      for (AccelKind k : {AccelKind::EmbreeMedium, AccelKind::EmbreeLow, AccelKind::EmbreeRefit}) {
        configs.push_back({std::string(loop::to_string(k)), k, make_config(k, mesh, setup, o)});
        if (k == AccelKind::EmbreeRefit)
          std::printf("%-30s %-28s %9.2f ms   (first commit, once)\n\n", "embree_refit", "build",
                      configs.back().accel->last_update().build_ms);
      }
  } catch (const std::exception& e) {
    std::cerr << "bvh_bench: " << e.what() << "\n";
    return 1;
  }

  // Frames through the one loop; measure = trace the rays, compare with ours_triangles' hits.
  std::vector<loop::Accel*> order;
  for (const Config& c : configs) order.push_back(c.accel.get());
  TraceOptions opt;
  opt.threads = o.threads;
  opt.isa = o.isa;
  opt.packets = o.packets;
  opt.counters = o.counters;
  std::vector<Row> rows;
  HitBatch ref, hits;
  AlignedVector<Vec3> pos(mesh.vertex_count());
  loop::LoopOptions lo;
  lo.frames = scene.frames();
  loop::run_frame_loop(scene, pos, order, lo, [&](const loop::FrameRecord& fr, loop::Accel& a, std::span<const Vec3>) {
    const double t0 = clock_ms(o.clock);
    const TraceTotals totals = a.trace(rays, fr.accel == 0 ? ref : hits, opt);
    const double trace_ms = clock_ms(o.clock) - t0;
    rows.push_back({.frame = fr.index, .config = fr.accel, .name = configs[fr.accel].name,
                    .embree = configs[fr.accel].embree(), .times = fr.times, .frame_ms = fr.update_wall_ms,
                    .source_ms = fr.source_ms, .trace_ms = trace_ms, .totals = totals,
                    .agreement = fr.accel > 0 ? compare_hits(ref, hits) : HitAgreement{},
                    .sah_cost = a.sah_cost().value_or(std::numeric_limits<double>::quiet_NaN())});
  });
  print_tables(configs, rows, rays.size());

  if (!o.out_dir.empty()) {
    try {
      const Table table = tabulate(Schema{"ptc-bvh-bench", 2}, rows, visit_row);
      std::vector<std::string> leaf_names;
      for (ClusterLeaf l : o.leaves) leaf_names.push_back(to_string(l));
      std::vector<std::string> format_names;
      for (bvh::LeafFormat f : o.formats) format_names.push_back(std::string(to_string(f)));
      const nlohmann::json params = {
          {"levels", o.levels}, {"frames", o.reps}, {"size", o.size}, {"threads", o.threads},
          {"clusters", o.clusterings}, {"max_count", o.max_count}, {"max_size", o.max_size},
          {"leaves", leaf_names}, {"leaf_formats", format_names}, {"deform", to_string(o.deform.kind)}, {"amplitude", o.deform.amplitude},
          {"period", o.deform.period}, {"vertex_order", to_string(o.vertex_order)},
          {"cluster_group_size", o.ccfg.cluster_group_size}, {"group_trees", to_string(o.ccfg.group_trees)}, {"isa", to_string(resolve(o.isa))},
          {"clock", o.clock == StageClock::ThreadCpu ? "cpu" : "wall"},
          {"sah_traversal", o.tcfg.build.cost.traversal}, {"sah_intersection", o.tcfg.build.cost.intersection},
          {"triangle_leaf", o.tcfg.build.max_leaf_size}};
      for (const auto& [key, value] : params.items()) manifest.set_parameter(key, value);
      manifest.set_result("triangles", mesh.triangle_count());
      manifest.set_result("rays", rays.size());
      OutputDir dir(o.out_dir);
      dir.write("bvh_bench.csv", table.csv.str());
      manifest.add_output("bvh_bench.csv", table.schema.id());
      manifest.add_output("manifest.json");
      dir.write("manifest.json", dump_json(manifest.to_json()));
      dir.commit();
      std::printf("\nwrote %s/{bvh_bench.csv,manifest.json}\n", o.out_dir.c_str());
    } catch (const std::exception& e) {
      std::cerr << "bvh_bench: " << e.what() << "\n";
      return 1;
    }
  }
  return 0;
}
