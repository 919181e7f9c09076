// The clustering result type (toolkit/clustering/clustering.h) against independent answers, item
// by item: clustering_from_labels against a brute-force grouping, validate() against a
// brute-force validity check and against one hand-made violation of every kind, split_disconnected
// against brute-force components. Degenerate inputs first; randomness is seeded.
#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"

#include <gtest/gtest.h>
#include <oneapi/tbb/global_control.h>

#include <algorithm>
#include <deque>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace ptc {
namespace {

using Ids = std::vector<std::uint32_t>;

// ---------------------------------------------------------------------------------------------
// Small meshes (topology only: validate and split_disconnected never read positions).

// Grid of nx * ny quads, two triangles each, over (nx+1)(ny+1) vertices.
std::vector<Tri> grid(std::uint32_t nx, std::uint32_t ny) {
  std::vector<Tri> t;
  for (std::uint32_t y = 0; y < ny; ++y)
    for (std::uint32_t x = 0; x < nx; ++x) {
      const std::uint32_t a = y * (nx + 1) + x, b = a + 1, c = a + nx + 1, d = c + 1;
      t.push_back({a, b, d});
      t.push_back({a, d, c});
    }
  return t;
}

// A grid plus the hard cases of docs/mesh_policy.md: a collapsed triangle (a, a, a), triangles
// with one repeated index, a duplicate and a reversed duplicate, a non-manifold fan on one edge
// and a separate component.
std::vector<Tri> hard_mesh() {
  std::vector<Tri> t = grid(3, 2);  // vertices 0..11
  t.push_back({5, 5, 5});
  t.push_back({0, 0, 1});
  t.push_back({1, 2, 2});
  t.push_back(t[0]);
  t.push_back({t[1][0], t[1][2], t[1][1]});
  for (std::uint32_t k = 0; k < 4; ++k) t.push_back({0, 4, 12 + k});  // fan on edge 0-4
  t.push_back({20, 21, 22});                                             // separate component
  t.push_back({21, 22, 23});
  return t;
}

// ---------------------------------------------------------------------------------------------
// Independent answers.

// Brute-force grouping: clusters = label classes, ordered by smallest triangle id.
std::vector<Ids> brute_groups(const Ids& labels) {
  std::map<std::uint32_t, Ids> by_label;
  for (std::uint32_t t = 0; t < labels.size(); ++t) by_label[labels[t]].push_back(t);
  std::vector<Ids> g;
  for (auto& [l, ts] : by_label) g.push_back(ts);
  std::sort(g.begin(), g.end(), [](const Ids& a, const Ids& b) { return a.front() < b.front(); });
  return g;
}

Ids brute_vertices(const Ids& ts, const std::vector<Tri>& tris) {
  std::set<std::uint32_t> v;
  for (auto t : ts) v.insert(tris[t].begin(), tris[t].end());
  return Ids(v.begin(), v.end());
}

// Do triangles s and t share an undirected edge {a, b}, a != b? (Straight from the definition.)
bool share_edge(const Tri& s, const Tri& t) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const std::uint32_t a = s[i], b = s[(i + 1) % 3], c = t[j], d = t[(j + 1) % 3];
      if (a != b && ((a == c && b == d) || (a == d && b == c))) return true;
    }
  return false;
}

// Edge-connected components of a set of triangles by breadth-first search over all pairs.
std::vector<Ids> brute_components(const Ids& ts, const std::vector<Tri>& tris) {
  std::vector<bool> done(ts.size(), false);
  std::vector<Ids> comps;
  for (std::size_t s = 0; s < ts.size(); ++s) {
    if (done[s]) continue;
    Ids comp;
    std::deque<std::size_t> q{s};
    done[s] = true;
    while (!q.empty()) {
      const std::size_t i = q.front();
      q.pop_front();
      comp.push_back(ts[i]);
      for (std::size_t j = 0; j < ts.size(); ++j)
        if (!done[j] && share_edge(tris[ts[i]], tris[ts[j]])) {
          done[j] = true;
          q.push_back(j);
        }
    }
    std::sort(comp.begin(), comp.end());
    comps.push_back(comp);
  }
  return comps;
}

// Every invariant of validate(), checked the slow and obvious way.
bool brute_valid(const Clustering& c, const std::vector<Tri>& tris, const ClusterLimits& lim) {
  const auto& to = c.triangle_offsets;
  const auto& vo = c.vertex_offsets;
  if (to.empty() || vo.size() != to.size() || to.front() != 0 || vo.front() != 0) return false;
  if (to.back() != c.triangle_order.size() || vo.back() != c.vertices.size()) return false;
  for (std::size_t k = 0; k + 1 < to.size(); ++k)
    if (to[k + 1] <= to[k] || vo[k + 1] < vo[k]) return false;  // decreasing, or an empty cluster
  if (c.triangle_order.size() != tris.size()) return false;
  std::set<std::uint32_t> all(c.triangle_order.begin(), c.triangle_order.end());
  if (all.size() != tris.size() || (!all.empty() && *all.rbegin() >= tris.size())) return false;
  for (std::size_t k = 0; k + 1 < to.size(); ++k) {
    const Ids ts(c.triangle_order.begin() + to[k], c.triangle_order.begin() + to[k + 1]);
    if (!std::is_sorted(ts.begin(), ts.end())) return false;
    const Ids vs(c.vertices.begin() + vo[k], c.vertices.begin() + vo[k + 1]);
    if (vs != brute_vertices(ts, tris)) return false;
    if (brute_components(ts, tris).size() != 1) return false;
    if (lim.max_triangles && ts.size() > lim.max_triangles) return false;
    if (lim.max_vertices && vs.size() > lim.max_vertices) return false;
  }
  return true;
}

