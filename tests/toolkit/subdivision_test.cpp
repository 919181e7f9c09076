// Subdivider against independent answers, vertex by vertex and triangle by triangle:
// - Loop against OpenMesh's Subdivider::Uniform::LoopT (run one level at a time; the vertex
//   correspondence comes from OpenMesh's own topology: an old vertex keeps its index, a new one
//   is identified by the two old vertices it is adjacent to, i.e. its parent edge);
// - Midpoint against a direct recursive per-triangle computation;
// - hand-derived rows (Loop's thesis formula for beta, high valences beyond OpenMesh's table).
#include "toolkit/mesh/subdivision.h"

#include <gtest/gtest.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

// ---------------------------------------------------------------------------------------------
// Test meshes

struct Soup {
  std::vector<Tri> tris;
  std::vector<Vec3> pos;
};

Soup icosahedron() {
  const double g = (1 + std::sqrt(5.0)) / 2;
  Soup s;
  s.pos = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
           {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  s.tris = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
            {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
            {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  return s;
}

Soup cube() {  // valences 3 to 6
  Soup s;
  for (int i = 0; i < 8; ++i) s.pos.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  s.tris = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
            {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return s;
}

// nu x nv torus; alternating diagonals give valences 4 and 8.
Soup torus(int nu, int nv) {
  Soup s;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * std::numbers::pi * i / nu, v = 2 * std::numbers::pi * j / nv;
      s.pos.emplace_back((2 + 0.7 * std::cos(v)) * std::cos(u), (2 + 0.7 * std::cos(v)) * std::sin(u), 0.7 * std::sin(v));
    }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const auto a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2) {
        s.tris.push_back({a, b, c});
        s.tris.push_back({a, c, d});
      } else {
        s.tris.push_back({a, b, d});
        s.tris.push_back({b, c, d});
      }
    }
  return s;
}

// Open nx x ny height field with alternating diagonals: boundary vertices of 1 to 4 triangles.
Soup grid(int nx, int ny, double spacing = 1.0, Vec3 offset = Vec3::Zero()) {
  Soup s;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      s.pos.push_back(offset + spacing * Vec3(i, j, 0.3 * std::sin(i) * std::cos(1.7 * j)));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2) {
        s.tris.push_back({a, b, c});
        s.tris.push_back({a, c, d});
      } else {
        s.tris.push_back({a, b, d});
        s.tris.push_back({b, c, d});
      }
    }
  return s;
}

// Closed bipyramid over an n-gon: two apexes of valence n, equator vertices of valence 4.
Soup bipyramid(int n) {
  Soup s;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    s.pos.emplace_back(std::cos(a), std::sin(a), 0.1 * std::sin(3 * a));
  }
  s.pos.emplace_back(0, 0, 1.3);
  s.pos.emplace_back(0, 0, -0.8);
  const auto top = static_cast<std::uint32_t>(n), bottom = static_cast<std::uint32_t>(n + 1);
  for (int i = 0; i < n; ++i) {
    const auto a = static_cast<std::uint32_t>(i), b = static_cast<std::uint32_t>((i + 1) % n);
    s.tris.push_back({a, b, top});
    s.tris.push_back({b, a, bottom});
  }
  return s;
}

Soup concat(const Soup& x, const Soup& y, Vec3 shift) {
  Soup s = x;
  const auto base = static_cast<std::uint32_t>(x.pos.size());
  for (const Vec3& p : y.pos) s.pos.push_back(p + shift);
  for (const Tri& f : y.tris) s.tris.push_back({f[0] + base, f[1] + base, f[2] + base});
  return s;
}

void jitter(std::vector<Vec3>& pos, double amount, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-amount, amount);
  for (Vec3& p : pos) p += Vec3(u(rng), u(rng), u(rng));
}

// Largest coordinate magnitude of the referenced vertices (the scale tolerances refer to).
double scale_of(const Soup& m) {
  double s = 0;
  for (const Tri& f : m.tris)
    for (std::uint32_t v : f) s = std::max(s, m.pos[v].cwiseAbs().maxCoeff());
  return s;
}

std::vector<Vec3> refine(const Subdivider& s, std::span<const Vec3> in) {
  std::vector<Vec3> out(s.vertex_count());
  s.apply(in, out);
  return out;
}

// Brute-force edge set, lexicographic (the documented numbering of new vertices).
std::vector<std::pair<std::uint32_t, std::uint32_t>> brute_edges(std::span<const Tri> tris) {
  std::set<std::pair<std::uint32_t, std::uint32_t>> e;
  for (const Tri& f : tris)
    for (int k = 0; k < 3; ++k)
      if (f[k] != f[(k + 1) % 3]) e.insert({std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])});
  return {e.begin(), e.end()};
}

// Oriented triangle up to rotation: smallest index first.
Tri normalized(Tri f) {
  while (f[0] > f[1] || f[0] > f[2]) f = {f[1], f[2], f[0]};
  return f;
}
std::vector<Tri> as_sorted_set(std::span<const Tri> tris) {
  std::vector<Tri> v;
  for (const Tri& f : tris) v.push_back(normalized(f));
  std::sort(v.begin(), v.end());
  return v;
}

// ---------------------------------------------------------------------------------------------
// OpenMesh oracle

struct OmTraits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<OmTraits>;

struct Refined {
  std::vector<std::pair<std::uint32_t, Vec3>> vertices;  // (our index, OpenMesh's position)
  std::vector<Tri> triangles;                            // in our numbering
};

// OpenMesh's mesh of the soup; false when OpenMesh refuses a triangle (complex vertex).
bool build_openmesh(const Soup& in, OmMesh& om) {
  for (const Vec3& p : in.pos) om.add_vertex(OmMesh::Point(p.x(), p.y(), p.z()));
  bool ok = true;
  for (const Tri& f : in.tris)
    ok &= om.add_face(om.vertex_handle(f[0]), om.vertex_handle(f[1]), om.vertex_handle(f[2])).is_valid();
  return ok;
}

