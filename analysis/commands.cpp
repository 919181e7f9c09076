#include "analysis/commands.h"

#include <chrono>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/cluster_report.h"
#include "analysis/manifest.h"
#include "analysis/progress.h"
#include "analysis/mesh_info.h"
#include "analysis/output_dir.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/topology.h"

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

void cmd_cluster(const ClusterOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw InputError("", "", "--out", "an output directory is required");
  RunManifest manifest("cluster", opt.argv);
  auto t0 = std::chrono::steady_clock::now();
  const LoadedMesh lm = read_mesh(opt.input);
  manifest.add_timing_ms("read", ms_since(t0));
  manifest.add_input(opt.input);
  const ClusterConfig& c = opt.config;
  manifest.set_parameter("method", to_string(c.method));
  manifest.set_parameter("objective", to_string(c.objective));
  manifest.set_parameter("max_count", c.max_count);
  manifest.set_parameter("max_size", c.max_size);
  manifest.set_parameter("size_bound", c.size_bound_mode == SizeBoundMode::Max ? "max" : "min");
  manifest.set_parameter("sphere", to_string(c.sphere));
  manifest.set_parameter("start", to_string(c.start));
  manifest.set_parameter("gwh_a1", c.gwh.a1);
  manifest.set_parameter("gwh_a2", c.gwh.a2);
  manifest.set_parameter("gwh_weight", c.gwh.weight == GwhWeight::Area ? "area" : "sqrt-area");
  manifest.set_parameter("target_clusters", c.target_clusters);
  manifest.set_parameter("max_triangles", c.max_triangles);

  t0 = std::chrono::steady_clock::now();
  Clustering clustering;
  {
    ProgressBar bar("clustering");
    clustering = cluster_mesh(lm.mesh, c, [&](double f) { bar.update(f); });
  }
  manifest.add_timing_ms("cluster", ms_since(t0));

  t0 = std::chrono::steady_clock::now();
  const EdgeMap edges = EdgeMap::build(lm.mesh.triangles(), lm.mesh.vertex_count());
  ClusterLimits limits;
  if (c.objective != ObjectiveKind::Acc || c.method == ClusterMethod::SahSplit || c.method == ClusterMethod::Meshopt)
    limits.max_vertices = c.max_count;
  const auto issues = validate(clustering, lm.mesh.triangles(), edges, limits);
  if (!issues.empty())  // a failed run: the algorithm broke its own invariants
    throw std::runtime_error("clustering failed validation: " + issues.front());
  manifest.add_timing_ms("validate", ms_since(t0));

  t0 = std::chrono::steady_clock::now();
  const auto rows = cluster_rows(lm.mesh, clustering, c);
  manifest.add_timing_ms("metrics", ms_since(t0));
  const nlohmann::json dist = cluster_distributions(rows);

  t0 = std::chrono::steady_clock::now();
  OutputDir dir(opt.out_dir);
  dir.write("triangles.csv", triangles_csv(clustering).str());
  dir.write("clusters.csv", clusters_csv(rows).str());
  std::vector<std::int32_t> face_cluster;
  for (std::uint32_t k : clustering.cluster_of_triangle()) face_cluster.push_back(static_cast<std::int32_t>(k));
  WriteOptions wo;
  wo.face_values = face_cluster;
  write_mesh(dir.path("clusters.ply"), lm.mesh, wo);
  manifest.add_timing_ms("write", ms_since(t0));
  for (const char* f : {"triangles.csv", "clusters.csv", "clusters.ply", "summary.json"}) manifest.add_output(f);
  manifest.set_result("triangles", lm.mesh.triangle_count());
  manifest.set_result("clusters", clustering.cluster_count());
  manifest.set_result("mean_triangles_per_cluster",
                      clustering.cluster_count() ? double(lm.mesh.triangle_count()) / double(clustering.cluster_count()) : 0.0);
  manifest.set_result("validation", "ok");
  manifest.set_result("distributions", dist);
  nlohmann::json summary = manifest.to_json();
  summary["schema"] = "ptc-cluster-summary/1";
  dir.write("summary.json", dump_json(summary));
  dir.commit();

  if (opt.json) {
    out << dump_json(summary["results"]);
    return;
  }
  const bool uses_objective = c.method == ClusterMethod::Growth || c.method == ClusterMethod::Contraction;
  out << fmt::format("{}: {} triangles -> {} clusters ({}{}, MaxCount {}{}) in {:.0f} ms\n", opt.input.string(),
                     lm.mesh.triangle_count(), clustering.cluster_count(), to_string(c.method),
                     uses_objective ? " / " + std::string(to_string(c.objective)) : std::string(), c.max_count,
                     uses_objective && c.objective == ObjectiveKind::Acc ? fmt::format(", MaxSize {}", c.max_size) : "",
                     summary["timings_ms"]["cluster"].get<double>());
  out << fmt::format("{:<14} {:>12} {:>12} {:>12} {:>12} {:>12}\n", "metric", "min", "p5", "p50", "p95", "max");
  for (const char* k : {"triangles", "vertices", "connectivity", "reg", "acc", "p_hit"}) {
    if (dist[k].is_null()) continue;
    const auto& d = dist[k];
    out << fmt::format("{:<14} {:>12.4g} {:>12.4g} {:>12.4g} {:>12.4g} {:>12.4g}\n", k, d["min"].get<double>(),
                       d["p5"].get<double>(), d["p50"].get<double>(), d["p95"].get<double>(), d["max"].get<double>());
  }
  out << "wrote " << opt.out_dir.string() << "/{triangles.csv,clusters.csv,clusters.ply,summary.json}\n";
}

}  // namespace ptc