// A clustering built by hand from groups (no call into the code under test).
Clustering from_groups(const std::vector<Ids>& groups, const std::vector<Tri>& tris) {
  Clustering c;
  for (const Ids& g : groups) {
    c.triangle_order.insert(c.triangle_order.end(), g.begin(), g.end());
    c.triangle_offsets.push_back(static_cast<std::uint32_t>(c.triangle_order.size()));
    const Ids v = brute_vertices(g, tris);
    c.vertices.insert(c.vertices.end(), v.begin(), v.end());
    c.vertex_offsets.push_back(static_cast<std::uint32_t>(c.vertices.size()));
  }
  return c;
}

void expect_equals_groups(const Clustering& c, const std::vector<Ids>& groups, const std::vector<Tri>& tris) {
  ASSERT_EQ(c.cluster_count(), groups.size());
  ASSERT_EQ(c.vertex_offsets.size(), groups.size() + 1);
  for (std::size_t k = 0; k < groups.size(); ++k) {
    const auto ts = c.triangles_of(k);
    EXPECT_EQ(Ids(ts.begin(), ts.end()), groups[k]) << "cluster " << k;
    const auto vs = c.vertices_of(k);
    EXPECT_EQ(Ids(vs.begin(), vs.end()), brute_vertices(groups[k], tris)) << "cluster " << k;
  }
}

bool has_issue(const std::vector<std::string>& issues, const std::string& text) {
  return std::any_of(issues.begin(), issues.end(), [&](const std::string& s) { return s.find(text) != std::string::npos; });
}

std::string joined(const std::vector<std::string>& issues) {
  std::string s;
  for (const auto& i : issues) s += i + "\n";
  return s;
}

// ---------------------------------------------------------------------------------------------
// clustering_from_labels

TEST(ClusteringFromLabels, EmptyInputGivesNoClusters) {
  const Clustering c = clustering_from_labels({}, {});
  EXPECT_EQ(c.cluster_count(), 0u);
  EXPECT_EQ(c.triangle_offsets, Ids{0});
  EXPECT_EQ(c.vertex_offsets, Ids{0});
  EXPECT_TRUE(c.triangle_order.empty());
  EXPECT_TRUE(c.cluster_of_triangle().empty());
  EXPECT_TRUE(validate(c, {}).empty());
}

TEST(ClusteringFromLabels, SizeMismatchThrows) {
  const std::vector<Tri> tris = grid(1, 1);
  const Ids labels{0};
  EXPECT_THROW((void)clustering_from_labels(labels, tris), std::invalid_argument);
}

TEST(ClusteringFromLabels, DegenerateTrianglesListTheirDistinctVerticesOnce) {
  const std::vector<Tri> tris{{4, 4, 4}, {7, 2, 7}, {2, 7, 4}};
  const Clustering c = clustering_from_labels(Ids{9, 3, 9}, tris);
  expect_equals_groups(c, {{0, 2}, {1}}, tris);
  EXPECT_EQ(Ids(c.vertices_of(0).begin(), c.vertices_of(0).end()), (Ids{2, 4, 7}));
  EXPECT_EQ(Ids(c.vertices_of(1).begin(), c.vertices_of(1).end()), (Ids{2, 7}));
}

TEST(ClusteringFromLabels, MatchesBruteForceGroupingOnRandomLabels) {
  std::mt19937 rng(12345);
  const std::vector<Tri> tris = hard_mesh();
  for (int trial = 0; trial < 200; ++trial) {
    // Label ranges from "all equal" to "all distinct", including the extreme 32-bit values.
    const std::uint32_t range = std::uniform_int_distribution<std::uint32_t>(1, 30)(rng);
    Ids labels(tris.size());
    for (auto& l : labels) {
      l = std::uniform_int_distribution<std::uint32_t>(0, range - 1)(rng);
      if (l == 0) l = 0xffffffffu;
      if (l == 1) l = 0x80000000u;
    }
    const Clustering c = clustering_from_labels(labels, tris);
    expect_equals_groups(c, brute_groups(labels), tris);
    // cluster_of_triangle is the inverse of the grouping, item by item.
    const Ids of = c.cluster_of_triangle();
    ASSERT_EQ(of.size(), tris.size());
    for (std::size_t k = 0; k < c.cluster_count(); ++k)
      for (auto t : c.triangles_of(k)) EXPECT_EQ(of[t], k);
    // Renaming the labels (a random bijection) changes nothing, bit for bit.
    std::map<std::uint32_t, std::uint32_t> rename;
    for (auto l : labels) rename.emplace(l, 0);
    Ids fresh(rename.size());
    std::iota(fresh.begin(), fresh.end(), 1000u);
    std::shuffle(fresh.begin(), fresh.end(), rng);
    std::size_t i = 0;
    for (auto& [l, r] : rename) r = fresh[i++];
    Ids renamed(labels.size());
    for (std::size_t t = 0; t < labels.size(); ++t) renamed[t] = rename[labels[t]];
    const Clustering d = clustering_from_labels(renamed, tris);
    EXPECT_EQ(d.triangle_order, c.triangle_order);
    EXPECT_EQ(d.triangle_offsets, c.triangle_offsets);
    EXPECT_EQ(d.vertices, c.vertices);
    EXPECT_EQ(d.vertex_offsets, c.vertex_offsets);
  }
}

