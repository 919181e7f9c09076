// `ptc experiment KIND SCENE ... --out DIR` and `ptc merge DIR... --out DIR` as library calls
// (analysis/experiments/experiments.h; docs/experiments.md).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "analysis/experiments/experiments.h"
#include "render/camera.h"
#include "toolkit/anim/scene.h"

namespace ptc {

struct ExperimentCommandOptions {
  std::string kind;                 ///< sweep, compare, drift, accuracy
  std::filesystem::path input;      ///< SCENE
  SceneOptions scene_options;
  std::optional<std::string> frames;  ///< --frames A:B (default: an animated scene's range, else 0:4)
  bool extend_frames = false;
  std::optional<std::string> deform;  ///< --deform KIND|none (static scenes)
  std::filesystem::path clusters;   ///< --clusters DIR: the method's clustering (compare, drift, accuracy)
  ClusterConfig cluster;            ///< the clustering flags (as `ptc cluster` takes them)
  std::vector<std::string> given;   ///< the ClusterConfig parameters the user set (names of kClusterParameters)
  std::vector<std::string> structure_flags;  ///< the cluster BVH's flags the user set (--cluster-leaf, --cluster-groups, ...)
  std::optional<std::string> max_counts;   ///< sweep: "0,10,50,100"
  std::optional<std::string> configs;      ///< compare: "acc_growth,standard,..."
  std::optional<std::string> reference;    ///< compare: perf_factor's denominator
  std::optional<std::string> clusterings;  ///< drift: "acc_growth,naive,..."
  std::optional<int> ao_samples;            ///< drift (default 1)
  std::optional<std::size_t> reference_rays;  ///< accuracy (default 512)
  bool method_given = false;        ///< --method or --objective was given (sweep only)
  int width = 256, height = 256;
  CameraSpec camera;
  std::optional<Vec3> light;
  unsigned threads = 0;             ///< 0: all cores
  bvh::ClusterLeaf cluster_leaf = bvh::ClusterLeaf::Linear;
  std::uint32_t cluster_group_size = bvh::cluster_scene_defaults().cluster_group_size;
  /// bvh::SceneConfig::min_cluster_groups (0 when --cluster-groups is given: groups of exactly up to N).
  std::uint32_t min_cluster_groups = bvh::cluster_scene_defaults().min_cluster_groups;
  bvh::GroupTrees group_trees = bvh::cluster_scene_defaults().group_trees;
  bvh::VertexOrder vertex_order = bvh::VertexOrder::Clusters;
  std::optional<std::string> shard;  ///< --shard K/N
  std::filesystem::path out_dir;
  bool json = false;
  bool quiet = false;               ///< no progress bar
  std::vector<std::string> argv;
};

/// Runs the experiment (one shard of it with --shard) and writes its files, summary.txt and
/// manifest.json atomically; prints the summary (or JSON). Bad input -> InputError, bad usage ->
/// UsageError, Ctrl-C -> Interrupted (nothing written).
void cmd_experiment(const ExperimentCommandOptions& opt, std::ostream& out);

struct MergeOptions {
  std::vector<std::filesystem::path> shards;  ///< output directories of `ptc experiment --shard K/N`
  std::filesystem::path out_dir;
  bool json = false;
  std::vector<std::string> argv;
};
/// Joins the shards of one experiment into the files a single run writes. Refuses (InputError
/// naming the directories and what differs) shards of different experiments, scenes, inputs,
/// parameters or ptc builds, a shard given twice, and a missing shard.
void cmd_merge(const MergeOptions& opt, std::ostream& out);

}  // namespace ptc
