#include "analysis/metrics/sphere_accuracy.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "toolkit/core/stopwatch.h"
#include "toolkit/clustering/morton_runs.h"
#include "toolkit/geometry/morton.h"

namespace ptc {

std::vector<std::vector<Vec3>> morton_point_sets(const Mesh& mesh, const SphereReportConfig& cfg,
                                                 std::vector<std::uint32_t>* run_first) {
  if (cfg.min_run < 1 || cfg.max_run < cfg.min_run || cfg.max_run > 0xffffffffu)
    throw std::invalid_argument("sphere report: need 1 <= min_run <= max_run");
  const Clustering runs = morton_runs(
      mesh, MortonRunsConfig{static_cast<std::uint32_t>(cfg.min_run), static_cast<std::uint32_t>(cfg.max_run), cfg.seed});
  // A set's points in the order its run first touches them along the Morton order (the order
  // the approximate methods see; the exact radius does not depend on it).
  const std::vector<std::uint32_t> order = morton_order(mesh.positions(), mesh.triangles());
  std::vector<std::uint32_t> rank(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) rank[order[i]] = static_cast<std::uint32_t>(i);
  std::vector<std::vector<Vec3>> sets;
  std::vector<std::uint32_t> stamp(mesh.vertex_count(), 0xffffffffu), tris;
  if (run_first) run_first->assign(runs.triangle_offsets.begin(), runs.triangle_offsets.end());
  for (std::size_t k = 0; k < runs.cluster_count(); ++k) {
    const auto t = runs.triangles_of(k);
    tris.assign(t.begin(), t.end());
    std::sort(tris.begin(), tris.end(), [&](std::uint32_t a, std::uint32_t b) { return rank[a] < rank[b]; });
    std::vector<Vec3> pts;
    Box3 box;
    for (std::uint32_t tri : tris)
      for (std::uint32_t v : mesh.triangle(tri))
        if (stamp[v] != k) {
          stamp[v] = static_cast<std::uint32_t>(k);
          pts.push_back(mesh.position(v));
          box.extend(mesh.position(v));
        }
    // On the set's local coordinates, as the clustering computes every sphere (cluster_metrics'
    // local origin: per axis 0 when the box touches or straddles 0, else its minimum, so p - o is
    // exact far away): in world coordinates the approximate methods' errors grew with the distance
    // from the origin (rel_err_max 5e-16 -> 5e-6 at 2^32) and overstated the routine's own.
    Vec3 origin;
    for (int a = 0; a < 3; ++a) origin[a] = (box.lo[a] <= 0.0 && box.hi[a] >= 0.0) ? 0.0 : box.lo[a];
    for (Vec3& q : pts) q -= origin;
    sets.push_back(std::move(pts));
  }
  return sets;
}

SphereReport run_sphere_report(const Mesh& mesh, const SphereReportConfig& cfg) {
  if (cfg.repeats < 1) throw std::invalid_argument("sphere report: repeats must be >= 1");
  SphereReport r;
  r.config = cfg;
  auto sets = morton_point_sets(mesh, cfg, &r.run_first);
  for (const auto& s : sets) r.run_points.push_back(static_cast<std::uint32_t>(s.size()));
  // Each set scaled by a power of two to a largest coordinate in [1, 2) (exact), as the
  // clustering normalises before CGAL: CGAL answers radius 0 below ~1e-70 and beyond ~1e70, and
  // distances of 1e-300 points underflow (the containment test then passed a radius of 0). The
  // radii are reported in the mesh's units (scaled back, exactly); errors are ratios.
  std::vector<int> exponent(sets.size(), 0);
  for (std::size_t s = 0; s < sets.size(); ++s) {
    double m = 0;
    for (const Vec3& q : sets[s]) m = std::max(m, q.cwiseAbs().maxCoeff());
    if (!(m > 0) || !std::isfinite(m)) continue;
    exponent[s] = std::ilogb(m);
    for (Vec3& q : sets[s]) q = Vec3(std::ldexp(q.x(), -exponent[s]), std::ldexp(q.y(), -exponent[s]), std::ldexp(q.z(), -exponent[s]));
  }

  r.exact_radius.resize(sets.size());
  for (std::size_t s = 0; s < sets.size(); ++s) r.exact_radius[s] = min_sphere_exact(sets[s]).radius;

  for (SphereMethod m : cfg.methods) {
    SphereMethodSummary sum;
    sum.method = m;
    std::vector<double> radii(sets.size());
    std::vector<double> ns(static_cast<std::size_t>(cfg.repeats));
    for (int rep = 0; rep < cfg.repeats; ++rep) {
      Stopwatch t0;
      for (std::size_t s = 0; s < sets.size(); ++s) radii[s] = bounding_sphere(m, sets[s]).radius;
      const double ms = t0.ms();
      ns[static_cast<std::size_t>(rep)] = sets.empty() ? 0.0 : 1e6 * ms / static_cast<double>(sets.size());
    }
    std::sort(ns.begin(), ns.end());
    sum.ns_per_sphere_min = ns.front();
    sum.ns_per_sphere_max = ns.back();
    sum.ns_per_sphere_median = ns.size() % 2 ? ns[ns.size() / 2] : 0.5 * (ns[ns.size() / 2 - 1] + ns[ns.size() / 2]);
    double err_sum = 0;
    sum.rel_err_max = sets.empty() ? 0.0 : -std::numeric_limits<double>::infinity();  // a too-small radius shows
    for (std::size_t s = 0; s < sets.size(); ++s) {
      const double ex = r.exact_radius[s];
      const double err = ex > 0 ? (radii[s] - ex) / ex : radii[s] - ex;
      err_sum += err;
      sum.rel_err_max = std::max(sum.rel_err_max, err);
      // Containment is checked on a recomputed sphere (the timing loop keeps only radii).
      const Sphere sp = bounding_sphere(m, sets[s]);
      if (!contains_all(sp, sets[s], m == SphereMethod::Exact ? exact_containment_tol(sp, sets[s]) : kSphereContainmentTol))
        ++sum.not_containing;
    }
    sum.rel_err_mean = sets.empty() ? 0.0 : err_sum / static_cast<double>(sets.size());
    for (std::size_t s = 0; s < sets.size(); ++s) radii[s] = std::ldexp(radii[s], exponent[s]);  // mesh units
    r.methods.push_back(sum);
    r.radius.push_back(std::move(radii));
  }
  for (std::size_t s = 0; s < sets.size(); ++s) r.exact_radius[s] = std::ldexp(r.exact_radius[s], exponent[s]);
  return r;
}

Table sphere_methods_table(const SphereReport& r) {
  const std::uint64_t sets = r.exact_radius.size();
  return tabulate(Schema{"ptc-spheres", 1}, r.methods, [sets](const SphereMethodSummary& m, Columns& col) {
    col("method", std::string(to_string(m.method)));
    col("point_sets", sets);
    col("ns_per_sphere", m.ns_per_sphere_median);
    col("ns_per_sphere_min", m.ns_per_sphere_min);
    col("ns_per_sphere_max", m.ns_per_sphere_max);
    col("rel_err_mean", m.rel_err_mean);
    col("rel_err_max", m.rel_err_max);
    col("not_containing", m.not_containing);
  });
}

Table sphere_sets_table(const SphereReport& r) {
  struct Row {
    std::uint64_t set = 0, triangles = 0, points = 0;
    SphereMethod method = SphereMethod::Exact;
    double radius = 0, exact = 0;
  };
  std::vector<Row> rows;
  for (std::size_t mi = 0; mi < r.methods.size(); ++mi)
    for (std::size_t s = 0; s < r.exact_radius.size(); ++s)
      rows.push_back({s, r.run_first[s + 1] - r.run_first[s], r.run_points[s], r.methods[mi].method, r.radius[mi][s],
                      r.exact_radius[s]});
  return tabulate(Schema{"ptc-sphere-sets", 1}, rows, [](const Row& x, Columns& col) {
    col("set_id", x.set);
    col("triangles", x.triangles);
    col("points", x.points);
    col("method", std::string(to_string(x.method)));
    col("radius", x.radius);
    col("exact_radius", x.exact);
    col("rel_err", x.exact > 0 ? (x.radius - x.exact) / x.exact : x.radius - x.exact);
  });
}

}  // namespace ptc