// LoopT applied `levels` times to om. OpenMesh vertex i of the input is our vertex alias[i]
// (identity unless a vertex was split into copies for OpenMesh); our_vertex_count is our input
// vertex count. New vertices are numbered by our documented rule: V + rank of the parent edge
// (smaller, larger endpoint) among the level's edges, both read off OpenMesh's mesh.
Refined openmesh_loop(OmMesh& om, std::vector<std::uint32_t> alias, std::size_t our_vertex_count, int levels) {
  std::vector<std::uint32_t>& ours = alias;
  std::size_t V = our_vertex_count;
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> rank;
    for (auto eh : om.edges()) {
      const auto h = om.halfedge_handle(eh, 0);
      const std::uint32_t a = ours[om.from_vertex_handle(h).idx()], b = ours[om.to_vertex_handle(h).idx()];
      rank[{std::min(a, b), std::max(a, b)}] = 0;
    }
    std::uint32_t r = 0;
    for (auto& [key, value] : rank) value = r++;
    const std::size_t old_count = om.n_vertices();
    OpenMesh::Subdivider::Uniform::LoopT<OmMesh, double> loop;
    loop(om, 1);
    ours.resize(om.n_vertices());
    for (std::size_t i = old_count; i < om.n_vertices(); ++i) {
      std::vector<std::uint32_t> parents;
      for (auto vv : om.vv_range(om.vertex_handle(static_cast<unsigned>(i))))
        if (static_cast<std::size_t>(vv.idx()) < old_count) parents.push_back(ours[vv.idx()]);
      EXPECT_EQ(parents.size(), 2u) << "new OpenMesh vertex " << i;
      if (parents.size() != 2) continue;
      ours[i] = static_cast<std::uint32_t>(V + rank.at({std::min(parents[0], parents[1]), std::max(parents[0], parents[1])}));
    }
    V += rank.size();
  }
  Refined out;
  for (std::size_t i = 0; i < om.n_vertices(); ++i) {
    const auto& p = om.point(om.vertex_handle(static_cast<unsigned>(i)));
    out.vertices.push_back({ours[i], Vec3(p[0], p[1], p[2])});
  }
  for (auto fh : om.faces()) {
    Tri f{};
    int k = 0;
    for (auto fv : om.fv_range(fh)) f[k++] = ours[fv.idx()];
    out.triangles.push_back(f);
  }
  return out;
}

Refined openmesh_loop(const Soup& in, std::vector<std::uint32_t> alias, std::size_t our_vertex_count, int levels) {
  OmMesh om;
  EXPECT_TRUE(build_openmesh(in, om)) << "OpenMesh refused a triangle of the test mesh";
  return openmesh_loop(om, std::move(alias), our_vertex_count, levels);
}

Refined openmesh_loop(const Soup& in, int levels) {
  std::vector<std::uint32_t> alias(in.pos.size());
  for (std::uint32_t i = 0; i < alias.size(); ++i) alias[i] = i;
  return openmesh_loop(in, alias, in.pos.size(), levels);
}

// Every refined vertex of `s` applied to `in` matches OpenMesh within 1e-12 of the mesh's
// scale, except the indices in `skip`; the triangle sets agree.
void expect_matches_openmesh(const Subdivider& s, const Soup& in, const Refined& om, const std::set<std::uint32_t>& skip = {}) {
  const std::vector<Vec3> ours = refine(s, in.pos);
  const double tol = 1e-12 * std::max(1.0, scale_of(in));
  std::vector<int> seen(s.vertex_count(), 0);
  for (const auto& [i, p] : om.vertices) {
    ASSERT_LT(i, s.vertex_count());
    ++seen[i];
    if (skip.count(i)) continue;
    EXPECT_LE((ours[i] - p).norm(), tol) << "vertex " << i << ": ours " << ours[i].transpose() << " OpenMesh "
                                         << p.transpose();
  }
  for (std::size_t i = 0; i < seen.size(); ++i)
    if (!skip.count(static_cast<std::uint32_t>(i))) {
      EXPECT_EQ(seen[i], 1) << "vertex " << i;
    }
  EXPECT_EQ(as_sorted_set(s.triangles()), as_sorted_set(om.triangles));
}

// ---------------------------------------------------------------------------------------------
// Midpoint oracle: direct recursive split of each triangle's corner positions, in the
// documented child order.
void direct_midpoint(const Vec3& a, const Vec3& b, const Vec3& c, int levels, std::vector<std::array<Vec3, 3>>& out) {
  if (levels == 0) {
    out.push_back({a, b, c});
    return;
  }
  const Vec3 ab = 0.5 * (a + b), bc = 0.5 * (b + c), ca = 0.5 * (c + a);
  direct_midpoint(a, ab, ca, levels - 1, out);
  direct_midpoint(ab, b, bc, levels - 1, out);
  direct_midpoint(ca, bc, c, levels - 1, out);
  direct_midpoint(ab, bc, ca, levels - 1, out);
}

// Every corner of every refined triangle equals the direct computation (tolerance relative to
// the mesh's scale; 0 demands bitwise equality).
void expect_matches_direct_midpoint(const Soup& in, int levels, double rel_tol) {
  const Subdivider s = Subdivider::build(in.tris, in.pos.size(), SubdivisionScheme::Midpoint, levels);
  const std::vector<Vec3> out = refine(s, in.pos);
  const std::size_t per = std::size_t{1} << (2 * levels);
  ASSERT_EQ(s.triangles().size(), per * in.tris.size());
  const double tol = rel_tol * std::max(1.0, scale_of(in));
  std::vector<std::array<Vec3, 3>> expected;
  for (std::size_t t = 0; t < in.tris.size(); ++t) {
    expected.clear();
    const Tri& f = in.tris[t];
    direct_midpoint(in.pos[f[0]], in.pos[f[1]], in.pos[f[2]], levels, expected);
    for (std::size_t c = 0; c < per; ++c)
      for (int k = 0; k < 3; ++k) {
        const Vec3& got = out[s.triangles()[per * t + c][k]];
        if (rel_tol == 0) {
          EXPECT_EQ(got, expected[c][k]) << "triangle " << t << " child " << c << " corner " << k;
        } else {
          EXPECT_LE((got - expected[c][k]).norm(), tol) << "triangle " << t << " child " << c << " corner " << k;
        }
      }
  }
}

