// The front door of clustering (cluster.h): configuration checks, the one enum -> objective type
// dispatch, and the enum <-> string mapping used at the command-line edge.
//
// Configuration rules (std::invalid_argument otherwise):
// - max_size must be finite and >= 0;
// - max_count = max_size = 0: the Standard baseline, one triangle per cluster, for every method
//   and objective (no objective is evaluated);
// - Acc (growth, contraction): max_count > 0 and max_size > 0 (exactly one of them 0 is an error:
//   regBound or sizeBound would divide by 0);
// - Naive, GWH01: max_count >= 3 (their only limit; max_size is not used by them and may be any
//   value >= 0, but max_count = 0 with max_size > 0 is rejected: without a vertex limit they
//   would merge every edge-connected component into one cluster);
// - SahSplit, Meshopt: the checks of sah_split.h / meshopt.h;
// - regions (growth and contraction with Acc or Naive only; ignored elsewhere: the command line
//   refuses it there).
// Acc on a mesh whose AvgSA is 0 (every triangle collapsed to a point) gives one triangle per
// cluster: every sphere has radius 0, so reg = 0 and Acc = -regBound < 0 for every merge.
#include "toolkit/clustering/cluster.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>

#include "toolkit/anim/weld.h"
#include "toolkit/clustering/contraction.h"
#include "toolkit/clustering/growth.h"
#include "toolkit/clustering/meshopt.h"
#include "toolkit/clustering/objectives.h"
#include "toolkit/clustering/regions.h"
#include "toolkit/clustering/sah_split.h"
#include "toolkit/geometry/sphere.h"
#include "toolkit/geometry/triangle.h"

namespace ptc {

namespace {

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) return false;
  return true;
}

Clustering one_per_triangle(const Mesh& mesh) {
  std::vector<std::uint32_t> labels(mesh.triangle_count());
  std::iota(labels.begin(), labels.end(), 0u);
  return clustering_from_labels(labels, mesh.triangles());
}

template <ClusterObjective O>
ClusterRun run_method(const ClusterTables& tables, O& objective, const ClusterConfig& config,
                      const ProgressFn& progress) {
  if (config.method == ClusterMethod::Growth) {
    GrowthOptions o;
    o.start = config.start;
    return grow_clusters(tables, objective, o, progress);
  }
  ContractionOptions o;
  o.target_clusters = config.target_clusters;
  return contract_clusters(tables, objective, o, progress);
}

}  // namespace

namespace detail {

ClusterRun run_objective(const ClusterTables& tables, const ClusterConfig& config, double avg_sa,
                         const ProgressFn& progress) {
  switch (config.objective) {
    case ObjectiveKind::Acc: {
      ClusterParams params;
      params.max_count = config.max_count;
      params.max_size = config.max_size;
      params.avg_sa = avg_sa;
      params.size_bound_mode = config.size_bound_mode;
      params.sphere = config.sphere;
      AccObjective objective(tables, params,
                            config.method == ClusterMethod::Growth ? AccTuning::for_growth() : AccTuning::for_contraction());
      return run_method(tables, objective, config, progress);
    }
    case ObjectiveKind::Naive: {
      NaiveObjective objective(tables, config.max_count);
      return run_method(tables, objective, config, progress);
    }
    case ObjectiveKind::Gwh01: {
      Gwh01Objective objective(tables, config.max_count, config.gwh);
      return run_method(tables, objective, config, progress);
    }
  }
  throw std::invalid_argument("cluster_mesh: unknown objective");
}

}  // namespace detail

std::string_view to_string(ClusterMethod m) {
  switch (m) {
    case ClusterMethod::Growth: return "growth";
    case ClusterMethod::Contraction: return "contraction";
    case ClusterMethod::SahSplit: return "sah-split";
    case ClusterMethod::Meshopt: return "meshopt";
  }
  return "?";
}

std::string_view to_string(ObjectiveKind o) {
  switch (o) {
    case ObjectiveKind::Acc: return "acc";
    case ObjectiveKind::Naive: return "naive";
    case ObjectiveKind::Gwh01: return "gwh01";
  }
  return "?";
}

std::string_view to_string(StartRule s) {
  switch (s) {
    case StartRule::IndexOrder: return "index";
    case StartRule::SpatialOrder: return "spatial";
    case StartRule::FewestFree: return "fewest-free";
  }
  return "?";
}

std::string_view to_string(ClusterAdjacency a) {
  switch (a) {
    case ClusterAdjacency::Auto: return "auto";
    case ClusterAdjacency::Edges: return "edges";
    case ClusterAdjacency::Positions: return "positions";
  }
  return "?";
}

