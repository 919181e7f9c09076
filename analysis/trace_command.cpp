#include "analysis/trace_command.h"

#include <tbb/info.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <chrono>
#include <fstream>
#include <memory>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/csv.h"
#include "analysis/manifest.h"
#include "analysis/cmd_animate.h"
#include "analysis/output_dir.h"
#include "analysis/scene_file.h"
#include "analysis/scene_trace.h"
#include "analysis/trace_clusters.h"
#include "bvh/trace_scene.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

nlohmann::json vec_json(const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

nlohmann::json legend_json(const ColorLegend& l) {
  return {{"quantity", l.quantity}, {"colormap", l.colormap}, {"min", l.min}, {"max", l.max}, {"note", l.note}};
}

double per_ray(std::uint64_t total, std::uint64_t rays) { return rays ? double(total) / double(rays) : 0.0; }

unsigned effective_threads(unsigned t) {
  return t ? t : static_cast<unsigned>(tbb::info::default_concurrency());
}

}  // namespace

std::vector<std::string> trace_csv_columns() {
  return {"mesh", "bvh", "triangles", "clusters", "width", "height", "threads", "setup_ms", "build_ms",
          "rays", "hits", "trace_ms", "mrays_per_s", "nodes_visited", "triangles_tested", "nodes_per_ray",
          "triangles_per_ray", "shadow_rays", "shadow_occluded", "shadow_trace_ms", "shadow_mrays_per_s",
          "ao_samples", "ao_rays", "ao_occluded", "ao_trace_ms", "ao_mrays_per_s", "frame", "static_triangles",
          "moving_triangles", "static_build_ms", "update_ms"};
}

namespace {

// "F": a frame number >= 0 (decimal integer).
std::int64_t parse_one_frame(const std::string& s) {
  std::int64_t v = -1;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v < 0)
    throw InputError("", "", "--frame", fmt::format("'{}' is not a frame number (an integer >= 0)", s.substr(0, 32)));
  return v;
}

// Opens SCENE (open_scene), recording the read time and, for a file, the input in the manifest.
Scene open_recorded(const std::filesystem::path& input, const SceneOptions& options, RunManifest& manifest) {
  const auto t0 = Clock::now();
  Scene scene = open_scene(input.string(), options);
  manifest.add_timing_ms("read", ms_since(t0));
  std::error_code ec;
  if (std::filesystem::is_regular_file(input, ec)) manifest.add_input(input);
  return scene;
}

// read_clusters (trace_clusters.h), recording the read time and the file in the manifest.
Clustering read_clusters_recorded(const std::filesystem::path& clusters, const Mesh& mesh, RunManifest& manifest) {
  const auto t0 = Clock::now();
  Clustering c = read_clusters(clusters, mesh);
  manifest.add_timing_ms("read_clusters", ms_since(t0));
  std::error_code ec;
  manifest.add_input(std::filesystem::is_directory(clusters, ec) ? clusters / "triangles.csv" : clusters);
  return c;
}

void check_range(const Scene& scene, const FrameRange& r, const std::string& arg, const char* option) {
  if (const std::size_t fc = scene.frame_count(); fc > 0 && r.last >= static_cast<std::int64_t>(fc))
    throw InputError("", "", option, fmt::format("frame {} is beyond the last frame of '{}' (frames 0..{})", r.last, arg, fc - 1));
}

// Whether the scene's camera / light were given (built-in scenes always, scene files when the
// key is present); otherwise the trace's own defaults frame the mesh.
struct SceneViewGiven {
  bool camera = false, light = false;
};
SceneViewGiven scene_view_given(const std::string& arg) {
  if (is_builtin_scene(arg)) return {true, true};
  std::string ext = std::filesystem::path(arg).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext != ".json") return {};
  try {
    std::ifstream in(arg, std::ios::binary);
    const nlohmann::json j = nlohmann::json::parse(in);
    return {j.contains("camera"), j.contains("light")};
  } catch (const std::exception&) {
    return {};
  }
}

}  // namespace

