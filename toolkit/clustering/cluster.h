// The front door of clustering: one configuration struct, one call. Strings from the command
// line become these enums at the edge (apps/ptc); algorithms never look anything up by name.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "toolkit/clustering/clustering.h"
#include "toolkit/geometry/cluster_metrics.h"
#include "toolkit/geometry/gwh01.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

enum class ClusterMethod {
  Growth,       ///< iterative growth from start triangles (method.md)
  Contraction,  ///< dual-graph edge contraction, best merge first (method.md, after GWH01)
  SahSplit,     ///< top-down SAH split into clusters of bounded triangle/vertex count (modern baseline)
  Meshopt,      ///< meshoptimizer 0.18 meshopt_buildMeshlets (modern baseline)
};
enum class ObjectiveKind {
  Acc,    ///< Garanzha: Acc = reg - regBound * sizeBound (larger is better; merge while > 0)
  Naive,  ///< "SAH clusters": Naive = sum 2 Area_i / SA(box), bounded by MaxCount vertices
  Gwh01,  ///< Garland-Willmott-Heckbert 2001: cost E_fit + a1 E_dir + a2 E_shape (lower is better)
};
enum class StartRule {
  IndexOrder,     ///< next untaken triangle in index order
  SpatialOrder,   ///< next untaken triangle in Morton order of centroids
  FewestFree,     ///< untaken triangle with the fewest untaken edge neighbours (ties: Morton order)
};

/// Which triangles count as neighbours while clusters grow or merge (docs/clustering.md,
/// "Adjacency"). Edges: triangles sharing a side by vertex ids (the paper's mesh edges).
/// Positions: triangles sharing a side whose corner positions coincide exactly in the mesh given
/// (the rest pose): a triangle soup, as the explode deformer or an STL-like pipeline hands it
/// over, clusters like the connected mesh it came from. Auto: Positions for a triangle soup (no
/// vertex used by two triangles, at least two triangles), Edges otherwise.
enum class ClusterAdjacency {
  Auto,
  Edges,
  Positions,
};

[[nodiscard]] std::string_view to_string(ClusterMethod m);
[[nodiscard]] std::string_view to_string(ClusterAdjacency a);
[[nodiscard]] std::optional<ClusterAdjacency> parse_cluster_adjacency(std::string_view s);  ///< auto|edges|positions
[[nodiscard]] std::string_view to_string(ObjectiveKind o);
[[nodiscard]] std::string_view to_string(StartRule s);
[[nodiscard]] std::optional<ClusterMethod> parse_cluster_method(std::string_view s);   ///< growth|contraction|sah-split|meshopt
[[nodiscard]] std::optional<ObjectiveKind> parse_objective(std::string_view s);        ///< acc|naive|gwh01
[[nodiscard]] std::optional<StartRule> parse_start_rule(std::string_view s);          ///< index|spatial|fewest-free

struct ClusterConfig {
  ClusterMethod method = ClusterMethod::Contraction;
  ObjectiveKind objective = ObjectiveKind::Acc;
  /// MaxCount (paper; vertices): Acc's regBound = N_V / MaxCount; Naive's and GWH01's hard
  /// vertex limit; the SAH split's and meshopt's vertex limit. 0 together with max_size = 0
  /// means "no clustering": one triangle per cluster (the paper's Standard baseline).
  std::uint32_t max_count = 50;
  /// MaxSize (paper; in units of AvgSA): Acc's sizeBound. Only Acc uses it.
  double max_size = 50;
  SizeBoundMode size_bound_mode = SizeBoundMode::Max;
  SphereMethod sphere = SphereMethod::Cgal;       ///< sphere inside the objective loop
  StartRule start = StartRule::SpatialOrder;      ///< growth only
  GwhParams gwh{};                                ///< GWH01 weights (a1 = 0.2, a2 = 2, area weights)
  std::uint32_t target_clusters = 0;              ///< GWH01 contraction: stop at this many clusters (0 = only MaxCount stops)
  std::uint32_t max_triangles = 0;                ///< SAH split / meshopt: triangle limit per cluster (0 = 2 * max_count)
  /// Growth and contraction with Acc or Naive: 0 or 1 = one run over the whole mesh; N >= 2 =
  /// cluster N spatial regions at once (regions.h: clusters stop at region borders; the same
  /// clusters at any thread count).
  std::uint32_t regions = 0;
  ClusterAdjacency adjacency = ClusterAdjacency::Auto;  ///< every method (not one triangle per cluster)
};

