// The per-cluster rows and CSV files of `ptc cluster` against independent recomputation.
#include "analysis/metrics/cluster_table.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <sstream>

#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"
#include "toolkit/mesh/mesh_report.h"
#include "toolkit/test_meshes.h"

namespace ptc {
namespace {

std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> f;
    std::istringstream ls(line);
    for (std::string x; std::getline(ls, x, ',');) f.push_back(x);
    rows.push_back(f);
  }
  return rows;
}

TEST(ClusterReport, RowsMatchMetricsRecomputedPerCluster) {
  const Mesh m = read_mesh(std::string(PTC_TEST_DATA) + "/meshes/elephant.off").mesh;
  ClusterConfig cfg;
  cfg.method = ClusterMethod::Growth;
  const Clustering c = cluster_mesh(m, cfg);
  const auto rows = cluster_rows(m, c, cfg);
  ASSERT_EQ(rows.size(), c.cluster_count());
  ClusterParams p;
  p.max_count = cfg.max_count;
  p.max_size = cfg.max_size;
  p.avg_sa = average_triangle_sphere_area(m.positions(), m.triangles());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto tris = c.triangles_of(k);
    const ClusterMetrics ref = cluster_metrics(m, tris, SphereMethod::Cgal);
    EXPECT_EQ(rows[k].m.triangles, tris.size());
    EXPECT_EQ(rows[k].m.vertices, c.vertices_of(k).size());
    EXPECT_EQ(rows[k].m.reg, ref.reg);
    // The rows read the clustering's vertex lists: the same values as the lists made from scratch.
    EXPECT_EQ(rows[k].m.sphere.radius, ref.sphere.radius) << k;
    EXPECT_EQ(rows[k].m.sphere.center, ref.sphere.center) << k;
    EXPECT_EQ(rows[k].m.box.lo, ref.box.lo) << k;
    EXPECT_EQ(rows[k].m.box.hi, ref.box.hi) << k;
    EXPECT_EQ(rows[k].m.area_p, ref.area_p) << k;
    EXPECT_EQ(rows[k].m.connectivity, ref.connectivity) << k;
    EXPECT_EQ(rows[k].acc, cluster_acc(ref, p)) << k;
    EXPECT_GT(rows[k].acc, 0.0) << "growth closes a cluster only while Acc stays positive";
  }
  // The AvgSA given by the caller (ptc cluster computes it once) gives the same rows, and is
  // the one used: a hundredth of the value changes Acc (sizeBound leaves its clamp at 1).
  const auto given = cluster_rows(m, c, cfg, p.avg_sa);
  const auto scaled = cluster_rows(m, c, cfg, 0.01 * p.avg_sa);
  ASSERT_EQ(given.size(), rows.size());
  std::size_t changed = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(given[k].acc, rows[k].acc) << k;
    changed += scaled[k].acc != rows[k].acc;
  }
  EXPECT_GT(changed, rows.size() / 2);
  // Without vertex lists (offsets dropped) the rows make them from the triangles: the same values.
  Clustering bare = c;
  bare.vertex_offsets.clear();
  bare.vertices.clear();
  const auto remade = cluster_rows(m, bare, cfg);
  ASSERT_EQ(remade.size(), rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(remade[k].m.vertices, rows[k].m.vertices) << k;
    EXPECT_EQ(remade[k].m.sphere.radius, rows[k].m.sphere.radius) << k;
    EXPECT_EQ(remade[k].acc, rows[k].acc) << k;
  }
  // clusters.csv: one row per cluster, values as computed (shortest round-trip text).
  const auto csv = parse_csv(clusters_table(rows).csv.str());
  ASSERT_EQ(csv.size(), rows.size() + 1);
  EXPECT_EQ(csv[0][0], "cluster_id");
  EXPECT_EQ(csv[0][4], "reg");
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(std::stoull(csv[k + 1][0]), k);
    EXPECT_EQ(std::stod(csv[k + 1][4]), rows[k].m.reg);
  }
  // triangles.csv: triangle_id,cluster_id in input order; every triangle once.
  const auto tcsv = parse_csv(triangles_table(c).csv.str());
  ASSERT_EQ(tcsv.size(), m.triangle_count() + 1);
  const auto label = c.cluster_of_triangle();
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    EXPECT_EQ(std::stoull(tcsv[t + 1][0]), t);
    EXPECT_EQ(std::stoull(tcsv[t + 1][1]), label[t]);
  }
  // Distributions equal summarize() over the column.
  const auto dist = cluster_distributions(rows);
  std::vector<double> reg;
  for (const auto& r : rows) reg.push_back(r.m.reg);
  const Summary s = summarize(reg);
  EXPECT_EQ(dist["reg"]["p95"].get<double>(), s.p95);
  EXPECT_EQ(dist["reg"]["min"].get<double>(), s.min);
  EXPECT_EQ(dist["reg"]["count"].get<std::size_t>(), rows.size());
}

