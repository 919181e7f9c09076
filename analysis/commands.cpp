#include "analysis/commands.h"

#include <chrono>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/manifest.h"
#include "analysis/mesh_info.h"
#include "analysis/output_dir.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {
double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

void cmd_info(const InfoOptions& opt, std::ostream& out) {
  const LoadedMesh lm = read_mesh(opt.input);
  const MeshReport rep = analyze_mesh(lm.mesh);
  if (opt.json)
    out << dump_json(mesh_info_json(opt.input, lm.report, rep));
  else
    out << mesh_info_text(opt.input, lm.report, rep);
}

void cmd_subdivide(const SubdivideOptions& opt, std::ostream& out) {
  if (const auto f = format_from_extension(opt.output); !f || *f == MeshFormat::Stl)
    throw InputError(opt.output.string(), "", "", "cannot write this format (use .off, .obj or .ply)");
  auto t0 = std::chrono::steady_clock::now();
  const LoadedMesh lm = read_mesh(opt.input);
  const double read_ms = ms_since(t0);
  t0 = std::chrono::steady_clock::now();
  // The subdivider's errors name the element (edge, triangle, levels) but not the file.
  const Subdivider sub = [&] {
    try {
      return Subdivider::build(lm.mesh.triangles(), lm.mesh.vertex_count(), opt.scheme, opt.levels);
    } catch (const InputError& e) {
      if (!e.file().empty()) throw;
      throw InputError(opt.input.string(), e.location(), e.element(), e.reason());
    }
  }();
  const Mesh refined = sub.apply(lm.mesh);
  const double sub_ms = ms_since(t0);
  t0 = std::chrono::steady_clock::now();
  write_mesh(opt.output, refined);
  const double write_ms = ms_since(t0);
  if (opt.json) {
    nlohmann::json j{{"input", opt.input.string()},       {"output", opt.output.string()},
                     {"scheme", to_string(opt.scheme)},   {"levels", opt.levels},
                     {"triangles_in", lm.mesh.triangle_count()}, {"vertices_in", lm.mesh.vertex_count()},
                     {"triangles_out", refined.triangle_count()}, {"vertices_out", refined.vertex_count()},
                     {"read_ms", read_ms},                {"subdivide_ms", sub_ms},
                     {"write_ms", write_ms}};
    out << dump_json(j);
  } else {
    out << fmt::format("{}: {} triangles, {} vertices -> {} x{} -> {}: {} triangles, {} vertices ({:.0f} ms)\n",
                       opt.input.string(), lm.mesh.triangle_count(), lm.mesh.vertex_count(), to_string(opt.scheme),
                       opt.levels, opt.output.string(), refined.triangle_count(), refined.vertex_count(), sub_ms);
  }
}

void cmd_spheres(const SpheresOptions& opt, std::ostream& out) {
  RunManifest manifest("spheres", opt.argv);
  auto t0 = std::chrono::steady_clock::now();
  const LoadedMesh lm = read_mesh(opt.input);
  manifest.add_timing_ms("read", ms_since(t0));
  manifest.add_input(opt.input);
  nlohmann::json methods = nlohmann::json::array();
  for (SphereMethod m : opt.config.methods) methods.push_back(to_string(m));
  manifest.set_parameter("min_run", opt.config.min_run);
  manifest.set_parameter("max_run", opt.config.max_run);
  manifest.set_parameter("seed", opt.config.seed);
  manifest.set_parameter("repeats", opt.config.repeats);
  manifest.set_parameter("methods", methods);
  manifest.set_parameter("threads", 1);

  t0 = std::chrono::steady_clock::now();
  const SphereReport rep = run_sphere_report(lm.mesh, opt.config);
  manifest.add_timing_ms("report", ms_since(t0));
  const CsvTable table = sphere_methods_csv(rep);

  if (!opt.out_dir.empty()) {
    OutputDir dir(opt.out_dir);
    dir.write("spheres.csv", table.str());
    dir.write("sphere_sets.csv", sphere_sets_csv(rep).str());
    manifest.add_output("spheres.csv");
    manifest.add_output("sphere_sets.csv");
    manifest.add_output("manifest.json");
    manifest.set_result("point_sets", rep.exact_radius.size());
    dir.write("manifest.json", dump_json(manifest.to_json()));
    dir.commit();
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
  out << fmt::format("bounding spheres of {} point sets ({}-{} Morton-ordered triangles each) of {}\n",
                     rep.exact_radius.size(), opt.config.min_run, opt.config.max_run, opt.input.string());
  out << fmt::format("{:<8} {:>14} {:>14} {:>14} {:>14}\n", "method", "ns/sphere", "rel_err_mean", "rel_err_max",
                     "not_containing");
  for (const auto& m : rep.methods)
    out << fmt::format("{:<8} {:>14.0f} {:>14.3e} {:>14.3e} {:>14}\n", to_string(m.method), m.ns_per_sphere_median,
                       m.rel_err_mean, m.rel_err_max, m.not_containing);
  if (!opt.out_dir.empty()) out << "wrote " << opt.out_dir.string() << "/{spheres.csv,sphere_sets.csv,manifest.json}\n";
}

}  // namespace ptc
