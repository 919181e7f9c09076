#include "commands/commands.h"
#include "apps/ptc/cli.h"

#include <iostream>

namespace ptc::cli {

void register_subdivide(CLI::App& app, Context& ctx) {
  auto opt = std::make_shared<SubdivideOptions>();
  auto scheme = std::make_shared<std::string>("midpoint");
  auto scheme_opt = std::make_shared<CLI::Option*>(nullptr);
  auto* c = ctx.add(app, "subdivide", "refine a mesh (1-to-4 midpoint split or Loop) keeping its shape", [opt, scheme, scheme_opt] {
    if (opt->levels == 0 && *scheme_opt && (*scheme_opt)->count() > 0)  // (it would do nothing)
      throw UsageError("--scheme", "not used with --levels 0 (nothing is refined)");
    opt->scheme = *parse_subdivision_scheme(*scheme);
    cmd_subdivide(*opt, std::cout);
  });
  c->add_option("MESH", opt->input, "mesh file")->required();
  c->add_option("--levels", opt->levels, "subdivision levels (each multiplies the triangles by 4)")
      ->check(whole_in(0, 8))
      ->capture_default_str();
  *scheme_opt = c->add_option("--scheme", *scheme, "midpoint (the surface is kept exactly) or loop (smooth; manifold input)")
                    ->check(enum_validator("scheme", parse_subdivision_scheme))
                    ->capture_default_str();
  c->add_option("--out", opt->output, "output mesh (.off .obj .ply), written atomically")->required();
  c->add_flag("--json", opt->json, "print JSON");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
