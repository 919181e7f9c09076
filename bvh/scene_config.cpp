#include "bvh/scene_config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

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

const char* to_string(FallbackSah s) {
  return s == FallbackSah::Eye ? "eye" : s == FallbackSah::Directions ? "directions" : "plain";
}

std::optional<FallbackSah> parse_fallback_sah(std::string_view s) {
  if (s == "eye") return FallbackSah::Eye;
  if (s == "directions") return FallbackSah::Directions;
  if (s == "plain") return FallbackSah::Plain;
  return std::nullopt;
}

const char* to_string(LeafFormat f) { return f == LeafFormat::Blocks ? "blocks" : "tables"; }

std::optional<LeafFormat> parse_leaf_format(std::string_view s) {
  if (s == "blocks") return LeafFormat::Blocks;
  if (s == "tables") return LeafFormat::Tables;
  return std::nullopt;
}

const char* to_string(LeafFormatChoice f) {
  return f == LeafFormatChoice::Auto ? "auto" : f == LeafFormatChoice::Blocks ? "blocks" : "tables";
}

std::optional<LeafFormatChoice> parse_leaf_format_choice(std::string_view s) {
  if (s == "auto") return LeafFormatChoice::Auto;
  if (s == "blocks") return LeafFormatChoice::Blocks;
  if (s == "tables") return LeafFormatChoice::Tables;
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

SceneConfig fallback_scene_defaults() {
  SceneConfig c = triangle_scene_defaults();
  c.build.cost.intersection = 0.1;
  return c;
}

SceneConfig cluster_scene_defaults() {
  SceneConfig c;
  c.build.cost = {1.0, 0.3};
  c.build.max_leaf_size = 1;
  c.build.median_split_below = 4;  // see BuildConfig: 6% faster build, SAH cost +0.3%
  c.cluster_group_size = 32;       // two-level build: see SceneConfig (docs/tracing.md, "Groups of 32 clusters")
  c.min_cluster_groups = 1024;     // small scenes: smaller groups, or the plain build (docs/tracing.md, "Groups of 32 clusters")
  c.group_trees = GroupTrees::Refit;  // the groups' trees fixed: build + collapse 3.0 -> 1.0 ms (docs/tracing.md)
  return c;
}

std::uint32_t cluster_group_size_used(std::size_t clusters, const SceneConfig& cfg) {
  std::size_t g = cfg.cluster_group_size;
  if (cfg.min_cluster_groups > 0) g = std::min(g, clusters / cfg.min_cluster_groups);
  return g > 1 ? static_cast<std::uint32_t>(g) : 0u;
}

Vec3 trace_frame_origin(const Mesh& mesh, const SceneConfig& cfg) {
  const auto p = mesh.positions();
  for (std::size_t v = 0; v < p.size(); ++v)
    if (!p[v].allFinite())
      throw std::invalid_argument("vertex " + std::to_string(v) + ": rest position (" + std::to_string(p[v].x()) + ", " +
                                  std::to_string(p[v].y()) + ", " + std::to_string(p[v].z()) + ") is not finite");
  if (cfg.origin && !cfg.origin->allFinite()) throw std::invalid_argument("scene: the trace frame's origin is not finite");
  if (cfg.origin) return *cfg.origin;
  const Box3 b = mesh.referenced_bounds();  // (an unused vertex far away would move the frame off the mesh)
  return b.empty() ? Vec3::Zero() : b.center();
}

FrameMap trace_frame(const Mesh& mesh, const SceneConfig& cfg) {
  const Vec3 origin = trace_frame_origin(mesh, cfg);
  if (cfg.scale) {  // (another scene's frame: a power of two, as trace_frame_scale gives)
    int e = 0;
    if (!std::isfinite(*cfg.scale) || !(*cfg.scale > 0) || std::frexp(*cfg.scale, &e) != 0.5)
      throw std::invalid_argument("trace frame scale " + std::to_string(*cfg.scale) + " is not a power of two");
    return {origin, *cfg.scale};
  }
  return {origin, trace_frame_scale(mesh, origin)};
}

double trace_frame_scale(const Mesh& mesh, const Vec3& origin) {
  // The largest |p - origin| coordinate over the vertices some triangle uses: the corners of
  // their box (an unused vertex does not set the frame; no ray reads its float position, though
  // the conversion into the frame still refuses one beyond the float range).
  const Box3 b = mesh.referenced_bounds();
  double e = 0;
  if (!b.empty()) e = std::max((b.lo - origin).cwiseAbs().maxCoeff(), (b.hi - origin).cwiseAbs().maxCoeff());
  if (!(e > 0) || !std::isfinite(e)) return 1.0;  // empty, one point, or not finite (reported elsewhere)
  const int k = std::ilogb(e);                       // e in [2^k, 2^(k+1))
  if (k > 100 || k < -100) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "the mesh reaches %.3g units from its centre: beyond the single-precision tracer's range "
                  "(%.2g to %.2g units; scale the mesh)",
                  e, std::ldexp(1.0, -100), std::ldexp(1.0, 101));
    throw FrameRangeError(buf);
  }
  if (k >= -8 && k < 16) return 1.0;
  return std::ldexp(1.0, -(k + 1));
}

}  // namespace ptc::bvh