std::optional<ClusterAdjacency> parse_cluster_adjacency(std::string_view s) {
  for (ClusterAdjacency a : {ClusterAdjacency::Auto, ClusterAdjacency::Edges, ClusterAdjacency::Positions})
    if (iequals(s, to_string(a))) return a;
  return std::nullopt;
}

bool is_triangle_soup(const Mesh& mesh) {
  const auto tris = mesh.triangles();
  if (tris.size() < 2) return false;
  // The triangle that first used each vertex; a second triangle using it ends the check.
  std::vector<std::uint32_t> owner(mesh.vertex_count(), 0xffffffffu);
  for (std::uint32_t t = 0; t < tris.size(); ++t)
    for (const std::uint32_t v : tris[t]) {
      if (v >= owner.size()) continue;  // not a valid mesh: let the algorithms report it
      if (owner[v] == 0xffffffffu) owner[v] = t;
      else if (owner[v] != t) return false;
    }
  return true;
}

ClusterAdjacency resolve_adjacency(const Mesh& mesh, ClusterAdjacency a) {
  if (a != ClusterAdjacency::Auto) return a;
  return is_triangle_soup(mesh) ? ClusterAdjacency::Positions : ClusterAdjacency::Edges;
}

ClusterAdjacency adjacency_on(const Mesh& mesh, ClusterAdjacency made_with) {
  return made_with == ClusterAdjacency::Positions ? made_with : resolve_adjacency(mesh, ClusterAdjacency::Auto);
}

namespace {
// The rest-pose weld of `mesh` (one frame: vertices at exactly the same position merge).
WeldMap weld_positions(const Mesh& mesh) {
  VertexWelder w(mesh.vertex_count());
  w.add_frame(mesh.positions());
  return w.finish();
}
}  // namespace

std::vector<Tri> adjacency_triangles(const Mesh& mesh, ClusterAdjacency a) {
  const auto tris = mesh.triangles();
  if (resolve_adjacency(mesh, a) == ClusterAdjacency::Edges || mesh.vertex_count() == 0)
    return {tris.begin(), tris.end()};
  // Each corner replaced by the first vertex at its position (ids of this mesh, so the
  // triangles index its own positions).
  const WeldMap w = weld_positions(mesh);
  std::vector<Tri> out(tris.begin(), tris.end());
  for (Tri& t : out)
    for (std::uint32_t& v : t) v = w.representative[w.remap[v]];
  return out;
}

std::optional<ClusterMethod> parse_cluster_method(std::string_view s) {
  for (ClusterMethod m : {ClusterMethod::Growth, ClusterMethod::Contraction, ClusterMethod::SahSplit,
                          ClusterMethod::Meshopt})
    if (iequals(s, to_string(m))) return m;
  return std::nullopt;
}

std::optional<ObjectiveKind> parse_objective(std::string_view s) {
  for (ObjectiveKind o : {ObjectiveKind::Acc, ObjectiveKind::Naive, ObjectiveKind::Gwh01})
    if (iequals(s, to_string(o))) return o;
  return std::nullopt;
}

std::optional<StartRule> parse_start_rule(std::string_view s) {
  for (StartRule r : {StartRule::IndexOrder, StartRule::SpatialOrder, StartRule::FewestFree})
    if (iequals(s, to_string(r))) return r;
  return std::nullopt;
}

std::vector<std::string_view> used_parameters(const ClusterConfig& c) {
  std::vector<std::string_view> u{"max_count", "max_size"};
  if (c.max_count == 0 && c.max_size == 0.0) return u;  // one triangle per cluster
  switch (c.method) {
    case ClusterMethod::SahSplit:
    case ClusterMethod::Meshopt: return {"max_count", "max_triangles", "adjacency"};
    case ClusterMethod::Growth:
    case ClusterMethod::Contraction: break;
  }
  u = {"objective", "max_count"};
  if (c.objective == ObjectiveKind::Acc) u.insert(u.end(), {"max_size", "size_bound", "sphere"});
  if (c.objective == ObjectiveKind::Gwh01) u.insert(u.end(), {"gwh_a1", "gwh_a2", "gwh_weight"});
  if (c.method == ClusterMethod::Growth) u.push_back("start");
  if (c.objective != ObjectiveKind::Gwh01) u.push_back("regions");  // growth and contraction
  if (c.method == ClusterMethod::Contraction) u.push_back("target_clusters");
  u.push_back("adjacency");
  return u;
}

ClusterLimits limits_of(const ClusterConfig& c) {
  ClusterLimits lim;
  if (c.max_count == 0 && c.max_size == 0.0) {
    lim.max_triangles = 1;
    return lim;
  }
  if (c.method == ClusterMethod::SahSplit) return sah_split_limits(c);
  if (c.method == ClusterMethod::Meshopt) return meshopt_limits(c);
  if (c.objective != ObjectiveKind::Acc) lim.max_vertices = c.max_count;
  return lim;
}

