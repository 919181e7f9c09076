// Reading `ptc cluster`'s triangles.csv back for tracing: the writer's output reads back to the
// same clustering; every defect is an InputError naming the file and line.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <fstream>

#include "analysis/metrics/cluster_table.h"
#include "commands/cluster_files.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/core/error.h"
#include "toolkit/mesh/subdivision.h"

namespace fs = std::filesystem;
using ptc::Mesh;
using ptc::Vec3;

namespace {

// A strip of 2n triangles along x (triangle k shares an edge with k - 1 and k + 1).
Mesh strip(int n) {
  std::vector<Vec3> p;
  std::vector<ptc::Tri> t;
  for (int i = 0; i <= n; ++i) p.push_back(Vec3(i, 0, 0)), p.push_back(Vec3(i, 1, 0));
  for (int i = 0; i < n; ++i) {
    const auto a = std::uint32_t(2 * i);
    t.push_back({a, a + 2, a + 1});
    t.push_back({a + 1, a + 2, a + 3});
  }
  return Mesh(std::move(t), std::move(p));
}

class TraceClusters : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("ptc_trace_clusters_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& text) const {
    std::ofstream(dir_ / "triangles.csv", std::ios::binary) << text;
    return dir_;
  }
  // The message of the InputError thrown by read_clusters (fails the test if none).
  std::string error(const std::string& text, const Mesh& m) const {
    write(text);
    try {
      (void)ptc::read_clusters(dir_, m);
    } catch (const ptc::InputError& e) {
      const std::string w = e.what();
      EXPECT_EQ(w.find('\n'), std::string::npos);
      EXPECT_NE(w.find("triangles.csv"), std::string::npos) << w;
      return w;
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return "";
  }
  fs::path dir_;
};

}  // namespace

TEST_F(TraceClusters, WriterOutputReadsBackToTheSameClustering) {
  Mesh m = ptc::subdivide(strip(6), ptc::SubdivisionScheme::Midpoint, 2);
  ptc::ClusterConfig cc;
  cc.method = ptc::ClusterMethod::Growth;
  cc.max_count = 8;
  cc.max_size = 8;
  const ptc::Clustering c = ptc::cluster_mesh(m, cc);
  ASSERT_GT(c.cluster_count(), 3u);
  write(ptc::triangles_table(c).csv.str());
  const ptc::Clustering back = ptc::read_clusters(dir_, m);
  EXPECT_EQ(back.cluster_of_triangle(), c.cluster_of_triangle());
  EXPECT_EQ(back.triangle_order, c.triangle_order);
  EXPECT_EQ(back.vertices, c.vertices);
  // The file itself can be named too.
  EXPECT_EQ(ptc::read_clusters(dir_ / "triangles.csv", m).triangle_offsets, c.triangle_offsets);
}

TEST_F(TraceClusters, RowsInAnyOrderCrlfAndSparseIds) {
  const Mesh m = strip(2);  // 4 triangles
  const ptc::Clustering c = ptc::read_clusters(write("triangle_id,cluster_id\r\n3,900\r\n0,7\r\n2,900\r\n1,7\r\n"), m);
  ASSERT_EQ(c.cluster_count(), 2u);
  EXPECT_EQ(c.cluster_of_triangle(), (std::vector<std::uint32_t>{0, 0, 1, 1}));
}

TEST_F(TraceClusters, DefectsNameFileLineAndElement) {
  const Mesh m = strip(2);  // 4 triangles: 0-1-2-3 in a chain
  const std::string h = "triangle_id,cluster_id\n";
  EXPECT_NE(error("", m).find("empty"), std::string::npos);
  EXPECT_NE(error("tri,cluster\n0,0\n", m).find("line 1: header"), std::string::npos);
  EXPECT_NE(error(h + "0,0\n1,0\n2,0\n", m).find("triangle 3: missing"), std::string::npos);            // too few
  EXPECT_NE(error(h + "0,0\n1,0\n2,0\n3,0\n4,0\n", m).find("line 6: triangle 4: out of range"), std::string::npos);
  EXPECT_NE(error(h + "0,0\n1,0\n1,0\n3,0\n", m).find("line 4: triangle 1: listed twice (first on line 3)"),
            std::string::npos);
  EXPECT_NE(error(h + "0,0\n1,x\n2,0\n3,0\n", m).find("line 3: triangle 1: cluster id 'x'"), std::string::npos);
  EXPECT_NE(error(h + "0,0\n-1,0\n2,0\n3,0\n", m).find("line 3"), std::string::npos);
  EXPECT_NE(error(h + "0,0\n1,0,5\n2,0\n3,0\n", m).find("line 3"), std::string::npos);
  EXPECT_NE(error(h + "0,0\n1,4294967296\n2,0\n3,0\n", m).find("line 3"), std::string::npos);
  EXPECT_NE(error(h + "0,0\n\n1,0\n2,0\n3,0\n", m).find("line 3: empty line"), std::string::npos);
  // Cluster 5 = triangles 0 and 3: not connected through shared edges (named at 3's line).
  EXPECT_NE(error(h + "0,5\n1,6\n2,6\n3,5\n", m).find("line 5: triangle 3: cluster 5 is not connected"), std::string::npos);
  // No such file / directory.
  try {
    (void)ptc::read_clusters(dir_ / "nowhere", m);
    ADD_FAILURE();
  } catch (const ptc::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos);
  }
}

