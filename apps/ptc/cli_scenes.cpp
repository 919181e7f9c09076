#include "commands/scenes.h"
#include "apps/ptc/cli.h"

#include <iostream>

namespace ptc::cli {

namespace {
struct ScenesArgs {
  ScenesOptions opt;
  std::string data_dir;
};
}  // namespace

void register_scenes(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<ScenesArgs>();
  auto* c = ctx.add(app, "scenes", "list the built-in scenes with their sizes and frame ranges", [a] {
    a->opt.scene_options.data_dir = a->data_dir;
    cmd_scenes(a->opt, std::cout);
  });
  c->add_option("NAME", a->opt.names, "only these scenes (default: all; building the large ones takes seconds)");
  c->add_option("--data-dir", a->data_dir, "meshes of built-in scenes (default: $PTC_DATA_DIR or <ptc>/../data)");
  c->add_flag("--json", a->opt.json, "print JSON (schema ptc-scenes/1)");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
