#include "analysis/metrics/sah_overhead.h"

#include <limits>
#include <vector>

#include "bvh/sah_builder.h"
#include "bvh/sah_cost.h"
#include "bvh/scene_config.h"

namespace ptc {
namespace {

// Absolute SAH cost (traversal 1, intersection 1, one primitive per leaf) of a binned build, in
// the frame's units (the caller divides by its scale squared).
double absolute_sah(const std::vector<bvh::Box3f>& boxes) {
  if (boxes.empty()) return 0.0;
  std::vector<bvh::Vec3f> centroids;
  centroids.reserve(boxes.size());
  bvh::Box3f all;
  for (const auto& b : boxes) centroids.push_back(b.center()), all.extend(b);
  bvh::BuildConfig cfg;
  cfg.cost = {1.0, 1.0};
  cfg.max_leaf_size = 1;
  const bvh::Bvh t = bvh::build_binned_sah({boxes, centroids, {}}, cfg);
  const double a = all.surface_area();
  const double normalised = bvh::sah_cost(t, boxes, {}, cfg.cost);
  // sah_cost divides by A(root); when that is 0 it counts every ratio as 1 (then 0 in absolute units).
  return a > 0 ? normalised * a : 0.0;
}

Box3 triangle_box(const Mesh& m, std::uint32_t t) {
  Box3 b;
  for (std::uint32_t v : m.triangle(t)) b.extend(m.position(v));
  return b;
}

}  // namespace

SahOverhead sah_overhead(const Mesh& mesh, const Clustering& c) {
  SahOverhead r;
  std::vector<bvh::Box3f> all, tops, one;
  all.reserve(mesh.triangle_count());
  // The boxes in floats in the mesh's trace frame (its box centre, a power-of-two scale), as the
  // BVHs are built: in world coordinates a mesh 1e7 from the origin had boxes rounded to whole
  // units (an overhead of 0.8 where the same mesh at the origin gave 1.03).
  const bvh::FrameMap frame = mesh.triangle_count() ? bvh::trace_frame(mesh, bvh::SceneConfig{}) : bvh::FrameMap{};
  for (std::uint32_t t = 0; t < mesh.triangle_count(); ++t) all.push_back(bvh::to_frame(triangle_box(mesh, t), frame));
  for (std::size_t k = 0; k < c.cluster_count(); ++k) {
    one.clear();
    bvh::Box3f box;
    for (std::uint32_t t : c.triangles_of(k)) one.push_back(all[t]), box.extend(all[t]);
    if (one.empty()) continue;
    r.clustered += absolute_sah(one) - box.surface_area();
    tops.push_back(box);
  }
  r.clustered += absolute_sah(tops);
  r.triangles = absolute_sah(all);
  const double to_mesh_units = 1.0 / (frame.scale * frame.scale);  // (exact: a power of two)
  r.clustered *= to_mesh_units, r.triangles *= to_mesh_units;
  // No area at all (every triangle degenerate): the ratio is undefined, not 0.
  r.overhead = r.triangles > 0                ? r.clustered / r.triangles
               : mesh.triangle_count() == 0 ? 0.0
                                             : std::numeric_limits<double>::quiet_NaN();
  return r;
}

}  // namespace ptc