// The file is read in blocks of 1 MiB: rows that straddle blocks, a row longer than a block (its
// cluster id after 3 MiB of spaces), no final newline, a final empty line, two of them.
TEST_F(TraceClusters, RowsAcrossBlocksAndLongRows) {
  const int n = 150000;  // 300,000 triangles: about 4 MB of rows, so rows straddle the blocks
  const Mesh m = strip(n);
  std::string csv = "triangle_id,cluster_id\n";
  std::vector<std::uint32_t> want(2 * n);
  for (int t = 0; t < 2 * n; ++t) {
    want[t] = static_cast<std::uint32_t>(t / 10);  // runs of 10 neighbours along the strip
    csv += std::to_string(t) + "," + std::to_string(1000 + t / 10) + "\n";
  }
  const auto pos = csv.find("\n77777,") + 1;  // one row padded beyond a block
  csv.insert(csv.find(',', pos) + 1, std::string(3 << 20, ' '));
  ptc::Clustering c = ptc::read_clusters(write(csv), m);
  EXPECT_EQ(c.cluster_count(), static_cast<std::size_t>(2 * n / 10));
  EXPECT_EQ(c.cluster_of_triangle(), want);
  csv.pop_back();  // no final newline
  c = ptc::read_clusters(write(csv), m);
  EXPECT_EQ(c.cluster_of_triangle(), want);
  EXPECT_EQ(ptc::read_clusters(write(csv + "\n\n"), m).cluster_of_triangle(), want);  // one final empty line
  const std::string e = error(csv + "\n\n\n", m);
  EXPECT_NE(e.find("line " + std::to_string(2 * n + 2) + ": empty line"), std::string::npos) << e;
  // An error far into the file names its line, and a duplicate its first line.
  std::string dup = csv;
  dup.replace(dup.rfind("\n") + 1, std::string::npos, "5,1000");
  const std::string d = error(dup, m);
  EXPECT_NE(d.find("line " + std::to_string(2 * n + 1) + ": triangle 5: listed twice (first on line 7)"), std::string::npos)
      << d;
}

// CRLF rows whose '\r' ends one block and '\n' starts the next; three triangles on one edge
// (labels A, B, A: the two A triangles are connected through it).
TEST_F(TraceClusters, CrlfAcrossABlockAndANonManifoldEdge) {
  const Mesh m = strip(2);
  std::string csv = "triangle_id,cluster_id\r\n0,7\r\n1,7\r\n2,9\r\n";
  const std::string last = "3,9";
  csv += last + std::string((1u << 20) - 1 - csv.size() - last.size(), ' ') + "\r\n";  // '\r' at 2^20 - 1
  ASSERT_EQ(csv[(1u << 20) - 1], '\r');
  EXPECT_EQ(ptc::read_clusters(write(csv), m).cluster_of_triangle(), (std::vector<std::uint32_t>{0, 0, 1, 1}));

  // Vertices 0 and 1 carry three triangles (a book of three pages); pages 0 and 2 form one cluster.
  const Mesh book(std::vector<ptc::Tri>{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}},
                  std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}});
  EXPECT_EQ(ptc::read_clusters(write("triangle_id,cluster_id\n0,5\n1,6\n2,5\n"), book).cluster_of_triangle(),
            (std::vector<std::uint32_t>{0, 1, 0}));
}

