// Shared pieces of the `ptc` command line. Each subcommand lives in its own cli_<name>.cpp and
// registers itself through a register_<name>() function listed in main.cpp; CLI11 is only
// included by apps/ptc (through a precompiled header: its headers are expensive).
#pragma once

#include <cstdio>
#include <cmath>
#include <filesystem>
#include <functional>
#include <optional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "commands/args.h"
#include "commands/errors.h"
#include "commands/scene_args.h"  // CameraSpec, SceneOptions
#include "commands/commands.h"  // ClusterConfig, flag_of

namespace ptc::cli {

/// Usage mistakes found after parsing are ptc::UsageError (toolkit/core/error.h): exit code 2.
using ptc::UsageError;

/// What every subcommand shares: the raw argv (recorded in manifests), the --threads value, and
/// the list of registered subcommands with the function that runs each.
struct Context {
  std::vector<std::string> args;
  int threads = 0;
  struct Entry {
    CLI::App* app;
    std::function<void()> run;
  };
  std::vector<Entry> commands;

  /// Adds a subcommand; `run` is called when it was the one given. Options are bound to
  /// objects the caller keeps alive (typically a shared_ptr captured by `run`).
  CLI::App* add(CLI::App& app, const std::string& name, const std::string& help, std::function<void()> run) {
    CLI::App* sub = app.add_subcommand(name, help);
    commands.push_back({sub, std::move(run)});
    return sub;
  }
};

// Strings from the command line become enums here, at the edge (style.md point 5).
template <class Parse>
CLI::Validator enum_validator(std::string name, Parse parse) {
  return CLI::Validator(
      [parse, name](std::string& s) -> std::string {
        return parse(s) ? std::string() : "'" + s + "' is not a valid " + name;
      },
      name);
}

/// The whole string as a double (std::stod's syntax; nan and inf included), or nothing.
inline std::optional<double> number_arg(const std::string& s) {
  try {
    std::size_t n = 0;
    const double v = std::stod(s, &n);
    if (n == s.size()) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

/// auto, off or a number above `above` (commands/args.h parse_auto_off_or_above; the auto value
/// does not matter for the check).
inline CLI::Validator auto_off_or_above_validator(double above) {
  return CLI::Validator(
      [above](std::string& s) -> std::string {
        if (parse_auto_off_or_above(s, 0.0, above)) return {};
        char bound[32];
        std::snprintf(bound, sizeof bound, "%g", above);
        return "'" + s + "' is not auto, off or a number above " + bound;
      },
      "auto|off|X");
}
/// --cluster-fallback (commands/args.h parse_cluster_fallback).
inline CLI::Validator cluster_fallback_validator() { return auto_off_or_above_validator(1.0); }
inline constexpr const char* kClusterFallbackHelp =
    "trace a frame of the cluster BVH on a BVH over its triangles, rebuilt that frame, when the clusters have come "
    "apart: their boxes' half area over the triangles' area (the swelling) above X. auto: X = 64 (2-3.6 on the "
    "built-in meshes but the explode scene, which passes it at frame 8); off: the cluster BVH on every frame (the "
    "method as published); or a number X > 1";

/// --fallback-refit (commands/args.h parse_fallback_refit).
inline CLI::Validator fallback_refit_validator() { return auto_off_or_above_validator(0.0); }
inline constexpr const char* kFallbackRefitHelp =
    "with the triangle fallback: keep its tree and refit it to the next frames while its SAH cost stays within "
    "(1 + X) of the cost right after its build, rebuild otherwise. auto: X = 0.2 (the tree is then kept about "
    "every other frame on the explode scene); off: rebuild it every frame";

/// --fallback-sah (bvh::parse_fallback_sah).
inline constexpr const char* kFallbackSahHelp =
    "with the triangle fallback: directions: build it for the camera's rays, its SAH pricing a box by its mean area "
    "across the primary rays' directions (on the explode scene 12-14% fewer nodes a primary ray than plain); eye: by "
    "the solid angle it shows the camera's eye (8-9% fewer again, but a dearer update and slower shadow rays: no "
    "faster a whole frame); plain: the plain SAH, every direction alike";

/// A finite number in [lo, hi]: refuses nan and inf (CLI11's Range lets nan through, since no
/// comparison with it fails) and names the bounds in %g form (its "0.000000" hid a bound of 1e-9).
inline CLI::Validator finite_in(double lo, double hi) {
  char desc[64];
  std::snprintf(desc, sizeof desc, "FLOAT in [%g, %g]", lo, hi);
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        const std::optional<double> v = number_arg(s);
        if (!v) return "'" + s + "' is not a number";
        char why[96];
        std::snprintf(why, sizeof why, "%s is not a finite number in [%g, %g]", s.c_str(), lo, hi);
        return std::isfinite(*v) && *v >= lo && *v <= hi ? std::string() : std::string(why);
      },
      desc);
}

/// A whole number in [lo, hi] (CLI11's Range said "Value 1.5 not in range 0 to 1048576" for a
/// fraction or a word).
inline CLI::Validator whole_in(long long lo, long long hi) {
  const std::string desc = "INT in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        long long v = 0;
        std::size_t n = 0;
        try {
          v = std::stoll(s, &n);
        } catch (const std::exception&) {
          n = 0;
        }
        if (s.empty() || n != s.size() || v < lo || v > hi)
          return "'" + s + "' is not a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
        return std::string();
      },
      desc);
}