double area(const Vec3& a, const Vec3& b, const Vec3& c) { return 0.5 * (b - a).cross(c - a).norm(); }

// ---------------------------------------------------------------------------------------------

TEST(SubdivScheme, ParseAndName) {
  EXPECT_EQ(parse_subdivision_scheme("loop"), SubdivisionScheme::Loop);
  EXPECT_EQ(parse_subdivision_scheme("Midpoint"), SubdivisionScheme::Midpoint);
  EXPECT_EQ(parse_subdivision_scheme("LOOP"), SubdivisionScheme::Loop);
  EXPECT_EQ(parse_subdivision_scheme(""), std::nullopt);
  EXPECT_EQ(parse_subdivision_scheme("loop "), std::nullopt);
  EXPECT_EQ(parse_subdivision_scheme("catmull-clark"), std::nullopt);
  for (auto s : {SubdivisionScheme::Midpoint, SubdivisionScheme::Loop}) EXPECT_EQ(parse_subdivision_scheme(to_string(s)), s);
}

TEST(SubdivLoop, ClosedMeshesMatchOpenMesh) {
  Soup ico = icosahedron(), cu = cube(), to = torus(8, 6), bi = bipyramid(40);  // valences 3 .. 40
  jitter(cu.pos, 0.05, 1);
  jitter(to.pos, 0.05, 2);
  for (const Soup* m : {&ico, &cu, &to, &bi})
    for (int levels : {1, 2}) {
      SCOPED_TRACE(testing::Message() << m->tris.size() << " triangles, " << levels << " levels");
      const Subdivider s = Subdivider::build(m->tris, m->pos.size(), SubdivisionScheme::Loop, levels);
      expect_matches_openmesh(s, *m, openmesh_loop(*m, levels));
    }
}

TEST(SubdivLoop, OpenMeshesWithBoundaryMatchOpenMesh) {
  Soup g = grid(5, 4);
  jitter(g.pos, 0.1, 3);
  Soup single{{{0, 1, 2}}, {{0, 0, 0}, {1, 0, 0.2}, {0.3, 1, -0.1}}};
  Soup cube_without_top = cube();
  cube_without_top.tris.erase(cube_without_top.tris.begin() + 2, cube_without_top.tris.begin() + 4);
  for (const Soup* m : {&g, &single, &cube_without_top})
    for (int levels : {1, 2}) {
      SCOPED_TRACE(testing::Message() << m->tris.size() << " triangles, " << levels << " levels");
      const Subdivider s = Subdivider::build(m->tris, m->pos.size(), SubdivisionScheme::Loop, levels);
      expect_matches_openmesh(s, *m, openmesh_loop(*m, levels));
    }
}

TEST(SubdivLoop, TwoComponentsMatchOpenMesh) {
  Soup m = concat(icosahedron(), grid(3, 3), Vec3(5, 0, 0));
  for (int levels : {1, 2}) {
    const Subdivider s = Subdivider::build(m.tris, m.pos.size(), SubdivisionScheme::Loop, levels);
    expect_matches_openmesh(s, m, openmesh_loop(m, levels));
  }
}

// The linear-map property animation relies on: the map built with one frame's topology, applied
// to another frame, equals subdividing that frame from scratch.
TEST(SubdivLoop, MapBuiltOnceAppliesToAnyFrame) {
  Soup rest = torus(10, 7);
  const Subdivider s = Subdivider::build(rest.tris, rest.pos.size(), SubdivisionScheme::Loop, 2);
  for (std::uint64_t frame = 0; frame < 3; ++frame) {
    Soup moved = rest;
    jitter(moved.pos, 0.3, 100 + frame);
    for (Vec3& p : moved.pos) p = Vec3(p.x() * 1.5, p.y() + 0.2 * p.x() * p.x(), p.z() - 4);  // a non-rigid motion
    expect_matches_openmesh(s, moved, openmesh_loop(moved, 2));
  }
}

TEST(SubdivLoop, ValenceBeyondOpenMeshTableUsesLoopsFormula) {
  // OpenMesh's LoopT tabulates weights up to valence 49; apexes here have valence 60. The
  // expected row is Loop's thesis form, beta = (5/8 - (3/8 + 1/4 cos(2 pi / n))^2) / n,
  // v' = (1 - n beta) v + beta * sum of neighbours, evaluated in long double.
  const int n = 60;
  const Soup m = bipyramid(n);
  const Subdivider s = Subdivider::build(m.tris, m.pos.size(), SubdivisionScheme::Loop, 1);
  const auto out = refine(s, m.pos);
  const long double pi = std::numbers::pi_v<long double>;
  const long double c = 0.375L + 0.25L * std::cos(2 * pi / n);
  const long double beta = (0.625L - c * c) / n;
  for (std::uint32_t apex : {static_cast<std::uint32_t>(n), static_cast<std::uint32_t>(n + 1)}) {
    for (int d = 0; d < 3; ++d) {
      long double sum = 0;
      for (int i = 0; i < n; ++i) sum += m.pos[i][d];
      const long double expected = (1 - n * beta) * m.pos[apex][d] + beta * sum;
      EXPECT_NEAR(out[apex][d], static_cast<double>(expected), 1e-14) << "apex " << apex << " coordinate " << d;
    }
    const auto row = s.row(apex);
    EXPECT_EQ(row.columns.size(), static_cast<std::size_t>(n + 1));
    EXPECT_EQ(row.columns[0], apex);  // the anchor is the vertex itself
  }
  // Equator vertex 0 (valence 4: vertices 1, n-1 and both apexes), and the edge 0-1 (opposite
  // vertices: the apexes).
  const long double c4 = 0.375L + 0.25L * std::cos(2 * pi / 4), beta4 = (0.625L - c4 * c4) / 4;
  const std::uint32_t ring[4] = {1, static_cast<std::uint32_t>(n - 1), static_cast<std::uint32_t>(n),
                                 static_cast<std::uint32_t>(n + 1)};
  const auto edges = brute_edges(m.tris);
  const std::size_t e01 = std::find(edges.begin(), edges.end(), std::pair<std::uint32_t, std::uint32_t>{0, 1}) - edges.begin();
  for (int d = 0; d < 3; ++d) {
    long double sum = 0;
    for (auto r : ring) sum += m.pos[r][d];
    EXPECT_NEAR(out[0][d], static_cast<double>((1 - 4 * beta4) * m.pos[0][d] + beta4 * sum), 1e-15);
    const double edge_point = 0.375 * (m.pos[0][d] + m.pos[1][d]) + 0.125 * (m.pos[n][d] + m.pos[n + 1][d]);
    EXPECT_NEAR(out[m.pos.size() + e01][d], edge_point, 1e-15);
  }
}

