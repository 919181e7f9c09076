// Per-cluster metrics of a clustering at the positions of a mesh, and the tables `ptc cluster`
// writes. Column lists are part of the interface (schema "ptc-clusters/1"): change them only
// with a new schema version.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/schema/table.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/geometry/cluster_metrics.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

/// One cluster's row. Acc, regBound and sizeBound use the run's MaxCount/MaxSize; they are NaN
/// when MaxCount = MaxSize = 0 (no objective: one triangle per cluster).
struct ClusterRow {
  ClusterMetrics m;
  double acc = 0, reg_bound = 0, size_bound = 0;
};

/// Metrics of every cluster (parallel over clusters; the sphere is the CGAL working path). The
/// vertex lists of `c` are read as the clusters' distinct vertices (as clustering_from_labels
/// makes them; validate() checks them); a clustering without usable vertex offsets gets them
/// made from its triangles. avg_sa: the mesh's AvgSA when the caller has it (see
/// cluster_mesh); computed here otherwise.
/// `adjacency`: when not empty, the triangles of a clustering made with adjacency by positions
/// (cluster.h adjacency_triangles of the rest pose): the vertices column then counts the
/// adjacency's distinct vertices (distinct rest positions), as the objective did, and so do
/// connectivity, regBound and Acc; every other column (areas, normals, sphere, box) comes from
/// the mesh's own triangles at `mesh`'s positions, as without.
[[nodiscard]] std::vector<ClusterRow> cluster_rows(const Mesh& mesh, const Clustering& c, const ClusterConfig& cfg,
                                                   std::optional<double> avg_sa = std::nullopt,
                                                   std::span<const Tri> adjacency = {});

/// triangles.csv (schema ptc-cluster-triangles/1): triangle_id,cluster_id in input triangle order.
[[nodiscard]] Table triangles_table(const Clustering& c);
/// The same bytes as triangles_table(c).csv.str() from `label` (c.cluster_of_triangle()), written
/// to `path` in blocks of 1 MiB (whole or not at all: toolkit/io/atomic_file.h) instead of held
/// as one string (16 bytes a triangle). Returns the schema id.
std::string write_triangles_csv(std::span<const std::uint32_t> label, const std::filesystem::path& path);
/// cluster_id,triangles,vertices,connectivity,reg,acc,sphere_radius,sphere_area,bbox_area,p_hit,
/// area,area_p,reg_bound,size_bound,n_avg_fallback
/// (clusters.csv, schema ptc-clusters/1; columns defined in docs/tables.md)
[[nodiscard]] Table clusters_table(const std::vector<ClusterRow>& rows);
/// The same bytes as clusters_table(rows).csv.str(), written to `path` in blocks of about 1 MiB
/// (whole or not at all). Returns the schema id.
std::string write_clusters_csv(const std::vector<ClusterRow>& rows, const std::filesystem::path& path);
/// {metric: {count, min, mean, p5, p50, p95, max}} for every numeric column of clusters.csv.
[[nodiscard]] nlohmann::json cluster_distributions(const std::vector<ClusterRow>& rows);

}  // namespace ptc
