#include "analysis/cmd_animate.h"

#include <charconv>
#include <chrono>
#include <cmath>
#include <limits>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/csv.h"
#include "analysis/manifest.h"
#include "analysis/output_dir.h"
#include "analysis/progress.h"
#include "analysis/scene_file.h"
#include "toolkit/core/error.h"

namespace fs = std::filesystem;

namespace ptc {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::int64_t parse_frame_number(std::string_view s, std::string_view whole) {
  std::int64_t v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v < 0)
    throw InputError("", "", "--frames",
                     fmt::format("'{}' is not A:B with non-negative integers A <= B (e.g. 0:59)", whole));
  return v;
}

nlohmann::json vec_json(const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

}  // namespace

FrameRange parse_frame_range(std::string_view s) {
  const auto colon = s.find(':');
  FrameRange r;
  if (colon == std::string_view::npos) {
    r.first = r.last = parse_frame_number(s, s);
  } else {
    r.first = parse_frame_number(s.substr(0, colon), s);
    r.last = parse_frame_number(s.substr(colon + 1), s);
  }
  if (r.last < r.first)
    throw InputError("", "", "--frames", fmt::format("'{}': the last frame {} is before the first {}", s, r.last, r.first));
  return r;
}

std::vector<double> triangle_areas(std::span<const Tri> triangles, std::span<const Vec3> positions) {
  std::vector<double> a(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Tri& f = triangles[t];
    a[t] = 0.5 * (positions[f[1]] - positions[f[0]]).cross(positions[f[2]] - positions[f[0]]).norm();
  }
  return a;
}

FrameStats frame_stats(std::int64_t frame, std::span<const Tri> triangles, std::span<const Vec3> positions,
                       std::span<const double> first_areas) {
  FrameStats s;
  s.frame = frame;
  for (const Vec3& p : positions) s.bounds.extend(p);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0;
  std::size_t counted = 0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Tri& f = triangles[t];
    const double a = 0.5 * (positions[f[1]] - positions[f[0]]).cross(positions[f[2]] - positions[f[0]]).norm();
    s.total_area += a;
    if (!(first_areas[t] > 0)) {
      ++s.degenerate_at_first;
      continue;
    }
    const double r = a / first_areas[t];
    lo = std::min(lo, r);
    hi = std::max(hi, r);
    sum += r;
    ++counted;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  s.area_ratio_min = counted ? lo : nan;
  s.area_ratio_max = counted ? hi : nan;
  s.area_ratio_mean = counted ? sum / double(counted) : nan;
  return s;
}

