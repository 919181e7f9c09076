#include "analysis/trace_command.h"

#include <tbb/info.h>

#include <chrono>
#include <memory>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/csv.h"
#include "analysis/manifest.h"
#include "analysis/output_dir.h"
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
          "ao_samples", "ao_rays", "ao_occluded", "ao_trace_ms", "ao_mrays_per_s"};
}

void cmd_trace(const TraceCommandOptions& opt, const ImageWriter& write_image, std::ostream& out) {
  if (opt.out_dir.empty()) throw InputError("", "", "--out", "an output directory is required");
  const RenderConfig& rc = opt.render;
  if (rc.width < 1 || rc.height < 1 || rc.width > 16384 || rc.height > 16384)
    throw InputError("", "", "--width/--height", "the image size must be 1..16384 pixels per side");
  if (rc.ao_samples < 0) throw InputError("", "", "--ao", "the sample count must be >= 0");
  if (rc.light && !(std::isfinite(rc.light->x()) && std::isfinite(rc.light->y()) && std::isfinite(rc.light->z())))
    throw InputError("", "", "--light", "not a finite vector");
  RunManifest manifest("trace", opt.argv);
  auto t0 = Clock::now();
  const LoadedMesh lm = read_mesh(opt.input);
  manifest.add_timing_ms("read", ms_since(t0));
  manifest.add_input(opt.input);
  const Mesh& mesh = lm.mesh;

  // The camera first: a bad vector fails before any expensive work.
  const bvh::PinholeCamera cam = make_camera(opt.camera, mesh.bounds(), rc.width, rc.height);

  Clustering clusters;
  const bool use_clusters = !opt.clusters.empty();
  if (use_clusters) {
    t0 = Clock::now();
    clusters = read_clusters(opt.clusters, mesh);
    manifest.add_timing_ms("read_clusters", ms_since(t0));
    std::error_code ec;
    manifest.add_input(std::filesystem::is_directory(opt.clusters, ec) ? opt.clusters / "triangles.csv" : opt.clusters);
  }

  // Build: construction (includes the per-clustering layout), then one per-frame update whose
  // stage times are the steady-state build time.
  t0 = Clock::now();
  std::unique_ptr<bvh::TriangleScene> ts;
  std::unique_ptr<bvh::ClusterScene> cs;
  if (use_clusters)
    cs = std::make_unique<bvh::ClusterScene>(mesh, bvh::view_of(clusters));
  else
    ts = std::make_unique<bvh::TriangleScene>(mesh);
  const double setup_ms = ms_since(t0);
  if (cs) cs->update(mesh.positions()); else ts->update(mesh.positions());
  const bvh::StageTimes st = cs ? cs->times() : ts->times();
  const bvh::TraceData& data = cs ? cs->data() : ts->data();
  manifest.add_timing_ms("setup", setup_ms);
  manifest.add_timing_ms("build", st.total_ms());

  t0 = Clock::now();
  const Render r = render_view(data, mesh, cam, rc);
  manifest.add_timing_ms("render", ms_since(t0));

  t0 = Clock::now();
  OutputDir dir(opt.out_dir);
  nlohmann::json images = nlohmann::json::object();
  auto put = [&](const std::string& name, const RgbImage& img, nlohmann::json legend) {
    write_image(dir.path(name), img);
    manifest.add_output(name);
    images[name] = std::move(legend);
  };
  ColorLegend dl, nl, tl;  // filled by the image functions, so those run before the legends are read
  const RgbImage depth = depth_image(r, dl), nodes = nodes_image(r, nl), tris = triangles_image(r, tl);
  put("shaded.png", shaded_image(r),
      {{"quantity", "Lambert shading"},
       {"note", fmt::format("albedo 0.9, ambient 0.2{}, diffuse 0.8{}; background (32,32,40)",
                            rc.ao_samples ? " x AO" : "", rc.shadows ? " x shadow" : "")}});
  put("depth.png", depth, legend_json(dl));
  put("normal.png", normal_image(r),
      {{"quantity", "facing geometric normal (world)"}, {"colormap", "rgb = 255 (n + 1) / 2"}, {"min", -1}, {"max", 1},
       {"note", "missed rays: black"}});
  put("cost_nodes.png", nodes, legend_json(nl));
  put("cost_triangles.png", tris, legend_json(tl));
  put("cost_legend.png", viridis_bar(256, 16), {{"quantity", "colour bar of the cost images"}, {"colormap", "viridis"},
                                                {"note", "left = legend min, right = legend max"}});
  if (rc.ao_samples > 0)
    put("ao.png", ao_image(r),
        {{"quantity", "ambient occlusion (fraction unoccluded)"}, {"colormap", "grey"}, {"min", 0}, {"max", 1},
         {"note", "missed rays: black"}});

  const std::size_t rays = r.primary_stats.rays;
  const unsigned threads = effective_threads(rc.threads);
  CsvTable csv(trace_csv_columns());
  csv.add_row({opt.input.string(), std::string(use_clusters ? "clusters" : "triangles"), std::uint64_t(mesh.triangle_count()),
               std::uint64_t(use_clusters ? clusters.cluster_count() : 0), std::int64_t(rc.width), std::int64_t(rc.height),
               std::uint64_t(threads), setup_ms, st.total_ms(), std::uint64_t(rays), r.primary_stats.hits,
               r.primary_stats.trace_ms, r.primary_stats.mrays_per_s(), r.primary_stats.nodes_visited,
               r.primary_stats.triangles_tested, per_ray(r.primary_stats.nodes_visited, rays),
               per_ray(r.primary_stats.triangles_tested, rays), r.shadow_stats.rays, r.shadow_stats.hits,
               r.shadow_stats.trace_ms, r.shadow_stats.mrays_per_s(), std::int64_t(rc.ao_samples), r.ao_stats.rays,
               r.ao_stats.hits, r.ao_stats.trace_ms, r.ao_stats.mrays_per_s()});
  dir.write("trace.csv", csv.str());
  manifest.add_output("trace.csv");
  manifest.add_output("manifest.json");

  manifest.set_parameter("bvh", use_clusters ? "clusters" : "triangles");
  if (use_clusters) manifest.set_parameter("clusters", opt.clusters.string());
  manifest.set_parameter("width", rc.width);
  manifest.set_parameter("height", rc.height);
  manifest.set_parameter("threads", threads);
  manifest.set_parameter("shadows", rc.shadows);
  manifest.set_parameter("ao_samples", rc.ao_samples);
  manifest.set_parameter("ao_distance_rel", rc.ao_distance_rel);
  manifest.set_parameter("seed", rc.seed);
  manifest.set_parameter("camera", {{"eye", vec_json(cam.eye)}, {"forward", vec_json(cam.forward)},
                                    {"right", vec_json(cam.right)}, {"up", vec_json(cam.up)},
                                    {"fov_y_deg", cam.fov_y_deg}, {"given", {{"eye", bool(opt.camera.eye)},
                                    {"look_at", bool(opt.camera.look_at)}, {"up", bool(opt.camera.up)},
                                    {"fov", bool(opt.camera.fov_deg)}}}});
  manifest.set_parameter("light", vec_json(r.light));
  manifest.set_parameter("ray_offset", "origin = p + 2^-18 M n, M = max |coordinate| of bounds and p in the trace frame");
  manifest.set_result("images", images);
  manifest.set_result("rays", rays);
  manifest.set_result("hits", r.primary_stats.hits);
  manifest.set_result("stage_ms", {{"vertices", st.vertices_ms}, {"boxes", st.boxes_ms}, {"build", st.build_ms},
                                   {"collapse", st.collapse_ms}, {"leaf_data", st.leaf_data_ms}, {"refit", st.refit_ms}});
  manifest.add_timing_ms("write", ms_since(t0));
  nlohmann::json mj = manifest.to_json();
  mj["schema"] = "ptc-trace/1";
  dir.write("manifest.json", dump_json(mj));
  dir.commit();

  out << fmt::format("{}: {} triangles, {} BVH{}; {}x{} pixels, {} thread(s); setup {:.1f} ms, build {:.1f} ms\n",
                     opt.input.string(), mesh.triangle_count(), use_clusters ? "cluster" : "triangle",
                     use_clusters ? fmt::format(" ({} clusters)", clusters.cluster_count()) : "", rc.width, rc.height,
                     threads, setup_ms, st.total_ms());
  out << fmt::format("{:<8} {:>10} {:>10} {:>10} {:>9} {:>10} {:>10}\n", "pass", "rays", "hits", "trace_ms", "Mrays/s",
                     "nodes/ray", "tris/ray");
  auto line = [&](const char* name, const PassStats& s) {
    out << fmt::format("{:<8} {:>10} {:>10} {:>10.2f} {:>9.2f} {:>10.2f} {:>10.2f}\n", name, s.rays, s.hits, s.trace_ms,
                       s.mrays_per_s(), per_ray(s.nodes_visited, s.rays), per_ray(s.triangles_tested, s.rays));
  };
  line("primary", r.primary_stats);
  if (rc.shadows) line("shadow", r.shadow_stats);
  if (rc.ao_samples > 0) line("ao", r.ao_stats);
  out << "wrote " << opt.out_dir.string() << "/{shaded,depth,normal,cost_nodes,cost_triangles,cost_legend"
      << (rc.ao_samples > 0 ? ",ao" : "") << "}.png, trace.csv, manifest.json\n";
}

