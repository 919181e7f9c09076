// Shared fixtures of the clustering tests (clustering_*_test.cpp): small hand-made meshes (the
// hard cases: non-manifold fans and books, degenerate triangles, closed surfaces where N_avg
// vanishes, many tiny components), their jittered generic versions (no two scores tie), the
// reference scenarios of the greedy tests, and the item-by-item partition check of the
// bounded-size baselines. Header-only; everything is inline in ptc::test_meshes.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/geometry/cluster_metrics.h"
#include "toolkit/geometry/gwh01.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/mesh.h"
#include "toolkit/mesh/topology.h"

namespace ptc::test_meshes {

using Ids = std::vector<std::uint32_t>;

// ---- Meshes (small, hand-made; jittered versions so that no two scores tie) ----------------

inline double jitter(std::uint64_t i) {  // splitmix64 -> [-1, 1], independent of the standard library
  std::uint64_t z = i + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-52 - 1.0;
}

inline Mesh jittered(const Mesh& m, double amp, std::uint64_t seed) {
  std::vector<Vec3> p(m.positions().begin(), m.positions().end());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::uint64_t k = 3 * (seed * 100000 + i);
    p[i] += amp * Vec3(jitter(k), jitter(k + 1), jitter(k + 2));
  }
  return m.with_positions(std::move(p));
}

/// nx x ny unit quads in the plane z = z0, shifted by x0 along x; two triangles per quad.
inline Mesh grid(int nx, int ny, double x0 = 0, double z0 = 0) {
  std::vector<Vec3> p;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) p.emplace_back(x0 + i, j, z0);
  std::vector<Tri> t;
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      t.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      t.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return Mesh(std::move(t), std::move(p));
}