TEST(ClusterOfTriangle, GarbageDoesNotCrashAndMarksMissingTriangles) {
  Clustering c;
  c.triangle_order = {2, 99, 0, 0};
  c.triangle_offsets = {0, 3, 1, 50};  // decreasing, then past the end
  const Ids of = c.cluster_of_triangle();
  ASSERT_EQ(of.size(), 4u);
  EXPECT_EQ(of[1], kNoCluster);
  EXPECT_EQ(of[3], kNoCluster);
  EXPECT_EQ(of[2], 0u);
  EXPECT_EQ(of[0], 2u);  // in clusters 0 and 2: the last one
  c.triangle_offsets.clear();
  EXPECT_EQ(c.cluster_of_triangle(), Ids(4, kNoCluster));
}

// ---------------------------------------------------------------------------------------------
// validate: every kind of violation, each named.

struct ValidateFixture : ::testing::Test {
  // grid(3, 2) = 12 triangles; edge neighbours: 0-1 0-3 1-6 2-3 2-5 3-8 4-5 5-10 6-7 6-9 8-9
  // 8-11 10-11. Four connected clusters of three triangles and five vertices each.
  std::vector<Tri> tris = grid(3, 2);
  std::vector<Ids> groups{{0, 1, 3}, {2, 4, 5}, {6, 7, 9}, {8, 10, 11}};
  Clustering good = from_groups(groups, tris);

  std::vector<std::string> check(const Clustering& c, ClusterLimits lim = {}) {
    auto issues = validate(c, tris, lim, 100);
    EXPECT_EQ(issues.empty(), brute_valid(c, tris, lim)) << joined(issues);
    return issues;
  }
};

TEST_F(ValidateFixture, ValidClusteringPasses) {
  ASSERT_TRUE(brute_valid(good, tris, {}));
  EXPECT_TRUE(check(good).empty());
  EXPECT_TRUE(check(good, {3, 5}).empty());
  // One triangle per cluster, and one cluster for everything, are valid too.
  std::vector<Ids> singles;
  for (std::uint32_t t = 0; t < tris.size(); ++t) singles.push_back({t});
  EXPECT_TRUE(check(from_groups(singles, tris), {1, 3}).empty());
  EXPECT_TRUE(check(from_groups({{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}}, tris)).empty());
}

TEST_F(ValidateFixture, MissingTriangle) {
  Clustering c = from_groups({{0, 1, 3}, {2, 4, 5}, {6, 7, 9}, {8, 11}}, tris);
  const auto issues = check(c);
  EXPECT_EQ(issues, std::vector<std::string>{"triangle 10 is in no cluster"});
}

TEST_F(ValidateFixture, TriangleInTwoClusters) {
  Clustering c = from_groups({{0, 1, 3}, {2, 4, 5}, {6, 7, 9}, {8, 9, 10, 11}}, tris);
  const auto issues = check(c);
  EXPECT_EQ(issues, std::vector<std::string>{"triangle 9 appears in clusters 2 and 3"});
}

TEST_F(ValidateFixture, TriangleTwiceInOneCluster) {
  Clustering c = good;
  c.triangle_order[2] = 1;  // cluster 0 = {0, 1, 1}; triangle 3 missing
  const auto issues = check(c);
  EXPECT_TRUE(has_issue(issues, "triangle 1 appears twice in cluster 0")) << joined(issues);
  EXPECT_TRUE(has_issue(issues, "triangle 3 is in no cluster")) << joined(issues);
}

