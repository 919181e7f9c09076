// read_mesh on real files: every sample mesh shipped with CGAL, paths that do not work, and a
// seeded fuzz of small valid files in every format.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <random>
#include <string>

#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

namespace fs = std::filesystem;

const fs::path kMeshes = fs::path(PTC_TEST_DATA) / "meshes";

// Invariants of any successful load.
void expect_consistent(const LoadedMesh& lm, const std::string& what) {
  const Mesh& m = lm.mesh;
  ASSERT_GT(m.triangle_count(), 0u) << what;
  if (lm.report.source_face.empty()) {  // triangle t is face t: only triangles, none skipped
    ASSERT_EQ(lm.report.faces, m.triangle_count()) << what;
    ASSERT_EQ(lm.report.polygons + lm.report.short_faces, 0u) << what;
  } else {
    ASSERT_EQ(lm.report.source_face.size(), m.triangle_count()) << what;
    ASSERT_GT(lm.report.polygons + lm.report.short_faces, 0u) << what;
  }
  for (std::size_t t = 0; t < m.triangle_count(); ++t) {
    for (std::uint32_t v : m.triangle(t)) ASSERT_LT(v, m.vertex_count()) << what;
    ASSERT_LT(lm.report.source_face_of(t), lm.report.faces) << what;
    if (t > 0) {
      ASSERT_LE(lm.report.source_face_of(t - 1), lm.report.source_face_of(t)) << what;
    }
  }
  for (const Vec3& p : m.positions()) ASSERT_TRUE(p.allFinite()) << what;
  EXPECT_EQ(m.triangle_count(),
            lm.report.faces - lm.report.short_faces - lm.report.polygons + lm.report.triangles_from_polygons)
      << what;
}

TEST(IoFiles, EverySampleMeshLoadsOrThrowsInputError) {
  ASSERT_TRUE(fs::is_directory(kMeshes)) << kMeshes;
  std::size_t loaded = 0, rejected = 0;
  for (const auto& entry : fs::directory_iterator(kMeshes)) {
    const fs::path& p = entry.path();
    try {
      const LoadedMesh lm = read_mesh(p);
      expect_consistent(lm, p.string());
      ++loaded;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), p.string());
      std::cout << "  rejected: " << e.what() << '\n';
      ++rejected;
    }  // anything else escapes and fails the test
  }
  std::cout << "  " << loaded << " loaded, " << rejected << " rejected\n";
  EXPECT_GT(loaded, 100u);
}

TEST(IoFiles, KnownSampleMeshes) {
  // Comments before the COFF keyword, colours, a pentagon (CGAL's mesh_with_colors.off).
  const auto colors = read_mesh(kMeshes / "mesh_with_colors.off");
  EXPECT_EQ(colors.mesh.vertex_count(), 8u);
  EXPECT_EQ(colors.report.faces, 4u);
  EXPECT_EQ(colors.report.polygons, 1u);
  EXPECT_EQ(colors.mesh.triangle_count(), 3u + 3u);
  EXPECT_EQ(colors.mesh.position(0), Vec3(-1, -1, 0));
  EXPECT_EQ(colors.mesh.triangle(3), (Tri{1, 3, 4}));
  // "# Output of a CGAL tool" lines before the header.
  EXPECT_GT(read_mesh(kMeshes / "cube-shuffled.off").mesh.triangle_count(), 0u);
  // Binary STL whose header starts with blanks, and one whose header says "FileType: Binary".
  for (const char* f : {"pig.stl", "sphere.stl"}) {
    const auto lm = read_mesh(kMeshes / f);
    EXPECT_TRUE(lm.report.binary) << f;
    EXPECT_EQ(lm.report.welded_vertices, 3 * lm.mesh.triangle_count() - lm.mesh.vertex_count()) << f;
    EXPECT_GT(lm.report.welded_vertices, 0u) << f;
  }
  // b9.ply declares "element face 0": a point cloud.
  try {
    (void)read_mesh(kMeshes / "b9.ply");
    ADD_FAILURE() << "b9.ply has no faces";
  } catch (const InputError& e) {
    EXPECT_EQ(e.reason(), "mesh has no triangles");
  }
}

TEST(IoFiles, PathsThatDoNotWork) {
  const auto error_of = [](const fs::path& p) {
    try {
      (void)read_mesh(p);
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), p.string());
      return e.reason();
    }
    ADD_FAILURE() << "no InputError for " << p;
    return std::string();
  };
  EXPECT_EQ(error_of("/nonexistent/dir/mesh.off"), "cannot open: No such file or directory");
  EXPECT_EQ(error_of(kMeshes / "armadillo.xyz"), "unknown mesh format '.xyz' (use .off, .obj, .ply or .stl)");
  EXPECT_EQ(error_of("noextension"), "unknown mesh format (no extension) (use .off, .obj, .ply or .stl)");
  // An animated asset: the hint says which commands read it (before the file is opened).
  EXPECT_EQ(error_of("/nonexistent/faerie.MD2"),
            "unknown mesh format '.MD2' (use .off, .obj, .ply or .stl; ptc trace, bench and animate read animated "
            "assets, and `ptc animate FILE --out DIR` writes their frames as .ply meshes)");
  const fs::path dir = fs::temp_directory_path() / ("ptc_io_files_" + std::to_string(::getpid()) + ".off");
  fs::create_directories(dir);
  const std::string is_dir =
      "is a directory, not a mesh file (a directory of frames is read by ptc trace, bench, viz, experiment and "
      "animate; give one frame's file here)";
  EXPECT_EQ(error_of(dir), is_dir);
  fs::remove_all(dir);
  // A directory without an extension (a frame sequence given to a command that reads one mesh)
  // is named as such, not as an unknown format.
  const fs::path frames = fs::temp_directory_path() / ("ptc_io_frames_" + std::to_string(::getpid()));
  fs::create_directories(frames);
  EXPECT_EQ(error_of(frames), is_dir);
  fs::remove_all(frames);
  EXPECT_EQ(format_from_extension("a/b.Off"), MeshFormat::Off);
  EXPECT_EQ(format_from_extension("B.OBJ"), MeshFormat::Obj);
  EXPECT_EQ(format_from_extension("c.pLy"), MeshFormat::Ply);
  EXPECT_EQ(format_from_extension("d.STL"), MeshFormat::Stl);
  EXPECT_EQ(format_from_extension("e.off.gz"), std::nullopt);
  EXPECT_EQ(format_from_extension("off"), std::nullopt);
}