void cmd_trace(const TraceCommandOptions& opt, const ImageWriter& write_image, std::ostream& out) {
  if (opt.out_dir.empty()) throw InputError("", "", "--out", "an output directory is required");
  const RenderConfig& rc0 = opt.render;
  if (rc0.width < 1 || rc0.height < 1 || rc0.width > 16384 || rc0.height > 16384)
    throw InputError("", "", "--width/--height", "the image size must be 1..16384 pixels per side");
  if (rc0.ao_samples < 0) throw InputError("", "", "--ao", "the sample count must be >= 0");
  if (rc0.light && !(std::isfinite(rc0.light->x()) && std::isfinite(rc0.light->y()) && std::isfinite(rc0.light->z())))
    throw InputError("", "", "--light", "not a finite vector");
  if (opt.frame && opt.frames) throw InputError("", "", "--frame/--frames", "give one frame or one range, not both");
  std::optional<FrameRange> asked;
  if (opt.frame) {
    const std::int64_t f = parse_one_frame(*opt.frame);
    asked = FrameRange{f, f};
  }
  if (opt.frames) asked = parse_frame_range(*opt.frames);
  const bool sequence = opt.frames.has_value();

  RunManifest manifest("trace", opt.argv);
  const std::string arg = opt.input.string();
  Scene scene = open_recorded(opt.input, opt.scene_options, manifest);
  const FrameRange range = asked ? *asked : FrameRange{scene.frames().first, scene.frames().first};
  check_range(scene, range, arg, opt.frames ? "--frames" : "--frame");

  // The first frame's positions: the camera and the trace frame are fixed from them.
  Mesh mesh = scene.rest();
  auto t0 = Clock::now();
  scene.positions(double(range.first), mesh.positions(), true);
  double positions_ms = ms_since(t0);
  const Box3 first_bounds = mesh.bounds();

  // Camera: flags > the scene's camera (built-in scenes, scene files with "camera") > framing.
  const SceneViewGiven given = scene_view_given(arg);
  CameraSpec spec = opt.camera;
  if (given.camera) {
    const SceneCamera& sc = scene.camera();
    if (!spec.eye) spec.eye = sc.eye;
    if (!spec.look_at) spec.look_at = sc.look_at;
    if (!spec.up) spec.up = sc.up;
    if (!spec.fov_deg) spec.fov_deg = sc.fov_deg;
  }
  // A bad vector fails before any expensive work.
  const bvh::PinholeCamera cam = make_camera(spec, first_bounds, rc0.width, rc0.height);
  RenderConfig rc = rc0;
  const char* light_from = rc.light ? "--light" : given.light ? "scene" : "default";
  if (!rc.light) rc.light = given.light ? scene.light().position : default_light(cam, first_bounds);

  Clustering clusters;
  const bool use_clusters = !opt.clusters.empty();
  if (use_clusters) {
    clusters = read_clusters_recorded(opt.clusters, scene.rest(), manifest);
  }
  std::size_t static_tris = 0;
  for (std::size_t p = 0; p < scene.part_count(); ++p)
    if (scene.is_static(p)) static_tris += scene.triangle_offset(p + 1) - scene.triangle_offset(p);
  const std::size_t moving_tris = mesh.triangle_count() - static_tris;

  // Build: the static BVH once, the moving BVH (construction, then one per-frame update whose
  // stage times are the steady-state figures of the first frame).
  SceneTracerConfig tcfg;
  tcfg.clusters = use_clusters ? &clusters : nullptr;
  tcfg.cluster_group_size = opt.cluster_group_size;
  tcfg.origin = first_bounds.center();
  SceneTracer tracer(mesh, PartLayout::of(scene), tcfg);
  manifest.add_timing_ms("static_build", tracer.static_build_ms());
  manifest.add_timing_ms("setup", tracer.moving_setup_ms());
  const char* bvh_kind = use_clusters ? "clusters" : "triangles";

  OutputDir dir(opt.out_dir);
  nlohmann::json images = nlohmann::json::object();
  CsvTable csv(trace_csv_columns());
  const unsigned threads = effective_threads(rc.threads);
  double render_ms = 0, write_ms = 0;
  nlohmann::json per_frame = nlohmann::json::array();

  out << fmt::format("{}: {} triangles ({} static, {} moving; {} part(s)), {}; {}x{} pixels, {} thread(s); "
                     "static BVH {:.1f} ms{}\n",
                     arg, mesh.triangle_count(), static_tris, moving_tris, scene.part_count(),
                     tracer.all_static() ? fmt::format("one {} BVH built once", use_clusters ? "cluster" : "triangle")
                     : tracer.split() ? fmt::format("static triangle BVH + moving {} BVH", use_clusters ? "cluster" : "triangle")
                                      : fmt::format("one {} BVH updated per frame", use_clusters ? "cluster" : "triangle"),
                     rc.width, rc.height, threads, tracer.static_build_ms(),
                     tracer.all_static() ? "" : fmt::format(", moving BVH setup {:.1f} ms", tracer.moving_setup_ms()));
  out << fmt::format("{:>6} {:>10} {:>9} {:<8} {:>10} {:>10} {:>10} {:>9} {:>10} {:>10}\n", "frame", "update_ms",
                     "build_ms", "pass", "rays", "hits", "trace_ms", "Mrays/s", "nodes/ray", "tris/ray");

  for (std::int64_t f = range.first; f <= range.last; ++f) {
    if (f != range.first) {
      t0 = Clock::now();
      scene.positions(double(f), mesh.positions(), /*update_static=*/false);
      positions_ms += ms_since(t0);
    }
    tracer.update(mesh.positions());
    const bvh::StageTimes st = tracer.moving_times();
    const double update_ms = st.vertices_ms + st.boxes_ms, build_ms = st.total_ms() - update_ms;

    t0 = Clock::now();
    const Render r = render_view(tracer.target(), mesh, cam, rc);
    render_ms += ms_since(t0);

    t0 = Clock::now();
    const std::string suffix = sequence ? fmt::format("_{:04d}", f) : "";
    auto put = [&](const std::string& base, const RgbImage& img, nlohmann::json legend) {
      const std::string name = base + suffix + ".png";
      write_image(dir.path(name), img);
      manifest.add_output(name);
      images[name] = std::move(legend);
    };
    ColorLegend dl, nl, tl;  // filled by the image functions, so those run before the legends are read
    const RgbImage depth = depth_image(r, dl), nodes = nodes_image(r, nl), tris = triangles_image(r, tl);
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
    if (f == range.first) {
      write_image(dir.path("cost_legend.png"), viridis_bar(256, 16));
      manifest.add_output("cost_legend.png");
      images["cost_legend.png"] = {{"quantity", "colour bar of the cost images"}, {"colormap", "viridis"},
                                   {"note", "left = legend min, right = legend max"}};
    }
    if (rc.ao_samples > 0)
      put("ao", ao_image(r),
          {{"quantity", "ambient occlusion (fraction unoccluded)"}, {"colormap", "grey"}, {"min", 0}, {"max", 1},
           {"note", "missed rays: black"}});
    write_ms += ms_since(t0);

    const std::size_t rays = r.primary_stats.rays;
    const bool first = f == range.first;
    csv.add_row({arg, std::string(bvh_kind), std::uint64_t(mesh.triangle_count()),
                 std::uint64_t(use_clusters ? clusters.cluster_count() : 0), std::int64_t(rc.width), std::int64_t(rc.height),
                 std::uint64_t(threads), first ? tracer.moving_setup_ms() : 0.0, build_ms, std::uint64_t(rays),
                 r.primary_stats.hits, r.primary_stats.trace_ms, r.primary_stats.mrays_per_s(),
                 r.primary_stats.nodes_visited, r.primary_stats.triangles_tested,
                 per_ray(r.primary_stats.nodes_visited, rays), per_ray(r.primary_stats.triangles_tested, rays),
                 r.shadow_stats.rays, r.shadow_stats.hits, r.shadow_stats.trace_ms, r.shadow_stats.mrays_per_s(),
                 std::int64_t(rc.ao_samples), r.ao_stats.rays, r.ao_stats.hits, r.ao_stats.trace_ms,
                 r.ao_stats.mrays_per_s(), f, std::uint64_t(static_tris), std::uint64_t(moving_tris),
                 first ? tracer.static_build_ms() : 0.0, update_ms});
    per_frame.push_back({{"frame", f}, {"rays", rays}, {"hits", r.primary_stats.hits},
                         {"stage_ms", {{"vertices", st.vertices_ms}, {"boxes", st.boxes_ms}, {"build", st.build_ms},
                                       {"collapse", st.collapse_ms}, {"leaf_data", st.leaf_data_ms},
                                       {"refit", st.refit_ms}}}});

    auto line = [&](const char* name, const PassStats& s, bool lead) {
      out << (lead ? fmt::format("{:>6} {:>10.2f} {:>9.2f} ", f, update_ms, build_ms) : fmt::format("{:>28}", ""))
          << fmt::format("{:<8} {:>10} {:>10} {:>10.2f} {:>9.2f} {:>10.2f} {:>10.2f}\n", name, s.rays, s.hits,
                         s.trace_ms, s.mrays_per_s(), per_ray(s.nodes_visited, s.rays), per_ray(s.triangles_tested, s.rays));
    };
    line("primary", r.primary_stats, true);
    if (rc.shadows) line("shadow", r.shadow_stats, false);
    if (rc.ao_samples > 0) line("ao", r.ao_stats, false);
  }
  manifest.add_timing_ms("positions", positions_ms);
  manifest.add_timing_ms("render", render_ms);
  t0 = Clock::now();
  dir.write("trace.csv", csv.str());
  manifest.add_output("trace.csv");
  manifest.add_output("manifest.json");

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
  if (use_clusters) manifest.set_parameter("cluster_group_size", opt.cluster_group_size);
  manifest.set_parameter("width", rc.width);
  manifest.set_parameter("height", rc.height);
  manifest.set_parameter("threads", threads);
  manifest.set_parameter("shadows", rc.shadows);
  manifest.set_parameter("ao_samples", rc.ao_samples);
  manifest.set_parameter("ao_distance_rel", rc.ao_distance_rel);
  manifest.set_parameter("seed", rc.seed);
  manifest.set_parameter("camera", {{"eye", vec_json(cam.eye)}, {"forward", vec_json(cam.forward)},
                                    {"right", vec_json(cam.right)}, {"up", vec_json(cam.up)},
                                    {"fov_y_deg", cam.fov_y_deg}, {"from_scene", given.camera},
                                    {"given", {{"eye", bool(opt.camera.eye)}, {"look_at", bool(opt.camera.look_at)},
                                               {"up", bool(opt.camera.up)}, {"fov", bool(opt.camera.fov_deg)}}}});
  manifest.set_parameter("light", {{"position", vec_json(*rc.light)}, {"from", light_from}});
  manifest.set_parameter("ray_offset", "origin = p + 2^-18 M n, M = max |coordinate| of bounds and p in the trace frame");
  manifest.set_result("images", images);
  manifest.set_result("rays", std::uint64_t(rc.width) * std::uint64_t(rc.height));  // per frame
  manifest.set_result("hits", per_frame.empty() ? nlohmann::json(0) : per_frame[0]["hits"]);  // first frame
  manifest.set_result("frames", per_frame);
  manifest.add_timing_ms("write", write_ms + ms_since(t0));
  nlohmann::json mj = manifest.to_json();
  mj["schema"] = "ptc-trace/2";
  dir.write("manifest.json", dump_json(mj));
  dir.commit();

  const std::string names = "{shaded,depth,normal,cost_nodes,cost_triangles" + std::string(rc.ao_samples > 0 ? ",ao" : "") + "}";
  out << "wrote " << opt.out_dir.string() << "/"
      << (sequence ? fmt::format("{}_{:04d}..{:04d}.png", names, range.first, range.last) : names + ".png")
      << ", cost_legend.png, trace.csv, manifest.json\n";
}

