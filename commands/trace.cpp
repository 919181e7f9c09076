// `ptc trace`: the frame loop over one configuration (the static + moving scene BVH), and per
// frame the rendered view, its images and its rows of trace.csv.
#include "commands/trace.h"

#include <iostream>
#include <ostream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/experiments/trace.h"
#include "analysis/loop/frame_loop.h"
#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "bvh/camera.h"
#include "bvh/cluster_scene.h"
#include "bvh/scene_tracer.h"
#include "commands/args.h"
#include "commands/output_dir.h"
#include "commands/scene_args.h"
#include "toolkit/core/memory.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"
#include "viz/png.h"
#include "toolkit/core/strings.h"

namespace ptc {
namespace {

nlohmann::json legend_json(const ColorLegend& l) {
  return {{"quantity", l.quantity}, {"colormap", l.colormap}, {"min", l.min}, {"max", l.max}, {"note", l.note}};
}

double per_ray(std::uint64_t total, std::uint64_t rays) { return rays ? double(total) / double(rays) : 0.0; }

void check_render_options(const RenderConfig& rc) {
  check_image_size(rc.width, rc.height);
  if (rc.ao_samples < 0) throw UsageError("--ao", "the sample count must be >= 0");
  if (rc.light && !rc.light->allFinite()) throw UsageError("--light", "not a finite vector");
}

// The images of one frame into `dir` (suffix "" for one frame, "_0007" in a sequence), each
// recorded with its legend.
void write_frame_images(const OutputDir& dir, const Render& r, const RenderConfig& rc, const std::string& suffix,
                        bool first, const std::optional<std::pair<double, double>>& cost_range, RunManifest& manifest,
                        nlohmann::json& images) {
  auto put = [&](const std::string& base, const RgbImage& img, nlohmann::json legend) {
    const std::string name = base + suffix + ".png";
    viz::write_png(dir.path(name), img);
    manifest.add_output(name);
    images[name] = std::move(legend);
  };
  ColorLegend dl, nl, tl;  // filled by the image functions, so those run before the legends are read
  const RgbImage depth = depth_image(r, dl), nodes = nodes_image(r, nl, cost_range),
                 tris = triangles_image(r, tl, cost_range);
  put("shaded", shaded_image(r),
      {{"quantity", "Lambert shading"},
       {"note", fmt::format("albedo 0.9, ambient 0.2{}, diffuse 0.8{}; background (32,32,40)",
                            rc.ao_samples ? " x AO" : "", rc.shadows ? " x shadow" : "")}});
  put("depth", depth, legend_json(dl));
  put("normal", normal_image(r),
      {{"quantity", "facing geometric normal (world)"}, {"colormap", "rgb = 255 (n + 1) / 2"}, {"min", -1}, {"max", 1},
       {"note", "missed rays: black"}});
  put("cost_nodes", nodes, legend_json(nl));
  put("cost_triangles", tris, legend_json(tl));
  if (first) {
    viz::write_png(dir.path("cost_legend.png"), viridis_bar(256, 16));
    manifest.add_output("cost_legend.png");
    images["cost_legend.png"] = {{"quantity", "colour bar of the cost images"}, {"colormap", "viridis"},
                                 {"note", "left = legend min, right = legend max"}};
  }
  if (rc.ao_samples > 0)
    put("ao", ao_image(r),
        {{"quantity", "ambient occlusion (fraction unoccluded)"}, {"colormap", "grey"}, {"min", 0}, {"max", 1},
         {"note", "missed rays: black"}});
}

}  // namespace

void cmd_trace(const TraceCommandOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw UsageError("--out", "an output directory is required");
  check_render_options(opt.render);
  if (opt.frame && opt.frames) throw UsageError("--frame/--frames", "give one frame or one range, not both");
  std::optional<FrameRange> asked;
  if (opt.frame) {
    const std::int64_t f = parse_frame(*opt.frame, "--frame");
    asked = FrameRange{f, f};
  }
  if (opt.frames) asked = parse_frame_range(*opt.frames, "--frames");
  const bool sequence = opt.frames.has_value();
  const std::optional<std::pair<double, double>> cost_range =
      opt.cost_range ? std::optional(parse_value_range(*opt.cost_range, "--cost-range")) : std::nullopt;
  if (cost_range && !(cost_range->second > 0.0))  // (the cost images count nodes and triangles)
    throw UsageError("--cost-range", "'" + *opt.cost_range + "': the costs are counts (>= 0), so MAX must be above 0");

  refuse_overwriting_input(opt.out_dir, opt.input);
  refuse_overwriting_input(opt.out_dir, opt.clusters);
  RunManifest manifest("trace", opt.argv, "ptc-trace/5");
  const std::string arg = opt.input.string();
  Scene scene = open_scene_recorded(opt.input, opt.scene_options, manifest);
  const bool deformed = opt.deform && *opt.deform != "none";  // (none, the default here: still)
  manifest.set_parameter("motion", apply_stand_in(scene, opt.deform.value_or("none"), arg));
  const FrameRange range = asked ? *asked : FrameRange{scene.frames().first, scene.frames().first};
  // (a stand-in motion is periodic: it has no range of its own, as in ptc bench)
  check_frames(scene, range, arg, opt.frames ? "--frames" : "--frame", opt.extend_frames || deformed);

  // The first frame's positions: the camera and the trace frame are fixed from them. (Kept apart
  // from the scene's rest mesh until the vertices are renumbered, which then renames the rest's
  // triangles where they are.) A still scene (every part static: a mesh file, no --deform) is
  // its rest pose in every frame: the rest mesh is traced and shown as it is, without a copy of
  // its positions (160 MB at 13.3M triangles, and the time to fill fresh memory with them).
  const bool still = scene.all_static();
  if (still && !opt.clusters.empty() && opt.cluster_fallback)
    throw UsageError("--cluster-fallback", "a still scene is built once and never updated: nothing falls back");
  if (still && !opt.clusters.empty() && opt.fallback_refit)
    throw UsageError("--fallback-refit", "a still scene is built once and never updated: nothing falls back");
  if (still && !opt.clusters.empty() && opt.fallback_sah)
    throw UsageError("--fallback-sah", "a still scene is built once and never updated: nothing falls back");
  if (still && !opt.clusters.empty() && opt.group_trees && !opt.cluster_group_size)
    throw UsageError("--group-trees", "a still scene is built once with the plain build: give --cluster-groups N > 1 too");
  std::vector<Vec3> first_pos;
  Stopwatch sw;
  if (!still) {
    first_pos.resize(scene.rest().vertex_count());
    scene.positions(double(range.first), first_pos, true);
    manifest.add_timing_ms("first_positions", sw.ms());
  }
  // (the camera's and the light's: the vertices some triangle uses)
  const Box3 first_bounds =
      referenced_bounds(scene.rest().triangles(), still ? scene.rest().positions() : std::span<const Vec3>(first_pos));

  // Camera and light: flags > the scene's own > framing the first frame (commands/scene_args.h).
  const CameraSpec spec = camera_for(opt.camera, scene);
  const bvh::PinholeCamera cam = make_camera(spec, first_bounds, opt.render.width, opt.render.height, arg);
  RenderConfig rc = opt.render;
  check_eye_reach(cam, opt.camera, scene, arg);
  const LightChoice light = light_for(rc.light, scene, cam, first_bounds, arg);
  rc.light = light.position;
  rc.light_intensity = light.intensity;

  Clustering clusters;
  const bool use_clusters = !opt.clusters.empty();
  if (use_clusters) clusters = read_clusters_recorded(opt.clusters, scene.rest(), manifest);

  // The one configuration: the static BVH built once, the moving BVH updated per frame.
  bvh::SceneTracerConfig tcfg;
  tcfg.clusters = use_clusters ? &clusters : nullptr;
  // --cluster-groups N applies to every cluster BVH; unset, a still scene takes the plain build.
  const std::uint32_t groups = opt.cluster_group_size.value_or(still ? 0u : bvh::cluster_scene_defaults().cluster_group_size);
  tcfg.cluster_group_size = tcfg.still_cluster_group_size = groups;
  if (opt.cluster_group_size) tcfg.min_cluster_groups = 0;  // (given: groups of exactly up to N)
  tcfg.group_trees = opt.group_trees.value_or(bvh::cluster_scene_defaults().group_trees);
  tcfg.cluster_fallback = opt.cluster_fallback.value_or(bvh::kAutoFallbackSwelling);
  tcfg.fallback_refit = opt.fallback_refit.value_or(bvh::kAutoFallbackRefitGrowth);
  // The fallback built for rays from the camera's eye, or for their mean directions, or plain
  // (--fallback-sah; docs/tracing.md, "The fallback built for the camera's eye").
  const bvh::FallbackSah fallback_sah = use_clusters && !still && tcfg.cluster_fallback > 0
                                            ? opt.fallback_sah.value_or(bvh::FallbackSah::Directions)
                                            : bvh::FallbackSah::Plain;
  if (fallback_sah == bvh::FallbackSah::Directions)
    tcfg.fallback_area_weights = bvh::direction_area_weights(cam, rc.width, rc.height);
  if (fallback_sah == bvh::FallbackSah::Eye) tcfg.fallback_area_eye = cam.eye;
  // Set up at the rest pose, as ptc bench and the experiments do, and updated to every frame in
  // the loop: the BVH's fixed parts (cluster order, group trees) and the trace frame do not depend
  // on which frame the run starts at, so a frame traces the same in any range (the camera frames
  // the first frame unless given).
  tcfg.origin = scene.rest().referenced_bounds().center();
  const bool renumbered = use_clusters && opt.vertex_order == bvh::VertexOrder::Clusters;
  manifest.set_parameter("vertex_order", use_clusters ? bvh::to_string(opt.vertex_order) : "input");
  std::optional<loop::SceneAccel> made;
  try {
    if (renumbered) {
      // The method's precomputation, as in ptc bench: each cluster's vertices consecutive, so
      // the cluster BVH's per-frame pass streams instead of gathering (832k, twist: 2.0 against
      // 3.2 ms a frame; the set-up takes as long either way). Triangle ids, and so every
      // output, stay.
      sw.restart();
      const std::vector<std::uint32_t> to_old =
          bvh::renumber_by_clusters(scene, clusters, bvh::cluster_config(tcfg, *tcfg.origin));
      if (!still) {
        std::vector<Vec3> moved(first_pos.size());
        for (std::size_t i = 0; i < moved.size(); ++i) moved[i] = first_pos[to_old[i]];
        first_pos = std::move(moved);
      }
      manifest.add_timing_ms("renumber_vertices", sw.ms());
      manifest.set_result("scene_after_renumbering", scene.describe());
    }
    made.emplace(scene.rest(), bvh::PartLayout::of(scene), tcfg);
  } catch (const bvh::FrameRangeError& e) {
    throw InputError(arg, "", "", e.what());
  }
  // The mesh the views are shaded from: the rest itself (still), else a copy of its topology
  // whose positions the loop moves to every frame.
  Mesh moving_mesh = still ? Mesh() : scene.rest().with_positions(std::move(first_pos));
  const Mesh& mesh = still ? scene.rest() : moving_mesh;
  loop::SceneAccel& accel = *made;
  const bvh::SceneTracer& tracer = accel.tracer();
  manifest.add_timing_ms("static_build", tracer.static_build_ms());
  manifest.add_timing_ms("setup", tracer.moving_setup_ms());
  const char* bvh_kind = use_clusters ? "clusters" : "triangles";
  // The scene's static parts (the tracer's own split differs: with clusters, an all-static
  // scene is one cluster BVH).
  std::size_t static_tris = 0;
  for (std::size_t p = 0; p < scene.part_count(); ++p)
    if (scene.is_static(p)) static_tris += scene.triangle_offset(p + 1) - scene.triangle_offset(p);
  const std::size_t moving_tris = mesh.triangle_count() - static_tris;

  OutputDir dir(opt.out_dir);
  nlohmann::json images = nlohmann::json::object();
  std::vector<TraceRow> rows;
  const unsigned threads = resolve_threads(rc.threads);
  double render_ms = 0, write_ms = 0, positions_ms = 0;
  std::size_t empty_frames = 0;  // frames without a primary hit: the first noted, the rest counted
  std::uint64_t hits = 0;        // primary hits over the frames (results.hits)
  nlohmann::json per_frame = nlohmann::json::array();
  std::uint64_t fallback_frames = 0, refit_frames = 0;

  std::ostringstream text;  // the table; --json prints the rows as JSON instead
  text << fmt::format("{}: {} ({} static, {} moving; {}), {}; {}x{} pixels, {}; static BVH {:.1f} ms{}\n", arg,
                     counted(mesh.triangle_count(), "triangle"), static_tris, moving_tris,
                     counted(scene.part_count(), "part"),
                     tracer.all_static() ? fmt::format("one {} BVH built once", use_clusters ? "cluster" : "triangle")
                     : tracer.split() ? fmt::format("static triangle BVH + moving {} BVH", use_clusters ? "cluster" : "triangle")
                                      : fmt::format("one {} BVH updated per frame", use_clusters ? "cluster" : "triangle"),
                     rc.width, rc.height, counted(threads, "thread"), tracer.static_build_ms(),
                     tracer.all_static() ? "" : fmt::format(", moving BVH setup {:.1f} ms", tracer.moving_setup_ms()));
  text << fmt::format("{:>6} {:>10} {:>9} {:<8} {:>10} {:>10} {:>10} {:>9} {:>10} {:>10}\n", "frame", "update_ms",
                     "build_ms", "pass", "rays", "hits", "trace_ms", "Mrays/s", "nodes/ray", "tris/ray");

  loop::LoopOptions lo;
  lo.frames = range;
  lo.fresh_positions = false;  // one configuration: nothing to keep apart
  lo.update_static = false;    // the static parts' positions stay those of the first frame
  lo.first_frame_given = true; // computed above for the camera and the trace frame
  lo.rest_positions = still;    // (no buffer then)
  loop::Accel* const accels[] = {&accel};
  std::int64_t frame_now = range.first;  // (a position beyond the tracer's range names the frame)
  try {
  loop::run_frame_loop(scene, moving_mesh.positions(), accels, lo, [&](const loop::FrameRecord& fr, loop::Accel& a,
                                                                  std::span<const Vec3>) {
    const std::int64_t f = fr.frame;
    frame_now = f + 1;  // (the loop moves the next frame's positions after this call)
    const bool first = fr.index == 0;
    positions_ms += fr.source_ms;
    Stopwatch t;
    const Render r = render_view(target_of(a), mesh, cam, rc);
    render_ms += t.ms();

    t.restart();
    write_frame_images(dir, r, rc, sequence ? fmt::format("_{:04d}", f) : "", first, cost_range, manifest, images);
    write_ms += t.ms();

    TraceRow base;
    base.mesh = arg;
    base.bvh = bvh_kind;
    base.triangles = mesh.triangle_count();
    base.clusters = use_clusters ? clusters.cluster_count() : 0;
    base.width = rc.width, base.height = rc.height;
    base.threads = threads;
    base.frame = f;
    base.ao_samples = rc.ao_samples;
    base.setup_ms = first ? tracer.moving_setup_ms() : 0.0;
    base.static_build_ms = first ? tracer.static_build_ms() : 0.0;
    base.update_ms = fr.times.update_ms;
    base.build_ms = fr.times.build_ms;
    base.stages = fr.times.stages;
    base.static_triangles = static_tris, base.moving_triangles = moving_tris;
    const RssSample mem = rss_sample();
    base.rss_mb = mem.rss_mb;
    base.peak_rss_mb = mem.peak_mb;
    auto pass = [&](const char* name, const PassStats& s, bool lead) {
      TraceRow row = base;
      row.pass = name;
      row.stats = s;
      rows.push_back(std::move(row));
      text << (lead ? fmt::format("{:>6} {:>10.2f} {:>9.2f} ", f, fr.times.update_ms, fr.times.build_ms)
                   : fmt::format("{:>28}", ""))
          << fmt::format("{:<8} {:>10} {:>10} {:>10.2f} {:>9.2f} {:>10.2f} {:>10.2f}\n", name, s.rays, s.hits,
                         s.trace_ms, s.mrays_per_s(), per_ray(s.nodes_visited, s.rays), per_ray(s.triangles_tested, s.rays));
    };
    pass("primary", r.primary_stats, true);
    if (rc.shadows) pass("shadow", r.shadow_stats, false);
    if (rc.ao_samples > 0) pass("ao", r.ao_stats, false);
    per_frame.push_back({{"frame", f}, {"rays", r.primary_stats.rays}, {"hits", r.primary_stats.hits}});
    if (tracer.moving_is_clusters()) {  // the moving cluster BVH's swelling, and whether its triangle fallback traced the frame
      per_frame.back()["swelling"] = tracer.moving_swelling();
      per_frame.back()["fallback"] = tracer.moving_fallback_active();
      per_frame.back()["fallback_refit"] = tracer.moving_fallback_refitted();
      fallback_frames += tracer.moving_fallback_active() ? 1 : 0;
      refit_frames += tracer.moving_fallback_refitted() ? 1 : 0;
    }
    hits += r.primary_stats.hits;
    if (r.primary_stats.hits == 0 && r.primary_stats.rays > 0 && ++empty_frames == 1)  // background only
      std::cerr << "ptc: note: no primary ray hit the mesh in frame " << f
                << " (the camera sees past it or from inside it: give --eye and --look-at)\n";
  });
  } catch (const bvh::FrameRangeError& e) {
    throw InputError(arg, "", fmt::format("frame {}", frame_now), e.what());
  }
  if (empty_frames > 1)  // said once, then counted
    std::cerr << "ptc: note: nor in " << counted(empty_frames - 1, "later frame") << " (trace.csv: hits 0)\n";
  manifest.add_timing_ms("positions", positions_ms);
  manifest.add_timing_ms("render", render_ms);
  sw.restart();
  const Table table = trace_table(rows);
  dir.write("trace.csv", table.csv.str());
  manifest.add_output("trace.csv", table.schema.id());

  manifest.set_parameter("scene", arg);
  manifest.set_parameter("frames", {range.first, range.last});
  manifest.set_parameter("bvh", bvh_kind);
  manifest.set_parameter("split", tracer.split() ? "static triangle BVH built once + moving BVH updated per frame"
                                  : tracer.all_static() ? "all static: one BVH built once"
                                                        : "all moving: one BVH updated per frame");
  manifest.set_parameter("parts", [&] {
    nlohmann::json a = nlohmann::json::array();
    for (std::size_t p = 0; p < scene.part_count(); ++p)
      a.push_back({{"name", scene.part(p).name}, {"static", scene.is_static(p)},
                   {"triangles", {scene.triangle_offset(p), scene.triangle_offset(p + 1)}}});
    return a;
  }());
  if (use_clusters) manifest.set_parameter("clusters", opt.clusters.string());
  // The group size used (0: the plain build; unset, the default N shrinks for a small scene:
  // bvh::cluster_group_size_used).
  const std::uint32_t groups_used = made->tracer().cluster_group_size();
  if (use_clusters) manifest.set_parameter("cluster_group_size", groups_used);
  if (use_clusters) manifest.set_parameter("min_cluster_groups", tcfg.min_cluster_groups);
  if (use_clusters && groups_used > 1) manifest.set_parameter("group_trees", bvh::to_string(tcfg.group_trees));
  if (use_clusters && !still) {
    manifest.set_parameter("cluster_fallback", tcfg.cluster_fallback);
    manifest.set_result("cluster_fallback_frames", fallback_frames);
    manifest.set_parameter("fallback_refit", tcfg.cluster_fallback > 0 ? tcfg.fallback_refit : 0.0);
    manifest.set_result("fallback_refit_frames", refit_frames);
    manifest.set_parameter("fallback_sah", bvh::to_string(fallback_sah));
    const auto& w = tcfg.fallback_area_weights;
    manifest.set_parameter("fallback_area_weights", std::vector<double>(w.begin(), w.end()));
    manifest.set_parameter("fallback_area_eye",
                           tcfg.fallback_area_eye ? vec_json(*tcfg.fallback_area_eye) : nlohmann::json(nullptr));
  }
  manifest.set_parameter("width", rc.width);
  manifest.set_parameter("height", rc.height);
  manifest.set_parameter("threads", threads);
  manifest.set_parameter("shadows", rc.shadows);
  manifest.set_parameter("ao_samples", rc.ao_samples);
  manifest.set_parameter("ao_distance_rel", rc.ao_distance_rel);
  manifest.set_parameter("seed", rc.seed);
  if (cost_range) manifest.set_parameter("cost_range", {cost_range->first, cost_range->second});
  manifest.set_parameter("camera", camera_json(cam, scene, opt.camera));
  manifest.set_parameter("light", light_json(light));
  manifest.set_parameter("ray_offset", "origin = p + 2^-18 M n, M = max |coordinate| of bounds and p in the trace frame");
  manifest.set_result("images", images);
  manifest.set_result("rays", std::uint64_t(rc.width) * std::uint64_t(rc.height));  // per frame
  manifest.set_result("hits", hits);  // over every frame traced (results.frames has them per frame)
  manifest.set_result("frames", per_frame);
  manifest.add_timing_ms("write", write_ms + sw.ms());
  (void)commit_with_manifest(dir, manifest);

  if (opt.json) {
    nlohmann::json j = nlohmann::json::array();
    for (const TraceRow& row : rows)
      j.push_back({{"frame", row.frame}, {"pass", row.pass}, {"rays", row.stats.rays}, {"hits", row.stats.hits},
                   {"trace_ms", row.stats.trace_ms}, {"mrays_per_s", row.stats.mrays_per_s()},
                   {"nodes_per_ray", per_ray(row.stats.nodes_visited, row.stats.rays)},
                   {"triangles_per_ray", per_ray(row.stats.triangles_tested, row.stats.rays)},
                   {"update_ms", row.update_ms}, {"build_ms", row.build_ms}});
    out << dump_json({{"schema", "ptc-trace-summary/1"}, {"scene", arg}, {"bvh", bvh_kind}, {"rows", j}});
    return;
  }
  out << text.str();
  if (tracer.moving_is_clusters() && tcfg.cluster_fallback > 0)
    out << fmt::format("cluster BVH: {} of {} traced on the triangle fallback (swelling above {:g}){}{}\n",
                       fallback_frames, counted(per_frame.size(), "frame"), tcfg.cluster_fallback,
                       tcfg.fallback_refit > 0 ? fmt::format("; its tree refitted on {} of them (cost growth at most {:g})",
                                                             refit_frames, tcfg.fallback_refit)
                                               : std::string("; its tree rebuilt on each"),
                       fallback_sah == bvh::FallbackSah::Eye          ? "; SAH for rays from the camera's eye"
                       : fallback_sah == bvh::FallbackSah::Directions ? "; SAH for the camera's ray directions"
                                                                      : "; plain SAH");
  const std::string names = "{shaded,depth,normal,cost_nodes,cost_triangles" + std::string(rc.ao_samples > 0 ? ",ao" : "") + "}";
  out << "wrote " << opt.out_dir.string() << "/"
      << (sequence ? fmt::format("{}_{:04d}..{:04d}.png", names, range.first, range.last) : names + ".png")
      << ", cost_legend.png, trace.csv, manifest.json\n";
}

}  // namespace ptc
