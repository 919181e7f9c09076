// `ptc trace SCENE [--frame F | --frames A:B] [--data-dir DIR] [--clusters DIR] [--width W --height H] [--eye X,Y,Z --look-at X,Y,Z --up X,Y,Z
// --fov DEG] [--shadows] [--ao N] [--threads T] [--seed S] --out DIR` (commands/trace.h).
#include <iostream>

#include "commands/trace.h"
#include "apps/ptc/cli.h"
#include "commands/args.h"

namespace ptc::cli {

namespace {
struct TraceArgs {
  TraceCommandOptions opt;
  std::string eye, look_at, up, light, frame, frames, data_dir;
  double fov = kDefaultFovDeg;
  CLI::App* app = nullptr;
};

CLI::Validator vec3_validator() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        std::string why;
        return parse_vec3(s, &why) ? std::string() : why;
      },
      "X,Y,Z");
}
}  // namespace

void register_trace(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<TraceArgs>();
  auto& rc = a->opt.render;
  auto* c = ctx.add(app, "trace", "render a scene with the reference tracer: images, trace.csv, manifest.json", [a, &ctx] {
    auto& o = a->opt;
    if (!a->eye.empty()) o.camera.eye = parse_vec3(a->eye);
    if (!a->look_at.empty()) o.camera.look_at = parse_vec3(a->look_at);
    if (!a->up.empty()) o.camera.up = parse_vec3(a->up);
    if (!a->light.empty()) o.render.light = parse_vec3(a->light);
    if (a->app->count("--fov")) o.camera.fov_deg = a->fov;
    if (a->app->count("--frame")) o.frame = a->frame;
    if (a->app->count("--frames")) o.frames = a->frames;
    if (!a->data_dir.empty()) o.scene_options.data_dir = a->data_dir;
    o.render.threads = static_cast<unsigned>(ctx.threads);
    o.argv = ctx.args;
    cmd_trace(o, std::cout);
  });
  a->app = c;
  c->add_option("SCENE", a->opt.input,
                "built-in scene name ('ptc scenes'), scene file (.json), mesh or animated asset file, or directory of frames")
      ->required();
  auto* one = c->add_option("--frame", a->frame, "trace frame F (default: the scene's first frame)");
  c->add_option("--frames", a->frames, "trace frames A:B: images shaded_0000.png ..., trace.csv rows per frame")
      ->excludes(one);
  c->add_flag("--extend-frames", a->opt.extend_frames, "allow frames outside the scene's listed range");
  c->add_option("--data-dir", a->data_dir, "meshes of built-in scenes (default: $PTC_DATA_DIR or <ptc>/../data)");
  c->add_option("--clusters", a->opt.clusters, "trace a cluster BVH over the clustering in DIR/triangles.csv (ptc cluster --out DIR)");
  c->add_option("--cluster-groups", a->opt.cluster_group_size,
                "with --clusters: two-level BVH build over fixed groups of at most N clusters; 0 = plain build")
      ->check(CLI::Range(0u, 1u << 20))
      ->capture_default_str();
  c->add_option("--width", rc.width, "image width in pixels")->check(CLI::Range(1, 16384))->capture_default_str();
  c->add_option("--height", rc.height, "image height in pixels")->check(CLI::Range(1, 16384))->capture_default_str();
  c->add_option("--eye", a->eye, "camera position (default: the scene's camera, else framing the whole first frame)")->check(vec3_validator());
  c->add_option("--look-at", a->look_at, "point the camera looks at (default: centre of the mesh's bounds)")
      ->check(vec3_validator());
  c->add_option("--up", a->up, "camera up direction (default: 0,1,0)")->check(vec3_validator());
  c->add_option("--fov", a->fov, "vertical field of view in degrees, in (0, 180)")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            double v = 0;
            try {
              std::size_t n = 0;
              v = std::stod(s, &n);
              if (n != s.size()) return "'" + s + "' is not a number";
            } catch (const std::exception&) {
              return "'" + s + "' is not a number";
            }
            return v > 0 && v < 180 ? std::string() : "the field of view must be in (0, 180) degrees";
          },
          "DEG"))
      ->capture_default_str();
  c->add_option("--light", a->light, "point light position (default: the scene's light, else above and right of the eye)")->check(vec3_validator());
  c->add_flag("--shadows", rc.shadows, "trace shadow rays to the point light");
  c->add_option("--ao", rc.ao_samples, "ambient-occlusion rays per pixel (0 = none)")->check(CLI::Range(0, 4096))->capture_default_str();
  c->add_option("--ao-distance", rc.ao_distance_rel, "AO max distance as a fraction of the mesh's bounds diagonal")
      ->check(CLI::Range(1e-9, 1e9))
      ->capture_default_str();
  c->add_option("--seed", rc.seed, "seed of the AO directions")->capture_default_str();
  c->add_option("--out", a->opt.out_dir, "output directory (written atomically)")->required();
  c->add_flag("--json", a->opt.json, "print the per-frame, per-pass figures as JSON");
  add_threads_option(c, ctx.threads);
}

}  // namespace ptc::cli
