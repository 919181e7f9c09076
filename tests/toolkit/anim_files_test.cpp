// File-based animation sources (toolkit/anim): welding, frame sequences, MD2 through assimp,
// MD3 with our own reader, the load_animation front door. Independent answers: a brute-force
// welder, our own MD2 decoder written from the format description (not assimp), assimp's MD3
// importer for frame 0 of MD3 files, positions written with write_mesh.
#include <gtest/gtest.h>
#include <unistd.h>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "common/temp_dir.h"
#include "toolkit/anim/assimp_source.h"
#include "toolkit/anim/frame_sequence.h"
#include "toolkit/anim/load_animation.h"
#include "toolkit/anim/md3.h"
#include "toolkit/anim/weld.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

namespace fs = std::filesystem;

const fs::path kFaerie = "/usr/share/assimp/models/MD2/faerie.md2";

class AnimFiles : public test::TempDirTest {};

using test::slurp;
using test::spit;

// Asserts that f() throws InputError whose message contains every one of `parts`.
template <class F>
void expect_input_error(F&& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no InputError thrown";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

std::vector<Vec3> positions_at(Animation& a, double t) {
  std::vector<Vec3> p(a.rest().vertex_count());
  a.positions(t, p);
  return p;
}

// ---------------------------------------------------------------------------------------------
// Welding

// Brute force: i and j weld iff equal (==) in every frame; classes numbered by first occurrence.
WeldMap brute_weld(const std::vector<std::vector<Vec3>>& frames) {
  const std::size_t n = frames.front().size();
  WeldMap m;
  m.remap.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    bool found = false;
    for (std::size_t w = 0; w < m.representative.size() && !found; ++w) {
      const std::size_t j = m.representative[w];
      bool same = true;
      for (const auto& f : frames) same = same && f[i] == f[j];  // NaN: never equal
      if (same) {
        m.remap[i] = static_cast<std::uint32_t>(w);
        found = true;
      }
    }
    if (!found) {
      m.remap[i] = static_cast<std::uint32_t>(m.representative.size());
      m.representative.push_back(static_cast<std::uint32_t>(i));
    }
  }
  return m;
}

TEST(AnimWeld, EmptyAndSingle) {
  const std::vector<std::vector<Vec3>> none{{}};
  const WeldMap e = weld_frames(none);
  EXPECT_EQ(e.welded_count(), 0u);
  EXPECT_EQ(e.merged(), 0u);
  const std::vector<std::vector<Vec3>> one{{Vec3(1, 2, 3)}, {Vec3(4, 5, 6)}};
  const WeldMap s = weld_frames(one);
  EXPECT_EQ(s.welded_count(), 1u);
  EXPECT_EQ(s.remap, std::vector<std::uint32_t>{0});
  VertexWelder w(3);
  EXPECT_THROW((void)w.finish(), std::logic_error);  // no frame: not "everything coincides"
  EXPECT_THROW(w.add_frame(std::vector<Vec3>(2)), std::invalid_argument);
}

TEST(AnimWeld, CoincideInOneFrameOnlyIsNotEnough) {
  // 0 and 1 touch in frame 0 and separate in frame 1; 0 and 2 coincide in both; -0.0 == +0.0;
  // NaN vertices never merge, not even with themselves' twins.
  const double nan = std::nan("");
  const std::vector<std::vector<Vec3>> frames{
      {Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(-0.0, 1, 0), Vec3(0.0, 1, 0), Vec3(nan, 0, 0), Vec3(nan, 0, 0)},
      {Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(1, 0, 0), Vec3(5, 5, -0.0), Vec3(5, 5, 0.0), Vec3(0, 0, 0), Vec3(0, 0, 0)}};
  const WeldMap w = weld_frames(frames);
  EXPECT_EQ(w.remap, (std::vector<std::uint32_t>{0, 1, 0, 2, 2, 3, 4}));
  EXPECT_EQ(w.representative, (std::vector<std::uint32_t>{0, 1, 3, 5, 6}));
  EXPECT_EQ(w.merged(), 2u);
  const std::vector<Tri> tris{{0, 1, 2}, {2, 3, 4}};
  EXPECT_EQ(w.apply(tris), (std::vector<Tri>{{0, 1, 0}, {0, 2, 2}}));  // degenerate kept, ids unchanged
}