// Many clusters (validate checks them in parallel chunks of 4096): the messages are those of a
// pass in cluster order, at 1 and 2 threads, cut to max_issues from the front. 13,200 triangles;
// a few clusters of two triangles among singletons break max_triangles = 1, some of them also
// connectivity (two triangles of neighbouring quads that share one vertex), at chunk borders.
TEST(ValidateChunks, MessagesInClusterOrderAtAnyThreadCount) {
  const std::vector<Tri> tris = grid(110, 60);
  const std::set<std::uint32_t> pair_quads{3, 2047, 2048, 2050, 4095, 4097, 5000, 6598};
  const std::set<std::uint32_t> split_quads{2048, 4095, 5000};  // {2q, 2q + 2}: one shared vertex
  std::vector<Ids> groups;
  std::vector<std::string> expected;
  std::vector<bool> used(tris.size(), false);
  for (std::uint32_t t = 0; t < tris.size(); ++t) {
    if (used[t]) continue;
    const std::uint32_t q = t / 2;
    Ids g{t};
    if (t % 2 == 0 && pair_quads.count(q)) g.push_back(split_quads.count(q) ? t + 2 : t + 1);
    for (const std::uint32_t u : g) used[u] = true;
    const auto k = groups.size();
    if (g.size() == 2 && split_quads.count(q)) expected.push_back("cluster " + std::to_string(k) + ": not edge-connected (2 pieces)");
    if (g.size() == 2) expected.push_back("cluster " + std::to_string(k) + ": 2 triangles > limit 1");
    groups.push_back(g);
  }
  ASSERT_GT(groups.size(), 3u * 4096u);
  ASSERT_EQ(expected.size(), pair_quads.size() + split_quads.size());
  const Clustering c = from_groups(groups, tris);
  for (const int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    EXPECT_EQ(validate(c, tris, {1, 0}, 100), expected) << threads << " threads";
    EXPECT_EQ(validate(c, tris, {1, 0}, 4), std::vector<std::string>(expected.begin(), expected.begin() + 4))
        << threads << " threads";
    EXPECT_TRUE(validate(c, tris, {2, 0}, 100).size() == split_quads.size()) << threads << " threads";
  }
}

// A cluster of out-of-range ids only, with an empty vertex list: its triangles have no corners
// to list, so the empty list is right; only the ids are reported.
TEST_F(ValidateFixture, OutOfRangeIdsWithAnEmptyVertexListGiveNoVertexMessage) {
  Clustering c = from_groups({{0, 1, 3}, {2, 4, 5}, {6, 7, 9}, {8, 10, 11}}, tris);
  c.triangle_order.push_back(99);
  c.triangle_offsets.push_back(static_cast<std::uint32_t>(c.triangle_order.size()));
  c.vertex_offsets.push_back(c.vertex_offsets.back());
  const auto issues = validate(c, tris, {}, 100);
  EXPECT_TRUE(has_issue(issues, "triangle id 99 out of range")) << joined(issues);
  EXPECT_FALSE(has_issue(issues, "vertex list")) << joined(issues);
}

TEST_F(ValidateFixture, DisconnectedCluster) {
  // 0, 2 and 11 share no edge (0 and 2 share a vertex, as do 2 and 11).
  Clustering c = from_groups({{0, 2, 11}, {1, 6, 7, 9}, {3, 8}, {4, 5, 10}}, tris);
  const auto issues = check(c);
  EXPECT_TRUE(has_issue(issues, "cluster 0: not edge-connected (3 pieces)")) << joined(issues);
  EXPECT_FALSE(has_issue(issues, "cluster 1")) << joined(issues);
}

TEST_F(ValidateFixture, SharedVertexIsNotConnection) {
  const std::vector<Tri> bowtie{{0, 1, 2}, {0, 3, 4}};
  const auto issues = validate(from_groups({{0, 1}}, bowtie), bowtie);
  EXPECT_EQ(issues, std::vector<std::string>{"cluster 0: not edge-connected (2 pieces)"});
}

TEST_F(ValidateFixture, CollapsedTriangleIsOnlyValidAlone) {
  const std::vector<Tri> t{{0, 1, 2}, {1, 1, 1}, {0, 0, 2}};
  // (0, 0, 2) shares edge 0-2 with (0, 1, 2); (1, 1, 1) has no edge at all.
  EXPECT_TRUE(validate(from_groups({{0, 2}, {1}}, t), t).empty());
  EXPECT_TRUE(brute_valid(from_groups({{0, 2}, {1}}, t), t, {}));
  const auto issues = validate(from_groups({{0, 1, 2}}, t), t);
  EXPECT_TRUE(has_issue(issues, "cluster 0: not edge-connected (2 pieces)")) << joined(issues);
}

TEST_F(ValidateFixture, WrongVertexLists) {
  {
    Clustering c = good;  // a vertex missing from cluster 1's list
    c.vertices.erase(c.vertices.begin() + c.vertex_offsets[1]);
    for (std::size_t k = 2; k < c.vertex_offsets.size(); ++k) --c.vertex_offsets[k];
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "cluster 1: vertex list has")) << joined(issues);
    EXPECT_TRUE(has_issue(issues, "1 missing")) << joined(issues);
  }
  {
    Clustering c = good;  // an extra vertex in cluster 3's list
    c.vertices.push_back(99);
    ++c.vertex_offsets.back();
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "cluster 3: vertex list has")) << joined(issues);
    EXPECT_TRUE(has_issue(issues, "1 extra e.g. 99")) << joined(issues);
  }
  {
    Clustering c = good;  // right vertices, wrong order
    std::swap(c.vertices[c.vertex_offsets[2]], c.vertices[c.vertex_offsets[2] + 1]);
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "cluster 2: vertex list not strictly ascending")) << joined(issues);
  }
  {
    Clustering c = good;  // a repeated vertex
    c.vertices.insert(c.vertices.begin() + c.vertex_offsets[1], c.vertices[c.vertex_offsets[1]]);
    for (std::size_t k = 1; k < c.vertex_offsets.size(); ++k) ++c.vertex_offsets[k];
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "cluster 0: vertex list not strictly ascending")) << joined(issues);
  }
}

