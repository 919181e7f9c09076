// The tracer against the brute-force loop over all triangles (same scalar watertight test, same
// trace frame), ray by ray and field by field, for triangle and cluster BVHs; adversarial rays
// on closed meshes (zero leaks); any-hit against closest-hit.
#include "bvh/tracer.h"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <variant>

#include <tbb/global_control.h>

#include "toolkit/clustering/morton_runs.h"
#include "bvh/camera.h"
#include "bvh/sah_builder.h"
#include "bvh/trace_scene.h"
#include "test_util.h"
#include "common/same_trace_data.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/topology.h"

namespace ptc::bvh {
namespace {

// *Sweep: the same scenes built per frame by the exact sweep builder (SceneConfig::builder).
enum class Kind { Triangles, TrianglesLeaf1, TrianglesLeaf16, Clusters80, Clusters80Linear, Clusters80Leaf4, Clusters7,
                  TrianglesSweep, Clusters80Sweep, Clusters80Tables, Clusters7Tables };
const char* name(Kind k) {
  switch (k) {
    case Kind::Triangles: return "triangles";
    case Kind::TrianglesLeaf1: return "triangles_leaf1";
    case Kind::TrianglesLeaf16: return "triangles_leaf16";
    case Kind::Clusters80: return "clusters80";
    case Kind::Clusters80Linear: return "clusters80_linear";
    case Kind::Clusters80Leaf4: return "clusters80_leaf4";
    case Kind::Clusters7: return "clusters7";
    case Kind::TrianglesSweep: return "triangles_sweep";
    case Kind::Clusters80Sweep: return "clusters80_sweep";
    case Kind::Clusters80Tables: return "clusters80_tables";
    case Kind::Clusters7Tables: return "clusters7_tables";
  }
  return "?";
}
const Kind kAllKinds[] = {Kind::Triangles,  Kind::TrianglesLeaf1,   Kind::TrianglesLeaf16, Kind::Clusters80,
                          Kind::Clusters80Linear, Kind::Clusters80Leaf4, Kind::Clusters7, Kind::TrianglesSweep,
                          Kind::Clusters80Sweep, Kind::Clusters80Tables, Kind::Clusters7Tables};

// Owns a scene of either flavour (and the clustering it was made from).
struct AnyScene {
  std::unique_ptr<Clustering> runs;
  std::variant<std::monostate, TriangleScene, ClusterScene> scene;
  const TraceData& data() const {
    return scene.index() == 1 ? std::get<1>(scene).data() : std::get<2>(scene).data();
  }
};

AnyScene make_scene(const Mesh& m, Kind k, std::optional<Vec3> origin = std::nullopt) {
  AnyScene s;
  SceneConfig cfg;
  cfg.origin = origin;
  switch (k) {
    case Kind::Triangles: s.scene.emplace<1>(m, cfg); break;
    case Kind::TrianglesSweep: cfg.builder = SahBuilder::Sweep; s.scene.emplace<1>(m, cfg); break;
    case Kind::TrianglesLeaf1: cfg.build.max_leaf_size = 1; s.scene.emplace<1>(m, cfg); break;
    case Kind::TrianglesLeaf16: cfg.build.max_leaf_size = 16; s.scene.emplace<1>(m, cfg); break;
    case Kind::Clusters80:
    case Kind::Clusters80Sweep:
    case Kind::Clusters80Linear:
    case Kind::Clusters80Leaf4:
    case Kind::Clusters7:
    case Kind::Clusters80Tables:  // (clusters of 80 triangles: two or three table groups each)
    case Kind::Clusters7Tables: {
      const bool seven = k == Kind::Clusters7 || k == Kind::Clusters7Tables;
      const bool tables = k == Kind::Clusters80Tables || k == Kind::Clusters7Tables;
      s.runs = std::make_unique<Clustering>(ptc::morton_runs(m, seven ? 7 : 80));
      cfg.build.max_leaf_size =
          k == Kind::Clusters80 || k == Kind::Clusters80Linear || k == Kind::Clusters80Sweep || k == Kind::Clusters80Tables ? 1 : 4;
      if (k == Kind::Clusters80Sweep) cfg.builder = SahBuilder::Sweep;
      if (k == Kind::Clusters80Linear || seven || tables) cfg.cluster_leaf = ClusterLeaf::Linear;
      // (explicit: auto would take the tables for the runs of 80 too)
      cfg.leaf_format = tables ? LeafFormatChoice::Tables : LeafFormatChoice::Blocks;
      if (seven) cfg.build.cost.traversal = 50.0;  // leaves of several clusters (indirect)
      s.scene.emplace<2>(m, view_of(*s.runs), cfg);
      EXPECT_EQ(s.data().format, tables ? LeafFormat::Tables : LeafFormat::Blocks);
      if (tables) {
        EXPECT_TRUE(s.data().blocks.empty());
        EXPECT_FALSE(s.data().tables.empty());
      }
      break;
    }
  }
  if (k == Kind::Clusters7 || k == Kind::Clusters7Tables) {
    std::size_t indirect = 0;
    for (const WideNode8& n : s.data().wide8.nodes)
      for (int i = 0; i < 8; ++i) indirect += n.is_leaf(i) && (n.count[i] & kIndirectLeaf);
    EXPECT_GT(indirect, 0u);
  }
  if (k == Kind::TrianglesSweep || k == Kind::Clusters80Sweep) {
    // The sweep really built the tree: the builder's cost is the exact sweep's over the same boxes.
    const bool tris = k == Kind::TrianglesSweep;
    const Bvh& b = tris ? std::get<1>(s.scene).bvh() : std::get<2>(s.scene).bvh();
    const auto& boxes = tris ? std::get<1>(s.scene).boxes() : std::get<2>(s.scene).boxes();
    const std::vector<std::uint32_t> none;
    // (the triangle scene's centroids are the triangles', the cluster scene's its boxes' centres)
    const std::vector<Vec3f> centroids =
        tris ? triangle_centroids(m.positions(), m.triangles(), s.data().origin) : box_centers(boxes);
    const Bvh want = build_sweep_sah({boxes, centroids, tris ? std::span<const std::uint32_t>(none)
                                                                      : std::span<const std::uint32_t>(std::get<2>(s.scene).weights())},
                                     cfg.build);
    // (centroids of the float triangle corners and of the double ones round apart in the last
    // place, which may swap ties: the cost is compared, not the order)
    EXPECT_NEAR(b.cost, want.cost, 1e-6 * want.cost) << name(k);
    const Bvh binned = build_binned_sah({boxes, centroids, tris ? std::span<const std::uint32_t>(none)
                                                                : std::span<const std::uint32_t>(std::get<2>(s.scene).weights())},
                                        cfg.build);
    // On a few hundred primitives the binned builder's bins resolve every split the sweep finds.
    if (boxes.size() > 500) {
      EXPECT_NE(b.cost, binned.cost) << name(k) << ": the binned tree, not the sweep's";
    }
  }
  // (a cluster's box comes from its vertex list and contains, not equals, its tree's boxes)
  const auto issues = validate(s.data(), m.triangle_count(), s.scene.index() == 1);
  EXPECT_TRUE(issues.empty()) << name(k) << ": " << test::joined(issues);
  return s;
}

// Same answer, bit for bit (the closest hit is the smallest (t, id), independent of the tree).
void expect_same(const Hit& got, const Hit& want, const std::string& what) {
  ASSERT_EQ(got.triangle, want.triangle) << what << " t=" << got.t << " vs " << want.t;
  if (!want.hit()) return;
  ASSERT_EQ(got.t, want.t) << what;
  ASSERT_EQ(got.u, want.u) << what;
  ASSERT_EQ(got.v, want.v) << what;
}

// Two traces of the same batch, field by field: every hit, t, u, v and counter, and the totals.
void expect_same_batch(const HitBatch& got, const TraceTotals& got_t, const HitBatch& want, const TraceTotals& want_t,
                       const std::string& what) {
  EXPECT_EQ(got_t.rays, want_t.rays) << what;
  EXPECT_EQ(got_t.hits, want_t.hits) << what;
  EXPECT_EQ(got_t.nodes_visited, want_t.nodes_visited) << what;
  EXPECT_EQ(got_t.triangles_tested, want_t.triangles_tested) << what;
  EXPECT_EQ(got.triangle, want.triangle) << what;
  EXPECT_EQ(got.t, want.t) << what;
  EXPECT_EQ(got.u, want.u) << what;
  EXPECT_EQ(got.v, want.v) << what;
  EXPECT_EQ(got.nodes_visited, want.nodes_visited) << what;
  EXPECT_EQ(got.triangles_tested, want.triangles_tested) << what;
}

Vec3f unit(std::mt19937& g) {
  std::normal_distribution<float> n;
  while (true) {
    const Vec3f d{n(g), n(g), n(g)};
    if (d[0] != 0 || d[1] != 0 || d[2] != 0) return d;
  }
}

// Random rays: half from random points of the enlarged bounds in random directions, half aimed
// at random points of random triangles.
struct RaySet {
  std::vector<Vec3> org;
  std::vector<Vec3f> dir;
};
RaySet random_rays(const Mesh& m, std::size_t n, std::uint32_t seed) {
  std::mt19937 g(seed);
  const Box3 b = m.bounds();
  const Vec3 c = b.center(), e = b.hi - b.lo;
  std::uniform_real_distribution<double> U(-1.0, 1.0), W(0.0, 1.0);
  std::uniform_int_distribution<std::uint32_t> T(0, static_cast<std::uint32_t>(m.triangle_count() - 1));
  RaySet r;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 o = c + Vec3(U(g) * e.x(), U(g) * e.y(), U(g) * e.z());
    r.org.push_back(o);
    if (i % 2) {
      r.dir.push_back(unit(g));
    } else {
      const auto k = m.corners(T(g));
      double w1 = W(g), w2 = W(g);
      if (w1 + w2 > 1) w1 = 1 - w1, w2 = 1 - w2;
      const Vec3 p = k[0] + w1 * (k[1] - k[0]) + w2 * (k[2] - k[0]);
      const Vec3 d = p - o;
      r.dir.push_back({float(d.x()), float(d.y()), float(d.z())});
    }
  }
  return r;
}

class TracerKinds : public ::testing::TestWithParam<Kind> {};

TEST_P(TracerKinds, RandomRaysMatchBruteForceRayByRay) {
  const Mesh m = test::load_mesh("armadillo.off");
  const AnyScene s = make_scene(m, GetParam());
  const RaySet rays = random_rays(m, 1200, 5);
  int hits = 0;
  for (std::size_t i = 0; i < rays.org.size(); ++i) {
    const Hit want = test::brute_force(m, s.data().origin, rays.org[i], rays.dir[i]);
    const Hit got = trace_ray(s.data(), rays.org[i], rays.dir[i]);
    expect_same(got, want, std::string(name(GetParam())) + " ray " + std::to_string(i));
    EXPECT_GT(got.nodes_visited, 0u);
    // Every instruction-set variant, forced: the same hit and the same counters.
    for (TraceIsa isa : {TraceIsa::Sse2, TraceIsa::Avx2, TraceIsa::Avx512Vl, TraceIsa::Avx512}) {
      const Hit h = trace_ray(s.data(), rays.org[i], rays.dir[i], HitMode::Closest, 0.0f, kInf, isa);
      expect_same(h, want, std::string(to_string(isa)) + " ray " + std::to_string(i));
      ASSERT_EQ(h.nodes_visited, got.nodes_visited);
      ASSERT_EQ(h.triangles_tested, got.triangles_tested);
    }
    hits += want.hit();
    // Any hit: occluded iff the closest hit exists; the reported triangle really is hit.
    const Hit any = trace_ray(s.data(), rays.org[i], rays.dir[i], HitMode::Any);
    ASSERT_EQ(any.hit(), want.hit()) << i;
    if (any.hit()) {
      const auto c = m.corners(any.triangle);
      const Vec3& f = s.data().origin;
      const auto h = intersect_triangle(make_watertight_ray(to_frame(rays.org[i], f), rays.dir[i]), to_frame(c[0], f),
                                        to_frame(c[1], f), to_frame(c[2], f), 0.0f, kInf);
      ASSERT_TRUE(h && h->t == any.t) << i;
      // Shadow-ray semantics: with tmax just short of the closest hit nothing occludes, with
      // tmax = the closest hit something does.
      EXPECT_TRUE(trace_ray(s.data(), rays.org[i], rays.dir[i], HitMode::Any, 0.0f, want.t).hit());
      const float before = std::nextafter(want.t, 0.0f);
      EXPECT_EQ(trace_ray(s.data(), rays.org[i], rays.dir[i], HitMode::Any, 0.0f, before).hit(),
                test::brute_force(m, s.data().origin, rays.org[i], rays.dir[i], 0.0f, before).hit());
    }
  }
  EXPECT_GT(hits, 500);
}

TEST_P(TracerKinds, BatchEqualsSingleRaysForAnyThreadCount) {
  const Mesh m = test::load_mesh("bunny00.off");
  const AnyScene s = make_scene(m, GetParam());
  const RaySet rs = random_rays(m, 3000, 9);
  RayBatch rays;
  rays.resize(rs.org.size());
  for (std::size_t i = 0; i < rs.org.size(); ++i) rays.set(i, rs.org[i], rs.dir[i]);
  for (HitMode mode : {HitMode::Closest, HitMode::Any}) {
    HitBatch h1, h2, hs;
    TraceOptions opt;
    opt.mode = mode;
    opt.threads = 1;
    const TraceTotals t1 = trace(s.data(), rays, h1, opt);
    opt.threads = 2;
    const TraceTotals t2 = trace(s.data(), rays, h2, opt);
    opt.isa = TraceIsa::Sse2;  // the baseline variant gives the same batch, field by field
    const TraceTotals ts = trace(s.data(), rays, hs, opt);
    HitBatch hv;  // and so does AVX2 where Auto is AVX-512
    opt.isa = TraceIsa::Avx2;
    const TraceTotals tv = trace(s.data(), rays, hv, opt);
    expect_same_batch(hs, ts, h1, t1, "sse2");
    expect_same_batch(hv, tv, h1, t1, "avx2");
    EXPECT_EQ(t1.rays, rays.size());
    EXPECT_EQ(t1.hits, t2.hits);
    EXPECT_EQ(t1.nodes_visited, t2.nodes_visited);
    std::uint64_t nodes = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Hit one = trace_ray(s.data(), rs.org[i], rs.dir[i], mode);
      ASSERT_EQ(h1.triangle[i], one.triangle);
      ASSERT_EQ(h2.triangle[i], one.triangle);
      ASSERT_EQ(h1.t[i], one.t);
      ASSERT_EQ(h2.u[i], one.u);
      ASSERT_EQ(h1.nodes_visited[i], one.nodes_visited);
      ASSERT_EQ(h2.triangles_tested[i], one.triangles_tested);
      nodes += h1.nodes_visited[i];
    }
    EXPECT_EQ(nodes, t1.nodes_visited);
  }
}