TEST_F(TraceClusters, ClustersOfAnotherMeshWithTheSameTriangleCountAreRefused) {
  // Same triangle count, other topology: triangle order reversed pairs up non-neighbours.
  const Mesh m = strip(4);  // 8 triangles
  std::vector<ptc::Tri> t(m.triangles().begin(), m.triangles().end());
  std::swap(t[1], t[6]);
  const Mesh other(t, std::vector<Vec3>(m.positions().begin(), m.positions().end()));
  const std::string csv = "triangle_id,cluster_id\n0,0\n1,0\n2,1\n3,1\n4,2\n5,2\n6,3\n7,3\n";
  write(csv);
  EXPECT_NO_THROW((void)ptc::read_clusters(dir_, m));
  EXPECT_NE(error(csv, other).find("is not connected"), std::string::npos);
}

TEST_F(TraceClusters, ASoupReadsBackConnectedByCoincidentCorners) {
  // The strip as a triangle soup (every corner its own vertex): pairs of neighbours share sides by
  // position only. A clustering made with adjacency by positions reads back, cluster for cluster;
  // one whose cluster is connected not even by positions is refused, naming the triangle.
  const Mesh m = strip(4);
  std::vector<Vec3> p;
  std::vector<ptc::Tri> t;
  for (const ptc::Tri& f : m.triangles()) {
    const auto b = static_cast<std::uint32_t>(p.size());
    for (std::uint32_t v : f) p.push_back(m.positions()[v]);
    t.push_back({b, b + 1, b + 2});
  }
  const Mesh soup(std::move(t), std::move(p));
  const std::string csv = "triangle_id,cluster_id\n0,0\n1,0\n2,1\n3,1\n4,1\n5,2\n6,2\n7,2\n";
  write(csv);
  const ptc::Clustering c = ptc::read_clusters(dir_, soup);
  ASSERT_EQ(c.cluster_count(), 3u);
  EXPECT_EQ(std::vector<std::uint32_t>(c.triangles_of(1).begin(), c.triangles_of(1).end()),
            (std::vector<std::uint32_t>{2, 3, 4}));
  EXPECT_EQ(c.vertices_of(1).size(), 9u);  // the soup's own vertices
  EXPECT_NE(error("triangle_id,cluster_id\n0,0\n1,1\n2,1\n3,0\n4,2\n5,2\n6,2\n7,2\n", soup)
                .find("line 5: triangle 3: cluster 0 is not connected through shared sides, not even by coincident"),
            std::string::npos);
}