TEST_F(ValidateFixture, TrianglesNotAscending) {
  Clustering c = good;
  std::swap(c.triangle_order[3], c.triangle_order[4]);
  const auto issues = check(c);
  EXPECT_EQ(issues, std::vector<std::string>{"cluster 1: triangles not in ascending order"});
}

TEST_F(ValidateFixture, LimitsExceeded) {
  const auto issues = check(good, {2, 4});
  // Every cluster has 3 triangles; clusters of three grid triangles have 5 vertices.
  for (int k = 0; k < 4; ++k) {
    EXPECT_TRUE(has_issue(issues, "cluster " + std::to_string(k) + ": 3 triangles > limit 2")) << joined(issues);
    EXPECT_TRUE(has_issue(issues, "cluster " + std::to_string(k) + ": 5 vertices > limit 4")) << joined(issues);
  }
  EXPECT_TRUE(check(good, {3, 0}).empty());
  EXPECT_TRUE(check(good, {0, 5}).empty());
}

TEST_F(ValidateFixture, EmptyCluster) {
  Clustering c = good;
  c.triangle_offsets.insert(c.triangle_offsets.begin() + 2, c.triangle_offsets[2]);
  c.vertex_offsets.insert(c.vertex_offsets.begin() + 2, c.vertex_offsets[2]);
  const auto issues = check(c);
  EXPECT_EQ(issues, std::vector<std::string>{"cluster 2: empty"});
}

TEST_F(ValidateFixture, BadOffsets) {
  {
    Clustering c = good;
    c.triangle_offsets.clear();
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "triangle_offsets is empty")) << joined(issues);
  }
  {
    Clustering c = good;
    c.triangle_offsets[0] = 1;
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "triangle_offsets[0] = 1, expected 0")) << joined(issues);
  }
  {
    Clustering c = good;
    c.triangle_offsets[2] = 1;  // 3 -> 1 -> 9
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "cluster 1: triangle_offsets decrease (3 -> 1)")) << joined(issues);
  }
  {
    Clustering c = good;
    c.triangle_offsets.back() = 1000;
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "triangle_offsets ends at 1000 but triangle_order has 12 entries")) << joined(issues);
  }
  {
    Clustering c = good;
    c.vertex_offsets.pop_back();
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "vertex_offsets has 4 entries, triangle_offsets 5")) << joined(issues);
  }
  {
    Clustering c = good;
    c.vertex_offsets[1] = 0xffffffffu;
    const auto issues = check(c);
    EXPECT_TRUE(has_issue(issues, "cluster 1: vertex_offsets decrease")) << joined(issues);
  }
}

TEST_F(ValidateFixture, OutOfRangeTriangleIds) {
  Clustering c = good;
  c.triangle_order[5] = 12;
  c.triangle_order[6] = 0xffffffffu;
  const auto issues = check(c);
  EXPECT_TRUE(has_issue(issues, "cluster 1: triangle id 12 out of range (the mesh has 12 triangles)")) << joined(issues);
  EXPECT_TRUE(has_issue(issues, "cluster 2: triangle id 4294967295 out of range")) << joined(issues);
  EXPECT_TRUE(has_issue(issues, "triangle 5 is in no cluster")) << joined(issues);
  // Without usable offsets the ids are reported by position.
  c.triangle_offsets[1] = 7;
  c.triangle_offsets[2] = 2;
  const auto issues2 = check(c);
  EXPECT_TRUE(has_issue(issues2, "position 6: triangle id 4294967295 out of range")) << joined(issues2);
}

TEST_F(ValidateFixture, MeshWithoutTrianglesAndClusteringOfAnother) {
  const auto issues = validate(good, {}, {}, 100);
  EXPECT_TRUE(has_issue(issues, "cluster 0: triangle id 0 out of range (the mesh has 0 triangles)")) << joined(issues);
}

TEST_F(ValidateFixture, AtMostMaxIssues) {
  Clustering c = good;
  for (auto& t : c.triangle_order) t += 100;
  EXPECT_EQ(validate(c, tris, {}, 5).size(), 5u);
  EXPECT_EQ(validate(c, tris, {}, 0).size(), 0u);
  // 12 ids out of range, 12 triangles in no cluster, 4 vertex lists naming vertices of no triangle.
  EXPECT_EQ(validate(c, tris, {}, 1000).size(), 28u);
}