// The batch's set-up of eight rays at once (the AVX2 and AVX-512 variants) refuses and accepts
// exactly the rays the per-ray set-up does, and makes the same ray of the rest: degenerate rays
// (zero, NaN and infinite directions, -0 components, a NaN or a float-overflowing origin, empty,
// negative or NaN intervals) mixed into eight-ray groups, each against trace_ray (the per-ray
// set-up), every variant. An odd ray follows every second random ray: a stride of three, coprime
// to eight, so every kind of odd ray lands in every lane of a group (checked).
TEST_P(TracerKinds, BatchSetUpRefusesWhatTheRaySetUpRefuses) {
  const Mesh m = test::load_mesh("bunny00.off");
  const AnyScene s = make_scene(m, GetParam());
  const RaySet rs = random_rays(m, 400, 13);
  const float nan = std::nanf(""), inf = kInf;
  const Vec3 c = m.bounds().center();
  struct Odd {
    Vec3 o;
    Vec3f d;
    float t0, t1;
  };
  const Odd odd[] = {
      {c, {0, 0, 0}, 0, inf},          {c, {nan, 1, 0}, 0, inf},       {c, {inf, 1, 0}, 0, inf},
      {c, {-0.0f, -0.0f, 1}, 0, inf},  {c, {-0.0f, 0.0f, -0.0f}, 0, inf}, {Vec3(nan, 0, 0), {1, 0, 0}, 0, inf},
      {Vec3(1e39, 0, 0), {-1, 0, 0}, 0, inf}, {c, {1, 0.5f, 0}, 2, 1}, {c, {1, 0.5f, 0}, -1, inf},
      {c, {1, 0.5f, 0}, nan, inf},     {c, {1, 0.5f, 0}, 0, nan},      {c, {0, 1, -0.0f}, 0, 3e38f},
      {c, {0, 0, 1}, 0, 0},            {c, {1e-30f, 1e-30f, 1e-30f}, 0, inf}, {c, {1, 0, 0}, inf, inf}};
  static_assert(std::size(odd) % 2 == 1, "an odd count of kinds: with the stride of 3 every kind visits every lane");
  std::vector<Vec3> org;
  std::vector<Vec3f> dir;
  std::vector<float> t0, t1;
  std::size_t k = 0;
  unsigned lane_seen[std::size(odd)] = {};  // per kind of odd ray: the lanes of a group it was put in
  for (std::size_t i = 0; i < rs.org.size(); ++i) {
    org.push_back(rs.org[i]), dir.push_back(rs.dir[i]), t0.push_back(0.0f), t1.push_back(inf);
    if (i % 2 == 1) {  // after every second random ray
      const std::size_t kind = k++ % std::size(odd);
      const Odd& x = odd[kind];
      if (org.size() + 8 <= rs.org.size()) lane_seen[kind] |= 1u << (org.size() % 8);  // (not in the tail)
      org.push_back(x.o), dir.push_back(x.d), t0.push_back(x.t0), t1.push_back(x.t1);
    }
  }
  for (std::size_t j = 0; j < std::size(odd); ++j) ASSERT_EQ(lane_seen[j], 0xffu) << "odd ray kind " << j;
  RayBatch rays;
  rays.resize(org.size());
  for (std::size_t i = 0; i < org.size(); ++i) rays.set(i, org[i], dir[i], t0[i], t1[i]);
  for (TraceIsa isa : {TraceIsa::Sse2, TraceIsa::Avx2, TraceIsa::Avx512Vl, TraceIsa::Avx512})
    for (HitMode mode : {HitMode::Closest, HitMode::Any}) {
      HitBatch h;
      TraceOptions opt;
      opt.mode = mode, opt.threads = 1, opt.isa = isa;
      trace(s.data(), rays, h, opt);
      for (std::size_t i = 0; i < rays.size(); ++i) {
        const Hit one = trace_ray(s.data(), org[i], dir[i], mode, t0[i], t1[i], TraceIsa::Sse2);
        const std::string what = std::string(to_string(isa)) + " ray " + std::to_string(i);
        ASSERT_EQ(h.triangle[i], one.triangle) << what;
        ASSERT_EQ(h.t[i], one.t) << what;
        ASSERT_EQ(h.u[i], one.u) << what;
        ASSERT_EQ(h.v[i], one.v) << what;
        ASSERT_EQ(h.nodes_visited[i], one.nodes_visited) << what;  // 0 for a refused ray
        ASSERT_EQ(h.triangles_tested[i], one.triangles_tested) << what;
      }
    }
}

