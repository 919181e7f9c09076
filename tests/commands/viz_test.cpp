// `ptc viz` in-process, its pictures checked by their pixels against independent answers: which
// triangle every pixel sees comes from a brute-force ray cast with the command's camera (from
// its manifest), which cluster a triangle is in from triangles.csv, cluster adjacency from a
// brute force over triangle pairs, per-cluster triangle counts counted here. The .vtp files are
// read back with VTK's own reader. Every test renders on its own Xvfb (--xvfb).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "commands/viz.h"
#include "common/brute_force.h"
#include "common/temp_dir.h"
#include "common/usage_flag.h"
#include "render/camera.h"
#include "render/images.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"
#include "viz/colour_scale.h"
#include "viz/legend.h"
#include "viz/partition_colours.h"
#include "viz/png.h"
#include "viz/vtp.h"

namespace fs = std::filesystem;

namespace ptc {
namespace {

using test::slurp;
using test::spit;

const fs::path kMeshes = fs::path(PTC_TEST_DATA) / "meshes";
constexpr std::uint32_t kMiss = 0xffffffffu;

using test::usage_flag;

class Viz : public test::TempDirTest {
 protected:
  void SetUp() override {
    TempDirTest::SetUp();
    mesh_ = read_mesh(kMeshes / "mushroom.off").mesh;
    ClusterConfig cfg;
    cfg.method = ClusterMethod::Growth;
    const Clustering c = cluster_mesh(mesh_, cfg);
    // triangles.csv with cluster ids scrambled (the command must not rely on dense ids).
    std::string csv = "triangle_id,cluster_id\n";
    label_.assign(mesh_.triangle_count(), 0);
    for (std::size_t k = 0; k < c.cluster_count(); ++k)
      for (std::uint32_t t : c.triangles_of(k)) label_[t] = static_cast<std::uint32_t>(k);
    for (std::size_t t = 0; t < mesh_.triangle_count(); ++t) csv += fmt_row(t, 1000 + 7 * label_[t]);
    fs::create_directories(dir_ / "cl");
    spit(dir_ / "cl" / "triangles.csv", csv);
    clusters_ = c.cluster_count();
  }
  static std::string fmt_row(std::size_t t, std::size_t k) { return std::to_string(t) + "," + std::to_string(k) + "\n"; }

