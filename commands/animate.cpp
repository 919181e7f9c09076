// `ptc animate`.
#include "commands/animate.h"

#include <charconv>
#include <chrono>
#include <cmath>
#include <limits>
#include <iostream>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/metrics/frame_stats.h"
#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "commands/args.h"
#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "commands/progress.h"
#include "commands/scene_args.h"
#include "toolkit/anim/scene_file.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/core/strings.h"

namespace fs = std::filesystem;

namespace ptc {

void cmd_animate(const AnimateOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw UsageError("--out", "an output directory is required");
  if (opt.format != MeshFormat::Ply && opt.format != MeshFormat::Obj)
    throw UsageError("--format", "frames are written as ply or obj");
  // Parse --frames before the (possibly long) scene construction: a typo fails at once.
  std::optional<FrameRange> asked;
  if (opt.frames) asked = parse_frame_range(*opt.frames, "--frames");

  refuse_overwriting_input(opt.out_dir, opt.scene);
  RunManifest manifest("animate", opt.argv, "ptc-animate/1");
  Scene scene = open_scene_recorded(opt.scene, opt.scene_options, manifest);  // every file it reads, hashed
  Stopwatch t0;

  const bool deformed = opt.deform && *opt.deform != "none";
  const bool still = scene.all_static() && !deformed;
  manifest.set_parameter("motion", apply_stand_in(scene, opt.deform.value_or("none"), opt.scene));
  const FrameRange range = asked ? *asked : scene.frames();
  // (a stand-in motion is periodic: it has no range of its own, as in ptc bench and ptc trace)
  check_frames(scene, range, opt.scene, "--frames", opt.extend_frames || deformed);

  const Mesh& rest = scene.rest();
  const char* ext = opt.format == MeshFormat::Ply ? "ply" : "obj";
  manifest.set_parameter("scene", opt.scene);
  manifest.set_parameter("frames", {range.first, range.last});
  manifest.set_parameter("format", ext);
  manifest.set_parameter("stats", opt.stats);

  OutputDir dir(opt.out_dir);
  // Frames that would not fit are refused before one is written (a stand-in motion has no range
  // of its own: a typo such as --frames 0:99999999999 would fill the disk). The size is a lower
  // bound: binary PLY's 24 bytes a vertex and 13 a triangle (OBJ's text takes more).
  const double frame_bytes = 24.0 * double(rest.vertex_count()) + 13.0 * double(rest.triangle_count()) + 256.0;
  try {
    dir.check_room(frame_bytes * double(range.count()), "--frames",
                   fmt::format("frames {}:{} ({} of {} or more each)", range.first, range.last,
                               counted(std::uint64_t(range.count()), "frame"), readable_bytes(frame_bytes)));
  } catch (const UsageError& e) {
    if (asked) throw;
    // The range is the scene's own (its file's "frames"), not a flag the user gave: said so.
    throw InputError(opt.scene, "", "frames", e.reason() + " (its own range; --frames A:B takes fewer)");
  }
  std::vector<Vec3> pos(rest.vertex_count());
  std::vector<double> first_areas;
  std::vector<FrameStats> stats;
  nlohmann::json files = nlohmann::json::array();
  double animate_ms = 0, write_ms = 0;
  {
    ProgressBar bar("animate");
    for (std::int64_t f = range.first; f <= range.last; ++f) {
      t0.restart();
      scene.positions(double(f), pos);
      animate_ms += t0.ms();
      for (const Vec3& p : pos)
        if (!p.allFinite())
          throw std::runtime_error(fmt::format("frame {} of '{}' has a non-finite vertex position", f, opt.scene));
      if (opt.stats) {
        if (f == range.first) first_areas = triangle_areas(rest.triangles(), pos);
        stats.push_back(frame_stats(f, rest.triangles(), pos, first_areas));
      }
      t0.restart();
      const std::string name = fmt::format("frame_{:04d}.{}", f, ext);
      write_mesh(dir.path(name), rest.with_positions(pos));
      write_ms += t0.ms();
      files.push_back(name);
      manifest.add_output(name);
      bar.update(double(f - range.first + 1) / double(range.count()));
    }
  }
  manifest.add_timing_ms("animate", animate_ms);
  manifest.add_timing_ms("write", write_ms);

  if (opt.stats) {
    const Table t = frame_stats_table(stats);
    dir.write("stats.csv", t.csv.str());
    manifest.add_output("stats.csv", t.schema.id());
  }

  nlohmann::json parts = nlohmann::json::array();
  for (std::size_t k = 0; k < scene.part_count(); ++k)
    parts.push_back({{"name", scene.part(k).name},
                     {"static", scene.is_static(k)},
                     {"vertex_begin", scene.vertex_offset(k)},
                     {"vertex_end", scene.vertex_offset(k + 1)},
                     {"triangle_begin", scene.triangle_offset(k)},
                     {"triangle_end", scene.triangle_offset(k + 1)},
                     {"source", scene.part(k).source->describe()}});
  manifest.set_result("triangles", rest.triangle_count());
  manifest.set_result("vertices", rest.vertex_count());
  manifest.set_result("frames_written", range.count());
  manifest.set_result("parts", parts);
  manifest.set_result("camera", {{"eye", vec_json(scene.camera().eye)},
                                 {"look_at", vec_json(scene.camera().look_at)},
                                 {"up", vec_json(scene.camera().up)},
                                 {"fov", scene.camera().fov_deg}});
  manifest.set_result("light", {{"position", vec_json(scene.light().position)}, {"intensity", scene.light().intensity}});
  // Whether they are the scene's own (else the defaults a command replaces with its own framing):
  // a frame directory takes only its scene's own view (toolkit/anim/scene_file.h animate_view).
  manifest.set_result("camera_own", scene.has_own_camera());
  manifest.set_result("light_own", scene.has_own_light());
  manifest.set_result("files", files);
  const nlohmann::json doc = commit_with_manifest(dir, manifest);

  if (still && range.count() > 1)  // (on stderr: --json's stdout stays one document)
    std::cerr << fmt::format(
        "ptc: note: '{}' does not move: its {} frames are the rest pose (--deform twist|bend|wave|rigid|explode gives it "
        "the stand-in motion ptc bench measures)\n",
        opt.scene, range.count());
  if (opt.json) {
    nlohmann::json results = doc["results"];
    if (opt.stats) {  // what the text mode prints: stats.csv's rows, with its column names (NaN as null)
      nlohmann::json rows = nlohmann::json::array();
      for (const FrameStats& st : stats)
        rows.push_back({{"frame", st.frame},
                        {"bbox_min_x", st.bounds.lo.x()},
                        {"bbox_min_y", st.bounds.lo.y()},
                        {"bbox_min_z", st.bounds.lo.z()},
                        {"bbox_max_x", st.bounds.hi.x()},
                        {"bbox_max_y", st.bounds.hi.y()},
                        {"bbox_max_z", st.bounds.hi.z()},
                        {"bbox_diagonal", st.bounds.extent().norm()},
                        {"total_area", st.total_area},
                        {"area_ratio_min", st.area_ratio_min},
                        {"area_ratio_mean", st.area_ratio_mean},
                        {"area_ratio_max", st.area_ratio_max},
                        {"degenerate_at_first", st.degenerate_at_first}});
      results["stats"] = std::move(rows);
    }
    out << dump_json(results);
    return;
  }
  out << fmt::format("{}: {}, {}, {}; frames {}..{} -> {}/frame_*.{} in {:.0f} ms (animate {:.0f} ms)\n",
                     scene.name(), counted(rest.triangle_count(), "triangle"),
                     counted(rest.vertex_count(), "vertex", "vertices"), counted(scene.part_count(), "part"), range.first,
                     range.last,
                     opt.out_dir.string(), ext, animate_ms + write_ms, animate_ms);
  if (opt.stats) {
    out << fmt::format("{:>6} {:>36} {:>12} {:>10} {:>10} {:>10}\n", "frame", "bbox min .. max (diagonal)", "total_area",
                       "ratio_min", "ratio_mean", "ratio_max");
    for (const FrameStats& s : stats)
      out << fmt::format("{:>6} {:>36} {:>12.6g} {:>10.4g} {:>10.4g} {:>10.4g}\n", s.frame,
                         fmt::format("({:.3g},{:.3g},{:.3g})..({:.3g},{:.3g},{:.3g}) ({:.4g})", s.bounds.lo.x(),
                                     s.bounds.lo.y(), s.bounds.lo.z(), s.bounds.hi.x(), s.bounds.hi.y(), s.bounds.hi.z(),
                                     s.bounds.extent().norm()),
                         s.total_area, s.area_ratio_min, s.area_ratio_mean, s.area_ratio_max);
    out << "wrote " << (opt.out_dir / "stats.csv").string() << "\n";
  }
}

}  // namespace ptc
