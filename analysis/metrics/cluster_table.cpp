#include "analysis/metrics/cluster_table.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include <oneapi/tbb/parallel_for.h>

#include "analysis/schema/json.h"
#include "toolkit/io/atomic_file.h"
#include "toolkit/mesh/mesh_report.h"

namespace ptc {

std::vector<ClusterRow> cluster_rows(const Mesh& mesh, const Clustering& c, const ClusterConfig& cfg,
                                     std::optional<double> avg_sa, std::span<const Tri> adjacency) {
  if (!adjacency.empty() && adjacency.size() != mesh.triangle_count())
    throw std::invalid_argument("cluster_rows: the adjacency has " + std::to_string(adjacency.size()) +
                                " triangles, the mesh " + std::to_string(mesh.triangle_count()));
  std::vector<ClusterRow> rows(c.cluster_count());
  const bool has_objective = cfg.max_count > 0 && cfg.max_size > 0;
  ClusterParams params;
  if (has_objective) {
    params.max_count = cfg.max_count;
    params.max_size = cfg.max_size;
    params.size_bound_mode = cfg.size_bound_mode;
    params.avg_sa = avg_sa ? *avg_sa : average_triangle_sphere_area(mesh.positions(), mesh.triangles());
  }
  const bool usable = has_objective && params.avg_sa > 0 && std::isfinite(params.avg_sa);  // (inf: coordinates near the double range)
  // The clustering's vertex lists, when it has them (offsets per cluster, ending at the list's
  // end); else each cluster's are made from its triangles.
  const bool lists = c.vertex_offsets.size() == c.triangle_offsets.size() && !c.vertex_offsets.empty() &&
                     c.vertex_offsets.back() == c.vertices.size() &&
                     std::is_sorted(c.vertex_offsets.begin(), c.vertex_offsets.end());
  oneapi::tbb::parallel_for(std::size_t{0}, rows.size(), [&](std::size_t k) {
    ClusterRow& r = rows[k];
    r.m = cluster_metrics(mesh, c.triangles_of(k), SphereMethod::Cgal,
                          lists ? c.vertices_of(k) : std::span<const std::uint32_t>());
    if (!adjacency.empty() && r.m.triangles > 0) {
      // The vertex count of the adjacency (distinct rest positions), as the objective counted.
      std::vector<std::uint32_t> ids;
      ids.reserve(3 * r.m.triangles);
      for (const std::uint32_t t : c.triangles_of(k))
        if (t < adjacency.size()) ids.insert(ids.end(), adjacency[t].begin(), adjacency[t].end());
      std::sort(ids.begin(), ids.end());
      r.m.vertices = static_cast<std::size_t>(std::unique(ids.begin(), ids.end()) - ids.begin());
      r.m.connectivity = static_cast<double>(r.m.triangles) / static_cast<double>(r.m.vertices);
    }
    if (usable) {
      r.reg_bound = reg_bound(r.m.vertices, params.max_count);
      r.size_bound = size_bound(r.m.sphere.surface_area(), params.max_size, params.avg_sa, params.size_bound_mode);
      r.acc = acc(r.m.reg, r.reg_bound, r.size_bound);
    } else {
      r.acc = r.reg_bound = r.size_bound = std::numeric_limits<double>::quiet_NaN();
    }
  });
  return rows;
}

namespace {
const Schema kTrianglesSchema{"ptc-cluster-triangles", 1};
}  // namespace

Table triangles_table(const Clustering& c) {
  struct Row {
    std::uint64_t triangle = 0, cluster = 0;
  };
  const auto label = c.cluster_of_triangle();
  auto digits = [](std::size_t v) {
    std::size_t d = 1;
    for (; v >= 10; v /= 10) ++d;
    return d;
  };
  const std::size_t n = label.size(), most = n ? digits(n - 1) + digits(c.cluster_count()) + 2 : 0;
  return tabulate_each<Row>(
      kTrianglesSchema, n, [&](std::size_t i) { return Row{i, label[i]}; },
      [](const Row& r, Columns& col) {
        col("triangle_id", r.triangle);
        col("cluster_id", r.cluster);
      },
      64 + n * most);  // a bound on the text: the header and the longest row n times
}

std::string write_triangles_csv(std::span<const std::uint32_t> label, const std::filesystem::path& path) {
  // (Not through stream_each: its rows of two integers formatted in place, file included, take
  // half the time of the generic rows of variants: 0.06 against 0.13 s for 3.3M rows.)
  constexpr std::size_t kBlock = kCsvBlockBytes;
  AtomicFile f(path);
  std::string buf;
  buf.reserve(kBlock + 64);
  buf = "triangle_id,cluster_id\n";
  char* end = nullptr;
  for (std::size_t t = 0; t < label.size(); ++t) {
    char row[48];
    end = std::to_chars(row, row + 24, t).ptr;
    *end++ = ',';
    end = std::to_chars(end, row + sizeof row - 1, label[t]).ptr;
    *end++ = '\n';
    buf.append(row, end);
    if (buf.size() >= kBlock) {
      f.write(buf);
      buf.clear();
    }
  }
  f.write(buf);
  f.commit();
  return kTrianglesSchema.id();
}

namespace {
// Column name -> value, the one place that defines clusters.csv and the distributions.
template <class F>
void for_each_metric(const ClusterRow& r, F&& f) {
  f("triangles", static_cast<double>(r.m.triangles));
  f("vertices", static_cast<double>(r.m.vertices));
  f("connectivity", r.m.connectivity);
  f("reg", r.m.reg);
  f("acc", r.acc);
  f("sphere_radius", r.m.sphere.radius);
  f("sphere_area", r.m.sphere.surface_area());
  f("bbox_area", r.m.box.surface_area());
  f("p_hit", r.m.p_hit);
  f("area", r.m.area);
  f("area_p", r.m.area_p);
  f("reg_bound", r.reg_bound);
  f("size_bound", r.size_bound);
}
}  // namespace

namespace {
// clusters.csv's rows: the cluster's id and its metrics (a default row for the header).
struct ClustersCsvRow {
  std::uint64_t id = 0;
  const ClusterRow* r = nullptr;
};
void visit_clusters_csv_row(const ClustersCsvRow& x, Columns& col) {
  static const ClusterRow none{};
  const ClusterRow& r = x.r ? *x.r : none;
  col("cluster_id", x.id);
  for_each_metric(r, [&](const char* name, double v) {
    if (std::string_view(name) == "triangles" || std::string_view(name) == "vertices")
      col(name, static_cast<std::uint64_t>(v));
    else
      col(name, v);
  });
  col("n_avg_fallback", static_cast<std::uint64_t>(r.m.n_avg_fallback));
}
const Schema kClustersSchema{"ptc-clusters", 1};
}  // namespace

Table clusters_table(const std::vector<ClusterRow>& rows) {
  return tabulate_each<ClustersCsvRow>(
      kClustersSchema, rows.size(), [&](std::size_t k) { return ClustersCsvRow{k, &rows[k]}; },
      visit_clusters_csv_row);
}

std::string write_clusters_csv(const std::vector<ClusterRow>& rows, const std::filesystem::path& path) {
  AtomicFile f(path);
  const std::string id = stream_each<ClustersCsvRow>(
      kClustersSchema, rows.size(), [&](std::size_t k) { return ClustersCsvRow{k, &rows[k]}; },
      visit_clusters_csv_row, [&](std::string_view block) { f.write(block); });
  f.commit();
  return id;
}

nlohmann::json cluster_distributions(const std::vector<ClusterRow>& rows) {
  std::vector<std::string> names;
  std::vector<std::vector<double>> values;
  for_each_metric(ClusterRow{}, [&](const char* name, double) {
    names.emplace_back(name);
    values.emplace_back();
  });
  for (const auto& r : rows) {
    std::size_t i = 0;
    for_each_metric(r, [&](const char*, double v) { values[i++].push_back(v); });
  }
  nlohmann::json j = nlohmann::json::object();
  for (std::size_t i = 0; i < names.size(); ++i) {
    std::vector<double> finite;
    for (double v : values[i])
      if (!std::isnan(v)) finite.push_back(v);
    if (finite.empty() && !values[i].empty()) {
      j[names[i]] = nullptr;  // undefined for this run (e.g. acc without an objective)
      continue;
    }
    j[names[i]] = summary_json(summarize(finite));
  }
  return j;
}

}  // namespace ptc