/// Whether no vertex is used by two triangles and there are at least two: a triangle soup.
[[nodiscard]] bool is_triangle_soup(const Mesh& mesh);
/// Auto resolved for this mesh (Edges and Positions stay as they are).
[[nodiscard]] ClusterAdjacency resolve_adjacency(const Mesh& mesh, ClusterAdjacency a);
/// The adjacency under which a clustering made (elsewhere) with `made_with` is read on `mesh`, a
/// scene's rest mesh that may be a soup of the mesh it was made on (the explode deformer splits
/// every vertex; a frame sequence without welding): coincident corners when it was made so, or
/// when `mesh` is a soup (Auto's rule); edges otherwise. ptc viz and the experiments read a
/// given clustering with it, so that both see the same neighbours.
[[nodiscard]] ClusterAdjacency adjacency_on(const Mesh& mesh, ClusterAdjacency made_with);
/// The triangles whose shared sides are the adjacency `a` (resolved here if Auto): Edges, the
/// mesh's own; Positions, the mesh's triangles with every vertex replaced by the first vertex at
/// exactly its position (==, so -0.0 equals +0.0; a NaN equals nothing). Same count and order as
/// the mesh's: validate(clustering, mesh.triangles(), limits, n, adjacency_triangles(...))
/// checks a clustering made with `a`.
[[nodiscard]] std::vector<Tri> adjacency_triangles(const Mesh& mesh, ClusterAdjacency a);

/// What a configuration uses, asked of the clustering layer (not decided by a command): the
/// parameters of ClusterConfig that cluster_mesh reads for this method and objective, by name:
/// "objective", "max_count", "max_size", "size_bound", "sphere", "start", "gwh_a1", "gwh_a2",
/// "gwh_weight", "target_clusters", "max_triangles". For example sah-split and meshopt read
/// max_count and max_triangles only; Naive and GWH01 never read max_size; only growth reads
/// start; only contraction reads target_clusters; MaxCount = MaxSize = 0 (one triangle per
/// cluster) reads nothing else.
[[nodiscard]] std::vector<std::string_view> used_parameters(const ClusterConfig& config);

/// Every name used_parameters() can return.
inline constexpr std::string_view kClusterParameters[] = {"objective", "max_count",       "max_size",     "size_bound",
                                                          "sphere",    "start",           "gwh_a1",       "gwh_a2",
                                                          "gwh_weight", "target_clusters", "max_triangles", "regions",
                                                          "adjacency"};

/// The hard limits every cluster of cluster_mesh(mesh, config) keeps (for validate()):
/// sah-split and meshopt their vertex and triangle limits, Naive and GWH01 MaxCount vertices,
/// Acc none (its bounds are soft), MaxCount = MaxSize = 0 one triangle.
[[nodiscard]] ClusterLimits limits_of(const ClusterConfig& config);

/// A configuration cluster_mesh would refuse: the parameter (a name of used_parameters) and the
/// reason in the paper's words ("MaxCount must be >= 3 for the Naive objective").
struct ConfigProblem {
  std::string parameter;
  std::string reason;
};
/// The first problem of the configuration, or nullopt when cluster_mesh accepts it.
[[nodiscard]] std::optional<ConfigProblem> check(const ClusterConfig& config);

/// Progress callback: fraction done in [0, 1]; called at most a few hundred times.
using ProgressFn = std::function<void(double)>;

