// STL reader: ascii and binary (also with a header that starts with "solid"), welding of
// bit-identical corners, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "toolkit/core/error.h"
#include "io_helpers.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

LoadedMesh stl(std::string_view bytes) { return io_test::read(bytes, MeshFormat::Stl); }
InputError stl_error(std::string_view bytes) { return io_test::read_error(bytes, MeshFormat::Stl); }

using Facet = std::array<std::array<float, 3>, 3>;

std::string binary_stl(const std::vector<Facet>& facets, std::string header = "binary stl") {
  header.resize(80, ' ');
  std::string s = header;
  const auto put = [&](auto v) { s.append(reinterpret_cast<const char*>(&v), sizeof v); };  // little endian host
  put(static_cast<std::uint32_t>(facets.size()));
  for (const Facet& f : facets) {
    put(0.f), put(0.f), put(1.f);
    for (const auto& c : f)
      for (float x : c) put(x);
    put(std::uint16_t{0});
  }
  return s;
}

// A unit square as two facets sharing the diagonal (0,0,0)-(1,1,0), then a lone facet touching
// the square at (1,1,0) with a -0.0 coordinate that welds to +0.0.
const std::vector<Facet> kFacets = {
    Facet{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}}},
    Facet{{{0, 0, 0}, {1, 1, 0}, {0, 1, 0}}},
    Facet{{{1, 1, -0.f}, {2, 1, 0}, {2, 2, 0.5f}}},
};