/// A seed: a whole number >= 0 (an unsigned option would take "-5" as 2^64 - 5).
inline CLI::Validator seed_validator() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        return !s.empty() && s.find_first_not_of("0123456789") == std::string::npos ? std::string()
                                                                                   : "'" + s + "' is not a seed (a whole number >= 0)";
      },
      "UINT");
}

inline void add_threads_option(CLI::App* cmd, int& threads) {
  // One default for every command: all cores (oneTBB's default concurrency). `ptc bench --threads 1`
  // gives one-thread figures (ours and Embree's device alike).
  cmd->add_option("--threads", threads, "worker threads (default: all cores)")->check(whole_in(1, 4096));
}

/// The SCENE positional argument and --data-dir, as every command that takes a scene spells them.
struct SceneArg {
  std::filesystem::path input;
  std::string data_dir;
  void add_to(CLI::App* cmd);
  /// Fills the command's scene options (data directory of built-in scenes). --data-dir with a
  /// SCENE that is an existing mesh, asset or directory of frames (not a scene file, whose
  /// "${data}/" paths read it) is bad usage: it would do nothing.
  void apply(SceneOptions& o) const;
};

/// --eye, --look-at, --up, --fov and (with light = true) --light, as `ptc trace` and `ptc bench`
/// spell them; the values given become the CameraSpec's fields (commands/scene_args.h: flag >
/// the scene's camera > framing the mesh).
struct CameraArgs {
  std::string eye, look_at, up, light;
  double fov = kDefaultFovDeg;
  CLI::Option* fov_opt = nullptr;
  void add_to(CLI::App* cmd, bool with_light);
  [[nodiscard]] CameraSpec spec() const;
  [[nodiscard]] std::optional<Vec3> light_position() const;
};

/// --group-trees rebuild|refit (bvh::GroupTrees), as `ptc trace`, `ptc bench` and `ptc experiment`
/// spell it. get(): the choice; given without the two-level build (`two_level` false) it is a
/// usage error saying what it `needs`.
struct GroupTreesArg {
  std::string value = bvh::to_string(bvh::cluster_scene_defaults().group_trees);
  CLI::Option* opt = nullptr;
  void add_to(CLI::App* cmd);
  [[nodiscard]] bvh::GroupTrees get(bool two_level, const std::string& needs) const;
};

/// The triangle fallback's flags of `ptc bench` and `ptc trace` (--cluster-fallback,
/// --fallback-refit, --fallback-sah): the same help, checks and defaults in both.
struct FallbackFlags {
  std::string swelling = "auto", refit = "auto", sah = "directions";
  CLI::App* cmd = nullptr;
  void add_to(CLI::App* c);
  /// --fallback-refit or --fallback-sah given while the fallback is off (`on` false): UsageError.
  void require_fallback(bool on) const;
};

/// The clustering flags, as `ptc cluster` spells them (--method, --objective, --max-count, ...);
/// `ptc experiment` takes the same. apply() fills the ClusterConfig and lists the parameters the
/// user set (names of kClusterParameters) in `given`.
struct ClusterFlags {
  std::string method = "contraction", objective = "acc", size_bound = "max", sphere = "cgal", start = "spatial",
              gwh_weight = "area", adjacency = "auto";
  CLI::App* app = nullptr;
  /// with_method: --method and --objective (sweep and cluster; compare and drift name their
  /// clusterings instead).
  void add_to(CLI::App* cmd, ClusterConfig& cfg, bool with_method);
  void apply(ClusterConfig& cfg, std::vector<std::string>& given) const;
};

// One register function per subcommand (cli_<name>.cpp).
void register_info(CLI::App& app, Context& ctx);
void register_subdivide(CLI::App& app, Context& ctx);
void register_spheres(CLI::App& app, Context& ctx);
void register_cluster(CLI::App& app, Context& ctx);
void register_animate(CLI::App& app, Context& ctx);
void register_scenes(CLI::App& app, Context& ctx);
void register_trace(CLI::App& app, Context& ctx);
void register_bench(CLI::App& app, Context& ctx);
void register_experiment(CLI::App& app, Context& ctx);
void register_viz(CLI::App& app, Context& ctx);
void register_notebook(CLI::App& app, Context& ctx);
void register_merge(CLI::App& app, Context& ctx);

}  // namespace ptc::cli