// The packet path (TraceOptions::packets) against single rays, ray by ray: closest hits bit for
// bit, any hit on the same rays (and a real hit of that ray). The batch mixes a camera's rows
// (coherent: one lane group per packet), random rays (mixed octants and dominant axes: several
// groups per packet), rays exactly through vertices (edge functions of 0), degenerate rays (zero,
// NaN, empty interval) and bounded rays, in a count that is not a multiple of eight.
TEST_P(TracerKinds, PacketsEqualSingleRays) {
  const Mesh m = test::load_mesh("armadillo.off");
  const AnyScene s = make_scene(m, GetParam());
  const RayBatch cam = primary_rays(frame_box(m.bounds(), Vec3(0.3, -0.2, -1.0)), 48, 40);
  const RaySet rnd = random_rays(m, 1500, 21);
  RayBatch rays;
  std::vector<Vec3> org;
  std::vector<Vec3f> dir;
  std::vector<float> t0, t1;
  auto add = [&](const Vec3& o, const Vec3f& d, float a = 0.0f, float b = kInf) {
    org.push_back(o), dir.push_back(d), t0.push_back(a), t1.push_back(b);
  };
  const Vec3 c = m.bounds().center();
  // Whole packets of one ray exactly through a vertex (ties between the triangles around it),
  // from outside the mesh: every leaf on the way has all eight lanes (the ray-parallel leaf test).
  const Vec3 far = c + 3.0 * (m.bounds().hi - c);
  for (std::size_t v = 0; v < m.vertex_count(); v += 97) {
    const Vec3 d = m.position(v) - far;
    for (int k = 0; k < 8; ++k) add(far, {float(d.x()), float(d.y()), float(d.z())});
  }
  const std::size_t same_lanes = org.size();  // rays [0, same_lanes): packets of eight equal rays
  for (std::size_t i = 0; i < cam.size(); ++i)
    add(Vec3(cam.ox[i], cam.oy[i], cam.oz[i]), {cam.dx[i], cam.dy[i], cam.dz[i]});
  for (std::size_t i = 0; i < rnd.org.size(); ++i) add(rnd.org[i], rnd.dir[i]);
  for (std::size_t v = 0; v < m.vertex_count(); v += 37) {
    const Vec3 d = m.position(v) - c;
    add(c, {float(d.x()), float(d.y()), float(d.z())});
    if (v % 5 == 0) add(c, {float(d.x()), float(d.y()), float(d.z())}, 0.0f, 0.5f);  // ends before the vertex
  }
  add(c, {0, 0, 0});
  add(c, {std::nanf(""), 1, 0});
  add(c, {1, 0, 0}, 3.0f, 2.0f);
  add(Vec3(std::nan(""), 0, 0), {1, 0, 0});
  add(c, {0, 0, 1});  // axis-aligned, from inside
  rays.resize(org.size());
  for (std::size_t i = 0; i < org.size(); ++i) rays.set(i, org[i], dir[i], t0[i], t1[i]);
  ASSERT_NE(rays.size() % 8, 0u);
  for (HitMode mode : {HitMode::Closest, HitMode::Any}) {
    for (unsigned threads : {1u, 2u}) {
      HitBatch single, packed;
      TraceOptions opt;
      opt.mode = mode;
      opt.threads = threads;
      const TraceTotals ts = trace(s.data(), rays, single, opt);
      opt.packets = true;
      const TraceTotals tp = trace(s.data(), rays, packed, opt);
      EXPECT_EQ(tp.rays, ts.rays);
      EXPECT_EQ(tp.hits, ts.hits);
      std::uint64_t nodes = 0, tris = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        const std::string what = std::string(name(GetParam())) + " ray " + std::to_string(i);
        nodes += packed.nodes_visited[i];
        tris += packed.triangles_tested[i];
        if (mode == HitMode::Closest) {
          ASSERT_EQ(packed.triangle[i], single.triangle[i]) << what;
          ASSERT_EQ(packed.t[i], single.t[i]) << what;
          ASSERT_EQ(packed.u[i], single.u[i]) << what;
          ASSERT_EQ(packed.v[i], single.v[i]) << what;
          if (single.triangle[i] != kNoTriangle) {
            ASSERT_GT(packed.triangles_tested[i], 0u) << what;
          }
          continue;
        }
        ASSERT_EQ(packed.triangle[i] != kNoTriangle, single.triangle[i] != kNoTriangle) << what;
        if (packed.triangle[i] == kNoTriangle) continue;
        const auto k = m.corners(packed.triangle[i]);
        const Vec3& f = s.data().origin;
        const auto h = intersect_triangle(make_watertight_ray(to_frame(org[i], f), dir[i]), to_frame(k[0], f),
                                          to_frame(k[1], f), to_frame(k[2], f), t0[i], t1[i]);
        ASSERT_TRUE(h && h->t == packed.t[i]) << what;
      }
      EXPECT_EQ(nodes, tp.nodes_visited);
      EXPECT_EQ(tris, tp.triangles_tested);
      // A full packet stores its eight results at once (a transpose), a short one lane by lane:
      // a packet of eight equal rays and the same ray seven times walk alike, so every field and
      // counter of the seven must match, column by column.
      for (std::size_t first = 0; first < same_lanes; first += 8) {
        RayBatch eight, seven;
        eight.resize(8), seven.resize(7);
        for (std::size_t l = 0; l < 8; ++l) {
          eight.set(l, org[first], dir[first], t0[first], t1[first]);
          if (l < 7) seven.set(l, org[first], dir[first], t0[first], t1[first]);
        }
        HitBatch h8, h7;
        opt.threads = 1;
        const TraceTotals a8 = trace(s.data(), eight, h8, opt), a7 = trace(s.data(), seven, h7, opt);
        opt.threads = threads;
        const std::string what = std::string(name(GetParam())) + " packet of ray " + std::to_string(first);
        for (std::size_t l = 0; l < 7; ++l) {
          ASSERT_EQ(h8.triangle[l], h7.triangle[l]) << what;
          ASSERT_EQ(h8.t[l], h7.t[l]) << what;
          ASSERT_EQ(h8.u[l], h7.u[l]) << what;
          ASSERT_EQ(h8.v[l], h7.v[l]) << what;
          ASSERT_EQ(h8.nodes_visited[l], h7.nodes_visited[l]) << what;
          ASSERT_EQ(h8.triangles_tested[l], h7.triangles_tested[l]) << what;
        }
        EXPECT_EQ(a8.hits, a7.hits + (h8.triangle[7] != kNoTriangle ? 1 : 0)) << what;
        EXPECT_EQ(a8.triangles_tested, a7.triangles_tested + h8.triangles_tested[7]) << what;
        EXPECT_EQ(a8.nodes_visited, a7.nodes_visited + h8.nodes_visited[7]) << what;
      }
      // The packet path of the AVX2, AVX-512VL and AVX-512 variants: the same batch, field by field
      // (on a CPU without AVX-512 all three requests run the AVX2 code).
      HitBatch p2, p512, p512vl;
      opt.isa = TraceIsa::Avx2;
      const TraceTotals t2 = trace(s.data(), rays, p2, opt);
      opt.isa = TraceIsa::Avx512;
      const TraceTotals t512 = trace(s.data(), rays, p512, opt);
      opt.isa = TraceIsa::Avx512Vl;
      const TraceTotals t512vl = trace(s.data(), rays, p512vl, opt);
      EXPECT_EQ(t2.hits, tp.hits);
      expect_same_batch(p512, t512, p2, t2, "avx512 packets against avx2 packets");
      expect_same_batch(p512vl, t512vl, p2, t2, "avx512vl packets against avx2 packets");
    }
  }
}

// Rays from points inside a closed mesh towards every vertex (exactly through it) and through
// the midpoints of edges: all must hit (zero leaks), and the hits equal brute force on a sample.
TEST_P(TracerKinds, ClosedMeshZeroLeaksThroughVerticesAndEdges) {
  const Mesh m = test::load_mesh("armadillo.off");
  const AnyScene s = make_scene(m, GetParam());
  // Interior points: a little inside from triangle centroids, confirmed by the winding number.
  std::vector<Vec3> inside;
  for (std::uint32_t t = 0; inside.size() < 3 && t < m.triangle_count(); t += 4999) {
    const auto c = m.corners(t);
    const Vec3 n = (c[1] - c[0]).cross(c[2] - c[0]).normalized();
    const Vec3 cen = (c[0] + c[1] + c[2]) / 3.0;
    for (double sgn : {-1.0, 1.0}) {
      const Vec3 p = cen + sgn * 0.05 * n;
      if (std::abs(test::winding_number(m, p)) > 0.99) {
        inside.push_back(p);
        break;
      }
    }
  }
  ASSERT_EQ(inside.size(), 3u);
  std::size_t rays = 0, leaks = 0;
  for (const Vec3& o : inside) {
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
      const Vec3 d = m.position(v) - o;
      const Vec3f dir{float(d.x()), float(d.y()), float(d.z())};
      const Hit h = trace_ray(s.data(), o, dir);
      ++rays;
      leaks += !h.hit();
      if (v % 997 == 0) expect_same(h, test::brute_force(m, s.data().origin, o, dir), "vertex ray");
    }
    for (std::size_t t = 0; t < m.triangle_count(); t += 3) {
      const auto c = m.corners(t);
      for (int e = 0; e < 3; ++e) {
        const Vec3 d = 0.5 * (c[e] + c[(e + 1) % 3]) - o;
        const Hit h = trace_ray(s.data(), o, {float(d.x()), float(d.y()), float(d.z())}, HitMode::Any);
        ++rays;
        leaks += !h.hit();
      }
    }
  }
  EXPECT_EQ(leaks, 0u) << "of " << rays << " rays";
}

