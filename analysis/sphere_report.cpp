#include "analysis/sphere_report.h"

#include <algorithm>
#include <chrono>
#include <random>
#include <limits>
#include <stdexcept>

#include "toolkit/geometry/morton.h"

namespace ptc {

std::vector<std::vector<Vec3>> morton_point_sets(const Mesh& mesh, const SphereReportConfig& cfg,
                                                 std::vector<std::uint32_t>* run_first) {
  if (cfg.min_run < 1 || cfg.max_run < cfg.min_run)
    throw std::invalid_argument("sphere report: need 1 <= min_run <= max_run");
  const auto order = morton_order(mesh.positions(), mesh.triangles());
  std::mt19937_64 rng(cfg.seed);
  std::uniform_int_distribution<std::size_t> len(cfg.min_run, cfg.max_run);
  std::vector<std::vector<Vec3>> sets;
  std::vector<std::uint32_t> stamp(mesh.vertex_count(), 0xffffffffu);
  if (run_first) run_first->clear();
  for (std::size_t first = 0; first < order.size();) {
    const std::size_t last = std::min(order.size(), first + len(rng));
    const auto id = static_cast<std::uint32_t>(sets.size());
    std::vector<Vec3> pts;
    for (std::size_t i = first; i < last; ++i)
      for (std::uint32_t v : mesh.triangle(order[i]))
        if (stamp[v] != id) {
          stamp[v] = id;
          pts.push_back(mesh.position(v));
        }
    if (run_first) run_first->push_back(static_cast<std::uint32_t>(first));
    sets.push_back(std::move(pts));
    first = last;
  }
  if (run_first) run_first->push_back(static_cast<std::uint32_t>(order.size()));
  return sets;
}

SphereReport run_sphere_report(const Mesh& mesh, const SphereReportConfig& cfg) {
  if (cfg.repeats < 1) throw std::invalid_argument("sphere report: repeats must be >= 1");
  SphereReport r;
  r.config = cfg;
  const auto sets = morton_point_sets(mesh, cfg, &r.run_first);
  for (const auto& s : sets) r.run_points.push_back(static_cast<std::uint32_t>(s.size()));

  r.exact_radius.resize(sets.size());
  for (std::size_t s = 0; s < sets.size(); ++s) r.exact_radius[s] = min_sphere_exact(sets[s]).radius;

  for (SphereMethod m : cfg.methods) {
    SphereMethodSummary sum;
    sum.method = m;
    std::vector<double> radii(sets.size());
    std::vector<double> ns(static_cast<std::size_t>(cfg.repeats));
    for (int rep = 0; rep < cfg.repeats; ++rep) {
      const auto t0 = std::chrono::steady_clock::now();
      for (std::size_t s = 0; s < sets.size(); ++s) radii[s] = bounding_sphere(m, sets[s]).radius;
      const auto t1 = std::chrono::steady_clock::now();
      ns[static_cast<std::size_t>(rep)] =
          sets.empty() ? 0.0 : std::chrono::duration<double, std::nano>(t1 - t0).count() / static_cast<double>(sets.size());
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
    r.methods.push_back(sum);
    r.radius.push_back(std::move(radii));
  }
  return r;
}

CsvTable sphere_methods_csv(const SphereReport& r) {
  CsvTable t({"method", "point_sets", "ns_per_sphere", "ns_per_sphere_min", "ns_per_sphere_max", "rel_err_mean",
              "rel_err_max", "not_containing"});
  for (const auto& m : r.methods)
    t.add_row({std::string(to_string(m.method)), static_cast<std::uint64_t>(r.exact_radius.size()),
               m.ns_per_sphere_median, m.ns_per_sphere_min, m.ns_per_sphere_max, m.rel_err_mean, m.rel_err_max,
               static_cast<std::uint64_t>(m.not_containing)});
  return t;
}

CsvTable sphere_sets_csv(const SphereReport& r) {
  CsvTable t({"set_id", "triangles", "points", "method", "radius", "exact_radius", "rel_err"});
  for (std::size_t mi = 0; mi < r.methods.size(); ++mi)
    for (std::size_t s = 0; s < r.exact_radius.size(); ++s) {
      const double ex = r.exact_radius[s], rad = r.radius[mi][s];
      t.add_row({static_cast<std::uint64_t>(s), static_cast<std::uint64_t>(r.run_first[s + 1] - r.run_first[s]),
                 static_cast<std::uint64_t>(r.run_points[s]), std::string(to_string(r.methods[mi].method)), rad, ex,
                 ex > 0 ? (rad - ex) / ex : rad - ex});
    }
  return t;
}

}  // namespace ptc
