// The cost terms of hierarchical face clustering after Garland, Willmott, Heckbert 2001
// ("GWH01"; docs/method.md, "Baseline clusterings" 3): planarity E_fit from a point quadric,
// orientation E_dir, and shape E_shape from the irregularity gamma = P^2 / (4 pi A).
// The contraction algorithm that uses them lives elsewhere; these are pure functions.
#pragma once

#include <optional>
#include <string_view>
#include <cstdint>
#include <span>

#include <Eigen/Core>

#include "toolkit/core/types.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

/// Point quadric (method.md: A = sum p p^T, b = sum p, c = count), stored RELATIVE TO AN ORIGIN o:
/// A = sum w q q^T, b = sum w q, c = sum w with q = p - o.
///
/// Why an origin: the covariance A - b b^T / c cancels catastrophically when the points are far
/// from the coordinate origin (1e7 offset, 1e-3 features: the raw sums agree in all 16 digits and
/// the covariance is lost). With o inside the cluster every q is of the cluster's size and the
/// differences p - o of nearby doubles are exact.
/// Precision guarantee: with D = max |p - o| over the added points, the covariance entries (and
/// so c * E_fit) are accurate to about 10 eps c D^2 (eps = 2.2e-16), whatever the absolute
/// position; the normal's angular error is about that divided by the gap between the two
/// smallest eigenvalues. Keep o within the cluster (the default does) to make D the cluster size.
/// So exactly coplanar points give E_fit ~ 1e-16 times their spread, not 0, and a 1e7 offset with
/// 1e-3 features keeps the normal to ~1e-15 (tested).
///
/// Origin rule: Quadric(o) fixes o; a default-constructed Quadric has no origin yet and adopts
/// the first point added (or the origin of the first non-empty quadric added to it).
/// operator+= re-expresses the other quadric at this origin (exact when the origins are equal;
/// otherwise accurate when |o1 - o2| is of the order of the clusters' size, as for neighbours).
/// Weights w must be >= 0 (finite); add(p, w) is add(p) w times.
struct Quadric {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Vec3 b = Vec3::Zero();
  double c = 0;
  Vec3 origin = Vec3::Zero();
  bool has_origin = false;

  Quadric() = default;
  explicit Quadric(const Vec3& o) : origin(o), has_origin(true) {}

  void add(const Vec3& p, double w = 1);
  Quadric& operator+=(const Quadric& other);
  /// The same point set expressed relative to `new_origin`.
  [[nodiscard]] Quadric shifted(const Vec3& new_origin) const;
  [[nodiscard]] bool empty() const { return c == 0; }
};

/// Relative threshold of fit_plane's orientation test (see there).
inline constexpr double kOrientationTol = 1e-12;

/// Least-squares plane {x : normal . x + offset = 0} of a quadric's points.
struct PlaneFit {
  Vec3 normal = Vec3::UnitZ();   ///< unit normal (orientation: see fit_plane)
  double offset = 0;             ///< -normal . centroid (L); far from the origin prefer `centroid`
  double e_fit = 0;              ///< E_fit: mean (weighted) squared distance of the points to the plane (L^2), >= 0
  Vec3 centroid = Vec3::Zero();  ///< b / c + origin: a point of the plane (absolute, rounded to ulp(|centroid|))
};

/// Fits the plane (method.md, GWH01 E_fit): covariance Z = A - b b^T / c, normal = eigenvector of
/// the smallest eigenvalue (Eigen SelfAdjointEigenSolver::compute, the iterative QR solver:
/// computeDirect's closed form loses ~5e-9 in the eigenvectors when eigenvalues repeat, e.g. for
/// points on a circle), E_fit = smallest eigenvalue / c (clamped to >= 0 against rounding).
/// Orientation: normal . ref > 0 when |normal . ref| > kOrientationTol |ref| (pass e.g. the
/// area-weighted normal sum); otherwise (ref zero, or orthogonal up to rounding, where the sign of
/// the dot product would be noise) the normal's largest-magnitude component (the first on exact
/// ties) is made positive, so the result is deterministic.
/// Degenerate inputs: an empty quadric gives the default PlaneFit ((0,0,1), 0, 0, origin);
/// fewer than three distinct points or collinear points give e_fit = 0 and a normal from the
/// repeated eigenvalue's eigenspace (any unit vector orthogonal to the points' line, as returned
/// by Eigen; deterministic for a given input). A symmetric point set (all eigenvalues equal, e.g.
/// an octahedron's vertices) likewise gives a valid but arbitrary normal and the exact e_fit.
[[nodiscard]] PlaneFit fit_plane(const Quadric& q, const Vec3& ref = Vec3::Zero());

