// `ptc viz partition|heatmap|panel|export SCENE [--clusters DIR] [--frame F | --frames A:B]
// [--metric NAME] [--range MIN:MAX] [camera flags] [--width W --height H] [--no-borders] [--flat]
// [--shadows] [--interactive] [--xvfb] --out DIR` (commands/viz.h, docs/viz.md).
#include <iostream>

#include "apps/ptc/cli.h"
#include "commands/viz.h"

namespace ptc::cli {

namespace {
struct VizArgs {
  VizCommandOptions opt;
  SceneArg scene;
  CameraArgs camera;
  std::string kind, frame, frames, range, deform;
  bool no_borders = false, flat = false;
  CLI::App* app = nullptr;
};
}  // namespace

void register_viz(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<VizArgs>();
  auto* c = ctx.add(app, "viz",
                    "VTK pictures of a clustering: partition, per-cluster or per-pixel heatmap, partition | shaded | "
                    "heatmap panel, ParaView export (.vtp + .pvd)",
                    [a, &ctx] {
                      auto& o = a->opt;
                      o.kind = *parse_viz_kind(a->kind);
                      o.input = a->scene.input;
                      a->scene.apply(o.scene_options);
                      o.camera = a->camera.spec();
                      o.light = a->camera.light_position();
                      if (a->app->count("--frame")) o.frame = a->frame;
                      if (a->app->count("--frames")) o.frames = a->frames;
                      if (a->app->count("--range")) o.range = a->range;
                      if (a->app->count("--deform")) o.deform = a->deform;
                      o.borders = !a->no_borders;
                      o.lighting = !a->flat;
                      if (o.kind == VizKind::Export)  // (the .vtp files carry data, not pictures)
                        for (const char* f : {"--no-borders", "--flat", "--width", "--height", "--eye", "--look-at", "--up",
                                              "--fov", "--light", "--xvfb"})
                          if (a->app->count(f)) throw UsageError(f, "not used by viz export (it writes .vtp files, not pictures)");
                      o.threads = static_cast<unsigned>(ctx.threads);
                      o.argv = ctx.args;
                      cmd_viz(o, std::cout);
                    });
  a->app = c;
  c->add_option("KIND", a->kind, "partition, heatmap, panel or export")
      ->required()
      ->check(CLI::IsMember({"partition", "heatmap", "panel", "export"}));
  a->scene.add_to(c);
  auto* one = c->add_option("--frame", a->frame, "frame F (default: the scene's first frame)");
  c->add_option("--frames", a->frames, "frames A:B: numbered pictures with one colour range (and an MP4 when ffmpeg is installed)")
      ->excludes(one);
  c->add_flag("--extend-frames", a->opt.extend_frames, "allow frames outside the scene's listed range");
  c->add_option("--deform", a->deform,
                "stand-in motion of a static scene: twist, bend, wave, rigid or explode; none (the default) keeps it still")
      ->check(CLI::IsMember({"twist", "bend", "wave", "rigid", "explode", "none"}));
  c->add_option("--clusters", a->opt.clusters, "the clustering in DIR/triangles.csv (ptc cluster --out DIR)");
  c->add_option("--metric", a->opt.metric,
                "heatmap / panel: a per-cluster metric (reg, connectivity, acc, box_area_ratio, sah_share, ...) or "
                "the tracer's nodes_visited / triangles_tested (panel default: nodes_visited)");
  c->add_option("--range", a->range, "colour range MIN:MAX (default: the values', over all frames of --frames)");
  c->add_option("--width", a->opt.width, "picture width in pixels")->check(whole_in(1, 8192))->capture_default_str();
  c->add_option("--height", a->opt.height, "picture height in pixels")->check(whole_in(1, 8192))->capture_default_str();
  a->camera.add_to(c, /*with_light=*/true);
  c->add_flag("--no-borders", a->no_borders, "partition, panel: no lines on the cluster borders");
  c->add_flag("--flat", a->flat, "partition, per-cluster heatmap, panel: no lighting: every pixel is exactly its cluster's or value's colour");
  c->add_flag("--shadows", a->opt.shadows, "panel / pixel heatmap: shadow rays to the light in the traced image");
  c->add_flag("--interactive", a->opt.interactive, "also open a window on the display (partition, per-cluster heatmap, one frame)");
  c->add_flag("--xvfb", a->opt.force_xvfb, "render on a private Xvfb even when $DISPLAY answers");
  c->add_option("--out", a->opt.out_dir, "output directory (written atomically); required, except with --interactive");
  c->add_flag("--json", a->opt.json, "print what was written as JSON");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
