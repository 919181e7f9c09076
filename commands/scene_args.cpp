#include "commands/scene_args.h"

#include "commands/cluster_files.h"
#include "commands/inputs.h"
#include "render/view.h"
#include "toolkit/anim/scene_file.h"
#include "toolkit/core/stopwatch.h"

namespace ptc {

Scene open_scene_recorded(const std::filesystem::path& input, const SceneOptions& options, RunManifest& manifest) {
  Stopwatch sw;
  Scene scene = open_scene(input.string(), options);
  manifest.add_timing_ms("read", sw.ms());
  std::error_code ec;
  if (std::filesystem::is_regular_file(input, ec)) record_input(manifest, input);
  return scene;
}

Clustering read_clusters_recorded(const std::filesystem::path& clusters, const Mesh& mesh, RunManifest& manifest) {
  Stopwatch sw;
  Clustering c = read_clusters(clusters, mesh);
  manifest.add_timing_ms("read_clusters", sw.ms());
  std::error_code ec;
  record_input(manifest, std::filesystem::is_directory(clusters, ec) ? clusters / "triangles.csv" : clusters);
  return c;
}

CameraSpec camera_for(const CameraSpec& flags, const Scene& scene) {
  CameraSpec spec = flags;
  if (scene.has_own_camera()) {
    const SceneCamera& sc = scene.camera();
    if (!spec.eye) spec.eye = sc.eye;
    if (!spec.look_at) spec.look_at = sc.look_at;
    if (!spec.up) spec.up = sc.up;
    if (!spec.fov_deg) spec.fov_deg = sc.fov_deg;
  }
  return spec;
}

LightChoice light_for(const std::optional<Vec3>& flag, const Scene& scene, const bvh::PinholeCamera& cam,
                      const Box3& bounds) {
  if (flag) return {*flag, "--light"};
  if (scene.has_own_light()) return {scene.light().position, "scene"};
  return {default_light(cam, bounds), "default"};
}

}  // namespace ptc
