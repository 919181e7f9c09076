#include "commands/commands.h"
#include "apps/ptc/cli.h"

#include <iostream>

namespace ptc::cli {

void register_info(CLI::App& app, Context& ctx) {
  auto opt = std::make_shared<InfoOptions>();
  auto* c = ctx.add(app, "info", "counts, extent, area/edge statistics and defects of a mesh",
                    [opt] { cmd_info(*opt, std::cout); });
  c->add_option("MESH", opt->input, "mesh file (.off .obj .ply .stl)")->required();
  c->add_flag("--json", opt->json, "print JSON (schema ptc-info/1)");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