// Origins on the surface (vertices and random points of triangles), random directions.
TEST_P(TracerKinds, OriginsOnTheSurface) {
  const Mesh m = test::load_mesh("armadillo.off");
  const AnyScene s = make_scene(m, GetParam());
  std::mt19937 g(17);
  std::uniform_real_distribution<double> W(0.0, 1.0);
  std::size_t inward_misses = 0;
  for (std::uint32_t t = 0; t < m.triangle_count(); t += 131) {
    const auto c = m.corners(t);
    double w1 = W(g), w2 = W(g);
    if (w1 + w2 > 1) w1 = 1 - w1, w2 = 1 - w2;
    const Vec3 origins[2] = {c[0], c[0] + w1 * (c[1] - c[0]) + w2 * (c[2] - c[0])};
    const Vec3 n = (c[1] - c[0]).cross(c[2] - c[0]).normalized();
    for (const Vec3& o : origins) {
      const Vec3f d = unit(g);
      expect_same(trace_ray(s.data(), o, d), test::brute_force(m, s.data().origin, o, d), "surface origin");
      // Inward (armadillo is oriented outward): the ray stays inside the closed surface and
      // must hit something (its own triangle when the float origin lies just outside).
      const Vec3 in = -n + 0.5 * Vec3(d[0], d[1], d[2]).normalized();
      const Vec3f di{float(in.x()), float(in.y()), float(in.z())};
      const Hit h = trace_ray(s.data(), o, di);
      inward_misses += !h.hit();
      if (t % 5 == 0) expect_same(h, test::brute_force(m, s.data().origin, o, di), "inward");
    }
  }
  EXPECT_EQ(inward_misses, 0u);
}

// Axis-aligned rays (exact zero components of both signs) from origins on grid lines inside a
// closed cube whose faces are grids of coplanar triangles: the origins lie exactly on the slab
// planes of many boxes (0 * inf = NaN in a naive slab test) and the rays run exactly along
// edges and through vertices. Every ray must hit the face it points at, at the exact distance;
// scaled tiny (1e-3), huge (offset 1e7), in the default frame and in the world frame.
void axis_aligned_cube(Kind kind, double scale, const Vec3& offset, std::optional<Vec3> frame) {
  const int n = 8;
  const Mesh m = test::grid_cube(n, scale, offset);
  const AnyScene s = make_scene(m, kind, frame);
  const Vec3f axes[6] = {{1, 0, 0}, {-1, -0.0f, 0}, {0, 1, -0.0f}, {0, -1, 0}, {-0.0f, 0, 1}, {0, 0, -1}};
  std::size_t rays = 0, leaks = 0, wrong_t = 0;
  for (int i = 1; i < n; ++i)
    for (int j = 1; j < n; ++j)
      for (int k = 1; k < n; ++k)
        for (const Vec3f& d : axes) {
          // grid points (on the triangles' edge lines) and points between them
          for (double h : {0.0, 0.5}) {
            const Vec3 p = offset + scale * Vec3(2.0 * (i + h) / n - 1.0, 2.0 * (j + h) / n - 1.0, 2.0 * (k + h) / n - 1.0);
            if (h != 0.0 && (i + h >= n || j + h >= n || k + h >= n)) continue;
            const Hit hit = trace_ray(s.data(), p, d);
            ++rays;
            if (!hit.hit()) {
              ++leaks;
              continue;
            }
            // distance to the face, in the trace frame's floats
            int a = d[0] != 0 ? 0 : d[1] != 0 ? 1 : 2;
            const double face = offset[a] + (d[a] > 0 ? scale : -scale);
            const double exact = std::abs(face - p[a]);
            if (std::abs(hit.t - exact) > 1e-5 * scale + 4e-7 * std::abs(p[a] - s.data().origin[a])) ++wrong_t;
            if ((i + j + k) % 5 == 0) expect_same(hit, test::brute_force(m, s.data().origin, p, d), "axis ray");
          }
        }
  EXPECT_EQ(leaks, 0u) << "of " << rays;
  EXPECT_EQ(wrong_t, 0u) << "of " << rays;
}

// Nearly axis-aligned rays: the other two direction components tiny (denormal, just below and
// just above 1 / FLT_MAX, where 1/d overflows to inf or stays finite near FLT_MAX, and small
// normal values), mixed with exact zeros, from origins on the cube's grid lines: slab values of
// 0 * inf = NaN next to finite ones of the same node, and reciprocals near FLT_MAX. Every ray
// hits, and every fourth is compared with brute force.
TEST_P(TracerKinds, NearlyAxisAlignedRaysHitLikeBruteForce) {
  const int n = 8;
  const Mesh m = test::grid_cube(n, 1.0, Vec3::Zero());
  const AnyScene s = make_scene(m, GetParam(), std::nullopt);
  const float tiny[] = {1e-45f, 2.9e-39f, 3.0e-39f, 1e-30f};
  std::size_t rays = 0, misses = 0;
  for (int a = 0; a < 3; ++a)
    for (float sign : {1.0f, -1.0f})
      for (float e : tiny)
        for (int pattern = 0; pattern < 3; ++pattern) {
          Vec3f d{0.0f, 0.0f, 0.0f};
          d[a] = sign;
          const float e1 = pattern == 2 ? 0.0f : e, e2 = pattern == 1 ? -e : e;
          d[(a + 1) % 3] = e1, d[(a + 2) % 3] = e2;
          for (int i = 1; i < n; ++i)
            for (int j = 1; j < n; ++j)
              for (int k = 1; k < n; k += 2) {
                const Vec3 p(2.0 * i / n - 1.0, 2.0 * j / n - 1.0, 2.0 * k / n - 1.0);
                const Hit hit = trace_ray(s.data(), p, d);
                ++rays;
                misses += !hit.hit();
                if (rays % 4 == 0) expect_same(hit, test::brute_force(m, s.data().origin, p, d), "nearly axis-aligned ray");
              }
        }
  EXPECT_EQ(misses, 0u) << "of " << rays;
}

TEST_P(TracerKinds, AxisAlignedRaysUnitCube) { axis_aligned_cube(GetParam(), 1.0, Vec3::Zero(), std::nullopt); }
TEST_P(TracerKinds, AxisAlignedRaysTinyCube) { axis_aligned_cube(GetParam(), 1e-3, Vec3::Zero(), std::nullopt); }
TEST_P(TracerKinds, AxisAlignedRaysHugeOffsetRebased) {
  axis_aligned_cube(GetParam(), 1000.0, Vec3(1e7, -1e7, 1e7), std::nullopt);
}
TEST_P(TracerKinds, AxisAlignedRaysHugeOffsetWorldFrame) {
  axis_aligned_cube(GetParam(), 1000.0, Vec3(1e7, -1e7, 1e7), Vec3::Zero());
}

// Random rays from inside a tiny and a huge-offset closed mesh: zero leaks, brute force equal.
void random_inside(Kind kind, double scale, const Vec3& offset, std::optional<Vec3> frame) {
  Mesh base = test::load_mesh("armadillo.off");
  const Box3 b = base.bounds();
  const double s0 = (b.hi - b.lo).maxCoeff();
  std::vector<Vec3> p(base.positions().begin(), base.positions().end());
  for (Vec3& q : p) q = offset + (q - b.center()) * (scale / s0);
  const Mesh m = base.with_positions(std::move(p));
  const AnyScene s = make_scene(m, kind, frame);
  // Interior points as in the closed-mesh test.
  std::vector<Vec3> inside;
  for (std::uint32_t t = 0; inside.size() < 2 && t < m.triangle_count(); t += 7001) {
    const auto c = m.corners(t);
    const Vec3 n = (c[1] - c[0]).cross(c[2] - c[0]).normalized();
    const Vec3 q = (c[0] + c[1] + c[2]) / 3.0 - 4e-4 * scale * n;
    if (std::abs(test::winding_number(m, q)) > 0.99) inside.push_back(q);
  }
  ASSERT_EQ(inside.size(), 2u);
  std::mt19937 g(23);
  std::size_t leaks = 0;
  for (const Vec3& o : inside)
    for (int i = 0; i < 3000; ++i) {
      const Vec3f d = unit(g);
      const Hit h = trace_ray(s.data(), o, d);
      leaks += !h.hit();
      if (i % 50 == 0) expect_same(h, test::brute_force(m, s.data().origin, o, d), "inside ray");
    }
  EXPECT_EQ(leaks, 0u);
}

TEST_P(TracerKinds, TinySceneFromInside) { random_inside(GetParam(), 1e-3, Vec3::Zero(), std::nullopt); }