TEST(AnimWeld, MatchesBruteForceOnRandomFrames) {
  std::mt19937 rng(7);
  for (int round = 0; round < 30; ++round) {
    const std::size_t n = 1 + rng() % 60, nf = 1 + rng() % 4;
    // Few distinct values so that many vertices coincide in some frames but not all.
    std::uniform_int_distribution<int> v(0, round % 3 + 1);
    std::vector<std::vector<Vec3>> frames(nf, std::vector<Vec3>(n));
    for (auto& f : frames)
      for (auto& p : f) p = Vec3(v(rng), v(rng) * 0.5, 0.0);
    const WeldMap a = weld_frames(frames), b = brute_weld(frames);
    ASSERT_EQ(a.remap, b.remap) << "round " << round;
    ASSERT_EQ(a.representative, b.representative) << "round " << round;
    for (std::size_t i = 0; i < n; ++i)
      for (const auto& f : frames) ASSERT_EQ(a.gather(f)[a.remap[i]], f[i]);
  }
}

// ---------------------------------------------------------------------------------------------
// File lists

TEST(AnimFrameList, NaturalOrder) {
  EXPECT_TRUE(natural_less("f2.obj", "f10.obj"));
  EXPECT_FALSE(natural_less("f10.obj", "f2.obj"));
  EXPECT_TRUE(natural_less("f9.obj", "f010.obj"));
  EXPECT_TRUE(natural_less("a.obj", "b.obj"));
  EXPECT_TRUE(natural_less("f1.obj", "f1a.obj"));
  EXPECT_FALSE(natural_less("x", "x"));
  // leading zeros: equal values are ordered bytewise so the order stays total
  EXPECT_NE(natural_less("f01", "f1"), natural_less("f1", "f01"));
  EXPECT_TRUE(natural_less("f99999999999999999999", "f100000000000000000000"));  // longer than 64 bits
}

TEST_F(AnimFiles, ListsDirectoryAndGlobInNaturalOrder) {
  const Mesh m({{0, 1, 2}}, {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)});
  for (const char* n : {"w10.obj", "w2.obj", "w1.ply", "other.off"}) write_mesh(dir_ / n, m);
  spit(dir_ / "notes.txt", "x");
  const auto all = list_frame_files(dir_.string());
  ASSERT_EQ(all.size(), 4u);
  EXPECT_EQ(all[0].filename(), "other.off");
  EXPECT_EQ(all[1].filename(), "w1.ply");
  EXPECT_EQ(all[2].filename(), "w2.obj");
  EXPECT_EQ(all[3].filename(), "w10.obj");
  const auto g = list_frame_files((dir_ / "w*.obj").string());
  ASSERT_EQ(g.size(), 2u);
  EXPECT_EQ(g[0].filename(), "w2.obj");
  expect_input_error([&] { (void)list_frame_files((dir_ / "zz*.obj").string()); }, {"zz*.obj", "no file matches"});
  expect_input_error([&] { (void)list_frame_files((dir_ / "missing").string()); }, {"missing", "no such directory"});
  fs::create_directories(dir_ / "empty");
  expect_input_error([&] { (void)list_frame_files((dir_ / "empty").string()); }, {"empty", "no .obj/.ply/.off"});
}

// ---------------------------------------------------------------------------------------------
// Frame sequences

// A small grid of quads (2 triangles each), with frame k displaced by a known function.
Mesh grid(int n, double t) {
  std::vector<Vec3> p;
  std::vector<Tri> tris;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      p.emplace_back(i + 0.1 * t * j, j + 1.0 / 3.0, std::sin(0.7 * i + t) * 1e-3 + 1e7 * (t == 2.0));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      tris.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      tris.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return Mesh(tris, p);
}

