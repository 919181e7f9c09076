#include "commands/commands.h"
#include "apps/ptc/cli.h"

#include <iostream>

namespace ptc::cli {

namespace {
struct ClusterArgs {
  ClusterOptions opt;
  ClusterFlags flags;
};
}  // namespace

void register_cluster(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<ClusterArgs>();
  auto* c = ctx.add(app, "cluster", "group triangles into compact connected clusters (once per topology)", [a, &ctx] {
    a->flags.apply(a->opt.config, a->opt.given);
    a->opt.argv = ctx.args;
    cmd_cluster(a->opt, std::cout);
  });
  c->add_option("MESH", a->opt.input, "mesh file")->required();
  a->flags.add_to(c, a->opt.config, /*with_method=*/true);
  c->add_option("--out", a->opt.out_dir, "output directory (triangles.csv, clusters.csv, summary.json, clusters.ply)")
      ->required();
  c->add_flag("--json", a->opt.json, "print the summary's results as JSON");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