// The mesh and the rays' origins times 2^j, the directions unchanged: every hit is the same
// triangle with the same u and v and t times 2^j, bit for bit, single rays and packets. The base
// mesh (about 100 units) keeps the unscaled frame; the scaled ones get the frame scale that
// brings them to about one unit (trace_frame_scale). Before it, at 2^40 (about 1e14) the
// watertight test's products overflowed and every ray missed; far below, they underflowed.
TEST_P(TracerKinds, PowerOfTwoScaledScenesTraceTheSameHits) {
  const Mesh base = test::load_mesh("armadillo.off");
  const AnyScene s0 = make_scene(base, GetParam());
  ASSERT_EQ(s0.data().scale, 1.0);
  RaySet rs = random_rays(base, 600, 71);
  const RayBatch cam = primary_rays(frame_box(base.bounds(), Vec3(0.3, -0.2, -1.0)), 24, 20);
  for (std::size_t i = 0; i < cam.size(); ++i)
    rs.org.push_back(Vec3(cam.ox[i], cam.oy[i], cam.oz[i])), rs.dir.push_back({cam.dx[i], cam.dy[i], cam.dz[i]});
  auto batch = [&](double f) {
    RayBatch b;
    b.resize(rs.org.size());
    for (std::size_t i = 0; i < rs.org.size(); ++i) b.set(i, rs.org[i] * f, rs.dir[i]);
    return b;
  };
  auto run = [&](const TraceData& d, const RayBatch& b, int variant) {  // 0 single, 1 packets, 2 SSE2
    HitBatch h;
    TraceOptions opt;
    opt.packets = variant == 1;
    if (variant == 2) opt.isa = TraceIsa::Sse2;
    trace(d, b, h, opt);
    return h;
  };
  const RayBatch b0 = batch(1.0);
  const HitBatch h0 = run(s0.data(), b0, 0);
  std::size_t hits = 0;
  for (std::size_t i = 0; i < b0.size(); ++i) hits += h0.triangle[i] != kNoTriangle;
  ASSERT_GT(hits, b0.size() / 4);
  for (int j : {-95, -60, -30, 30, 45, 60, 90}) {
    std::vector<Vec3> p(base.positions().begin(), base.positions().end());
    for (Vec3& q : p) q = Vec3(std::ldexp(q.x(), j), std::ldexp(q.y(), j), std::ldexp(q.z(), j));
    const Mesh m = base.with_positions(std::move(p));
    const AnyScene s = make_scene(m, GetParam());
    EXPECT_NE(s.data().scale, 1.0) << j;
    const RayBatch b = batch(std::ldexp(1.0, j));
    for (int variant : {0, 1, 2}) {
      const HitBatch h = run(s.data(), b, variant);
      for (std::size_t i = 0; i < b.size(); ++i) {
        const std::string what = std::string(name(GetParam())) + " 2^" + std::to_string(j) + " variant " +
                                 std::to_string(variant) + " ray " + std::to_string(i);
        ASSERT_EQ(h.triangle[i], h0.triangle[i]) << what;
        if (h0.triangle[i] == kNoTriangle) continue;
        ASSERT_EQ(h.t[i], std::ldexp(h0.t[i], j)) << what;
        ASSERT_EQ(h.u[i], h0.u[i]) << what;
        ASSERT_EQ(h.v[i], h0.v[i]) << what;
      }
    }
    // and the brute force in the scaled frame agrees
    for (std::size_t i = 0; i < b.size(); i += 41)
      expect_same(trace_ray(s.data(), rs.org[i] * std::ldexp(1.0, j), rs.dir[i]),
                  test::brute_force(m, s.data().frame(), rs.org[i] * std::ldexp(1.0, j), rs.dir[i]), "brute force");
  }
}

// The variant `auto` picks, against the kernel's own account of the CPU (/proc/cpuinfo: vendor,
// family, flags), read independently of CPUID and the compiler's CPU checks.
TEST(Tracer, AutoVariantFollowsTheCpu) {
  std::ifstream in("/proc/cpuinfo");
  if (!in) GTEST_SKIP() << "no /proc/cpuinfo";
  std::string line, vendor, flags;
  long family = -1;
  while (std::getline(in, line) && !line.empty()) {  // the first processor's block
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string key = line.substr(0, colon);
    key.erase(key.find_last_not_of(" \t") + 1);
    const std::string value = colon + 2 <= line.size() ? line.substr(colon + 2) : "";
    if (key == "vendor_id") vendor = value;
    if (key == "cpu family") family = std::stol(value);
    if (key == "flags") flags = " " + value + " ";
  }
  ASSERT_FALSE(vendor.empty());
  ASSERT_GE(family, 0);
  auto has = [&](const char* f) { return flags.find(std::string(" ") + f + " ") != std::string::npos; };
  EXPECT_EQ(bvh::amd_cpu_family(), vendor == "AuthenticAMD" ? static_cast<unsigned>(family) : 0u);
  const bool avx512 = has("avx2") && has("avx512f") && has("avx512vl") && has("avx512dq") && has("avx512bw");
  const bvh::TraceIsa expected = avx512 ? (vendor == "AuthenticAMD" && family >= 0x1a ? bvh::TraceIsa::Avx512
                                                                                       : bvh::TraceIsa::Avx512Vl)
                                 : has("avx2") ? bvh::TraceIsa::Avx2
                                               : bvh::TraceIsa::Sse2;
  EXPECT_EQ(bvh::resolve(bvh::TraceIsa::Auto), expected) << vendor << " family " << family;
  EXPECT_EQ(bvh::resolve(bvh::TraceIsa::Sse2), bvh::TraceIsa::Sse2);
}

// The rule on every kind of CPU, against the table of what each request gives (bvh/tracer.h).
TEST(Tracer, VariantChoiceOnEveryKindOfCpu) {
  using I = bvh::TraceIsa;
  struct Cpu {
    bool avx2, avx512;
    unsigned family;
    I auto_, sse2, avx2_, vl, w512;
  };
  const Cpu cpus[] = {
      {false, false, 0, I::Sse2, I::Sse2, I::Sse2, I::Sse2, I::Sse2},                 // SSE2 only
      {true, false, 0x17, I::Avx2, I::Sse2, I::Avx2, I::Avx2, I::Avx2},               // Zen 2
      {true, true, 0, I::Avx512Vl, I::Sse2, I::Avx2, I::Avx512Vl, I::Avx512},         // Intel
      {true, true, 0x19, I::Avx512Vl, I::Sse2, I::Avx2, I::Avx512Vl, I::Avx512},      // Zen 4
      {true, true, 0x1a, I::Avx512, I::Sse2, I::Avx2, I::Avx512Vl, I::Avx512},        // Zen 5
      {true, true, 0x1b, I::Avx512, I::Sse2, I::Avx2, I::Avx512Vl, I::Avx512},        // later
      {false, true, 0x1a, I::Sse2, I::Sse2, I::Sse2, I::Sse2, I::Sse2},               // (AVX-512 without AVX2)
  };
  for (const Cpu& c : cpus) {
    const std::string what = "avx2 " + std::to_string(c.avx2) + " avx512 " + std::to_string(c.avx512) + " family " +
                             std::to_string(c.family);
    EXPECT_EQ(bvh::choose_isa(I::Auto, c.avx2, c.avx512, c.family), c.auto_) << what;
    EXPECT_EQ(bvh::choose_isa(I::Sse2, c.avx2, c.avx512, c.family), c.sse2) << what;
    EXPECT_EQ(bvh::choose_isa(I::Avx2, c.avx2, c.avx512, c.family), c.avx2_) << what;
    EXPECT_EQ(bvh::choose_isa(I::Avx512Vl, c.avx2, c.avx512, c.family), c.vl) << what;
    EXPECT_EQ(bvh::choose_isa(I::Avx512, c.avx2, c.avx512, c.family), c.w512) << what;
  }
}

// Beyond 2^100 (or below 2^-100) units the scaled directions would leave the float range: the
// scene is refused with a message that says so.
TEST(Tracer, ScenesBeyondTheFloatRangeAreRefused) {
  const Mesh base = test::load_mesh("elephant.off");
  for (int j : {-110, 110}) {
    std::vector<Vec3> p(base.positions().begin(), base.positions().end());
    for (Vec3& q : p) q = Vec3(std::ldexp(q.x(), j), std::ldexp(q.y(), j), std::ldexp(q.z(), j));
    const Mesh m = base.with_positions(std::move(p));
    try {
      TriangleScene s(m, SceneConfig{});
      ADD_FAILURE() << "2^" << j << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("beyond the single-precision tracer's range"), std::string::npos) << e.what();
    }
  }
}
TEST_P(TracerKinds, HugeOffsetSceneFromInside) { random_inside(GetParam(), 1e3, Vec3(-1e7, 1e7, 1e7), std::nullopt); }

INSTANTIATE_TEST_SUITE_P(AllScenes, TracerKinds, ::testing::ValuesIn(kAllKinds),
                         [](const auto& param_info) { return std::string(name(param_info.param)); });

TEST(Tracer, EmptyMeshAndDegenerateRays) {
  const Mesh empty({}, {});
  const TriangleScene s(empty);
  EXPECT_TRUE(validate(s.data(), 0).empty());
  EXPECT_FALSE(trace_ray(s.data(), Vec3::Zero(), {1, 0, 0}).hit());
  const Mesh one({{0, 1, 2}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
  const TriangleScene s1(one);
  EXPECT_TRUE(trace_ray(s1.data(), Vec3(0.2, 0.2, 1), {0, 0, -1}).hit());
  EXPECT_FALSE(trace_ray(s1.data(), Vec3(0.2, 0.2, 1), {0, 0, 0}).hit());  // zero direction
  EXPECT_FALSE(trace_ray(s1.data(), Vec3(0.2, 0.2, 1), {0, 0, std::nanf("")}).hit());
  EXPECT_FALSE(trace_ray(s1.data(), Vec3(0.2, 0.2, 1), {0, 0, -1}, HitMode::Closest, 2.0f, 3.0f).hit());
  RayBatch rays;
  HitBatch hits;
  EXPECT_EQ(trace(s1.data(), rays, hits).rays, 0u);
  // Cluster scenes (default settings: two-level build) on no clusters and on one.
  const std::vector<std::uint32_t> none, zero{0}, t0{0}, o01{0, 1};
  ClusterScene ce(empty, ClusterView{none, zero, none, {}}, test::two_level_defaults());
  EXPECT_TRUE(validate(ce.data(), 0).empty());
  EXPECT_FALSE(trace_ray(ce.data(), Vec3::Zero(), {1, 0, 0}).hit());
  ClusterScene c1(one, ClusterView{t0, o01, {}, {}}, test::two_level_defaults());
  EXPECT_TRUE(c1.fused_vertex_pass());
  c1.update(one.positions());
  EXPECT_TRUE(validate(c1.data(), 1).empty());
  EXPECT_TRUE(trace_ray(c1.data(), Vec3(0.2, 0.2, 1), {0, 0, -1}).hit());
}

TEST(Tracer, ClusterSceneRejectsBadClusterings) {
  const Mesh m = test::load_mesh("bunny00.off");
  Clustering r = ptc::morton_runs(m, 50);
  r.triangle_order[0] = r.triangle_order[1];
  EXPECT_THROW(ClusterScene(m, view_of(r)), std::invalid_argument);
  r = ptc::morton_runs(m, 50);
  r.triangle_offsets.back() -= 1;
  EXPECT_THROW(ClusterScene(m, view_of(r)), std::invalid_argument);
}

TEST(Tracer, UpdateFollowsTheAnimation) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Mesh moved = test::deformed(m, 0.05);
  const Clustering runs = ptc::morton_runs(m, 64);
  TriangleScene ts(m);
  ClusterScene cs(m, view_of(runs));
  ts.update(moved.positions());
  cs.update(moved.positions());
  EXPECT_TRUE(validate(ts.data(), m.triangle_count()).empty());
  EXPECT_TRUE(validate(cs.data(), m.triangle_count(), false).empty());
  const RaySet rs = random_rays(moved, 300, 3);
  for (std::size_t i = 0; i < rs.org.size(); ++i) {
    const Hit want = test::brute_force(moved, ts.data().origin, rs.org[i], rs.dir[i]);
    expect_same(trace_ray(ts.data(), rs.org[i], rs.dir[i]), want, "triangles, frame 2");
    expect_same(trace_ray(cs.data(), rs.org[i], rs.dir[i]), want, "clusters, frame 2");
  }
}


// A triangle soup of `m` (three own vertices a triangle) with hard cases appended: a duplicate
// of triangle 0, a zero-area triangle (collinear corners) and one with a repeated corner.
Mesh soup_with_hard_cases(const Mesh& m) {
  std::vector<Vec3> p;
  std::vector<Tri> t;
  auto add = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    const auto v = static_cast<std::uint32_t>(p.size());
    p.push_back(a), p.push_back(b), p.push_back(c);
    t.push_back({v, v + 1, v + 2});
  };
  for (std::size_t i = 0; i < m.triangle_count(); ++i) {
    const auto c = m.corners(i);
    add(c[0], c[1], c[2]);
  }
  const auto c0 = m.corners(0), c5 = m.corners(5);
  add(c0[0], c0[1], c0[2]);
  add(c5[0], 0.5 * (c5[0] + c5[1]), c5[1]);
  add(c5[2], c5[2], c5[0]);
  return Mesh(std::move(t), std::move(p));
}