void cmd_bench(const BenchCommandOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw InputError("", "", "--out", "an output directory is required");
  const PeerBenchConfig& c = opt.config;
  if (c.frames < 1) throw InputError("", "", "--frames", "must be >= 1");
  if (c.width < 1 || c.height < 1 || c.width > 16384 || c.height > 16384)
    throw InputError("", "", "--width/--height", "the image size must be 1..16384 pixels per side");
  if (c.threads < 1) throw InputError("", "", "--threads", "must be >= 1");
  RunManifest manifest("bench", opt.argv);
  auto t0 = Clock::now();
  const LoadedMesh lm = read_mesh(opt.input);
  manifest.add_timing_ms("read", ms_since(t0));
  manifest.add_input(opt.input);
  (void)make_camera(c.camera, lm.mesh.bounds(), c.width, c.height);  // bad vectors fail before any work
  // The output directory is checked before the (long) run, so a refused target costs nothing.
  OutputDir dir(opt.out_dir);
  Clustering given;
  if (!opt.clusters.empty()) {
    t0 = Clock::now();
    given = read_clusters(opt.clusters, lm.mesh);
    manifest.add_timing_ms("read_clusters", ms_since(t0));
    std::error_code ec;
    manifest.add_input(std::filesystem::is_directory(opt.clusters, ec) ? opt.clusters / "triangles.csv" : opt.clusters);
  }
  t0 = Clock::now();
  const PeerBenchResult r = run_peer_bench(lm.mesh, opt.clusters.empty() ? nullptr : &given, c);
  manifest.add_timing_ms("bench", ms_since(t0));
  if (r.cluster_ms > 0) manifest.add_timing_ms("cluster", r.cluster_ms);
  manifest.add_timing_ms("cluster_scene_setup", r.cluster_scene_setup_ms);

  dir.write("bench.csv", bench_csv(r).str());
  dir.write("summary.csv", bench_summary_csv(r).str());
  for (const char* f : {"bench.csv", "summary.csv", "manifest.json"}) manifest.add_output(f);
  manifest.set_parameter("frames", c.frames);
  manifest.set_parameter("width", c.width);
  manifest.set_parameter("height", c.height);
  manifest.set_parameter("threads", c.threads);
  manifest.set_parameter("deformation", to_string(c.deformation));
  manifest.set_parameter("clustering", r.clustering);
  manifest.set_parameter("cluster_leaf", bvh::to_string(c.cluster_leaf));
  manifest.set_parameter("tie_rel", c.tie_rel);
  manifest.set_parameter("embree_set_affinity", false);
  manifest.set_result("triangles", r.triangles);
  manifest.set_result("clusters", r.clusters);
  manifest.set_result("rays", r.rays);
  manifest.set_result("median_frames", nlohmann::json::array({r.median_first_frame, c.frames - 1}));
  nlohmann::json mj = manifest.to_json();
  mj["schema"] = "ptc-bench/1";
  dir.write("manifest.json", dump_json(mj));
  dir.commit();

  out << fmt::format("{}: {} triangles, {} vertices; {} clusters ({}{}; cluster scene setup {:.1f} ms); {} frames of "
                     "'{}'; {} thread(s)\n",
                     opt.input.string(), r.triangles, r.vertices, r.clusters, r.clustering,
                     r.cluster_ms > 0 ? fmt::format(", clustered in {:.0f} ms", r.cluster_ms) : "",
                     r.cluster_scene_setup_ms, c.frames, to_string(c.deformation), c.threads);
  out << bench_table(r);
  out << "wrote " << opt.out_dir.string() << "/{bench.csv,summary.csv,manifest.json}\n";
}

}  // namespace ptc