TEST_F(AnimFiles, ThreeFramesWrittenAndReadBackGiveTheSamePositions) {
  for (const char* ext : {".obj", ".ply", ".off"}) {
    const fs::path sub = dir_ / (std::string("seq") + (ext + 1));
    fs::create_directories(sub);
    std::vector<Mesh> frames;
    for (int k = 0; k < 3; ++k) {
      frames.push_back(grid(4, k));
      write_mesh(sub / ("frame_" + std::to_string(k) + ext), frames.back());
    }
    for (FrameLoading mode : {FrameLoading::Lazy, FrameLoading::Eager}) {
      FrameSequenceOptions o;
      o.loading = mode;
      FrameSequence s(sub.string(), o);
      ASSERT_EQ(s.frame_count(), 3u);
      ASSERT_EQ(s.rest().vertex_count(), frames[0].vertex_count());
      EXPECT_TRUE(std::equal(s.rest().triangles().begin(), s.rest().triangles().end(), frames[0].triangles().begin()));
      // Out of order on purpose: the lazy cache must not return a stale frame.
      for (int k : {2, 0, 1, 2, 1}) {
        const auto p = positions_at(s, k);
        for (std::size_t v = 0; v < p.size(); ++v)
          ASSERT_EQ(p[v], frames[static_cast<std::size_t>(k)].position(v)) << ext << " frame " << k << " vertex " << v;
      }
      for (int k : {1, 0}) {  // midpoints t + 0.5
        const auto p = positions_at(s, k + 0.5);
        for (std::size_t v = 0; v < p.size(); ++v) {
          const Vec3 mid = 0.5 * (frames[k].position(v) + frames[k + 1].position(v));
          ASSERT_LE((p[v] - mid).norm(), 1e-15 * (1.0 + mid.norm())) << ext << " t " << k + 0.5 << " vertex " << v;
        }
      }
      std::vector<Vec3> out(s.rest().vertex_count());
      EXPECT_THROW(s.positions(-0.5, out), std::out_of_range);
      EXPECT_THROW(s.positions(2.0001, out), std::out_of_range);
      EXPECT_THROW(s.positions(std::nan(""), out), std::out_of_range);
      std::vector<Vec3> small(3);
      EXPECT_THROW(s.positions(0, small), std::invalid_argument);
    }
  }
}

TEST_F(AnimFiles, SingleFrameSequenceIsStatic) {
  const Mesh g = grid(2, 1);
  write_mesh(dir_ / "only.ply", g);
  FrameSequence s((dir_ / "only*.ply").string());
  EXPECT_TRUE(s.is_static());
  EXPECT_EQ(s.frame_count(), 1u);
  const std::vector<Vec3> want(g.positions().begin(), g.positions().end());
  EXPECT_EQ(positions_at(s, 0), want);
  EXPECT_EQ(positions_at(s, 41.5), want);  // any finite time
  std::vector<Vec3> out(want.size());
  EXPECT_THROW(s.positions(std::nan(""), out), std::out_of_range);
}

TEST_F(AnimFiles, MismatchedFrameNamesFileAndElement) {
  write_mesh(dir_ / "f0.obj", grid(3, 0));
  write_mesh(dir_ / "f1.obj", grid(3, 1));
  // Frame 2: same counts, triangle 5 differs.
  Mesh g = grid(3, 2);
  std::vector<Tri> tris(g.triangles().begin(), g.triangles().end());
  std::swap(tris[5][0], tris[5][1]);
  write_mesh(dir_ / "f2.obj", Mesh(tris, std::vector<Vec3>(g.positions().begin(), g.positions().end())));
  FrameSequenceOptions eager;
  eager.loading = FrameLoading::Eager;
  expect_input_error([&] { FrameSequence s(dir_.string(), eager); }, {"f2.obj", "triangle 5", "f0.obj"});
  // Lazy: construction succeeds, the error surfaces when frame 2 is needed (also for t = 1.5).
  FrameSequence lazy(dir_.string());
  EXPECT_NO_THROW((void)positions_at(lazy, 1));
  expect_input_error([&] { (void)positions_at(lazy, 1.5); }, {"f2.obj", "triangle 5"});
  expect_input_error([&] { (void)positions_at(lazy, 2); }, {"f2.obj", "triangle 5"});
  EXPECT_NO_THROW((void)positions_at(lazy, 0.5));  // the cache was not poisoned
  // Vertex count.
  write_mesh(dir_ / "f2.obj", grid(4, 2));
  expect_input_error([&] { FrameSequence s(dir_.string(), eager); }, {"f2.obj", "vertex count", "25 vertices", "has 16"});
  // Triangle count (same vertices, one triangle fewer).
  tris.pop_back();
  write_mesh(dir_ / "f2.obj", Mesh(tris, std::vector<Vec3>(g.positions().begin(), g.positions().end())));
  expect_input_error([&] { FrameSequence s(dir_.string(), eager); }, {"f2.obj", "triangle count", "17 triangles"});
}

