// What `ptc trace`, `ptc bench` (and the later experiment and viz commands) share about a SCENE
// argument: opening it with its inputs recorded, reading a clustering for it, and the one
// "flag > scene > default" rule for the camera and the light.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "analysis/schema/manifest.h"
#include "bvh/camera.h"
#include "render/camera.h"
#include "toolkit/anim/scene.h"
#include "toolkit/clustering/clustering.h"

namespace ptc {

/// open_scene (toolkit/anim/scene_file.h), recording the read time and, for a file, the input.
[[nodiscard]] Scene open_scene_recorded(const std::filesystem::path& input, const SceneOptions& options,
                                        RunManifest& manifest);

/// read_clusters (commands/cluster_files.h), recording the read time and the file.
[[nodiscard]] Clustering read_clusters_recorded(const std::filesystem::path& clusters, const Mesh& mesh,
                                                RunManifest& manifest);

/// The camera: every field the user gave (flags) wins; the others come from the scene's own
/// camera when it has one (Scene::has_own_camera: built-in scenes, scene files with "camera");
/// what is still unset is filled by make_camera's framing of the mesh.
[[nodiscard]] CameraSpec camera_for(const CameraSpec& flags, const Scene& scene);

/// The light: --light > the scene's own light > render's default_light(cam, bounds).
struct LightChoice {
  Vec3 position = Vec3::Zero();
  const char* from = "default";  ///< "--light", "scene" or "default" (recorded in manifests)
};
[[nodiscard]] LightChoice light_for(const std::optional<Vec3>& flag, const Scene& scene, const bvh::PinholeCamera& cam,
                                    const Box3& bounds);

}  // namespace ptc
