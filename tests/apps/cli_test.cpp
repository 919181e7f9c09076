// The `ptc` command as a user runs it: exit codes, one-line errors naming file and element,
// atomic outputs, and every sample mesh of libcgal-demo giving a result or a clear error.
#include <cpuid.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <sys/stat.h>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli_harness.h"
#include "common/csv_rows.h"

namespace fs = std::filesystem;

namespace {

using ptc::test::kCube;
using ptc::test::lines;
using ptc::test::RunResult;
using ptc::test::slurp;

class Cli : public ptc::test::CliTest {};

TEST_F(Cli, UsageErrorsExitTwo) {
  EXPECT_EQ(ptc({}).code, 2);
  EXPECT_EQ(ptc({"info"}).code, 2);
  EXPECT_EQ(ptc({"info", "x.off", "--bogus"}).code, 2);
  EXPECT_EQ(ptc({"frobnicate"}).code, 2);
  const auto cube = write("cube.off", kCube).string();
  EXPECT_EQ(ptc({"subdivide", cube, "--levels", "-1", "--out", (dir_ / "o.off").string()}).code, 2);
  EXPECT_EQ(ptc({"subdivide", cube, "--scheme", "butterfly", "--out", (dir_ / "o.off").string()}).code, 2);
  EXPECT_EQ(ptc({"spheres", cube, "--methods", "exact,bogus"}).code, 2);
  {
    const auto twice = ptc({"spheres", cube, "--methods", "exact,ritter,exact"});
    EXPECT_EQ(twice.code, 2);
    EXPECT_NE(twice.err.find("--methods: 'exact' is listed twice"), std::string::npos) << twice.err;
  }
  EXPECT_EQ(ptc({"spheres", cube, "--min-run", "10", "--max-run", "5"}).code, 2);
  EXPECT_EQ(ptc({"info", "--help"}).code, 0);
}

TEST_F(Cli, BadInputExitsOneWithOneLineNamingFileAndElement) {
  const auto missing = (dir_ / "missing.off").string();
  auto r = ptc({"info", missing});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("missing.off"), std::string::npos) << r.err;

  const auto nan = write("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").string();
  r = ptc({"info", nan});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("nan.off"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("vertex 1"), std::string::npos) << r.err;

  const auto idx = write("idx.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").string();
  r = ptc({"info", idx});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("idx.obj"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("line 4"), std::string::npos) << r.err;

  const auto lie = write("lie.off", "OFF\n1000000000000 1 0\n0 0 0\n").string();
  r = ptc({"info", lie});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;

  const auto unknown = write("mesh.xyz", "1 2 3\n").string();
  r = ptc({"info", unknown});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("mesh.xyz"), std::string::npos) << r.err;
}

// A file read anyway (a face with 2 corners skipped, surplus PLY values): one note per thing on
// stderr with the file name, the counts in `ptc info`, and the rest of the run as usual.
TEST_F(Cli, FilesReadAnywayGiveOneNoteEach) {
  const auto shortf = write("short.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n").string();
  auto r = ptc({"info", shortf, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "ptc: note: " + shortf +
                       ": 1 face has fewer than 3 corners and was skipped (first: face 1 (line 5))\n");
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["short_faces_skipped"], 1);
  EXPECT_EQ(j["faces_in_file"], 2);
  EXPECT_EQ(j["triangles"], 1);
  ASSERT_EQ(j["notes"].size(), 1u);
  const auto surplus = write("surplus.ply",
                             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 9 9\n")
                           .string();
  r = ptc({"info", surplus});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("surplus.ply: 1 line carries more values than the header declares"), std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find("note"), std::string::npos) << r.out;
  // A clean file has no note.
  r = ptc({"info", write("cube.off", kCube).string()});
  EXPECT_EQ(r.err, "");
}

TEST_F(Cli, InfoJsonMatchesTheMesh) {
  const auto cube = write("cube.off", kCube).string();
  auto r = ptc({"info", cube, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["schema"], "ptc-info/1");
  EXPECT_EQ(j["triangles"], 12);
  EXPECT_EQ(j["vertices"], 8);
  EXPECT_EQ(j["edges"], 18);
  EXPECT_EQ(j["boundary_edges"], 0);
  EXPECT_EQ(j["closed_manifold"], true);
  EXPECT_EQ(j["euler_characteristic"], 2);
  EXPECT_DOUBLE_EQ(j["total_area"].get<double>(), 6.0);
  r = ptc({"info", cube});
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("triangles"), std::string::npos);
}

TEST_F(Cli, InfoOnAMeshWhoseAreasOverflowSaysSo) {
  // 1e160 units: every edge length is a double, every area (1e320) is beyond the range.
  const auto big = write("big.off", "OFF\n4 2 0\n0 0 0\n1e160 0 0\n0 1e160 0\n1e160 1e160 0\n3 0 1 2\n3 1 3 2\n").string();
  auto r = ptc({"info", big});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("inf (beyond double's range"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("nan"), std::string::npos) << r.out;  // the median of two infinite areas was -nan
  EXPECT_NE(r.out.find("median 1e+160"), std::string::npos) << r.out;  // edge lengths stay finite
}