TEST_F(AnimFiles, MissingAndTruncatedFramesAreInputErrors) {
  write_mesh(dir_ / "a0.ply", grid(3, 0));
  write_mesh(dir_ / "a1.ply", grid(3, 1));
  write_mesh(dir_ / "a2.ply", grid(3, 2));
  FrameSequence lazy(dir_.string());
  fs::remove(dir_ / "a2.ply");  // disappears after listing
  expect_input_error([&] { (void)positions_at(lazy, 2); }, {"a2.ply"});
  const std::string bytes = slurp(dir_ / "a1.ply");
  spit(dir_ / "a1.ply", bytes.substr(0, bytes.size() - 7));  // truncated binary PLY
  FrameSequence lazy2(std::vector<fs::path>{dir_ / "a0.ply", dir_ / "a1.ply"});
  expect_input_error([&] { (void)positions_at(lazy2, 1); }, {"a1.ply"});
  FrameSequenceOptions eager;
  eager.loading = FrameLoading::Eager;
  expect_input_error([&] { FrameSequence s(std::vector<fs::path>{dir_ / "a0.ply", dir_ / "a1.ply"}, eager); }, {"a1.ply"});
  expect_input_error([&] { FrameSequence s(std::vector<fs::path>{dir_ / "nope.obj"}); }, {"nope.obj"});
}