  // A scene file: the mushroom twisted over frames 0..last.
  fs::path twisted_scene(int last) const {
    const fs::path scene = dir_ / "scene.json";
    spit(scene, R"({"schema": "ptc-scene/1", "frames": [0, )" + std::to_string(last) +
                    R"(], "meshes": [{"name": "s", "file": ")" + (kMeshes / "mushroom.off").string() +
                    R"(", "deform": {"kind": "twist", "axis": "y", "amplitude": 1.0, "period": 8}}]})");
    return scene;
  }

  VizCommandOptions options(VizKind kind, const std::string& out) const {
    VizCommandOptions o;
    o.kind = kind;
    o.input = kMeshes / "mushroom.off";
    o.clusters = dir_ / "cl";
    o.width = 160, o.height = 120;
    o.force_xvfb = true;
    o.out_dir = dir_ / out;
    return o;
  }
  nlohmann::json manifest(const std::string& out) const { return nlohmann::json::parse(slurp(dir_ / out / "manifest.json")); }
  // `ptc viz heatmap --metric METRIC --flat` into `out`: its image, and the image's scale in the manifest.
  std::pair<RgbImage, nlohmann::json> unlit_heatmap(const std::string& out, const std::string& metric) const {
    VizCommandOptions o = options(VizKind::Heatmap, out);
    o.metric = metric;
    o.lighting = false;
    std::ostringstream text;
    cmd_viz(o, text);
    const std::string png = "heatmap_" + metric + ".png";
    return {viz::read_png(dir_ / out / png), manifest(out)["results"]["images"][png]["scale"]};
  }

  // The command's camera (from its manifest) and the triangle each pixel sees by brute force.
  std::vector<std::uint32_t> pixel_triangles(const nlohmann::json& m, int w, int h) const {
    const auto& c = m["parameters"]["camera"];
    auto v = [](const nlohmann::json& a) { return Vec3(a[0], a[1], a[2]); };
    bvh::PinholeCamera cam;
    cam.eye = v(c["eye"]), cam.forward = v(c["forward"]), cam.right = v(c["right"]), cam.up = v(c["up"]);
    cam.fov_y_deg = c["fov_y_deg"];
    const bvh::RayBatch rays = camera_rays(cam, w, h);
    std::vector<std::uint32_t> ids(static_cast<std::size_t>(w) * h);
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const bvh::Hit hit = bvh::test::brute_force(mesh_, Vec3::Zero(), Vec3(rays.ox[i], rays.oy[i], rays.oz[i]),
                                                  bvh::Vec3f{rays.dx[i], rays.dy[i], rays.dz[i]});
      ids[i] = hit.hit() ? hit.triangle : kMiss;
    }
    return ids;
  }
  // The cluster each pixel sees (kMiss for a miss).
  std::vector<std::uint32_t> pixel_clusters(const std::vector<std::uint32_t>& ids) const {
    std::vector<std::uint32_t> c(ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) c[i] = ids[i] == kMiss ? kMiss : label_[ids[i]];
    return c;
  }
  // Pixels whose (2r+1)^2 neighbourhood sees one triangle (or cluster).
  static bool interior(const std::vector<std::uint32_t>& ids, int w, int h, int x, int y, int r = 1) {
    if (x < r || y < r || x >= w - r || y >= h - r) return false;
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx)
        if (ids[static_cast<std::size_t>(y + dy) * w + x + dx] != ids[static_cast<std::size_t>(y) * w + x]) return false;
    return true;
  }
  // Calls visit(x, y, t) for each pixel of the command's 160 x 120 picture that sees triangle t
  // inside one cluster (its 3 x 3 neighbourhood in the same cluster); returns how many.
  template <class Visit>
  std::size_t for_each_cluster_pixel(const nlohmann::json& m, Visit visit) const {
    const auto ids = pixel_triangles(m, 160, 120);
    const auto cls = pixel_clusters(ids);
    std::size_t n = 0;
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) {
        const std::uint32_t t = ids[static_cast<std::size_t>(y) * 160 + x];
        if (!interior(cls, 160, 120, x, y) || t == kMiss) continue;
        visit(x, y, t);
        ++n;
      }
    return n;
  }
  // Cluster pairs sharing a mesh edge: every triangle side keyed by its sorted vertex pair.
  std::set<std::pair<std::uint32_t, std::uint32_t>> adjacent_clusters() const {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> sides;
    for (std::uint32_t t = 0; t < mesh_.triangle_count(); ++t)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = mesh_.triangle(t)[k], b = mesh_.triangle(t)[(k + 1) % 3];
        if (a != b) sides[{std::min(a, b), std::max(a, b)}].push_back(t);
      }
    std::set<std::pair<std::uint32_t, std::uint32_t>> adj;
    for (const auto& [e, tris] : sides)
      for (std::uint32_t s : tris)
        for (std::uint32_t t : tris)
          if (label_[s] < label_[t]) adj.insert({label_[s], label_[t]});
    return adj;
  }

  Mesh mesh_;
  std::vector<std::uint32_t> label_;
  std::size_t clusters_ = 0;
};

// Nearest palette colour by chromaticity (a lit pixel is a multiple of its colour).
int nearest_palette(Rgb8 p) {
  const double sp = p[0] + p[1] + p[2] + 1e-9;
  int best = -1;
  double bd = 1e9;
  const auto pal = viz::qualitative_palette();
  for (std::size_t i = 0; i < pal.size(); ++i) {
    const double sc = pal[i][0] + pal[i][1] + pal[i][2];
    double d = 0;
    for (int k = 0; k < 3; ++k) d += std::abs(p[k] / sp - pal[i][k] / sc);
    if (d < bd) bd = d, best = static_cast<int>(i);
  }
  return best;
}

