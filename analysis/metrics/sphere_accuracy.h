// Speed against error of the bounding-sphere methods on the clusters of a real mesh: the mesh's
// triangles in Morton order are cut into runs of min_run..max_run triangles (seeded lengths);
// each run's unique vertices form one point set. Every method's radius is compared with the
// exact minimal radius, point set by point set, and every method is timed over all point sets
// (one thread, `repeats` times, median reported).
#pragma once

#include <cstdint>
#include <vector>

#include "analysis/schema/table.h"
#include "toolkit/geometry/sphere.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

struct SphereReportConfig {
  std::size_t min_run = 64;   ///< fewest triangles per point set (>= 1)
  std::size_t max_run = 128;  ///< most triangles per point set (>= min_run)
  std::uint64_t seed = 1;     ///< seeds the run lengths
  int repeats = 5;            ///< timing repetitions per method (>= 1); median reported
  std::vector<SphereMethod> methods{std::begin(kAllSphereMethods), std::end(kAllSphereMethods)};
};

struct SphereMethodSummary {
  SphereMethod method;
  double ns_per_sphere_median = 0, ns_per_sphere_min = 0, ns_per_sphere_max = 0;
  double rel_err_mean = 0, rel_err_max = 0;  ///< (r - r_exact) / r_exact over the point sets
  std::size_t not_containing = 0;            ///< point sets whose sphere misses a point (contains_all false)
};

struct SphereReport {
  SphereReportConfig config;
  std::vector<std::uint32_t> run_first;    ///< first index into the Morton order, per point set (+ end)
  std::vector<std::uint32_t> run_points;   ///< unique vertices per point set
  std::vector<double> exact_radius;        ///< per point set
  std::vector<SphereMethodSummary> methods;
  std::vector<std::vector<double>> radius; ///< [method][point set]
};

/// The point sets the report measures: the mesh's triangles in Morton order cut into runs of
/// seeded length in [min_run, max_run]; each set holds its run's unique vertices.
/// `run_first` receives each run's first index into the Morton order (plus the end).
[[nodiscard]] std::vector<std::vector<Vec3>> morton_point_sets(const Mesh& mesh, const SphereReportConfig& config,
                                                               std::vector<std::uint32_t>* run_first = nullptr);

/// Throws std::invalid_argument on a bad configuration; an empty mesh gives an empty report.
[[nodiscard]] SphereReport run_sphere_report(const Mesh& mesh, const SphereReportConfig& config);

/// One row per method: method, point_sets, ns_per_sphere (median), min, max, rel_err_mean, rel_err_max, not_containing.
[[nodiscard]] Table sphere_methods_table(const SphereReport& r);  ///< spheres.csv, schema ptc-spheres/1
/// One row per (point set, method): set_id, triangles, points, method, radius, exact_radius, rel_err.
[[nodiscard]] Table sphere_sets_table(const SphereReport& r);  ///< sphere_sets.csv, schema ptc-sphere-sets/1

}  // namespace ptc