TEST_F(AnimFiles, WeldedSoupSequenceRecoversTheSharedVertices) {
  // Frames written as soups (three own vertices per triangle); welding must give back the grid's
  // topology: one vertex per grid vertex, the same positions at every frame.
  std::vector<Mesh> frames;
  for (int k = 0; k < 3; ++k) {
    const Mesh g = grid(3, k);
    frames.push_back(g);
    std::vector<Vec3> p;
    std::vector<Tri> t;
    for (const Tri& f : g.triangles()) {
      const auto b = static_cast<std::uint32_t>(p.size());
      for (int c = 0; c < 3; ++c) p.push_back(g.position(f[c]));
      t.push_back({b, b + 1, b + 2});
    }
    write_mesh(dir_ / ("s" + std::to_string(k) + ".obj"), Mesh(t, p));
  }
  for (FrameLoading mode : {FrameLoading::Lazy, FrameLoading::Eager}) {
    FrameSequenceOptions o;
    o.weld = true;
    o.loading = mode;
    FrameSequence s(dir_.string(), o);
    EXPECT_EQ(s.rest().vertex_count(), frames[0].vertex_count());
    EXPECT_EQ(s.merged_vertices(), 3 * frames[0].triangle_count() - frames[0].vertex_count());
    EXPECT_NE(s.describe().find("welded"), std::string::npos);
    for (int k : {0, 2, 1}) {
      const auto p = positions_at(s, k);
      for (std::size_t t = 0; t < frames[0].triangle_count(); ++t)
        for (int c = 0; c < 3; ++c)
          ASSERT_EQ(p[s.rest().triangle(t)[c]], frames[k].position(frames[k].triangle(t)[c]));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// MD2: our own decoder of the file, written from the format description.

struct Md2Decoded {
  std::vector<std::array<std::uint16_t, 3>> tris;
  std::vector<std::vector<Vec3>> frames;  // per frame, per MD2 vertex, in assimp's world axes
};

Md2Decoded decode_md2(const std::string& b) {
  auto u32 = [&](std::size_t o) {
    std::uint32_t v;
    std::memcpy(&v, b.data() + o, 4);
    return v;
  };
  auto f32 = [&](std::size_t o) {
    float v;
    std::memcpy(&v, b.data() + o, 4);
    return v;
  };
  Md2Decoded d;
  const std::uint32_t framesize = u32(16), nxyz = u32(24), ntris = u32(32), nframes = u32(40), ofs_tris = u32(52),
                      ofs_frames = u32(56);
  for (std::uint32_t t = 0; t < ntris; ++t) {
    std::array<std::uint16_t, 3> tri;
    std::memcpy(tri.data(), b.data() + ofs_tris + 12 * t, 6);
    d.tris.push_back(tri);
  }
  for (std::uint32_t k = 0; k < nframes; ++k) {
    const std::size_t f = ofs_frames + std::size_t{k} * framesize;
    std::vector<Vec3> p;
    for (std::uint32_t v = 0; v < nxyz; ++v) {
      const auto* q = reinterpret_cast<const unsigned char*>(b.data() + f + 40 + 4 * v);
      float x = static_cast<float>(q[0]) * f32(f + 0);
      x += f32(f + 12);
      float y = static_cast<float>(q[1]) * f32(f + 4);
      y += f32(f + 16);
      float z = static_cast<float>(q[2]) * f32(f + 8);
      z += f32(f + 20);
      // assimp 5.2 (Debian 12) keeps the file's axes in the mesh and rotates the scene with its
      // root node, (x, y, z) -> (x, z, -y), as for MD3; it also reverses each face's corners.
      p.emplace_back(x, z, -y);
    }
    d.frames.push_back(std::move(p));
  }
  return d;
}

TEST(AnimMd2, EveryFrameMatchesTheFileAndMidpointsInterpolate) {
  const Md2Decoded d = decode_md2(slurp(kFaerie));
  ASSERT_EQ(d.frames.size(), 198u);
  auto a = load_md2(kFaerie);
  ASSERT_EQ(a->frame_count(), d.frames.size());
  ASSERT_EQ(a->rest().triangle_count(), d.tris.size());
  EXPECT_EQ(a->frames_per_second(), 10.0);
  EXPECT_FALSE(a->is_static());
  std::vector<std::vector<Vec3>> got;
  for (std::size_t k = 0; k < d.frames.size(); ++k) {
    got.push_back(positions_at(*a, static_cast<double>(k)));
    for (std::size_t t = 0; t < d.tris.size(); ++t)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(got[k][a->rest().triangle(t)[c]], d.frames[k][d.tris[t][2 - c]]) << "frame " << k << " tri " << t;
  }
  for (std::size_t k : {0u, 57u, 196u}) {
    const auto p = positions_at(*a, static_cast<double>(k) + 0.5);
    for (std::size_t v = 0; v < p.size(); ++v) {
      const Vec3 mid = 0.5 * (got[k][v] + got[k + 1][v]);
      ASSERT_LE((p[v] - mid).norm(), 1e-12 * (1.0 + mid.norm()));
    }
  }
  // Welding: corners of one MD2 vertex share a welded vertex; distinct welded vertices differ
  // in at least one frame (brute force over pairs).
  std::vector<std::int64_t> welded_of(d.frames[0].size(), -1);
  for (std::size_t t = 0; t < d.tris.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      auto& w = welded_of[d.tris[t][2 - c]];
      const auto mine = static_cast<std::int64_t>(a->rest().triangle(t)[c]);
      if (w < 0) w = mine;
      ASSERT_EQ(w, mine) << "MD2 vertex " << d.tris[t][2 - c] << " split by welding";
    }
  const std::size_t nv = a->rest().vertex_count();
  EXPECT_LE(nv, d.frames[0].size());
  for (std::size_t i = 0; i < nv; ++i)
    for (std::size_t j = i + 1; j < nv; ++j) {
      bool differ = false;
      for (std::size_t k = 0; k < got.size() && !differ; ++k) differ = got[k][i] != got[k][j];
      ASSERT_TRUE(differ) << "welded vertices " << i << " and " << j << " coincide in every frame";
    }
  // Unwelded: the raw soup, 3 vertices per triangle.
  Md2Options raw;
  raw.weld = false;
  auto s = load_md2(kFaerie, raw);
  EXPECT_EQ(s->rest().vertex_count(), 3 * d.tris.size());
}

TEST_F(AnimFiles, Md2MissingTruncatedAndCorrupt) {
  expect_input_error([&] { (void)load_md2(dir_ / "none.md2"); }, {"none.md2", "no such file"});
  const std::string b = slurp(kFaerie);
  spit(dir_ / "short.md2", b.substr(0, 40));
  expect_input_error([&] { (void)load_md2(dir_ / "short.md2"); }, {"short.md2", "header", "truncated"});
  spit(dir_ / "half.md2", b.substr(0, b.size() / 2));
  expect_input_error([&] { (void)load_md2(dir_ / "half.md2"); }, {"half.md2", "frames", "outside the file"});
  std::string bad = b;
  const std::uint32_t ofs_tris = [&] {
    std::uint32_t v;
    std::memcpy(&v, b.data() + 52, 4);
    return v;
  }();
  bad[ofs_tris + 12 * 3 + 2] = static_cast<char>(0xff);  // triangle 3, corner 1: index >= num_xyz
  bad[ofs_tris + 12 * 3 + 3] = static_cast<char>(0xff);
  spit(dir_ / "badidx.md2", bad);
  expect_input_error([&] { (void)load_md2(dir_ / "badidx.md2"); },
                     {"badidx.md2", "triangle 3 vertex 1", "65535", byte_loc(ofs_tris + 12 * 3 + 2)});
  std::string magic = b;
  magic[0] = 'X';
  spit(dir_ / "magic.md2", magic);
  expect_input_error([&] { (void)load_md2(dir_ / "magic.md2"); }, {"magic.md2", "IDP2"});
}

// ---------------------------------------------------------------------------------------------
// MD3

// Faerie's welded frames 0..4, split into two surfaces (first 300 triangles, the rest), written
// as MD3 in the file's own axes.
struct Md3Fixture {
  std::vector<Md3SurfaceData> surfaces;
  std::vector<std::vector<Vec3>> quantised;  // per frame, per concatenated vertex: round(64 p) / 64
};

Md3Fixture faerie_md3(std::size_t frames) {
  auto a = load_md2(kFaerie);
  Md3Fixture f;
  const auto tris = a->rest().triangles();
  const std::size_t split = 300;
  for (int s = 0; s < 2; ++s) {
    Md3SurfaceData sd;
    sd.name = s == 0 ? "upper" : "lower";
    std::vector<std::int64_t> local(a->rest().vertex_count(), -1);
    std::vector<std::uint32_t> global;
    for (std::size_t t = s == 0 ? 0 : split; t < (s == 0 ? split : tris.size()); ++t) {
      Tri lt;
      for (int c = 0; c < 3; ++c) {
        auto& l = local[tris[t][c]];
        if (l < 0) {
          l = static_cast<std::int64_t>(global.size());
          global.push_back(tris[t][c]);
        }
        lt[c] = static_cast<std::uint32_t>(l);
      }
      sd.triangles.push_back(lt);
    }
    for (std::size_t k = 0; k < frames; ++k) {
      const auto p = positions_at(*a, static_cast<double>(k));
      std::vector<Vec3> fp;
      for (auto g : global) fp.push_back(p[g]);
      sd.frames.push_back(fp);
    }
    f.surfaces.push_back(std::move(sd));
  }
  f.quantised.assign(frames, {});
  for (const auto& sd : f.surfaces)
    for (std::size_t k = 0; k < frames; ++k)
      for (const Vec3& p : sd.frames[k])
        f.quantised[k].push_back(Vec3(std::round(p.x() * 64), std::round(p.y() * 64), std::round(p.z() * 64)) / 64.0);
  return f;
}

TEST_F(AnimFiles, Md3ReadsEveryFrameOfEverySurface) {
  const Md3Fixture fx = faerie_md3(5);
  write_md3(dir_ / "faerie.md3", fx.surfaces);
  const Md3Model m = read_md3(dir_ / "faerie.md3");
  ASSERT_EQ(m.surfaces.size(), 2u);
  ASSERT_EQ(m.frames.size(), 5u);
  EXPECT_EQ(m.surfaces[1].first_vertex, fx.surfaces[0].frames[0].size());
  EXPECT_EQ(m.triangles.size(), fx.surfaces[0].triangles.size() + fx.surfaces[1].triangles.size());
  for (std::size_t k = 0; k < 5; ++k) {
    ASSERT_EQ(m.frames[k].size(), fx.quantised[k].size());
    for (std::size_t v = 0; v < m.frames[k].size(); ++v) ASSERT_EQ(m.frames[k][v], fx.quantised[k][v]);
  }
  // The source in file axes, no flip, no weld: stored frames at integer times, midpoints at k + 0.5.
  Md3Options plain;
  plain.y_up = plain.flip_winding = plain.weld = false;
  auto a = load_md3(dir_ / "faerie.md3", plain);
  EXPECT_EQ(a->frame_count(), 5u);
  EXPECT_TRUE(std::equal(m.triangles.begin(), m.triangles.end(), a->rest().triangles().begin()));
  for (std::size_t k = 0; k < 5; ++k) EXPECT_EQ(positions_at(*a, static_cast<double>(k)), fx.quantised[k]);
  const auto mid = positions_at(*a, 2.5);
  for (std::size_t v = 0; v < mid.size(); ++v)
    ASSERT_LE((mid[v] - 0.5 * (fx.quantised[2][v] + fx.quantised[3][v])).norm(), 1e-12);
  // Defaults: y up (x, z, -y), flipped winding; welding merges the vertices the two surfaces share.
  auto b = load_md3(dir_ / "faerie.md3");
  EXPECT_LT(b->rest().vertex_count(), a->rest().vertex_count());
  for (std::size_t k : {0u, 4u}) {
    const auto pa = positions_at(*a, static_cast<double>(k)), pb = positions_at(*b, static_cast<double>(k));
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const Tri& ta = a->rest().triangle(t);
      const Tri& tb = b->rest().triangle(t);
      for (int c = 0; c < 3; ++c) {
        const Vec3 p = pa[ta[c == 0 ? 0 : 3 - c]];
        ASSERT_EQ(pb[tb[c]], Vec3(p.x(), p.z(), -p.y())) << "frame " << k << " triangle " << t;
      }
    }
  }
}

TEST_F(AnimFiles, Md3FrameZeroMatchesAssimpVertexByVertex) {
  const Md3Fixture fx = faerie_md3(3);
  write_md3(dir_ / "x.md3", fx.surfaces);
  Md3Options o;
  o.weld = false;
  auto ours = load_md3(dir_ / "x.md3", o);
  const auto p0 = positions_at(*ours, 0);
  Assimp::Importer imp;
  const aiScene* s = imp.ReadFile((dir_ / "x.md3").string(), aiProcess_ValidateDataStructure);
  ASSERT_NE(s, nullptr) << imp.GetErrorString();
  ASSERT_EQ(s->mNumMeshes, 2u);
  const aiMatrix4x4 root = s->mRootNode->mTransformation;
  // assimp stores the surfaces in reverse order (its loader fills mMeshes from the back).
  std::size_t tri = 0, checked = 0;
  for (std::size_t surf = 0; surf < 2; ++surf) {
    const aiMesh* m = s->mMeshes[1 - surf];
    ASSERT_EQ(m->mNumFaces, fx.surfaces[surf].triangles.size());
    for (unsigned f = 0; f < m->mNumFaces; ++f, ++tri)
      for (unsigned c = 0; c < 3; ++c) {
        const aiVector3D v = root * m->mVertices[m->mFaces[f].mIndices[c]];
        ASSERT_EQ(p0[ours->rest().triangle(tri)[c]], Vec3(v.x, v.y, v.z)) << "surface " << surf << " face " << f;
        ++checked;
      }
  }
  EXPECT_EQ(checked, 3 * ours->rest().triangle_count());
}

TEST_F(AnimFiles, Md3TruncatedAtAnyByteIsAnInputError) {
  Md3SurfaceData sd;
  sd.name = "tri";
  sd.triangles = {{0, 1, 2}, {0, 2, 3}};
  sd.frames = {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)},
               {Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(1, 1, 1), Vec3(0, 1, 1)}};
  const std::string good = encode_md3({sd, sd}, "tiny");
  EXPECT_NO_THROW((void)parse_md3(good, "tiny.md3"));
  for (std::size_t n = 0; n < good.size(); ++n) {
    // Cutting the file anywhere must give an InputError naming the file, an offset and a field
    // (the last surface's shaders/st/xyz end the file, so every cut removes something needed).
    try {
      (void)parse_md3(std::string_view(good).substr(0, n), "tiny.md3");
      ADD_FAILURE() << "cut at " << n << " accepted";
    } catch (const InputError& e) {
      ASSERT_EQ(e.file(), "tiny.md3");
      ASSERT_EQ(e.location().rfind("byte ", 0), 0u) << e.what();
      ASSERT_FALSE(e.element().empty()) << e.what();
    }
  }
  const fs::path p = dir_ / "cut.md3";
  spit(p, good.substr(0, 200));
  expect_input_error([&] { (void)load_md3(p); }, {"cut.md3", "truncated"});
  expect_input_error([&] { (void)load_md3(dir_ / "missing.md3"); }, {"missing.md3"});
}

