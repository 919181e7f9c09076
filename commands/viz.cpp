// `ptc viz`: partitions, heatmaps and panels rendered with VTK beside the tracer's images, and
// the ParaView export. Inputs are checked before a display is opened (an error never waits for
// an Xvfb); the export needs no display at all.
#include "commands/viz.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/loop/accel.h"
#include "analysis/metrics/cluster_frame.h"
#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "bvh/cluster_scene.h"
#include "commands/args.h"
#include "commands/child_process.h"
#include "commands/cluster_files.h"
#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "commands/scene_args.h"
#include "render/view.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"
#include "viz/colour_scale.h"
#include "viz/display.h"
#include "viz/legend.h"
#include "viz/partition_colours.h"
#include "viz/png.h"
#include "viz/renderer.h"
#include "viz/vtp.h"
#include "toolkit/core/strings.h"
#include "toolkit/anim/frame_sequence.h"

namespace ptc {

std::optional<VizKind> parse_viz_kind(std::string_view s) {
  if (s == "partition") return VizKind::Partition;
  if (s == "heatmap") return VizKind::Heatmap;
  if (s == "panel") return VizKind::Panel;
  if (s == "export") return VizKind::Export;
  return std::nullopt;
}

std::string_view to_string(VizKind k) {
  switch (k) {
    case VizKind::Partition: return "partition";
    case VizKind::Heatmap: return "heatmap";
    case VizKind::Panel: return "panel";
    case VizKind::Export: return "export";
  }
  return "?";
}

namespace {

constexpr int kGap = 4;

bool is_pixel_metric(const std::string& m) {
  return std::find_if(std::begin(kPixelMetrics), std::end(kPixelMetrics), [&](const char* p) { return m == p; }) !=
         std::end(kPixelMetrics);
}

// Runs ffmpeg on the numbered PNGs; returns "" or why there is no MP4 (Interrupted on Ctrl-C).
std::string make_mp4(const std::filesystem::path& dir, const std::string& base, std::int64_t first, const std::string& mp4) {
  const std::string ffmpeg = resolve_program("ffmpeg");
  if (ffmpeg.empty()) return "ffmpeg is not installed (Debian package ffmpeg): no MP4, the numbered PNGs are the series";
  const ChildResult r = run_child({ffmpeg, "-nostdin", "-y", "-loglevel", "error", "-framerate", "24", "-start_number",
                                   std::to_string(first), "-i", base + "_%04d.png", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                                   "-c:v", "libx264", "-pix_fmt", "yuv420p", mp4},
                                  dir, dir / ".ffmpeg.log");
  if (!r.started) return "ffmpeg could not be started: no MP4";
  if (r.code != 0) {
    std::error_code ec;
    std::filesystem::remove(dir / mp4, ec);
    return "ffmpeg failed (exit " + std::to_string(r.code) + "): no MP4";
  }
  return "";
}

nlohmann::json scale_json(const viz::ColourScale& s, const viz::OutOfRange& o) {
  return {{"metric", s.title}, {"colormap", s.colormap}, {"min", s.min}, {"max", s.max}, {"range_from", s.from},
          {"below_range", o.below}, {"above_range", o.above}, {"nan", o.nan}};
}

std::string range_note(const viz::OutOfRange& o, const char* what) {
  std::string n;
  if (o.below) n += fmt::format("{} {} below the range drawn at the bottom colour", o.below, what);
  if (o.above) n += fmt::format("{}{} {} above the range drawn at the top colour", n.empty() ? "" : "; ", o.above, what);
  if (o.nan) n += fmt::format("{}{} {} not a number (grey)", n.empty() ? "" : "; ", o.nan, what);
  return n;
}

}  // namespace

void cmd_viz(const VizCommandOptions& opt, std::ostream& out) {
  const VizKind kind = opt.kind;
  // ---- usage, before anything is read
  if (opt.out_dir.empty() && !opt.interactive) throw UsageError("--out", "an output directory is required");
  check_image_size(opt.width, opt.height);
  if (opt.width > 8192 || opt.height > 8192) throw UsageError(opt.width > 8192 ? "--width" : "--height", "at most 8192 pixels for VTK pictures");
  if (opt.frame && opt.frames) throw UsageError("--frame/--frames", "give one frame or one range, not both");
  if (kind == VizKind::Panel && 3 * std::max(opt.width, viz::kMinLegendWidth) + 2 * kGap > 8192)
    throw UsageError("--width", fmt::format("a panel is three pictures side by side: at most {} pixels each", (8192 - 2 * kGap) / 3));
  std::string metric = opt.metric;
  if (kind == VizKind::Panel && metric.empty()) metric = "nodes_visited";
  if (kind == VizKind::Heatmap && metric.empty())
    throw UsageError("--metric", fmt::format("a heatmap needs --metric NAME ({}, {}, {})", kPixelMetrics[0], kPixelMetrics[1],
                                             cluster_metric_names()));
  if ((kind == VizKind::Partition || kind == VizKind::Export) && !metric.empty())
    throw UsageError("--metric", fmt::format("{} draws no metric (heatmap and panel do)", to_string(kind)));
  const bool pixel_metric = is_pixel_metric(metric);
  // Ratios (diverging about 1) are never negative: their colour range stops at 0.
  const std::optional<ClusterMetricInfo> cmetric = metric.empty() || pixel_metric ? std::nullopt : find_cluster_metric(metric);
  const double ratio_floor = cmetric && cmetric->diverging && cmetric->centre == 1.0 ? 0.0 : -std::numeric_limits<double>::infinity();
  if (!metric.empty() && !pixel_metric && !cmetric)
    throw UsageError("--metric", fmt::format("'{}' is not a metric ({}, {}, {})", metric, kPixelMetrics[0], kPixelMetrics[1],
                                             cluster_metric_names()));
  if (opt.shadows && !(kind == VizKind::Panel || (kind == VizKind::Heatmap && pixel_metric)))  // (it would do nothing)
    throw UsageError("--shadows", fmt::format("needs a traced picture: panel, or a heatmap of {} or {} (viz {}{} traces "
                                              "no rays)",
                                              kPixelMetrics[0], kPixelMetrics[1], to_string(kind),
                                              kind == VizKind::Heatmap ? " of a per-cluster metric" : ""));
  // Picture flags that would change nothing in this kind's picture (the export's are refused by the CLI).
  if (kind != VizKind::Export) {
    if (!opt.borders && kind != VizKind::Partition && kind != VizKind::Panel)
      throw UsageError("--no-borders", "only viz partition and panel draw cluster borders (a heatmap draws none)");
    if (!opt.lighting && kind == VizKind::Heatmap && pixel_metric)
      throw UsageError("--flat", fmt::format("a heatmap of {} is drawn in flat colours already (only meshes are lit)", metric));
    if (opt.light && kind == VizKind::Heatmap && pixel_metric && !opt.shadows)
      throw UsageError("--light", fmt::format("a heatmap of {} traces no shadow rays without --shadows (the light would change nothing)", metric));
    if (opt.light && (kind == VizKind::Partition || (kind == VizKind::Heatmap && !pixel_metric)))
      throw UsageError("--light", fmt::format("viz {} draws the mesh with a headlight (--light is for viz panel's shaded "
                                              "picture and for --shadows)",
                                              kind == VizKind::Heatmap ? "heatmap of a per-cluster metric" : to_string(kind)));
  }
  if (opt.clusters.empty() && !(kind == VizKind::Heatmap && pixel_metric))
    throw UsageError("--clusters", fmt::format("viz {}{} needs --clusters DIR (a `ptc cluster` output)", to_string(kind),
                                               kind == VizKind::Heatmap ? " of a per-cluster metric" : ""));
  if (opt.range && metric.empty()) throw UsageError("--range", "only heatmaps and panels have a colour range");
  // A flag (not_full) is drawn on 0 .. 1 unless --range says otherwise (a frame whose clusters
  // are all of one kind would otherwise get a one-value range).
  const bool flag = cmetric && cmetric->flag;
  const std::optional<std::pair<double, double>> fixed =
      opt.range ? std::optional(parse_value_range(*opt.range, "--range"))
      : flag    ? std::optional(std::pair<double, double>(0.0, 1.0))
                : std::nullopt;
  if (opt.range && ratio_floor == 0.0 && fixed->first < 0.0)
    throw UsageError("--range", fmt::format("{} is a ratio, never below 0: give MIN >= 0", metric));
  if (opt.interactive && (kind == VizKind::Panel || kind == VizKind::Export || pixel_metric))
    throw UsageError("--interactive", "a window shows the mesh: viz partition or a heatmap of a per-cluster metric");
  if (opt.interactive && opt.frames) throw UsageError("--interactive", "a window shows one frame (--frame F)");
  if (opt.light && !opt.light->allFinite()) throw UsageError("--light", "not a finite vector");
  std::optional<FrameRange> asked;
  if (opt.frame) {
    const std::int64_t f = parse_frame(*opt.frame, "--frame");
    asked = FrameRange{f, f};
  }
  if (opt.frames) asked = parse_frame_range(*opt.frames, "--frames");
  const bool series = opt.frames.has_value();

  if (!opt.out_dir.empty()) {
    refuse_overwriting_input(opt.out_dir, opt.input);
    if (!opt.clusters.empty()) refuse_overwriting_input(opt.out_dir, opt.clusters);
  }
  RunManifest manifest("viz", opt.argv, "ptc-viz/1");
  const std::string arg = opt.input.string();
  // Positions beyond the single-precision tracer's range (its BVHs, the metrics' cluster BVH):
  // an input error naming the file and, where there is one, the frame.
  const auto naming_input = [&](const std::string& element, auto&& make) {
    try {
      return make();
    } catch (const bvh::FrameRangeError& e) {
      throw InputError(arg, "", element, e.what());
    }
  };
  Scene scene = open_scene_recorded(opt.input, opt.scene_options, manifest);
  const bool deformed = opt.deform && *opt.deform != "none";  // (none: as without the flag)
  manifest.set_parameter("motion", apply_stand_in(scene, opt.deform.value_or("none"), arg));
  const FrameRange range = asked ? *asked : FrameRange{scene.frames().first, scene.frames().first};
  check_frames(scene, range, arg, opt.frames ? "--frames" : "--frame", opt.extend_frames || deformed);
  const std::int64_t reference_frame = scene.frames().first;

  Mesh mesh = scene.rest();
  scene.positions(double(range.first), mesh.positions(), true);
  const Box3 first_bounds = mesh.referenced_bounds();  // (the camera's: unreferenced vertices are not framed)
  // The export writes data, not pictures: no camera (a mesh no camera can frame still exports).
  const bvh::PinholeCamera cam = kind == VizKind::Export
                                     ? bvh::PinholeCamera{}
                                     : make_camera(camera_for(opt.camera, scene), first_bounds, opt.width, opt.height, arg);

  const bool use_clusters = !opt.clusters.empty();
  Clustering clusters;
  ClusteringInfo ci;
  if (use_clusters) {
    clusters = read_clusters_recorded(opt.clusters, scene.rest(), manifest);
    ci = clustering_info_recorded(opt.clusters, manifest);  // Acc's parameters come from it
  }
  const std::vector<std::uint32_t> cluster_of = use_clusters ? clusters.cluster_of_triangle() : std::vector<std::uint32_t>();

  // Partition colours: fixed by the connectivity, so one colouring serves every frame.
  std::vector<std::uint32_t> colour;
  std::uint32_t colours_used = 0;
  std::vector<std::array<std::uint32_t, 2>> borders;
  // A clustering made by coincident corners (cluster.h): the rest pose's adjacency triangles,
  // once, for the partition and the metrics; empty for one made by edges.
  std::vector<Tri> adjacency;
  // (the scene's mesh may be a soup of the one clustered, e.g. under the explode deformer: the
  // clustering is read as the experiments read it, adjacency_on)
  if (use_clusters) ci.cfg.adjacency = adjacency_on(scene.rest(), ci.cfg.adjacency);
  if (use_clusters && ci.cfg.adjacency == ClusterAdjacency::Positions)
    adjacency = adjacency_triangles(scene.rest(), ClusterAdjacency::Positions);
  if (use_clusters) {
    // A soup's clusters meet at sides whose corners coincide at rest: the colouring and the
    // borders follow that adjacency (border corners are the first vertex at each rest position).
    const Mesh& rest = scene.rest();
    std::optional<Mesh> welded;
    if (!adjacency.empty())
      welded.emplace(adjacency, std::vector<Vec3>(rest.positions().begin(), rest.positions().end()));
    viz::PartitionTopology topo = viz::partition_topology(welded ? *welded : rest, clusters);
    colour = viz::dsatur_colouring(topo.graph);
    for (std::uint32_t c : colour) colours_used = std::max(colours_used, c + 1);
    if (opt.borders) borders = std::move(topo.borders);
  }

  const bool needs_trace = kind == VizKind::Panel || pixel_metric;
  const bool needs_metrics = kind == VizKind::Export || cmetric.has_value();
  RenderConfig rc;
  rc.width = opt.width, rc.height = opt.height, rc.shadows = opt.shadows, rc.threads = opt.threads;
  if (needs_trace) check_eye_reach(cam, opt.camera, scene, arg);
  const LightChoice light = needs_trace ? light_for(opt.light, scene, cam, first_bounds, arg) : LightChoice{};
  rc.light = light.position;
  rc.light_intensity = light.intensity;
  std::unique_ptr<loop::SceneAccel> accel;
  if (needs_trace) {
    bvh::SceneTracerConfig tcfg;
    tcfg.clusters = use_clusters ? &clusters : nullptr;
    // At the rest pose, as ptc trace, ptc bench and the experiments: a frame's picture does not
    // depend on the range it is drawn in.
    tcfg.origin = scene.rest().referenced_bounds().center();
    accel = naming_input("", [&] { return std::make_unique<loop::SceneAccel>(scene.rest(), bvh::PartLayout::of(scene), tcfg); });
  }

  // The reference frame's rows (drift "since frame 0": the scene's first frame) and positions.
  std::vector<ClusterRow> ref_rows;
  std::vector<Vec3> ref_positions;
  if (needs_metrics) {
    Mesh ref = scene.rest();
    scene.positions(double(reference_frame), ref.positions(), true);
    ref_positions.assign(ref.positions().begin(), ref.positions().end());
    ref_rows = naming_input("", [&] { return cluster_frame_metrics(ref, clusters, ci.cfg, {}, {}, adjacency).rows; });
  }

  // The `_prev` metrics of the first frame shown compare with the frame before it (none before
  // the reference frame: the frame itself).
  std::vector<ClusterRow> first_prev;
  if (needs_metrics && range.first > reference_frame) {
    Mesh pm = scene.rest();
    scene.positions(double(range.first - 1), pm.positions(), true);
    first_prev = cluster_rows(pm, clusters, ci.cfg, std::nullopt, adjacency);
  }
  // One frame's metric values: per cluster (cluster metrics) or per pixel (the tracer's counters).
  std::vector<ClusterRow> prev_rows = first_prev;
  struct FrameData {
    std::optional<ClusterFrameMetrics> metrics;
    std::optional<Render> render;
    std::vector<double> values;
  };
  std::unique_ptr<bvh::ClusterScene> sah_tree;  // made at the first frame that needs metrics
  // `known`: the frame's per-cluster values kept from the range pass (nothing to recompute).
  auto frame_data = [&](std::int64_t f, bool for_range_only, const std::vector<double>* known) {
    FrameData d;
    scene.positions(double(f), mesh.positions(), true);
    if (needs_trace && (pixel_metric || !for_range_only)) {
      accel->update(mesh.positions());
      d.render = render_view(target_of(*accel), mesh, cam, rc);
      if (pixel_metric) {
        const auto& counts = metric == "nodes_visited" ? d.render->primary.nodes_visited : d.render->primary.triangles_tested;
        d.values.assign(counts.begin(), counts.end());
      }
    }
    if (known) {
      d.values = *known;
    } else if (needs_metrics) {
      // sah_share on the drift study's cluster BVH: set up at the rest pose, updated to the frame.
      d.metrics = naming_input(fmt::format("frame {}", f), [&] {
        if (!sah_tree) sah_tree = cluster_bvh_at_rest(scene.rest(), clusters);
        sah_tree->update(mesh.positions());
        return cluster_frame_metrics(mesh, clusters, ci.cfg, ref_rows, prev_rows, adjacency, sah_tree.get());
      });
      prev_rows = d.metrics->rows;
      if (cmetric) d.values = d.metrics->of(metric);
    }
    return d;
  };

  // The output directory before any long work or a display (a foreign directory is refused now).
  std::optional<OutputDir> dir;
  if (!opt.out_dir.empty()) dir.emplace(opt.out_dir);

  // A fixed colour range over a series: the values of every frame first (unless --range).
  // A per-cluster metric's values are kept for the rendering pass when they fit in 256 MB
  // (clusters x frames doubles); pixel counters are traced again.
  std::optional<viz::ColourScale> series_scale;
  std::vector<std::vector<double>> kept;
  if (!metric.empty() && series && !fixed && range.count() > 1) {
    const bool keep = cmetric && double(clusters.cluster_count()) * double(range.count()) <= 32.0 * (1 << 20);
    std::vector<double> lohi;
    for (std::int64_t f = range.first; f <= range.last; ++f) {
      throw_if_cancelled();
      FrameData d = frame_data(f, true, nullptr);
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (double v : d.values)
        if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
      if (lo <= hi) lohi.push_back(lo), lohi.push_back(hi);
      if (keep) kept.push_back(std::move(d.values));
    }
    series_scale = viz::make_scale(metric, lohi, cmetric && cmetric->diverging, cmetric ? cmetric->centre : 0, std::nullopt,
                                   pixel_metric, ratio_floor);
    series_scale->from = fmt::format("values of frames {}:{}", range.first, range.last);
    prev_rows = first_prev;
  }

  // ---- the display (not for the export) and the pictures
  std::optional<viz::Display> display;
  std::unique_ptr<viz::Renderer> renderer;
  if (kind != VizKind::Export) {
    viz::Display::Options dopt;
    dopt.interactive = opt.interactive;
    dopt.force_xvfb = opt.force_xvfb;
    display.emplace(viz::Display::acquire(dopt));
    renderer = std::make_unique<viz::Renderer>(*display);
    manifest.set_parameter("display", display->describe());
  }

  nlohmann::json images = nlohmann::json::object();
  std::vector<std::pair<double, std::string>> pvd;
  std::vector<std::string> written;
  // The title's name: the file's or folder's name, a glob's whole pattern ("*.off" alone says not
  // which folder's frames).
  const std::string scene_name = opt.input.filename().string().empty() || is_glob_pattern(arg)
                                     ? arg
                                     : opt.input.filename().string();
  const std::string base = kind == VizKind::Partition ? "partition"
                           : kind == VizKind::Heatmap ? "heatmap_" + metric
                           : kind == VizKind::Panel   ? "panel"
                                                      : "clusters";
  auto put_png = [&](const std::string& name, const RgbImage& img, nlohmann::json info) {
    if (!dir) return;
    viz::write_png(dir->path(name), img);
    manifest.add_output(name);
    images[name] = std::move(info);
    written.push_back(name);
  };
  viz::MeshStyle partition_style;
  if (use_clusters) {
    partition_style.triangle_colours.resize(mesh.triangle_count());
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
      partition_style.triangle_colours[t] = viz::palette_colour(colour[cluster_of[t]]);
    partition_style.lines = borders;
    partition_style.lighting = opt.lighting;
  }
  Stopwatch sw;
  double render_ms = 0;
  for (std::int64_t f = range.first; f <= range.last; ++f) {
    throw_if_cancelled();
    FrameData d = frame_data(f, false, kept.empty() ? nullptr : &kept[static_cast<std::size_t>(f - range.first)]);
    const std::string suffix = series ? fmt::format("_{:04d}", f) : "";
    if (kind == VizKind::Export) {
      viz::VtpArrays a;
      std::vector<std::int32_t> cid(mesh.triangle_count()), cix(mesh.triangle_count());
      for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
        cid[t] = static_cast<std::int32_t>(cluster_of[t]), cix[t] = static_cast<std::int32_t>(colour[cluster_of[t]]);
      a.cell_int = {{"cluster_id", std::move(cid)}, {"colour_index", std::move(cix)}};
      for (std::size_t i = 0; i < cluster_metric_infos().size(); ++i) {
        std::vector<double> v(mesh.triangle_count());
        for (std::size_t t = 0; t < v.size(); ++t) v[t] = d.metrics->values[i][cluster_of[t]];
        a.cell.emplace_back(std::string(cluster_metric_infos()[i].name), std::move(v));
      }
      std::vector<Vec3> disp(mesh.vertex_count());
      for (std::size_t v = 0; v < disp.size(); ++v) disp[v] = mesh.position(v) - ref_positions[v];
      a.point = {{"displacement", std::move(disp)}};
      const std::string name = fmt::format("clusters_{:04d}.vtp", f);
      viz::write_vtp(dir->path(name), mesh, a);
      manifest.add_output(name);
      written.push_back(name);
      pvd.emplace_back(double(f), name);
      continue;
    }
    Stopwatch rt;
    // The pictures of the frame.
    auto partition_picture = [&] { return renderer->mesh(mesh, partition_style, cam, opt.width, opt.height); };
    viz::ColourScale scale;
    viz::OutOfRange oor;
    RgbImage heat;
    if (!metric.empty()) {
      scale = series_scale ? *series_scale
                           : viz::make_scale(metric, d.values, cmetric && cmetric->diverging, cmetric ? cmetric->centre : 0,
                                             fixed, pixel_metric, ratio_floor);
      if (!series_scale && !fixed) scale.from = fmt::format("values of frame {}", f);
      if (!opt.range && flag) scale.from = "a flag: 0 full, 1 not full";
      scale.integer = pixel_metric || (cmetric && cmetric->integer);
      oor = viz::out_of_range(scale, d.values);
      if (pixel_metric) {
        heat = RgbImage(opt.width, opt.height);
        for (std::size_t i = 0; i < d.values.size(); ++i) heat.set(i, viz::colour_of(scale, d.values[i]));
      } else {
        viz::MeshStyle hs;
        hs.lighting = opt.lighting;
        hs.triangle_colours.resize(mesh.triangle_count());
        for (std::size_t t = 0; t < mesh.triangle_count(); ++t) hs.triangle_colours[t] = viz::colour_of(scale, d.values[cluster_of[t]]);
        if (opt.interactive) {
          renderer->interact(mesh, hs, cam, opt.width, opt.height, fmt::format("ptc viz heatmap {} - {}", metric, scene_name));
          throw_if_cancelled();
        }
        heat = renderer->mesh(mesh, hs, cam, opt.width, opt.height);
      }
      const std::string note = range_note(oor, pixel_metric ? "pixels" : "clusters");
      heat = viz::vstack(std::vector<RgbImage>{heat, viz::legend_strip(*renderer, scale, opt.width, note)}, 0, viz::kBackground);
    }
    const nlohmann::json frame_info = {{"frame", f}};
    if (kind == VizKind::Partition) {
      if (opt.interactive) {
        renderer->interact(mesh, partition_style, cam, opt.width, opt.height, fmt::format("ptc viz partition - {}", scene_name));
        throw_if_cancelled();
      }
      put_png(base + suffix + ".png", partition_picture(),
              {{"frame", f}, {"clusters", clusters.cluster_count()}, {"colours", colours_used}, {"borders", opt.borders}});
    } else if (kind == VizKind::Heatmap) {
      put_png(base + suffix + ".png", heat, {{"frame", f}, {"scale", scale_json(scale, oor)}});
    } else {  // panel: partition | shaded | heatmap, a title line above
      const RgbImage part = partition_picture();
      const RgbImage shaded = shaded_image(*d.render);
      const viz::LegendLayout ll = viz::legend_layout(opt.width);
      auto caption = [&](const std::string& text) {
        const std::vector<viz::TextItem> items{{text, ll.bar_x0, 11, 14, -1, {235, 235, 235}, true}};
        return renderer->text(ll.width, ll.height, items);
      };
      const RgbImage left = viz::vstack(std::vector<RgbImage>{part, caption(fmt::format("partition: {}, {}",
                                                                                           counted(clusters.cluster_count(), "cluster"),
                                                                                           counted(colours_used, "colour")))},
                                        0, viz::kBackground);
      const RgbImage middle = viz::vstack(
          std::vector<RgbImage>{shaded, caption(std::string("shaded: ptc's tracer, cluster BVH") + (opt.shadows ? ", shadows" : ""))}, 0,
          viz::kBackground);
      const RgbImage row = viz::hstack(std::vector<RgbImage>{left, middle, heat}, kGap, viz::kBackground);
      // The title's parts on as many lines as the row's width needs (a 128-pixel panel cut it
      // off): a bold character takes about 0.62 of the font size.
      const std::vector<std::string> parts = {scene_name, fmt::format("frame {}", f), ci.title,
                                              fmt::format("{}, {}", counted(mesh.triangle_count(), "triangle"),
                                                          counted(clusters.cluster_count(), "cluster"))};
      constexpr int kTitleSize = 15, kLine = 20;
      const auto fits = [&](const std::string& t) { return 0.62 * kTitleSize * double(t.size()) <= double(row.width - 16); };
      std::vector<std::string> lines;
      for (const std::string& piece : parts) {
        if (!lines.empty() && fits(lines.back() + "  |  " + piece)) lines.back() += "  |  " + piece;
        else lines.push_back(piece);
      }
      std::vector<viz::TextItem> title;
      for (std::size_t i = 0; i < lines.size(); ++i)
        title.push_back({lines[i], 8, 14 + kLine * int(i), kTitleSize, -1, {245, 245, 245}, true});
      const RgbImage top = renderer->text(row.width, 28 + kLine * int(lines.size() - 1), title);
      put_png(base + suffix + ".png", viz::vstack(std::vector<RgbImage>{top, row}, 0, viz::kBackground),
              {{"frame", f}, {"left", "partition"}, {"middle", "shaded"}, {"right", scale_json(scale, oor)}});
    }
    render_ms += rt.ms();
  }
  std::string mp4_note;
  if (kind == VizKind::Export && dir) {
    dir->write("clusters.pvd", viz::pvd_xml(pvd));
    manifest.add_output("clusters.pvd");
    written.push_back("clusters.pvd");
  } else if (series && dir && range.count() > 1) {
    mp4_note = make_mp4(dir->path(""), base, range.first, base + ".mp4");
    if (mp4_note.empty()) {
      manifest.add_output(base + ".mp4");
      written.push_back(base + ".mp4");
    }
  }

  manifest.add_timing_ms("render", render_ms);
  manifest.add_timing_ms("frames", sw.ms());
  manifest.set_parameter("kind", std::string(to_string(kind)));
  manifest.set_parameter("scene", arg);
  manifest.set_parameter("frames", {range.first, range.last});
  manifest.set_parameter("reference_frame", reference_frame);
  if (!metric.empty()) manifest.set_parameter("metric", metric);
  if (opt.range) manifest.set_parameter("range", {fixed->first, fixed->second});
  if (use_clusters) {
    manifest.set_parameter("clusters", opt.clusters.string());
    manifest.set_parameter("clustering", ci.title);
    manifest.set_parameter("metric_parameters_from", ci.from);
  }
  if (kind != VizKind::Export) {  // (the export draws nothing)
    manifest.set_parameter("width", opt.width);
    manifest.set_parameter("height", opt.height);
    manifest.set_parameter("borders", opt.borders);
    manifest.set_parameter("lighting", opt.lighting ? "headlight, ambient 0.2, diffuse 0.8" : "none: flat colours");
    manifest.set_parameter("camera", {{"eye", vec_json(cam.eye)}, {"forward", vec_json(cam.forward)}, {"right", vec_json(cam.right)},
                                      {"up", vec_json(cam.up)}, {"fov_y_deg", cam.fov_y_deg}});
  }
  if (needs_trace) manifest.set_parameter("light", light_json(light));
  if (use_clusters) {
    manifest.set_result("clusters", clusters.cluster_count());
    manifest.set_result("colours", colours_used);
  }
  manifest.set_result("images", images);
  if (!mp4_note.empty()) manifest.set_result("mp4", mp4_note);
  if (dir) (void)commit_with_manifest(*dir, manifest);

  if (opt.json) {
    out << dump_json({{"schema", "ptc-viz-summary/1"}, {"kind", std::string(to_string(kind))}, {"scene", arg},
                      {"frames", {range.first, range.last}}, {"clusters", use_clusters ? clusters.cluster_count() : 0},
                      {"colours", colours_used}, {"outputs", written}, {"images", images},
                      {"mp4", mp4_note.empty() ? nlohmann::json(nullptr) : nlohmann::json(mp4_note)}});
    return;
  }
  if (use_clusters)
    out << fmt::format("{}: {}, {} in {} (no two clusters that share an edge alike)\n", arg,
                       counted(mesh.triangle_count(), "triangle"), counted(clusters.cluster_count(), "cluster"),
                       counted(colours_used, "colour"));
  if (!mp4_note.empty()) std::cerr << "ptc: note: " << mp4_note << "\n";  // (as every note: on stderr)
  if (dir) {
    out << "wrote " << opt.out_dir.string() << "/";
    if (written.size() == 1) out << written[0];
    else {
      // clusters_0003.vtp for one frame, clusters_0003..0007.vtp for several
      const std::string frames = range.count() == 1 ? fmt::format("{:04d}", range.first)
                                                    : fmt::format("{:04d}..{:04d}", range.first, range.last);
      if (series && kind != VizKind::Export)
        out << fmt::format("{}_{}.png", base, frames) << (mp4_note.empty() && range.count() > 1 ? ", " + base + ".mp4" : "");
      else
        out << fmt::format("{}_{}.vtp, clusters.pvd", base, frames);
    }
    out << ", manifest.json\n";
  }
}

}  // namespace ptc
