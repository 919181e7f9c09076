// The clustering objectives (toolkit/clustering/objectives/*.h) against independent answers:
// every incremental score of a merge A + B is compared with the from-scratch quantities of
// geometry/cluster_metrics.h and geometry/gwh01.h on the merged triangle set, on random adjacent
// cluster pairs of real and hand-made meshes (degenerate and non-manifold ones first).
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include <boost/graph/adjacency_list.hpp>

#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/growth.h"
#include "toolkit/clustering/objectives.h"
#include "toolkit/clustering/objectives/acc.h"
#include "toolkit/clustering/objectives/gwh01.h"
#include "toolkit/clustering/objectives/naive.h"
#include "toolkit/geometry/cluster_metrics.h"
#include "toolkit/geometry/gwh01.h"
#include "toolkit/geometry/morton.h"
#include "toolkit/geometry/sphere.h"
#include "toolkit/geometry/triangle.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/topology.h"
#include "test_meshes.h"

namespace ptc {
namespace {

using Ids = std::vector<std::uint32_t>;
using namespace test_meshes;  // jitter, regular_tetrahedron, load (grid, book, degenerate_mix: own jittered versions)

// ---- Meshes (own jittered variants; the shared ones are in test_meshes.h) -----------------

/// nx x ny quads, each split into two triangles, in z = 0 plus `amp` x jitter on all axes.
Mesh grid(int nx, int ny, double amp, std::uint64_t seed = 1) {
  const Mesh g = test_meshes::grid(nx, ny);
  std::vector<Vec3> p(g.positions().begin(), g.positions().end());
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::uint64_t k = 3 * (seed * 1000 + i);
    p[i] += amp * Vec3(jitter(k), jitter(k + 1), jitter(k + 2));
  }
  return g.with_positions(std::move(p));
}

/// Four triangles on one edge (valence 4: non-manifold) plus a triangle on each free side of two of
/// them, slightly jittered.
Mesh book() {
  std::vector<Vec3> p{{0, 0, 0}, {0, 0, 1}, {1, 0, 0.5}, {0, 1, 0.4}, {-1, 0.1, 0.5}, {0, -1, 0.6},
                      {1.2, 0.8, 0.1}, {0.8, 1.1, 1.2}};
  for (std::size_t i = 0; i < p.size(); ++i) p[i] += 0.01 * Vec3(jitter(3 * i), jitter(3 * i + 1), jitter(3 * i + 2));
  std::vector<Tri> t{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {1, 0, 5}, {0, 2, 6}, {3, 1, 7}};
  return Mesh(std::move(t), std::move(p));
}

/// A jittered grid with degenerate triangles mixed in: a repeated index (a, a, b), a triangle
/// (a, b, a) on a grid edge, a collinear (zero-area) one, and a triangle made of one vertex.
Mesh degenerate_mix() {
  Mesh g = grid(4, 3, 0.05, 7);
  std::vector<Tri> t(g.triangles().begin(), g.triangles().end());
  std::vector<Vec3> p(g.positions().begin(), g.positions().end());
  t.push_back({0, 0, 1});
  t.push_back({6, 7, 6});
  p.push_back(0.5 * (p[1] + p[2]));
  t.push_back({1, static_cast<std::uint32_t>(p.size() - 1), 2});  // collinear with edge (1, 2)
  t.push_back({3, 3, 3});
  return Mesh(std::move(t), std::move(p));
}

// ---- Independent construction of a candidate merge ------------------------------------------

Ids sorted_vertices(const Mesh& m, const Ids& tris) {
  Ids v;
  for (std::uint32_t t : tris) v.insert(v.end(), m.triangle(t).begin(), m.triangle(t).end());
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

/// Owns the lists a MergeContext points to.
struct Candidate {
  Ids a, b, va, added, shared;
  MergeContext ctx;
};

/// MergeContext of A + B from its definition: vertex set algebra, and the removed boundary by
/// counting, per mesh edge, the triangles of A and of B on it.
void make_candidate(const Mesh& m, const EdgeMap& em, const Ids& a, const Ids& b, Candidate& c) {
  c.a = a;
  c.b = b;
  c.va = sorted_vertices(m, a);
  const Ids vb = sorted_vertices(m, b);
  c.added.clear();
  c.shared.clear();
  std::set_difference(vb.begin(), vb.end(), c.va.begin(), c.va.end(), std::back_inserter(c.added));
  std::set_intersection(vb.begin(), vb.end(), c.va.begin(), c.va.end(), std::back_inserter(c.shared));
  const std::set<std::uint32_t> sa(a.begin(), a.end()), sb(b.begin(), b.end());
  double removed = 0;
  for (std::size_t e = 0; e < em.edge_count(); ++e) {
    int na = 0, nb = 0;
    for (std::uint32_t t : em.triangles_of(e)) {
      na += sa.count(t) ? 1 : 0;
      nb += sb.count(t) ? 1 : 0;
    }
    if (na > 0 && nb > 0) {
      const Edge& ed = em.edge(e);
      removed += safe_norm(m.position(ed.v1) - m.position(ed.v0)) * ((na == 1) + (nb == 1));
    }
  }
  c.ctx.a_triangles = c.a;
  c.ctx.b_triangles = c.b;
  c.ctx.a_vertices = c.va;
  c.ctx.added = c.added;
  c.ctx.shared = c.shared;
  c.ctx.vertex_count = static_cast<std::uint32_t>(c.va.size() + c.added.size());
  c.ctx.boundary_removed = removed;
}

/// The objective's summary of a triangle set, built as growth builds it: one triangle at a time.
template <class O>
typename O::Summary summary_of(O& o, const Mesh& m, const EdgeMap& em, const Ids& tris) {
  typename O::Summary s = o.single(tris[0]);
  Ids sofar{tris[0]};
  for (std::size_t i = 1; i < tris.size(); ++i) {
    Candidate c;
    make_candidate(m, em, sofar, {tris[i]}, c);
    const auto ev = o.evaluate(s, o.single(tris[i]), c.ctx, Precision::Exact);
    s = o.merge(s, o.single(tris[i]), c.ctx, ev);
    sofar.push_back(tris[i]);
  }
  return s;
}

/// Two disjoint, edge-adjacent, edge-connected triangle sets of about na and nb triangles (BFS).
std::pair<Ids, Ids> random_pair(const ClusterTables& tb, std::mt19937_64& rng, std::size_t na, std::size_t nb) {
  const std::uint32_t T = tb.triangle_count();
  std::vector<char> used(T, 0);
  auto bfs = [&](std::uint32_t seed, std::size_t n) {
    Ids out{seed}, queue{seed};
    used[seed] = 1;
    for (std::size_t q = 0; q < queue.size() && out.size() < n; ++q)
      for (std::uint32_t u : tb.neighbours_of(queue[q]))
        if (!used[u] && out.size() < n) {
          used[u] = 1;
          out.push_back(u);
          queue.push_back(u);
        }
    return out;
  };
  for (;;) {
    std::fill(used.begin(), used.end(), 0);
    const Ids a = bfs(static_cast<std::uint32_t>(rng() % T), na);
    Ids border;
    for (std::uint32_t t : a)
      for (std::uint32_t u : tb.neighbours_of(t))
        if (!used[u]) border.push_back(u);
    if (border.empty()) continue;
    const Ids b = bfs(border[rng() % border.size()], nb);
    return {a, b};
  }
}

Ids merged(const Ids& a, const Ids& b) {
  Ids u = a;
  u.insert(u.end(), b.begin(), b.end());
  std::sort(u.begin(), u.end());
  return u;
}

ClusterParams acc_params(const Mesh& m, double max_count, double max_size, SphereMethod s = SphereMethod::Cgal) {
  ClusterParams p;
  p.max_count = max_count;
  p.max_size = max_size;
  p.avg_sa = average_triangle_sphere_area(m.positions(), m.triangles());
  p.sphere = s;
  return p;
}

/// |acc - reference| relative to the size of Acc's two terms (Acc itself may be near 0).
double acc_error(double acc_value, const ClusterMetrics& cm, const ClusterParams& p) {
  const double reference = cluster_acc(cm, p);
  const double terms = std::abs(cm.reg) + reg_bound(cm.vertices, p.max_count) *
                                              size_bound(cm.sphere.surface_area(), p.max_size, p.avg_sa,
                                                         p.size_bound_mode);
  return std::abs(acc_value - reference) / terms;
}

// ---- ClusterTables -----------------------------------------------------------------------

/// A book of 24 pages on one edge (beyond kMaxCliqueValence: the dual graph links them as a path,
/// but every pair of pages shares the edge), two duplicated pages and a page (a, b, a) on it.
Mesh big_book() {
  std::vector<Vec3> p{{0, 0, 0}, {0, 0, 1}};
  std::vector<Tri> t;
  for (std::uint32_t k = 0; k < 24; ++k) {
    const double a = 0.26 * k;
    p.push_back({std::cos(a), std::sin(a), 0.5});
    t.push_back({k % 2 ? 1u : 0u, k % 2 ? 0u : 1u, k + 2});
  }
  t.push_back(t[3]);
  t.push_back(t[7]);
  t.push_back({0, 1, 0});
  t.push_back({2, 3, 4});  // shares the edge (2, 3) with nothing, (3, 4) with nothing
  return Mesh(std::move(t), std::move(p));
}

/// The dual graph's neighbours of t, by brute force over all pairs: triangles that share two
/// distinct vertex ids of a side, where that side's edge has at most kMaxCliqueValence triangles;
/// on an edge with more, the triangles before and after t among the edge's triangles ascending
/// (a path). Two triangles on two common edges are neighbours when either edge makes them so.
Ids brute_neighbours(const Mesh& m, std::uint32_t t) {
  using Side = std::pair<std::uint32_t, std::uint32_t>;
  auto sides = [&](std::uint32_t u) {
    std::set<Side> s;
    const Tri& f = m.triangle(u);
    for (int k = 0; k < 3; ++k)
      if (f[k] != f[(k + 1) % 3]) s.insert({std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])});
    return s;
  };
  std::set<std::uint32_t> out;
  for (const Side& e : sides(t)) {
    Ids on;  // the edge's triangles, ascending
    for (std::uint32_t u = 0; u < m.triangle_count(); ++u)
      if (sides(u).count(e) > 0) on.push_back(u);
    const auto at = std::find(on.begin(), on.end(), t) - on.begin();
    for (std::size_t i = 0; i < on.size(); ++i)
      if (on[i] != t && (on.size() <= kMaxCliqueValence || i + 1 == std::size_t(at) || i == std::size_t(at) + 1))
        out.insert(on[i]);
  }
  return Ids(out.begin(), out.end());
}

