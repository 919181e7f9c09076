#include "commands/animate.h"
#include "apps/ptc/cli.h"

#include <iostream>

namespace ptc::cli {

namespace {
struct AnimateArgs {
  AnimateOptions opt;
  std::string format = "ply";
  std::string data_dir;
  std::string frames;
  CLI::Option* frames_opt = nullptr;
};
}  // namespace

void register_animate(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<AnimateArgs>();
  auto* c = ctx.add(app, "animate", "write the frames of a scene as a mesh sequence (frame_0000.ply ...)", [a, &ctx] {
    a->opt.format = *parse_mesh_format(a->format);
    a->opt.scene_options.data_dir = a->data_dir;
    a->opt.argv = ctx.args;
    if (a->frames_opt->count() > 0) a->opt.frames = a->frames;
    cmd_animate(a->opt, std::cout);
  });
  c->add_option("SCENE", a->opt.scene,
                "built-in scene name ('ptc scenes'), scene file (.json), mesh or animated asset file, or directory of frames")
      ->required();
  a->frames_opt = c->add_option("--frames", a->frames, "inclusive frame range A:B (default: the scene's range)");
  c->add_flag("--extend-frames", a->opt.extend_frames, "allow frames outside the scene's listed range");
  c->add_option("--out", a->opt.out_dir, "output directory (written whole or not at all)")->required();
  c->add_option("--format", a->format, "frame file format: ply (binary) or obj")
      ->check(CLI::IsMember({"ply", "obj"}))
      ->capture_default_str();
  c->add_flag("--stats", a->opt.stats, "print per-frame bounding box and triangle-area change; write stats.csv");
  c->add_option("--data-dir", a->data_dir, "meshes of built-in scenes (default: $PTC_DATA_DIR or <ptc>/../data)");
  c->add_flag("--json", a->opt.json, "print JSON");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