TEST_F(Viz, PartitionNeverGivesNeighboursOneColour) {
  for (bool flat : {true, false}) {
    VizCommandOptions o = options(VizKind::Partition, flat ? "flat" : "lit");
    o.lighting = !flat;
    o.borders = !flat;
    std::ostringstream out;
    cmd_viz(o, out);
    const std::string name = flat ? "flat" : "lit";
    const RgbImage img = viz::read_png(dir_ / name / "partition.png");
    ASSERT_EQ(img.width, 160);
    ASSERT_EQ(img.height, 120);
    const nlohmann::json m = manifest(name);
    EXPECT_EQ(m["results"]["clusters"], clusters_);
    const int colours = m["results"]["colours"];
    EXPECT_GE(colours, 3);
    EXPECT_LE(colours, 12);
    const auto ids = pixel_triangles(m, img.width, img.height);
    const auto cls = pixel_clusters(ids);
    // Every interior pixel of a cluster shows one colour (exactly a palette colour when flat; the
    // palette colour of its hue when lit, away from the border lines).
    std::map<std::uint32_t, std::set<int>> seen;  // cluster -> palette indices seen
    std::size_t checked = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        if (!interior(cls, img.width, img.height, x, y, flat ? 1 : 2)) continue;
        const std::uint32_t t = ids[static_cast<std::size_t>(y) * img.width + x];
        if (t == kMiss) {
          EXPECT_EQ(img.at(x, y), viz::kBackground);
          continue;
        }
        const Rgb8 p = img.at(x, y);
        int idx = nearest_palette(p);
        if (flat) {
          const auto pal = viz::qualitative_palette();
          ASSERT_GE(idx, 0);
          EXPECT_EQ(p, pal[static_cast<std::size_t>(idx)]) << "pixel (" << x << ", " << y << ") is not a palette colour";
        }
        seen[label_[t]].insert(idx);
        ++checked;
      }
    EXPECT_GT(checked, 600u) << name;
    std::set<int> used;
    for (const auto& [k, s] : seen) {
      EXPECT_EQ(s.size(), 1u) << name << ": cluster " << k << " shows " << s.size() << " colours";
      used.insert(*s.begin());
    }
    EXPECT_GT(seen.size(), clusters_ / 8) << name << ": many clusters are visible";
    EXPECT_LE(used.size(), static_cast<std::size_t>(colours));
    EXPECT_GE(used.size(), 3u);
    std::size_t pairs = 0;
    for (const auto& [a, b] : adjacent_clusters()) {
      if (!seen.count(a) || !seen.count(b)) continue;
      EXPECT_NE(*seen[a].begin(), *seen[b].begin()) << name << ": neighbours " << a << " and " << b << " share a colour";
      ++pairs;
    }
    EXPECT_GT(pairs, 20u);
    if (!flat) {  // the border lines darken pixels on cluster borders, and only there
      std::size_t dark_on_border = 0;
      for (int y = 2; y + 2 < img.height; ++y)
        for (int x = 2; x + 2 < img.width; ++x) {
          const Rgb8 p = img.at(x, y);
          if (p != Rgb8{0, 0, 0}) continue;  // the lines' colour (unlit); shaded surface keeps >= 0.2 of its colour
          const std::uint32_t t = ids[static_cast<std::size_t>(y) * img.width + x];
          if (t == kMiss) continue;
          bool border = false;
          for (int dy = -2; dy <= 2; ++dy)  // a line touches pixels near the edge
            for (int dx = -2; dx <= 2; ++dx) {
              const std::uint32_t u = ids[static_cast<std::size_t>(y + dy) * img.width + x + dx];
              border = border || u == kMiss || label_[u] != label_[t];
            }
          dark_on_border += border;
          EXPECT_TRUE(border) << "dark pixel (" << x << ", " << y << ") inside cluster " << label_[t];
        }
      EXPECT_GT(dark_on_border, 50u);
    }
  }
}