TEST(ClusterReport, ASoupWithItsAdjacencyScoresLikeItsConnectedMesh) {
  // The elephant as a triangle soup (every corner its own vertex), clustered by coincident
  // corners: with the adjacency's triangles its rows equal, column for column, those of the
  // connected mesh clustered by edges (the same partition; the connected mesh is numbered by
  // first use, as the weld numbers it). Without, the vertices are the soup's own (3 a triangle).
  const Mesh e = test_meshes::load("elephant.off");
  const Mesh ref = test_meshes::by_first_use(e), soup = test_meshes::soup_of(e);
  ClusterConfig cfg;
  cfg.method = ClusterMethod::Growth;
  const Clustering cr = cluster_mesh(ref, cfg), cs = cluster_mesh(soup, cfg);
  ASSERT_EQ(cr.triangle_order, cs.triangle_order);
  const std::vector<Tri> adj = adjacency_triangles(soup, ClusterAdjacency::Auto);
  const auto want = cluster_rows(ref, cr, cfg), got = cluster_rows(soup, cs, cfg, std::nullopt, adj),
             own = cluster_rows(soup, cs, cfg);
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) {
    EXPECT_EQ(got[k].m.vertices, want[k].m.vertices) << k;
    EXPECT_EQ(got[k].m.triangles, want[k].m.triangles) << k;
    EXPECT_DOUBLE_EQ(got[k].m.connectivity, want[k].m.connectivity) << k;
    EXPECT_DOUBLE_EQ(got[k].m.reg, want[k].m.reg) << k;
    EXPECT_DOUBLE_EQ(got[k].m.sphere.radius, want[k].m.sphere.radius) << k;
    // The soup's sphere comes from its corners, each rest position three to six times: CGAL may
    // differ in the last bit, and Acc, a difference, shows it at ~1e-16 absolute.
    EXPECT_NEAR(got[k].acc, want[k].acc, 1e-12) << k;
    EXPECT_DOUBLE_EQ(got[k].reg_bound, want[k].reg_bound) << k;
    EXPECT_EQ(own[k].m.vertices, 3 * own[k].m.triangles) << k;
  }
  EXPECT_THROW((void)cluster_rows(soup, cs, cfg, std::nullopt, std::span<const Tri>(adj).subspan(1)),
               std::invalid_argument);
}

TEST(ClusterReport, NoObjectiveGivesNanAccAndNullDistribution) {
  const Mesh m({{0, 1, 2}, {0, 2, 3}}, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  ClusterConfig cfg;
  cfg.method = ClusterMethod::Growth;
  cfg.max_count = 0;
  cfg.max_size = 0;
  const Clustering c = cluster_mesh(m, cfg);
  ASSERT_EQ(c.cluster_count(), 2u);  // one triangle per cluster
  const auto rows = cluster_rows(m, c, cfg);
  EXPECT_TRUE(std::isnan(rows[0].acc));
  EXPECT_TRUE(cluster_distributions(rows)["acc"].is_null());
  EXPECT_EQ(cluster_distributions(rows)["triangles"]["max"].get<double>(), 1.0);
}

}  // namespace
}  // namespace ptc

