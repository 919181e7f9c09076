// What `ptc trace`, `ptc bench` (and the later experiment and viz commands) share about a SCENE
// argument: opening it with its inputs recorded, reading a clustering for it, and the one
// "flag > scene > default" rule for the camera and the light.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "analysis/schema/manifest.h"
#include "bvh/camera.h"
#include "commands/cluster_files.h"
#include "render/camera.h"
#include "toolkit/anim/scene.h"
#include "toolkit/clustering/clustering.h"

namespace ptc {


/// open_scene (toolkit/anim/scene_file.h), recording the read time and every file it read (the
/// input, a scene file's meshes, a built-in scene's data, a sequence's frames) with its hash.
[[nodiscard]] Scene open_scene_recorded(const std::filesystem::path& input, const SceneOptions& options,
                                        RunManifest& manifest);

/// A scene that moves over a frame range, as `ptc bench` and `ptc experiment` take it: an animated
/// scene with its own motion, or a static one (a mesh file) with a stand-in motion.
struct MovingScene {
  Scene scene;
  FrameRange range;
  std::string motion;  ///< "scene", "stand-in: the twist deformer (deform_preset)" or "none: ..."
};
/// Opens SCENE (open_scene_recorded) and its motion: `deform` (--deform KIND|none) gives a static
/// scene its stand-in motion (default twist); an animated scene refuses it. `frames` (--frames,
/// parse_frame_range) defaults to an animated scene's range, else 0:4; frames outside an animated
/// scene's range need `extend` (--extend-frames). UsageError naming the flag otherwise.
[[nodiscard]] MovingScene open_moving_scene(const std::filesystem::path& input, const SceneOptions& options,
                                            const std::optional<std::string>& deform,
                                            const std::optional<std::string>& frames, bool extend,
                                            RunManifest& manifest);

/// --deform KIND|none on `scene` (named `arg` in messages): a static scene moves by the built-in
/// scenes' deformer of that kind (deform_preset); none leaves the scene as it is. Returns the
/// manifest's `motion` text ("stand-in: ...", "none: the rest pose every frame" or "scene").
/// UsageError naming --deform for an unknown kind, or a kind given for an animated scene.
[[nodiscard]] std::string apply_stand_in(Scene& scene, const std::string& deform, const std::string& arg);

/// read_clusters (commands/cluster_files.h), recording the read time and the file.
[[nodiscard]] Clustering read_clusters_recorded(const std::filesystem::path& clusters, const Mesh& mesh,
                                                RunManifest& manifest);
/// clustering_info (commands/cluster_files.h), recording the manifest it read the parameters
/// from, when there was one, among the inputs.
[[nodiscard]] ClusteringInfo clustering_info_recorded(const std::filesystem::path& clusters, RunManifest& manifest);

/// The camera: every field the user gave (flags) wins; the others come from the scene's own
/// camera when it has one (Scene::has_own_camera: built-in scenes, scene files with "camera");
/// what is still unset is filled by make_camera's framing of the mesh.
[[nodiscard]] CameraSpec camera_for(const CameraSpec& flags, const Scene& scene);

/// --data-dir given with `input` as SCENE: a usage error (exit 2, naming the flag) unless the
/// scene opener would read the data directory for it (scene_reads_data_dir, toolkit/anim/scene_file.h).
void refuse_unused_data_dir(const std::filesystem::path& input);

/// The light: --light > the scene's own light > render's default_light(cam, bounds).
struct LightChoice {
  Vec3 position = Vec3::Zero();
  const char* from = "default";  ///< "--light", "scene" or "default" (recorded in manifests)
  double intensity = 1.0;        ///< the scene's light.intensity (also when --light moves it), else 1
};
/// The manifests' record of a light ("light": position, where it came from, intensity).
[[nodiscard]] nlohmann::json light_json(const LightChoice& light);
/// The manifests' record of a camera as ptc trace and ptc bench give it ("camera": eye, axes,
/// vertical field of view, whether the scene's own camera was used, and which `flags` were given).
[[nodiscard]] nlohmann::json camera_json(const bvh::PinholeCamera& cam, const Scene& scene, const CameraSpec& flags);
/// A light whose difference to the scene's rest bounds overflows is refused (a usage error for
/// --light, else InputError naming `input` and "light"); a far light is not (shadow rays start on
/// the surface; a light at 1e308 lights and shadows as one at 1e30).
[[nodiscard]] LightChoice light_for(const std::optional<Vec3>& flag, const Scene& scene, const bvh::PinholeCamera& cam,
                                    const Box3& bounds, std::string_view input);

/// The camera's eye (`flags` are the user's, camera_for's input): refused as check_reach says,
/// naming --eye when it was given, the scene's camera when it has one, else --fov or --look-at
/// when they moved the framing camera, else the input.
void check_eye_reach(const bvh::PinholeCamera& cam, const CameraSpec& flags, const Scene& scene, std::string_view input);

/// A ray's origin as the tracer takes it: within kTraceReach units of the scene's trace frame
/// (the rest pose's centre and power-of-two scale, bvh::trace_frame_scale) of that centre,
/// Embree's bound too (docs/tracing.md, "The trace frame at any scale"). Farther, the rays'
/// floats lose the mesh (an eye at 1e300 saw nothing). (Scenes with static and moving parts
/// trace each in its own part's frame, whose scale may be larger: the check takes the whole
/// rest pose's.)
/// Throws UsageError naming `flag` when `from` is the flag, else InputError naming `input` and
/// `element` ("camera", "light"). A mesh beyond the frame's own range is left to the BVH's check.
inline constexpr double kTraceReach = 1e18;
void check_reach(const Scene& scene, const Vec3& p, std::string_view what, std::string_view flag, std::string_view from,
                 std::string_view element, std::string_view input);

}  // namespace ptc