// The connectivity check against a brute force, item by item: random labellings (grown regions,
// some with a triangle moved to another label, so that a cluster falls apart) on a mesh with a
// non-manifold edge (a fin of three triangles on one side), a triangle with a repeated corner, a
// duplicated triangle and a lone triangle. The brute force walks each cluster from its first
// triangle through triangles of the same label that share two distinct corners; read_clusters
// must accept exactly the labellings where every cluster is reached whole, and otherwise name the
// first triangle (ascending) of the first cluster (by first triangle) that is not reached.
TEST_F(TraceClusters, ConnectivityAgreesWithABruteForceWalk) {
  Mesh grid = ptc::subdivide(strip(3), ptc::SubdivisionScheme::Midpoint, 1);  // 24 triangles
  std::vector<ptc::Tri> t(grid.triangles().begin(), grid.triangles().end());
  std::vector<Vec3> p(grid.positions().begin(), grid.positions().end());
  const auto v = [&](Vec3 x) {
    p.push_back(x);
    return static_cast<std::uint32_t>(p.size() - 1);
  };
  const ptc::Tri e = t[5];
  t.push_back({e[0], e[1], v(Vec3(0.3, 0.4, 2.0))});   // a third triangle on t[5]'s first side
  t.push_back({e[1], e[0], v(Vec3(0.2, 0.7, -2.0))});  // and a fourth
  t.push_back({e[2], e[2], t[9][1]});                   // a repeated corner (a segment)
  t.push_back(t[12]);                                   // a duplicate
  const std::uint32_t a = v(Vec3(9, 9, 9)), b = v(Vec3(9, 10, 9)), c = v(Vec3(10, 9, 9));
  t.push_back({a, b, c});  // alone
  const Mesh m(t, p);  // every vertex at a position of its own: adjacency by positions is the same
  const std::size_t T = t.size();
  auto share_side = [&](std::size_t x, std::size_t y) {  // a side {s0, s1}, s0 != s1, of both
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t s0 = t[y][i], s1 = t[y][(i + 1) % 3], r0 = t[x][k], r1 = t[x][(k + 1) % 3];
        if (s0 != s1 && ((r0 == s0 && r1 == s1) || (r0 == s1 && r1 == s0))) return true;
      }
    return false;
  };
  std::mt19937 rng(7);
  int refused = 0, accepted = 0;
  for (int trial = 0; trial < 300; ++trial) {
    // Regions grown from a few random seeds, then maybe one triangle moved to another label.
    const int k = 1 + static_cast<int>(rng() % 5);
    std::vector<int> label(T, -1);
    std::vector<std::size_t> queue;
    for (int s = 0; s < k; ++s) {
      const std::size_t seed = rng() % T;
      if (label[seed] < 0) label[seed] = s, queue.push_back(seed);
    }
    for (std::size_t q = 0; q < queue.size(); ++q)
      for (std::size_t y = 0; y < T; ++y)
        if (label[y] < 0 && share_side(queue[q], y)) label[y] = label[queue[q]], queue.push_back(y);
    for (std::size_t x = 0; x < T; ++x)
      if (label[x] < 0) label[x] = 100 + static_cast<int>(x);  // unreached: a cluster of its own
    if (rng() % 2) label[rng() % T] = static_cast<int>(rng() % static_cast<unsigned>(k));
    std::string csv = "triangle_id,cluster_id\n";
    for (std::size_t x = 0; x < T; ++x) csv += std::to_string(x) + "," + std::to_string(label[x]) + "\n";

    // The brute force: clusters in the order of their first triangles.
    std::string want;
    std::vector<bool> done(T, false);
    for (std::size_t first = 0; first < T && want.empty(); ++first) {
      if (done[first]) continue;
      std::vector<bool> reached(T, false);
      std::vector<std::size_t> walk{first};
      reached[first] = true;
      for (std::size_t q = 0; q < walk.size(); ++q)
        for (std::size_t y = 0; y < T; ++y)
          if (!reached[y] && label[y] == label[first] && share_side(walk[q], y)) reached[y] = true, walk.push_back(y);
      for (std::size_t y = 0; y < T; ++y) {
        if (label[y] != label[first]) continue;
        done[y] = true;
        if (!reached[y] && want.empty())
          want = "line " + std::to_string(y + 2) + ": triangle " + std::to_string(y) + ": cluster " +
                 std::to_string(label[y]) + " is not connected through shared sides, not even by coincident corners "
                 "(triangle " + std::to_string(first) + " of the same cluster cannot be reached";
      }
    }
    if (want.empty()) {
      ++accepted;
      write(csv);
      const ptc::Clustering got = ptc::read_clusters(dir_, m);
      for (std::size_t x = 0; x < T; ++x)
        for (std::size_t y = 0; y < T; ++y)
          ASSERT_EQ(got.cluster_of_triangle()[x] == got.cluster_of_triangle()[y], label[x] == label[y]) << csv;
    } else {
      ++refused;
      const std::string got = error(csv, m);
      EXPECT_NE(got.find(want), std::string::npos) << got << "\nwanted: " << want << "\n" << csv;
    }
  }
  EXPECT_GT(accepted, 50);
  EXPECT_GT(refused, 50);
}

// Clusters of very different sizes one after the other (the side table grows and is reused): a
// strip of 20,000 triangles cut into runs of 1, 2, 3, ... triangles reads back; the same with
// one triangle of the longest run given to the next run's cluster splits that run, and the
// error names the first triangle after the cut.
TEST_F(TraceClusters, ClustersOfGrowingSizesAndOneCutInTheLargest) {
  const Mesh m = strip(10000);
  const std::size_t T = m.triangle_count();
  std::vector<std::uint32_t> label(T);
  std::vector<std::size_t> run_start;
  for (std::size_t t = 0, len = 1, id = 0; t < T; t += len, ++len, ++id) {
    run_start.push_back(t);
    for (std::size_t i = t; i < std::min(T, t + len); ++i) label[i] = static_cast<std::uint32_t>(id);
  }
  auto csv_of = [&](const std::vector<std::uint32_t>& l) {
    std::string s = "triangle_id,cluster_id\n";
    for (std::size_t t = 0; t < T; ++t) s += std::to_string(t) + "," + std::to_string(l[t]) + "\n";
    return s;
  };
  const ptc::Clustering c = ptc::read_clusters(write(csv_of(label)), m);
  ASSERT_EQ(c.cluster_count(), run_start.size());
  EXPECT_EQ(c.cluster_of_triangle(), label);
  // The longest complete run: [run_start[n - 2], run_start[n - 1]); its middle triangle moves to
  // the last run's cluster (and is cut off from it too, so only the first failure is named).
  const std::size_t n = run_start.size(), lo = run_start[n - 2], hi = run_start[n - 1], mid = (lo + hi) / 2;
  label[mid] = label[hi];
  const std::string e = error(csv_of(label), m);
  EXPECT_NE(e.find("line " + std::to_string(mid + 3) + ": triangle " + std::to_string(mid + 1) + ": cluster " +
                   std::to_string(label[lo]) + " is not connected"),
            std::string::npos)
      << e;
}