void cmd_bench(const BenchCommandOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw InputError("", "", "--out", "an output directory is required");
  PeerBenchConfig c = opt.config;
  if (c.width < 1 || c.height < 1 || c.width > 16384 || c.height > 16384)
    throw InputError("", "", "--width/--height", "the image size must be 1..16384 pixels per side");
  if (c.threads < 1) throw InputError("", "", "--threads", "must be >= 1");
  // --frames: "A:B" (a range of scene frames) or "N" (N frames from the scene's first; for a
  // static scene under the stand-in deformation, frames 0 .. N-1 as before).
  std::optional<FrameRange> asked;
  std::optional<std::int64_t> count;
  if (opt.frames) {
    if (opt.frames->find(':') != std::string::npos) {
      asked = parse_frame_range(*opt.frames);
    } else {
      std::int64_t n = 0;
      const std::string& f = *opt.frames;
      const auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), n);
      if (f.empty() || ec != std::errc() || p != f.data() + f.size() || n < 1 || n > 100000)
        throw InputError("", "", "--frames", fmt::format("'{}' is neither a frame count 1..100000 nor a range A:B", f.substr(0, 32)));
      count = n;
    }
  } else if (c.frames < 1) {
    throw InputError("", "", "--frames", "must be >= 1");
  }
  RunManifest manifest("bench", opt.argv);
  const std::string arg = opt.input.string();
  Scene scene = open_recorded(opt.input, opt.scene_options, manifest);
  const Mesh& mesh = scene.rest();
  const bool animated = !scene.all_static();
  if (animated && opt.deform_given && c.deformation != Deformation::None)
    throw InputError("", "", "--deform",
                     fmt::format("'{}' is animated: the stand-in deformation applies to static scenes (mesh files) only",
                                 arg));
  FrameRange range;
  if (asked)
    range = *asked;
  else if (count)
    range = {animated ? scene.frames().first : 0, (animated ? scene.frames().first : 0) + *count - 1};
  else
    range = animated ? scene.frames() : FrameRange{0, c.frames - 1};
  if (range.count() > 100000) throw InputError("", "", "--frames", "at most 100000 frames");
  if (animated) check_range(scene, range, arg, "--frames");
  c.first_frame = range.first;
  c.frames = static_cast<int>(range.count());
  if (animated) {
    c.deformation = Deformation::None;
    c.positions = [&scene](std::int64_t f, std::span<Vec3> p) { scene.positions(double(f), p, true); };
    c.renumber_positions = [&scene](std::span<const std::uint32_t> to_old) { scene.renumber_vertices(to_old); };
    c.part_offsets.assign(scene.vertex_offsets().begin(), scene.vertex_offsets().end());
  }
  // Camera as for trace: given fields > the scene's camera > framing the rest bounds.
  if (scene_view_given(arg).camera) {
    const SceneCamera& sc = scene.camera();
    if (!c.camera.eye) c.camera.eye = sc.eye;
    if (!c.camera.look_at) c.camera.look_at = sc.look_at;
    if (!c.camera.up) c.camera.up = sc.up;
    if (!c.camera.fov_deg) c.camera.fov_deg = sc.fov_deg;
  }
  (void)make_camera(c.camera, mesh.bounds(), c.width, c.height);  // bad vectors fail before any work
  // The output directory is checked before the (long) run, so a refused target costs nothing.
  OutputDir dir(opt.out_dir);
  Clustering given;
  if (!opt.clusters.empty()) {
    given = read_clusters_recorded(opt.clusters, mesh, manifest);
  }
  const auto t0 = Clock::now();
  const PeerBenchResult r = run_peer_bench(mesh, opt.clusters.empty() ? nullptr : &given, c);
  manifest.add_timing_ms("bench", ms_since(t0));
  if (r.cluster_ms > 0) manifest.add_timing_ms("cluster", r.cluster_ms);
  manifest.add_timing_ms("cluster_scene_setup", r.cluster_scene_setup_ms);
  if (c.cluster_vertex_order) manifest.add_timing_ms("renumber_vertices", r.renumber_ms);

  dir.write("bench.csv", bench_csv(r).str());
  dir.write("summary.csv", bench_summary_csv(r).str());
  for (const char* f : {"bench.csv", "summary.csv", "manifest.json"}) manifest.add_output(f);
  manifest.set_parameter("scene", arg);
  manifest.set_parameter("frames", c.frames);
  manifest.set_parameter("frame_range", {range.first, range.last});
  manifest.set_parameter("motion", animated ? "scene" : "stand-in deformation");
  manifest.set_parameter("camera_from_scene", scene_view_given(arg).camera);
  manifest.set_parameter("width", c.width);
  manifest.set_parameter("height", c.height);
  manifest.set_parameter("threads", c.threads);
  manifest.set_parameter("deformation", animated ? "none (scene positions)" : to_string(c.deformation));
  manifest.set_parameter("clustering", r.clustering);
  manifest.set_parameter("cluster_leaf", bvh::to_string(c.cluster_leaf));
  manifest.set_parameter("cluster_group_size", c.cluster_group_size);
  manifest.set_parameter("vertex_order", r.vertex_order);
  manifest.set_parameter("tie_rel", c.tie_rel);
  manifest.set_parameter("embree_set_affinity", false);
  manifest.set_result("triangles", r.triangles);
  manifest.set_result("clusters", r.clusters);
  manifest.set_result("rays", r.rays);
  manifest.set_result("fused_vertex_pass", r.fused_vertex_pass);
  if (animated) manifest.set_result("scene_after_renumbering", scene.describe());
  manifest.set_result("median_frames", nlohmann::json::array({r.median_first_frame, c.frames - 1}));
  nlohmann::json mj = manifest.to_json();
  mj["schema"] = "ptc-bench/1";
  dir.write("manifest.json", dump_json(mj));
  dir.commit();

  out << fmt::format("{}: {} triangles, {} vertices; {} clusters ({}{}; cluster scene setup {:.1f} ms); frames {}..{} "
                     "of {}; {} thread(s)\n",
                     arg, r.triangles, r.vertices, r.clusters, r.clustering,
                     r.cluster_ms > 0 ? fmt::format(", clustered in {:.0f} ms", r.cluster_ms) : "",
                     r.cluster_scene_setup_ms, range.first, range.last,
                     animated ? std::string("the scene") : fmt::format("'{}'", to_string(c.deformation)), c.threads);
  out << bench_table(r);
  out << "wrote " << opt.out_dir.string() << "/{bench.csv,summary.csv,manifest.json}\n";
}

}  // namespace ptc