TEST_F(Viz, ClusterHeatmapColoursEveryClusterByItsValue) {
  // triangles per cluster: counted here from the clustering; the extremes get the ends of viridis.
  std::map<std::uint32_t, double> count;
  for (std::uint32_t k : label_) count[k] += 1;
  double lo = 1e9, hi = -1e9;
  for (const auto& [k, n] : count) lo = std::min(lo, n), hi = std::max(hi, n);
  ASSERT_LT(lo, hi);
  for (const bool fixed : {false, true}) {
    VizCommandOptions o = options(VizKind::Heatmap, fixed ? "fixed" : "auto");
    o.metric = "triangles";
    o.lighting = false;
    if (fixed) o.range = "0:20";
    std::ostringstream out;
    cmd_viz(o, out);
    const std::string name = fixed ? "fixed" : "auto";
    const RgbImage img = viz::read_png(dir_ / name / "heatmap_triangles.png");
    const viz::LegendLayout ll = viz::legend_layout(160);
    ASSERT_EQ(img.width, ll.width) << "a legend at least kMinLegendWidth wide";
    // (the legend in the same picture, taller by 14 pixels a line where its note wraps)
    ASSERT_GE(img.height, 120 + ll.height);
    ASSERT_EQ((img.height - 120 - ll.height) % 14, 0) << img.height;
    const nlohmann::json m = manifest(name);
    const auto& sc = m["results"]["images"]["heatmap_triangles.png"]["scale"];
    const double mn = fixed ? 0.0 : lo, mx = fixed ? 20.0 : hi;
    EXPECT_EQ(sc["min"].get<double>(), mn);
    EXPECT_EQ(sc["max"].get<double>(), mx);
    EXPECT_EQ(sc["range_from"], fixed ? "--range" : "values of frame 0");
    std::set<double> values;
    const std::size_t checked = for_each_cluster_pixel(m, [&](int x, int y, std::uint32_t t) {
      const double v = count[label_[t]];
      EXPECT_EQ(img.at(x, y), viridis((v - mn) / (mx - mn))) << "pixel (" << x << ", " << y << ")";
      values.insert(v);
    });
    EXPECT_GT(checked, 600u);
    EXPECT_GE(values.size(), 5u) << "clusters of several sizes are visible";
    // The legend's bar is the map from min (left) to max (right).
    EXPECT_EQ(img.at(ll.bar_x0, 120 + (ll.bar_y0 + ll.bar_y1) / 2), viridis(0.5 / (ll.bar_x1 - ll.bar_x0)));
    EXPECT_EQ(img.at(ll.bar_x1 - 1, 120 + (ll.bar_y0 + ll.bar_y1) / 2), viridis(1.0 - 0.5 / (ll.bar_x1 - ll.bar_x0)));
  }
}

// not_full (meshoptimizer's flag: fewer vertices than MaxCount) is drawn on 0 .. 1 without
// --range (a frame of all-full or all-not-full clusters had a one-value range), said so in the
// legend, and not recorded as a --range; every cluster pixel is one end of the map.
TEST_F(Viz, NotFullIsAFlagFromZeroToOne) {
  const auto [img, sc] = unlit_heatmap("nf", "not_full");
  const nlohmann::json m = manifest("nf");
  EXPECT_EQ(sc["min"].get<double>(), 0.0);
  EXPECT_EQ(sc["max"].get<double>(), 1.0);
  EXPECT_EQ(sc["range_from"], "a flag: 0 full, 1 not full");
  EXPECT_FALSE(m["parameters"].contains("range"));
  const std::size_t checked = for_each_cluster_pixel(m, [&](int x, int y, std::uint32_t) {
    EXPECT_TRUE(img.at(x, y) == viridis(0.0) || img.at(x, y) == viridis(1.0)) << "pixel (" << x << ", " << y << ")";
  });
  EXPECT_GT(checked, 600u);
}

TEST_F(Viz, DivergingMetricsAreCentred) {
  // box_area_ratio: 1 at the reference frame itself, the centre colour everywhere
  const auto [img, sc] = unlit_heatmap("div", "box_area_ratio");
  EXPECT_EQ(sc["colormap"], "coolwarm");
  EXPECT_DOUBLE_EQ(sc["min"].get<double>() + sc["max"].get<double>(), 2.0) << "symmetric about 1";
  EXPECT_EQ(img.at(48, 40), coolwarm(0.5));
}