TEST(SubdivLoop, NonManifoldVertexIsACorner) {
  // Two tetrahedra touching at vertex 0 (no boundary, two closed fans), and a bowtie of two
  // open fans at vertex 0. Vertex 0 keeps its position at every level. Everything else of the
  // first level equals OpenMesh on the mesh with vertex 0 split into one copy per fan (a new
  // position reads only old positions, and vertex 0's old position is the same in both copies).
  Soup tetras{{{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}, {0, 5, 4}, {0, 6, 5}, {0, 4, 6}, {4, 5, 6}},
              {{0, 0, 0}, {1, 0, 0.3}, {0.2, 1, 0.1}, {0.4, 0.3, 1}, {-1, 0.1, -0.2}, {-0.1, -1, 0}, {-0.3, -0.2, -1}}};
  Soup bowtie{{{0, 1, 2}, {0, 2, 3}, {0, 4, 5}, {0, 5, 6}},
              {{0, 0, 0}, {1, -0.5, 0}, {1.2, 0.2, 0.3}, {0.8, 0.9, 0}, {-1, 0.4, 0}, {-1.1, -0.3, 0.2}, {-0.7, -1, 0}}};
  for (Soup* m : {&tetras, &bowtie}) {
    // Split: the second fan (triangles from index half on) uses a copy of vertex 0.
    Soup split = *m;
    const auto copy = static_cast<std::uint32_t>(split.pos.size());
    split.pos.push_back(split.pos[0]);
    for (std::size_t t = split.tris.size() / 2; t < split.tris.size(); ++t)
      for (auto& v : split.tris[t])
        if (v == 0) v = copy;
    std::vector<std::uint32_t> alias(split.pos.size());
    for (std::uint32_t i = 0; i < alias.size(); ++i) alias[i] = i;
    alias[copy] = 0;

    const Subdivider s1 = Subdivider::build(m->tris, m->pos.size(), SubdivisionScheme::Loop, 1);
    expect_matches_openmesh(s1, *m, openmesh_loop(split, alias, m->pos.size(), 1), {0});
    EXPECT_EQ(refine(s1, m->pos)[0], m->pos[0]);
    const Subdivider s3 = Subdivider::build(m->tris, m->pos.size(), SubdivisionScheme::Loop, 3);
    EXPECT_EQ(refine(s3, m->pos)[0], m->pos[0]);
  }
}

TEST(SubdivLoop, OrientationIsNotRequired) {
  // The cube with two faces flipped: same positions as the consistently oriented cube, and each
  // flipped parent's children are the flipped children.
  Soup good = cube();
  jitter(good.pos, 0.05, 9);
  Soup bad = good;
  for (std::size_t t : {3u, 7u}) std::swap(bad.tris[t][1], bad.tris[t][2]);
  const Subdivider sg = Subdivider::build(good.tris, good.pos.size(), SubdivisionScheme::Loop, 2);
  const Subdivider sb = Subdivider::build(bad.tris, bad.pos.size(), SubdivisionScheme::Loop, 2);
  ASSERT_EQ(sg.vertex_count(), sb.vertex_count());
  const auto pg = refine(sg, good.pos), pb = refine(sb, bad.pos);
  for (std::size_t i = 0; i < pg.size(); ++i) EXPECT_LE((pg[i] - pb[i]).norm(), 1e-15) << "vertex " << i;
  for (std::size_t t = 0; t < good.tris.size(); ++t) {
    const bool flipped = t == 3 || t == 7;
    std::vector<Tri> want;
    for (Tri g : sg.triangles().subspan(16 * t, 16)) want.push_back(flipped ? Tri{g[0], g[2], g[1]} : g);
    EXPECT_EQ(as_sorted_set(want), as_sorted_set(sb.triangles().subspan(16 * t, 16))) << "triangle " << t;
  }
}

TEST(SubdivLoop, FuzzPiercedTorusAgainstOpenMesh) {
  // Tori with random triangles removed: boundaries of every shape and bowtie vertices. Where
  // OpenMesh accepts the mesh, level 1 matches it everywhere except at the vertices OpenMesh
  // calls non-manifold (ours keep their position: corners) and at isolated vertices (OpenMesh
  // leaves them undefined; ours are carried unchanged). Without non-manifold vertices, level 2
  // matches too.
  std::mt19937_64 rng(77);
  int compared = 0, compared_two_levels = 0;
  for (int round = 0; round < 150; ++round) {
    Soup full = torus(6, 5);
    jitter(full.pos, 0.1, 1000 + static_cast<std::uint64_t>(round));
    Soup m = full;
    for (int k = 1 + round % 6; k > 0 && !m.tris.empty(); --k) m.tris.erase(m.tris.begin() + static_cast<std::ptrdiff_t>(rng() % m.tris.size()));
    if (round % 5 == 0)  // and sometimes a band, for long boundaries
      m.tris.erase(m.tris.begin(), m.tris.begin() + 10);
    if (m.tris.empty()) continue;
    OmMesh om;
    if (!build_openmesh(m, om)) continue;
    std::set<std::uint32_t> skip;
    bool non_manifold = false;
    for (auto vh : om.vertices()) {
      if (om.is_isolated(vh)) skip.insert(static_cast<std::uint32_t>(vh.idx()));
      else if (!om.is_manifold(vh)) {
        skip.insert(static_cast<std::uint32_t>(vh.idx()));
        non_manifold = true;
      }
    }
    SCOPED_TRACE(testing::Message() << "round " << round);
    const int levels = non_manifold ? 1 : 2;
    const Subdivider s = Subdivider::build(m.tris, m.pos.size(), SubdivisionScheme::Loop, levels);
    std::vector<std::uint32_t> alias(m.pos.size());
    for (std::uint32_t i = 0; i < alias.size(); ++i) alias[i] = i;
    expect_matches_openmesh(s, m, openmesh_loop(om, alias, m.pos.size(), levels), skip);
    const auto out = refine(s, m.pos);
    for (std::uint32_t v : skip) EXPECT_EQ(out[v], m.pos[v]) << "vertex " << v;
    ++compared;
    compared_two_levels += levels == 2;
  }
  EXPECT_GT(compared, 100);
  EXPECT_GT(compared_two_levels, 10);
}