namespace ptc {
namespace {

std::string read_whole(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The streamed triangles.csv and clusters.csv are the generic table's text byte for byte:
// triangles.csv for no triangles, one, a clustering over several 1 MiB blocks, labels up to
// 2^32 - 1; clusters.csv over several blocks, with nan and infinite values, and empty; a write
// that cannot start throws and leaves nothing behind.
TEST(ClusterReport, StreamedCsvFilesAreTheTablesText) {
  const auto dir = std::filesystem::temp_directory_path() / ("ptc_tri_csv_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::mt19937 rng(3);
  for (const std::size_t T : {std::size_t{0}, std::size_t{1}, std::size_t{77}, std::size_t{150000}}) {
    // Clusters as runs of random length with random ids (the last few at the top of the range).
    std::vector<std::uint32_t> label(T);
    for (std::size_t t = 0; t < T;) {
      const std::size_t len = 1 + rng() % 40;
      const std::uint32_t id = T > 100 && t + len >= T ? 0xffffffffu - static_cast<std::uint32_t>(rng() % 3)
                                                       : static_cast<std::uint32_t>(rng());
      for (std::size_t i = t; i < std::min(T, t + len); ++i) label[i] = id;
      t += len;
    }
    const Clustering c = clustering_from_labels(label, std::vector<Tri>(T, Tri{0, 1, 2}));
    const Table want = triangles_table(c);
    const auto path = dir / ("t" + std::to_string(T) + ".csv");
    EXPECT_EQ(write_triangles_csv(c.cluster_of_triangle(), path), want.schema.id());
    EXPECT_EQ(read_whole(path), want.csv.str()) << T;
    // The labels as given (not renumbered): the rows carry them verbatim.
    write_triangles_csv(label, path);
    const std::string text = read_whole(path);
    if (T > 0) {
      const std::string last = std::to_string(T - 1) + "," + std::to_string(label[T - 1]) + "\n";
      EXPECT_EQ(text.substr(text.size() - last.size()), last);
    }
  }
  // clusters.csv in blocks: the elephant subdivided once, in clusters of two triangles (several
  // MiB of text),
  // then rows with nan and infinite values and a default row.
  {
    const Mesh m = subdivide(read_mesh(std::string(PTC_TEST_DATA) + "/meshes/elephant.off").mesh,
                             SubdivisionScheme::Midpoint, 1);
    std::vector<std::uint32_t> pairs(m.triangle_count());
    for (std::size_t t = 0; t < pairs.size(); ++t) pairs[t] = static_cast<std::uint32_t>(t / 2);
    ClusterConfig cfg;
    std::vector<ClusterRow> rows = cluster_rows(m, clustering_from_labels(pairs, m.triangles()), cfg);
    ClusterRow odd = rows[0];
    odd.acc = std::numeric_limits<double>::quiet_NaN();
    odd.m.reg = std::numeric_limits<double>::infinity();
    odd.m.area = -std::numeric_limits<double>::infinity();
    rows.push_back(odd);
    rows.push_back(ClusterRow{});
    const Table want = clusters_table(rows);
    ASSERT_GT(want.csv.str().size(), std::size_t{2} << 20);  // three blocks at least
    const auto path = dir / "clusters.csv";
    EXPECT_EQ(write_clusters_csv(rows, path), want.schema.id());
    EXPECT_EQ(read_whole(path), want.csv.str());
    EXPECT_EQ(write_clusters_csv({}, path), want.schema.id());
    EXPECT_EQ(read_whole(path), clusters_table({}).csv.str());
  }
  EXPECT_THROW(write_triangles_csv(std::vector<std::uint32_t>{1, 2}, dir / "missing" / "t.csv"), InputError);
  EXPECT_THROW(write_clusters_csv({}, dir / "missing" / "c.csv"), InputError);
  EXPECT_FALSE(std::filesystem::exists(dir / "missing"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace ptc