TEST_F(Viz, PixelHeatmapHasItsNumbersAndAFixedRangeClampsVisibly) {
  VizCommandOptions o = options(VizKind::Heatmap, "px");
  o.metric = "nodes_visited";
  o.clusters.clear();  // the triangle BVH
  std::ostringstream out;
  cmd_viz(o, out);
  const nlohmann::json m = manifest("px");
  const auto& sc = m["results"]["images"]["heatmap_nodes_visited.png"]["scale"];
  EXPECT_EQ(sc["min"].get<double>(), 0.0);
  const double mx = sc["max"].get<double>();
  EXPECT_GE(mx, 2.0);
  const RgbImage img = viz::read_png(dir_ / "px" / "heatmap_nodes_visited.png");
  std::size_t top = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) top += img.at(x, y) == viridis(1.0);
  EXPECT_GT(top, 0u) << "the most expensive pixel has the top colour";

  o.out_dir = dir_ / "px2";
  o.range = "0:1";
  cmd_viz(o, out);
  const nlohmann::json m2 = manifest("px2");
  const auto& sc2 = m2["results"]["images"]["heatmap_nodes_visited.png"]["scale"];
  EXPECT_EQ(sc2["max"].get<double>(), 1.0);
  EXPECT_GT(sc2["above_range"].get<std::size_t>(), 100u) << "clamped pixels are counted";
}

TEST_F(Viz, PanelIsPartitionShadedAndHeatmapUnderATitle) {
  VizCommandOptions o = options(VizKind::Panel, "panel");
  std::ostringstream out;
  cmd_viz(o, out);
  const RgbImage panel = viz::read_png(dir_ / "panel" / "panel.png");
  const viz::LegendLayout ll = viz::legend_layout(160);
  EXPECT_EQ(panel.width, 3 * ll.width + 2 * 4) << "three columns as wide as the legend";
  // The title: one line of 28 pixels, and 20 more for each line it wraps to within the width.
  const int top = panel.height - 120 - ll.height;
  EXPECT_GE(top, 28);
  EXPECT_EQ((top - 28) % 20, 0) << top;
  // Its text stays inside the picture: the last 6 columns of the title band are background.
  for (int y = 0; y < top; ++y)
    for (int x = panel.width - 6; x < panel.width; ++x) EXPECT_EQ(panel.at(x, y), viz::kBackground) << x << " " << y;
  // The left third is the partition picture of `viz partition` with the same flags.
  VizCommandOptions p = options(VizKind::Partition, "part");
  cmd_viz(p, out);
  const RgbImage part = viz::read_png(dir_ / "part" / "partition.png");
  std::size_t differ = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) differ += panel.at(x, top + y) != part.at(x, y);
  EXPECT_EQ(differ, 0u);
  // The middle third is the tracer's shaded image: missed rays show the tracer's background.
  const auto ids = pixel_triangles(manifest("panel"), 160, 120);
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x)
      if (ids[static_cast<std::size_t>(y) * 160 + x] == kMiss) {
        EXPECT_EQ(panel.at(ll.width + 4 + x, top + y), viz::kBackground);
      }
}