TEST(SubdivLoop, RejectsNonManifoldEdgeNamingIt) {
  // Three triangles on edge (12, 40), among degenerate triangles and a duplicate.
  std::vector<Tri> tris{{12, 40, 1}, {40, 12, 2}, {12, 40, 3}, {5, 5, 6}, {7, 8, 7}, {1, 2, 3}, {1, 2, 3}};
  try {
    (void)Subdivider::build(tris, 41, SubdivisionScheme::Loop, 1);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "");
    EXPECT_EQ(e.element(), "edge (12, 40)");
    EXPECT_NE(e.reason().find("3 triangles (0, 1, 2)"), std::string::npos) << e.what();
  }
}

TEST(SubdivLoop, RejectsRepeatedIndexNamingTheTriangle) {
  for (const Tri bad : {Tri{3, 3, 4}, Tri{3, 4, 3}, Tri{4, 4, 4}}) {
    std::vector<Tri> tris{{0, 1, 2}, {0, 2, 3}, bad};
    try {
      (void)Subdivider::build(tris, 5, SubdivisionScheme::Loop, 2);
      FAIL() << "no InputError";
    } catch (const InputError& e) {
      EXPECT_EQ(e.element(), "triangle 2");
    }
  }
  // Two triangles on the same corners (a two-sided pillow, or a duplicate): one level would be
  // defined, the next not (four triangles on the children's inner edges): rejected up front.
  for (const Tri second : {Tri{0, 2, 1}, Tri{1, 2, 0}}) {
    std::vector<Tri> tris{{3, 4, 5}, {0, 1, 2}, second};
    try {
      (void)Subdivider::build(tris, 6, SubdivisionScheme::Loop, 1);
      FAIL() << "no InputError";
    } catch (const InputError& e) {
      EXPECT_EQ(e.element(), "triangle 2");
      EXPECT_NE(e.reason().find("as triangle 1"), std::string::npos) << e.what();
    }
  }
  // Levels 0 is the identity and checks nothing.
  EXPECT_NO_THROW((void)Subdivider::build(std::vector<Tri>{{1, 1, 1}}, 2, SubdivisionScheme::Loop, 0));
}

TEST(SubdivLoop, TranslationInvariantFarFromOrigin) {
  // Offsets of 1e7 and features of 1e-3: Loop(P + o) - o equals Loop(P) to within one ulp of
  // 1e7 (the anchored evaluation keeps the differences exact).
  Soup near = grid(6, 5, 1e-3);
  jitter(near.pos, 2e-4, 5);
  Soup far = near;
  const Vec3 o(1e7, -1e7, 1e7);
  for (Vec3& p : far.pos) p += o;
  const Subdivider s = Subdivider::build(near.tris, near.pos.size(), SubdivisionScheme::Loop, 2);
  const auto a = refine(s, near.pos), b = refine(s, far.pos);
  const double ulp = std::nextafter(1e7, 2e7) - 1e7;
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LE((b[i] - o - a[i]).cwiseAbs().maxCoeff(), ulp) << "vertex " << i;
}

// ---------------------------------------------------------------------------------------------