void cmd_animate(const AnimateOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw InputError("", "", "--out", "an output directory is required");
  if (opt.format != MeshFormat::Ply && opt.format != MeshFormat::Obj)
    throw InputError("", "", "--format", "frames are written as ply or obj");
  // Parse --frames before the (possibly long) scene construction: a typo fails at once.
  std::optional<FrameRange> asked;
  if (opt.frames) asked = parse_frame_range(*opt.frames);

  RunManifest manifest("animate", opt.argv);
  auto t0 = std::chrono::steady_clock::now();
  Scene scene = open_scene(opt.scene, opt.scene_options);
  manifest.add_timing_ms("load", ms_since(t0));
  std::error_code ec;
  if (fs::is_regular_file(opt.scene, ec)) manifest.add_input(opt.scene);

  const FrameRange range = asked ? *asked : scene.frames();
  if (const std::size_t fc = scene.frame_count(); fc > 0 && range.last >= static_cast<std::int64_t>(fc))
    throw InputError("", "", "--frames",
                     fmt::format("frame {} is beyond the last frame of '{}' (frames 0..{})", range.last, opt.scene, fc - 1));

  const Mesh& rest = scene.rest();
  const char* ext = opt.format == MeshFormat::Ply ? "ply" : "obj";
  manifest.set_parameter("scene", opt.scene);
  manifest.set_parameter("frames", {range.first, range.last});
  manifest.set_parameter("format", ext);
  manifest.set_parameter("stats", opt.stats);

  OutputDir dir(opt.out_dir);
  std::vector<Vec3> pos(rest.vertex_count());
  std::vector<double> first_areas;
  std::vector<FrameStats> stats;
  nlohmann::json files = nlohmann::json::array();
  double animate_ms = 0, write_ms = 0;
  {
    ProgressBar bar("animate");
    for (std::int64_t f = range.first; f <= range.last; ++f) {
      t0 = std::chrono::steady_clock::now();
      scene.positions(double(f), pos);
      animate_ms += ms_since(t0);
      for (const Vec3& p : pos)
        if (!p.allFinite())
          throw std::runtime_error(fmt::format("frame {} of '{}' has a non-finite vertex position", f, opt.scene));
      if (opt.stats) {
        if (f == range.first) first_areas = triangle_areas(rest.triangles(), pos);
        stats.push_back(frame_stats(f, rest.triangles(), pos, first_areas));
      }
      t0 = std::chrono::steady_clock::now();
      const std::string name = fmt::format("frame_{:04d}.{}", f, ext);
      write_mesh(dir.path(name), rest.with_positions(pos));
      write_ms += ms_since(t0);
      files.push_back(name);
      manifest.add_output(name);
      bar.update(double(f - range.first + 1) / double(range.count()));
    }
  }
  manifest.add_timing_ms("animate", animate_ms);
  manifest.add_timing_ms("write", write_ms);

  if (opt.stats) {
    CsvTable csv({"frame", "bbox_min_x", "bbox_min_y", "bbox_min_z", "bbox_max_x", "bbox_max_y", "bbox_max_z",
                  "bbox_diagonal", "total_area", "area_ratio_min", "area_ratio_mean", "area_ratio_max",
                  "degenerate_at_first"});
    for (const FrameStats& s : stats)
      csv.add_row({s.frame, s.bounds.lo.x(), s.bounds.lo.y(), s.bounds.lo.z(), s.bounds.hi.x(), s.bounds.hi.y(),
                   s.bounds.hi.z(), s.bounds.extent().norm(), s.total_area, s.area_ratio_min, s.area_ratio_mean,
                   s.area_ratio_max, static_cast<std::uint64_t>(s.degenerate_at_first)});
    dir.write("stats.csv", csv.str());
    manifest.add_output("stats.csv");
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
  manifest.set_result("files", files);
  manifest.add_output("manifest.json");
  nlohmann::json doc = manifest.to_json();
  doc["schema"] = "ptc-animate/1";
  dir.write("manifest.json", dump_json(doc));
  dir.commit();

  if (opt.json) {
    out << dump_json(doc["results"]);
    return;
  }
  out << fmt::format("{}: {} triangles, {} vertices, {} part(s); frames {}..{} -> {}/frame_*.{} in {:.0f} ms (animate {:.0f} ms)\n",
                     scene.name(), rest.triangle_count(), rest.vertex_count(), scene.part_count(), range.first, range.last,
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

void cmd_scenes(const ScenesOptions& opt, std::ostream& out) {
  std::vector<std::string> names = opt.names;
  if (names.empty())
    for (const auto& b : builtin_scenes()) names.push_back(b.name);
  for (const auto& n : names)
    if (!is_builtin_scene(n)) throw InputError("", "", n, "no such built-in scene");

  nlohmann::json list = nlohmann::json::array();
  if (!opt.json)
    out << fmt::format("{:<22} {:>10} {:>10} {:>8} {:>7} {:>10}  {}\n", "scene", "triangles", "vertices", "animated",
                       "static", "frames", "description");
  for (const auto& n : names) {
    std::string desc;
    for (const auto& b : builtin_scenes())
      if (b.name == n) desc = b.description;
    nlohmann::json row{{"name", n}, {"description", desc}};
    try {
      const Scene s = make_builtin_scene(n, opt.scene_options);
      std::size_t animated = 0;
      for (std::size_t k = 0; k < s.part_count(); ++k) animated += !s.is_static(k);
      row["available"] = true;
      row["triangles"] = s.rest().triangle_count();
      row["vertices"] = s.rest().vertex_count();
      row["animated_parts"] = animated;
      row["static_parts"] = s.part_count() - animated;
      row["frames"] = {s.frames().first, s.frames().last};
      row["source_frames"] = s.frame_count();  // 0 = unbounded
      if (!opt.json)
        out << fmt::format("{:<22} {:>10} {:>10} {:>8} {:>7} {:>10}  {}\n", n, s.rest().triangle_count(),
                           s.rest().vertex_count(), animated, s.part_count() - animated,
                           fmt::format("{}:{}", s.frames().first, s.frames().last), desc);
    } catch (const InputError& e) {
      row["available"] = false;
      row["reason"] = e.what();
      if (!opt.json) out << fmt::format("{:<22} unavailable: {}\n", n, e.what());
    }
    list.push_back(std::move(row));
  }
  if (opt.json) out << dump_json({{"schema", "ptc-scenes/1"}, {"scenes", list}});
}

}  // namespace ptc
