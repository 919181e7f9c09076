// `ptc spheres`.
#include "commands/commands.h"

#include <optional>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/core/strings.h"

namespace ptc {

void cmd_spheres(const SpheresOptions& opt, std::ostream& out) {
  refuse_overwriting_input(opt.out_dir, opt.input);
  std::optional<OutputDir> dir;  // a refused --out fails before the (long) report
  if (!opt.out_dir.empty()) dir.emplace(opt.out_dir);
  RunManifest manifest("spheres", opt.argv, "ptc-spheres-run/1");
  const LoadedMesh lm = read_mesh_recorded(opt.input, manifest);
  Stopwatch t0;
  nlohmann::json methods = nlohmann::json::array();
  for (SphereMethod m : opt.config.methods) methods.push_back(to_string(m));
  manifest.set_parameter("min_run", opt.config.min_run);
  manifest.set_parameter("max_run", opt.config.max_run);
  manifest.set_parameter("seed", opt.config.seed);
  manifest.set_parameter("repeats", opt.config.repeats);
  manifest.set_parameter("methods", methods);
  manifest.set_parameter("threads", 1);

  t0.restart();
  const SphereReport rep = run_sphere_report(lm.mesh, opt.config);
  manifest.add_timing_ms("report", t0.ms());
  const Table table = sphere_methods_table(rep), sets = sphere_sets_table(rep);

  if (dir) {
    dir->write("spheres.csv", table.csv.str());
    dir->write("sphere_sets.csv", sets.csv.str());
    manifest.add_output("spheres.csv", table.schema.id());
    manifest.add_output("sphere_sets.csv", sets.schema.id());
    manifest.set_result("point_sets", rep.exact_radius.size());
    (void)commit_with_manifest(*dir, manifest);
  }
  if (opt.json) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& m : rep.methods)
      j.push_back({{"method", to_string(m.method)},
                   {"ns_per_sphere", m.ns_per_sphere_median},
                   {"rel_err_mean", m.rel_err_mean},
                   {"rel_err_max", m.rel_err_max},
                   {"not_containing", m.not_containing}});
    out << dump_json(j);
    return;
  }
  out << fmt::format("bounding spheres of {} (runs of {}-{} Morton-ordered triangles; the last, or a "
                     "smaller mesh's only one, may be shorter) of {}\n",
                     counted(rep.exact_radius.size(), "point set"), opt.config.min_run,
                     opt.config.max_run, opt.input.string());
  out << fmt::format("{:<8} {:>14} {:>14} {:>14} {:>14}\n", "method", "ns/sphere", "rel_err_mean", "rel_err_max",
                     "not_containing");
  for (const auto& m : rep.methods)
    out << fmt::format("{:<8} {:>14.0f} {:>14.3e} {:>14.3e} {:>14}\n", to_string(m.method), m.ns_per_sphere_median,
                       m.rel_err_mean, m.rel_err_max, m.not_containing);
  if (!opt.out_dir.empty()) out << "wrote " << opt.out_dir.string() << "/{spheres.csv,sphere_sets.csv,manifest.json}\n";
}

}  // namespace ptc
