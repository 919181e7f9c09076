// One rendered view of a scene: primary rays of a pinhole camera (closest hit), optional shadow
// rays to a point light and ambient-occlusion rays (any hit), and the images made from them:
// shaded, depth, normal, ambient occlusion and traversal-cost heatmaps.
//
// Shading (Lambert): c = albedo * (k_a * ao + k_d * max(0, n . l) * lit), k_a = 0.2, k_d = 0.8,
// albedo = 0.9 grey; ao = 1 without --ao; lit = 1 without --shadows; n = the geometric normal
// facing the viewer, l = unit direction to the light. Missed rays: background (32, 32, 40).
// Colours are linear values written as 8-bit (no gamma curve: the figures are for comparison).
#pragma once

#include <optional>
#include <vector>

#include "render/images.h"
#include "render/rays.h"
#include "bvh/camera.h"

namespace ptc {

struct RenderConfig {
  int width = 512, height = 512;  ///< pixels, 1..16384 each
  bool shadows = false;           ///< trace shadow rays to the light
  int ao_samples = 0;             ///< ambient-occlusion rays per pixel (0 = none)
  double ao_distance_rel = 0.25;  ///< AO max distance as a fraction of the scene's bounds diagonal
  std::uint64_t seed = 1;         ///< AO sampling seed
  std::optional<Vec3> light;      ///< point light (world); default: default_light()
  double light_intensity = 1.0;   ///< >= 0: scales the light's diffuse term in shaded_image (a scene's light.intensity)
  unsigned threads = 0;           ///< tracer threads (0 = all cores)
};

/// The default light: above and to the right of the eye, at the eye's distance from the centre
/// of the bounds: eye + 0.5 d right + 0.8 d up, d = |centre - eye|.
[[nodiscard]] Vec3 default_light(const bvh::PinholeCamera& cam, const Box3& bounds);

struct Render {
  int width = 0, height = 0;
  bvh::RayBatch rays;     ///< primary rays (unit directions, row-major from the top-left pixel)
  bvh::HitBatch primary;  ///< closest hits with counters
  SurfaceHits surface;
  Vec3 light = Vec3::Zero();
  double light_intensity = 1.0;   ///< RenderConfig::light_intensity
  std::vector<std::uint8_t> lit;  ///< per pixel, when shadows were traced
  std::vector<float> ao;          ///< per pixel, when AO was traced
  PassStats primary_stats, shadow_stats, ao_stats;
};

/// Traces the view. `scene` must hold `mesh`'s current positions (TriangleScene or ClusterScene
/// data, or target_of(bvh::SceneTracer) with combined triangle ids). Ray offsets and the AO distance are relative to mesh.referenced_bounds() (see render/rays.h).
[[nodiscard]] Render render_view(const TraceTarget& scene, const Mesh& mesh, const bvh::PinholeCamera& cam,
                                 const RenderConfig& cfg);
[[nodiscard]] Render render_view(const bvh::TraceData& scene, const Mesh& mesh, const bvh::PinholeCamera& cam,
                                 const RenderConfig& cfg);

[[nodiscard]] RgbImage shaded_image(const Render& r);
/// Distance from the eye (t of the unit-direction primary ray), grey: near = white, far = dark
/// grey (40); legend min/max = the nearest/farthest hit distance. Missed rays: black.
[[nodiscard]] RgbImage depth_image(const Render& r, ColorLegend& legend);
/// World-space facing normal n as colour round(255 * (n + 1) / 2); missed rays: black.
[[nodiscard]] RgbImage normal_image(const Render& r);
/// AO fraction as grey (1 = white); missed rays: black. Requires r.ao.
[[nodiscard]] RgbImage ao_image(const Render& r);
/// Per-pixel primary-ray cost heatmaps (viridis, legend 0..max, or the given range: cost_heatmap).
[[nodiscard]] RgbImage nodes_image(const Render& r, ColorLegend& legend, const std::optional<std::pair<double, double>>& range = {});
[[nodiscard]] RgbImage triangles_image(const Render& r, ColorLegend& legend,
                                       const std::optional<std::pair<double, double>>& range = {});

}  // namespace ptc
