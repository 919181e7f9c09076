// Reading a clustering back for tracing: `ptc cluster --out DIR` writes DIR/triangles.csv
// (header `triangle_id,cluster_id`, one row per triangle), which `ptc trace --clusters DIR` and
// `ptc bench --clusters DIR` read and check against the mesh they trace.
#pragma once

#include <filesystem>
#include <string>

#include "toolkit/clustering/cluster.h"

#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

/// Reads `dir`/triangles.csv (or `dir` itself when it is a file) and checks it against `mesh`:
/// header `triangle_id,cluster_id`; every row two non-negative integers; every triangle id
/// 0 .. T-1 exactly once (T = mesh.triangle_count(); rows in any order); cluster ids any
/// 32-bit values; every cluster connected through shared edges of `mesh` (the BVH assumes
/// compact clusters, and a clustering of another mesh with the same triangle count fails here,
/// unless its clusters are connected in `mesh` too, as one-triangle clusters always are).
/// Any violation throws InputError naming the file, the line (1-based, header = line 1) and the
/// element ("triangle 12", "cluster 3"), e.g. "clusters/triangles.csv: line 7: triangle 5:
/// cluster 2 is not connected (triangle 5 shares no edge path with triangle 0 of the cluster)".
/// Clusters are renumbered densely (clustering_from_labels).
[[nodiscard]] Clustering read_clusters(const std::filesystem::path& dir, const Mesh& mesh);

/// The parameters a clustering was made with, from `ptc cluster`'s DIR/manifest.json beside
/// triangles.csv (MaxCount, MaxSize, size bound, sphere, method, objective, adjacency): the
/// per-cluster metrics of a given clustering (acc needs MaxCount and MaxSize) use them, in
/// `ptc viz` and in the experiments. Without a manifest, or with one that is not ptc cluster's
/// (another program's, or not JSON): the defaults, from_manifest false, and `from` says which.
/// A ptc cluster manifest whose parameters are not what it writes throws InputError naming the
/// file and the field.
struct ClusteringInfo {
  ClusterConfig cfg;
  std::string title;  ///< "contraction / acc, MaxCount 50, MaxSize 50"
  std::string from;   ///< "DIR/manifest.json" or "defaults (no manifest.json beside triangles.csv)"
  bool from_manifest = false;
};
[[nodiscard]] ClusteringInfo clustering_info(const std::filesystem::path& clusters);

}  // namespace ptc