// The neighbour lists (built from the sides alone, with or without the edge map beside them)
// against brute force over all pairs and against Boost's dual graph of the edge map (a clique
// of at most kMaxCliqueValence triangles on an edge, a path beyond: big_book's edge has 26).
TEST(ClusterTables, NeighboursAreTheBoostDualGraphsAdjacency) {
  for (const Mesh& m : {grid(5, 4, 0.1), book(), degenerate_mix(), big_book(), load("elephant.off")}) {
    const ClusterTables with = ClusterTables::build(m), without = ClusterTables::build(m, /*with_edges=*/false);
    EXPECT_EQ(without.edges.edge_count(), 0u);
    EXPECT_EQ(with.neighbour_offsets, without.neighbour_offsets);
    EXPECT_EQ(with.neighbours, without.neighbours);
    const DualGraph g = build_dual_graph(with.edges, m.triangle_count());
    const bool small = m.triangle_count() < 2000;
    for (std::uint32_t t = 0; t < m.triangle_count(); ++t) {
      const auto nb = without.neighbours_of(t);
      if (small) {
        EXPECT_EQ(Ids(nb.begin(), nb.end()), brute_neighbours(m, t)) << "triangle " << t;
      }
      std::set<std::uint32_t> expected;
      for (auto [it, end] = boost::adjacent_vertices(t, g); it != end; ++it) expected.insert(static_cast<std::uint32_t>(*it));
      EXPECT_EQ(Ids(nb.begin(), nb.end()), Ids(expected.begin(), expected.end())) << "triangle " << t;
    }
  }
}

