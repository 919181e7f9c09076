// `ptc cluster`.
#include "commands/commands.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/metrics/cluster_table.h"
#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "commands/progress.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/geometry/triangle.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/topology.h"
#include "toolkit/core/strings.h"

namespace ptc {

namespace {

// A cluster's metrics measured on the mesh times 2^-k, in the mesh's own units: lengths (the
// sphere, the box) times 2^k, areas times 2^2k (exact unless they leave double's range); the
// ratios (reg, connectivity, p_hit, Acc's terms) are the same at any scale.
void unscale_lengths(ClusterMetrics& m, int k) {
  if (!m.sphere.is_empty()) m.sphere.center = times_pow2(m.sphere.center, k), m.sphere.radius = times_pow2(m.sphere.radius, k);
  if (!m.box.empty()) m.box.lo = times_pow2(m.box.lo, k), m.box.hi = times_pow2(m.box.hi, k);
  m.area = times_pow2(m.area, 2 * k);
  m.area_c = times_pow2(m.area_c, 2 * k);
  m.area_p = times_pow2(m.area_p, 2 * k);
}

// The value of a used parameter, for the manifest.
nlohmann::json value_of(const ClusterConfig& c, std::string_view p) {
  if (p == "objective") return to_string(c.objective);
  if (p == "max_count") return c.max_count;
  if (p == "max_size") return c.max_size;
  if (p == "size_bound") return to_string(c.size_bound_mode);
  if (p == "sphere") return to_string(c.sphere);
  if (p == "start") return to_string(c.start);
  if (p == "gwh_a1") return c.gwh.a1;
  if (p == "gwh_a2") return c.gwh.a2;
  if (p == "gwh_weight") return to_string(c.gwh.weight);
  if (p == "target_clusters") return c.target_clusters;
  if (p == "max_triangles") return c.max_triangles;
  if (p == "regions") return c.regions;
  if (p == "adjacency") return to_string(c.adjacency);
  return nullptr;
}

}  // namespace

std::string flag_of(std::string_view parameter) {
  std::string f = "--" + std::string(parameter);
  for (char& ch : f)
    if (ch == '_') ch = '-';
  return f;
}

void check_cluster_options(const ClusterConfig& c, const std::vector<std::string>& given) {
  const std::vector<std::string_view> used = used_parameters(c);
  for (const std::string& g : given)
    if (std::find(used.begin(), used.end(), g) == used.end()) {
      std::string uses;
      for (std::string_view u : used) uses += (uses.empty() ? "" : ", ") + flag_of(u);
      if (c.max_count == 0 && c.max_size == 0.0)  // one triangle per cluster: no method runs
        throw UsageError(flag_of(g), fmt::format("not used with --max-count 0 --max-size 0 (one triangle per cluster, "
                                                 "whatever the method; it uses {})",
                                                 uses));
      throw UsageError(flag_of(g), fmt::format("not used by --method {}{} (it uses {})", to_string(c.method),
                                               c.method == ClusterMethod::Growth || c.method == ClusterMethod::Contraction
                                                   ? fmt::format(" --objective {}", to_string(c.objective))
                                                   : std::string(),
                                               uses));
    }
  if (const auto p = check(c)) throw UsageError(flag_of(p->parameter), p->reason);
}

void cmd_cluster(const ClusterOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw UsageError("--out", "an output directory is required");
  check_cluster_options(opt.config, opt.given);
  refuse_overwriting_input(opt.out_dir, opt.input);
  RunManifest manifest("cluster", opt.argv, "ptc-cluster/1");
  LoadedMesh lm = read_mesh_recorded(opt.input, manifest);
  std::vector<std::uint32_t>().swap(lm.report.source_face);  // not used here: 4 bytes a triangle
  Stopwatch t0;
  const ClusterConfig& c = opt.config;
  // What the method used, and only that (toolkit/clustering used_parameters).
  manifest.set_parameter("method", to_string(c.method));
  for (std::string_view p : used_parameters(c)) manifest.set_parameter(std::string(p), value_of(c, p));
  // The Acc, reg_bound and size_bound columns of clusters.csv are evaluated for every method
  // with these (for a method without Acc: the defaults), so a clustering of any method can be
  // scored by the paper's objective.
  manifest.set_parameter("metrics", {{"max_count", c.max_count}, {"max_size", c.max_size},
                                     {"size_bound", to_string(c.size_bound_mode)}, {"sphere", "cgal"}});

  OutputDir dir(opt.out_dir);  // a refused target fails before the clustering
  t0.restart();
  Clustering clustering;
  // AvgSA once, for the clustering (Acc) and for the metrics' Acc columns: the clustering's own
  // when an Acc objective ran (on the whole mesh it comes out of the tables' pass), else computed
  // here (the metrics score every method by the paper's objective).
  double acc_avg_sa = std::numeric_limits<double>::quiet_NaN();  // left alone when no Acc objective ran
  // A mesh of extreme size (extreme_scale_exponent: its triangles' extent beyond 2^100 or below
  // 2^-100) is clustered and measured as the same mesh times the power of two 2^pow2 that brings it
  // near 1 (exact, and every method gives the same clusters at either scale: cluster_mesh, which
  // then sees 0), so that its areas neither underflow nor overflow; clusters.csv's lengths
  // and areas are then scaled back.
  const int pow2 = extreme_scale_exponent(lm.mesh);
  std::optional<Mesh> scaled;
  if (pow2 != 0) {
    scaled = scaled_by_pow2(lm.mesh, pow2);
    std::cerr << fmt::format("ptc: note: {}: coordinates of extreme scale: clustered and measured at 2^{} times "
                             "its size (exact); clusters.csv's lengths and areas are in the mesh's units\n",
                             opt.input.string(), pow2);
  }
  const Mesh& work = scaled ? *scaled : lm.mesh;
  {
    ProgressBar bar("clustering");
    try {
      clustering = cluster_mesh(work, c, [&](double f) { bar.update(f); }, std::nullopt, &acc_avg_sa);
    } catch (const std::invalid_argument& e) {  // what the mesh cannot give (the flags were checked before)
      throw InputError(opt.input.string(), "", "", e.what());
    }
  }
  // --target-clusters stops the contraction early, never forces it on: say when it did nothing.
  if (c.method == ClusterMethod::Contraction && c.target_clusters > 0) {
    if (c.target_clusters >= lm.mesh.triangle_count())
      std::cerr << fmt::format("ptc: note: --target-clusters {} is not below the mesh's {}: it stopped nothing\n",
                               c.target_clusters, counted(lm.mesh.triangle_count(), "triangle"));
    else if (clustering.cluster_count() > c.target_clusters)
      std::cerr << fmt::format("ptc: note: the contraction stopped at {} clusters, above --target-clusters {}: its limits "
                               "(--max-count{}) allow no further merge of neighbours, or the mesh has that many parts\n",
                               clustering.cluster_count(), c.target_clusters,
                               c.objective == ObjectiveKind::Acc ? ", --max-size" : "");
  }
  if (acc_avg_sa == 0.0 && !work.empty())
    std::cerr << "ptc: note: " << opt.input.string()
              << ": every triangle collapses to a point (AvgSA = 0): one cluster per triangle; acc, reg_bound and "
                 "size_bound are nan\n";
  const std::optional<double> avg_sa =
      c.max_count > 0 && c.max_size > 0
          ? std::optional<double>(!std::isnan(acc_avg_sa) ? acc_avg_sa
                                                          : average_triangle_sphere_area(work.positions(), work.triangles()))
          : std::nullopt;
  if (avg_sa && std::isinf(*avg_sa))  // (a method without the Acc objective clustered the mesh anyway; cluster_rows leaves them nan)
    std::cerr << "ptc: note: " << opt.input.string()
              << ": the triangles' mean bounding-sphere area (AvgSA) overflows in double precision: acc, reg_bound "
                 "and size_bound are nan\n";
  manifest.add_timing_ms("cluster", t0.ms());

  throw_if_cancelled();  // between stages (a stage of a 13M-triangle mesh takes seconds)
  t0.restart();
  // Connectivity and the vertex limit by the adjacency the clustering grew over.
  const ClusterAdjacency adjacency = resolve_adjacency(lm.mesh, c.adjacency);
  const std::vector<Tri> adjacency_tris =
      adjacency == ClusterAdjacency::Edges ? std::vector<Tri>() : adjacency_triangles(lm.mesh, adjacency);
  const auto issues = validate(clustering, lm.mesh.triangles(), limits_of(c), 20, adjacency_tris);
  if (!issues.empty())  // a failed run: the algorithm broke its own invariants
    throw std::runtime_error("clustering failed validation: " + issues.front());
  manifest.add_timing_ms("validate", t0.ms());

  throw_if_cancelled();  // between stages (a stage of a 13M-triangle mesh takes seconds)
  t0.restart();
  std::vector<ClusterRow> rows = cluster_rows(work, clustering, c, avg_sa, adjacency_tris);
  if (pow2 != 0)
    for (ClusterRow& r : rows) unscale_lengths(r.m, -pow2);  // (a length times 2^-pow2, an area times 2^-2pow2)
  manifest.add_timing_ms("metrics", t0.ms());
  const nlohmann::json dist = cluster_distributions(rows);

  throw_if_cancelled();  // between stages (a stage of a 13M-triangle mesh takes seconds)
  t0.restart();
  std::string tri_schema, cluster_schema;
  // Each triangle's cluster once, for triangles.csv (streamed in blocks: it is 16 bytes a
  // triangle) and as clusters.ply's face values (the same 32 bits read as int32).
  const std::vector<std::uint32_t> label = clustering.cluster_of_triangle();
  tri_schema = write_triangles_csv(label, dir.path("triangles.csv"));
  cluster_schema = write_clusters_csv(rows, dir.path("clusters.csv"));  // in blocks, as triangles.csv
  WriteOptions wo;
  // (int32 and uint32 may alias each other; ids at or above 2^31 read negative, as a cast gave.)
  wo.face_values = std::span<const std::int32_t>(reinterpret_cast<const std::int32_t*>(label.data()), label.size());
  write_mesh(dir.path("clusters.ply"), lm.mesh, wo);
  manifest.add_timing_ms("write", t0.ms());
  manifest.add_output("triangles.csv", tri_schema);
  manifest.add_output("clusters.csv", cluster_schema);
  manifest.add_output("clusters.ply");
  manifest.add_output("summary.json", "ptc-cluster-summary/2");
  manifest.set_result("triangles", lm.mesh.triangle_count());
  manifest.set_result("clusters", clustering.cluster_count());
  manifest.set_result("mean_triangles_per_cluster",
                      clustering.cluster_count() ? double(lm.mesh.triangle_count()) / double(clustering.cluster_count()) : 0.0);
  manifest.set_result("validation", "ok");
  if (c.max_count > 0 || c.max_size > 0) manifest.set_result("adjacency", to_string(adjacency));
  manifest.set_result("distributions", dist);
  // summary.json: the results alone (counts and the distribution of every clusters.csv column).
  nlohmann::json summary = manifest.to_json()["results"];
  summary["schema"] = "ptc-cluster-summary/2";
  dir.write("summary.json", dump_json(summary));
  const nlohmann::json mj = commit_with_manifest(dir, manifest);

  if (opt.json) {
    out << dump_json(summary);
    return;
  }
  const bool uses_objective = c.method == ClusterMethod::Growth || c.method == ClusterMethod::Contraction;
  out << fmt::format("{}: {} -> {} ({}{}, MaxCount {}{}) in {:.0f} ms\n", opt.input.string(),
                     counted(lm.mesh.triangle_count(), "triangle"), counted(clustering.cluster_count(), "cluster"),
                     to_string(c.method),
                     uses_objective ? " / " + std::string(to_string(c.objective)) : std::string(), c.max_count,
                     uses_objective && c.objective == ObjectiveKind::Acc ? fmt::format(", MaxSize {}", c.max_size) : "",
                     mj["timings_ms"]["cluster"].get<double>());
  if (adjacency == ClusterAdjacency::Positions && (c.max_count > 0 || c.max_size > 0))
    out << "adjacency: positions (sides whose corners coincide; "
        << (c.adjacency == ClusterAdjacency::Auto ? "auto: the mesh is a triangle soup" : "--adjacency positions")
        << ")\n";
  out << fmt::format("{:<14} {:>12} {:>12} {:>12} {:>12} {:>12}\n", "metric", "min", "p5", "p50", "p95", "max");
  for (const char* k : {"triangles", "vertices", "connectivity", "reg", "acc", "p_hit"}) {
    if (dist[k].is_null()) continue;
    const auto& d = dist[k];
    out << fmt::format("{:<14} {:>12.4g} {:>12.4g} {:>12.4g} {:>12.4g} {:>12.4g}\n", k, d["min"].get<double>(),
                       d["p5"].get<double>(), d["p50"].get<double>(), d["p95"].get<double>(), d["max"].get<double>());
  }
  out << "wrote " << opt.out_dir.string() << "/{triangles.csv,clusters.csv,clusters.ply,summary.json,manifest.json}\n";
}

}  // namespace ptc