// The soup with each triangle moved along its unit normal by amount * (box diagonal) * f, f in
// [0.5, 1.5) a seeded hash of the triangle (the explode scene's motion); zero-area triangles stay.
Mesh flown_apart(const Mesh& soup, double amount) {
  std::vector<Vec3> p(soup.positions().begin(), soup.positions().end());
  const double d = (soup.bounds().hi - soup.bounds().lo).norm();
  for (std::size_t i = 0; i < soup.triangle_count(); ++i) {
    const auto c = soup.corners(i);
    const Vec3 n = (c[1] - c[0]).cross(c[2] - c[0]);
    if (!(n.norm() > 0)) continue;
    const double f = 0.5 + double((i * 2654435761u) % 1000u) / 1000.0;
    for (int k = 0; k < 3; ++k) p[3 * i + k] += amount * d * f * n.normalized();
  }
  return soup.with_positions(std::move(p));
}

// Every slot box of a wide tree against the union of triangle_boxes (the build's widened boxes)
// of the triangles below the slot (leaves read through the lane ids: a leaf's first `count`
// lanes), and the tree's SAH cost as wide_sah_cost defines it, summed over those boxes. Returns
// the cost.
template <class Nodes>
double expect_exact_boxes(const Nodes& nodes, const TraceData& d, const Mesh& now, const SahCostModel& model,
                          const std::string& what) {
  double inner = 0.0, leaf = 0.0;
  std::vector<Vec3f> fp;
  for (const Vec3& p : now.positions()) fp.push_back(to_frame(p, d.frame()));
  const std::vector<Box3f> tri_boxes = triangle_boxes(fp, now.triangles());
  std::function<Box3f(std::uint32_t)> walk = [&](std::uint32_t i) {
    Box3f node;
    for (int k = 0; k < nodes[i].kWidth; ++k) {
      if (nodes[i].is_empty(k)) continue;
      Box3f b;
      if (nodes[i].is_leaf(k)) {
        for (std::uint32_t l = 0; l < nodes[i].count[k]; ++l)
          b.extend(tri_boxes[d.triangle_ids[4 * std::size_t(nodes[i].child[k]) + l]]);
        leaf += nodes[i].count[k] * b.surface_area();
      } else {
        b = walk(nodes[i].child[k]);
        inner += b.surface_area();
      }
      EXPECT_EQ(nodes[i].child_box(k), b) << what << " node " << i << " slot " << k;
      node.extend(b);
    }
    return node;
  };
  const Box3f root = walk(0);
  return (model.traversal * (inner + root.surface_area()) + model.intersection * leaf) / root.surface_area();
}

// SceneConfig::refit_growth: a TriangleScene refitted to the positions it was built with holds
// the same bytes; refitted to frames whose triangles fly apart, every box of both wide trees is
// the exact box of its triangles, the hits are brute force's and the bytes the same at 1, 2 and
// 3 threads; a limit every refit passes rebuilds, and the rebuilt data is a fresh scene's; the
// schedule: a refit that fails at its first frame pauses the attempts for 1, 2, 4, then 8
// frames, and a frame whose growth, extrapolated as the square of the age, would pass the limit
// rebuilds without trying.
TEST(Tracer, TriangleSceneRefitsWhileItsCostAllowsAndRebuildsOtherwise) {
  const Mesh soup = soup_with_hard_cases(test::load_mesh("bunny00.off"));
  SceneConfig cfg = fallback_scene_defaults();
  cfg.origin = soup.bounds().center();  // (one trace frame for every scene below)
  cfg.scale = trace_frame_scale(soup, *cfg.origin);
  cfg.refit_growth = 1e9;
  {
    TriangleScene s(soup, cfg);
    EXPECT_FALSE(s.refit_tried());
    const TraceData built = s.data();
    s.update(soup.positions());
    ASSERT_TRUE(s.refit_tried() && s.refitted());
    test::expect_same_data(s.data(), built, "refitted to the build's own positions");
    EXPECT_EQ(s.wide_cost(), s.built_wide_cost());
  }
  std::vector<TraceData> first;
  for (int threads : {1, 2, 3}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    TriangleScene s(soup, cfg);
    for (int f = 1; f <= 4; ++f) {
      const Mesh now = flown_apart(soup, 0.002 * f);
      s.update(now.positions());
      const std::string what = "threads " + std::to_string(threads) + " frame " + std::to_string(f);
      ASSERT_TRUE(s.refitted()) << what;
      const TraceData& d = s.data();
      ASSERT_TRUE(validate(d, soup.triangle_count()).empty()) << what << test::joined(validate(d, soup.triangle_count()));
      if (threads > 1) {
        test::expect_same_data(d, first[f - 1], what);
        continue;
      }
      first.push_back(d);
      expect_exact_boxes(d.wide.nodes, d, now, cfg.build.cost, what + " 4-wide");
      const double cost = expect_exact_boxes(d.wide8.nodes, d, now, cfg.build.cost, what + " 8-wide");
      EXPECT_NEAR(s.wide_cost(), cost, 1e-9 * cost) << what;
      EXPECT_GT(s.wide_cost(), s.built_wide_cost()) << what;  // (the triangles spread)
      const RaySet rs = random_rays(now, 300, 40u + f);
      for (std::size_t i = 0; i < rs.org.size(); ++i)
        expect_same(trace_ray(d, rs.org[i], rs.dir[i]), test::brute_force(now, d.frame(), rs.org[i], rs.dir[i]),
                    what + " ray " + std::to_string(i));
    }
  }
  {  // A limit every refit passes: rebuilt, as a fresh scene over the frame.
    cfg.refit_growth = 1e-12;
    TriangleScene s(soup, cfg);
    const Mesh now = flown_apart(soup, 0.003);
    s.update(now.positions());
    EXPECT_TRUE(s.refit_tried());
    EXPECT_FALSE(s.refitted());
    EXPECT_EQ(s.wide_cost(), s.built_wide_cost());
    const TriangleScene fresh(now, cfg);
    test::expect_same_data(s.data(), fresh.data(), "rebuilt after a refit over the limit");
  }
  {  // The pauses after refits that fail at their first frame: attempts on updates 1, 3, 6, 11, 20, 29.
    TriangleScene s(soup, cfg);
    std::vector<int> tried;
    for (int u = 1; u <= 30; ++u) {
      s.update(flown_apart(soup, 0.001 * u).positions());
      ASSERT_FALSE(s.refitted()) << "update " << u;
      if (s.refit_tried()) tried.push_back(u);
    }
    EXPECT_EQ(tried, (std::vector<int>{1, 3, 6, 11, 20, 29}));
  }
  {  // A refit that fails after a kept frame: no pause, the next update tries again; the
     // rejected frame's stages hold the refit's time and the rebuild's.
    cfg.refit_growth = 1e9;
    TriangleScene probe(soup, cfg);
    probe.update(flown_apart(soup, 0.001).positions());
    const double g1 = probe.wide_cost() / probe.built_wide_cost() - 1.0;
    cfg.refit_growth = 10.0 * g1;  // (the extrapolation after one kept frame, 4 g1, passes)
    TriangleScene s(soup, cfg);
    s.update(flown_apart(soup, 0.001).positions());
    ASSERT_TRUE(s.refitted());
    const auto t0 = std::chrono::steady_clock::now();
    s.update(flown_apart(soup, 0.05).positions());  // (a jump no limit of 10 g1 holds)
    const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_TRUE(s.refit_tried());
    EXPECT_FALSE(s.refitted());
    const StageTimes& t = s.times();
    EXPECT_GT(t.refit_ms, 0.0);
    EXPECT_GT(t.leaf_data_ms, 0.0);
    EXPECT_GT(t.build_ms, 0.0);
    EXPECT_GT(t.collapse_ms, 0.0);
    EXPECT_LE(t.total_ms(), wall + 1e-6);
    s.update(flown_apart(soup, 0.0505).positions());
    EXPECT_TRUE(s.refit_tried());
    EXPECT_TRUE(s.refitted());
  }
  {  // The extrapolation: a limit of twice the first frame's growth keeps one frame in two.
    cfg.refit_growth = 1e9;
    TriangleScene probe(soup, cfg);
    probe.update(flown_apart(soup, 0.001).positions());
    const double g1 = probe.wide_cost() / probe.built_wide_cost() - 1.0;
    ASSERT_GT(g1, 0.0);
    cfg.refit_growth = 2.0 * g1;
    TriangleScene s(soup, cfg);
    for (int u = 1; u <= 6; ++u) {
      s.update(flown_apart(soup, 0.001 * u).positions());
      EXPECT_EQ(s.refitted(), u % 2 == 1) << "update " << u;
      EXPECT_EQ(s.refit_tried(), u % 2 == 1) << "update " << u;
      if (s.refitted()) {
        EXPECT_LE(s.wide_cost(), (1.0 + cfg.refit_growth) * s.built_wide_cost()) << "update " << u;
      }
    }
  }
}

}  // namespace
}  // namespace ptc::bvh

