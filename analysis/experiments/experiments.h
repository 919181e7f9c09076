// The paper's experiments (issue 12; docs/experiments.md has every table and column):
//
//   sweep     Figure 6: per MaxCount = MaxSize value, per frame, the time of each stage (update,
//             build, trace, total) of the cluster BVH.
//   compare   Figure 7: per frame, the whole frame (update + build + trace of primary and shadow
//             rays) of the method and every baseline, and the performance factor
//             total(config) / total(reference), the paper's definition.
//   drift     cluster quality over the frames, per clustering: per cluster and frame (reg, Acc,
//             sphere radius and box area against the first frame, p_hit, SAH share), per frame
//             (SAH cost of the cluster and the triangle BVH, meshoptimizer's SAH overhead, EPO,
//             the per-ray counters of primary, shadow and AO rays), the rank correlation of
//             connectivity with drift, and the fit of the measured cost per ray to SAH and EPO.
//   accuracy  speed against error of the toolkit's approximations (analysis/experiments/accuracy.h).
//
// Each experiment is a list of work items (study.h); run_experiment() measures the items of
// one shard and returns their rows, file by file, as CSV text; assemble() turns the rows of any
// set of items (one run, one shard, or the shards of a study merged) into the experiment's
// files, derived tables included, and its printed summary. A single run, a shard and `ptc merge`
// all go through assemble(), so merged shards give the single run's files row by row.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "analysis/experiments/study.h"
#include "analysis/schema/csv.h"
#include "analysis/schema/table.h"

namespace ptc {

enum class ExperimentKind { Sweep, Compare, Drift, Accuracy };
[[nodiscard]] const char* to_string(ExperimentKind k);
[[nodiscard]] std::optional<ExperimentKind> parse_experiment_kind(std::string_view s);

/// compare's configurations besides the clusterings (study::kClusteringNames, "given").
inline constexpr const char* kCompareStructures[] = {"standard", "embree_low", "embree_refit", "embree_medium"};

struct ExperimentParams {
  ExperimentKind kind = ExperimentKind::Sweep;
  std::string scene;                 ///< the SCENE argument as given (the `scene` column)
  ClusterConfig cluster;             ///< the user's clustering parameters (method/objective: sweep's)
  const Clustering* given = nullptr;  ///< --clusters DIR: compare's and drift's method, accuracy's clustering
  /// The parameters `given` was made with (its `ptc cluster` manifest): its per-cluster metrics
  /// (acc needs MaxCount and MaxSize) use them; nullopt: `cluster`'s.
  std::optional<ClusterConfig> given_cluster;
  /// A clustering will be given (the item list is known before it is read); implied by `given`.
  bool clusters_given = false;
  [[nodiscard]] bool has_given() const { return given != nullptr || clusters_given; }
  /// sweep: the MaxCount = MaxSize values (0: one triangle per cluster, the standard).
  std::vector<std::uint32_t> max_counts{0, 10, 50, 100};
  /// compare: the configurations (clusterings by name, "given", kCompareStructures).
  std::vector<std::string> configs;
  /// compare: the configuration perf_factor divides by.
  std::string reference = "acc_contraction";
  /// drift: the clusterings (names of study::kClusteringNames or "given").
  std::vector<std::string> clusterings;
  int ao_samples = 1;                ///< drift: AO rays per primary hit for the counters (0: no AO pass)
  std::size_t reference_rays = 512;  ///< accuracy: rays checked against the double brute force
};

/// The configurations compare runs by default (the method, its baselines and Embree's modes).
[[nodiscard]] std::vector<std::string> default_compare_configs(bool given);
/// The clusterings drift runs by default.
[[nodiscard]] std::vector<std::string> default_drift_clusterings(bool given);

/// The names of the work items, in order (what a shard splits).
[[nodiscard]] std::vector<std::string> experiment_items(const ExperimentParams& p);

/// The rows of the files of one kind, as CSV text, with how many rows each item gave.
struct FileRows {
  std::string file;   ///< "sweep.csv"
  Schema schema;
  CsvText rows;
  std::vector<std::pair<std::size_t, std::size_t>> item_rows;  ///< (item index, rows), in row order
};

/// An empty file of rows (no items yet).
[[nodiscard]] FileRows file_rows(std::string file, Schema schema, std::vector<std::string> header);
/// Appends the rows of one item (a table of the file's schema and columns) to `f`.
void add_item_rows(FileRows& f, std::size_t item, const Table& t);

struct ExperimentRun {
  std::vector<std::string> items;     ///< every item of the experiment
  std::vector<std::size_t> done;      ///< the items this run measured (the shard's)
  std::vector<FileRows> files;        ///< the primary files (assemble() derives the rest)
  std::size_t triangles = 0, vertices = 0, rays = 0;
  std::map<std::string, double> timings_ms;  ///< per item: clustering and setup
};

/// Measures the shard's items. Throws std::invalid_argument for a bad configuration (a name
/// that is no configuration, a clustering cluster_mesh refuses), Interrupted on Ctrl-C.
[[nodiscard]] ExperimentRun run_experiment(Scene& scene, const ExperimentParams& p, const study::StudySetup& setup);

/// The files an experiment writes and its summary, from the primary files' rows of any set of
/// items (in item order).
struct Assembled {
  std::vector<FileRows> files;  ///< primary (derived columns filled) then derived files
  std::string text;             ///< the printed summary
};
/// `reference`: compare's perf_factor denominator (ExperimentParams::reference).
[[nodiscard]] Assembled assemble(ExperimentKind kind, std::vector<FileRows> primaries, const std::string& reference);

/// A verdict's value as the summaries print it: x with `least` decimals, or more (up to 6) where
/// fewer would put the printed value on the other side of a bound, or on it, while x is not:
/// 0.7969 against the criterion 0.8 prints as 0.797, not as 0.80.
[[nodiscard]] std::string verdict_number(double x, int least, std::initializer_list<double> bounds);

/// The primary files of a kind (their names), in the order run_experiment returns them.
[[nodiscard]] std::vector<std::string> primary_files(ExperimentKind kind);

}  // namespace ptc