TEST(AnimMd3, CorruptFieldsAreNamed) {
  Md3SurfaceData sd;
  sd.name = "tri";
  sd.triangles = {{0, 1, 2}};
  sd.frames = {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0)}};
  const std::string good = encode_md3({sd}, "t");
  auto put = [](std::string s, std::size_t off, std::int32_t v) {
    std::memcpy(s.data() + off, &v, 4);
    return s;
  };
  const std::size_t surf = 108 + 56;  // header + one frame, no tags
  expect_input_error([&] { (void)parse_md3(put(good, 0, 0), "a.md3"); }, {"a.md3", "byte 0", "header ident"});
  expect_input_error([&] { (void)parse_md3(put(good, 4, 14), "a.md3"); }, {"header version", "version 14"});
  expect_input_error([&] { (void)parse_md3(put(good, 76, 0), "a.md3"); }, {"header num_frames", "no frames"});
  expect_input_error([&] { (void)parse_md3(put(good, 84, -3), "a.md3"); }, {"header num_surfaces", "negative"});
  expect_input_error([&] { (void)parse_md3(put(good, surf + 72, 2), "a.md3"); },
                     {"surface 0 num_frames", "2 frames, the header has 1"});
  expect_input_error([&] { (void)parse_md3(put(good, surf + 80, 1 << 30), "a.md3"); }, {"surface 0 st", "truncated"});
  const std::size_t tri0 = surf + 108;
  expect_input_error([&] { (void)parse_md3(put(good, tri0 + 4, 3), "a.md3"); },
                     {"a.md3", byte_loc(tri0 + 4), "surface 0 triangle 0 index 1", "vertex index 3 outside [0, 3)"});
  expect_input_error([&] { (void)parse_md3(put(good, tri0 + 8, -1), "a.md3"); }, {"triangle 0 index 2", "-1"});
  // Coordinates beyond int16 / 64 cannot be written.
  sd.frames[0][1] = Vec3(600, 0, 0);
  expect_input_error([&] { (void)encode_md3({sd}, "big"); }, {"big", "surface 0 frame 0 vertex 1", "int16"});
}