// Random corruption of valid clusterings: validate() never crashes, stays within max_issues,
// and is empty exactly when the brute-force check says the clustering is valid.
TEST(ValidateFuzz, AgreesWithBruteForceOnCorruptedClusterings) {
  std::mt19937 rng(777);
  const std::vector<Tri> tris = hard_mesh();
  int valid_seen = 0, invalid_seen = 0, disconnected_only = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    // Start from random labels: half of the time as they are (mostly disconnected classes), half
    // of the time split into brute-force components (valid).
    Ids labels(tris.size());
    const std::uint32_t range = std::uniform_int_distribution<std::uint32_t>(1, 6)(rng);
    for (auto& l : labels) l = std::uniform_int_distribution<std::uint32_t>(0, range - 1)(rng);
    std::vector<Ids> groups;
    const bool split = trial % 2 == 0;
    for (const Ids& g : brute_groups(labels)) {
      if (!split) groups.push_back(g);
      for (const Ids& comp : brute_components(g, tris))
        if (split) groups.push_back(comp);
    }
    std::sort(groups.begin(), groups.end(), [](const Ids& a, const Ids& b) { return a.front() < b.front(); });
    Clustering c = from_groups(groups, tris);
    // Corrupt a few entries (or none).
    const int edits = std::uniform_int_distribution<int>(0, 3)(rng);
    for (int e = 0; e < edits; ++e) {
      auto pick = [&](auto& v) -> std::uint32_t& {
        return v[std::uniform_int_distribution<std::size_t>(0, v.size() - 1)(rng)];
      };
      auto value = [&] {
        switch (std::uniform_int_distribution<int>(0, 3)(rng)) {
          case 0: return 0xffffffffu;
          case 1: return static_cast<std::uint32_t>(tris.size());
          default: return std::uniform_int_distribution<std::uint32_t>(0, 30)(rng);
        }
      };
      switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
        case 0: pick(c.triangle_order) = value(); break;
        case 1: pick(c.triangle_offsets) = value(); break;
        case 2: if (!c.vertices.empty()) pick(c.vertices) = value(); break;
        case 3: pick(c.vertex_offsets) = value(); break;
        case 4: c.triangle_order.pop_back(); break;
        case 5: c.vertex_offsets.push_back(value()); break;
      }
    }
    const auto issues = validate(c, tris, {}, 7);
    EXPECT_LE(issues.size(), 7u);
    const bool ok = brute_valid(c, tris, {});
    EXPECT_EQ(issues.empty(), ok) << "trial " << trial << "\n" << joined(issues);
    (ok ? valid_seen : invalid_seen)++;
    if (!ok && edits == 0) ++disconnected_only;  // the uncorrupted label classes
  }
  EXPECT_GT(valid_seen, 100);
  EXPECT_GT(invalid_seen, 1000);
  EXPECT_GT(disconnected_only, 100);
}

// ---------------------------------------------------------------------------------------------
// split_disconnected

TEST(SplitDisconnected, EmptyAndConnectedInputs) {
  EXPECT_EQ(split_disconnected(Clustering{}, {}).cluster_count(), 0u);
  const std::vector<Tri> tris = grid(2, 2);
  const Clustering one = from_groups({{0, 1, 2, 3, 4, 5, 6, 7}}, tris);
  const Clustering s = split_disconnected(one, tris);
  EXPECT_EQ(s.triangle_order, one.triangle_order);
  EXPECT_EQ(s.triangle_offsets, one.triangle_offsets);
  EXPECT_EQ(s.vertices, one.vertices);
}

TEST(SplitDisconnected, NotAPartitionThrows) {
  const std::vector<Tri> tris = grid(1, 2);
  Clustering c = from_groups({{0, 1}, {2, 3}}, tris);
  c.triangle_order[3] = 0;
  EXPECT_THROW((void)split_disconnected(c, tris), std::invalid_argument);
  c = from_groups({{0, 1}, {2}}, tris);
  EXPECT_THROW((void)split_disconnected(c, tris), std::invalid_argument);
  c = from_groups({{0, 1}, {2, 3}}, tris);
  c.triangle_offsets[1] = 9;
  EXPECT_THROW((void)split_disconnected(c, tris), std::invalid_argument);
}

TEST(SplitDisconnected, MatchesBruteForceComponentsOnRandomLabelings) {
  std::mt19937 rng(4242);
  const std::vector<std::vector<Tri>> meshes{hard_mesh(), grid(5, 4), grid(1, 9)};
  for (const auto& tris : meshes) {
    for (int trial = 0; trial < 300; ++trial) {
      Ids labels(tris.size());
      const std::uint32_t range = std::uniform_int_distribution<std::uint32_t>(1, 8)(rng);
      for (auto& l : labels) l = std::uniform_int_distribution<std::uint32_t>(0, range - 1)(rng);
      // Input: the label classes as clusters, most of them disconnected.
      const std::vector<Ids> groups = brute_groups(labels);
      const Clustering split = split_disconnected(from_groups(groups, tris), tris);
      // Expected: the brute-force components of every class, ordered by smallest triangle id.
      std::vector<Ids> expected;
      for (const Ids& g : groups)
        for (const Ids& comp : brute_components(g, tris)) expected.push_back(comp);
      std::sort(expected.begin(), expected.end(), [](const Ids& a, const Ids& b) { return a.front() < b.front(); });
      expect_equals_groups(split, expected, tris);
      EXPECT_TRUE(validate(split, tris).empty());
      // Every piece lies inside one input cluster, and pieces of a cluster are its union.
      const Ids of = split.cluster_of_triangle();
      for (const Ids& g : groups) {
        std::set<std::uint32_t> pieces;
        for (auto t : g) pieces.insert(of[t]);
        std::size_t n = 0;
        for (auto p : pieces) {
          for (auto t : split.triangles_of(p)) EXPECT_EQ(labels[t], labels[g.front()]);
          n += split.triangles_of(p).size();
        }
        EXPECT_EQ(n, g.size());
      }
    }
  }
}


