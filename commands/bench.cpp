// `ptc bench`.
#include "commands/bench.h"

#include <iostream>
#include <ostream>
#include <string_view>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "commands/args.h"
#include "commands/output_dir.h"
#include "commands/scene_args.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/core/strings.h"

namespace ptc {

void cmd_bench(const BenchCommandOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw UsageError("--out", "an output directory is required");
  PeerBenchConfig c = opt.config;
  check_image_size(c.width, c.height);
  c.threads = resolve_threads(c.threads);
  refuse_overwriting_input(opt.out_dir, opt.input);
  refuse_overwriting_input(opt.out_dir, opt.clusters);
  RunManifest manifest("bench", opt.argv, "ptc-bench/8");
  const std::string arg = opt.input.string();
  MovingScene ms = open_moving_scene(opt.input, opt.scene_options, opt.deform, opt.frames, opt.extend_frames, manifest);
  Scene& scene = ms.scene;
  const FrameRange range = ms.range;
  const std::string& motion = ms.motion;
  c.frames = range;
  // The cluster size: the flag, else the scene's own, else the bench's default.
  const char* max_count_from = "--max-count";
  if (opt.max_count) c.max_count = *opt.max_count;
  else if (scene.cluster_max_count()) c.max_count = *scene.cluster_max_count(), max_count_from = "scene";
  else max_count_from = "default";
  c.camera = camera_for(c.camera, scene);
  if (opt.light && !opt.light->allFinite()) throw UsageError("--light", "not a finite vector");
  // Bad vectors fail before any work; the light as `ptc trace` picks it (flag > scene > default).
  const Box3 shape = scene.rest().referenced_bounds();  // (unreferenced vertices are not framed)
  const bvh::PinholeCamera cam = make_camera(c.camera, shape, c.width, c.height, arg);
  c.made_camera = cam;  // (the bench's rays: the same camera, framed once)
  check_eye_reach(cam, opt.config.camera, scene, arg);
  const LightChoice light = opt.shadows ? light_for(opt.light, scene, cam, shape, arg) : LightChoice{};  // (only the shadow rays' target)
  if (opt.shadows) c.light = light.position;
  // The output directory is checked before the (long) run, so a refused target costs nothing.
  OutputDir dir(opt.out_dir);
  std::optional<Clustering> given;  // (handed over to the bench, which renames it with the vertices)
  if (!opt.clusters.empty()) given = read_clusters_recorded(opt.clusters, scene.rest(), manifest);
  Stopwatch sw;
  PeerBenchResult r;
  try {
    r = run_peer_bench(scene, std::move(given), c);
  } catch (const bvh::FrameRangeError& e) {
    throw InputError(arg, "", e.frame ? fmt::format("frame {}", *e.frame) : std::string(), e.what());
  }
  manifest.add_timing_ms("bench", sw.ms());
  {  // as `ptc trace` says it: a view where no ray meets the mesh measures the background only
    std::uint64_t hits = 0, rays = 0;
    for (const BenchRow& row : r.rows)
      if (row.config == "ours_triangles") hits += row.hits, rays += row.rays;
    if (rays > 0 && hits == 0)
      std::cerr << "ptc: note: no primary ray hit the mesh in any frame (the camera sees past it or from inside it: "
                   "give --eye and --look-at); the times measure empty rays\n";
  }
  if (r.cluster_ms > 0) manifest.add_timing_ms("cluster", r.cluster_ms);
  manifest.add_timing_ms("cluster_scene_setup", r.cluster_scene_setup_ms);
  if (c.vertex_order == bvh::VertexOrder::Clusters) manifest.add_timing_ms("renumber_vertices", r.renumber_ms);

  const Table bench = bench_table(r), summary = bench_summary_table(r);
  dir.write("bench.csv", bench.csv.str());
  dir.write("summary.csv", summary.csv.str());
  manifest.add_output("bench.csv", bench.schema.id());
  manifest.add_output("summary.csv", summary.schema.id());
  manifest.set_parameter("scene", arg);
  manifest.set_parameter("frames", {range.first, range.last});
  manifest.set_parameter("motion", motion);
  manifest.set_parameter("camera_from_scene", scene.has_own_camera());
  // The camera the rays came from, as ptc trace records it (the bench's was only in argv).
  manifest.set_parameter("camera", camera_json(cam, scene, opt.config.camera));
  manifest.set_parameter("width", c.width);
  manifest.set_parameter("height", c.height);
  manifest.set_parameter("threads", c.threads);
  manifest.set_parameter("clustering", r.clustering);
  if (opt.clusters.empty()) {
    manifest.set_parameter("max_count", c.max_count);
    manifest.set_parameter("max_count_from", max_count_from);  // --max-count, scene or default
    manifest.set_parameter("adjacency", to_string(c.adjacency));
  }
  manifest.set_parameter("cluster_leaf", bvh::to_string(c.cluster_leaf));
  manifest.set_parameter("leaf_format", bvh::to_string(c.leaf_format));
  // The group size used (0: the plain build; --cluster-groups N unset, the default N = 32 shrinks
  // for a scene of under 32 x 1024 clusters, bvh::cluster_group_size_used), and the minimum of groups.
  manifest.set_parameter("cluster_group_size", r.cluster_group_size);
  manifest.set_parameter("min_cluster_groups", c.min_cluster_groups);
  manifest.set_parameter("group_trees", r.cluster_group_size > 1 ? std::string(bvh::to_string(c.group_trees))
                                                                  : std::string("none (plain build)"));
  manifest.set_parameter("vertex_order", r.vertex_order);
  // The triangle fallback's swelling threshold (0: off), and the frames traced on it.
  manifest.set_parameter("cluster_fallback", c.cluster_fallback);
  {
    std::uint64_t fell = 0;
    for (const BenchRow& row : r.rows) fell += row.fallback ? 1 : 0;
    manifest.set_result("cluster_fallback_frames", fell);
  }
  // The fallback's refit limit (0: rebuilt every frame), and the frames on which it kept its tree.
  manifest.set_parameter("fallback_refit", c.cluster_fallback > 0 ? c.fallback_refit : 0.0);
  {
    std::uint64_t kept = 0;
    for (const BenchRow& row : r.rows) kept += row.fallback_refit ? 1 : 0;
    manifest.set_result("fallback_refit_frames", kept);
  }
  // The fallback's SAH: for rays from the camera's eye (the point), for their directions (the
  // weights), or plain (neither: weights 1, 1, 1, no point).
  manifest.set_parameter("fallback_sah", bvh::to_string(r.fallback_sah));
  manifest.set_parameter("fallback_area_weights", std::vector<double>(r.fallback_area_weights.begin(), r.fallback_area_weights.end()));
  manifest.set_parameter("fallback_area_eye", r.fallback_area_eye ? vec_json(*r.fallback_area_eye) : nlohmann::json(nullptr));
  manifest.set_parameter("tie_rel", c.tie.rel_t);
  manifest.set_parameter("embree_set_affinity", false);
  manifest.set_parameter("shadows", opt.shadows);
  manifest.set_parameter("packets", opt.config.packets);
  manifest.set_parameter("isa", bvh::to_string(r.isa));  // our tracer's variant (Embree keeps its own)
  if (opt.config.packets) manifest.set_parameter("embree_packet_width", opt.config.embree_packet_width);
  if (opt.config.packets && opt.shadows)
    manifest.set_parameter("embree_shadow_hint", std::string(to_string(opt.config.embree_shadow_hint)));
  if (opt.shadows) manifest.set_parameter("shadow_order", opt.config.shadow_morton ? "morton" : "pixel");
  if (opt.shadows) manifest.set_parameter("light", {{"position", vec_json(light.position)}, {"from", light.from}});
  manifest.set_result("triangles", r.triangles);
  manifest.set_result("clusters", r.clusters);
  manifest.set_result("rays", r.rays);
  manifest.set_result("fused_vertex_pass", r.fused_vertex_pass);
  manifest.set_result("cluster_leaves", {{"format", bvh::to_string(r.cluster_leaves.format)},
                                         {"units", r.cluster_leaves.units},
                                         {"triangles", r.cluster_leaves.triangles},
                                         {"vertices", r.cluster_leaves.vertices},
                                         {"lanes", r.cluster_leaves.lanes},
                                         {"estimated_blocks_bytes", r.cluster_leaf_estimate.blocks},
                                         {"estimated_tables_bytes", r.cluster_leaf_estimate.tables}});
  manifest.set_result("scene_after_renumbering", scene.describe());
  manifest.set_result("median_frames",  // places in the run (0: the run's first frame)
                      nlohmann::json::array({r.median_first_frame, static_cast<int>(range.count()) - 1}));
  manifest.set_result("median_scene_frames",  // the same frames by their scene frame numbers
                      nlohmann::json::array({range.first + r.median_first_frame, range.last}));
  (void)commit_with_manifest(dir, manifest);

  if (opt.json) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& s : r.summary)
      j.push_back({{"config", s.config}, {"update_ms", s.update_ms}, {"build_ms", s.build_ms},
                   {"update_build_ms", s.update_build_ms}, {"trace_ms", s.trace_ms}, {"mrays_per_s", s.mrays_per_s},
                   {"shadow_ms", s.shadow_ms}, {"whole_frame_ms", s.whole_frame_ms},
                   {"mismatches", s.mismatches}, {"ties", s.ties}, {"shadow_mismatches", s.shadow_mismatches}});
    out << dump_json({{"schema", "ptc-bench-medians/2"}, {"medians", j}});
    return;
  }
  out << fmt::format("{}: {}, {}; {} ({}{}; cluster scene setup {:.1f} ms); frames {}..{} ({}); {}\n", arg,
                     counted(r.triangles, "triangle"), counted(r.vertices, "vertex", "vertices"),
                     counted(r.clusters, "cluster"),
                     r.clustering + (opt.clusters.empty() && max_count_from == std::string_view("scene")
                                         ? " (the scene's cluster size)"
                                         : ""),
                     r.cluster_ms > 0 ? fmt::format(", clustered in {:.0f} ms", r.cluster_ms) : "",
                     r.cluster_scene_setup_ms, range.first, range.last, motion, counted(c.threads, "thread"));
  out << bench_text(r);
  out << "wrote " << opt.out_dir.string() << "/{bench.csv,summary.csv,manifest.json}\n";
}

}  // namespace ptc
