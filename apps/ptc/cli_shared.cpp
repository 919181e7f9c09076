// The flags several subcommands share, defined once (cli.h).
#include "apps/ptc/cli.h"

namespace ptc::cli {

namespace {
CLI::Validator vec3_validator() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        std::string why;
        return parse_vec3(s, &why) ? std::string() : why;
      },
      "X,Y,Z");
}
}  // namespace

void SceneArg::add_to(CLI::App* cmd) {
  cmd->add_option("SCENE", input,
                  "built-in scene name ('ptc scenes'), scene file (.json), mesh or animated asset file, or directory of "
                  "frames")
      ->required();
  cmd->add_option("--data-dir", data_dir, "meshes of built-in scenes (default: $PTC_DATA_DIR or <ptc>/../data)");
}

void CameraArgs::add_to(CLI::App* c, bool with_light) {
  c->add_option("--eye", eye, "camera position (default: the scene's camera, else framing the whole first frame)")
      ->check(vec3_validator());
  c->add_option("--look-at", look_at, "point the camera looks at (default: centre of the mesh's bounds)")
      ->check(vec3_validator());
  c->add_option("--up", up, "camera up direction (default: 0,1,0)")->check(vec3_validator());
  fov_opt = c->add_option("--fov", fov, "vertical field of view in degrees, in (0, 180)")
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
  if (with_light)
    c->add_option("--light", light, "point light position (default: the scene's light, else above and right of the eye)")
        ->check(vec3_validator());
}

CameraSpec CameraArgs::spec() const {
  CameraSpec s;
  if (!eye.empty()) s.eye = parse_vec3(eye);
  if (!look_at.empty()) s.look_at = parse_vec3(look_at);
  if (!up.empty()) s.up = parse_vec3(up);
  if (fov_opt && fov_opt->count()) s.fov_deg = fov;
  return s;
}

std::optional<Vec3> CameraArgs::light_position() const {
  return light.empty() ? std::nullopt : parse_vec3(light);
}

}  // namespace ptc::cli
