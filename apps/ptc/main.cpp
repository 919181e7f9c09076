// The `ptc` command: parses arguments (CLI11, only in this file: its headers are expensive),
// calls the library, maps errors to exit codes: 0 success, 1 bad input or failed run (one line
// on stderr), 2 bad usage.
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <oneapi/tbb/global_control.h>

#include "analysis/commands.h"
#include "toolkit/core/error.h"

namespace {

// Strings from the command line become enums here, at the edge (style.md point 5).
template <class Parse>
CLI::Validator enum_validator(std::string name, Parse parse) {
  return CLI::Validator(
      [parse, name](std::string& s) -> std::string {
        return parse(s) ? std::string() : "'" + s + "' is not a valid " + name;
      },
      name);
}

void add_threads_option(CLI::App* cmd, int& threads) {
  cmd->add_option("--threads", threads, "worker threads (default: all cores)")->check(CLI::Range(1, 4096));
}

}  // namespace

int main(int argc, char** argv) {
  using namespace ptc;
  std::vector<std::string> args(argv, argv + argc);

  CLI::App app{"ptc - precomputed triangle clusters for ray tracing animated meshes"};
  app.set_version_flag("--version", std::string("ptc ") + PTC_VERSION);
  app.require_subcommand(1);
  int threads = 0;

  // info
  InfoOptions info;
  auto* c_info = app.add_subcommand("info", "counts, extent, area/edge statistics and defects of a mesh");
  c_info->add_option("MESH", info.input, "mesh file (.off .obj .ply .stl)")->required();
  c_info->add_flag("--json", info.json, "print JSON (schema ptc-info/1)");
  add_threads_option(c_info, threads);

  // subdivide
  SubdivideOptions sub;
  std::string scheme = "midpoint";
  auto* c_sub = app.add_subcommand("subdivide", "refine a mesh (1-to-4 midpoint split or Loop) keeping its shape");
  c_sub->add_option("MESH", sub.input, "mesh file")->required();
  c_sub->add_option("--levels", sub.levels, "subdivision levels (each multiplies the triangles by 4)")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  c_sub->add_option("--scheme", scheme, "midpoint (the surface is kept exactly) or loop (smooth; manifold input)")
      ->check(enum_validator("scheme", parse_subdivision_scheme))
      ->capture_default_str();
  c_sub->add_option("--out", sub.output, "output mesh (.off .obj .ply), written atomically")->required();
  c_sub->add_flag("--json", sub.json, "print JSON");
  add_threads_option(c_sub, threads);

  // spheres
  SpheresOptions sph;
  std::vector<std::string> methods;
  auto* c_sph = app.add_subcommand("spheres", "bounding-sphere methods: time per sphere and radius error vs exact");
  c_sph->add_option("MESH", sph.input, "mesh file")->required();
  c_sph->add_option("--min-run", sph.config.min_run, "fewest triangles per point set")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  c_sph->add_option("--max-run", sph.config.max_run, "most triangles per point set")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  c_sph->add_option("--repeats", sph.config.repeats, "timing repetitions (median reported)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  c_sph->add_option("--seed", sph.config.seed, "seed of the run lengths")->capture_default_str();
  c_sph->add_option("--methods", methods, "subset of: exact cgal ritter epos6 epos14 epos26")
      ->delimiter(',')
      ->check(enum_validator("sphere method", parse_sphere_method));
  c_sph->add_option("--out", sph.out_dir, "output directory (spheres.csv, sphere_sets.csv, manifest.json)");
  c_sph->add_flag("--json", sph.json, "print JSON");
  add_threads_option(c_sph, threads);  // accepted for uniformity; the timings are one-thread by design

  // cluster
  ClusterOptions clu;
  std::string method = "contraction", objective = "acc", size_bound = "max", sphere = "cgal", start = "spatial",
              gwh_weight = "area";
  auto* c_clu = app.add_subcommand("cluster", "group triangles into compact connected clusters (once per topology)");
  c_clu->add_option("MESH", clu.input, "mesh file")->required();
  c_clu->add_option("--method", method, "growth, contraction, sah-split or meshopt")
      ->check(enum_validator("method", parse_cluster_method))
      ->capture_default_str();
  c_clu->add_option("--objective", objective, "acc (Garanzha 2009), naive (SAH clusters) or gwh01 (Garland et al. 2001)")
      ->check(enum_validator("objective", parse_objective))
      ->capture_default_str();
  c_clu->add_option("--max-count", clu.config.max_count, "MaxCount (vertices); 0 with --max-size 0 = one triangle per cluster")
      ->check(CLI::Range(0u, 1u << 20))
      ->capture_default_str();
  c_clu->add_option("--max-size", clu.config.max_size, "MaxSize (sphere area in units of the mean triangle sphere area)")
      ->check(CLI::Range(0.0, 1e12))
      ->capture_default_str();
  c_clu->add_option("--size-bound", size_bound, "max (as printed in the paper) or min")
      ->check(CLI::IsMember({"max", "min"}))
      ->capture_default_str();
  c_clu->add_option("--sphere", sphere, "bounding sphere inside the objective: exact cgal ritter epos6 epos14 epos26")
      ->check(enum_validator("sphere method", parse_sphere_method))
      ->capture_default_str();
  c_clu->add_option("--start", start, "growth start rule: index, spatial or fewest-free")
      ->check(enum_validator("start rule", parse_start_rule))
      ->capture_default_str();
  c_clu->add_option("--gwh-a1", clu.config.gwh.a1, "GWH01 weight of E_dir")->check(CLI::Range(0.0, 1e6))->capture_default_str();
  c_clu->add_option("--gwh-a2", clu.config.gwh.a2, "GWH01 weight of E_shape")->check(CLI::Range(0.0, 1e6))->capture_default_str();
  c_clu->add_option("--gwh-weight", gwh_weight, "GWH01 E_dir weights: area or sqrt-area")
      ->check(CLI::IsMember({"area", "sqrt-area"}))
      ->capture_default_str();
  c_clu->add_option("--target-clusters", clu.config.target_clusters, "GWH01 contraction: stop at this many clusters (0 = off)")
      ->capture_default_str();
  c_clu->add_option("--max-triangles", clu.config.max_triangles, "sah-split/meshopt triangle limit (0 = 2 x max-count)")
      ->capture_default_str();
  c_clu->add_option("--out", clu.out_dir, "output directory (triangles.csv, clusters.csv, summary.json, clusters.ply)")
      ->required();
  c_clu->add_flag("--json", clu.json, "print the summary's results as JSON");
  add_threads_option(c_clu, threads);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "ptc: " << e.what() << " (run 'ptc --help')\n";
    return 2;
  }
  if (sph.config.max_run < sph.config.min_run) {
    std::cerr << "ptc: --max-run " << sph.config.max_run << " is smaller than --min-run " << sph.config.min_run << "\n";
    return 2;
  }

  std::optional<oneapi::tbb::global_control> thread_limit;
  if (threads > 0) thread_limit.emplace(oneapi::tbb::global_control::max_allowed_parallelism, threads);

  try {
    if (*c_info) {
      cmd_info(info, std::cout);
    } else if (*c_sub) {
      sub.scheme = *parse_subdivision_scheme(scheme);
      cmd_subdivide(sub, std::cout);
    } else if (*c_clu) {
      clu.config.method = *parse_cluster_method(method);
      clu.config.objective = *parse_objective(objective);
      clu.config.size_bound_mode = size_bound == "max" ? SizeBoundMode::Max : SizeBoundMode::Min;
      clu.config.sphere = *parse_sphere_method(sphere);
      clu.config.start = *parse_start_rule(start);
      clu.config.gwh.weight = gwh_weight == "area" ? GwhWeight::Area : GwhWeight::SqrtArea;
      clu.argv = args;
      cmd_cluster(clu, std::cout);
    } else if (*c_sph) {
      if (!methods.empty()) {
        sph.config.methods.clear();
        for (const auto& m : methods) sph.config.methods.push_back(*parse_sphere_method(m));
      }
      sph.argv = args;
      cmd_spheres(sph, std::cout);
    }
  } catch (const InputError& e) {
    std::cerr << "ptc: error: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "ptc: error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "ptc: error: " << e.what() << "\n";
    return 1;
  }
  std::cout.flush();
  if (!std::cout) {
    std::cerr << "ptc: error: cannot write to stdout\n";
    return 1;
  }
  return 0;
}