/// Weights of E_dir: Area (w_i = Area_i, method.md's formula) or SqrtArea (w_i = sqrt(Area_i),
/// what Garland's code does; the term is then no longer scale-invariant: unit 1/L).
enum class GwhWeight { Area, SqrtArea };
/// "area", "sqrt-area".
[[nodiscard]] std::string_view to_string(GwhWeight w);
[[nodiscard]] std::optional<GwhWeight> parse_gwh_weight(std::string_view s);

/// E_dir = sum_i w_i (1 - n . n_i)^2 / sum_i Area_i (GWH01; method.md). `plane_normal` is the
/// fitted unit normal n, n_i the triangles' unit normals (zero for degenerate triangles, whose
/// Area_i = 0 gives them weight 0). Range [0, 4] for Area weights. Returns 0 when sum Area_i = 0.
/// Throws std::invalid_argument if the spans differ in size.
[[nodiscard]] double e_dir(const Vec3& plane_normal, std::span<const Vec3> unit_normals, std::span<const double> areas,
                           GwhWeight weight = GwhWeight::Area);

/// Irregularity gamma = P^2 / (4 pi A) (GWH01): 1 for a disc, 4/pi for a square; a curved
/// surface can go below 1 (a closed one has P = 0, gamma = 0). A = 0 gives +inf (also when
/// P = 0: an empty or zero-area cluster is maximally irregular). Requires P >= 0, A >= 0.
[[nodiscard]] double irregularity(double perimeter, double area);

/// E_shape of a merge (GWH01; method.md): max(0, (gamma_new - max(gamma_1, gamma_2)) / gamma_new);
/// only a worsening counts. Range [0, 1]. Conventions: 0 when gamma_new <= max(gamma_1, gamma_2)
/// (including gamma_new = 0 and gamma_new = max = +inf); 1 when gamma_new = +inf > max. NaN in,
/// NaN out.
[[nodiscard]] double shape_cost(double gamma_new, double gamma_1, double gamma_2);

/// The GWH01 terms of one cluster.
struct GwhTerms {
  PlaneFit fit;          ///< quadric of the cluster's distinct vertices, oriented by the area-weighted normal sum
  double e_dir = 0;      ///< e_dir(fit.normal, triangle normals, areas, weight)
  double perimeter = 0;  ///< total length of the boundary edges (L)
  double area = 0;       ///< sum_i Area_i (one side, L^2)
  double gamma = 0;      ///< irregularity(perimeter, area)
};

/// Computes GwhTerms for the triangles `triangle_ids` of `mesh` (a set: distinct ids <
/// triangle_count(), otherwise std::invalid_argument). The quadric's origin is the cluster's
/// lowest-index vertex. Boundary edges are the undirected edges used by exactly one triangle of
/// the cluster (a triangle that uses an edge twice, as (a, b, a), counts once; collapsed sides
/// with equal indices are not edges; edges used by three or more are not boundary) — the policy
/// of toolkit/mesh/topology.h. Empty cluster: default terms with gamma = +inf.
[[nodiscard]] GwhTerms gwh_terms(const Mesh& mesh, std::span<const std::uint32_t> triangle_ids,
                                 GwhWeight weight = GwhWeight::Area);

/// Weights of the GWH01 cost, defaults from the paper as used by Garanzha 2009 (method.md).
struct GwhParams {
  double a1 = 0.2;                      ///< weight of E_dir (dimensionless), >= 0
  double a2 = 2.0;                      ///< weight of E_shape (dimensionless), >= 0
  GwhWeight weight = GwhWeight::Area;   ///< E_dir weighting (for callers computing gwh_terms)
};

/// Cost of merging clusters 1 and 2 into `merged` (lower is better; GWH01 contracts the lowest):
/// E_fit(merged) + a1 * E_dir(merged) + a2 * shape_cost(gamma_merged, gamma_1, gamma_2).
/// Note: E_fit has unit L^2 while the other terms are dimensionless, so the sum depends on the
/// mesh's scale; this function does not normalise it.
[[nodiscard]] double gwh_cost(const GwhTerms& merged, const GwhTerms& part1, const GwhTerms& part2,
                              const GwhParams& params = {});

}  // namespace ptc
