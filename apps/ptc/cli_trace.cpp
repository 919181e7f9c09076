// `ptc trace SCENE [--frame F | --frames A:B] [--data-dir DIR] [--clusters DIR] [--width W --height H] [--eye X,Y,Z --look-at X,Y,Z --up X,Y,Z
// --fov DEG] [--shadows] [--ao N] [--threads T] [--seed S] --out DIR` (commands/trace.h).
#include <iostream>

#include "commands/trace.h"
#include "apps/ptc/cli.h"

namespace ptc::cli {

namespace {
struct TraceArgs {
  TraceCommandOptions opt;
  SceneArg scene;
  CameraArgs camera;
  std::string frame, frames, cost_range, deform, vertex_order = "input";
  GroupTreesArg group_trees;
  std::uint32_t cluster_groups = bvh::cluster_scene_defaults().cluster_group_size;  // (given: opt.cluster_group_size)
  FallbackFlags fallback;
  CLI::App* app = nullptr;
};
}  // namespace

void register_trace(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<TraceArgs>();
  auto& rc = a->opt.render;
  auto* c = ctx.add(app, "trace", "render a scene with the reference tracer: images, trace.csv, manifest.json", [a, &ctx] {
    auto& o = a->opt;
    o.input = a->scene.input;
    a->scene.apply(o.scene_options);
    o.camera = a->camera.spec();
    o.render.light = a->camera.light_position();
    if (a->app->count("--frame")) o.frame = a->frame;
    if (a->app->count("--frames")) o.frames = a->frames;
    if (a->app->count("--cost-range")) o.cost_range = a->cost_range;
    if (a->app->count("--deform")) o.deform = a->deform;
    // Flags that would do nothing are refused, as `ptc cluster` refuses a flag its method does not use.
    for (const char* f : {"--cluster-groups", "--vertex-order", "--cluster-fallback", "--fallback-refit", "--fallback-sah"})
      if (a->app->count(f) && o.clusters.empty()) throw UsageError(f, "needs a cluster BVH (--clusters DIR)");
    o.vertex_order = *bvh::parse_vertex_order(a->vertex_order);
    for (const char* f : {"--ao-distance", "--seed"})
      if (a->app->count(f) && o.render.ao_samples == 0) throw UsageError(f, "needs ambient occlusion (--ao N > 0)");
    if (a->app->count("--cluster-groups")) o.cluster_group_size = a->cluster_groups;
    if (a->app->count("--cluster-fallback")) o.cluster_fallback = *parse_cluster_fallback(a->fallback.swelling);
    if (a->app->count("--fallback-refit")) o.fallback_refit = *parse_fallback_refit(a->fallback.refit);
    if (a->app->count("--fallback-sah")) o.fallback_sah = *bvh::parse_fallback_sah(a->fallback.sah);
    a->fallback.require_fallback(!o.cluster_fallback || *o.cluster_fallback > 0);  // (unset: auto, on)
    const bvh::GroupTrees trees = a->group_trees.get(
        !o.clusters.empty() && o.cluster_group_size.value_or(bvh::cluster_scene_defaults().cluster_group_size) > 1,
        "a cluster BVH with the two-level build (--clusters DIR, --cluster-groups N > 1)");
    if (a->app->count("--group-trees")) o.group_trees = trees;
    o.render.threads = static_cast<unsigned>(ctx.threads);
    o.argv = ctx.args;
    cmd_trace(o, std::cout);
  });
  a->app = c;
  a->scene.add_to(c);
  auto* one = c->add_option("--frame", a->frame, "trace frame F (default: the scene's first frame)");
  c->add_option("--frames", a->frames, "trace frames A:B: images shaded_0000.png ..., trace.csv rows per frame")
      ->excludes(one);
  c->add_flag("--extend-frames", a->opt.extend_frames, "allow frames outside the scene's listed range");
  c->add_option("--deform", a->deform,
                "stand-in motion of a static scene (a mesh file): twist, bend, wave, rigid or explode, the motion "
                "ptc bench measures; none (the default) keeps it still")
      ->check(CLI::IsMember({"twist", "bend", "wave", "rigid", "explode", "none"}));
  c->add_option("--clusters", a->opt.clusters, "trace a cluster BVH over the clustering in DIR/triangles.csv (ptc cluster --out DIR)");
  c->add_option("--cluster-groups", a->cluster_groups,
                "with --clusters: two-level BVH build over fixed groups of at most N clusters; 0 = plain build "
                "(the default N below is for moving parts; a still scene, built once, takes the plain build unless given)")
      ->check(whole_in(0, 1 << 20))
      ->capture_default_str();
  a->group_trees.add_to(c);
  a->fallback.add_to(c);
  c->add_option("--vertex-order", a->vertex_order,
                "with --clusters: clusters renumbers the vertices once so each cluster's are consecutive (the "
                "method's precomputation, as in ptc bench: each frame's update streams instead of gathering, which "
                "pays over a sequence; the same images and hits), or input: keep the file's order")
      ->check(enum_validator("vertex order", bvh::parse_vertex_order))
      ->capture_default_str();
  c->add_option("--width", rc.width, "image width in pixels")->check(whole_in(1, kMaxImageSide))->capture_default_str();
  c->add_option("--height", rc.height, "image height in pixels")->check(whole_in(1, kMaxImageSide))->capture_default_str();
  a->camera.add_to(c, /*with_light=*/true);
  c->add_flag("--shadows", rc.shadows, "trace shadow rays to the point light");
  c->add_option("--ao", rc.ao_samples, "ambient-occlusion rays per pixel (0 = none)")->check(whole_in(0, 4096))->capture_default_str();
  c->add_option("--ao-distance", rc.ao_distance_rel, "AO max distance as a fraction of the mesh's bounds diagonal")
      ->check(finite_in(1e-9, 1e9))
      ->capture_default_str();
  c->add_option("--seed", rc.seed, "seed of the AO directions")->check(seed_validator())->capture_default_str();
  c->add_option("--cost-range", a->cost_range,
                "colour range MIN:MAX of the cost images (default: each image's 0..max); with numbers: ptc viz heatmap");
  c->add_option("--out", a->opt.out_dir, "output directory (written atomically)")->required();
  c->add_flag("--json", a->opt.json, "print the per-frame, per-pass figures as JSON");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