TEST(SubdivMidpoint, MatchesDirectPerTriangleComputation) {
  Soup to = torus(9, 5), g = grid(4, 3), single{{{0, 1, 2}}, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  jitter(to.pos, 0.1, 11);
  for (const Soup* m : {&to, &g, &single})
    for (int levels : {1, 2, 3}) expect_matches_direct_midpoint(*m, levels, 4e-16);
}

TEST(SubdivMidpoint, DegenerateAndNonManifoldInput) {
  // Non-manifold edge (0, 1), collapsed sides, a triangle a b a, a point triangle, a duplicate.
  Soup m{{{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {2, 2, 3}, {1, 3, 1}, {4, 4, 4}, {0, 1, 2}, {3, 4, 2}},
         {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, -1, 0.2}, {0.4, 0.1, 1}}};
  for (int levels : {1, 2}) expect_matches_direct_midpoint(m, levels, 4e-16);
  const Subdivider s = Subdivider::build(m.tris, m.pos.size(), SubdivisionScheme::Midpoint, 1);
  EXPECT_EQ(s.vertex_count(), m.pos.size() + brute_edges(m.tris).size());
  // The non-manifold edge has one midpoint shared by its three triangles (a conforming split).
  const auto edges = brute_edges(m.tris);
  const auto mid01 = static_cast<std::uint32_t>(m.pos.size() + (std::find(edges.begin(), edges.end(), std::pair<std::uint32_t, std::uint32_t>{0, 1}) - edges.begin()));
  for (std::size_t t : {0u, 1u, 2u, 6u}) EXPECT_EQ(s.triangles()[4 * t + 3][0], mid01) << "triangle " << t;
}

TEST(SubdivMidpoint, KeepsTheSurface) {
  // Every refined vertex lies on its root triangle (barycentric coordinates in [0, 1], on its
  // plane) and each triangle's area is kept to 1e-12 relative.
  Soup m = torus(7, 5);
  jitter(m.pos, 0.2, 13);
  const int levels = 3;
  const Subdivider s = Subdivider::build(m.tris, m.pos.size(), SubdivisionScheme::Midpoint, levels);
  const auto out = refine(s, m.pos);
  const std::size_t per = 64;
  double total_before = 0, total_after = 0;
  for (std::size_t t = 0; t < m.tris.size(); ++t) {
    const Vec3 &a = m.pos[m.tris[t][0]], &b = m.pos[m.tris[t][1]], &c = m.pos[m.tris[t][2]];
    Eigen::Matrix<double, 3, 2> J;
    J << b - a, c - a;
    const double parent = area(a, b, c);
    double children = 0;
    for (std::size_t k = 0; k < per; ++k) {
      const Tri& f = s.triangles()[per * t + k];
      children += area(out[f[0]], out[f[1]], out[f[2]]);
      for (std::uint32_t v : f) {
        const Eigen::Vector2d uv = J.colPivHouseholderQr().solve(out[v] - a);
        EXPECT_LE((a + J * uv - out[v]).norm(), 1e-12) << "off the plane of triangle " << t;
        for (double w : {uv.x(), uv.y(), 1 - uv.x() - uv.y()}) {
          EXPECT_GE(w, -1e-12) << "outside triangle " << t;
          EXPECT_LE(w, 1 + 1e-12) << "outside triangle " << t;
        }
      }
    }
    EXPECT_NEAR(children, parent, 1e-12 * parent) << "triangle " << t;
    total_before += parent;
    total_after += children;
  }
  EXPECT_NEAR(total_after, total_before, 1e-12 * total_before);
  // A conforming split of a surface without coincident vertices has no coincident refined vertices.
  std::set<std::array<double, 3>> distinct;
  for (const Vec3& p : out) distinct.insert({p.x(), p.y(), p.z()});
  EXPECT_EQ(distinct.size(), s.vertex_count());
}

TEST(SubdivMidpoint, MapBuiltOnceAppliesToAnyFrame) {
  Soup rest = torus(6, 5);
  const Subdivider s = Subdivider::build(rest.tris, rest.pos.size(), SubdivisionScheme::Midpoint, 2);
  Soup moved = rest;
  jitter(moved.pos, 0.5, 21);
  const auto got = refine(s, moved.pos);
  std::vector<std::array<Vec3, 3>> expected;
  for (std::size_t t = 0; t < moved.tris.size(); ++t) {
    expected.clear();
    direct_midpoint(moved.pos[moved.tris[t][0]], moved.pos[moved.tris[t][1]], moved.pos[moved.tris[t][2]], 2, expected);
    for (std::size_t c = 0; c < 16; ++c)
      for (int k = 0; k < 3; ++k) EXPECT_LE((got[s.triangles()[16 * t + c][k]] - expected[c][k]).norm(), 1e-15);
  }
}

TEST(SubdivMidpoint, HugeOffsetTinyFeaturesExact) {
  // Level 1: every midpoint is bitwise the correctly rounded 1/2 (a + b), old vertices are copies.
  Soup m = grid(5, 4, 1e-3, Vec3(1e7, -1e7, 1e7));
  jitter(m.pos, 3e-4, 17);
  const Subdivider s = Subdivider::build(m.tris, m.pos.size(), SubdivisionScheme::Midpoint, 1);
  const auto out = refine(s, m.pos);
  const auto edges = brute_edges(m.tris);
  ASSERT_EQ(out.size(), m.pos.size() + edges.size());
  for (std::size_t v = 0; v < m.pos.size(); ++v) EXPECT_EQ(out[v], m.pos[v]);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const Vec3 expected = 0.5 * (m.pos[edges[e].first] + m.pos[edges[e].second]);
    EXPECT_EQ(out[m.pos.size() + e], expected) << "edge " << edges[e].first << "-" << edges[e].second;
    EXPECT_GT((out[m.pos.size() + e] - m.pos[edges[e].first]).norm(), 1e-4);  // the feature survives
  }
  // Levels 1-3 on dyadic coordinates (1e7 + k 2^-10): every refined vertex is representable,
  // so the direct computation and ours must agree bitwise.
  Soup dyadic = grid(4, 3, 1.0 / 1024, Vec3(1e7, 1e7, -1e7));
  for (Vec3& p : dyadic.pos) p.z() = -1e7 + std::round((p.z() + 1e7) * 1024) / 1024;
  for (int levels : {1, 2, 3}) expect_matches_direct_midpoint(dyadic, levels, 0);
}

// ---------------------------------------------------------------------------------------------

TEST(SubdivCommon, EmptyInput) {
  for (auto scheme : {SubdivisionScheme::Midpoint, SubdivisionScheme::Loop}) {
    const Subdivider s = Subdivider::build({}, 0, scheme, 2);
    EXPECT_TRUE(s.triangles().empty());
    EXPECT_EQ(s.vertex_count(), 0u);
    EXPECT_NO_THROW(s.apply({}, {}));
    // Vertices without triangles are carried unchanged.
    const std::vector<Vec3> lone{{1, 2, 3}, {-4, 5, 6e300}};
    const Subdivider t = Subdivider::build({}, lone.size(), scheme, 3);
    EXPECT_TRUE(t.triangles().empty());
    EXPECT_EQ(refine(t, lone), lone);
  }
  const Subdivider d;
  EXPECT_EQ(d.vertex_count(), 0u);
  EXPECT_TRUE(d.triangles().empty());
}

TEST(SubdivCommon, LevelZeroIsIdentity) {
  Soup m = torus(5, 4);
  jitter(m.pos, 0.1, 31);
  m.pos.emplace_back(9, 9, 9);  // unreferenced
  for (auto scheme : {SubdivisionScheme::Midpoint, SubdivisionScheme::Loop}) {
    const Subdivider s = Subdivider::build(m.tris, m.pos.size(), scheme, 0);
    EXPECT_EQ(std::vector<Tri>(s.triangles().begin(), s.triangles().end()), m.tris);
    EXPECT_EQ(refine(s, m.pos), m.pos);
  }
}

