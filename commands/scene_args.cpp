#include "commands/scene_args.h"

#include <cmath>
#include <iostream>
#include <string_view>

#include <fmt/format.h>

#include "analysis/schema/json.h"
#include "commands/args.h"
#include "commands/cluster_files.h"
#include "bvh/scene_config.h"
#include "commands/inputs.h"
#include "render/view.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/scene.h"
#include "toolkit/anim/scene_file.h"
#include "toolkit/core/error.h"
#include "toolkit/core/input_log.h"
#include "toolkit/core/stopwatch.h"

namespace ptc {

namespace {
// `input` (when it is a file) and every file in `log` (the files opening it read) in the
// manifest's inputs, each once, with its hash (commands/inputs.h).
void record_scene_inputs(RunManifest& manifest, const std::filesystem::path& input, const InputLog& log) {
  std::error_code ec;
  const bool file = std::filesystem::is_regular_file(input, ec);
  const std::filesystem::path self = file ? std::filesystem::absolute(input, ec).lexically_normal() : std::filesystem::path();
  if (file) record_input(manifest, input);  // as the user named it
  for (const auto& f : log.files())         // (each once, absolute)
    if (f != self) record_input(manifest, f);
}
}  // namespace

Scene open_scene_recorded(const std::filesystem::path& input, const SceneOptions& options, RunManifest& manifest) {
  Stopwatch sw;
  InputLog log;  // every file the scene reads: its data files, a scene file's meshes, frames
  Scene scene = open_scene(input.string(), options);
  manifest.add_timing_ms("read", sw.ms());
  record_scene_inputs(manifest, input, log);
  return scene;
}

std::string apply_stand_in(Scene& scene, const std::string& deform, const std::string& arg) {
  if (deform == "none") return scene.all_static() ? "none: the rest pose every frame" : "scene";
  const std::optional<DeformKind> k = parse_deform_kind(deform);
  if (!k)
    throw UsageError("--deform", fmt::format("'{}' is not a deformer (twist, bend, wave, rigid, explode or none)", deform));
  if (!scene.all_static())
    throw UsageError("--deform",
                     fmt::format("'{}' is animated: the stand-in motion applies to static scenes (mesh files) only", arg));
  const DeformParams params = deform_preset(*k);
  // Twist and bend move a vertex by its place along the axis: a mesh flat across it stays still.
  if ((*k == DeformKind::Twist || *k == DeformKind::Bend) && !scene.rest().empty() &&
      !(scene.rest().referenced_bounds().extent()[params.axis] > 0.0))
    std::cerr << fmt::format("ptc: note: the {} deformer leaves '{}' still: it has no extent along {} (the deformer's "
                             "axis); wave, rigid or explode move it\n",
                             to_string(*k), arg, "xyz"[params.axis]);
  scene = deform_scene(scene, params);
  return fmt::format("stand-in: the {} deformer (deform_preset)", to_string(*k));
}

MovingScene open_moving_scene(const std::filesystem::path& input, const SceneOptions& options,
                              const std::optional<std::string>& deform_arg, const std::optional<std::string>& frames,
                              bool extend, RunManifest& manifest) {
  std::optional<FrameRange> asked;
  if (frames) asked = parse_frame_range(*frames, "--frames");
  const std::string arg = input.string();
  MovingScene m{open_scene_recorded(input, options, manifest), {}, "scene"};
  const bool animated = !m.scene.all_static();
  if (animated && deform_arg)
    throw UsageError("--deform",
                     fmt::format("'{}' is animated: the stand-in motion applies to static scenes (mesh files) only", arg));
  // A static scene moves by its stand-in motion (twist unless --deform says otherwise).
  if (!animated) m.motion = apply_stand_in(m.scene, deform_arg.value_or("twist"), arg);
  m.range = asked ? *asked : animated ? m.scene.frames() : FrameRange{0, 4};
  if (m.range.count() > 100000) throw UsageError("--frames", "at most 100000 frames");
  // The stand-in motion of a static scene has no range of its own (a periodic deformer): any frame.
  check_frames(m.scene, m.range, arg, "--frames", extend || !animated);
  return m;
}

Clustering read_clusters_recorded(const std::filesystem::path& clusters, const Mesh& mesh, RunManifest& manifest) {
  Stopwatch sw;
  Clustering c = read_clusters(clusters, mesh);
  manifest.add_timing_ms("read_clusters", sw.ms());
  std::error_code ec;
  record_input(manifest, std::filesystem::is_directory(clusters, ec) ? clusters / "triangles.csv" : clusters);
  return c;
}

ClusteringInfo clustering_info_recorded(const std::filesystem::path& clusters, RunManifest& manifest) {
  ClusteringInfo ci = clustering_info(clusters);
  if (ci.from_manifest) record_input(manifest, ci.from);
  return ci;
}

CameraSpec camera_for(const CameraSpec& flags, const Scene& scene) {
  CameraSpec spec = flags;
  if (scene.has_own_camera()) {
    const SceneCamera& sc = scene.camera();
    if (!spec.eye) {
      spec.eye = sc.eye;
      if (flags.look_at) spec.eye_look_flag = "--look-at";  // (the scene's eye: the flag given is --look-at)
    }
    if (!spec.look_at) spec.look_at = sc.look_at;
    if (!spec.up) spec.up = sc.up;
    if (!spec.fov_deg) spec.fov_deg = sc.fov_deg;
  }
  return spec;
}

nlohmann::json light_json(const LightChoice& light) {
  return {{"position", vec_json(light.position)}, {"from", light.from}, {"intensity", light.intensity}};
}

nlohmann::json camera_json(const bvh::PinholeCamera& cam, const Scene& scene, const CameraSpec& flags) {
  return {{"eye", vec_json(cam.eye)},
          {"forward", vec_json(cam.forward)},
          {"right", vec_json(cam.right)},
          {"up", vec_json(cam.up)},
          {"fov_y_deg", cam.fov_y_deg},
          {"from_scene", scene.has_own_camera()},
          {"given",
           {{"eye", bool(flags.eye)}, {"look_at", bool(flags.look_at)}, {"up", bool(flags.up)}, {"fov", bool(flags.fov_deg)}}}};
}

LightChoice light_for(const std::optional<Vec3>& flag, const Scene& scene, const bvh::PinholeCamera& cam,
                      const Box3& bounds, std::string_view input) {
  // (--light moves the light; its intensity stays the scene's own, 1 for a scene without one)
  const double intensity = scene.has_own_light() ? scene.light().intensity : 1.0;
  const LightChoice c = flag                    ? LightChoice{*flag, "--light", intensity}
                        : scene.has_own_light() ? LightChoice{scene.light().position, "scene", intensity}
                                                : LightChoice{default_light(cam, bounds), "default", intensity};
  // The light is not a ray origin (shadow rays leave the surface toward it): it only has to be a
  // double's distance away, its difference to the scene finite (the directions are taken without
  // overflowing squares, render/rays.cpp).
  const Box3 b = scene.rest().referenced_bounds();
  if (!b.empty() && b.lo.allFinite() && b.hi.allFinite() &&
      (!(c.position - b.lo).allFinite() || !(c.position - b.hi).allFinite())) {
    const std::string reason = fmt::format("the light ({:.6g}, {:.6g}, {:.6g}) and the scene are too far apart: their "
                                           "difference is beyond double's range",
                                           c.position.x(), c.position.y(), c.position.z());
    if (std::string_view(c.from) == "--light") throw UsageError("--light", reason);
    throw InputError(std::string(input), "", "light", reason);
  }
  return c;
}

void check_eye_reach(const bvh::PinholeCamera& cam, const CameraSpec& flags, const Scene& scene, std::string_view input) {
  if (flags.eye) return check_reach(scene, cam.eye, "the camera's eye", "--eye", "--eye", "camera", input);
  if (scene.has_own_camera()) return check_reach(scene, cam.eye, "the camera's eye", "--eye", "scene", "camera", input);
  // Framed by make_camera: its distance follows --fov and --look-at when they were given.
  const char* flag = flags.fov_deg ? "--fov" : flags.look_at ? "--look-at" : "";
  check_reach(scene, cam.eye, "the eye of the camera framing the mesh", flag, *flag ? flag : "default", "camera", input);
}

void check_reach(const Scene& scene, const Vec3& p, std::string_view what, std::string_view flag, std::string_view from,
                 std::string_view element, std::string_view input) {
  const Mesh& rest = scene.rest();
  if (rest.vertex_count() == 0) return;
  const Vec3 centre = rest.referenced_bounds().center();
  double scale = 1.0;
  try {
    scale = bvh::trace_frame_scale(rest, centre);
  } catch (const bvh::FrameRangeError&) {
    return;  // (the mesh itself is refused when its BVH is made)
  }
  if (!centre.allFinite()) return;
  const double d = (p - centre).cwiseAbs().maxCoeff();
  if (std::isfinite(d) && d * scale <= kTraceReach) return;
  const std::string reason =
      fmt::format("{} ({:.6g}, {:.6g}, {:.6g}) lies {:.3g} units from the scene's centre, beyond the tracer's reach "
                  "(at most {:.3g} units for this scene, {:g} in its single-precision frame); move it closer",
                  what, p.x(), p.y(), p.z(), d, kTraceReach / scale, kTraceReach);
  if (from == flag) throw UsageError(std::string(flag), reason);
  throw InputError(std::string(input), "", std::string(element), reason);
}

void refuse_unused_data_dir(const std::filesystem::path& input) {
  const std::string arg = input.string();
  if (scene_reads_data_dir(arg)) return;
  std::error_code ec;
  const bool exists = std::filesystem::exists(input, ec);
  const std::string what = !exists                                    ? "not a built-in scene"
                           : std::filesystem::is_directory(input, ec) ? "a directory of frames"
                                                                      : "a file";
  throw UsageError("--data-dir", "not used: '" + arg + "' is " + what +
                                     (exists && is_builtin_scene(arg) ? " (it also names a built-in scene; the path wins)" : "") +
                                     " (--data-dir locates the meshes of built-in scenes and the ${data}/ paths of "
                                     "scene files)");
}

}  // namespace ptc
