// Every behaviour of the `ptc` command as a library call (apps/ptc only parses arguments).
// Each function reads its inputs, writes its outputs (atomically) and prints results to `out`;
// bad input throws InputError (the command maps it to exit code 1).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "analysis/metrics/sphere_accuracy.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/mesh/subdivision.h"

namespace ptc {

struct InfoOptions {
  std::filesystem::path input;
  bool json = false;  ///< machine-readable stdout (schema ptc-info/1)
};
void cmd_info(const InfoOptions& opt, std::ostream& out);

struct SubdivideOptions {
  std::filesystem::path input;
  std::filesystem::path output;  ///< .off, .obj or .ply; written atomically
  SubdivisionScheme scheme = SubdivisionScheme::Midpoint;
  int levels = 1;                ///< 0..8
  bool json = false;
};
void cmd_subdivide(const SubdivideOptions& opt, std::ostream& out);

struct SpheresOptions {
  std::filesystem::path input;
  std::filesystem::path out_dir;   ///< spheres.csv, sphere_sets.csv, manifest.json (empty: no files)
  SphereReportConfig config;
  bool json = false;
  std::vector<std::string> argv;   ///< recorded in the manifest
};
void cmd_spheres(const SpheresOptions& opt, std::ostream& out);

struct ClusterOptions {
  std::filesystem::path input;
  std::filesystem::path out_dir;   ///< triangles.csv, clusters.csv, summary.json, clusters.ply (required)
  ClusterConfig config;
  /// The ClusterConfig parameters the user set explicitly ("objective", "max_size", ...: the
  /// names of used_parameters); one the method does not use is a UsageError.
  std::vector<std::string> given;
  bool json = false;
  std::vector<std::string> argv;
};
/// A ClusterConfig parameter (cluster.h kClusterParameters) as the user spells it: "max_count"
/// -> "--max-count".
[[nodiscard]] std::string flag_of(std::string_view parameter);
/// UsageError (naming the flag) for a given parameter the configuration does not use, or a
/// configuration cluster_mesh would refuse.
void check_cluster_options(const ClusterConfig& config, const std::vector<std::string>& given);
void cmd_cluster(const ClusterOptions& opt, std::ostream& out);

}  // namespace ptc