TEST(SubdivCommon, NegativeLevelsAreBadInput) {
  try {
    (void)Subdivider::build(cube().tris, 8, SubdivisionScheme::Loop, -1);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.element(), "levels");
  }
  // Too many levels for 32-bit indices: refused before any allocation.
  EXPECT_THROW((void)Subdivider::build(cube().tris, 8, SubdivisionScheme::Midpoint, 16), InputError);
  // An index out of range is a programmer error, as for Mesh.
  EXPECT_THROW((void)Subdivider::build(std::vector<Tri>{{0, 1, 8}}, 8, SubdivisionScheme::Midpoint, 1),
               std::invalid_argument);
}

TEST(SubdivCommon, UnreferencedVerticesAreCarried) {
  // The icosahedron with unreferenced vertices interleaved (indices shifted): unreferenced ones
  // keep index and position bitwise; the rest equals OpenMesh on the mesh without them.
  const Soup ico = icosahedron();
  Soup m;
  std::vector<std::uint32_t> where;
  for (std::size_t i = 0; i < ico.pos.size(); ++i) {
    if (i % 3 == 0) m.pos.emplace_back(100.0 + static_cast<double>(i), -7, 3);
    where.push_back(static_cast<std::uint32_t>(m.pos.size()));
    m.pos.push_back(ico.pos[i]);
  }
  m.pos.emplace_back(1e300, -0.0, 5e-324);
  for (const Tri& f : ico.tris) m.tris.push_back({where[f[0]], where[f[1]], where[f[2]]});
  for (auto scheme : {SubdivisionScheme::Midpoint, SubdivisionScheme::Loop}) {
    const Subdivider s = Subdivider::build(m.tris, m.pos.size(), scheme, 2);
    const auto out = refine(s, m.pos);
    std::set<std::uint32_t> unreferenced;
    for (std::uint32_t v = 0; v < m.pos.size(); ++v)
      if (std::find(where.begin(), where.end(), v) == where.end()) {
        unreferenced.insert(v);
        EXPECT_EQ(out[v], m.pos[v]) << "vertex " << v;
        EXPECT_TRUE(std::signbit(out[v].y()) == std::signbit(m.pos[v].y()));
      }
    if (scheme == SubdivisionScheme::Loop) {
      // OpenMesh leaves isolated vertices' positions undefined: compare the others only.
      Refined om = openmesh_loop(m, 2);
      std::erase_if(om.vertices, [&](const auto& iv) { return unreferenced.count(iv.first) != 0; });
      for (std::uint32_t u : unreferenced) om.vertices.push_back({u, m.pos[u]});
      expect_matches_openmesh(s, m, om);
    } else {
      expect_matches_direct_midpoint(m, 2, 4e-16);
    }
  }
}

TEST(SubdivCommon, Counts) {
  const Soup ms[] = {icosahedron(), torus(6, 4), grid(3, 2), Soup{{{0, 1, 2}}, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}};
  for (const Soup& m : ms)
    for (auto scheme : {SubdivisionScheme::Midpoint, SubdivisionScheme::Loop}) {
      std::size_t V = m.pos.size();
      std::vector<Tri> level(m.tris);
      for (int levels = 0; levels <= 3; ++levels) {
        const Subdivider s = Subdivider::build(m.tris, m.pos.size(), scheme, levels);
        EXPECT_EQ(s.triangles().size(), m.tris.size() << (2 * levels));
        EXPECT_EQ(s.vertex_count(), V);
        EXPECT_EQ(s.source_vertex_count(), m.pos.size());
        // V -> V + E of the previous level's topology.
        V += brute_edges(s.triangles()).size();
      }
    }
}

TEST(SubdivCommon, RowsAreConvexCombinations) {
  // Results check themselves: each row's columns are distinct input vertices, weights are
  // positive and sum to 1, the anchor has the largest weight; Midpoint rows lie on one triangle.
  Soup m = concat(torus(6, 5), grid(3, 3), Vec3(9, 0, 0));
  for (auto scheme : {SubdivisionScheme::Midpoint, SubdivisionScheme::Loop}) {
    const Subdivider s = Subdivider::build(m.tris, m.pos.size(), scheme, 3);
    std::size_t entries = 0;
    for (std::size_t i = 0; i < s.vertex_count(); ++i) {
      const auto r = s.row(i);
      ASSERT_FALSE(r.columns.empty());
      entries += r.columns.size();
      std::set<std::uint32_t> cols(r.columns.begin(), r.columns.end());
      EXPECT_EQ(cols.size(), r.columns.size());
      EXPECT_LT(*cols.rbegin(), m.pos.size());
      double sum = 0;
      for (double w : r.weights) {
        EXPECT_GT(w, 0);
        EXPECT_LE(w, r.weights[0]);
        sum += w;
      }
      EXPECT_NEAR(sum, 1.0, 1e-14);
      if (scheme == SubdivisionScheme::Midpoint) {
        EXPECT_LE(r.columns.size(), 3u);
      }
    }
    EXPECT_EQ(entries, s.nonzero_count());
  }
}

TEST(SubdivCommon, ApplyChecksItsArguments) {
  const Soup m = icosahedron();
  const Subdivider s = Subdivider::build(m.tris, m.pos.size(), SubdivisionScheme::Loop, 1);
  std::vector<Vec3> out(s.vertex_count());
  EXPECT_THROW(s.apply(std::span<const Vec3>(m.pos).first(11), out), std::invalid_argument);
  EXPECT_THROW(s.apply(m.pos, std::span<Vec3>(out).first(out.size() - 1)), std::invalid_argument);
  std::vector<Vec3> both(s.vertex_count() + m.pos.size());
  std::copy(m.pos.begin(), m.pos.end(), both.begin());
  EXPECT_THROW(s.apply(std::span<const Vec3>(both).first(m.pos.size()), std::span<Vec3>(both).subspan(5, s.vertex_count())),
               std::invalid_argument);
  EXPECT_NO_THROW(s.apply(std::span<const Vec3>(both).first(m.pos.size()), std::span<Vec3>(both).subspan(m.pos.size())));

  Soup other = icosahedron();
  std::swap(other.tris[0][1], other.tris[0][2]);
  EXPECT_THROW((void)s.apply(Mesh(other.tris, other.pos)), std::invalid_argument);
}