// The bounds in round-trip digits: a small mesh far from the origin keeps its extent (9 digits
// printed 100000000 for both ends of z below, and 2e+18 for both ends of x).
TEST_F(Cli, InfoPrintsTheBoundsInRoundTripDigits) {
  const auto far = write("far.off", "OFF\n3 1 0\n2e18 100000000 100000000\n2000000000000001024 100000001 100000000.5\n"
                                    "2e18 100000000 100000000.25\n3 0 1 2\n").string();
  const auto r = ptc({"info", far});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("bbox min                  2e+18 100000000 100000000\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("bbox max                  2.000000000000001e+18 100000001 100000000.5\n"), std::string::npos)
      << r.out;
}

TEST_F(Cli, SubdivideCountsAndAtomicOutput) {
  const auto cube = write("cube.off", kCube).string();
  const auto out = (dir_ / "fine.ply").string();
  auto r = ptc({"subdivide", cube, "--levels", "2", "--out", out, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["triangles_out"], 12 * 16);
  r = ptc({"info", out, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto k = nlohmann::json::parse(r.out);
  EXPECT_EQ(k["triangles"], 192);
  EXPECT_EQ(k["closed_manifold"], true);
  EXPECT_DOUBLE_EQ(k["total_area"].get<double>(), 6.0);  // midpoint split keeps the surface
  // A failing run must not touch the existing output.
  const std::string before = slurp(out);
  const auto bad = write("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n").string();
  r = ptc({"subdivide", bad, "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(slurp(out), before);
  EXPECT_EQ(r.err.find("replaced"), std::string::npos) << r.err;
  // A run that does replace a file the user had says so (and a first write does not).
  r = ptc({"subdivide", cube, "--out", (dir_ / "new.off").string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("replaced"), std::string::npos) << r.err;
  r = ptc({"subdivide", cube, "--out", out});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("ptc: note: replaced the existing " + out), std::string::npos) << r.err;
  // A symbolic link as --out (dangling or not) is replaced by the file, said; what it points to
  // is untouched.
  const fs::path kept = dir_ / "kept.off";
  fs::copy_file(out, kept);
  const std::string kept_bytes = slurp(kept);
  for (const fs::path& to : {kept, dir_ / "nowhere" / "x.off"}) {
    const fs::path link = dir_ / "link.off";
    fs::remove(link);
    fs::create_symlink(to, link);
    r = ptc({"subdivide", cube, "--out", link.string()});
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_NE(r.err.find("ptc: note: replaced the symbolic link " + link.string() + " (to " + to.string() +
                         ", which is untouched) by the file"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::is_symlink(link));
    EXPECT_TRUE(fs::is_regular_file(link));
  }
  EXPECT_EQ(slurp(kept), kept_bytes);
  // A FIFO as --out is refused before any work (the rename would have replaced it by a file).
  const fs::path fifo = dir_ / "fifo.off";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  r = ptc({"subdivide", cube, "--out", fifo.string()});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("--out: '" + fifo.string() + "' is a FIFO"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::is_fifo(fifo));
  // Loop refuses a non-manifold mesh with a clear error.
  const auto fan = write("fan.off", "OFF\n5 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n0 -1 0\n3 0 1 2\n3 1 0 3\n3 0 1 4\n").string();
  r = ptc({"subdivide", fan, "--scheme", "loop", "--out", (dir_ / "fan2.off").string()});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("fan.off"), std::string::npos) << r.err;  // names the file ...
  EXPECT_NE(r.err.find("edge (0, 1)"), std::string::npos) << r.err;  // ... and the element
  EXPECT_FALSE(fs::exists(dir_ / "fan2.off"));
}

TEST_F(Cli, SpheresWritesCsvAndManifestAtomically) {
  const auto mesh = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  const auto out = dir_ / "spheres";
  auto r = ptc({"spheres", mesh, "--repeats", "1", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_TRUE(fs::exists(out / "spheres.csv"));
  ASSERT_TRUE(fs::exists(out / "sphere_sets.csv"));
  ASSERT_TRUE(fs::exists(out / "manifest.json"));
  const std::string csv = slurp(out / "spheres.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "method,point_sets,ns_per_sphere,ns_per_sphere_min,ns_per_sphere_max,rel_err_mean,rel_err_max,not_containing");
  EXPECT_EQ(lines(csv), 7u);  // header + 6 methods
  const auto m = nlohmann::json::parse(slurp(out / "manifest.json"));
  EXPECT_EQ(m["command"], "spheres");
  EXPECT_EQ(m["inputs"][0]["fnv1a64"].get<std::string>().size(), 16u);
  EXPECT_TRUE(m["build"]["libraries"].contains("cgal"));
  EXPECT_TRUE(m["machine"].contains("logical_cores"));
  // A failed run leaves the previous directory whole; no temporary directories remain.
  const auto bad = write("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n").string();
  r = ptc({"spheres", bad, "--out", out.string()});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(slurp(out / "spheres.csv"), csv);
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".spheres.tmp"), std::string::npos) << e.path();
  // A trailing slash names the same directory.
  r = ptc({"spheres", mesh, "--repeats", "1", "--methods", "ritter", "--out", out.string() + "/"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(lines(slurp(out / "spheres.csv")), 2u);
  // A directory ptc did not write is never replaced.
  fs::create_directories(dir_ / "precious");
  std::ofstream(dir_ / "precious" / "thesis.txt") << "years of work";
  r = ptc({"spheres", mesh, "--repeats", "1", "--methods", "ritter", "--out", (dir_ / "precious").string()});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("precious"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(dir_ / "precious" / "thesis.txt"), "years of work");
}

TEST_F(Cli, NonUtf8FileNamesWork) {
  const auto p = write("bad\xff.off", kCube).string();
  const auto r = ptc({"info", p, "--json"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::accept(r.out));
}

TEST_F(Cli, EverySampleMeshGivesAResultOrAClearError) {
  std::size_t ok = 0, rejected = 0;
  for (const auto& e : fs::directory_iterator(std::string(PTC_TEST_DATA) + "/meshes")) {
    const auto r = ptc({"info", e.path().string(), "--json"});
    ASSERT_TRUE(r.code == 0 || r.code == 1) << e.path() << " exit " << r.code << "\n" << r.err;
    if (r.code == 0) {
      EXPECT_TRUE(nlohmann::json::accept(r.out)) << e.path();
      ++ok;
    } else {
      EXPECT_EQ(lines(r.err), 1u) << e.path() << ": " << r.err;
      EXPECT_NE(r.err.find(e.path().filename().string()), std::string::npos) << r.err;
      ++rejected;
    }
  }
  EXPECT_GT(ok, 100u);
  std::cout << "[ sample meshes ] " << ok << " loaded, " << rejected << " rejected with a clear error\n";
}

}  // namespace

namespace {

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> f;
  std::stringstream ss(line);
  for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
  return f;
}

/// The cluster files against each other, item by item: clusters.csv's leading columns and
/// p_hit = 2 area / bbox_area per row (two-sided); triangles.csv's per-triangle cluster ids counted against
/// clusters.csv's `triangles`; clusters.ply's per-face cluster_id (binary little endian, parsed
/// here by hand) equal to triangles.csv; summary.json's distributions with mean, min, p5, p50,
/// p95, max for every metric, min <= p5 <= p50 <= p95 <= max.
void expect_cluster_files(const fs::path& out, std::size_t triangles, std::size_t clusters) {
  std::istringstream csv(slurp(out / "clusters.csv"));
  std::string line;
  std::getline(csv, line);
  const auto cols = split_csv_line(line);
  const std::vector<std::string> want{"cluster_id", "triangles", "vertices", "connectivity", "reg", "acc",
                                      "sphere_radius", "sphere_area", "bbox_area", "p_hit"};
  ASSERT_GE(cols.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) EXPECT_EQ(cols[i], want[i]);
  const auto col = [&](const char* name) {
    return static_cast<std::size_t>(std::find(cols.begin(), cols.end(), name) - cols.begin());
  };
  ASSERT_LT(col("area"), cols.size());
  std::vector<std::size_t> per_cluster;
  while (std::getline(csv, line)) {
    const auto f = split_csv_line(line);
    ASSERT_EQ(f.size(), cols.size());
    EXPECT_EQ(std::stoull(f[0]), per_cluster.size());
    per_cluster.push_back(std::stoull(f[1]));
    const double area = std::stod(f[col("area")]), box = std::stod(f[col("bbox_area")]);
    // Both sides of a triangle count (cluster_metrics.h: p_hit = Naive = sum 2 Area_i / SA(box)).
    if (box > 0) {
      EXPECT_NEAR(std::stod(f[col("p_hit")]), 2 * area / box, 1e-12 * (1 + area / box)) << line;
    }
  }
  ASSERT_EQ(per_cluster.size(), clusters);
  std::vector<std::size_t> counted(clusters, 0);
  std::vector<std::int32_t> label;
  std::istringstream tri(slurp(out / "triangles.csv"));
  std::getline(tri, line);
  while (std::getline(tri, line)) {
    label.push_back(static_cast<std::int32_t>(std::stoll(line.substr(line.find(',') + 1))));
    ++counted.at(static_cast<std::size_t>(label.back()));
  }
  ASSERT_EQ(label.size(), triangles);
  EXPECT_EQ(counted, per_cluster);
  // clusters.ply: header, vertices (3 doubles), faces (uchar 3, 3 int, int cluster_id).
  const std::string ply = slurp(out / "clusters.ply");
  const auto end = ply.find("end_header\n");
  ASSERT_NE(end, std::string::npos);
  const std::string header = ply.substr(0, end);
  EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(header.find("property int cluster_id"), std::string::npos);
  const auto vpos = header.find("element vertex ");
  const std::size_t nv = std::stoull(header.substr(vpos + 15));
  std::size_t at = end + 11 + nv * 24;
  ASSERT_EQ(ply.size(), at + triangles * 17);
  for (std::size_t t = 0; t < triangles; ++t, at += 17) {
    std::int32_t id = 0;
    std::memcpy(&id, ply.data() + at + 13, 4);  // little-endian host (x86_64)
    ASSERT_EQ(id, label[t]) << "face " << t;
  }
  const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
  const auto& dist = summary["distributions"];
  for (const char* metric : {"triangles", "vertices", "connectivity", "reg", "sphere_radius", "sphere_area",
                             "bbox_area", "p_hit"}) {
    SCOPED_TRACE(metric);
    ASSERT_TRUE(dist.contains(metric));
    for (const char* k : {"mean", "min", "p5", "p50", "p95", "max"}) ASSERT_TRUE(dist[metric].contains(k)) << k;
    const auto& d = dist[metric];
    EXPECT_LE(d["min"].get<double>(), d["p5"].get<double>());
    EXPECT_LE(d["p5"].get<double>(), d["p50"].get<double>());
    EXPECT_LE(d["p50"].get<double>(), d["p95"].get<double>());
    EXPECT_LE(d["p95"].get<double>(), d["max"].get<double>());
    EXPECT_LE(d["min"].get<double>(), d["mean"].get<double>());
    EXPECT_LE(d["mean"].get<double>(), d["max"].get<double>());
  }
  EXPECT_EQ(dist["triangles"]["mean"].get<double>(), double(triangles) / double(clusters));
}

TEST_F(Cli, ClusterWritesTheFourFilesConsistently) {
  const auto mesh = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  const auto out = dir_ / "clu";
  for (const char* method : {"growth", "contraction", "sah-split", "meshopt"}) {
    SCOPED_TRACE(method);
    auto r = ptc({"cluster", mesh, "--method", method, "--max-count", "40", "--out", out.string(), "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    const auto res = nlohmann::json::parse(r.out);
    const std::size_t clusters = res["clusters"];
    const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
    EXPECT_EQ(summary["schema"], "ptc-cluster-summary/2");
    EXPECT_EQ(summary["validation"], "ok");
    EXPECT_EQ(summary["clusters"], clusters);
    const auto manifest = nlohmann::json::parse(slurp(out / "manifest.json"));
    EXPECT_EQ(manifest["parameters"]["method"], method);
    EXPECT_EQ(manifest["parameters"]["max_count"], 40);
    EXPECT_EQ(manifest["output_schemas"]["clusters.csv"], "ptc-clusters/1");
    EXPECT_EQ(manifest["output_schemas"]["triangles.csv"], "ptc-cluster-triangles/1");
    // Only what the method used is recorded.
    const bool objective = std::string(method) == "growth" || std::string(method) == "contraction";
    EXPECT_EQ(manifest["parameters"].contains("objective"), objective);
    EXPECT_EQ(manifest["parameters"].contains("max_triangles"), !objective);
    EXPECT_EQ(manifest["parameters"].contains("start"), std::string(method) == "growth");
    // Memory per stage: the peak so far and the resident size at each stage's end (MB), never
    // above the run's peak, which is at least the mesh's own arrays.
    const double peak = manifest["max_rss_mb"];
    EXPECT_GT(peak, 1.0);
    for (const auto& [stage, ms] : manifest["timings_ms"].items()) {
      SCOPED_TRACE(stage);
      ASSERT_TRUE(manifest["peak_rss_mb"].contains(stage));
      ASSERT_TRUE(manifest["rss_mb"].contains(stage));
      EXPECT_GT(manifest["rss_mb"][stage].get<double>(), 0.0);
      EXPECT_LE(manifest["rss_mb"][stage].get<double>(), manifest["peak_rss_mb"][stage].get<double>());
      EXPECT_LE(manifest["peak_rss_mb"][stage].get<double>(), peak);
    }
    EXPECT_LE(manifest["peak_rss_mb"]["read"].get<double>(), manifest["peak_rss_mb"]["write"].get<double>());
    EXPECT_EQ(lines(slurp(out / "clusters.csv")), clusters + 1);
    // triangles.csv covers every triangle of the input once, with ids < clusters.
    std::istringstream tri(slurp(out / "triangles.csv"));
    std::string line;
    std::getline(tri, line);
    EXPECT_EQ(line, "triangle_id,cluster_id");
    std::size_t n = 0;
    while (std::getline(tri, line)) {
      const auto comma = line.find(',');
      EXPECT_EQ(std::stoull(line.substr(0, comma)), n);
      EXPECT_LT(std::stoull(line.substr(comma + 1)), clusters);
      ++n;
    }
    r = ptc({"info", (out / "clusters.ply").string(), "--json"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(nlohmann::json::parse(r.out)["triangles"], n);
    expect_cluster_files(out, n, clusters);
  }
}

TEST_F(Cli, ClusterATriangleSoupByCoincidentCorners) {
  // The cube as a soup (every corner its own vertex). auto: clusters over sides whose corners
  // coincide, said on stdout and in the manifest; edges: one triangle per cluster (no shared
  // vertex ids). The clustering reads back for `ptc trace --clusters`.
  std::string off = "OFF\n36 12 0\n";
  const double c[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& t : f)
    for (int k : t) off += std::to_string(c[k][0]) + " " + std::to_string(c[k][1]) + " " + std::to_string(c[k][2]) + "\n";
  for (int t = 0; t < 12; ++t)
    off += "3 " + std::to_string(3 * t) + " " + std::to_string(3 * t + 1) + " " + std::to_string(3 * t + 2) + "\n";
  const fs::path soup = write("soup.off", off);
  auto info = ptc({"info", soup.string(), "--json"});
  ASSERT_EQ(info.code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["triangle_soup"], true);
  info = ptc({"info", soup.string()});
  EXPECT_NE(info.out.find("yes (no vertex shared by two triangles"), std::string::npos) << info.out;
  EXPECT_EQ(nlohmann::json::parse(ptc({"info", std::string(PTC_TEST_DATA) + "/meshes/elephant.off", "--json"}).out)["triangle_soup"],
            false);
  auto r = ptc({"cluster", soup.string(), "--method", "growth", "--max-count", "8", "--out", (dir_ / "a").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("adjacency: positions (sides whose corners coincide; auto: the mesh is a triangle soup)"),
            std::string::npos) << r.out;
  auto manifest = nlohmann::json::parse(slurp(dir_ / "a" / "manifest.json"));
  EXPECT_EQ(manifest["parameters"]["adjacency"], "auto");
  EXPECT_EQ(manifest["results"]["adjacency"], "positions");
  EXPECT_LT(manifest["results"]["clusters"].get<std::size_t>(), 12u);
  r = ptc({"trace", soup.string(), "--clusters", (dir_ / "a").string(), "--width", "16", "--height", "16", "--out",
           (dir_ / "t").string()});
  EXPECT_EQ(r.code, 0) << r.err;
  r = ptc({"cluster", soup.string(), "--method", "growth", "--max-count", "8", "--adjacency", "edges", "--out",
           (dir_ / "e").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  manifest = nlohmann::json::parse(slurp(dir_ / "e" / "manifest.json"));
  EXPECT_EQ(manifest["results"]["adjacency"], "edges");
  EXPECT_EQ(manifest["results"]["clusters"], 12);
  r = ptc({"cluster", soup.string(), "--adjacency", "vertices", "--out", (dir_ / "x").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("--adjacency"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "x"));
}

TEST_F(Cli, ClusteringAndTracerInstructionSetsAreRecorded) {
  // The manifest names the clones of the clustering's hot code the loader picked
  // (toolkit/core/isa.h): x86-64-v3 exactly when the CPU has every feature of that level and the
  // OS saves the AVX registers, the baseline otherwise. The independent answer reads the CPUID
  // bits itself (this machine's /proc/cpuinfo omits LZCNT's "abm" although the CPU has it).
  unsigned a = 0, b = 0, c1 = 0, d = 0, b7 = 0, c7 = 0, cx = 0;
  ASSERT_TRUE(__get_cpuid(1, &a, &b, &c1, &d));
  const bool leaf7 = __get_cpuid_count(7, 0, &a, &b7, &c7, &d);
  const bool ext = __get_cpuid(0x80000001u, &a, &b, &cx, &d);
  auto bit = [](unsigned r, int i) { return ((r >> i) & 1u) != 0; };
  // FMA, MOVBE, XSAVE, OSXSAVE, AVX, F16C
  bool v3 = bit(c1, 12) && bit(c1, 22) && bit(c1, 26) && bit(c1, 27) && bit(c1, 28) && bit(c1, 29);
  v3 = v3 && leaf7 && bit(b7, 3) && bit(b7, 5) && bit(b7, 8);  // BMI1 AVX2 BMI2
  v3 = v3 && ext && bit(cx, 5);                                // LZCNT
  if (v3) {
    unsigned lo = 0, hi = 0;
    __asm__("xgetbv" : "=a"(lo), "=d"(hi) : "c"(0));
    v3 = (lo & 6u) == 6u;  // XMM and YMM state enabled by the OS
  }
  const std::string mesh = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  const RunResult r = ptc({"cluster", mesh, "--max-count", "30", "--out", (dir_ / "isa").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto machine = nlohmann::json::parse(slurp(dir_ / "isa" / "manifest.json"))["machine"];
  EXPECT_EQ(machine["clustering_isa"].get<std::string>(), std::string(v3 ? "x86-64-v3" : "x86-64"));
  // And the tracer's default variant (bvh/tracer.h): with AVX-512 F, DQ, BW and VL and the OS
  // saving the opmask and ZMM state, avx512 on an AMD CPU (vendor string "AuthenticAMD") of
  // family 1Ah or later (Zen 5) and avx512vl on others; else avx2 with AVX2 and the YMM state,
  // else sse2.
  bool avx2 = bit(c1, 27) && bit(c1, 28) && leaf7 && bit(b7, 5);
  unsigned xlo = 0, xhi = 0;
  if (avx2) __asm__("xgetbv" : "=a"(xlo), "=d"(xhi) : "c"(0));
  avx2 = avx2 && (xlo & 6u) == 6u;
  const bool avx512 = avx2 && bit(b7, 16) && bit(b7, 17) && bit(b7, 30) && bit(b7, 31) && (xlo & 0xe0u) == 0xe0u;
  unsigned v0 = 0, vb = 0, vc = 0, vd = 0;
  ASSERT_TRUE(__get_cpuid(0, &v0, &vb, &vc, &vd));
  const bool amd = vb == 0x68747541u && vd == 0x69746e65u && vc == 0x444d4163u;  // "Auth" "enti" "cAMD"
  unsigned f1 = 0, fb = 0, fc = 0, fd = 0;
  ASSERT_TRUE(__get_cpuid(1, &f1, &fb, &fc, &fd));
  const unsigned family = ((f1 >> 8) & 0xfu) == 0xfu ? 0xfu + ((f1 >> 20) & 0xffu) : (f1 >> 8) & 0xfu;
  EXPECT_EQ(machine["trace_isa"].get<std::string>(),
            std::string(avx512 ? (amd && family >= 0x1au ? "avx512" : "avx512vl") : avx2 ? "avx2" : "sse2"));
}

TEST_F(Cli, MallocOnHugePagesIsRecordedAndCanBeTurnedOff) {
  // ptc sets GLIBC_TUNABLES glibc.malloc.hugetlb=1 and executes itself once (commands/process.h),
  // unless PTC_HUGEPAGES=0, the user named the tunable, or the kernel has THP off; the manifest
  // says which. The outputs are the same either way.
  std::string mode;
  std::getline(std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled"), mode);
  const bool thp = !mode.empty() && mode.find("[never]") == std::string::npos;
  const auto mesh = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  auto run = [&](const char* var, const char* value, const std::string& out) {
    if (var) ::setenv(var, value, 1);
    const RunResult r = ptc({"cluster", mesh, "--max-count", "30", "--out", (dir_ / out).string()});
    if (var) ::unsetenv(var);
    EXPECT_EQ(r.code, 0) << r.err;
    return nlohmann::json::parse(slurp(dir_ / out / "manifest.json"))["machine"];
  };
  // Runs without a GLIBC_TUNABLES of the test's own environment (given back at the end).
  const char* had = std::getenv("GLIBC_TUNABLES");
  const std::string saved = had ? had : "";
  ::unsetenv("GLIBC_TUNABLES");
  const auto on = run(nullptr, nullptr, "on");
  EXPECT_EQ(on["malloc_hugepages"], thp);
  if (thp) {
    EXPECT_TRUE(on["transparent_hugepages"] == "madvise" || on["transparent_hugepages"] == "always");
  }
  EXPECT_EQ(run("PTC_HUGEPAGES", "0", "off")["malloc_hugepages"], false);
  EXPECT_EQ(run("GLIBC_TUNABLES", "glibc.malloc.hugetlb=0", "user")["malloc_hugepages"], false);
  EXPECT_EQ(slurp(dir_ / "on" / "triangles.csv"), slurp(dir_ / "off" / "triangles.csv"));
  EXPECT_EQ(slurp(dir_ / "on" / "clusters.csv"), slurp(dir_ / "user" / "clusters.csv"));
  if (had) ::setenv("GLIBC_TUNABLES", saved.c_str(), 1);
}

// Meshes the Acc objective cannot scale: all triangles of zero area (AvgSA = 0: one cluster per
// triangle, said in a note, the nan columns documented in docs/tables.md), and coordinates whose
// sphere areas overflow double (refused, naming the file, in the user's words).
TEST_F(Cli, ClusterOnMeshesWithoutASizeScale) {
  const auto zero = write("allsame.off", "OFF\n3 1 0\n0 0 0\n0 0 0\n0 0 0\n3 0 1 2\n");
  auto r = ptc({"cluster", zero.string(), "--out", (dir_ / "z").string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("allsame.off: every triangle collapses to a point (AvgSA = 0): one cluster per triangle"),
            std::string::npos)
      << r.err;
  {  // and the columns are as docs/tables.md says: acc, reg_bound, size_bound nan, reg 0
    const auto rows = ptc::test::csv_rows(slurp(dir_ / "z" / "clusters.csv"));  // common/csv_rows.h
    ASSERT_EQ(rows.size(), 1u);
    for (const char* col : {"acc", "reg_bound", "size_bound"}) EXPECT_EQ(rows[0].at(col), "nan") << col;
    EXPECT_EQ(rows[0].at("reg"), "0");
  }
  // A square of 1e300 units and one of 1e-300 (areas beyond double's range: AvgSA overflowed or
  // underflowed, and Acc refused the first and made one cluster per triangle of the second) are
  // clustered and measured at a power-of-two scale: for every method, the same clusters and the
  // same ratio columns as the unit square, lengths and areas in the mesh's units, with a note.
  const auto unit = write("unit.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n");
  const auto huge = write("huge.off", "OFF\n4 2 0\n0 0 0\n1e300 0 0\n0 1e300 0\n1e300 1e300 0\n3 0 1 2\n3 1 3 2\n");
  const auto tiny = write("tiny.off", "OFF\n4 2 0\n0 0 0\n1e-300 0 0\n0 1e-300 0\n1e-300 1e-300 0\n3 0 1 2\n3 1 3 2\n");
  for (const char* method : {"growth", "contraction", "sah-split", "meshopt"}) {
    const fs::path u = dir_ / (std::string("u_") + method);
    r = ptc({"cluster", unit.string(), "--method", method, "--out", u.string()});
    ASSERT_EQ(r.code, 0) << method << " " << r.err;
    const auto want = ptc::test::csv_rows(slurp(u / "clusters.csv"));
    for (const auto& [mesh, size] : {std::pair{huge, 1e300}, std::pair{tiny, 1e-300}}) {
      const fs::path out = dir_ / (std::string("s_") + method + (size > 1 ? "_huge" : "_tiny"));
      r = ptc({"cluster", mesh.string(), "--method", method, "--out", out.string()});
      ASSERT_EQ(r.code, 0) << method << " " << r.err;
      EXPECT_NE(r.err.find(mesh.filename().string() + ": coordinates of extreme scale: clustered and measured at 2^"),
                std::string::npos)
          << r.err;
      EXPECT_EQ(r.err.find("collapses to a point"), std::string::npos) << r.err;
      EXPECT_EQ(slurp(out / "triangles.csv"), slurp(u / "triangles.csv")) << method;
      const auto rows = ptc::test::csv_rows(slurp(out / "clusters.csv"));
      ASSERT_EQ(rows.size(), want.size()) << method;
      for (std::size_t i = 0; i < rows.size(); ++i) {
        for (const char* col : {"triangles", "vertices", "connectivity"})
          EXPECT_EQ(rows[i].at(col), want[i].at(col)) << method << " " << col;
        // (1e300 and 1e-300 are not powers of two times 1: ratios and lengths agree to rounding)
        for (const char* col : {"reg", "acc", "p_hit", "reg_bound", "size_bound"})
          EXPECT_NEAR(std::stod(rows[i].at(col)), std::stod(want[i].at(col)), 1e-12) << method << " " << col;
        EXPECT_NEAR(std::stod(rows[i].at("sphere_radius")) / size, std::stod(want[i].at("sphere_radius")), 1e-12) << method;
        if (size > 1) EXPECT_TRUE(std::isinf(std::stod(rows[i].at("area")))) << method;  // (1e600: beyond double)
        else EXPECT_EQ(std::stod(rows[i].at("area")), 0.0) << method;                     // (1e-600: below it)
      }
    }
  }
}

TEST_F(Cli, ClusterRejectsBadArguments) {
  const auto mesh = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  EXPECT_EQ(ptc({"cluster", mesh}).code, 2);  // --out is required
  EXPECT_EQ(ptc({"cluster", mesh, "--method", "kmeans", "--out", (dir_ / "x").string()}).code, 2);
  EXPECT_EQ(ptc({"cluster", mesh, "--objective", "best", "--out", (dir_ / "x").string()}).code, 2);
  EXPECT_EQ(ptc({"cluster", mesh, "--max-count", "-3", "--out", (dir_ / "x").string()}).code, 2);
  // Inconsistent parameters are bad usage, in the flags' words, with one line.
  auto r = ptc({"cluster", mesh, "--max-count", "0", "--max-size", "5", "--out", (dir_ / "x").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("--max-count"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("cluster_mesh"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "x"));
  // Numbers that are not finite are bad usage too, naming the flag (CLI11's range let nan through).
  for (const char* flag : {"--gwh-a1", "--max-size"}) {
    std::vector<std::string> args{"cluster", mesh, flag, "nan", "--out", (dir_ / "x").string()};
    if (std::string(flag) == "--gwh-a1") args.insert(args.end(), {"--objective", "gwh01"});
    r = ptc(args);
    EXPECT_EQ(r.code, 2) << flag << ": " << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(std::string(flag) + ": nan is not a finite number"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "x"));
  }
  // meshoptimizer's limits are explained, not an abort.
  r = ptc({"cluster", mesh, "--method", "meshopt", "--max-count", "1000", "--out", (dir_ / "x").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("--max-count"), std::string::npos) << r.err;
  // Regions and a target cluster count for the whole mesh do not go together.
  r = ptc({"cluster", mesh, "--method", "contraction", "--regions", "4", "--target-clusters", "100", "--out",
           (dir_ / "x").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find("--regions"), std::string::npos) << r.err;
  // A flag the method does not use is refused, naming it and what the method uses.
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--method", "sah-split", "--objective", "naive"},
        {"--method", "meshopt", "--max-size", "10"},
        {"--method", "growth", "--objective", "naive", "--max-size", "10"},
        {"--method", "contraction", "--start", "index"},
        {"--method", "growth", "--target-clusters", "5"},
        {"--method", "growth", "--objective", "acc", "--gwh-a1", "1"},
        {"--method", "growth", "--objective", "gwh01", "--regions", "4"}}) {
    std::vector<std::string> args{"cluster", mesh, "--out", (dir_ / "x").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    r = ptc(args);
    EXPECT_EQ(r.code, 2) << extra[1] << " " << extra[2] << ": " << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(extra[2]), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("not used by --method " + extra[1]), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "x"));
  }
  // One triangle per cluster runs no method: that is the reason given, not the method.
  r = ptc({"cluster", mesh, "--method", "growth", "--objective", "acc", "--max-count", "0", "--max-size", "0", "--out",
           (dir_ / "x").string()});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--objective: not used with --max-count 0 --max-size 0 (one triangle per cluster"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
}

}  // namespace

namespace {

// `ptc info --json`'s memory estimate against the peak the commands themselves record (their
// manifests' max_rss_mb, VmHWM) on the armadillo midpoint-subdivided once (208k triangles):
// within 25% for both clusterings, in one run and in 8 regions, and what fits into the machine
// follows from the same model.
TEST_F(Cli, InfoMemoryEstimateAgreesWithTheMeasuredPeak) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "the model is of the release build; AddressSanitizer's shadow memory and quarantine "
                  "take 3 to 5 times as much";
#endif
  const auto mesh = (dir_ / "a1.ply").string();
  ASSERT_EQ(ptc({"subdivide", std::string(PTC_TEST_DATA) + "/meshes/armadillo.off", "--levels", "1", "--out", mesh}).code, 0);
  auto r = ptc({"info", mesh, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto est = nlohmann::json::parse(r.out)["memory_estimate"];
  for (const char* method : {"growth", "contraction"}) {
    SCOPED_TRACE(method);
    const auto out = dir_ / (std::string("c_") + method);
    r = ptc({"cluster", mesh, "--method", method, "--out", out.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    const double measured = nlohmann::json::parse(slurp(out / "manifest.json"))["max_rss_mb"];
    const double estimated = est["peak_mb"][std::string("cluster_") + method];
    EXPECT_NEAR(estimated / measured, 1.0, 0.25) << "estimated " << estimated << " MB, measured " << measured << " MB";
    // In 8 regions on the default threads (all cores, as the estimate assumes).
    const auto rout = dir_ / (std::string("r_") + method);
    r = ptc({"cluster", mesh, "--method", method, "--regions", "8", "--out", rout.string()});
    ASSERT_EQ(r.code, 0) << r.err;
    const double rmeasured = nlohmann::json::parse(slurp(rout / "manifest.json"))["max_rss_mb"];
    const double restimated = est["peak_mb"][std::string("cluster_") + method + "_regions_8"];
    EXPECT_NEAR(restimated / rmeasured, 1.0, 0.25) << "regions: estimated " << restimated << " MB, measured " << rmeasured
                                                  << " MB";
  }
  const double machine = est["machine_memory_mb"];
  ASSERT_GT(machine, 0.0);
  const double largest = est["largest_triangles_for_machine"]["cluster_growth"];
  EXPECT_GT(largest, 1e6);  // any machine that builds ptc clusters a million triangles
  EXPECT_LT(largest, machine * 1048576.0 / 100.0);  // never under 100 bytes a triangle
}

}  // namespace

namespace {
// Flags that would do nothing in the chosen mode are bad usage, naming the flag (found by a
// new user: they were accepted silently).
TEST_F(Cli, FlagsThatWouldDoNothingAreRefused) {
  const auto mesh = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  // The export writes .vtp files: picture and camera flags draw nothing there.
  const std::vector<std::vector<std::string>> flags = {{"--flat"},          {"--no-borders"},     {"--width", "100"},
                                                       {"--height", "100"}, {"--eye", "1,2,3"},   {"--look-at", "0,0,0"},
                                                       {"--up", "0,0,1"},   {"--fov", "30"},      {"--light", "1,1,1"},
                                                       {"--xvfb"}};
  for (const auto& f : flags) {
    const std::string& flag = f[0];
    std::vector<std::string> args = {"viz", "export", mesh, "--clusters", (dir_ / "none").string()};
    args.insert(args.end(), f.begin(), f.end());
    args.insert(args.end(), {"--out", (dir_ / "v").string()});
    const auto r = ptc(args);
    EXPECT_EQ(r.code, 2) << flag << ": " << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(flag + ": not used by viz export"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "v"));
  }
  // Pictures that a flag would not change: borders on a heatmap, no lighting on a per-pixel
  // heatmap (flat already), a light where nothing is lit by it (found by a new user: each gave
  // the same bytes as without it, and the manifest recorded it as used).
  struct Case {
    std::vector<std::string> args;
    std::string flag, says;
  };
  const std::string cl = (dir_ / "none").string();
  for (const Case& k : {Case{{"heatmap", "--metric", "reg", "--clusters", cl, "--no-borders"}, "--no-borders", "a heatmap draws none"},
                        Case{{"heatmap", "--metric", "nodes_visited", "--no-borders"}, "--no-borders", "a heatmap draws none"},
                        Case{{"heatmap", "--metric", "nodes_visited", "--flat"}, "--flat", "flat colours already"},
                        Case{{"partition", "--clusters", cl, "--light", "1,2,3"}, "--light", "viz partition draws the mesh with a headlight"},
                        Case{{"heatmap", "--metric", "reg", "--clusters", cl, "--light", "1,2,3"}, "--light", "per-cluster metric draws the mesh with a headlight"},
                        Case{{"heatmap", "--metric", "triangles_tested", "--light", "1,2,3"}, "--light", "no shadow rays without --shadows"}}) {
    std::vector<std::string> args = {"viz", k.args[0], mesh};
    args.insert(args.end(), k.args.begin() + 1, k.args.end());
    args.insert(args.end(), {"--out", (dir_ / "v").string()});
    const auto r = ptc(args);
    EXPECT_EQ(r.code, 2) << k.flag << ": " << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_NE(r.err.find(k.flag + ": "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(k.says), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "v"));
  }
  // --scheme with --levels 0: nothing is refined.
  {
    const auto s0 = ptc({"subdivide", mesh, "--levels", "0", "--scheme", "loop", "--out", (dir_ / "s.off").string()});
    EXPECT_EQ(s0.code, 2) << s0.err;
    EXPECT_NE(s0.err.find("--scheme: not used with --levels 0 (nothing is refined)"), std::string::npos) << s0.err;
    EXPECT_FALSE(fs::exists(dir_ / "s.off"));
  }
  // --data-dir locates built-in scenes' meshes: with a mesh file or a directory of frames it does nothing.
  fs::create_directories(dir_ / "frames");
  for (const std::string& scene : {mesh, (dir_ / "frames").string(), (dir_ / "frames" / "*.ply").string()}) {
    const auto d = ptc({"trace", scene, "--data-dir", "/nonexistent", "--out", (dir_ / "t").string()});
    EXPECT_EQ(d.code, 2) << scene << ": " << d.err;
    EXPECT_EQ(lines(d.err), 1u) << d.err;
    EXPECT_NE(d.err.find("--data-dir: not used: '" + scene + "' is "), std::string::npos) << d.err;
    EXPECT_FALSE(fs::exists(dir_ / "t"));
  }
  const auto r = ptc({"notebook", (dir_ / "none").string(), "--execute", "--no-figures", "--out", (dir_ / "n").string()});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--execute"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "n"));
}
}  // namespace

namespace {
// CLI11's words for common slips, said in the user's: an unknown command, a flag given twice, a
// fraction or a word for a whole number.
TEST_F(Cli, CommonSlipsAreNamed) {
  const auto mesh = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  auto r = ptc({"foo"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("'foo' is not a ptc command (info, subdivide"), std::string::npos) << r.err;
  r = ptc({"trace", mesh, "--width", "16", "--width", "17", "--out", (dir_ / "o").string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("--width: given more than once"), std::string::npos) << r.err;
  for (const char* v : {"1.5", "abc", "-3"}) {
    r = ptc({"cluster", mesh, "--max-count", v, "--out", (dir_ / "o").string()});
    EXPECT_EQ(r.code, 2) << v;
    EXPECT_NE(r.err.find(std::string("--max-count: '") + v + "' is not a whole number in [0, 1048576]"), std::string::npos)
        << r.err;
  }
  // --frame where a command takes a range only (trace and viz take both).
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  for (const Case& k : {Case{{"bench", mesh, "--frame", "3"}, "--frame: ptc bench takes a range of frames: --frames 3:3 for one"},
                        Case{{"animate", mesh, "--frame=4"}, "--frame: ptc animate takes a range of frames: --frames 4:4 for one"},
                        Case{{"experiment", "sweep", mesh, "--frame", "2"},
                             "--frame: ptc experiment sweep takes a range of frames: --frames 2:2 for one"}}) {
    std::vector<std::string> a = k.args;
    a.insert(a.end(), {"--out", (dir_ / "o").string()});
    r = ptc(a);
    EXPECT_EQ(r.code, 2) << k.says;
    EXPECT_NE(r.err.find(k.says), std::string::npos) << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}
}  // namespace

namespace {
// An output file in a directory that does not exist: named as the user gave it, with the reason
// (the message named the hidden temporary file instead).
TEST_F(Cli, OutputInAMissingDirectoryIsNamedAsGiven) {
  const auto cube = write("cube.off", ptc::test::kCube).string();
  const auto out = (dir_ / "nodir" / "s.off").string();
  const auto r = ptc({"subdivide", cube, "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find(out + ": cannot write it: the directory '" + (dir_ / "nodir").string() + "' does not exist"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find(".tmp"), std::string::npos) << r.err;
}

// What a new user ran into (a sweep of unusual inputs, 2026-12-07), each with the answer the
// standards ask for: a light at 1e308 lights and shadows as one at 1e30 (its squared distance
// overflowed, and the picture had no shadows, silently), an eye beyond the tracer's reach is
// refused, an up vector of 1e-300 taken (Eigen called it zero), an
// empty file name named, a byte order mark in triangles.csv read, numbers that are not whole
// refused in the tool's words, a missing --data-dir said as such, a frame directory with a gap
// in its numbers noted, and a re-run that writes fewer files said.
TEST_F(Cli, SlipsOfANewUser) {
  const auto cube = write("cube.off", kCube);
  const std::string out = (dir_ / "t").string();
  auto trace = [&](std::vector<std::string> extra, const std::string& mesh) {
    std::vector<std::string> a = {"trace", mesh, "--width", "8", "--height", "8"};
    a.insert(a.end(), extra.begin(), extra.end());
    a.insert(a.end(), {"--out", out});
    return ptc(a);
  };
  // The same picture, shadows and counters with the light at 1e308 and at 1e30 in the same
  // direction (their directions agree to far below a float's precision).
  const std::vector<std::string> view = {"--shadows", "--eye", "2.5,1.8,3", "--look-at", "0.5,0.5,0.5"};
  std::string images[2], csvs[2];
  for (int k = 0; k < 2; ++k) {
    std::vector<std::string> a = view;
    a.insert(a.end(), {"--light", k == 0 ? "1e308,1.5e308,1.2e308" : "1e30,1.5e30,1.2e30"});
    const RunResult lit = trace(a, cube.string());
    ASSERT_EQ(lit.code, 0) << lit.err;
    images[k] = slurp(dir_ / "t" / "shaded.png");
    for (const auto& row : ptc::test::csv_rows(slurp(dir_ / "t" / "trace.csv")))
      if (row.at("pass") == "shadow") csvs[k] = row.at("rays") + " " + row.at("hits") + " " + row.at("nodes_per_ray");
    fs::remove_all(out);
  }
  EXPECT_FALSE(images[0].empty());
  EXPECT_EQ(images[0], images[1]);
  EXPECT_FALSE(csvs[0].empty());
  EXPECT_EQ(csvs[0], csvs[1]);
  RunResult r = trace({"--eye", "1e300,1e300,1e300", "--look-at", "-1e300,-1e300,-1e300"}, cube.string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--eye"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the camera's eye"), std::string::npos) << r.err;
  // Within reach: a light at 1e12 units still lights (and shadows) the unit cube.
  r = trace({"--light", "1e12,2e12,3e12"}, cube.string());
  EXPECT_EQ(r.code, 0) << r.err;
  fs::remove_all(out);
  // A scene file's own camera that far: bad input (exit 1) naming the file and its camera.
  const auto scene = write("far.json", "{\"meshes\": [{\"file\": \"cube.off\"}], \"camera\": {\"eye\": [0, 0, 1e100], "
                                       "\"look_at\": [0.5, 0.5, 0.5]}}");
  r = trace({}, scene.string());
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("far.json: camera: the camera's eye"), std::string::npos) << r.err;
  // A framing camera pushed that far by --fov: --fov is named.
  r = trace({"--fov", "1e-30"}, cube.string());
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--fov: the eye of the camera framing the mesh"), std::string::npos) << r.err;
  // An up vector of 1e-300 is a direction.
  r = trace({"--eye", "0.5,0.5,5", "--look-at", "0.5,0.5,0.5", "--up", "1e-300,1e-300,0"}, cube.string());
  EXPECT_EQ(r.code, 0) << r.err;
  fs::remove_all(out);
  // More bench threads than the machine runs: Embree would take fewer (and oneTBB said so in its
  // own words), so the run is refused.
  r = ptc({"bench", cube.string(), "--threads", "4096", "--out", (dir_ / "b").string()});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--threads: 4096 threads on a machine that runs"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("TBB"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "b"));
  // subdivide: a directory as --out is named as one; too many levels name --levels.
  fs::create_directories(dir_ / "outdir");
  r = ptc({"subdivide", cube.string(), "--out", (dir_ / "outdir").string()});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("outdir' is a directory"), std::string::npos) << r.err;
  const std::string armadillo = std::string(PTC_TEST_DATA) + "/meshes/armadillo.off";
  r = ptc({"subdivide", armadillo, "--levels", "8", "--out", (dir_ / "s.off").string()});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("armadillo.off: --levels: 8 levels of"), std::string::npos) << r.err;
  // ptc info's memory estimate takes the threads a run would take: --threads when given.
  r = ptc({"info", cube.string(), "--json", "--threads", "1"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["memory_estimate"]["threads"], 1);
  r = ptc({"info", ""});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("'': an empty file name"), std::string::npos) << r.err;
  for (const char* flag : {"--target-clusters", "--max-triangles"}) {
    r = ptc({"cluster", cube.string(), flag, "-1", "--out", (dir_ / "c").string()});
    EXPECT_EQ(r.code, 2) << flag << " " << r.err;
    EXPECT_NE(r.err.find(std::string(flag) + ": '-1' is not a whole number in [0, 4294967295]"), std::string::npos) << r.err;
  }
  // --target-clusters that stops nothing, or that the limits keep the contraction from reaching.
  r = ptc({"cluster", cube.string(), "--method", "contraction", "--target-clusters", "100", "--out", (dir_ / "tc").string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("--target-clusters 100 is not below the mesh's 12 triangles: it stopped nothing"), std::string::npos)
      << r.err;
  r = ptc({"cluster", cube.string(), "--method", "contraction", "--objective", "naive", "--max-count", "3",
           "--target-clusters", "1", "--out", (dir_ / "tc").string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("ptc: note: the contraction stopped at 12 clusters, above --target-clusters 1"), std::string::npos)
      << r.err;
  // triangles.csv saved by a spreadsheet, with a UTF-8 byte order mark.
  ASSERT_EQ(ptc({"cluster", cube.string(), "--out", (dir_ / "c").string()}).code, 0);
  const std::string csv = slurp(dir_ / "c" / "triangles.csv");
  std::ofstream(dir_ / "c" / "triangles.csv", std::ios::binary) << "\xEF\xBB\xBF" << csv;
  r = trace({"--clusters", (dir_ / "c").string()}, cube.string());
  EXPECT_EQ(r.code, 0) << r.err;
  fs::remove_all(out);
  // --data-dir that does not exist.
  r = trace({"--data-dir", (dir_ / "nowhere").string()}, "armadillo-twist");
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("missing: the data directory given by --data-dir, " + (dir_ / "nowhere").string() + ", does not exist"),
            std::string::npos)
      << r.err;
  // A frame directory whose numbers skip one.
  fs::create_directories(dir_ / "frames");
  fs::copy_file(cube, dir_ / "frames" / "frame_0000.off");
  fs::copy_file(cube, dir_ / "frames" / "frame_0002.off");
  r = trace({"--frames", "0:1"}, (dir_ / "frames").string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("the frame files' numbers are not consecutive (frame_0000.off is followed by frame_0002.off): "
                       "frames are the files in name order, so frame 1 reads frame_0002.off"),
            std::string::npos)
      << r.err;
  // Names whose counter is not their last number (a constant suffix): consecutive, no note.
  fs::create_directories(dir_ / "frames_v");
  fs::copy_file(cube, dir_ / "frames_v" / "f_0001_v2.off");
  fs::copy_file(cube, dir_ / "frames_v" / "f_0002_v2.off");
  {
    const RunResult v = ptc({"trace", (dir_ / "frames_v").string(), "--frames", "0:1", "--width", "8", "--height", "8",
                             "--out", (dir_ / "tv").string()});
    EXPECT_EQ(v.code, 0) << v.err;
    EXPECT_EQ(v.err.find("not consecutive"), std::string::npos) << v.err;
  }
  // The same command again with fewer frames: the later frames' files go, and that is said.
  r = trace({"--frames", "0:0"}, (dir_ / "frames").string());
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("ptc: note: replaced the previous output in " + out + " (its "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("shaded_0001.png"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("this run did not write them again"), std::string::npos) << r.err;
  r = trace({"--frames", "0:0"}, (dir_ / "frames").string());  // (the same files: nothing to say)
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err.find("replaced"), std::string::npos) << r.err;
  // One triangle is one triangle (not "1 triangles"), in the lines that count things.
  const auto one = write("one.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  r = ptc({"cluster", one.string(), "--out", (dir_ / "c1").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(one.string() + ": 1 triangle -> 1 cluster ("), std::string::npos) << r.out;
  r = ptc({"subdivide", one.string(), "--levels", "1", "--out", (dir_ / "one4.off").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(": 1 triangle, 3 vertices -> "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(": 4 triangles, 6 vertices ("), std::string::npos) << r.out;
  r = trace({"--threads", "1"}, one.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find(": 1 triangle (1 static, 0 moving; 1 part), "), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("8x8 pixels, 1 thread; "), std::string::npos) << r.out;
}

// The output of another command replaced by a run with the same --out is said, naming the
// command and the files that are gone (found by a new user: a `ptc cluster` output vanished
// under an experiment without a word); the same command again replaces silently, as documented.
TEST_F(Cli, ReplacingAnotherCommandsOutputIsSaid) {
  const auto mesh = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  const std::string out = (dir_ / "o").string();
  ASSERT_EQ(ptc({"cluster", mesh, "--out", out}).code, 0);
  const std::vector<std::string> sweep = {"experiment", "sweep", mesh, "--frames", "0:1", "--width", "8", "--height",
                                          "8", "--max-counts", "0,20", "--quiet", "--out", out};
  const auto r = ptc(sweep);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("ptc: note: replaced the output of `ptc cluster` in " + out +
                       " (its clusters.csv, clusters.ply, summary.json, triangles.csv are gone)"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "o" / "triangles.csv"));
  const auto again = ptc(sweep);
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(again.err.find("replaced the output"), std::string::npos) << again.err;
  // Another kind of experiment is another output too.
  const auto cmp = ptc({"experiment", "compare", mesh, "--configs", "standard,acc_growth", "--frames", "0:1", "--width",
                        "8", "--height", "8", "--quiet", "--out", out});
  ASSERT_EQ(cmp.code, 0) << cmp.err;
  EXPECT_NE(cmp.err.find("ptc: note: replaced the output of `ptc experiment sweep` in " + out + " (its sweep.csv, "
                         "sweep_summary.csv are gone)"),
            std::string::npos)
      << cmp.err;
}

}  // namespace

// A command started with its stdout closed (`>&-`) opens /dev/null there first: otherwise the next
// file ptc opens takes descriptor 1 and what it prints lands in it. viz's X display connection
// took it, its text went into the X protocol and the run hung in XCloseDisplay; the outputs of the
// other commands were written through descriptor 1. Now: the same triangles.csv as with stdout
// open, and viz ends (a timeout of 120 s would say 124).
TEST_F(Cli, AClosedStdoutIsNotReused) {
  const auto mesh = std::string(PTC_TEST_DATA) + "/meshes/mushroom.off";
  const std::string open_out = (dir_ / "open").string(), closed_out = (dir_ / "closed").string();
  ASSERT_EQ(ptc({"cluster", mesh, "--method", "growth", "--out", open_out}).code, 0);
  const std::vector<std::string> closed = {"timeout", "120", "sh", "-c", "exec \"$0\" \"$@\" >&-", PTC_BIN};
  const RunResult c = run(closed, {"cluster", mesh, "--method", "growth", "--out", closed_out});
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_EQ(slurp(dir_ / "closed" / "triangles.csv"), slurp(dir_ / "open" / "triangles.csv"));
  const RunResult v = run(closed, {"viz", "partition", mesh, "--clusters", open_out, "--width", "64", "--height", "64",
                                   "--out", (dir_ / "v").string()});
  EXPECT_EQ(v.code, 0) << v.err;
  EXPECT_TRUE(fs::exists(dir_ / "v" / "partition.png")) << v.err;
}

// Names of up to 255 bytes are legal; ptc's temporaries beside them (".NAME.tmp-PID-N") were not,
// so a name of 243-255 bytes was refused ("File name too long"), by subdivide after all its work.
TEST_F(Cli, TheLongestLegalNamesAreWritten) {
  const auto cube = write("cube.off", ptc::test::kCube).string();
  const std::string file = std::string(251, 'f') + ".off", dir = std::string(255, 'd');
  RunResult r = ptc({"subdivide", cube, "--out", (dir_ / file).string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(dir_ / file));
  r = ptc({"cluster", cube, "--out", (dir_ / dir).string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_regular_file(dir_ / dir / "triangles.csv"));
  r = ptc({"cluster", cube, "--out", (dir_ / dir).string()});  // replacing it: its ".old" too
  EXPECT_EQ(r.code, 0) << r.err;
  for (const auto& e : fs::directory_iterator(dir_)) EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos);
}

// A stdout that cannot take the text (a full device): exit 1 with the reason, and, when the
// output was committed before, that it is whole (a script sees the failure, not a lost output).
TEST_F(Cli, AFullStdoutIsSaidWithTheOutputsState) {
  const auto cube = write("cube.off", ptc::test::kCube).string();
  const std::vector<std::string> full = {"sh", "-c", "exec \"$0\" \"$@\" >/dev/full", PTC_BIN};
  RunResult r = run(full, {"info", cube, "--json"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(r.err, "ptc: error: cannot write to stdout: No space left on device\n");
  const std::string out = (dir_ / "c").string();
  r = run(full, {"cluster", cube, "--out", out});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("ptc: error: cannot write to stdout: No space left on device (" + out + " was written whole)"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "c" / "triangles.csv"));
  for (const std::vector<std::string>& help : {std::vector<std::string>{"--help"}, {"cluster", "--help"}, {"--version"}}) {
    r = run(full, help);
    EXPECT_EQ(r.code, 1) << help[0];
    // (the reason too: the short version text fails inside CLI11's own write, before the flush)
    EXPECT_NE(r.err.find("ptc: error: cannot write to stdout: No space left on device"), std::string::npos) << r.err;
  }
}

// A temporary of the output left by a run that no handler could clean up (kill -9) is said on the
// next run into that output and left alone (it may hold files the user had there); one of a
// process that still runs is not a leftover.
TEST_F(Cli, TemporariesOfAKilledRunAreSaid) {
  const auto cube = write("cube.off", ptc::test::kCube).string();
  const std::string out = (dir_ / "c").string();
  ASSERT_EQ(ptc({"cluster", cube, "--out", out}).code, 0);
  const RunResult sh = run({"sh", "-c", "echo $$"}, {});  // a process id that has ended
  const std::string dead = sh.out.substr(0, sh.out.find('\n'));
  const fs::path stale = dir_ / (".c.tmp-" + dead + "-0"), live = dir_ / (".c.tmp-" + std::to_string(getpid()) + "-0");
  fs::create_directory(stale);
  ptc::test::spit(stale / "notes.txt", "the user's notes\n");
  fs::create_directory(live);
  const RunResult r = ptc({"cluster", cube, "--out", out});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("ptc: note: " + stale.string() + " is left from an earlier run into " + out +
                       " that was killed (kill -9, a crash); ptc leaves it alone: files you had in " + out +
                       " may be inside"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find(live.filename().string()), std::string::npos) << r.err;
  EXPECT_EQ(slurp(stale / "notes.txt"), "the user's notes\n");
}

// An output in a directory that exists but takes no new files (/dev/fd, /proc) said the directory
// "does not exist", or only "cannot create the output directory".
TEST_F(Cli, ADirectoryThatTakesNoNewFilesIsNamedAsSuch) {
  const auto cube = write("cube.off", ptc::test::kCube).string();
  RunResult r = ptc({"subdivide", cube, "--out", "/dev/fd/7.off"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(r.err, "ptc: error: /dev/fd/7.off: cannot write it: the directory '/dev/fd' takes no new files\n");
  r = ptc({"cluster", cube, "--out", "/proc/self/clusters"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(r.err, "ptc: error: /proc/self/clusters: cannot write into its directory '/proc/self': it takes no new entries\n");
}
