// `ptc bench SCENE [--clusters DIR | --max-count N --adjacency A] [--frames A:B] [--data-dir DIR] [--width W --height H]
// [--threads T] [--deform KIND|none] [--vertex-order clusters|input] [--json] --out DIR` (commands/bench.h).
#include <cmath>
#include <iostream>
#include <optional>
#include <string>

#include <tbb/info.h>

#include "commands/bench.h"
#include "apps/ptc/cli.h"

namespace ptc::cli {

namespace {
struct BenchArgs {
  BenchCommandOptions opt;
  SceneArg scene;
  CameraArgs camera;
  GroupTreesArg group_trees;
  std::string deform, cluster_leaf = "linear", leaf_format = "auto", frames, vertex_order = "clusters", adjacency = "auto", isa = "auto";
  std::string embree_shadow_hint = "best", shadow_order = "pixel";
  FallbackFlags fallback;
  std::uint32_t max_count = kBenchDefaultMaxCount;
  CLI::App* app = nullptr;
};

}  // namespace

void register_bench(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<BenchArgs>();
  auto& cfg = a->opt.config;
  auto* c = ctx.add(app, "bench",
                    "our triangle and cluster BVHs beside Embree MEDIUM/LOW/REFIT over animated frames, same rays",
                    [a, &ctx] {
                      auto& o = a->opt;
                      if (a->app->count("--deform")) o.deform = a->deform;
                      o.config.cluster_leaf =
                          *bvh::parse_cluster_leaf(a->cluster_leaf);
                      o.config.leaf_format = *bvh::parse_leaf_format_choice(a->leaf_format);
                      if (o.config.leaf_format == bvh::LeafFormatChoice::Tables &&
                          o.config.cluster_leaf != bvh::ClusterLeaf::Linear)
                        throw UsageError("--leaf-format", "tables needs linear cluster leaves (--cluster-leaf block-tree keeps blocks)");
                      if (a->app->count("--cluster-groups")) o.config.min_cluster_groups = 0;  // (given: exact)
                      o.config.group_trees = a->group_trees.get(o.config.cluster_group_size > 1,
                                                                "the two-level build (--cluster-groups N, N > 1)");
                      o.config.threads = static_cast<unsigned>(ctx.threads);  // 0: all cores
                      // Embree's device takes at most the machine's threads (it lowers threads=N to
                      // them, and oneTBB then warns that our N-thread arenas get fewer workers): the two
                      // sides would not run with the same threads.
                      if (const int cores = tbb::info::default_concurrency(); ctx.threads > cores)
                        throw UsageError("--threads", std::to_string(ctx.threads) + " threads on a machine that runs " +
                                                          std::to_string(cores) +
                                                          " at once: Embree would take " + std::to_string(cores) +
                                                          ", so both sides could not run with the same threads");
                      o.config.vertex_order = *bvh::parse_vertex_order(a->vertex_order);
                      o.config.adjacency = *parse_cluster_adjacency(a->adjacency);
                      o.config.isa = *bvh::parse_trace_isa(a->isa);
                      o.config.embree_shadow_hint = *parse_embree_shadow_hint(a->embree_shadow_hint);
                      o.config.cluster_fallback = *parse_cluster_fallback(a->fallback.swelling);
                      o.config.fallback_refit = *parse_fallback_refit(a->fallback.refit);
                      o.config.fallback_sah = *bvh::parse_fallback_sah(a->fallback.sah);
                      a->fallback.require_fallback(o.config.cluster_fallback > 0);
                      if (o.config.isa != bvh::TraceIsa::Auto && bvh::resolve(o.config.isa) != o.config.isa)
                        throw UsageError("--isa", std::string("this CPU has no ") +
                                                      (o.config.isa == bvh::TraceIsa::Avx512 || o.config.isa == bvh::TraceIsa::Avx512Vl
                                                           ? "AVX-512 (F, VL, DQ and BW)"
                                                           : "AVX2") +
                                                      "; the widest it has is " + bvh::to_string(bvh::resolve(bvh::TraceIsa::Auto)));
                      // Our packet path is AVX2 / AVX-512 code; the baseline variant would trace single
                      // rays while the run says packets.
                      if (o.config.packets && bvh::resolve(o.config.isa) == bvh::TraceIsa::Sse2)
                        throw UsageError("--packets", o.config.isa == bvh::TraceIsa::Sse2
                                                          ? "our packet path needs avx2, avx512vl or avx512 (--isa sse2 traces single rays)"
                                                          : "our packet path needs AVX2, which this CPU does not have");
                      if (a->app->count("--frames")) o.frames = a->frames;
                      if (a->app->count("--max-count")) o.max_count = a->max_count;
                      o.input = a->scene.input;
                      a->scene.apply(o.scene_options);
                      o.config.camera = a->camera.spec();
                      o.light = a->camera.light_position();
                      if (a->app->count("--light") && !o.shadows)  // (the light is only the shadow rays' target)
                        throw UsageError("--light", "needs shadow rays (drop --no-shadows)");
                      if (a->app->count("--embree-shadow-hint") && !o.shadows)
                        throw UsageError("--embree-shadow-hint", "needs shadow rays (drop --no-shadows)");
                      if (a->app->count("--shadow-order") && !o.shadows)
                        throw UsageError("--shadow-order", "needs shadow rays (drop --no-shadows)");
                      o.config.shadow_morton = a->shadow_order == "morton";
                      o.argv = ctx.args;
                      cmd_bench(o, std::cout);
                    });
  a->app = c;
  a->scene.add_to(c);
  a->camera.add_to(c, /*with_light=*/true);
  c->add_flag("--no-shadows", [a](std::int64_t) { a->opt.shadows = false; },
              "primary rays only (default: the whole frame includes shadow rays to the light)");
  auto* packets = c->add_flag("--packets", cfg.packets,
                              "trace primary and shadow rays in packets (ours: 8, one ray per AVX2 lane; Embree: "
                              "rtcIntersectN / rtcOccludedN, N = --embree-packet-width); default: single "
                              "rays on both sides");
  c->add_option("--embree-packet-width", cfg.embree_packet_width,
                "with --packets: Embree's packet width, 4, 8 or 16 (rtcIntersect4/8/16)")
      ->check(CLI::IsMember({4, 8, 16}))
      ->needs(packets)
      ->capture_default_str();
  c->add_option("--shadow-order", a->shadow_order,
                "the shadow rays' order, the same for every configuration: pixel (the primary hits' order) or morton "
                "(by the Morton code of the hit points, made once a frame and counted in every whole frame)")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            return s == "pixel" || s == "morton" ? std::string() : "'" + s + "' is not a valid shadow order (pixel or morton)";
          },
          "pixel|morton"))
      ->capture_default_str();
  c->add_option("--embree-shadow-hint", a->embree_shadow_hint,
                "with --packets: the context flag of Embree's shadow packets (rtcOccludedN), best (each frame "
                "timed with both, the faster counted), coherent or incoherent (Embree's default); its primary "
                "packets are coherent")
      ->check(enum_validator("Embree shadow hint (best, coherent or incoherent)", parse_embree_shadow_hint))
      ->needs(packets)
      ->capture_default_str();
  c->add_option("--isa", a->isa,
                "our tracer's instruction set: auto (with AVX-512: avx512 on AMD Zen 5 and later, avx512vl on others; else the widest up to avx2), sse2, avx2, avx512vl (AVX2's 256-bit code in AVX-512's encoding) or avx512 (the same hits "
                "and counters; Embree keeps its own)")
      ->check(enum_validator("instruction set", bvh::parse_trace_isa))
      ->capture_default_str();
  auto* cl = c->add_option("--clusters", a->opt.clusters, "use the clustering in DIR/triangles.csv (ptc cluster --out DIR)");
  static_assert(kBenchDefaultMaxCount == 32, "the --max-count help quotes the default");
  c->add_option("--max-count", a->max_count,
                "otherwise: growth/Acc clustering with MaxCount = MaxSize = N (0: one triangle per cluster, the "
                "paper's standard); default: the scene's own cluster size ('ptc scenes' lists them; a scene "
                "file's \"clusters\": {\"max_count\": N}), else 32")
      ->check(whole_in(0, kMaxSceneClusterCount))
      ->excludes(cl);  // (no default shown: the scene's own, else 32, as the text says)
  c->add_option("--adjacency", a->adjacency,
                "otherwise: neighbouring triangles of that clustering: edges (shared vertex ids), positions (sides "
                "whose corner positions coincide at rest) or auto (positions for a triangle soup, else edges)")
      ->check(enum_validator("adjacency", parse_cluster_adjacency))
      ->excludes(cl)
      ->capture_default_str();
  c->add_option("--frames", a->frames,
                "scene frames A:B (default: an animated scene's range, else 0:4 of --deform); the first is left "
                "out of the medians");
  c->add_flag("--extend-frames", a->opt.extend_frames, "allow frames outside the scene's listed range");
  c->add_option("--width", cfg.width, "primary rays per image row")->check(whole_in(1, kMaxImageSide))->capture_default_str();
  c->add_option("--height", cfg.height, "image rows")->check(whole_in(1, kMaxImageSide))->capture_default_str();
  add_threads_option(c, ctx.threads);  // ours and Embree's device alike
  c->add_option("--deform", a->deform,
                "stand-in motion of a static scene (mesh file): twist (default), bend, wave, rigid, explode (the "
                "built-in scenes' deformers) or none")
      ->check(CLI::IsMember({"twist", "bend", "wave", "rigid", "explode", "none"}));
  c->add_option("--cluster-leaf", a->cluster_leaf, "cluster leaves: linear (the paper's, default) or block-tree")
      ->check(enum_validator("cluster leaf", bvh::parse_cluster_leaf))
      ->capture_default_str();
  static_assert(bvh::kAutoTablesMaxShare == 0.85, "the --leaf-format help quotes the share");
  c->add_option("--leaf-format", a->leaf_format,
                "how the cluster BVH's linear leaves hold their triangles: blocks (four triangles' corners "
                "each, 36 bytes a triangle), tables (per-group vertex tables and corner slots, 512 bytes a "
                "group of up to 32 triangles on up to 32 vertices; the same hits; for meshes that share "
                "vertices: a triangle soup gets groups of five triangles) or auto (tables when their estimated "
                "bytes are at most 0.85 of the blocks', else blocks; the summary's "
                "\"cluster leaves\" line and the manifest's results.cluster_leaves.format say which)")
      ->check(enum_validator("leaf format", bvh::parse_leaf_format_choice))
      ->capture_default_str();
  c->add_option("--cluster-groups", cfg.cluster_group_size,
                "two-level cluster BVH build over fixed groups of at most N clusters (subtrees of the rest-pose "
                "BVH); 0 = the plain build over all cluster boxes; unset: N = 32, but at least 1024 groups (smaller "
                "groups under 32,768 clusters, the plain build under 2,048)")
      ->check(whole_in(0, 1 << 20))
      ->capture_default_str();
  a->group_trees.add_to(c);
  a->fallback.add_to(c);
  c->add_option("--vertex-order", a->vertex_order,
                "clusters: renumber the vertices once so each cluster's are consecutive (the cluster path then "
                "streams, no gather; every configuration sees the same mesh), or input: keep the file's order")
      ->check(enum_validator("vertex order", bvh::parse_vertex_order))
      ->capture_default_str();
  c->add_option("--out", a->opt.out_dir, "output directory: bench.csv, summary.csv, manifest.json")->required();
  c->add_flag("--json", a->opt.json, "print the summary as JSON");
}

}  // namespace ptc::cli