// Renumbering the mesh's vertices: positions moved, corners renamed, triangle order kept; the
// inverse permutation; a clustering's vertex lists renamed and sorted again (validate() still
// holds); bad permutations and lists refused.
TEST(Renumbering, MeshAndClusteringFollowThePermutation) {
  const Mesh m({{0, 1, 2}, {2, 1, 3}, {3, 4, 2}, {5, 5, 5}},
               {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0), Vec3(0, 2, 0), Vec3(9, 9, 9), Vec3(7, 7, 7)});
  const Ids to_old{6, 3, 0, 5, 2, 4, 1};
  const Ids to_new = inverse_permutation(to_old);
  for (std::uint32_t i = 0; i < to_old.size(); ++i) EXPECT_EQ(to_new[to_old[i]], i);
  const Mesh r = renumber_vertices(m, to_old);
  ASSERT_EQ(r.vertex_count(), m.vertex_count());
  ASSERT_EQ(r.triangle_count(), m.triangle_count());
  for (std::uint32_t i = 0; i < to_old.size(); ++i) EXPECT_EQ(r.position(i), m.position(to_old[i]));
  for (std::size_t t = 0; t < m.triangle_count(); ++t)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(r.triangle(t)[c], to_new[m.triangle(t)[c]]) << t;
  EXPECT_THROW((void)inverse_permutation(Ids{0, 0, 1}), std::invalid_argument);
  EXPECT_THROW((void)inverse_permutation(Ids{0, 3, 1}), std::invalid_argument);
  EXPECT_THROW((void)renumber_vertices(m, Ids{0, 1}), std::invalid_argument);
  EXPECT_THROW((void)renumber_vertices(m, Ids{0, 1, 2, 3, 4, 5, 5}), std::invalid_argument);
  EXPECT_TRUE(renumber_vertices(Mesh(), {}).empty());

  const Clustering c = clustering_from_labels(Ids{0, 0, 1, 2}, m.triangles());
  const Clustering rc = renumber_vertices(c, to_new);
  EXPECT_EQ(rc.triangle_order, c.triangle_order);
  EXPECT_EQ(rc.triangle_offsets, c.triangle_offsets);
  EXPECT_EQ(rc.vertex_offsets, c.vertex_offsets);
  for (std::size_t k = 0; k < c.cluster_count(); ++k) {
    Ids want;
    for (std::uint32_t v : c.vertices_of(k)) want.push_back(to_new[v]);
    std::sort(want.begin(), want.end());
    EXPECT_EQ(Ids(rc.vertices_of(k).begin(), rc.vertices_of(k).end()), want) << k;
  }
  EXPECT_TRUE(validate(rc, r.triangles()).empty());
  EXPECT_THROW((void)renumber_vertices(c, Ids{0, 1}), std::invalid_argument);
  Clustering broken = c;
  broken.vertex_offsets.back() += 5;
  EXPECT_THROW((void)renumber_vertices(broken, to_new), std::invalid_argument);
  // The form that takes the clustering over: the same lists; refused before anything changes,
  // so the caller's clustering is intact after the throw.
  Clustering moved = c;
  const Clustering rm = renumber_vertices(std::move(moved), to_new);
  EXPECT_EQ(rm.vertices, rc.vertices);
  EXPECT_EQ(rm.vertex_offsets, rc.vertex_offsets);
  EXPECT_EQ(rm.triangle_order, rc.triangle_order);
  for (const Ids& bad : {Ids{0, 1}, Ids{}}) {
    Clustering keep = c;
    EXPECT_THROW((void)renumber_vertices(std::move(keep), bad), std::invalid_argument);
    EXPECT_EQ(keep.vertices, c.vertices);
  }
  Clustering keep_broken = broken;
  EXPECT_THROW((void)renumber_vertices(std::move(keep_broken), to_new), std::invalid_argument);
  EXPECT_EQ(keep_broken.vertices, broken.vertices);
}