// ---- fuzz ----------------------------------------------------------------------------------------

std::string le_bytes(std::initializer_list<float> xs) {
  std::string s;
  for (float x : xs) s.append(reinterpret_cast<const char*>(&x), 4);
  return s;
}

struct Seed {
  const char* name;
  MeshFormat format;
  std::string bytes;
};

std::vector<Seed> seeds() {
  std::vector<Seed> s;
  s.push_back({"off", MeshFormat::Off,
               "# c\nCOFF 5 3 0\n0 0 0 1 1 1\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1e-3\n"
               "3 0 1 2\n4 0 1 2 3 # quad\n5 0 1 4 2 3 0.5 0.5 0.5\n"});
  s.push_back({"obj", MeshFormat::Obj,
               "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\nf -4//1 -2//1 -1//1\n"
               "f 1 2 3 4\ng x\n"});
  s.push_back({"ply ascii", MeshFormat::Ply,
               "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
               "property uchar red\nelement face 2\nproperty list uchar int vertex_indices\n"
               "element edge 1\nproperty list uchar int v\nend_header\n"
               "0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n3 0 1 2\n4 0 1 2 3\n2 0 1\n"});
  {
    std::string ply =
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nelement face 2\nproperty list uchar int vertex_indices\nproperty uchar q\n"
        "element edge 1\nproperty list ushort short v\nend_header\n";
    ply += le_bytes({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
    const std::int32_t f0[] = {0, 1, 2}, f1[] = {0, 2, 3, 1};
    ply += '\3';
    ply.append(reinterpret_cast<const char*>(f0), sizeof f0);
    ply += '\7';
    ply += '\4';
    ply.append(reinterpret_cast<const char*>(f1), sizeof f1);
    ply += '\7';
    ply += std::string("\2\0\1\0\2\0", 6);
    s.push_back({"ply binary", MeshFormat::Ply, ply});
  }
  s.push_back({"stl ascii", MeshFormat::Stl,
               "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\n"
               "facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\n"
               "endsolid t\n"});
  {
    std::string stl(80, ' ');
    stl.replace(0, 5, "solid");
    const std::uint32_t n = 2;
    stl.append(reinterpret_cast<const char*>(&n), 4);
    for (int f = 0; f < 2; ++f) {
      stl += le_bytes({0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 1, 0});
      stl += std::string(2, '\0');
    }
    s.push_back({"stl binary", MeshFormat::Stl, stl});
  }
  return s;
}

std::string mutate(std::string s, std::mt19937& rng) {
  static const std::string interesting = "0123456789-+.eE \t\n#/naif\xff\x80";
  const auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  const int ops = 1 + static_cast<int>(pick(4));
  for (int i = 0; i < ops; ++i) {
    if (s.empty()) s = "x";
    switch (pick(7)) {
      case 0: s[pick(s.size())] = static_cast<char>(pick(256)); break;                       // random byte
      case 1: s[pick(s.size())] = interesting[pick(interesting.size())]; break;              // plausible byte
      case 2: s.insert(pick(s.size() + 1), 1, interesting[pick(interesting.size())]); break;  // insertion
      case 3: s.erase(pick(s.size()), 1 + pick(4)); break;                                   // deletion
      case 4: s.resize(pick(s.size() + 1)); break;                                           // truncation
      case 5: {                                                                              // duplication
        const std::size_t at = pick(s.size()), len = 1 + pick(16);
        s.insert(pick(s.size() + 1), s.substr(at, len));
        break;
      }
      default: s[pick(s.size())] ^= static_cast<char>(1 << pick(8));  // bit flip
    }
  }
  return s;
}

TEST(IoFiles, FuzzedFilesLoadOrThrowInputError) {
  for (const Seed& seed : seeds()) {
    SCOPED_TRACE(seed.name);
    expect_consistent(read_mesh_from_memory(seed.bytes, seed.format, "seed"), "seed");  // seeds are valid
    std::mt19937 rng(20240611);
    std::size_t loaded = 0, rejected = 0;
    for (int i = 0; i < 400; ++i) {
      const std::string bytes = mutate(seed.bytes, rng);
      try {
        const LoadedMesh lm = read_mesh_from_memory(bytes, seed.format, "fuzz");
        expect_consistent(lm, "mutation " + std::to_string(i));
        ++loaded;
      } catch (const InputError& e) {
        EXPECT_EQ(e.file(), "fuzz");
        EXPECT_FALSE(e.reason().empty());
        ++rejected;
      } catch (const std::exception& e) {
        ADD_FAILURE() << "mutation " << i << " threw " << typeid(e).name() << ": " << e.what();
      }
    }
    // Both outcomes happen, or the mutations are not exercising the parser.
    EXPECT_GT(loaded, 0u);
    EXPECT_GT(rejected, 0u);
  }
}

}  // namespace
}  // namespace ptc