inline Mesh icosahedron() {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> p{{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                      {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<Tri> t{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                     {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                     {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  return Mesh(std::move(t), std::move(p));
}

/// A cube without its top face, each face split 2 x 2 into 8 triangles (40 triangles).
inline Mesh open_cube() {
  std::vector<Vec3> p;
  std::vector<Tri> t;
  auto face = [&](const Vec3& o, const Vec3& u, const Vec3& v) {
    const auto base = static_cast<std::uint32_t>(p.size());
    for (int j = 0; j <= 2; ++j)
      for (int i = 0; i <= 2; ++i) p.push_back(o + 0.5 * i * u + 0.5 * j * v);
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        const std::uint32_t a = base + j * 3 + i, b = a + 1, c = a + 4, d = a + 3;
        t.push_back({a, b, c});
        t.push_back({a, c, d});
      }
  };
  face({0, 0, 0}, {0, 1, 0}, {1, 0, 0});  // bottom
  face({0, 0, 0}, {1, 0, 0}, {0, 0, 1});
  face({1, 0, 0}, {0, 1, 0}, {0, 0, 1});
  face({1, 1, 0}, {-1, 0, 0}, {0, 0, 1});
  face({0, 1, 0}, {0, -1, 0}, {0, 0, 1});
  // weld coincident vertices
  std::vector<Vec3> q;
  std::vector<std::uint32_t> remap(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    std::size_t k = 0;
    while (k < q.size() && (q[k] - p[i]).norm() > 1e-12) ++k;
    if (k == q.size()) q.push_back(p[i]);
    remap[i] = static_cast<std::uint32_t>(k);
  }
  for (Tri& f : t)
    for (auto& v : f) v = remap[v];
  return Mesh(std::move(t), std::move(q));
}

/// n triangles around a center vertex (closed fan when `closed`).
inline Mesh fan(int n, bool closed) {
  std::vector<Vec3> p{{0, 0, 0}};
  for (int i = 0; i < n + (closed ? 0 : 1); ++i) {
    const double a = 2.0 * std::numbers::pi * i / (n + (closed ? 0 : 1.5));
    p.emplace_back(std::cos(a), std::sin(a), 0.2 * std::sin(3 * a));
  }
  std::vector<Tri> t;
  const int rim = static_cast<int>(p.size()) - 1;
  for (int i = 0; i < n; ++i)
    t.push_back({0, static_cast<std::uint32_t>(1 + i), static_cast<std::uint32_t>(1 + (i + 1) % rim)});
  return Mesh(std::move(t), std::move(p));
}

/// A latitude-longitude patch of the unit sphere: nu x nv cells, two triangles each.
inline Mesh sphere_patch(int nu, int nv) {
  std::vector<Vec3> p;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double th = 0.3 + 1.2 * j / nv, ph = 1.6 * i / nu;
      p.emplace_back(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    }
  std::vector<Tri> t;
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      t.push_back({id(i, j), id(i, j + 1), id(i + 1, j + 1)});
      t.push_back({id(i, j), id(i + 1, j + 1), id(i + 1, j)});
    }
  return Mesh(std::move(t), std::move(p));
}

/// Four triangles on one edge (non-manifold, valence 4) and two more on free sides.
inline Mesh book() {
  std::vector<Vec3> p{{0, 0, 0}, {0, 0, 1}, {1, 0, 0.5}, {0, 1, 0.4}, {-1, 0.1, 0.5}, {0, -1, 0.6},
                      {1.2, 0.8, 0.1}, {0.8, 1.1, 1.2}};
  std::vector<Tri> t{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {1, 0, 5}, {0, 2, 6}, {3, 1, 7}};
  return Mesh(std::move(t), std::move(p));
}

/// A grid with degenerate triangles: (a, a, b), (a, b, a) on a grid edge, a collinear one, (v, v, v).
inline Mesh degenerate_mix() {
  Mesh g = jittered(grid(4, 3), 0.1, 9);
  std::vector<Tri> t(g.triangles().begin(), g.triangles().end());
  std::vector<Vec3> p(g.positions().begin(), g.positions().end());
  t.push_back({0, 0, 1});
  t.push_back({6, 7, 6});
  p.push_back(0.5 * (p[1] + p[2]));
  t.push_back({1, static_cast<std::uint32_t>(p.size() - 1), 2});
  t.push_back({3, 3, 3});
  return Mesh(std::move(t), std::move(p));
}

inline Mesh regular_tetrahedron() {
  std::vector<Vec3> p{{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  std::vector<Tri> t{{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  return Mesh(std::move(t), std::move(p));
}

/// Separate pieces: single triangles, pairs, a strip; far apart.
inline Mesh components() {
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (int k = 0; k < 12; ++k) {
    const auto b = static_cast<std::uint32_t>(p.size());
    const Vec3 o(5.0 * k, 0.3 * k, 0);
    const int n = k % 4;  // 0: a triangle, 1: two, 2: three, 3: four, in a strip
    for (int i = 0; i < n + 3; ++i) p.push_back(o + Vec3(0.5 * i + 0.1 * jitter(7 * k + i), i % 2, 0.05 * jitter(k + 99 * i)));
    for (int i = 0; i <= n; ++i) t.push_back({b + i, b + i + 1, b + i + 2});
  }
  return Mesh(std::move(t), std::move(p));
}

/// The grid with a deterministic height pattern (not planar: exercises normal cones).
/// n separate triangles on a 3D lattice (10 x 10 x ...): n components, every edge a boundary.
inline Mesh triangle_lattice(std::uint32_t n) {
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (std::uint32_t i = 0; i < n; ++i) {
    const Vec3 o(i % 10, (i / 10) % 10, i / 100);
    const auto b = static_cast<std::uint32_t>(p.size());
    p.push_back(o);
    p.push_back(o + Vec3(0.3, 0, 0));
    p.push_back(o + Vec3(0, 0.3, 0.1));
    t.push_back({b, b + 1, b + 2});
  }
  return Mesh(std::move(t), std::move(p));
}

/// n triangles on the single edge 0-1, apexes on a circle: one non-manifold edge, all
/// edge-connected, n + 2 vertices.
inline Mesh edge_fan(std::uint32_t n) {
  std::vector<Vec3> p{Vec3(0, 0, -1), Vec3(0, 0, 1)};
  std::vector<Tri> t;
  for (std::uint32_t i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    p.emplace_back(std::cos(a), std::sin(a), 0.0);
    t.push_back({0, 1, i + 2});
  }
  return Mesh(std::move(t), std::move(p));
}

inline Mesh bumpy_grid(int nx, int ny) {
  Mesh g = grid(nx, ny);
  std::vector<Vec3> p(g.positions().begin(), g.positions().end());
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) p[static_cast<std::size_t>(j * (nx + 1) + i)].z() = 0.25 * ((i * 7 + j * 3) % 5);
  return g.with_positions(std::move(p));
}

/// Both meshes side by side (b's vertex ids shifted).
inline Mesh concat(const Mesh& a, const Mesh& b) {
  std::vector<Vec3> p(a.positions().begin(), a.positions().end());
  p.insert(p.end(), b.positions().begin(), b.positions().end());
  std::vector<Tri> t(a.triangles().begin(), a.triangles().end());
  const auto off = static_cast<std::uint32_t>(a.vertex_count());
  for (Tri f : b.triangles()) t.push_back({f[0] + off, f[1] + off, f[2] + off});
  return Mesh(std::move(t), std::move(p));
}

/// The mesh as a triangle soup: every corner its own vertex, at the same position (the explode
/// deformer's rest pose).
inline Mesh soup_of(const Mesh& m) {
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (const Tri& f : m.triangles()) {
    const auto b = static_cast<std::uint32_t>(p.size());
    for (std::uint32_t v : f) p.push_back(m.positions()[v]);
    t.push_back({b, b + 1, b + 2});
  }
  return Mesh(std::move(t), std::move(p));
}

/// The mesh with its vertices renumbered by first use in triangle order (unused ones dropped):
/// the numbering the weld of soup_of(m) gives, so both are the same mesh.
inline Mesh by_first_use(const Mesh& m) {
  std::vector<std::uint32_t> id(m.vertex_count(), 0xffffffffu);
  std::vector<Vec3> p;
  std::vector<Tri> t;
  for (Tri f : m.triangles()) {
    for (std::uint32_t& v : f) {
      if (id[v] == 0xffffffffu) id[v] = static_cast<std::uint32_t>(p.size()), p.push_back(m.positions()[v]);
      v = id[v];
    }
    t.push_back(f);
  }
  return Mesh(std::move(t), std::move(p));
}

inline Mesh load(const char* name) { return read_mesh(std::string(PTC_TEST_DATA) + "/meshes/" + name).mesh; }

struct Named {
  const char* name;
  Mesh mesh;
};

/// The reference meshes: generic (no ties) versions.
inline std::vector<Named> generic_meshes() {
  return {{"icosahedron", jittered(icosahedron(), 0.05, 1)},
          {"grid", jittered(grid(6, 5), 0.15, 2)},
          {"open cube", jittered(open_cube(), 0.04, 3)},
          {"fan", jittered(fan(10, false), 0.05, 4)},
          {"closed fan", jittered(fan(9, true), 0.05, 5)},
          {"sphere patch", jittered(sphere_patch(5, 4), 0.02, 6)},
          {"book", jittered(book(), 0.02, 7)},
          {"degenerate mix", degenerate_mix()},
          {"tetrahedron", jittered(regular_tetrahedron(), 0.01, 8)},
          {"components", components()}};
}

// ---- Scenarios of the greedy reference tests ---------------------------------------------------

struct Scenario {
  ObjectiveKind kind = ObjectiveKind::Acc;
  double max_count = 10, max_size = 10;
  SizeBoundMode mode = SizeBoundMode::Max;
  SphereMethod sphere = SphereMethod::Cgal;
  GwhParams gwh{};
  std::uint32_t target = 0;
};

inline std::string describe(const Scenario& s) {
  return std::string(to_string(s.kind)) + " MaxCount " + std::to_string(s.max_count) + " MaxSize " +
         std::to_string(s.max_size) + (s.mode == SizeBoundMode::Min ? " min" : "") + " sphere " +
         std::string(to_string(s.sphere)) + " target " + std::to_string(s.target);
}

inline ClusterParams acc_params(const Mesh& m, const Scenario& s) {
  ClusterParams p;
  p.max_count = s.max_count;
  p.max_size = s.max_size;
  p.size_bound_mode = s.mode;
  p.sphere = s.sphere;
  p.avg_sa = average_triangle_sphere_area(m.positions(), m.triangles());
  return p;
}

inline std::size_t vertex_count(const Mesh& m, const Ids& ids) {
  std::set<std::uint32_t> v;
  for (std::uint32_t t : ids) v.insert(m.triangle(t).begin(), m.triangle(t).end());
  return v.size();
}

// ---- Bounded-size baselines (sah-split, meshopt) -----------------------------------------------

// Checks the result item by item against the mesh, without validate(): every triangle exactly
// once, and every cluster's triangle and distinct-vertex counts within the limits.
inline void expect_partition_within_limits(const Clustering& c, const Mesh& m, const ClusterLimits& lim) {
  ASSERT_EQ(c.triangle_order.size(), m.triangle_count());
  std::vector<int> seen(m.triangle_count(), 0);
  for (std::size_t k = 0; k < c.cluster_count(); ++k) {
    const auto ts = c.triangles_of(k);
    EXPECT_FALSE(ts.empty());
    std::set<std::uint32_t> v;
    for (auto t : ts) {
      ++seen[t];
      v.insert(m.triangle(t).begin(), m.triangle(t).end());
    }
    EXPECT_LE(ts.size(), lim.max_triangles) << "cluster " << k;
    EXPECT_LE(v.size(), lim.max_vertices) << "cluster " << k;
  }
  for (std::size_t t = 0; t < seen.size(); ++t) EXPECT_EQ(seen[t], 1) << "triangle " << t;
}

inline std::string joined(const std::vector<std::string>& issues) {
  std::string s;
  for (const auto& i : issues) s += i + "\n";
  return s;
}


/// The objective of the greedy reference implementations (growth and contraction tests): the
/// score of merging a and b (u = a u b), recomputed from scratch.
struct Reference {
  const Mesh& m;
  Scenario s;
  ClusterParams acc;
  double inv_l2 = 1;

  Reference(const Mesh& mesh, const Scenario& setup) : m(mesh), s(setup), acc(acc_params(mesh, setup)) {
    const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
    double sum = 0;
    for (const Edge& e : em.edges()) sum += (m.position(e.v1) - m.position(e.v0)).norm();
    const double l = em.edge_count() ? sum / static_cast<double>(em.edge_count()) : 0.0;
    inv_l2 = l > 0 ? 1.0 / (l * l) : 1.0;
  }
  [[nodiscard]] bool only_positive() const { return s.kind == ObjectiveKind::Acc; }
  [[nodiscard]] bool legal(const Ids& u) const { return s.kind == ObjectiveKind::Acc || static_cast<double>(vertex_count(m, u)) <= s.max_count; }
  [[nodiscard]] double score(const Ids& u, const Ids& a, const Ids& b) const {
    switch (s.kind) {
      case ObjectiveKind::Acc: return cluster_acc(m, u, acc);
      case ObjectiveKind::Naive: return cluster_metrics(m, u).naive;
      case ObjectiveKind::Gwh01: {
        const GwhTerms tu = gwh_terms(m, u, s.gwh.weight), ta = gwh_terms(m, a, s.gwh.weight),
                       tb = gwh_terms(m, b, s.gwh.weight);
        return -(tu.fit.e_fit * inv_l2 + s.gwh.a1 * tu.e_dir + s.gwh.a2 * shape_cost(tu.gamma, ta.gamma, tb.gamma));
      }
    }
    return 0;
  }
};

// ---- Checks shared by the greedy tests --------------------------------------------------------

/// Two labelings describe the same partition (cluster by cluster, in canonical order).
inline void expect_same_partition(const Mesh& m, std::span<const std::uint32_t> l1, std::span<const std::uint32_t> l2,
                           const std::string& what) {
  const Clustering c1 = clustering_from_labels(l1, m.triangles()), c2 = clustering_from_labels(l2, m.triangles());
  EXPECT_EQ(c1.triangle_order, c2.triangle_order) << what;
  EXPECT_EQ(c1.triangle_offsets, c2.triangle_offsets) << what;
}

/// validate() finds nothing (max_vertices = 0: no vertex bound).
inline void expect_valid(const Mesh& m, const Clustering& c, std::uint32_t max_vertices, const std::string& what) {
  ClusterLimits lim;
  lim.max_vertices = max_vertices;
  const auto issues = validate(c, m.triangles(), lim);
  EXPECT_TRUE(issues.empty()) << what << ": " << (issues.empty() ? "" : issues.front());
}

}  // namespace ptc::test_meshes