namespace ptc::bvh {
namespace {

// A ray whose float edge function rounds to exactly 0 while the exact value is -2^-46: the
// double recomputation must decide (the ray is inside triangle 1 = (A, B, C) and outside
// triangle 0 = (C, B, D), which share edge BC). Without it the SIMD kernel would report
// triangle 0, which lies on the wrong side.
TEST(Tracer, DoubleFallbackDecidesAnEdgeFunctionThatRoundsToZero) {
  const double e = std::ldexp(1.0, -23);
  const std::vector<Vec3> p{{-1, 1, 2}, {-1, -1 - e, 2}, {1 + e, 1 + 2 * e, 2}, {1, -1, 1.5}};  // A B C D
  const Mesh m({{2, 1, 3}, {0, 1, 2}}, p);
  SceneConfig at_zero;
  at_zero.origin = Vec3::Zero();
  const TriangleScene s(m, at_zero);
  const WatertightRay r = make_watertight_ray({0, 0, 0}, {0, 0, 1});
  auto f = [&](int v) { return to_frame(p[v], Vec3::Zero()); };
  EXPECT_TRUE(intersect_triangle(r, f(0), f(1), f(2), 0.0f, kInf));
  EXPECT_FALSE(intersect_triangle(r, f(2), f(1), f(3), 0.0f, kInf));
  const Hit h = trace_ray(s.data(), Vec3::Zero(), {0, 0, 1});
  EXPECT_EQ(h.triangle, 1u);
  expect_same(h, test::brute_force(m, Vec3::Zero(), Vec3::Zero(), {0, 0, 1}), "fallback");
}

// The bunny with two unreferenced vertices, one far away before all others and one after them.
Mesh with_unreferenced_ends(const Mesh& base) {
  std::vector<Vec3> p{Vec3(1e3, -1e3, 5)};
  p.insert(p.end(), base.positions().begin(), base.positions().end());
  p.push_back(Vec3(-1e3, 1e3, 0));
  std::vector<Tri> t(base.triangles().begin(), base.triangles().end());
  for (Tri& x : t)
    for (auto& v : x) v += 1;
  return Mesh(t, p);
}

// The bench's clustering: growth, Acc, MaxCount = MaxSize = 50.
Clustering acc50(const Mesh& m) {
  ClusterConfig cc;
  cc.method = ClusterMethod::Growth;
  cc.objective = ObjectiveKind::Acc;
  cc.max_count = 50;
  cc.max_size = 50;
  return cluster_mesh(m, cc);
}

// The bench's clustering of a mesh, and the mesh and clustering renumbered in its vertex order
// (cluster_vertex_order with the default cluster scene settings).
struct Renumbered {
  explicit Renumbered(Mesh mesh)
      : m(std::move(mesh)),
        cl(acc50(m)),
        to_old(cluster_vertex_order(m, view_of(cl), {}, test::two_level_defaults())),
        rm(renumber_vertices(m, to_old)),
        rcl(renumber_vertices(cl, inverse_permutation(to_old))) {}
  Mesh m;
  Clustering cl;
  std::vector<std::uint32_t> to_old;
  Mesh rm;
  Clustering rcl;
};

// The method's clusters (toolkit/clustering: growth, Acc, MaxCount = MaxSize = 50, the bench's
// configuration) in both leaf modes, plain and two-level builds, over two animated frames: ray by ray equal to brute force,
// any-hit agreeing with closest-hit on occlusion.
TEST(Tracer, AccClustersMatchBruteForce) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Clustering cl = acc50(m);
  ASSERT_GT(cl.cluster_count(), 10u);
  const Mesh moved = test::deformed(m, 0.03);
  for (std::uint32_t group : {0u, 3u, 8u})  // plain build, and two-level builds (SceneConfig::cluster_group_size)
  for (GroupTrees trees : {GroupTrees::Rebuild, GroupTrees::Refit})
  for (ClusterLeaf mode : {ClusterLeaf::Linear, ClusterLeaf::BlockTree}) {
    if (group == 0 && trees == GroupTrees::Refit) continue;  // (no groups: the same plain build)
    SCOPED_TRACE("cluster_group_size " + std::to_string(group) + ", group trees " + to_string(trees));
    SceneConfig cfg = test::two_level_defaults();
    cfg.cluster_leaf = mode;
    cfg.cluster_group_size = group;
    cfg.group_trees = trees;
    ClusterScene s(m, view_of(cl), cfg);
    for (const Mesh* frame : {&m, &moved}) {
      s.update(frame->positions());
      const auto issues = validate(s.data(), m.triangle_count(), false);
      ASSERT_TRUE(issues.empty()) << test::joined(issues);
      const RaySet rs = random_rays(*frame, 200, 31);
      int hits = 0;
      for (std::size_t i = 0; i < rs.org.size(); ++i) {
        const Hit want = test::brute_force(*frame, s.data().origin, rs.org[i], rs.dir[i]);
        expect_same(trace_ray(s.data(), rs.org[i], rs.dir[i]), want, std::string(to_string(mode)) + " acc ray");
        EXPECT_EQ(trace_ray(s.data(), rs.org[i], rs.dir[i], HitMode::Any).hit(), want.hit());
        hits += want.hit();
      }
      EXPECT_GT(hits, 60);
    }
  }
}

// Fixed group trees whose leaves hold several clusters (max_leaf_size > 1: the groups' trees
// refer to fixed ranges, the top's leaves still hold one group each) over a moved frame: a valid
// flat structure, and brute force's hits ray by ray. Block-tree leaves hold one cluster each (a
// leaf of several would bypass their trees): refused with such settings, whatever the build.
TEST(Tracer, FixedGroupTreesWithLeavesOfSeveralClusters) {
  const Mesh m = test::load_mesh("bunny00.off");
  const Clustering runs = ptc::morton_runs(m, 6);
  const Mesh moved = test::deformed(m, 0.08);
  SceneConfig cfg = test::two_level_defaults();
  cfg.group_trees = GroupTrees::Refit;
  cfg.cluster_group_size = 16;
  cfg.build.max_leaf_size = 4;
  cfg.build.cost.intersection = 0.05;  // (cheap triangles: the builder makes leaves of several clusters)
  ClusterScene s(m, view_of(runs), cfg);
  s.update(moved.positions());
  ASSERT_FALSE(s.data().ranges.empty()) << "no leaf of several clusters: the test needs some";
  const auto issues = validate(s.data(), m.triangle_count(), true);
  ASSERT_TRUE(issues.empty()) << test::joined(issues);
  const RaySet rs = random_rays(moved, 300, 13);
  for (std::size_t i = 0; i < rs.org.size(); ++i)
    expect_same(trace_ray(s.data(), rs.org[i], rs.dir[i]), test::brute_force(moved, s.data().origin, rs.org[i], rs.dir[i]),
                "ray " + std::to_string(i));
  for (GroupTrees trees : {GroupTrees::Rebuild, GroupTrees::Refit}) {
    SceneConfig bt = cfg;
    bt.group_trees = trees;
    bt.cluster_leaf = ClusterLeaf::BlockTree;
    EXPECT_THROW(ClusterScene(m, view_of(runs), bt), std::invalid_argument);
    bt.build.max_leaf_size = 1;
    EXPECT_NO_THROW(ClusterScene(m, view_of(runs), bt));
  }
}

// The scene's per-frame cluster boxes (computed from vertices renumbered in first-touch order)
// equal, bit for bit, brute-force min/max over each cluster's ORIGINAL vertex list in the frame,
// widened by one ulp: Acc clusters (shared boundary vertices) and Morton runs (no vertex lists:
// triangle corners), on a mesh with unreferenced vertices (one before, one after the used ones),
// over two frames; the traced hits stay those of brute force.
TEST(Tracer, ClusterBoxesEqualBruteForceOverTheOriginalVertices) {
  const Mesh base = test::load_mesh("bunny00.off");
  const Mesh m = with_unreferenced_ends(base);
  const Clustering cl = acc50(m);
  const Clustering runs = ptc::morton_runs(m, 37);
  std::vector<std::uint32_t> corner_offsets{0}, corners;  // the runs' implied vertex lists
  for (std::size_t c = 0; c + 1 < runs.triangle_offsets.size(); ++c) {
    for (std::uint32_t i = runs.triangle_offsets[c]; i < runs.triangle_offsets[c + 1]; ++i)
      for (std::uint32_t v : m.triangles()[runs.triangle_order[i]]) corners.push_back(v);
    corner_offsets.push_back(static_cast<std::uint32_t>(corners.size()));
  }
  const Mesh moved = test::deformed(m, 0.04);
  for (int which = 0; which < 2; ++which) {
    const ClusterView view = which == 0 ? view_of(cl) : view_of(runs);
    const std::span<const std::uint32_t> offs = which == 0 ? std::span<const std::uint32_t>(cl.vertex_offsets)
                                                           : std::span<const std::uint32_t>(corner_offsets);
    const std::span<const std::uint32_t> verts =
        which == 0 ? std::span<const std::uint32_t>(cl.vertices) : std::span<const std::uint32_t>(corners);
    ClusterScene s(m, view);
    for (const Mesh* frame : {&m, &moved}) {
      s.update(frame->positions());
      ASSERT_EQ(s.boxes().size(), offs.size() - 1);
      for (std::size_t c = 0; c + 1 < offs.size(); ++c) {
        Box3f want;
        for (int a = 0; a < 3; ++a) {
          float lo = kInf, hi = -kInf;
          for (std::uint32_t i = offs[c]; i < offs[c + 1]; ++i) {
            const Vec3f f = to_frame(frame->positions()[verts[i]], s.data().origin);
            lo = std::min(lo, f[a]), hi = std::max(hi, f[a]);
          }
          want.lo[a] = next_below(lo), want.hi[a] = next_above(hi);
        }
        ASSERT_EQ(s.boxes()[std::find(s.cluster_ids().begin(), s.cluster_ids().end(), c) - s.cluster_ids().begin()], want)
            << "clustering " << which << " cluster " << c;
      }
      const auto issues = validate(s.data(), m.triangle_count(), true);
      ASSERT_TRUE(issues.empty()) << test::joined(issues);
      const RaySet rs = random_rays(*frame, 150, 41);
      for (std::size_t i = 0; i < rs.org.size(); ++i)
        expect_same(trace_ray(s.data(), rs.org[i], rs.dir[i]),
                    test::brute_force(*frame, s.data().origin, rs.org[i], rs.dir[i]), "renumbered");
    }
    EXPECT_THROW(s.update(base.positions()), std::invalid_argument);  // wrong vertex count
  }
}


// The method's precomputation: the mesh renumbered once with cluster_vertex_order (and the
// clustering with it). The cluster scene then takes the fused conversion + box pass; its boxes,
// its tree and every traced hit (triangle id, t, u, v) equal those of the scene over the original
// numbering, ray by ray, in both leaf modes, over two frames; and brute force on the renumbered
// mesh agrees. Unreferenced vertices (first and last) included.
TEST(Tracer, RenumberedMeshTakesTheFusedPassAndTracesTheSame) {
  const Mesh base = test::load_mesh("bunny00.off");
  const Renumbered r(with_unreferenced_ends(base));
  const auto& [m, cl, to_old, rm, rcl] = r;
  ASSERT_TRUE(validate(rcl, rm.triangles()).empty());
  const Mesh moved = test::deformed(m, 0.04);
  std::vector<Vec3> rmoved(m.vertex_count());
  for (std::size_t i = 0; i < to_old.size(); ++i) rmoved[i] = moved.positions()[to_old[i]];
  const Mesh rm_moved = rm.with_positions(rmoved);
  for (ClusterLeaf mode : {ClusterLeaf::Linear, ClusterLeaf::BlockTree}) {
    SceneConfig cfg = test::two_level_defaults();
    cfg.cluster_leaf = mode;
    ClusterScene a(m, view_of(cl), cfg), b(rm, view_of(rcl), cfg);
    EXPECT_FALSE(a.fused_vertex_pass()) << "the file's order happens to be the clusters' (the test needs both paths)";
    ASSERT_TRUE(b.fused_vertex_pass());
    EXPECT_EQ(a.data().origin, b.data().origin);
    for (int f = 0; f < 2; ++f) {
      a.update((f ? moved : m).positions());
      b.update((f ? rm_moved : rm).positions());
      // (one pass over the input: fused into the boxes, or alone with the boxes from the fill)
      EXPECT_TRUE(b.times().vertices_ms == 0.0 || b.times().boxes_ms == 0.0);
      ASSERT_TRUE(std::ranges::equal(a.boxes(), b.boxes())) << "frame " << f;
      EXPECT_EQ(a.bvh().prim_order, b.bvh().prim_order);
      // The blocks (and the block trees' boxes, refitted from them) byte for byte.
      test::expect_same_data(a.data(), b.data(), "frame " + std::to_string(f));
      ASSERT_TRUE(validate(b.data(), rm.triangle_count(), false).empty());
      const Mesh& frame = f ? rm_moved : rm;
      const RaySet rs = random_rays(frame, 200, 57);
      int hits = 0;
      for (std::size_t i = 0; i < rs.org.size(); ++i) {
        const Hit hb = trace_ray(b.data(), rs.org[i], rs.dir[i]);
        const Hit ha = trace_ray(a.data(), rs.org[i], rs.dir[i]);
        EXPECT_EQ(hb.triangle, ha.triangle) << i;
        EXPECT_EQ(hb.t, ha.t) << i;
        EXPECT_EQ(hb.u, ha.u) << i;
        EXPECT_EQ(hb.v, ha.v) << i;
        expect_same(hb, test::brute_force(frame, b.data().origin, rs.org[i], rs.dir[i]), "renumbered mesh");
        hits += hb.hit();
      }
      EXPECT_GT(hits, 50);
    }
  }
  // A clustering given without vertex lists (the scene uses the triangles' corners) takes the
  // fused pass when the mesh was renumbered over those corner lists.
  const Clustering runs = ptc::morton_runs(m, 37);
  const ClusterView no_lists{runs.triangle_order, runs.triangle_offsets, {}, {}};
  const Mesh rr = renumber_vertices(m, cluster_vertex_order(m, no_lists, {}, test::two_level_defaults()));
  ClusterScene c(rr, no_lists), c_old(m, no_lists);
  EXPECT_TRUE(c.fused_vertex_pass());
  EXPECT_FALSE(c_old.fused_vertex_pass());
  EXPECT_TRUE(std::ranges::equal(c.boxes(), c_old.boxes()));
  EXPECT_THROW(c.update(base.positions()), std::invalid_argument);  // wrong vertex count
}


// Positions that are not finite in the float trace frame (NaN, infinity, or beyond float range
// from the origin) are refused with the vertex named, at construction and per frame, by both
// scene kinds, in the fused and the gathering cluster paths and on both instruction sets;
// a referenced or an unreferenced vertex alike. The scene stays usable with good positions.
TEST(Tracer, NonFinitePositionsAreRefusedNamingTheVertex) {
  const Mesh base = test::load_mesh("bunny00.off");
  const Renumbered r(with_unreferenced_ends(base));
  const auto& [m, cl, to_old, rm, rcl] = r;
  auto expect_names = [](auto&& fn, std::size_t v, const std::string& what) {
    try {
      fn();
      ADD_FAILURE() << what << ": accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("vertex " + std::to_string(v) + ":"), std::string::npos)
          << what << ": " << e.what();
    }
  };
  const double nan = std::nan("");
  for (const Vec3& bad : {Vec3(nan, 0, 0), Vec3(0, std::numeric_limits<double>::infinity(), 0), Vec3(0, 0, 1e39)}) {
    for (const std::size_t v : {std::size_t(0), std::size_t(500), m.vertex_count() - 1}) {  // unreferenced, used, unreferenced
      const std::string what = "vertex " + std::to_string(v) + " = " + std::to_string(bad.x()) + "," +
                               std::to_string(bad.y()) + "," + std::to_string(bad.z());
      std::vector<Vec3> p(m.positions().begin(), m.positions().end());
      p[v] = bad;
      if (bad.allFinite() && v != 500) {
        // finite in double, beyond the float range, and used by no triangle: the frame is the
        // triangles' (it stays), and the conversion refuses the vertex, naming it.
        expect_names([&] { TriangleScene s(m.with_positions(p)); }, v, what + " triangle ctor");
        expect_names([&] { ClusterScene s(m.with_positions(p), view_of(cl), test::two_level_defaults()); }, v,
                     what + " cluster ctor");
      } else if (bad.allFinite()) {
        // finite in double, beyond the float range, used: at construction the frame's origin (the
        // bounds' centre) moves out with the vertex, and the mesh's extent is refused.
        try {
          ClusterScene s(m.with_positions(p), view_of(cl), test::two_level_defaults());
          ADD_FAILURE() << what << ": accepted";
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("beyond the single-precision tracer's range"), std::string::npos)
              << e.what();
        }
      } else {
        expect_names([&] { TriangleScene s(m.with_positions(p)); }, v, what + " triangle ctor");
        expect_names([&] { ClusterScene s(m.with_positions(p), view_of(cl), test::two_level_defaults()); }, v,
                     what + " cluster ctor");
      }
      TriangleScene ts(m);
      expect_names([&] { ts.update(p); }, v, what + " triangle update");
      ClusterScene gather(m, view_of(cl), test::two_level_defaults());
      ASSERT_FALSE(gather.fused_vertex_pass());
      expect_names([&] { gather.update(p); }, v, what + " gathering update");
      ClusterScene fused(rm, view_of(rcl), test::two_level_defaults());
      ASSERT_TRUE(fused.fused_vertex_pass());
      std::vector<Vec3> rp(m.vertex_count());
      for (std::size_t i = 0; i < rp.size(); ++i) rp[i] = p[to_old[i]];
      const std::size_t rv = inverse_permutation(to_old)[v];
      expect_names([&] { fused.update(rp); }, rv, what + " fused update");
      fused.update(rm.positions());  // still usable
      EXPECT_TRUE(validate(fused.data(), rm.triangle_count()).empty());
    }
  }
}

}  // namespace
}  // namespace ptc::bvh