TEST(SubdivCommon, MeshConvenienceSharesTheRefinedTopology) {
  Soup m = torus(6, 4);
  const Mesh rest(m.tris, m.pos);
  const Subdivider s = Subdivider::build(rest.triangles(), rest.vertex_count(), SubdivisionScheme::Loop, 2);
  jitter(m.pos, 0.2, 41);
  const Mesh a = s.apply(rest), b = s.apply(rest.with_positions(m.pos));
  EXPECT_EQ(a.shared_triangles(), b.shared_triangles());
  EXPECT_EQ(a.vertex_count(), s.vertex_count());
  const auto pb = refine(s, m.pos);
  EXPECT_TRUE(std::equal(pb.begin(), pb.end(), b.positions().begin()));
  const Mesh c = subdivide(rest, SubdivisionScheme::Loop, 2);
  EXPECT_TRUE(std::equal(a.positions().begin(), a.positions().end(), c.positions().begin()));
  EXPECT_EQ(std::vector<Tri>(c.triangles().begin(), c.triangles().end()),
            std::vector<Tri>(a.triangles().begin(), a.triangles().end()));
}

TEST(SubdivMidpoint, FuzzRandomTriangleSoups) {
  // Random soups (repeated indices, non-manifold edges, duplicates, unreferenced vertices):
  // always the direct computation, and Loop either works or throws InputError.
  std::mt19937_64 rng(2024);
  for (int round = 0; round < 200; ++round) {
    const std::uint32_t V = 1 + static_cast<std::uint32_t>(rng() % 12);
    const std::size_t T = rng() % 20;
    Soup m;
    for (std::uint32_t v = 0; v < V; ++v)
      m.pos.emplace_back(static_cast<double>(rng() % 1000) / 7.0, static_cast<double>(rng() % 1000) / 3.0, -static_cast<double>(rng() % 100));
    for (std::size_t t = 0; t < T; ++t)
      m.tris.push_back({static_cast<std::uint32_t>(rng() % V), static_cast<std::uint32_t>(rng() % V), static_cast<std::uint32_t>(rng() % V)});
    SCOPED_TRACE(testing::Message() << "round " << round);
    expect_matches_direct_midpoint(m, 1 + round % 2, 4e-16);
    try {
      const Subdivider s = Subdivider::build(m.tris, V, SubdivisionScheme::Loop, 2);
      EXPECT_EQ(s.triangles().size(), 16 * T);
      (void)refine(s, m.pos);
    } catch (const InputError&) {
    }
  }
}

}  // namespace
}  // namespace ptc

namespace ptc {
namespace {

// A real scanned mesh (CGAL's elephant, 5.6k triangles, read by the project's reader) against
// OpenMesh's LoopT, vertex by vertex.
TEST(SubdivLoop, RealMeshMatchesOpenMesh) {
  const LoadedMesh lm = read_mesh(std::string(PTC_TEST_DATA) + "/meshes/elephant.off");
  Soup m{std::vector<Tri>(lm.mesh.triangles().begin(), lm.mesh.triangles().end()),
         std::vector<Vec3>(lm.mesh.positions().begin(), lm.mesh.positions().end())};
  const Subdivider s = Subdivider::build(m.tris, m.pos.size(), SubdivisionScheme::Loop, 1);
  expect_matches_openmesh(s, m, openmesh_loop(m, 1));
}

}  // namespace
}  // namespace ptc

namespace ptc {
namespace {

// Corners near +-1.8e308 on both sides: the stencil's differences overflow, and the sum is taken
// again on the positions scaled by 2^-8. Every new position is finite and, both schemes' weights
// being powers of two here or close to them, equals the same mesh's subdivision at 2^-600 times
// the size, scaled back, to a relative 1e-15 (an independent run at a harmless scale).
TEST(SubdivOverflow, CornersNearTheDoubleRangeStayFinite) {
  Soup ico = icosahedron();
  const double big = 1.7e308;  // (differences of opposite corners overflow)
  for (const SubdivisionScheme scheme : {SubdivisionScheme::Midpoint, SubdivisionScheme::Loop}) {
    for (int levels : {1, 2}) {
      const Subdivider s = Subdivider::build(ico.tris, ico.pos.size(), scheme, levels);
      std::vector<Vec3> huge(ico.pos.size()), small(ico.pos.size());
      double m = 0;
      for (const Vec3& p : ico.pos) m = std::max(m, p.cwiseAbs().maxCoeff());
      for (std::size_t i = 0; i < huge.size(); ++i) huge[i] = ico.pos[i] / m * big, small[i] = ico.pos[i] / m * 0x1p-600;
      std::vector<Vec3> out_huge(s.vertex_count()), out_small(s.vertex_count());
      s.apply(huge, out_huge);
      s.apply(small, out_small);
      for (std::size_t i = 0; i < out_huge.size(); ++i) {
        ASSERT_TRUE(out_huge[i].allFinite()) << i;
        const Vec3 want = (out_small[i] * 0x1p600) * big;
        EXPECT_LE((out_huge[i] - want).cwiseAbs().maxCoeff(), 1e-15 * big) << i;
      }
    }
  }
  // The midpoint of -1.7e308 and 1.7e308 is 0.
  const std::vector<Tri> tri{{0, 1, 2}};
  const std::vector<Vec3> pos{{-1.7e308, 0, 0}, {1.7e308, 0, 0}, {0, 1.7e308, 0}};
  const Subdivider mid = Subdivider::build(tri, 3, SubdivisionScheme::Midpoint, 1);
  std::vector<Vec3> out(mid.vertex_count());
  mid.apply(pos, out);
  for (const Vec3& p : out) ASSERT_TRUE(p.allFinite());
  EXPECT_TRUE(std::find(out.begin(), out.end(), Vec3(0, 0, 0)) != out.end());
}

}  // namespace
}  // namespace ptc
