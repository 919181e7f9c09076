// The flags several subcommands share, defined once (cli.h).
#include "apps/ptc/cli.h"
#include "commands/commands.h"

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

void SceneArg::apply(SceneOptions& o) const {
  if (data_dir.empty()) return;
  refuse_unused_data_dir(input);  // (commands/scene_args.h: the scene opener's rule)
  o.data_dir = data_dir;
}

void GroupTreesArg::add_to(CLI::App* cmd) {
  opt = cmd->add_option("--group-trees", value,
                        "with the cluster BVH's two-level build (--cluster-groups N > 1): rebuild each group's tree "
                        "over its cluster boxes every frame, or refit: keep the tree built at the rest pose and refit "
                        "its boxes (the build then sees one box per group)")
            ->check(enum_validator("group trees", bvh::parse_group_trees))
            ->capture_default_str();
}

bvh::GroupTrees GroupTreesArg::get(bool two_level, const std::string& needs) const {
  if (opt && opt->count() && !two_level) throw UsageError("--group-trees", "needs " + needs);
  return *bvh::parse_group_trees(value);
}

void FallbackFlags::add_to(CLI::App* c) {
  cmd = c;
  static_assert(bvh::kAutoFallbackSwelling == 64.0, "the --cluster-fallback help quotes the threshold");
  c->add_option("--cluster-fallback", swelling, kClusterFallbackHelp)->check(cluster_fallback_validator())->capture_default_str();
  static_assert(bvh::kAutoFallbackRefitGrowth == 0.2, "the --fallback-refit help quotes the limit");
  c->add_option("--fallback-refit", refit, kFallbackRefitHelp)->check(fallback_refit_validator())->capture_default_str();
  c->add_option("--fallback-sah", sah, kFallbackSahHelp)
      ->check(enum_validator("fallback SAH (eye, directions or plain)", bvh::parse_fallback_sah))
      ->capture_default_str();
}

void FallbackFlags::require_fallback(bool on) const {
  for (const char* f : {"--fallback-refit", "--fallback-sah"})
    if (!on && cmd->count(f)) throw UsageError(f, "needs the triangle fallback (--cluster-fallback auto or X)");
}

void CameraArgs::add_to(CLI::App* c, bool with_light) {
  c->add_option("--eye", eye, "camera position (default: the scene's camera, else framing the whole first frame)")
      ->check(vec3_validator());
  c->add_option("--look-at", look_at, "point the camera looks at (default: centre of the mesh's bounds)")
      ->check(vec3_validator());
  c->add_option("--up", up, "camera up direction (default: 0,1,0)")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            std::string why;
            const auto v = parse_vec3(s, &why);
            if (!v) return why;
            // (exactly zero: Eigen's isZero() calls 1e-300 zero too, while any direction normalises)
            return v->cwiseAbs().maxCoeff() == 0.0 ? "the up vector is zero" : std::string();
          },
          "X,Y,Z"));
  fov_opt = c->add_option("--fov", fov, "vertical field of view in degrees, in (0, 180)")
                ->check(CLI::Validator(
                    [](std::string& s) -> std::string {
                      const std::optional<double> v = number_arg(s);
                      if (!v) return "'" + s + "' is not a number";
                      return *v > 0 && *v < 180 ? std::string() : "the field of view must be in (0, 180) degrees";
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

void ClusterFlags::add_to(CLI::App* c, ClusterConfig& cfg, bool with_method) {
  app = c;
  if (with_method) {
    c->add_option("--method", method, "growth, contraction, sah-split or meshopt")
        ->check(enum_validator("method", parse_cluster_method))
        ->capture_default_str();
    c->add_option("--objective", objective, "acc (Garanzha 2009), naive (SAH clusters) or gwh01 (Garland et al. 2001)")
        ->check(enum_validator("objective", parse_objective))
        ->capture_default_str();
  }
  c->add_option("--max-count", cfg.max_count, "MaxCount (vertices); 0 with --max-size 0 = one triangle per cluster")
      ->check(whole_in(0, 1 << 20))
      ->capture_default_str();
  c->add_option("--max-size", cfg.max_size, "MaxSize (sphere area in units of the mean triangle sphere area)")
      ->check(finite_in(0.0, 1e12))
      ->capture_default_str();
  c->add_option("--size-bound", size_bound, "max (as printed in the paper) or min")
      ->check(enum_validator("size bound", parse_size_bound_mode))
      ->capture_default_str();
  c->add_option("--sphere", sphere, "bounding sphere inside the objective: exact cgal ritter epos6 epos14 epos26")
      ->check(enum_validator("sphere method", parse_sphere_method))
      ->capture_default_str();
  c->add_option("--start", start, "growth start rule: index, spatial or fewest-free")
      ->check(enum_validator("start rule", parse_start_rule))
      ->capture_default_str();
  c->add_option("--gwh-a1", cfg.gwh.a1, "GWH01 weight of E_dir")->check(finite_in(0.0, 1e6))->capture_default_str();
  c->add_option("--gwh-a2", cfg.gwh.a2, "GWH01 weight of E_shape")->check(finite_in(0.0, 1e6))->capture_default_str();
  c->add_option("--gwh-weight", gwh_weight, "GWH01 E_dir weights: area or sqrt-area")
      ->check(enum_validator("weight", parse_gwh_weight))
      ->capture_default_str();
  c->add_option("--target-clusters", cfg.target_clusters, "contraction (any objective): stop at this many clusters (0 = off)")
      ->check(whole_in(0, 4294967295LL))
      ->capture_default_str();
  c->add_option("--max-triangles", cfg.max_triangles, "sah-split/meshopt triangle limit (0 = 2 x max-count)")
      ->check(whole_in(0, 4294967295LL))
      ->capture_default_str();
  c->add_option("--regions", cfg.regions,
                "growth or contraction with acc or naive: cluster N spatial regions at once, on all --threads "
                "(clusters stop at region borders; the same clusters at any thread count); 0 or 1 = one region")
      ->check(whole_in(0, 1 << 24))
      ->capture_default_str();
  c->add_option("--adjacency", adjacency,
                "neighbouring triangles: edges (shared vertex ids, the paper's), positions (sides whose corner "
                "positions coincide) or auto (positions for a triangle soup, else edges)")
      ->check(enum_validator("adjacency", parse_cluster_adjacency))
      ->capture_default_str();
}

void ClusterFlags::apply(ClusterConfig& cf, std::vector<std::string>& given) const {
  cf.method = *parse_cluster_method(method);
  cf.objective = *parse_objective(objective);
  cf.size_bound_mode = *parse_size_bound_mode(size_bound);
  cf.sphere = *parse_sphere_method(sphere);
  cf.start = *parse_start_rule(start);
  cf.gwh.weight = *parse_gwh_weight(gwh_weight);
  cf.adjacency = *parse_cluster_adjacency(adjacency);
  for (std::string_view p : kClusterParameters) {
    const std::string flag = flag_of(p);
    if (app->get_option_no_throw(flag) && app->count(flag)) given.emplace_back(p);
  }
}

}  // namespace ptc::cli