std::optional<ConfigProblem> check(const ClusterConfig& c) {
  if (!(c.max_size >= 0.0) || !std::isfinite(c.max_size))
    return ConfigProblem{"max_size", "MaxSize must be a finite number >= 0"};
  if (c.max_count == 0 && c.max_size == 0.0) return std::nullopt;
  if (c.regions > 1) {
    const bool regional = (c.method == ClusterMethod::Growth || c.method == ClusterMethod::Contraction) &&
                          c.objective != ObjectiveKind::Gwh01;
    if (!regional)
      return ConfigProblem{"regions", "regions are a mode of growth and contraction with the acc or naive objective"};
    if (c.method == ClusterMethod::Contraction && c.target_clusters > 0)
      return ConfigProblem{"regions", "regions cannot be combined with a target cluster count (a target for the "
                                      "whole mesh, not for each region)"};
  }
  if (c.method == ClusterMethod::SahSplit || c.method == ClusterMethod::Meshopt) {
    try {  // the limits' own checks (sah_split.h, meshopt.h: meshoptimizer's bounds)
      (void)(c.method == ClusterMethod::SahSplit ? sah_split_limits(c) : meshopt_limits(c));
    } catch (const std::invalid_argument& e) {
      const std::string why = e.what();
      const auto colon = why.find(": ");
      std::string reason = colon == std::string::npos ? why : why.substr(colon + 2);
      for (auto [from, to] : {std::pair<std::string, std::string>{"max_count", "MaxCount"},
                              {"max_triangles", "the triangle limit"}})
        for (std::size_t p; (p = reason.find(from)) != std::string::npos;) reason.replace(p, from.size(), to);
      return ConfigProblem{why.find("max_triangles") != std::string::npos ? "max_triangles" : "max_count", reason};
    }
    return std::nullopt;
  }
  switch (c.objective) {
    case ObjectiveKind::Acc:
      if (c.max_count == 0 || c.max_size == 0.0)
        return ConfigProblem{c.max_count == 0 ? "max_count" : "max_size",
                             "Acc needs MaxCount > 0 and MaxSize > 0 (both 0: one triangle per cluster)"};
      return std::nullopt;
    case ObjectiveKind::Naive:
    case ObjectiveKind::Gwh01:
      if (c.max_count < 3)
        return ConfigProblem{"max_count", std::string("MaxCount must be >= 3 for the ") +
                                              std::string(to_string(c.objective)) + " objective (its vertex limit)"};
      return std::nullopt;
  }
  return std::nullopt;
}

// The power of two cluster_mesh scales a mesh by (header).
int extreme_scale_exponent(const Mesh& mesh) {
  if (mesh.triangle_count() == 0) return 0;
  const Box3 b = mesh.referenced_bounds();
  if (b.empty() || !b.lo.allFinite() || !b.hi.allFinite()) return 0;
  // Half the extent: finite for any finite box (corners near 1e308 of opposite signs overflow
  // the extent itself, and such a mesh went unscaled: its areas overflowed, found by a new user).
  const double half = (0.5 * b.hi - 0.5 * b.lo).maxCoeff();
  if (!(half > 0.0) || !std::isfinite(half)) return 0;
  const int e = std::ilogb(half) + 1;  // the extent's exponent (2 x half is exact unless it overflows)
  if (e <= 100 && e >= -100) return 0;
  // Every position (unreferenced ones too) must stay a finite normal number where it is not 0.
  double largest = 0.0;
  for (const Vec3& p : mesh.positions()) largest = std::max(largest, p.cwiseAbs().maxCoeff());
  if (!std::isfinite(largest) || std::ilogb(largest) - e > 1000) return 0;
  return -e;
}

Mesh scaled_by_pow2(const Mesh& mesh, int k) {
  std::vector<Vec3> p(mesh.positions().begin(), mesh.positions().end());
  for (Vec3& q : p) q = times_pow2(q, k);
  return mesh.with_positions(std::move(p));
}