// ---------------------------------------------------------------------------------------------
// Front door

TEST_F(AnimFiles, LoadAnimationDispatchesByPath) {
  EXPECT_EQ(classify_animation_path(dir_.string()), AnimationFileKind::FrameSequence);
  EXPECT_EQ(classify_animation_path((dir_ / "f*.obj").string()), AnimationFileKind::FrameSequence);
  EXPECT_EQ(classify_animation_path("a.MD2"), AnimationFileKind::Md2);
  EXPECT_EQ(classify_animation_path("a.md3"), AnimationFileKind::Md3);
  EXPECT_EQ(classify_animation_path("a.ply"), AnimationFileKind::MeshFile);
  EXPECT_EQ(classify_animation_path("a.x"), AnimationFileKind::AssimpAsset);
  auto md2 = load_animation(kFaerie.string());
  EXPECT_EQ(md2->frame_count(), 198u);
  write_mesh(dir_ / "m.off", grid(2, 0));
  auto st = load_animation((dir_ / "m.off").string());
  EXPECT_TRUE(st->is_static());
  const Mesh g0 = grid(2, 0);
  EXPECT_EQ(positions_at(*st, 17.25), std::vector<Vec3>(g0.positions().begin(), g0.positions().end()));
  write_mesh(dir_ / "g1.obj", grid(2, 1));
  write_mesh(dir_ / "g2.obj", grid(2, 2));
  auto seq = load_animation((dir_ / "g*.obj").string());
  EXPECT_EQ(seq->frame_count(), 2u);
  expect_input_error([&] { (void)load_animation((dir_ / "nothing.x").string()); }, {"nothing.x", "no such file"});
  expect_input_error([&] { (void)load_animation((dir_ / "nothing.md3").string()); }, {"nothing.md3"});
  spit(dir_ / "garbage.fbx", "this is not an fbx file at all");
  expect_input_error([&] { (void)load_animation((dir_ / "garbage.fbx").string()); }, {"garbage.fbx", "assimp"});
}

}  // namespace
}  // namespace ptc
