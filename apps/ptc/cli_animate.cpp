#include "commands/animate.h"
#include "apps/ptc/cli.h"

#include <iostream>

namespace ptc::cli {

namespace {
struct AnimateArgs {
  AnimateOptions opt;
  std::string format = "ply";
  SceneArg scene;
  std::string frames, deform;
  CLI::Option* frames_opt = nullptr;
  CLI::Option* deform_opt = nullptr;
};
}  // namespace

void register_animate(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<AnimateArgs>();
  auto* c = ctx.add(app, "animate", "write the frames of a scene as a mesh sequence (frame_0000.ply ...)", [a, &ctx] {
    a->opt.format = *parse_mesh_format(a->format);
    a->opt.scene = a->scene.input.string();
    a->scene.apply(a->opt.scene_options);
    a->opt.argv = ctx.args;
    if (a->frames_opt->count() > 0) a->opt.frames = a->frames;
    if (a->deform_opt->count() > 0) a->opt.deform = a->deform;
    cmd_animate(a->opt, std::cout);
  });
  a->scene.add_to(c);
  a->frames_opt = c->add_option("--frames", a->frames, "inclusive frame range A:B (default: the scene's range)");
  c->add_flag("--extend-frames", a->opt.extend_frames, "allow frames outside the scene's listed range");
  a->deform_opt = c->add_option("--deform", a->deform,
                                "stand-in motion of a static scene (a mesh file): twist, bend, wave, rigid or explode, "
                                "the motion ptc bench measures; none (the default) keeps it still")
                      ->check(CLI::IsMember({"twist", "bend", "wave", "rigid", "explode", "none"}));
  c->add_option("--out", a->opt.out_dir, "output directory (written whole or not at all)")->required();
  c->add_option("--format", a->format, "frame file format: ply (binary) or obj")
      ->check(CLI::IsMember({"ply", "obj"}))
      ->capture_default_str();
  c->add_flag("--stats", a->opt.stats, "print per-frame bounding box and triangle-area change; write stats.csv");
  c->add_flag("--json", a->opt.json, "print JSON");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