Clustering cluster_mesh(const Mesh& mesh, const ClusterConfig& config, const ProgressFn& progress,
                        std::optional<double> known_avg_sa, double* avg_sa_used) {
  if (!(config.max_size >= 0.0) || !std::isfinite(config.max_size))
    throw std::invalid_argument("cluster_mesh: max_size must be finite and >= 0, got " +
                                std::to_string(config.max_size));
  if (config.max_count == 0 && config.max_size == 0.0) {  // the Standard baseline
    if (progress) progress(1.0);
    return one_per_triangle(mesh);
  }
  // A mesh of extreme size clusters as the same mesh times the power of two that brings its
  // triangles' extent near 1 (extreme_scale_exponent; exact, and every method is invariant under
  // it, above): the areas of triangles of 1e-160 units underflow to 0 and those of 1e160 units
  // overflow. Meshes whose extent lies in [2^-100, 2^100] are clustered as they are.
  if (const int k = extreme_scale_exponent(mesh); k != 0) {
    const std::optional<double> known = known_avg_sa ? std::optional<double>(times_pow2(*known_avg_sa, 2 * k)) : std::nullopt;
    double used = std::numeric_limits<double>::quiet_NaN();
    const Clustering c = cluster_mesh(scaled_by_pow2(mesh, k), config, progress, known, &used);
    if (avg_sa_used && !std::isnan(used)) *avg_sa_used = times_pow2(used, -2 * k);  // (the mesh's own units)
    return c;
  }
  // Adjacency by positions: the same method over the welded mesh (same triangles, same order, the
  // same positions per corner), its clusters relabelled onto this mesh's vertex ids.
  if (resolve_adjacency(mesh, config.adjacency) == ClusterAdjacency::Positions && mesh.vertex_count() > 0) {
    const WeldMap w = weld_positions(mesh);
    if (!w.identity()) {
      const Mesh welded(w.apply(mesh.triangles()), w.gather(mesh.positions()));
      ClusterConfig on_welded = config;
      on_welded.adjacency = ClusterAdjacency::Edges;
      const Clustering c = cluster_mesh(welded, on_welded, progress, known_avg_sa, avg_sa_used);
      return clustering_from_labels(c.cluster_of_triangle(), mesh.triangles());
    }
  }
  switch (config.method) {
    case ClusterMethod::SahSplit: return sah_split_clusters(mesh, config);
    case ClusterMethod::Meshopt: return meshopt_clusters(mesh, config);
    case ClusterMethod::Growth:
    case ClusterMethod::Contraction: break;
  }

  // Growth and contraction: the objective's own checks, then the one dispatch (detail::run_objective).
  // Acc on the whole mesh takes AvgSA (and the centroids' box of the start rule) from the pass
  // over the triangles that builds the tables (ClusterTables::build with_sums); in regions each
  // region builds its own tables, so AvgSA is computed alone.
  const bool whole = config.regions <= 1;
  std::optional<ClusterTables> tables;
  auto build_tables = [&](bool with_sums) {
    // Edge lengths only for GWH01 (its boundary term and length scale). The contraction reads
    // the neighbour lists once and, while its clusters stay small, the per-triangle areas and
    // normals rarely: lean tables on large meshes (detail::lean_tables_for).
    tables.emplace(ClusterTables::build(mesh, /*with_edges=*/config.objective == ObjectiveKind::Gwh01, with_sums,
                                        detail::lean_tables_for(config.method, mesh.triangle_count())));
  };
  double avg_sa = 0.0;
  switch (config.objective) {
    case ObjectiveKind::Acc:
      if (config.max_count == 0 || config.max_size == 0.0)
        throw std::invalid_argument("cluster_mesh: Acc needs max_count > 0 and max_size > 0 (both 0 = one triangle "
                                    "per cluster); got max_count " + std::to_string(config.max_count) +
                                    ", max_size " + std::to_string(config.max_size));
      if (mesh.empty()) return Clustering{};
      if (known_avg_sa) {
        avg_sa = *known_avg_sa;
      } else if (whole) {
        build_tables(/*with_sums=*/true);
        avg_sa = tables->avg_sphere_area;
      } else {
        avg_sa = average_triangle_sphere_area(mesh.positions(), mesh.triangles());
      }
      if (avg_sa_used) *avg_sa_used = avg_sa;
      if (std::isinf(avg_sa))  // (a NaN corner, which files cannot hold, leaves one triangle per cluster below)
        throw std::invalid_argument("the mean bounding-sphere area of the triangles (AvgSA, the Acc objective's size "
                                    "scale) is not finite in double precision: the coordinates are too large (scale "
                                    "the mesh)");
      if (!(avg_sa > 0.0)) return one_per_triangle(mesh);  // see the file comment
      break;
    case ObjectiveKind::Naive:
      if (config.max_count == 0)
        throw std::invalid_argument("cluster_mesh: Naive needs max_count >= 3 (its only limit)");
      break;
    case ObjectiveKind::Gwh01:
      if (config.max_count == 0)
        throw std::invalid_argument("cluster_mesh: GWH01 needs max_count >= 3 (its vertex limit)");
      break;
  }
  if (!whole) return cluster_in_regions(mesh, config, avg_sa, progress);
  if (!tables) build_tables(/*with_sums=*/false);
  return clustering_from_labels(detail::run_objective(*tables, config, avg_sa, progress).labels, mesh.triangles());
}

}  // namespace ptc