// One triangle repeated 100,000 times (a pipeline's stuck output): each edge holds every copy,
// so the neighbours are a path in triangle order, 2 (T - 1) entries, not a clique of 3 10^10
// (which overflowed the 32-bit offsets and crashed `ptc cluster`, found by a new user's sweep).
// Clustered by growth and contraction, every copy lands in exactly one cluster, of at most
// MaxCount vertices.
TEST(ClusterTables, ManyCopiesOfOneTriangleAreAPath) {
  constexpr std::uint32_t T = 100000;
  const Mesh m(std::vector<Tri>(T, Tri{0, 1, 2}), std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  const ClusterTables tb = ClusterTables::build(m, /*with_edges=*/false);
  ASSERT_EQ(tb.neighbours.size(), 2u * (T - 1));
  for (std::uint32_t t = 0; t < T; t += 997) {
    Ids want;
    if (t > 0) want.push_back(t - 1);
    if (t + 1 < T) want.push_back(t + 1);
    EXPECT_EQ(Ids(tb.neighbours_of(t).begin(), tb.neighbours_of(t).end()), want) << t;
  }
  EXPECT_EQ(Ids(tb.neighbours_of(T - 1).begin(), tb.neighbours_of(T - 1).end()), Ids{T - 2});
  const Mesh copies(std::vector<Tri>(20000, Tri{0, 1, 2}), std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  for (const ClusterMethod method : {ClusterMethod::Growth, ClusterMethod::Contraction}) {
    ClusterConfig cfg;
    cfg.method = method;
    cfg.max_count = 50;
    cfg.max_size = 50;
    const Clustering c = cluster_mesh(copies, cfg);
    std::vector<int> seen(copies.triangle_count(), 0);
    for (std::size_t k = 0; k < c.cluster_count(); ++k) {
      EXPECT_LE(c.vertices_of(k).size(), 50u) << to_string(method);  // (MaxCount counts vertices: 3 here)
      for (std::uint32_t t : c.triangles_of(k)) ++seen[t];
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(copies.triangle_count())) << to_string(method);
  }
}

// Meshes whose every edge has at most two triangles take the neighbour build's one-pass path
// (three slots a triangle): a pillow (two triangles sharing all three edges: each lists the
// other once), a triangle (a, a, b) and one (a, b, a) on border edges, a one-vertex triangle, an
// isolated triangle, and two pillows sharing a vertex only. Brute force, triangle by triangle.
TEST(ClusterTables, NeighboursOnMeshesWithoutNonManifoldEdges) {
  Mesh g = grid(4, 3, 0.05, 11);
  std::vector<Tri> t(g.triangles().begin(), g.triangles().end());
  std::vector<Vec3> p(g.positions().begin(), g.positions().end());
  t.push_back({0, 0, 1});  // grid border edge (0, 1)
  t.push_back({4, 9, 4});  // grid border edge (4, 9)
  t.push_back({2, 2, 2});
  const auto n = static_cast<std::uint32_t>(p.size());
  for (int k = 0; k < 5; ++k) p.push_back(Vec3(5.0 + k, 0.3 * k, 0.1 * k * k));
  t.push_back({n, n + 1, n + 2});  // pillow
  t.push_back({n, n + 2, n + 1});
  t.push_back({n, n + 3, n + 4});  // second pillow on vertex n
  t.push_back({n + 4, n + 3, n});
  p.push_back(Vec3(-3, -3, 1));
  p.push_back(Vec3(-2, -3, 1));
  p.push_back(Vec3(-3, -2, 1));
  t.push_back({n + 5, n + 6, n + 7});  // isolated
  const Mesh m(std::move(t), std::move(p));
  const ClusterTables with = ClusterTables::build(m), without = ClusterTables::build(m, /*with_edges=*/false);
  for (std::size_t e = 0; e < with.edges.edge_count(); ++e) ASSERT_LE(with.edges.valence(e), 2u) << "edge " << e;
  EXPECT_EQ(with.neighbour_offsets, without.neighbour_offsets);
  EXPECT_EQ(with.neighbours, without.neighbours);
  for (std::uint32_t f = 0; f < m.triangle_count(); ++f) {
    const auto nb = without.neighbours_of(f);
    EXPECT_EQ(Ids(nb.begin(), nb.end()), brute_neighbours(m, f)) << "triangle " << f;
  }
  const auto T = static_cast<std::uint32_t>(m.triangle_count());
  EXPECT_EQ(Ids(without.neighbours_of(T - 5).begin(), without.neighbours_of(T - 5).end()), Ids{T - 4});  // pillow
  EXPECT_TRUE(without.neighbours_of(T - 1).empty());
}

// ClusterTables::build with_sums: AvgSA bit for bit average_triangle_sphere_area's (a mesh of
// three chunks and one of less than one; 1, 2 and 4 threads), the centroids' box as a plain
// pass builds it, and the Morton order from that box equal to morton_order's own.
TEST(ClusterTables, SumsInTheTablesPassEqualTheSeparatePasses) {
  Mesh far = grid(230, 160, 0.3, 5);  // 73,600 triangles: two chunks of AvgSA's sum
  {
    std::vector<Vec3> p(far.positions().begin(), far.positions().end());
    for (Vec3& q : p) q = 1e-3 * q + Vec3(3e6, -2e5, 7.0);  // far from the origin, small triangles
    far = far.with_positions(std::move(p));
  }
  for (const Mesh& m : {grid(400, 170, 0.2, 3), far, degenerate_mix(), load("elephant.off")}) {
    const double expected = average_triangle_sphere_area(m.positions(), m.triangles());
    Box3 box;
    for (const Tri& f : m.triangles()) box.extend(triangle_centroid(m.position(f[0]), m.position(f[1]), m.position(f[2])));
    const std::vector<std::uint32_t> order = morton_order(m.positions(), m.triangles());
    for (int threads : {1, 2, 4}) {
      tbb::task_arena(threads).execute([&] {
        const ClusterTables with = ClusterTables::build(m, /*with_edges=*/false, /*with_sums=*/true);
        EXPECT_TRUE(with.with_sums);
        EXPECT_EQ(std::bit_cast<std::uint64_t>(with.avg_sphere_area), std::bit_cast<std::uint64_t>(expected))
            << m.triangle_count() << " triangles, " << threads << " threads";
        EXPECT_EQ(with.centroid_bounds.lo, box.lo);
        EXPECT_EQ(with.centroid_bounds.hi, box.hi);
        EXPECT_EQ(morton_order(m.positions(), m.triangles(), MortonGrid::Cube, &with.centroid_bounds), order);
        const ClusterTables without = ClusterTables::build(m, /*with_edges=*/false);
        EXPECT_FALSE(without.with_sums);
        EXPECT_EQ(without.avg_sphere_area, 0.0);
        EXPECT_EQ(with.area, without.area);
        EXPECT_EQ(with.normal, without.normal);
      });
    }
  }
}

// Lean tables store no areas, normals or neighbour lists; geometry_of makes the same bits as
// the full tables hold (multi-chunk grids near and far from the origin, degenerate, tiny and
// huge triangles), and the neighbour lists made alone equal the full tables' ones.
TEST(ClusterTables, LeanTablesMakeTheSameBits) {
  Mesh far = grid(230, 160, 0.3, 5);
  {
    std::vector<Vec3> p(far.positions().begin(), far.positions().end());
    for (Vec3& q : p) q = 1e-3 * q + Vec3(3e6, -2e5, 7.0);
    far = far.with_positions(std::move(p));
  }
  std::vector<Mesh> meshes = {far, degenerate_mix(), load("elephant.off")};
  for (const double scale : {1e-150, 1e150}) {
    std::vector<Vec3> p(meshes[2].positions().begin(), meshes[2].positions().end());
    for (Vec3& q : p) q *= scale;
    meshes.push_back(meshes[2].with_positions(std::move(p)));
  }
  for (const Mesh& m : meshes) {
    const ClusterTables full = ClusterTables::build(m, /*with_edges=*/false, /*with_sums=*/true);
    const ClusterTables lean = ClusterTables::build(m, /*with_edges=*/false, /*with_sums=*/true, /*lean=*/true);
    EXPECT_FALSE(full.lean);
    EXPECT_TRUE(lean.lean);
    EXPECT_TRUE(lean.area.empty() && lean.normal.empty() && lean.neighbours.empty() && lean.neighbour_offsets.empty());
    EXPECT_EQ(std::bit_cast<std::uint64_t>(lean.avg_sphere_area), std::bit_cast<std::uint64_t>(full.avg_sphere_area));
    for (std::uint32_t t = 0; t < full.triangle_count(); ++t) {
      const TriangleGeometry g = lean.geometry_of(t);
      ASSERT_EQ(std::bit_cast<std::uint64_t>(g.area), std::bit_cast<std::uint64_t>(full.area[t])) << "triangle " << t;
      for (int k = 0; k < 3; ++k)
        ASSERT_EQ(std::bit_cast<std::uint64_t>(g.normal[k]), std::bit_cast<std::uint64_t>(full.normal[t][k]))
            << "triangle " << t;
    }
    std::vector<std::uint32_t> offsets, neighbours;
    build_neighbours(m.triangles(), m.vertex_count(), offsets, neighbours);
    EXPECT_EQ(offsets, full.neighbour_offsets);
    EXPECT_EQ(neighbours, full.neighbours);
  }
  // Growth reads them all the time and refuses lean tables.
  const Mesh g = grid(4, 4, 0.1, 1);
  const ClusterTables lean = ClusterTables::build(g, false, false, true);
  NaiveObjective naive(lean, 5);
  EXPECT_THROW((void)grow_clusters(lean, naive, GrowthOptions{}), std::logic_error);
  // Acc's growth runs in an instruction-set clone: the exception leaves it without ending the
  // program (isa.h: GCC 12 compiles calls to clones as calls that cannot throw).
  ClusterParams params;
  params.max_count = 10;
  params.max_size = 10;
  params.avg_sa = 1.0;
  AccObjective acc(lean, params, AccTuning::for_growth());
  EXPECT_THROW((void)grow_clusters(lean, acc, GrowthOptions{}), std::logic_error);
}

TEST(ClusterTables, DegenerateTriangles) {
  const Mesh m = degenerate_mix();
  const ClusterTables tb = ClusterTables::build(m);
  const std::uint32_t T = tb.triangle_count();
  std::uint32_t v[3], e[3];
  EXPECT_EQ(tb.distinct_vertices(T - 4, v), 2);  // (0, 0, 1)
  EXPECT_EQ(tb.distinct_edges(T - 4, e), 1);
  EXPECT_EQ(tb.distinct_vertices(T - 3, v), 2);  // (6, 7, 6)
  EXPECT_EQ(tb.distinct_edges(T - 3, e), 1);
  EXPECT_DOUBLE_EQ(tb.triangle_perimeter(T - 3), safe_norm(m.position(7) - m.position(6)));
  EXPECT_EQ(tb.distinct_vertices(T - 1, v), 1);  // (3, 3, 3): no edge, no neighbour
  EXPECT_EQ(tb.distinct_edges(T - 1, e), 0);
  EXPECT_TRUE(tb.neighbours_of(T - 1).empty());
  EXPECT_EQ(tb.area[T - 2], 0.0);  // collinear
  EXPECT_TRUE(tb.normal[T - 2].isZero(0.0));
  for (std::uint32_t t = 0; t < T; ++t) {  // per-triangle data as triangle.h computes it
    const auto c = m.corners(t);
    const TriangleGeometry g = triangle_geometry(c[0], c[1], c[2]);
    EXPECT_EQ(tb.area[t], g.area);
    EXPECT_EQ(tb.normal[t], g.normal);
  }
}

// ---- Acc -----------------------------------------------------------------------------------

TEST(AccObjective, RejectsBadParameters) {
  const Mesh m = grid(2, 2, 0.1);
  const ClusterTables tb = ClusterTables::build(m);
  EXPECT_THROW(AccObjective(tb, acc_params(m, 0, 10)), std::invalid_argument);
  EXPECT_THROW(AccObjective(tb, acc_params(m, 10, 0)), std::invalid_argument);
  ClusterParams p = acc_params(m, 10, 10);
  p.avg_sa = 0;
  EXPECT_THROW(AccObjective(tb, p), std::invalid_argument);
}

// Closed surfaces: the normal sum vanishes, N_avg comes from average_normal's fallback rule.
TEST(AccObjective, FallbackNormalOnClosedSurfaces) {
  for (const char* name : {"regular tetrahedron", "cube.off"}) {
    const Mesh m = std::string(name) == "cube.off" ? load(name) : regular_tetrahedron();
    const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
    const ClusterTables tb = ClusterTables::build(m);
    const ClusterParams p = acc_params(m, 10, 10);
    AccObjective o(tb, p);
    Ids all(m.triangle_count());
    std::iota(all.begin(), all.end(), 0u);
    const Ids a(all.begin(), all.end() - 1), b{all.back()};
    const auto sa = summary_of(o, m, em, a);
    Candidate c;
    make_candidate(m, em, a, b, c);
    const auto ev = o.evaluate(sa, o.single(b[0]), c.ctx, Precision::Exact);
    const ClusterMetrics cm = cluster_metrics(m, all);
    ASSERT_TRUE(cm.n_avg_fallback) << name;
    EXPECT_TRUE(ev.fallback) << name;
    EXPECT_EQ(ev.n_avg, cm.n_avg) << name;
    EXPECT_NEAR(ev.area_p, cm.area_p, 1e-13 * cm.area) << name;
    EXPECT_LE(acc_error(ev.score, cm, p), 1e-12) << name;
  }
}

// A nearly closed surface: |sum n_i| ~ 1e-8 per normal, far above the fallback threshold but where
// an incremental sum (in merge order) would tilt N_avg by ~1e-8 rad; the objective recomputes the
// sum in ascending order there (kRecomputeNormalSum), so N_avg is the same bits as cluster_metrics'.
TEST(AccObjective, NearCancellationOfTheNormalSum) {
  for (double eps : {3e-7, 1e-6, 1e-5}) {
    Mesh m = regular_tetrahedron();
    std::vector<Vec3> p(m.positions().begin(), m.positions().end());
    p[0] += eps * Vec3(0.3, -0.7, 0.2);
    m = m.with_positions(std::move(p));
    const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
    const ClusterTables tb = ClusterTables::build(m);
    const ClusterParams params = acc_params(m, 10, 10);
    AccObjective o(tb, params);
    for (const Ids& a : {Ids{2, 1, 0}, Ids{1, 2, 3}, Ids{3, 0, 2}}) {
      Ids b;
      for (std::uint32_t t = 0; t < 4; ++t)
        if (std::find(a.begin(), a.end(), t) == a.end()) b.push_back(t);
      Candidate c;
      make_candidate(m, em, a, b, c);
      const auto ev = o.evaluate(summary_of(o, m, em, a), o.single(b[0]), c.ctx, Precision::Exact);
      const ClusterMetrics cm = cluster_metrics(m, Ids{0, 1, 2, 3});
      ASSERT_FALSE(cm.n_avg_fallback) << eps;
      EXPECT_EQ(ev.n_avg, cm.n_avg) << eps;
      EXPECT_LE(acc_error(ev.score, cm, params), 1e-12) << eps;
    }
  }
}

// The exact score equals cluster_acc of the merged set, for each sphere method, and the bound is
// a bound. Random pairs of clusters of 1 to 60 triangles on a real mesh (curved: the AreaP
// identity and the summed path both occur).
TEST(AccObjective, ExactScoreEqualsClusterAccFromScratch) {
  const Mesh m = load("elephant.off");
  const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
  const ClusterTables tb = ClusterTables::build(m);
  for (SphereMethod sm : {SphereMethod::Cgal, SphereMethod::Ritter, SphereMethod::Epos26, SphereMethod::Exact})
  for (const AccTuning& tuning : {AccTuning::for_contraction(), AccTuning::for_growth(), AccTuning{false, true}}) {
    const ClusterParams p = acc_params(m, 40, 20, sm);
    AccObjective o(tb, p, tuning);
    std::mt19937_64 rng(42);
    const int trials = sm == SphereMethod::Exact ? 8 : 40;
    double worst = 0, worst_area_p = 0;
    int bounded = 0;
    for (int i = 0; i < trials; ++i) {
      const auto [a, b] = random_pair(tb, rng, 1 + rng() % 60, 1 + rng() % 40);
      const auto sa = summary_of(o, m, em, a), sb = summary_of(o, m, em, b);
      Candidate c;
      make_candidate(m, em, a, b, c);
      const auto ev = o.evaluate(sa, sb, c.ctx, Precision::Exact);
      ASSERT_TRUE(ev.exact);
      const ClusterMetrics cm = cluster_metrics(m, merged(a, b), sm);
      worst = std::max(worst, acc_error(ev.score, cm, p));
      worst_area_p = std::max(worst_area_p, std::abs(ev.area_p - cm.area_p) / cm.area_p);
      for (Precision pr : {Precision::UpperBoundAllowed, Precision::RefinedBound, Precision::TightBound}) {
        const auto bound = o.evaluate(sa, sb, c.ctx, pr);
        EXPECT_GE(bound.score, ev.score) << "trial " << i;
        bounded += bound.exact ? 0 : 1;
      }
    }
    EXPECT_LE(worst, 1e-12) << to_string(sm);
    EXPECT_LE(worst_area_p, 1e-13) << to_string(sm);
    if (o.minimal_sphere()) {
      EXPECT_GT(bounded, 0) << "the bound path was not exercised";
    }
  }
}

// The contraction's cache keeps the sphere of an exact evaluation (known_of) and makes the rest
// again (evaluate_with): the same Evaluation, field by field and bit for bit, for every sphere
// method, pairs of every size (singletons included), on the elephant and far from the origin.
TEST(AccObjective, EvaluateWithTheKnownSphereIsTheExactEvaluation) {
  const Mesh elephant = load("elephant.off");
  std::vector<Vec3> far(elephant.positions().begin(), elephant.positions().end());
  for (Vec3& v : far) v = 1e-3 * v + Vec3(4e6, -2e6, 1e6);
  const Mesh moved_far = elephant.with_positions(std::move(far));
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  int checked = 0;
  for (const Mesh* m : {&elephant, &moved_far}) {
    const EdgeMap em = EdgeMap::build(m->triangles(), m->vertex_count());
    const ClusterTables tb = ClusterTables::build(*m);
    for (SphereMethod sm : {SphereMethod::Cgal, SphereMethod::Ritter, SphereMethod::Epos26}) {
      AccObjective o(tb, acc_params(*m, 40, 20, sm), AccTuning::for_contraction());
      std::mt19937_64 rng(7);
      for (int i = 0; i < 30; ++i) {
        const auto [a, b] = random_pair(tb, rng, 1 + rng() % 50, 1 + rng() % 30);
        const auto sa = summary_of(o, *m, em, a), sb = summary_of(o, *m, em, b);
        Candidate c;
        make_candidate(*m, em, a, b, c);
        const auto ev = o.evaluate(sa, sb, c.ctx, Precision::Exact);
        const auto again = o.evaluate_with(sa, sb, c.ctx, AccObjective::known_of(ev));
        const std::string what = std::string(to_string(sm)) + ", trial " + std::to_string(i);
        EXPECT_TRUE(again.exact) << what;
        EXPECT_EQ(bits(again.score), bits(ev.score)) << what;
        EXPECT_EQ(bits(again.reg), bits(ev.reg)) << what;
        EXPECT_EQ(bits(again.area_p), bits(ev.area_p)) << what;
        EXPECT_EQ(again.fallback, ev.fallback) << what;
        for (int k = 0; k < 3; ++k) {
          EXPECT_EQ(bits(again.n_avg[k]), bits(ev.n_avg[k])) << what;
          EXPECT_EQ(bits(again.normal_sum[k]), bits(ev.normal_sum[k])) << what;
          EXPECT_EQ(bits(again.box.lo[k]), bits(ev.box.lo[k])) << what;
          EXPECT_EQ(bits(again.box.hi[k]), bits(ev.box.hi[k])) << what;
          EXPECT_EQ(bits(again.sphere.center[k]), bits(ev.sphere.center[k])) << what;
        }
        EXPECT_EQ(bits(again.sphere.radius), bits(ev.sphere.radius)) << what;
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 180);
}

// Growth's case: B is one triangle adding at most one vertex; with the vertex memo on, every
// score still equals the from-scratch value (the memo is exact), also after many additions; every
// bound level bounds it, and TightBound's three-point sphere, when it claims exactness, is exact.
TEST(AccObjective, VertexMemoIsExact) {
  const Mesh m = load("elephant.off");
  const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
  const ClusterTables tb = ClusterTables::build(m);
  const ClusterParams p = acc_params(m, 60, 30);
  AccObjective o(tb, p, AccTuning::for_growth());
  std::mt19937_64 rng(7);
  double worst = 0;
  int exact_early = 0;
  for (int cluster = 0; cluster < 5; ++cluster) {
    Ids members{static_cast<std::uint32_t>(rng() % m.triangle_count())};
    auto s = o.single(members[0]);
    for (int step = 0; step < 60; ++step) {
      Ids frontier;
      for (std::uint32_t t : members)
        for (std::uint32_t u : tb.neighbours_of(t))
          if (std::find(members.begin(), members.end(), u) == members.end()) frontier.push_back(u);
      if (frontier.empty()) break;
      std::sort(frontier.begin(), frontier.end());
      frontier.erase(std::unique(frontier.begin(), frontier.end()), frontier.end());
      for (std::uint32_t d : frontier) {  // evaluate all (fills and uses the memo), as growth does
        Candidate c;
        make_candidate(m, em, members, {d}, c);
        const ClusterMetrics cm = cluster_metrics(m, merged(members, {d}));
        for (Precision pr : {Precision::UpperBoundAllowed, Precision::RefinedBound, Precision::TightBound}) {
          const auto ev = o.evaluate(s, o.single(d), c.ctx, pr);
          if (ev.exact) {
            ++exact_early;
            worst = std::max(worst, acc_error(ev.score, cm, p));
          } else {
            EXPECT_GE(ev.score, cluster_acc(cm, p) - 1e-12);
          }
        }
        const auto ev = o.evaluate(s, o.single(d), c.ctx, Precision::Exact);
        worst = std::max(worst, acc_error(ev.score, cm, p));
      }
      const std::uint32_t d = frontier[rng() % frontier.size()];
      Candidate c;
      make_candidate(m, em, members, {d}, c);
      const auto ev = o.evaluate(s, o.single(d), c.ctx, Precision::Exact);
      s = o.merge(s, o.single(d), c.ctx, ev);
      members.push_back(d);
    }
  }
  EXPECT_LE(worst, 1e-12);
  EXPECT_GT(exact_early, 100);  // the cheap exact paths (inside the sphere, memo, three points) ran
}

// The 26-DOP bound (stored as floats rounded inwards, acc.h) where it is the binding one: two
// triangles whose merged minimal sphere has the diameter P Q along one of the DOP's 10 extra
// directions, so half that direction's width is R itself. The bound must stay at or above the exact
// score (a float rounded outwards, or to nearest, lifts R_lb above R by up to 1e-7 and fails here),
// and near the origin at unit scale it must be tight (the DOP is what the bound used). Far from the
// origin (1e6), beyond the float range (1e39) and in its subnormals (1e-40) the floats are coarse,
// infinite or zero and the bound weaker, never wrong.
TEST(AccObjective, DopBoundIsABoundWhereItIsTight) {
  const Vec3 dirs[10] = {{1, 1, 1}, {1, 1, -1}, {1, -1, 1}, {-1, 1, 1}, {1, 1, 0},
                         {1, -1, 0}, {1, 0, 1}, {1, 0, -1}, {0, 1, 1}, {0, 1, -1}};
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int tight = 0;
  for (const auto& [offset, scale] : {std::pair{0.0, 1.0}, {1e6, 1.0}, {0.0, 1e39}, {0.0, 1e-40}}) {
    for (int trial = 0; trial < 40; ++trial) {
      const Vec3 u = dirs[trial % 10].normalized();
      const Vec3 w1 = u.unitOrthogonal(), w2 = u.cross(w1);
      const double d = scale * (0.1 + 0.05 * unit(rng));
      const Vec3 c = offset * Vec3(1, 1, 1) + scale * Vec3(unit(rng), unit(rng), unit(rng));
      // P, Q: the diameter; X, Y: well inside its sphere, off the axis.
      std::vector<Vec3> p{c - d * u, c + d * u, c + 0.1 * d * w1 + 0.05 * d * u, c + 0.1 * d * w2 - 0.05 * d * u};
      const Mesh m(std::vector<Tri>{{0, 2, 3}, {1, 3, 2}}, std::move(p));
      const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
      const ClusterTables tb = ClusterTables::build(m);
      AccObjective o(tb, acc_params(m, 50, 50), AccTuning{.vertex_memo = false, .dop_bound = true});
      Candidate cand;
      make_candidate(m, em, {0}, {1}, cand);
      const auto exact = o.evaluate(o.single(0), o.single(1), cand.ctx, Precision::Exact);
      ASSERT_TRUE(exact.exact);
      ASSERT_NEAR(exact.sphere.radius, d, 1e-12 * (d + offset)) << "offset " << offset << ", scale " << scale;
      const auto bound = o.evaluate(o.single(0), o.single(1), cand.ctx, Precision::UpperBoundAllowed);
      EXPECT_GE(bound.score, exact.score) << "offset " << offset << ", scale " << scale << ", trial " << trial;
      if (offset == 0.0 && scale == 1.0 && !bound.exact) {
        // Floats of coordinates near 1 are good to ~1e-7; the bound without the DOP is ~20% off.
        EXPECT_LE(bound.score - exact.score, 1e-5 * std::abs(exact.score)) << "trial " << trial;
        ++tight;
      }
    }
  }
  EXPECT_GE(tight, 30);  // the bound path ran (not a cheaper exact answer)
}

// single()'s 26-DOP in floats, rounded inwards four at a time: every end equals the float nearest
// the double extent from inside (nextafter from the nearest conversion), bit for bit, on
// coordinates around every edge of the float range: zeros of both signs, below the smallest
// subnormal, subnormals, exactly representable values, halfway cases, FLT_MAX and beyond, and
// values that overflow to infinity.
TEST(AccObjective, DopEndsAreTheNearestFloatsInside) {
  auto up = [](double x) {  // the smallest float >= x (x finite or infinite)
    float f = static_cast<float>(x);
    if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
  };
  auto down = [&](double x) { return -up(-x); };
  const double fmax = std::numeric_limits<float>::max();
  const std::vector<double> special{0.0, -0.0, 1e-46, -1e-46, 1.4e-45, -2.9e-45, 3e-45, 1e-39, -1e-39,
                                    1.0, -1.0, 1.0 + 0x1p-24, 1.0 + 0x1p-23, 1.0 + 3 * 0x1p-25, -(1.0 + 0x1p-24),
                                    fmax, -fmax, fmax * (1 + 0x1p-25), fmax * (1 + 0x1p-23), -fmax * (1 + 0x1p-23),
                                    1e39, -1e39, 1e300, -1e300, 0.1, -0.1, 1e-7, 123456.789};
  std::mt19937_64 rng(5);
  std::vector<Vec3> p;
  std::vector<Tri> tris;
  for (int t = 0; t < 3000; ++t) {
    for (int c = 0; c < 3; ++c) {
      Vec3 v;
      for (int k = 0; k < 3; ++k) {
        const std::uint64_t r = rng();
        v[k] = r % 3 == 0 ? special[(r >> 8) % special.size()]
                          : std::ldexp(static_cast<double>(static_cast<std::int64_t>(r >> 11) - (1ll << 52)),
                                       static_cast<int>((r >> 3) % 40) - 60);
      }
      p.push_back(v);
    }
    const auto b = static_cast<std::uint32_t>(3 * t);
    tris.push_back({b, b + 1, b + 2});
  }
  const Mesh m(std::move(tris), std::move(p));
  const ClusterTables tb = ClusterTables::build(m);
  ClusterParams params;
  params.max_count = 50;
  params.max_size = 50;
  params.avg_sa = 1.0;
  AccObjective o(tb, params, AccTuning{.vertex_memo = false, .dop_bound = true});
  auto bits = [](float f) { return std::bit_cast<std::uint32_t>(f); };
  int stepped = 0;
  for (std::uint32_t t = 0; t < m.triangle_count(); ++t) {
    const AccObjective::Summary s = o.single(t);
    double lo[10], hi[10];
    std::fill(lo, lo + 10, std::numeric_limits<double>::infinity());
    std::fill(hi, hi + 10, -std::numeric_limits<double>::infinity());
    for (std::uint32_t v : m.triangle(t)) {
      const double x = m.position(v).x(), y = m.position(v).y(), z = m.position(v).z();
      const double proj[10] = {x + y + z, x + y - z, x - y + z, -x + y + z, x + y, x - y, x + z, x - z, y + z, y - z};
      for (int k = 0; k < 10; ++k) lo[k] = std::min(lo[k], proj[k]), hi[k] = std::max(hi[k], proj[k]);
    }
    for (int k = 0; k < 10; ++k) {
      ASSERT_EQ(bits(s.dop_lo[k]), bits(up(lo[k]))) << "triangle " << t << ", direction " << k << ", lo " << lo[k];
      ASSERT_EQ(bits(s.dop_hi[k]), bits(down(hi[k]))) << "triangle " << t << ", direction " << k << ", hi " << hi[k];
      stepped += static_cast<double>(s.dop_lo[k]) != lo[k];
    }
  }
  EXPECT_GT(stepped, 10000);  // most ends did round
}

// Precision::SupportBound (the contraction's middle level): an upper bound on the exact score,
// never above the O(1) bound, usually much tighter; when it is exact, the exact evaluation itself.
// Its R^2 keeps the 1e-12 margin below the exact sphere's, also where the three points span the
// exact sphere (then it is within that margin of it). Near the origin, far from it and tiny.
TEST(AccObjective, SupportBoundBoundsTheExactScoreWithItsMargin) {
  const Mesh elephant = load("elephant.off");
  auto scaled = [&](double s, const Vec3& t) {
    std::vector<Vec3> p(elephant.positions().begin(), elephant.positions().end());
    for (Vec3& v : p) v = s * v + t;
    return elephant.with_positions(std::move(p));
  };
  const Mesh far = scaled(1e-3, Vec3(4e6, -2e6, 1e6)), tiny = scaled(1e-30, Vec3(0, 0, 0)),
             tinier = scaled(1e-100, Vec3(0, 0, 0));
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  int bounds = 0, tighter = 0, spanned = 0;
  for (const Mesh* m : {&elephant, &far, &tiny, &tinier}) {
    const EdgeMap em = EdgeMap::build(m->triangles(), m->vertex_count());
    const ClusterTables tb = ClusterTables::build(*m);
    AccObjective o(tb, acc_params(*m, 40, 20), AccTuning::for_contraction());
    std::mt19937_64 rng(17);
    for (int i = 0; i < 60; ++i) {
      const auto [a, b] = random_pair(tb, rng, 1 + rng() % 50, 1 + rng() % 30);
      const auto sa = summary_of(o, *m, em, a), sb = summary_of(o, *m, em, b);
      Candidate c;
      make_candidate(*m, em, a, b, c);
      const auto exact = o.evaluate(sa, sb, c.ctx, Precision::Exact);
      const auto support = o.evaluate(sa, sb, c.ctx, Precision::SupportBound);
      const auto cheap = o.evaluate(sa, sb, c.ctx, Precision::UpperBoundAllowed);
      const std::string what = "trial " + std::to_string(i) + ", scale " + std::to_string(m->position(0).norm());
      if (support.exact) {
        EXPECT_EQ(bits(support.score), bits(exact.score)) << what;
        EXPECT_EQ(bits(support.sphere.radius), bits(exact.sphere.radius)) << what;
        continue;
      }
      ++bounds;
      EXPECT_GE(support.score, exact.score) << what;
      ASSERT_FALSE(cheap.exact) << what;
      EXPECT_LE(support.score, cheap.score) << what;
      tighter += support.score < cheap.score;
      const double r2 = exact.sphere.radius * exact.sphere.radius;
      const double s2 = o.support_r2(c.ctx, exact.box);
      EXPECT_LE(s2, r2 * (1.0 - 0.5e-12)) << what;
      spanned += s2 >= r2 * (1.0 - 3e-12);
    }
  }
  EXPECT_GE(bounds, 160);
  EXPECT_GE(tighter, bounds / 2);
  EXPECT_GE(spanned, 20);  // the margin check met spheres the three points span
}

// AccTuning::large_bounds: a pair whose A has at least AccObjective::kLargeFrom vertices gets its
// bounds (UpperBoundAllowed and SupportBound) from what A keeps (ten points, the normals' second
// moment, their signed sum and horizon around A's own N_avg) instead of A's members. Upper bounds
// on the exact score, near it: pairs of a large A (grown one triangle at a time, so that it keeps
// its sums from earlier merges) and a B of one to 200 triangles (large too from 64), on a closed
// sphere (clusters that nearly close: N_avg recomputed), the hand (curved: cones that do not
// certify AreaP), far from the origin and tiny.
TEST(AccObjective, LargeClusterBoundsBoundTheExactScore) {
  const Mesh sphere = load("larger_sphere.off"), hand = load("hand.off");
  auto moved = [](const Mesh& m, double s, const Vec3& t) {
    std::vector<Vec3> p(m.positions().begin(), m.positions().end());
    for (Vec3& v : p) v = s * v + t;
    return m.with_positions(std::move(p));
  };
  const Mesh far = moved(hand, 1e-3, Vec3(4e6, -2e6, 1e6)), tiny = moved(hand, 1e-30, Vec3(0, 0, 0));
  AccTuning without = AccTuning::for_contraction();
  without.large_bounds = false;
  int pairs = 0, large_b = 0, near_support = 0, tighter_cheap = 0, recomputed = 0, settled = 0;
  for (const Mesh* m : {&sphere, &hand, &far, &tiny}) {
    const EdgeMap em = EdgeMap::build(m->triangles(), m->vertex_count());
    const ClusterTables tb = ClusterTables::build(*m);
    AccObjective o(tb, acc_params(*m, 1048576, 1e9), AccTuning::for_contraction());
    AccObjective plain(tb, acc_params(*m, 1048576, 1e9), without);
    std::mt19937_64 rng(29);
    for (int i = 0; i < (m == &sphere ? 9 : 8); ++i) {
      // On the sphere (1,620 triangles) most unions nearly close it.
      const bool closing = m == &sphere && i % 3 != 2;
      const std::size_t na = closing ? 1530 + rng() % 60 : 100 + rng() % 700, nb = 1 + rng() % (closing ? 25 : 200);
      const auto [a, b] = random_pair(tb, rng, na, nb);
      const auto sa = summary_of(o, *m, em, a), sb = summary_of(o, *m, em, b);
      Candidate c;
      make_candidate(*m, em, a, b, c);
      if (c.ctx.a_vertices.size() < AccObjective::kLargeFrom) continue;
      const std::string what = "trial " + std::to_string(i) + ", " + std::to_string(a.size()) + " + " +
                               std::to_string(b.size()) + " triangles, scale " + std::to_string(m->position(0).norm());
      const auto exact = o.evaluate(sa, sb, c.ctx, Precision::Exact);
      ASSERT_TRUE(exact.exact) << what;
      const auto support = o.evaluate(sa, sb, c.ctx, Precision::SupportBound);
      const auto cheap = o.evaluate(sa, sb, c.ctx, Precision::UpperBoundAllowed);
      // The objective without the kept sums, on summaries made alike (its own, with no Large).
      const auto pa = summary_of(plain, *m, em, a), pb = summary_of(plain, *m, em, b);
      const auto plain_exact = plain.evaluate(pa, pb, c.ctx, Precision::Exact);
      const auto plain_cheap = plain.evaluate(pa, pb, c.ctx, Precision::UpperBoundAllowed);
      EXPECT_EQ(std::bit_cast<std::uint64_t>(plain_exact.score), std::bit_cast<std::uint64_t>(exact.score)) << what;
      ++pairs;
      large_b += b.size() >= AccObjective::kLargeFrom;
      const Vec3 ns = sa.normal_sum + sb.normal_sum;
      recomputed += ns.norm() < AccObjective::kRecomputeNormalSum * (sa.nonzero + sb.nonzero);
      for (const auto* ev : {&support, &cheap}) {
        if (ev->exact) {
          EXPECT_EQ(std::bit_cast<std::uint64_t>(ev->score), std::bit_cast<std::uint64_t>(exact.score)) << what;
        } else {
          EXPECT_GE(ev->score, exact.score) << what;
        }
      }
      EXPECT_LE(cheap.score, plain_cheap.score) << what;  // never looser than the total area's bound
      tighter_cheap += cheap.score < plain_cheap.score;
      EXPECT_LE(support.score, cheap.score) << what;
      if (cheap.settled) {  // keyed as SupportBound's: it must be that key
        ++settled;
        EXPECT_EQ(std::bit_cast<std::uint64_t>(support.score), std::bit_cast<std::uint64_t>(cheap.score)) << what;
      }
      if (cheap.settled) {  // keyed as SupportBound's: it must be that key
        ++settled;
        EXPECT_EQ(std::bit_cast<std::uint64_t>(support.score), std::bit_cast<std::uint64_t>(cheap.score)) << what;
      }
      near_support += support.score <= exact.score + 0.02 * std::abs(exact.score);
    }
  }
  EXPECT_GE(pairs, 30);
  EXPECT_GE(large_b, 8);
  EXPECT_GE(recomputed, 3);
  EXPECT_GE(settled, 5);  // (12 of 33 here)
  EXPECT_GE(tighter_cheap, pairs / 2);
  EXPECT_GE(near_support, pairs / 3);  // (B of up to 200 triangles: the contraction's are mostly one or two)
}

// ---- Naive ---------------------------------------------------------------------------------

TEST(NaiveObjective, ScoreEqualsClusterMetricsAndLimitIsMaxCount) {
  const Mesh m = load("elephant.off");
  const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
  const ClusterTables tb = ClusterTables::build(m);
  EXPECT_THROW(NaiveObjective(tb, 2), std::invalid_argument);
  NaiveObjective o(tb, 30);
  std::mt19937_64 rng(3);
  for (int i = 0; i < 50; ++i) {
    const auto [a, b] = random_pair(tb, rng, 1 + rng() % 30, 1 + rng() % 30);
    Candidate c;
    make_candidate(m, em, a, b, c);
    const auto ev = o.evaluate(summary_of(o, m, em, a), summary_of(o, m, em, b), c.ctx, Precision::Exact);
    const ClusterMetrics cm = cluster_metrics(m, merged(a, b));
    EXPECT_NEAR(ev.score, cm.naive, 1e-14 * cm.naive);
    EXPECT_EQ(o.legal(c.ctx), cm.vertices <= 30);
  }
}

// ---- GWH01 ---------------------------------------------------------------------------------

double mean_edge_length(const Mesh& m) {
  const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
  double s = 0;
  for (const Edge& e : em.edges()) s += (m.position(e.v1) - m.position(e.v0)).norm();
  return s / static_cast<double>(em.edge_count());
}

void check_gwh(const Mesh& m, GwhWeight weight, int trials, std::size_t max_size) {
  const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
  const ClusterTables tb = ClusterTables::build(m);
  GwhParams params;
  params.weight = weight;
  Gwh01Objective o(tb, 1000, params);
  const double l = mean_edge_length(m);
  EXPECT_NEAR(o.fit_scale(), 1.0 / (l * l), 1e-12 / (l * l));
  std::mt19937_64 rng(11);
  for (int i = 0; i < trials; ++i) {
    const auto [a, b] = random_pair(tb, rng, 1 + rng() % max_size, 1 + rng() % max_size);
    Candidate c;
    make_candidate(m, em, a, b, c);
    const auto ev = o.evaluate(summary_of(o, m, em, a), summary_of(o, m, em, b), c.ctx, Precision::Exact);
    const GwhTerms tm = gwh_terms(m, merged(a, b), weight), ta = gwh_terms(m, a, weight), tb2 = gwh_terms(m, b, weight);
    // E_fit: the quadric merged with shared vertices subtracted, against the direct sum; the
    // error bound of gwh01.h is ~10 eps D^2 (D: cluster size), here taken relative to l^2.
    EXPECT_NEAR(ev.e_fit * o.fit_scale(), tm.fit.e_fit * o.fit_scale(), 1e-11) << "trial " << i;
    EXPECT_NEAR(ev.e_dir, tm.e_dir, 1e-12) << "trial " << i;  // the moment identity, measured
    EXPECT_NEAR(ev.perimeter, tm.perimeter, 1e-12 * std::max(1.0, tm.perimeter)) << "trial " << i;
    const double expected = -(tm.fit.e_fit * o.fit_scale() + params.a1 * tm.e_dir +
                               params.a2 * shape_cost(tm.gamma, ta.gamma, tb2.gamma));
    EXPECT_NEAR(ev.score, expected, 1e-10) << "trial " << i;
  }
}

TEST(Gwh01Objective, TermsEqualGwhTermsOfTheMergedSet) {
  check_gwh(load("elephant.off"), GwhWeight::Area, 60, 50);
  check_gwh(load("elephant.off"), GwhWeight::SqrtArea, 20, 50);
}

TEST(Gwh01Objective, NonManifoldAndDegenerateTriangles) {
  check_gwh(book(), GwhWeight::Area, 40, 3);
  check_gwh(degenerate_mix(), GwhWeight::Area, 60, 8);
}

TEST(Gwh01Objective, RejectsBadParameters) {
  const Mesh m = grid(2, 2, 0.1);
  const ClusterTables tb = ClusterTables::build(m);
  EXPECT_THROW(Gwh01Objective(tb, 2, GwhParams{}), std::invalid_argument);
  GwhParams p;
  p.a1 = -1;
  EXPECT_THROW(Gwh01Objective(tb, 10, p), std::invalid_argument);
  // Tables without the edge map (what growth with Acc or Naive builds) cannot serve GWH01.
  const ClusterTables bare = ClusterTables::build(m, /*with_edges=*/false);
  EXPECT_FALSE(bare.with_edges);
  EXPECT_THROW(Gwh01Objective(bare, 10, GwhParams{}), std::logic_error);
}

// Scaling a mesh by a power of two scales every length exactly, so every scale-free score must be
// bit-identical: Acc, Naive, and GWH01 thanks to the normalisation of E_fit (without it, the cost
// would change).
TEST(Objectives, ScoresAreScaleFree) {
  const Mesh m = load("elephant.off");
  std::vector<Vec3> scaled(m.positions().begin(), m.positions().end());
  for (Vec3& p : scaled) p *= 1024.0;
  const Mesh m2 = m.with_positions(std::move(scaled));
  const EdgeMap em = EdgeMap::build(m.triangles(), m.vertex_count());
  const ClusterTables t1 = ClusterTables::build(m), t2 = ClusterTables::build(m2);
  AccObjective a1(t1, acc_params(m, 40, 20)), a2(t2, acc_params(m2, 40, 20));
  Gwh01Objective g1(t1, 1000, GwhParams{}), g2(t2, 1000, GwhParams{});
  NaiveObjective n1(t1, 1000), n2(t2, 1000);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 20; ++i) {
    const auto [a, b] = random_pair(t1, rng, 1 + rng() % 40, 1 + rng() % 40);
    Candidate c1, c2;
    make_candidate(m, em, a, b, c1);
    make_candidate(m2, em, a, b, c2);
    EXPECT_EQ(a1.evaluate(summary_of(a1, m, em, a), summary_of(a1, m, em, b), c1.ctx, Precision::Exact).score,
              a2.evaluate(summary_of(a2, m2, em, a), summary_of(a2, m2, em, b), c2.ctx, Precision::Exact).score);
    EXPECT_EQ(g1.evaluate(summary_of(g1, m, em, a), summary_of(g1, m, em, b), c1.ctx, Precision::Exact).score,
              g2.evaluate(summary_of(g2, m2, em, a), summary_of(g2, m2, em, b), c2.ctx, Precision::Exact).score);
    EXPECT_EQ(n1.evaluate(summary_of(n1, m, em, a), summary_of(n1, m, em, b), c1.ctx, Precision::Exact).score,
              n2.evaluate(summary_of(n2, m2, em, a), summary_of(n2, m2, em, b), c2.ctx, Precision::Exact).score);
  }
}

}  // namespace
}  // namespace ptc