// The in-place renumbering against the copying one (the brute force: a gather), item by item:
// random permutations (one long cycle, fixed points, many short cycles), the triangle array
// renamed where it is when not shared and copied when another mesh shares it (that mesh keeps
// its corners), and bad permutations refused with inverse_permutation's message and nothing changed.
TEST(Renumbering, InPlaceEqualsTheGatherAndLeavesSharersAlone) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 60; ++trial) {
    const std::size_t n = 1 + rng() % (trial < 30 ? 12 : 5000);
    std::vector<Vec3> pos(n);
    for (std::size_t i = 0; i < n; ++i) pos[i] = Vec3(double(rng() % 1000), double(i), -double(i) * 0.5);
    std::vector<Tri> tris(2 * n);
    for (Tri& t : tris)
      for (auto& v : t) v = static_cast<std::uint32_t>(rng() % n);
    Ids to_old(n);
    std::iota(to_old.begin(), to_old.end(), 0u);
    if (trial % 3 == 0) {  // one cycle through every vertex
      for (std::size_t i = 0; i < n; ++i) to_old[i] = static_cast<std::uint32_t>((i + 1) % n);
    } else if (trial % 3 == 1) {  // a shuffle (many cycles)
      std::shuffle(to_old.begin(), to_old.end(), rng);
    } else {  // mostly fixed points, a few swaps
      for (std::size_t k = 0; k + 1 < n && k < 4; ++k) std::swap(to_old[rng() % n], to_old[rng() % n]);
    }
    const Mesh original(tris, pos);
    const Mesh want = renumber_vertices(original, to_old);
    // Not shared: renamed where it is.
    Mesh alone(tris, pos);
    const Tri* before = alone.triangles().data();
    alone.renumber_vertices(to_old);
    EXPECT_EQ(alone.triangles().data(), before) << trial;
    // Shared with another mesh: that one keeps its corners and positions.
    Mesh shared(tris, pos);
    const Mesh sharer = shared.with_positions(pos);
    shared.renumber_vertices(to_old);
    for (const Mesh* m : {&alone, &shared}) {
      ASSERT_EQ(m->vertex_count(), n);
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(m->position(i), want.position(i)) << trial << " vertex " << i;
      for (std::size_t t = 0; t < tris.size(); ++t) ASSERT_EQ(m->triangle(t), want.triangle(t)) << trial << " triangle " << t;
    }
    for (std::size_t t = 0; t < tris.size(); ++t) ASSERT_EQ(sharer.triangle(t), tris[t]) << trial;
    for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(sharer.position(i), pos[i]) << trial;
    // Mesh::sharing another mesh's array (no copy): renaming copies it, the owner keeps its own.
    const Mesh owner(tris, pos);
    Mesh viewer = Mesh::sharing(owner.shared_triangles(), pos);
    EXPECT_EQ(viewer.triangles().data(), owner.triangles().data()) << trial;
    viewer.renumber_vertices(to_old);
    EXPECT_NE(viewer.triangles().data(), owner.triangles().data()) << trial;
    for (std::size_t t = 0; t < tris.size(); ++t) {
      ASSERT_EQ(viewer.triangle(t), want.triangle(t)) << trial << " triangle " << t;
      ASSERT_EQ(owner.triangle(t), tris[t]) << trial;
    }
  }
  {  // Mesh::sharing checks the indices against its positions, as the constructor does
    const Mesh quad({{0, 1, 2}, {2, 1, 3}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)});
    EXPECT_THROW((void)Mesh::sharing(quad.shared_triangles(), std::vector<Vec3>(3)), std::invalid_argument);
    EXPECT_EQ(Mesh::sharing(nullptr, {}).triangle_count(), 0u);
  }
  // Refused before anything changes, with the message inverse_permutation gives.
  const Mesh m({{0, 1, 2}, {2, 1, 3}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)});
  for (const Ids& bad : {Ids{0, 1, 2, 2}, Ids{3, 1, 0, 4}, Ids{0, 1, 2}, Ids{0, 1, 2, 3, 4}}) {
    Mesh c = m.with_positions(std::vector<Vec3>(m.positions().begin(), m.positions().end()));
    std::string want_msg;
    if (bad.size() == m.vertex_count()) {
      try {
        (void)inverse_permutation(bad);
      } catch (const std::invalid_argument& e) {
        want_msg = e.what();
      }
      try {
        check_permutation(bad);
        ADD_FAILURE() << "check_permutation accepted a bad permutation";
      } catch (const std::invalid_argument& e) {
        EXPECT_EQ(std::string(e.what()), want_msg);
      }
    }
    try {
      c.renumber_vertices(bad);
      ADD_FAILURE() << "renumbered with a bad permutation";
    } catch (const std::invalid_argument& e) {
      if (!want_msg.empty()) {
        EXPECT_EQ(std::string(e.what()), want_msg);
      }
    }
    for (std::size_t i = 0; i < m.vertex_count(); ++i) EXPECT_EQ(c.position(i), m.position(i));
    for (std::size_t t = 0; t < m.triangle_count(); ++t) EXPECT_EQ(c.triangle(t), m.triangle(t));
  }
  check_permutation(Ids{});  // the empty permutation
  Mesh empty;
  empty.renumber_vertices(Ids{});
  EXPECT_TRUE(empty.empty());
}

}  // namespace
}  // namespace ptc
