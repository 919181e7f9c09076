#include "commands/commands.h"
#include "apps/ptc/cli.h"

#include <algorithm>

#include <iostream>

namespace ptc::cli {

void register_spheres(CLI::App& app, Context& ctx) {
  auto opt = std::make_shared<SpheresOptions>();
  auto methods = std::make_shared<std::vector<std::string>>();
  auto* c = ctx.add(app, "spheres", "bounding-sphere methods: time per sphere and radius error vs exact",
                    [opt, methods, &ctx] {
                      if (opt->config.max_run < opt->config.min_run)
                        throw UsageError("--max-run", std::to_string(opt->config.max_run) +
                                                        " is smaller than --min-run " +
                                                        std::to_string(opt->config.min_run));
                      if (!methods->empty()) {
                        opt->config.methods.clear();
                        for (const auto& m : *methods) {
                          const SphereMethod k = *parse_sphere_method(m);
                          if (std::find(opt->config.methods.begin(), opt->config.methods.end(), k) !=
                              opt->config.methods.end())
                            throw UsageError("--methods", "'" + m + "' is listed twice (each method once)");
                          opt->config.methods.push_back(k);
                        }
                      }
                      opt->argv = ctx.args;
                      cmd_spheres(*opt, std::cout);
                    });
  c->add_option("MESH", opt->input, "mesh file")->required();
  c->add_option("--min-run", opt->config.min_run, "fewest triangles per point set")
      ->check(whole_in(1, 1 << 20))
      ->capture_default_str();
  c->add_option("--max-run", opt->config.max_run, "most triangles per point set")
      ->check(whole_in(1, 1 << 20))
      ->capture_default_str();
  c->add_option("--repeats", opt->config.repeats, "timing repetitions (median reported)")
      ->check(whole_in(1, 1000))
      ->capture_default_str();
  c->add_option("--seed", opt->config.seed, "seed of the run lengths")->check(seed_validator())->capture_default_str();
  c->add_option("--methods", *methods, "subset of: exact cgal ritter epos6 epos14 epos26")
      ->delimiter(',')
      ->check(enum_validator("sphere method", parse_sphere_method));
  c->add_option("--out", opt->out_dir, "output directory (spheres.csv, sphere_sets.csv, manifest.json)");
  c->add_flag("--json", opt->json, "print JSON");
  add_threads_option(c, ctx.threads);  // accepted for uniformity; the timings are one-thread by design
}

}  // namespace ptc::cli