TEST_F(Viz, ExportReadsBackWithVtkCellByCell) {
  // An animated scene: the sphere twisted over frames 0..2.
  const fs::path scene = twisted_scene(2);
  VizCommandOptions o = options(VizKind::Export, "vtp");
  o.input = scene;
  o.frames = "0:2";
  std::ostringstream out;
  cmd_viz(o, out);
  const std::string pvd = slurp(dir_ / "vtp" / "clusters.pvd");
  std::vector<std::string> files;
  const std::regex ds(R"re(<DataSet timestep="(\d+)"[^>]* file="([^"]+)"/>)re");
  for (auto it = std::sregex_iterator(pvd.begin(), pvd.end(), ds); it != std::sregex_iterator(); ++it) {
    EXPECT_EQ(std::stoi((*it)[1]), static_cast<int>(files.size()));
    files.push_back((*it)[2]);
  }
  ASSERT_EQ(files.size(), 3u);
  // It draws nothing, so its manifest records no camera and no picture size.
  const nlohmann::json params = manifest("vtp")["parameters"];
  EXPECT_FALSE(params.contains("camera")) << params.dump();
  EXPECT_FALSE(params.contains("width")) << params.dump();
  std::vector<Vec3> first;
  for (std::size_t f = 0; f < files.size(); ++f) {
    const viz::VtpContents c = viz::read_vtp(dir_ / "vtp" / files[f]);
    ASSERT_EQ(c.points.size(), mesh_.vertex_count());
    ASSERT_EQ(c.triangles.size(), mesh_.triangle_count());
    for (std::size_t t = 0; t < mesh_.triangle_count(); ++t)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(c.triangles[t][k], mesh_.triangle(t)[k]);
    if (f == 0) first = c.points;
    std::map<std::string, std::vector<std::int32_t>> ints(c.arrays.cell_int.begin(), c.arrays.cell_int.end());
    std::map<std::string, std::vector<double>> cells(c.arrays.cell.begin(), c.arrays.cell.end());
    ASSERT_TRUE(ints.count("cluster_id") && ints.count("colour_index"));
    for (const char* name : {"reg", "connectivity", "box_area_ratio", "sah_share", "acc", "triangles"})
      EXPECT_TRUE(cells.count(name)) << name;
    // cluster ids: the clustering's (renumbered densely in triangles.csv's order of first use is
    // not promised; one id per cluster of ours is).
    std::map<std::uint32_t, std::int32_t> id_of;
    std::map<std::uint32_t, double> count;
    for (std::uint32_t k : label_) count[k] += 1;
    for (std::size_t t = 0; t < mesh_.triangle_count(); ++t) {
      const auto [it, fresh] = id_of.emplace(label_[t], ints["cluster_id"][t]);
      EXPECT_EQ(it->second, ints["cluster_id"][t]) << "triangle " << t;
      EXPECT_EQ(cells["triangles"][t], count[label_[t]]);
    }
    EXPECT_EQ(id_of.size(), clusters_);
    for (const auto& [a, b] : adjacent_clusters()) {
      // colour_index differs between neighbours: compare through any triangle of each.
      std::int32_t ca = -1, cb = -1;
      for (std::size_t t = 0; t < mesh_.triangle_count(); ++t) {
        if (label_[t] == a) ca = ints["colour_index"][t];
        if (label_[t] == b) cb = ints["colour_index"][t];
      }
      EXPECT_NE(ca, cb);
    }
    ASSERT_EQ(c.arrays.point.size(), 1u);
    EXPECT_EQ(c.arrays.point[0].first, "displacement");
    double moved = 0;
    for (std::size_t v = 0; v < c.points.size(); ++v) {
      const Vec3 d = c.points[v] - first[v];
      EXPECT_NEAR((c.arrays.point[0].second[v] - d).norm(), 0.0, 1e-12);
      moved = std::max(moved, d.norm());
    }
    if (f == 0) EXPECT_EQ(moved, 0.0);
    else EXPECT_GT(moved, 1e-3) << "the twist moves the vertices";
  }
}

TEST_F(Viz, AStaticMeshMovesOnlyWithAStandInMotion) {
  // Without --deform a mesh file stays in its rest pose; with --deform twist it moves, and an
  // animated scene refuses the flag.
  for (const bool deform : {false, true}) {
    VizCommandOptions o = options(VizKind::Export, deform ? "twist" : "rest");
    o.frames = "0:2";
    if (deform) o.deform = "twist";
    std::ostringstream out;
    cmd_viz(o, out);
    const viz::VtpContents a = viz::read_vtp(dir_ / (deform ? "twist" : "rest") / "clusters_0000.vtp");
    const viz::VtpContents b = viz::read_vtp(dir_ / (deform ? "twist" : "rest") / "clusters_0002.vtp");
    double moved = 0;
    for (std::size_t v = 0; v < a.points.size(); ++v) moved = std::max(moved, (b.points[v] - a.points[v]).norm());
    if (deform) EXPECT_GT(moved, 1e-3);
    else EXPECT_EQ(moved, 0.0);
    EXPECT_EQ(manifest(deform ? "twist" : "rest")["parameters"]["motion"],
              deform ? "stand-in: the twist deformer (deform_preset)" : "none: the rest pose every frame");
  }
  const fs::path scene = dir_ / "scene.json";
  spit(scene, R"({"schema": "ptc-scene/1", "frames": [0, 2], "meshes": [{"name": "s", "file": ")" +
                  (kMeshes / "mushroom.off").string() + R"(", "deform": {"kind": "wave", "axis": "y"}}]})");
  VizCommandOptions o = options(VizKind::Export, "anim");
  o.input = scene;
  o.deform = "twist";
  std::ostringstream out;
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--deform");
  o.deform = "melt";
  o.input = kMeshes / "mushroom.off";
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--deform");
}