// A cluster beyond the side table's limit (its sides sorted instead): a strip of 200,000
// triangles as one cluster of 150,000 and one of 50,000 reads back; with the middle triangle of
// the large one moved to the small one, the large one is cut there and the error names the
// triangle after the cut.
TEST_F(TraceClusters, AHugeClusterSortsItsSides) {
  const Mesh m = strip(100000);
  const std::size_t T = m.triangle_count(), big = 150000;
  std::vector<std::uint32_t> label(T);
  for (std::size_t t = 0; t < T; ++t) label[t] = t < big ? 0u : 1u;
  auto csv_of = [&](const std::vector<std::uint32_t>& l) {
    std::string s = "triangle_id,cluster_id\n";
    for (std::size_t t = 0; t < T; ++t) s += std::to_string(t) + "," + std::to_string(l[t]) + "\n";
    return s;
  };
  EXPECT_EQ(ptc::read_clusters(write(csv_of(label)), m).cluster_of_triangle(), label);
  label[big / 2] = 1;
  const std::string e = error(csv_of(label), m);
  EXPECT_NE(e.find("line " + std::to_string(big / 2 + 3) + ": triangle " + std::to_string(big / 2 + 1) +
                   ": cluster 0 is not connected"),
            std::string::npos)
      << e;
}

// The parameters of a given clustering come from ptc cluster's manifest beside triangles.csv: no
// manifest, or one that is not ptc cluster's (not JSON, another schema), gives the defaults and
// says which; an edited ptc cluster manifest is an error naming the field (found by a new user:
// a broken manifest was recorded as "no manifest", and max_count -5 gave the defaults silently,
// recorded as read from the file).
TEST_F(TraceClusters, ClusteringParametersComeFromPtcClustersManifestOrAreSaidToBeDefaults) {
  write("triangle_id,cluster_id\n0,0\n1,0\n");
  auto info_with = [&](const std::string& manifest) {
    fs::remove(dir_ / "manifest.json");
    if (!manifest.empty()) std::ofstream(dir_ / "manifest.json", std::ios::binary) << manifest;
    return ptc::clustering_info(dir_);
  };
  ptc::ClusteringInfo ci = info_with("");
  EXPECT_FALSE(ci.from_manifest);
  EXPECT_EQ(ci.from, "defaults (no manifest.json beside triangles.csv)");
  ci = info_with("{broken");
  EXPECT_FALSE(ci.from_manifest);
  EXPECT_EQ(ci.from, "defaults (" + (dir_ / "manifest.json").string() + " is not ptc cluster's manifest: not valid JSON)");
  ci = info_with(R"({"schema": "someone-else/1", "parameters": {"max_count": 7}})");
  EXPECT_FALSE(ci.from_manifest);
  EXPECT_EQ(ci.cfg.max_count, ptc::ClusterConfig{}.max_count);
  ci = info_with(R"({"schema": "ptc-cluster/1", "parameters": {"max_count": 7, "max_size": 9.5, "method": "contraction", "objective": "gwh01"}})");
  EXPECT_TRUE(ci.from_manifest);
  EXPECT_EQ(ci.cfg.max_count, 7u);
  EXPECT_EQ(ci.cfg.max_size, 9.5);
  EXPECT_EQ(ci.cfg.method, ptc::ClusterMethod::Contraction);
  EXPECT_EQ(ci.cfg.objective, ptc::ObjectiveKind::Gwh01);
  for (const auto& [manifest, field] : std::vector<std::pair<std::string, std::string>>{
           {R"({"schema": "ptc-cluster/1", "parameters": {"max_count": -5}})", "parameters.max_count"},
           {R"({"schema": "ptc-cluster/1", "parameters": {"max_size": "x"}})", "parameters.max_size"},
           {R"({"schema": "ptc-cluster/1", "parameters": {"method": "melt"}})", "parameters.method"},
           {R"({"schema": "ptc-cluster/1", "parameters": {"objective": 3}})", "parameters.objective"},
           {R"({"schema": "ptc-cluster/1"})", "parameters"}}) {
    try {
      (void)info_with(manifest);
      ADD_FAILURE() << "no error for " << manifest;
    } catch (const ptc::InputError& e) {
      EXPECT_EQ(e.file(), (dir_ / "manifest.json").string());
      EXPECT_EQ(e.element(), field) << manifest;
    }
  }
}
