#include "render/view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "render/camera.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/geometry/triangle.h"

namespace ptc {
namespace {

constexpr double kAmbient = 0.2, kDiffuse = 0.8, kAlbedo = 0.9;
constexpr Rgb8 kBackground{32, 32, 40};


}  // namespace

Vec3 default_light(const bvh::PinholeCamera& cam, const Box3& bounds) {
  const double d = bounds.empty() ? 1.0 : (bounds.center() - cam.eye).norm();
  return cam.eye + 0.5 * d * cam.right + 0.8 * d * cam.up;
}

Render render_view(const bvh::TraceData& scene, const Mesh& mesh, const bvh::PinholeCamera& cam, const RenderConfig& cfg) {
  return render_view(target_of(scene), mesh, cam, cfg);
}

Render render_view(const TraceTarget& scene, const Mesh& mesh, const bvh::PinholeCamera& cam, const RenderConfig& cfg) {
  Render r;
  r.width = cfg.width, r.height = cfg.height;
  r.rays = camera_rays(cam, cfg.width, cfg.height);
  bvh::TraceOptions opt;
  opt.mode = bvh::HitMode::Closest;
  opt.threads = cfg.threads;
  opt.counters = true;
  Stopwatch t0;
  const bvh::TraceTotals tt = scene.trace(r.rays, r.primary, opt);
  r.primary_stats.add(tt, t0.ms());
  r.surface = surface_hits(mesh, r.rays, r.primary);
  const RayFrame frame{mesh.referenced_bounds(), scene.origin};
  r.light = cfg.light.value_or(default_light(cam, frame.bounds));
  if (!(cfg.light_intensity >= 0.0 && std::isfinite(cfg.light_intensity)))
    throw std::invalid_argument("render_view: the light's intensity must be finite and >= 0");
  r.light_intensity = cfg.light_intensity;
  if (cfg.shadows) {
    ShadowResult s = trace_shadows(scene, r.surface, r.light, frame, cfg.threads);
    r.lit = std::move(s.lit);
    r.shadow_stats = s.stats;
  }
  if (cfg.ao_samples > 0) {
    AoConfig ac;
    ac.samples = cfg.ao_samples;
    ac.max_distance_rel = cfg.ao_distance_rel;
    ac.seed = cfg.seed;
    AoResult a = trace_ao(scene, r.surface, ac, frame, cfg.threads);
    r.ao = std::move(a.ao);
    r.ao_stats = a.stats;
  }
  return r;
}

RgbImage shaded_image(const Render& r) {
  RgbImage img(r.width, r.height, kBackground);
  for (std::size_t i = 0; i < img.pixel_count(); ++i) {
    if (!r.surface.hit[i]) continue;
    const Vec3 to_light = r.light - r.surface.point[i];
    const double n = to_light.norm();
    const Vec3 l = std::isfinite(n) ? to_light.normalized() : unit_vector(to_light);  // (a light at 1e308)
    const double diffuse =
        r.light_intensity * std::max(0.0, r.surface.normal[i].dot(l)) * (r.lit.empty() ? 1.0 : double(r.lit[i]));
    const double ambient = r.ao.empty() ? 1.0 : double(r.ao[i]);
    const std::uint8_t g = to_u8(kAlbedo * (kAmbient * ambient + kDiffuse * diffuse));
    img.set(i, {g, g, g});
  }
  return img;
}

RgbImage depth_image(const Render& r, ColorLegend& legend) {
  RgbImage img(r.width, r.height);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t i = 0; i < img.pixel_count(); ++i)
    if (r.surface.hit[i]) lo = std::min(lo, double(r.primary.t[i])), hi = std::max(hi, double(r.primary.t[i]));
  legend.quantity = "depth";
  legend.colormap = "grey (near = 255, far = 40)";
  legend.min = std::isfinite(lo) ? lo : 0.0;
  legend.max = std::isfinite(hi) ? hi : 0.0;
  legend.note = "distance from the eye in scene units; missed rays: black";
  for (std::size_t i = 0; i < img.pixel_count(); ++i) {
    if (!r.surface.hit[i]) continue;
    const double f = hi > lo ? (double(r.primary.t[i]) - lo) / (hi - lo) : 0.0;
    const std::uint8_t g = to_u8((255.0 - 215.0 * f) / 255.0);
    img.set(i, {g, g, g});
  }
  return img;
}

RgbImage normal_image(const Render& r) {
  RgbImage img(r.width, r.height);
  for (std::size_t i = 0; i < img.pixel_count(); ++i) {
    if (!r.surface.hit[i]) continue;
    const Vec3& n = r.surface.normal[i];
    img.set(i, {to_u8(0.5 * (n.x() + 1.0)), to_u8(0.5 * (n.y() + 1.0)), to_u8(0.5 * (n.z() + 1.0))});
  }
  return img;
}

RgbImage ao_image(const Render& r) {
  if (r.ao.size() != static_cast<std::size_t>(r.width) * static_cast<std::size_t>(r.height))
    throw std::invalid_argument("ao_image: no ambient occlusion was traced");
  RgbImage img(r.width, r.height);
  for (std::size_t i = 0; i < img.pixel_count(); ++i) {
    if (!r.surface.hit[i]) continue;
    const std::uint8_t g = to_u8(r.ao[i]);
    img.set(i, {g, g, g});
  }
  return img;
}

RgbImage nodes_image(const Render& r, ColorLegend& legend, const std::optional<std::pair<double, double>>& range) {
  legend.quantity = "nodes_visited";
  legend.note = "8-wide nodes whose boxes a primary ray tested; viridis from min (dark) to max (yellow)";
  return cost_heatmap(r.primary.nodes_visited, r.width, r.height, legend, range);
}

RgbImage triangles_image(const Render& r, ColorLegend& legend, const std::optional<std::pair<double, double>>& range) {
  legend.quantity = "triangles_tested";
  legend.note = "triangles a primary ray tested (padding lanes not counted); viridis from min (dark) to max (yellow)";
  return cost_heatmap(r.primary.triangles_tested, r.width, r.height, legend, range);
}

}  // namespace ptc