TEST_F(Viz, PrevMetricsCompareWithTheFrameBeforeWhateverFramesAreShown) {
  const fs::path scene = twisted_scene(3);
  std::ostringstream out;
  VizCommandOptions one = options(VizKind::Export, "one");
  one.input = scene;
  one.frame = "3";
  cmd_viz(one, out);
  VizCommandOptions two = options(VizKind::Export, "two");
  two.input = scene;
  two.frames = "2:3";
  cmd_viz(two, out);
  auto cells = [](const fs::path& f) {
    const viz::VtpContents c = viz::read_vtp(f);
    return std::map<std::string, std::vector<double>>(c.arrays.cell.begin(), c.arrays.cell.end());
  };
  auto a = cells(dir_ / "one" / "clusters_0003.vtp"), b = cells(dir_ / "two" / "clusters_0003.vtp");
  for (const char* m : {"box_area_ratio_prev", "sphere_radius_ratio_prev", "box_area_ratio"}) EXPECT_EQ(a[m], b[m]) << m;
  EXPECT_NE(a["box_area_ratio_prev"], a["box_area_ratio"]) << "frame 3 against frame 2, not against frame 0";
}

TEST_F(Viz, SeriesShareOneRangeAndSayWhyThereIsNoMp4) {
  const fs::path scene = twisted_scene(2);
  VizCommandOptions o = options(VizKind::Heatmap, "series");
  o.input = scene;
  o.frames = "0:2";
  o.metric = "box_area_ratio";
  std::ostringstream out;
  testing::internal::CaptureStderr();
  cmd_viz(o, out);
  const std::string err = testing::internal::GetCapturedStderr();
  const nlohmann::json m = manifest("series");
  std::set<std::pair<double, double>> ranges;
  for (int f = 0; f <= 2; ++f) {
    const std::string name = "heatmap_box_area_ratio_000" + std::to_string(f) + ".png";
    ASSERT_TRUE(fs::exists(dir_ / "series" / name)) << name;
    const auto& sc = m["results"]["images"][name]["scale"];
    ranges.insert({sc["min"].get<double>(), sc["max"].get<double>()});
    EXPECT_EQ(sc["range_from"], "values of frames 0:2");
  }
  EXPECT_EQ(ranges.size(), 1u) << "one colour range for the whole series";
  EXPECT_GT(ranges.begin()->second, 1.0) << "the twist changes box areas";
  // The series' frame 2 (values kept from the range pass) is the picture of frame 2 alone with
  // that range.
  VizCommandOptions one = options(VizKind::Heatmap, "one");
  one.input = scene;
  one.frame = "2";
  one.metric = "box_area_ratio";
  one.range = fmt::format("{:.17g}:{:.17g}", ranges.begin()->first, ranges.begin()->second);
  {  // the series' camera (framed on its first frame), not one framed on frame 2
    const auto& c = m["parameters"]["camera"];
    auto v = [](const nlohmann::json& a) { return Vec3(a[0], a[1], a[2]); };
    one.camera.eye = v(c["eye"]);
    one.camera.look_at = v(c["eye"]) + v(c["forward"]);
    one.camera.up = v(c["up"]);
    one.camera.fov_deg = c["fov_y_deg"].get<double>();
  }
  cmd_viz(one, out);
  const RgbImage a = viz::read_png(dir_ / "series" / "heatmap_box_area_ratio_0002.png");
  const RgbImage b = viz::read_png(dir_ / "one" / "heatmap_box_area_ratio.png");
  ASSERT_EQ(a.width, b.width);
  std::size_t differ = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < a.width; ++x) differ += a.at(x, y) != b.at(x, y);
  EXPECT_EQ(differ, 0u) << "only the legends may differ (where the range came from)";
  if (viz::find_program("ffmpeg").empty()) {  // a note, on stderr as every note (it was on stdout)
    EXPECT_NE(err.find("ptc: note: ffmpeg is not installed"), std::string::npos) << err;
    EXPECT_EQ(out.str().find("ffmpeg"), std::string::npos) << out.str();
    EXPECT_FALSE(fs::exists(dir_ / "series" / "heatmap_box_area_ratio.mp4"));
  } else {
    EXPECT_TRUE(fs::exists(dir_ / "series" / "heatmap_box_area_ratio.mp4"));
  }
}

