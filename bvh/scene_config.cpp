#include "bvh/scene_config.h"

#include <stdexcept>
#include <string>

namespace ptc::bvh {

const char* to_string(ClusterLeaf l) { return l == ClusterLeaf::Linear ? "linear" : "block-tree"; }

const char* to_string(SahBuilder b) { return b == SahBuilder::Binned ? "binned" : "sweep"; }

const char* to_string(GroupTrees g) { return g == GroupTrees::Rebuild ? "rebuild" : "refit"; }

std::optional<GroupTrees> parse_group_trees(std::string_view s) {
  if (s == "rebuild") return GroupTrees::Rebuild;
  if (s == "refit") return GroupTrees::Refit;
  return std::nullopt;
}

std::optional<ClusterLeaf> parse_cluster_leaf(std::string_view s) {
  if (s == "linear") return ClusterLeaf::Linear;
  if (s == "block-tree") return ClusterLeaf::BlockTree;
  return std::nullopt;
}

SceneConfig triangle_scene_defaults() {
  SceneConfig c;
  c.build.cost = {1.0, 0.3};
  c.build.max_leaf_size = 8;
  return c;
}

SceneConfig cluster_scene_defaults() {
  SceneConfig c;
  c.build.cost = {1.0, 0.3};
  c.build.max_leaf_size = 1;
  c.build.median_split_below = 4;  // see BuildConfig: 6% faster build, SAH cost +0.3%
  c.cluster_group_size = 8;        // two-level build: see SceneConfig (bench/bvh_bench.cpp --groups)
  c.group_trees = GroupTrees::Refit;  // the groups' trees fixed: build + collapse 3.0 -> 1.0 ms (docs/tracing.md)
  return c;
}

Vec3 trace_frame_origin(const Mesh& mesh, const SceneConfig& cfg) {
  const auto p = mesh.positions();
  for (std::size_t v = 0; v < p.size(); ++v)
    if (!p[v].allFinite())
      throw std::invalid_argument("vertex " + std::to_string(v) + ": rest position (" + std::to_string(p[v].x()) + ", " +
                                  std::to_string(p[v].y()) + ", " + std::to_string(p[v].z()) + ") is not finite");
  if (cfg.origin && !cfg.origin->allFinite()) throw std::invalid_argument("scene: the trace frame's origin is not finite");
  if (cfg.origin) return *cfg.origin;
  const Box3 b = mesh.bounds();
  return b.empty() ? Vec3::Zero() : b.center();
}

}  // namespace ptc::bvh
