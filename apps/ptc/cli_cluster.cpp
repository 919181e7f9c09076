#include "commands/commands.h"
#include "apps/ptc/cli.h"

#include <iostream>

namespace ptc::cli {

namespace {
struct ClusterArgs {
  ClusterOptions opt;
  std::string method = "contraction", objective = "acc", size_bound = "max", sphere = "cgal", start = "spatial",
              gwh_weight = "area";
  CLI::App* app = nullptr;
};
}  // namespace

void register_cluster(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<ClusterArgs>();
  auto& cfg = a->opt.config;
  auto* c = ctx.add(app, "cluster", "group triangles into compact connected clusters (once per topology)", [a, &ctx] {
    auto& cf = a->opt.config;
    cf.method = *parse_cluster_method(a->method);
    cf.objective = *parse_objective(a->objective);
    cf.size_bound_mode = *parse_size_bound_mode(a->size_bound);
    cf.sphere = *parse_sphere_method(a->sphere);
    cf.start = *parse_start_rule(a->start);
    cf.gwh.weight = *parse_gwh_weight(a->gwh_weight);
    for (std::string_view p : kClusterParameters)
      if (a->app->count(flag_of(p))) a->opt.given.emplace_back(p);
    a->opt.argv = ctx.args;
    cmd_cluster(a->opt, std::cout);
  });
  a->app = c;
  c->add_option("MESH", a->opt.input, "mesh file")->required();
  c->add_option("--method", a->method, "growth, contraction, sah-split or meshopt")
      ->check(enum_validator("method", parse_cluster_method))
      ->capture_default_str();
  c->add_option("--objective", a->objective, "acc (Garanzha 2009), naive (SAH clusters) or gwh01 (Garland et al. 2001)")
      ->check(enum_validator("objective", parse_objective))
      ->capture_default_str();
  c->add_option("--max-count", cfg.max_count, "MaxCount (vertices); 0 with --max-size 0 = one triangle per cluster")
      ->check(CLI::Range(0u, 1u << 20))
      ->capture_default_str();
  c->add_option("--max-size", cfg.max_size, "MaxSize (sphere area in units of the mean triangle sphere area)")
      ->check(CLI::Range(0.0, 1e12))
      ->capture_default_str();
  c->add_option("--size-bound", a->size_bound, "max (as printed in the paper) or min")
      ->check(enum_validator("size bound", parse_size_bound_mode))
      ->capture_default_str();
  c->add_option("--sphere", a->sphere, "bounding sphere inside the objective: exact cgal ritter epos6 epos14 epos26")
      ->check(enum_validator("sphere method", parse_sphere_method))
      ->capture_default_str();
  c->add_option("--start", a->start, "growth start rule: index, spatial or fewest-free")
      ->check(enum_validator("start rule", parse_start_rule))
      ->capture_default_str();
  c->add_option("--gwh-a1", cfg.gwh.a1, "GWH01 weight of E_dir")->check(CLI::Range(0.0, 1e6))->capture_default_str();
  c->add_option("--gwh-a2", cfg.gwh.a2, "GWH01 weight of E_shape")->check(CLI::Range(0.0, 1e6))->capture_default_str();
  c->add_option("--gwh-weight", a->gwh_weight, "GWH01 E_dir weights: area or sqrt-area")
      ->check(enum_validator("weight", parse_gwh_weight))
      ->capture_default_str();
  c->add_option("--target-clusters", cfg.target_clusters, "GWH01 contraction: stop at this many clusters (0 = off)")
      ->capture_default_str();
  c->add_option("--max-triangles", cfg.max_triangles, "sah-split/meshopt triangle limit (0 = 2 x max-count)")
      ->capture_default_str();
  c->add_option("--out", a->opt.out_dir, "output directory (triangles.csv, clusters.csv, summary.json, clusters.ply)")
      ->required();
  c->add_flag("--json", a->opt.json, "print the summary's results as JSON");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