TEST_F(Viz, UsageErrorsNameTheFlagAndComeBeforeAnyDisplay) {
  std::ostringstream out;
  VizCommandOptions o = options(VizKind::Heatmap, "u");
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--metric");  // heatmap without a metric
  o.metric = "colourfulness";
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--metric");
  o.metric = "reg";
  o.range = "1";
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--range");
  o.range = "2:1";
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--range");
  o.range = "-1:nan";
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--range");
  o.metric = "box_area_ratio";  // a ratio's range below 0 (it was taken)
  o.range = "-1:0.5";
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--range");
  o.metric = "reg";
  o.range.reset();
  o.clusters.clear();
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--clusters");  // a per-cluster metric needs clusters
  // --shadows where no ray is traced (a per-cluster heatmap, a partition, an export): refused.
  o.clusters = options(VizKind::Heatmap, "u").clusters;
  o.shadows = true;
  EXPECT_EQ(usage_flag([&] { cmd_viz(o, out); }), "--shadows");
  o.shadows = false;
  for (const VizKind k : {VizKind::Partition, VizKind::Export}) {
    VizCommandOptions e = options(k, "u");
    e.shadows = true;
    EXPECT_EQ(usage_flag([&] { cmd_viz(e, out); }), "--shadows") << to_string(k);
  }
  VizCommandOptions p = options(VizKind::Partition, "u");
  p.metric = "reg";
  EXPECT_EQ(usage_flag([&] { cmd_viz(p, out); }), "--metric");
  p.metric.clear();
  p.range = "0:1";
  EXPECT_EQ(usage_flag([&] { cmd_viz(p, out); }), "--range");
  p.range.reset();
  p.out_dir.clear();
  EXPECT_EQ(usage_flag([&] { cmd_viz(p, out); }), "--out");
  VizCommandOptions q = options(VizKind::Panel, "u");
  q.interactive = true;
  EXPECT_EQ(usage_flag([&] { cmd_viz(q, out); }), "--interactive");
  q.interactive = false;
  q.frame = "0", q.frames = "0:1";
  EXPECT_EQ(usage_flag([&] { cmd_viz(q, out); }), "--frame/--frames");
  q.frames.reset();
  q.width = 9000;
  EXPECT_EQ(usage_flag([&] { cmd_viz(q, out); }), "--width");
  q.width = 2800;  // fine alone, but three side by side are wider than VTK's 8192
  EXPECT_EQ(usage_flag([&] { cmd_viz(q, out); }), "--width");
  EXPECT_FALSE(fs::exists(dir_ / "u"));
}

TEST_F(Viz, NoDisplayAndNoXvfbIsOneLineAndNothingIsWritten) {
  const char* path = std::getenv("PATH");
  const char* display = std::getenv("DISPLAY");
  const std::string saved_path = path ? path : "", saved_display = display ? display : "";
  fs::create_directories(dir_ / "empty_bin");
  setenv("PATH", (dir_ / "empty_bin").c_str(), 1);
  unsetenv("DISPLAY");
  VizCommandOptions o = options(VizKind::Partition, "nox");
  o.force_xvfb = false;
  std::string what;
  try {
    std::ostringstream out;
    cmd_viz(o, out);
  } catch (const InputError& e) {
    what = e.what();
  }
  setenv("PATH", saved_path.c_str(), 1);
  if (!saved_display.empty()) setenv("DISPLAY", saved_display.c_str(), 1);
  EXPECT_NE(what.find("Xvfb is not installed"), std::string::npos) << what;
  EXPECT_NE(what.find("apt-get install"), std::string::npos) << what;
  EXPECT_FALSE(fs::exists(dir_ / "nox"));
  // The export needs no display at all.
  setenv("PATH", (dir_ / "empty_bin").c_str(), 1);
  unsetenv("DISPLAY");
  VizCommandOptions e = options(VizKind::Export, "nox_export");
  e.force_xvfb = false;
  std::ostringstream out;
  EXPECT_NO_THROW(cmd_viz(e, out));
  setenv("PATH", saved_path.c_str(), 1);
  if (!saved_display.empty()) setenv("DISPLAY", saved_display.c_str(), 1);
  EXPECT_TRUE(fs::exists(dir_ / "nox_export" / "clusters_0000.vtp"));
}

}  // namespace
}  // namespace ptc