void expect_square_and_facet(const LoadedMesh& lm) {
  const Mesh& m = lm.mesh;
  // 9 corners, 6 distinct positions: vertices numbered by first occurrence.
  ASSERT_EQ(m.vertex_count(), 6u);
  EXPECT_EQ(m.position(0), Vec3(0, 0, 0));
  EXPECT_EQ(m.position(1), Vec3(1, 0, 0));
  EXPECT_EQ(m.position(2), Vec3(1, 1, 0));
  EXPECT_EQ(m.position(3), Vec3(0, 1, 0));
  EXPECT_EQ(m.position(4), Vec3(2, 1, 0));
  EXPECT_EQ(m.position(5), Vec3(2, 2, 0.5));
  ASSERT_EQ(m.triangle_count(), 3u);
  EXPECT_EQ(m.triangle(0), (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangle(1), (Tri{0, 2, 3}));
  EXPECT_EQ(m.triangle(2), (Tri{2, 4, 5}));
  EXPECT_EQ(lm.report.format, MeshFormat::Stl);
  EXPECT_EQ(lm.report.faces, 3u);
  EXPECT_EQ(lm.report.welded_vertices, 3u);
  EXPECT_EQ(lm.report.polygons, 0u);
  EXPECT_TRUE(lm.report.source_face.empty());  // triangle t is face t
  for (std::size_t t = 0; t < 3; ++t) EXPECT_EQ(lm.report.source_face_of(t), t);
}

const char* kAscii =
    "solid square\n"
    "  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 1 0\n"
    "    endloop\n  endfacet\n"
    "  facet normal 0 0 1\n    outer loop\n      vertex 0.0 0e0 0\n      vertex 1 1.000 0\n      vertex 0 1 0\n"
    "    endloop\n  endfacet\n"
    "endsolid square\n"
    "SOLID second\r\n"
    "  FACET NORMAL 0 0 -1.5e-1\r\n    OUTER LOOP\r\n      VERTEX 1 1 -0\r\n      VERTEX 2 1 0\r\n"
    "      VERTEX 2 2 0.5\r\n    ENDLOOP\r\n  ENDFACET\r\n"
    "ENDSOLID second\r\n";

TEST(IoStl, AsciiWeldsBitIdenticalCornersAcrossSolids) {
  const auto lm = stl(kAscii);
  expect_square_and_facet(lm);
  EXPECT_FALSE(lm.report.binary);
}

// An ascii file that starts with "SOLID" (keywords are case-insensitive) or with a UTF-8 byte-order
// mark is ascii too (both were read as binary and refused by its header's facet count).
TEST(IoStl, AsciiStartingWithUpperCaseSolidOrAByteOrderMark) {
  std::string upper = kAscii;
  upper.replace(0, 5, "SOLID");
  for (const std::string& text : {upper, "\xEF\xBB\xBF" + std::string(kAscii), "\xEF\xBB\xBF" + upper}) {
    const auto lm = stl(text);
    expect_square_and_facet(lm);
    EXPECT_FALSE(lm.report.binary);
  }
}

TEST(IoStl, Binary) {
  const auto lm = stl(binary_stl(kFacets));
  expect_square_and_facet(lm);
  EXPECT_TRUE(lm.report.binary);
}

TEST(IoStl, BinaryWhoseHeaderStartsWithSolid) {
  const auto lm = stl(binary_stl(kFacets, "solid exported by a tool that should not have"));
  expect_square_and_facet(lm);
  EXPECT_TRUE(lm.report.binary);
  // ... and whose size does not match its count: padded, with a newline in the header, or with
  // fewer facets counted than it holds. Its NUL bytes say binary (it was parsed as ascii and
  // refused: "file ends before 'endsolid'", or raw binary bytes quoted as a keyword).
  for (const std::string& header : {std::string("solid exported"), std::string("solid x\n")}) {
    const auto padded = stl(binary_stl(kFacets, header) + std::string(1, '\0'));
    expect_square_and_facet(padded);
    EXPECT_TRUE(padded.report.binary);
    std::string fewer = binary_stl(kFacets, header);
    const std::uint32_t two = 2;
    std::memcpy(fewer.data() + 80, &two, 4);
    const auto f = stl(fewer);
    EXPECT_TRUE(f.report.binary);
    EXPECT_EQ(f.mesh.triangle_count(), 2u);
    EXPECT_EQ(f.report.trailing_bytes, 50u);
  }
  // An ascii file with a garbled line still gets the ascii error (no NUL: not taken for binary).
  const InputError e = stl_error("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 q\n");
  EXPECT_NE(std::string(e.what()).find("line 6"), std::string::npos) << e.what();
}

TEST(IoStl, DegenerateFacetsAreKept) {
  const auto lm = stl(binary_stl({Facet{{{1, 2, 3}, {1, 2, 3}, {1, 2, 3}}}, Facet{{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}}}));
  ASSERT_EQ(lm.mesh.triangle_count(), 2u);
  EXPECT_EQ(lm.mesh.triangle(0), (Tri{0, 0, 0}));
  EXPECT_EQ(lm.mesh.triangle(1), (Tri{1, 2, 3}));
  EXPECT_EQ(lm.report.welded_vertices, 2u);
}

TEST(IoStl, NanAndInfFacets) {
  std::vector<Facet> f = kFacets;
  f[1][2][1] = std::nanf("");
  auto e = stl_error(binary_stl(f));
  EXPECT_EQ(e.element(), "facet 1");
  EXPECT_EQ(e.location(), "byte " + std::to_string(84 + 50 + 12 + 24 + 4));
  EXPECT_EQ(e.reason(), "vertex 2 coordinate 1 is NaN");
  f = kFacets;
  f[2][0][0] = INFINITY;
  e = stl_error(binary_stl(f));
  EXPECT_EQ(e.element(), "facet 2");
  EXPECT_EQ(e.reason(), "vertex 0 coordinate 0 is infinite");
  std::string a = kAscii;
  a.replace(a.find("vertex 1 0 0"), 12, "vertex 1 0 nan");
  e = stl_error(a);
  EXPECT_EQ(e.location(), "line 5");
  EXPECT_EQ(e.element(), "facet 0");
  EXPECT_EQ(e.reason(), "vertex 1 coordinate 2 is NaN");
}

TEST(IoStl, GarbledAscii) {
  std::string a = kAscii;
  a.replace(a.find("vertex 0 1 0"), 12, "vertex 0 1x 0");
  auto e = stl_error(a);
  EXPECT_EQ(e.location(), "line 13");
  EXPECT_EQ(e.element(), "facet 1");
  EXPECT_EQ(e.reason(), "vertex 2 coordinate 1 '1x' is not a number");
  a = kAscii;
  a.replace(a.find("outer loop"), 10, "outer lop");
  e = stl_error(a);
  EXPECT_EQ(e.location(), "line 3");
  EXPECT_EQ(e.reason(), "expected 'loop', found 'lop'");
  a = kAscii;
  a.replace(a.find("endloop"), 7, "vertex 5 5 5\nendloop");
  e = stl_error(a);
  EXPECT_EQ(e.reason(), "expected 'endloop', found 'vertex'");  // 4 corners
  e = stl_error("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n");
  EXPECT_EQ(e.location(), "line 6");
  EXPECT_EQ(e.reason(), "expected 'vertex', found 'endloop'");  // 2 corners
  e = stl_error("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\nendsolid\ngarbage\n");
  EXPECT_EQ(e.reason(), "expected 'solid', found 'garbage'");
}

TEST(IoStl, TruncatedAscii) {
  const std::string full = kAscii;
  auto e = stl_error(full.substr(0, full.find("endsolid square")));
  EXPECT_EQ(e.element(), "facet 2");
  EXPECT_EQ(e.reason(), "file ends before 'endsolid' (after 2 facets)");
  e = stl_error(full.substr(0, full.find("1.000") + 3));  // mid-number: "1.0" then the end
  EXPECT_EQ(e.element(), "facet 1");
  EXPECT_EQ(e.reason(), "file ends where vertex 1 coordinate 2 was expected");
  for (std::size_t cut = 0; cut < full.find("endsolid square") + 3; ++cut) {
    try {
      (void)stl(full.substr(0, cut));
      ADD_FAILURE() << "loaded a file cut at byte " << cut;
    } catch (const InputError& err) {
      EXPECT_EQ(err.file(), "t.stl");
    }
  }
}

TEST(IoStl, TruncatedBinaryAndBadCounts) {
  const std::string full = binary_stl(kFacets);
  auto e = stl_error(full.substr(0, 84 + 50 + 17));  // mid facet 1
  EXPECT_EQ(e.location(), "byte 80");
  EXPECT_EQ(e.element(), "header");
  EXPECT_EQ(e.reason(), "header claims 3 facets (150 bytes) but the file has only 67 bytes left");
  e = stl_error(full.substr(0, 50));
  EXPECT_EQ(e.reason(), "file has 50 bytes; a binary STL needs at least 84");
  std::string lie = full;
  const std::uint32_t n = 0xFFFFFFFFu;
  std::memcpy(lie.data() + 80, &n, 4);
  e = stl_error(lie);
  EXPECT_NE(e.reason().find("header claims 4294967295 facets"), std::string::npos) << e.what();
  for (std::size_t cut = 0; cut < full.size(); ++cut) {
    try {
      (void)stl(full.substr(0, cut));
      ADD_FAILURE() << "loaded a file cut at byte " << cut;
    } catch (const InputError& err) {
      EXPECT_EQ(err.file(), "t.stl");
    }
  }
  e = stl_error(binary_stl({}));
  EXPECT_EQ(e.reason(), "mesh has no triangles");
  // A header counting fewer facets than the file holds: the count is taken, and the bytes after
  // it are reported (a note once there is room for a facet; padding of less is not).
  std::string fewer = full;
  const std::uint32_t two = 2;
  std::memcpy(fewer.data() + 80, &two, 4);
  const LoadedMesh lf = stl(fewer);
  EXPECT_EQ(lf.mesh.triangle_count(), 2u);
  EXPECT_EQ(lf.report.trailing_bytes, 50u);
  const std::vector<std::string> notes = read_notes(lf.report);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0], "50 bytes after the 2 facets the header counts were ignored (room for 1 more; a header with too "
                      "small a count drops them)");
  const LoadedMesh padded = stl(full + std::string(49, '\0'));
  EXPECT_EQ(padded.report.trailing_bytes, 49u);
  EXPECT_TRUE(read_notes(padded.report).empty());
  EXPECT_EQ(stl(full).report.trailing_bytes, 0u);
  e = stl_error("");
  EXPECT_NE(e.reason().find("84"), std::string::npos) << e.what();
  e = stl_error("solid empty\nendsolid empty\n");
  EXPECT_EQ(e.reason(), "mesh has no triangles");
}

}  // namespace
}  // namespace ptc