/// The power of two by which cluster_mesh scales a mesh of extreme size before clustering it
/// (exact, so the same clusters as at an ordinary size): minus the binary exponent of its
/// triangles' extent (the largest side of the referenced vertices' box) when that lies beyond
/// 2^100 or below 2^-100 and every position times the power stays finite (a small mesh far from
/// the origin may not be scaled: its coordinates would overflow); else 0. A stray unreferenced
/// vertex does not count.
[[nodiscard]] int extreme_scale_exponent(const Mesh& mesh);
/// The mesh with every position times 2^k (exact where the results are normal doubles), the
/// same triangles.
[[nodiscard]] Mesh scaled_by_pow2(const Mesh& mesh, int k);

/// Clusters the mesh's triangles. Deterministic (same input, same output, bit for bit, every
/// method; tested). Invariance (tested in clustering_frontdoor_test and the method tests):
/// - rigid motion (rotation + translation; up to rounding ties): contraction with Acc or GWH01;
///   growth with Acc or GWH01 and StartRule::IndexOrder (the spatial and fewest-free rules order
///   by Morton code, which is axis-aligned: translation only);
/// - NOT rotation: the Naive objective (it scores axis-aligned boxes), sah-split (axis-aligned
///   planes), meshopt (axis-aligned kd-tree and start); all of them are invariant under uniform
///   scaling by a power of two (exact in floating point), and a rotated input is still clustered
///   validly. Translation changes only rounding for them.
/// Throws std::invalid_argument on an inconsistent configuration (e.g. max_count = 0 with
/// max_size > 0). avg_sa: the mesh's AvgSA, average_triangle_sphere_area(mesh), when the caller
/// has it already; computed here otherwise. Read by the Acc objective only. avg_sa_used, when
/// not null, receives the AvgSA the Acc objective ran with (the given one or the one computed
/// here, average_triangle_sphere_area's value bit for bit), and is left alone when no Acc
/// objective ran. ptc cluster takes it from there for the metrics: on the whole mesh the value
/// comes out of the pass that builds the clustering's tables, which a separate pass would
/// repeat (0.6 s at 13M triangles).
[[nodiscard]] Clustering cluster_mesh(const Mesh& mesh, const ClusterConfig& config, const ProgressFn& progress = {},
                                      std::optional<double> avg_sa = std::nullopt, double* avg_sa_used = nullptr);

struct ClusterTables;
struct ClusterRun;
namespace detail {
/// Internal (cluster_mesh and regions.h): config's objective over `tables` (avg_sa: Acc's AvgSA),
/// then growth or contraction by config.method.
[[nodiscard]] ClusterRun run_objective(const ClusterTables& tables, const ClusterConfig& config, double avg_sa,
                                       const ProgressFn& progress);
/// The contraction's tables are lean (ClusterTables::build lean: no stored areas and normals,
/// 48 bytes a triangle less) from this many triangles of the mesh on (regions: of the whole
/// mesh, not of the region). Below it they
/// keep the areas and normals: a contraction whose clusters grow large (high --max-count and
/// --max-size, --target-clusters) reads them for every member of a pair it evaluates, and
/// remaking them was 80% of such a run (docs/scale.md, "Lean tables from 2M triangles").
/// Either way the same clusters bit for bit.
inline constexpr std::uint32_t kLeanContractionTriangles = 1u << 21;
/// What the lean tables leave out, bytes a triangle: the area (8) and normal (24) and the
/// neighbour list (an offset and about three neighbours, 16). ptc info's memory model adds it to
/// the contraction's rate below kLeanContractionTriangles (measured: docs/scale.md).
inline constexpr double kLeanSavedBytesPerTriangle = 48;
/// Whether cluster_mesh builds lean tables for this method on a mesh of `triangles`.
[[nodiscard]] inline bool lean_tables_for(ClusterMethod method, std::size_t triangles) {
  return method == ClusterMethod::Contraction && triangles >= kLeanContractionTriangles;
}
}  // namespace detail

}  // namespace ptc
