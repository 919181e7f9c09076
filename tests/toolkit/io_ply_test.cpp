// PLY reader against files built byte by byte: all three encodings, skipped properties and
// elements (lists included), every scalar type name, and each kind of bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <unistd.h>

#include <functional>
#include <random>

#include "common/temp_dir.h"
#include "toolkit/core/error.h"
#include "io_helpers.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/io/readers.h"

namespace ptc {
namespace {

LoadedMesh ply(std::string_view bytes) { return io_test::read(bytes, MeshFormat::Ply); }
InputError ply_error(std::string_view bytes) { return io_test::read_error(bytes, MeshFormat::Ply); }

// Binary data in either byte order.
struct Bytes {
  bool big = false;
  std::string s;
  template <class T>
  Bytes& put(T v) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (big)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    s.append(b, sizeof(T));
    return *this;
  }
};

// Four vertices with mixed coordinate types, a vertex list property, an edge element with a list
// before the faces, a triangle and a quad with extra face properties, and a material element last.
const char* kHeaderBody =
    "comment made by hand\n"
    "obj_info nothing to see\n"
    "element vertex 4\n"
    "property float x\n"
    "property uchar red\n"
    "property double y\n"
    "property int16 z\n"
    "property list uchar float texcoord\n"
    "element edge 2\n"
    "property int vertex1\n"
    "property list ushort int path\n"
    "property char flag\n"
    "element face 2\n"
    "property uchar flags\n"
    "property list uint8 uint32 vertex_indices\n"
    "property float quality\n"
    "element material 1\n"
    "property uchar r\n"
    "property float64 shininess\n"
    "end_header\n";

std::string binary_file(bool big) {
  std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") + " 1.0\n" +
                  kHeaderBody;
  Bytes b{big, {}};
  // vertices: x (float), red, y (double), z (int16), texcoord list
  b.put(0.5f).put<std::uint8_t>(200).put(-1.25).put<std::int16_t>(3).put<std::uint8_t>(2).put(0.25f).put(0.75f);
  b.put(0.1f).put<std::uint8_t>(0).put(1e-300).put<std::int16_t>(-2).put<std::uint8_t>(0);
  b.put(-7.0f).put<std::uint8_t>(1).put(2.0).put<std::int16_t>(32767).put<std::uint8_t>(1).put(9.f);
  b.put(1e30f).put<std::uint8_t>(2).put(-0.0).put<std::int16_t>(-32768).put<std::uint8_t>(0);
  // edges: vertex1, path (ushort count, ints), flag
  b.put<std::int32_t>(0).put<std::uint16_t>(3).put<std::int32_t>(0).put<std::int32_t>(1).put<std::int32_t>(2).put<std::int8_t>(-1);
  b.put<std::int32_t>(1).put<std::uint16_t>(0).put<std::int8_t>(5);
  // faces: flags, vertex_indices, quality
  b.put<std::uint8_t>(1).put<std::uint8_t>(3).put<std::uint32_t>(0).put<std::uint32_t>(1).put<std::uint32_t>(2).put(0.5f);
  b.put<std::uint8_t>(2).put<std::uint8_t>(4).put<std::uint32_t>(3).put<std::uint32_t>(2).put<std::uint32_t>(1).put<std::uint32_t>(0).put(1.5f);
  // material
  b.put<std::uint8_t>(9).put(0.125);
  return s + b.s;
}

const char* kAsciiFile =
    "ply\nformat ascii 1.0\n"
    "comment made by hand\n"
    "element vertex 4\n"
    "property float x\nproperty uchar red\nproperty double y\nproperty int16 z\n"
    "property list uchar float texcoord\n"
    "element edge 2\nproperty int vertex1\nproperty list ushort int path\nproperty char flag\n"
    "element face 2\nproperty uchar flags\nproperty list uint8 uint32 vertex_indices\nproperty float quality\n"
    "element material 1\nproperty uchar r\nproperty float64 shininess\n"
    "end_header\n"
    "0.5 200 -1.25 3 2 0.25 0.75\n"
    "0.1 0 1e-300 -2 0\n"
    "-7 1 2 32767 1 9\n"
    "1e30 2 -0 -32768 0\n"
    "0 3 0 1 2 -1\n"
    "1 0 5\n"
    "1 3 0 1 2 0.5\n"
    "2 4 3 2 1 0 1.5\n"
    "9 0.125\n";

void expect_reference_mesh(const LoadedMesh& lm, bool float_x) {
  const Mesh& m = lm.mesh;
  ASSERT_EQ(m.vertex_count(), 4u);
  // Binary x is a float (0.1f widened); ascii x is the decimal text read as double.
  EXPECT_EQ(m.position(0), Vec3(0.5, -1.25, 3));
  EXPECT_EQ(m.position(1), Vec3(float_x ? static_cast<double>(0.1f) : 0.1, 1e-300, -2));
  EXPECT_EQ(m.position(2), Vec3(-7, 2, 32767));
  EXPECT_EQ(m.position(3), Vec3(float_x ? static_cast<double>(1e30f) : 1e30, 0, -32768));
  EXPECT_TRUE(std::signbit(m.position(3).y()));
  ASSERT_EQ(m.triangle_count(), 3u);
  EXPECT_EQ(m.triangle(0), (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangle(1), (Tri{3, 2, 1}));
  EXPECT_EQ(m.triangle(2), (Tri{3, 1, 0}));
  EXPECT_EQ(lm.report.format, MeshFormat::Ply);
  EXPECT_EQ(lm.report.faces, 2u);
  EXPECT_EQ(lm.report.polygons, 1u);
  EXPECT_EQ(lm.report.triangles_from_polygons, 2u);
  EXPECT_EQ(lm.report.source_face, (std::vector<std::uint32_t>{0, 1, 1}));
}

TEST(IoPly, BinaryLittleEndian) {
  const auto lm = ply(binary_file(false));
  expect_reference_mesh(lm, true);
  EXPECT_TRUE(lm.report.binary);
}

TEST(IoPly, BinaryBigEndian) {
  const auto lm = ply(binary_file(true));
  expect_reference_mesh(lm, true);
  EXPECT_TRUE(lm.report.binary);
}

TEST(IoPly, Ascii) {
  const auto lm = ply(kAsciiFile);
  expect_reference_mesh(lm, false);
  EXPECT_FALSE(lm.report.binary);
}

TEST(IoPly, CrLfHeaderFaceBeforeVertexAndVertexIndexName) {
  std::string s =
      "ply\r\nformat binary_little_endian 1.0\r\n"
      "element face 1\r\nproperty list int short vertex_index\r\n"
      "element vertex 3\r\nproperty int x\r\nproperty uint y\r\nproperty char z\r\nend_header\r\n";
  Bytes b;
  b.put<std::int32_t>(3).put<std::int16_t>(2).put<std::int16_t>(0).put<std::int16_t>(1);
  b.put<std::int32_t>(-5).put<std::uint32_t>(4000000000u).put<std::int8_t>(-128);
  b.put<std::int32_t>(1).put<std::uint32_t>(0).put<std::int8_t>(127);
  b.put<std::int32_t>(2).put<std::uint32_t>(1).put<std::int8_t>(0);
  const auto lm = ply(s + b.s);
  ASSERT_EQ(lm.mesh.vertex_count(), 3u);
  EXPECT_EQ(lm.mesh.position(0), Vec3(-5, 4000000000.0, -128));
  EXPECT_EQ(lm.mesh.position(1), Vec3(1, 0, 127));
  EXPECT_EQ(lm.mesh.position(2), Vec3(2, 1, 0));
  ASSERT_EQ(lm.mesh.triangle_count(), 1u);
  EXPECT_EQ(lm.mesh.triangle(0), (Tri{2, 0, 1}));
}

// ---- errors --------------------------------------------------------------------------------------

std::string ascii_tri(std::string_view vertex_lines, std::string_view face_lines, int nv = 3, int nf = 1) {
  return "ply\nformat ascii 1.0\nelement vertex " + std::to_string(nv) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(nf) +
         "\nproperty list uchar int vertex_indices\nend_header\n" + std::string(vertex_lines) +
         std::string(face_lines);
}

TEST(IoPly, BadHeaderLinesNameTheLine) {
  struct Case {
    std::string text, location, reason_part;
  };
  const Case cases[] = {
      {"", "line 1", "file is empty"},
      {"plx\nformat ascii 1.0\nend_header\n", "line 1", "missing 'ply'"},
      {"ply\nformat binary_middle_endian 1.0\nend_header\n", "line 2", "unknown format 'binary_middle_endian'"},
      {"ply\nformat ascii 2.0\nend_header\n", "line 2", "unsupported format version '2.0'"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty floaty x\nend_header\n", "line 4",
       "unknown property type 'floaty'"},
      {"ply\nformat ascii 1.0\nelemnt vertex 3\nend_header\n", "line 3", "unknown header keyword 'elemnt'"},
      {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "line 3", "property before any element"},
      {"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", "line 3", "not a non-negative integer"},
      {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", "line 4", "no end_header"},
      {"ply\nelement vertex 0\nend_header\n", "line 3", "no format line"},
      {"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n", "line 5",
       "no vertex element"},
      {"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n", "line 3",
       "vertex element has no z property"},
      {"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 0\nproperty list uchar float vertex_indices\nend_header\n",
       "line 8", "must have an integer type"},
      {"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 0\nproperty int vertex_indices\nend_header\n",
       "line 8", "must be a list"},
      {"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
       "element face 0\nproperty uchar red\nend_header\n",
       "line 7", "face element has no vertex_indices list"},
      {"ply\nformat ascii 1.0\nelement vertex 0\nproperty list float float x\nend_header\n", "line 4",
       "list count type must be an integer type"},
  };
  for (const Case& c : cases) {
    const InputError e = ply_error(c.text);
    EXPECT_EQ(e.location(), c.location) << e.what();
    EXPECT_EQ(e.element(), "header") << e.what();
    EXPECT_NE(e.reason().find(c.reason_part), std::string::npos) << e.what();
  }
}

TEST(IoPly, HeaderClaiming2To40VerticesThrowsBeforeAllocating) {
  for (const char* fmt : {"ascii", "binary_little_endian"}) {
    const std::string s = std::string("ply\nformat ") + fmt +
                          " 1.0\nelement vertex 1099511627776\nproperty float x\nproperty float y\nproperty float z\n"
                          "end_header\n0 0 0\n";
    const InputError e = ply_error(s);
    EXPECT_EQ(e.location(), "line 3") << e.what();
    EXPECT_EQ(e.element(), "header");
    EXPECT_NE(e.reason().find("exceeds the 32-bit limit"), std::string::npos) << e.what();
  }
  // Within 32 bits, but more than the bytes after the header can hold (12 bytes per vertex).
  const std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\n"
      "property float z\nend_header\n0123456789ab";
  const InputError e = ply_error(s);
  EXPECT_EQ(e.location(), "line 3");
  EXPECT_NE(e.reason().find("header claims 1000000000 vertices"), std::string::npos) << e.what();
  EXPECT_NE(e.reason().find("only 12 bytes"), std::string::npos) << e.what();
  // A skipped element claiming too much is caught the same way.
  const InputError f = ply_error(binary_file(false).replace(binary_file(false).find("edge 2"), 6, "edge 4000000000"));
  EXPECT_EQ(f.location(), "line 11");
  EXPECT_NE(f.reason().find("'edge' elements"), std::string::npos) << f.what();
}

TEST(IoPly, TruncatedBinaryAtEveryByte) {
  for (bool big : {false, true}) {
    const std::string full = binary_file(big);
    const std::size_t data = full.find("end_header\n") + 11;
    for (std::size_t cut = 0; cut < full.size(); ++cut) {
      try {
        (void)ply(full.substr(0, cut));
        ADD_FAILURE() << "loaded a file cut at byte " << cut;
      } catch (const InputError& e) {
        EXPECT_EQ(e.file(), "t.ply");
        if (cut >= data) {
          // Either the up-front check (the header claims more than the bytes left can hold) or the
          // element being read when the data ran out, at its byte offset.
          const bool claim = e.element() == "header" && e.reason().find("header claims") != std::string::npos;
          const bool at_byte = e.location().rfind("byte ", 0) == 0 && !e.element().empty() &&
                               e.reason().find("file ends after") != std::string::npos;
          EXPECT_TRUE(claim || at_byte) << "cut " << cut << ": " << e.what();
        } else {
          EXPECT_EQ(e.location().rfind("line ", 0), 0u) << "cut " << cut << ": " << e.what();
        }
      }
    }
  }
  // Fixed-size data cut short: the header claims more than is left.
  const std::string full = binary_file(false);
  const std::size_t data = full.find("end_header\n") + 11;
  InputError e = ply_error(full.substr(0, data + 20));
  EXPECT_EQ(e.location(), "line 5");
  EXPECT_EQ(e.element(), "header");
  EXPECT_EQ(e.reason(), "header claims 4 vertices (at least 16 bytes each) but the file has only 20 bytes after the header");
  // Cut inside face 1's index list (2 of its 4 indices present): the minimum sizes still fit, the
  // reader runs out at the third index.
  const std::size_t face1 = full.size() - 9 - 22;
  e = ply_error(full.substr(0, face1 + 10));
  EXPECT_EQ(e.element(), "face 1");
  EXPECT_EQ(e.reason(), "file ends after 1 of 2 faces");
  EXPECT_EQ(e.location(), "byte " + std::to_string(face1 + 2));
}

TEST(IoPly, TruncatedAscii) {
  const std::string full = kAsciiFile;
  // Cut early: fewer bytes are left than the claimed elements need (2 per value at least).
  auto e = ply_error(full.substr(0, full.find("-7 1 2")));
  EXPECT_EQ(e.element(), "header");
  EXPECT_EQ(e.location(), "line 10");
  EXPECT_EQ(e.reason(), "header claims 2 'edge' elements (at least 6 bytes each) but the file has only 46 bytes after the header");
  // Cut late: the reader runs out of tokens.
  e = ply_error(full.substr(0, full.find(" 1 0 1.5")));  // mid face 1's index list
  EXPECT_EQ(e.element(), "face 1");
  EXPECT_EQ(e.reason(), "file ends after 1 of 2 faces");
  e = ply_error(full.substr(0, full.size() - 6));  // inside the material
  EXPECT_EQ(e.element(), "material 0");
  EXPECT_EQ(e.reason(), "file ends after 0 of 1 'material' elements");
}

TEST(IoPly, NanInfGarbledAndBadIndicesAscii) {
  auto e = ply_error(ascii_tri("0 0 0\n1 nan 0\n0 1 0\n", "3 0 1 2\n"));
  EXPECT_EQ(e.location(), "line 11");
  EXPECT_EQ(e.element(), "vertex 1");
  EXPECT_EQ(e.reason(), "y is NaN");
  e = ply_error(ascii_tri("0 0 0\n1 0 0\n0 1 inf\n", "3 0 1 2\n"));
  EXPECT_EQ(e.reason(), "z is infinite");
  e = ply_error(ascii_tri("0 0 0\n1 0 0\n0 1 0x\n", "3 0 1 2\n"));
  EXPECT_EQ(e.location(), "line 12");
  EXPECT_EQ(e.element(), "vertex 2");
  EXPECT_EQ(e.reason(), "value of 'z' '0x' is not a number");
  e = ply_error(ascii_tri("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 2.5\n"));
  EXPECT_EQ(e.element(), "face 0");
  EXPECT_EQ(e.reason(), "index of 'vertex_indices' '2.5' is not an integer");
  e = ply_error(ascii_tri("0 0 0\n1 0 0\n0 1 0\n", "3 0 -1 2\n"));
  EXPECT_EQ(e.location(), "line 13");
  EXPECT_EQ(e.reason(), "index -1 is negative");
  e = ply_error(ascii_tri("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 57\n"));
  EXPECT_EQ(e.reason(), "index 57 out of range [0, 3)");
  e = ply_error(ascii_tri("0 0 0\n1 0 0\n0 1 0\n", "", 3, 0));
  EXPECT_EQ(e.reason(), "mesh has no triangles");
  e = ply_error("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                "end_header\n0 0 0\n");
  EXPECT_EQ(e.reason(), "mesh has no triangles");
}

TEST(IoPly, NanAndBadIndicesBinary) {
  const std::string head =
      "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const auto file = [&](float y1, std::uint8_t n, std::int32_t last) {
    Bytes b{true, {}};
    b.put(0.f).put(0.f).put(0.f).put(1.f).put(y1).put(0.f).put(0.f).put(1.f).put(0.f);
    b.put(n);
    for (std::int32_t i = 0; i + 1 < n; ++i) b.put(i);
    if (n > 0) b.put(last);
    return head + b.s;
  };
  EXPECT_EQ(ply(file(0.f, 3, 2)).mesh.triangle_count(), 1u);
  auto e = ply_error(file(std::nanf(""), 3, 2));
  EXPECT_EQ(e.element(), "vertex 1");
  EXPECT_EQ(e.location(), "byte " + std::to_string(head.size() + 12));
  EXPECT_EQ(e.reason(), "y is NaN");
  e = ply_error(file(-INFINITY, 3, 2));
  EXPECT_EQ(e.reason(), "y is infinite");
  e = ply_error(file(0.f, 3, -1));
  EXPECT_EQ(e.element(), "face 0");
  EXPECT_EQ(e.location(), "byte " + std::to_string(head.size() + 36 + 1 + 8));
  EXPECT_EQ(e.reason(), "index -1 is negative");
  e = ply_error(file(0.f, 3, 3));
  EXPECT_EQ(e.reason(), "index 3 out of range [0, 3)");
  e = ply_error(file(0.f, 2, 1));  // the only face is short
  EXPECT_EQ(e.reason(), "mesh has no triangles (its 1 face has fewer than 3 corners)");
  e = ply_error(file(0.f, 2, 7));  // a short face's indices are still checked
  EXPECT_EQ(e.reason(), "index 7 out of range [0, 3)");
}

// Faces with 0, 1 or 2 corners among good ones (issue 15): skipped and counted in both encodings,
// face numbers kept.
TEST(IoPly, FacesWithFewerThanThreeCornersAreSkippedAndCounted) {
  const std::string ascii = ascii_tri("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 2\n2 0 1\n0\n3 2 1 0\n", 3, 4);
  std::string bin =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\nend_header\n";
  Bytes b{false, {}};
  b.put(0.f).put(0.f).put(0.f).put(1.f).put(0.f).put(0.f).put(0.f).put(1.f).put(0.f);
  b.put(std::uint8_t{3}).put(0).put(1).put(2);
  b.put(std::uint8_t{2}).put(0).put(1);
  b.put(std::uint8_t{0});
  b.put(std::uint8_t{3}).put(2).put(1).put(0);
  bin += b.s;
  for (const std::string& file : {ascii, bin}) {
    const auto lm = ply(file);
    ASSERT_EQ(lm.mesh.triangle_count(), 2u);
    EXPECT_EQ(lm.mesh.triangle(1), (Tri{2, 1, 0}));
    EXPECT_EQ(lm.report.faces, 4u);
    EXPECT_EQ(lm.report.short_faces, 2u);
    EXPECT_EQ(lm.report.source_face, (std::vector<std::uint32_t>{0, 3}));
  }
  EXPECT_EQ(ply(ascii).report.first_short_face, "face 1 (line 14)");
  EXPECT_EQ(ply(bin).report.first_short_face, "face 1 (byte " + std::to_string(bin.size() - 13 - 9 - 1) + ")");
}

// ASCII PLY is read one element per line. MeshLab/VCG write face lines with more values than the
// header declares (issue 15): the surplus is ignored and counted once, with the first line named.
// An element whose values run onto the next line still reads.
TEST(IoPly, AsciiSurplusValuesPerLineAreIgnoredAndCounted) {
  const auto lm = ply(ascii_tri("0 0 0 0.5 0.5\n1 0 0\n0 1 0\n", "3 0 1 2 0 0 0 0\n3 2 1 0 7\n", 3, 2));
  ASSERT_EQ(lm.mesh.vertex_count(), 3u);
  EXPECT_EQ(lm.mesh.position(1), Vec3(1, 0, 0));
  ASSERT_EQ(lm.mesh.triangle_count(), 2u);
  EXPECT_EQ(lm.mesh.triangle(0), (Tri{0, 1, 2}));
  EXPECT_EQ(lm.mesh.triangle(1), (Tri{2, 1, 0}));
  EXPECT_EQ(lm.report.surplus_lines, 3u);
  EXPECT_EQ(lm.report.first_surplus, "vertex 0 (line 10): 2 extra values");
  const auto notes = read_notes(lm.report);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0],
            "3 lines carry more values than the header declares; the extra values were ignored (first: vertex 0 "
            "(line 10): 2 extra values)");
  // Values continued on the next line, and blank lines between elements.
  const auto wrapped = ply(ascii_tri("0 0\n0\n\n1 0 0\n0 1 0\n", "3 0\n1 2\n", 3, 1));
  EXPECT_EQ(wrapped.mesh.triangle(0), (Tri{0, 1, 2}));
  EXPECT_EQ(wrapped.report.surplus_lines, 0u);
  // Surplus values are not checked as numbers (they belong to no declared property), but a file
  // that puts several elements on one line runs short and says so.
  EXPECT_EQ(ply(ascii_tri("0 0 0 x\n1 0 0\n0 1 0\n", "3 0 1 2\n")).report.surplus_lines, 1u);
  const auto e = ply_error(ascii_tri("0 0 0 1 0 0 0 1 0\n", "3 0 1 2\n"));
  EXPECT_EQ(e.reason(),
            "file ends after 2 of 3 vertices (2 lines carried more values than the header declares, first: vertex 0 "
            "(line 10): 6 extra values)");
  const auto one = ply_error(ascii_tri("0 0 0\n1 0 0\n0 1 0\n", "3 0 1 2 3 0 2 1\n", 3, 2));
  EXPECT_EQ(one.reason(),
            "file ends after 1 of 2 faces (1 line carried more values than the header declares, first: face 0 "
            "(line 13): 4 extra values)");
}

}  // namespace
}  // namespace ptc

namespace ptc {
namespace {

// Found by review: an element without properties claims no bytes, so its count escaped the
// size check and the ascii reader looped over it (a 200-byte file hung `ptc info`).
TEST(IoPly, ElementWithoutPropertiesIsSkippedWhateverItsCount) {
  for (const char* enc : {"ascii", "binary_little_endian"}) {
    std::string h = std::string("ply\nformat ") + enc +
                    " 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
                    "element junk 4000000000\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    if (std::string(enc) == "ascii") {
      h += "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    } else {
      for (double v : {0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0}) h.append(reinterpret_cast<const char*>(&v), 8);
      h.push_back(3);
      for (std::int32_t i : {0, 1, 2}) h.append(reinterpret_cast<const char*>(&i), 4);
    }
    const LoadedMesh m = ply(h);
    EXPECT_EQ(m.mesh.triangle_count(), 1u) << enc;
    EXPECT_EQ(m.mesh.position(1), Vec3(1, 0, 0)) << enc;
  }
  // Counts beyond 32 bits are rejected in the header, naming the line.
  const InputError e = ply_error("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                 "property float z\nelement junk 9000000000000000000\nend_header\n");
  EXPECT_EQ(e.location(), "line 7");
}

// Found by review: duplicate checks were linear per header line (quadratic headers).
TEST(IoPly, HugeHeaderIsLinear) {
  std::string h = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 1\nproperty list uchar int vertex_indices\n";
  for (int i = 0; i < 100000; ++i) h += "element e" + std::to_string(i) + " 0\n";
  h += "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(ply(h).mesh.triangle_count(), 1u);  // ctest's timeout catches a quadratic regression
  h.insert(h.find("end_header"), "element e7 0\n");
  EXPECT_NE(std::string(ply_error(h).what()).find("declared twice"), std::string::npos);
}

std::string fmt_report(const ReadReport& r) {
  std::string o = " faces " + std::to_string(r.faces) + " polygons " + std::to_string(r.polygons) + " from " +
                  std::to_string(r.triangles_from_polygons) + " short " + std::to_string(r.short_faces) + " " +
                  r.first_short_face + " surplus " + std::to_string(r.surplus_lines) + " " + r.first_surplus +
                  " binary " + std::to_string(r.binary) + " source";
  for (std::uint32_t f : r.source_face) (o += ' ') += std::to_string(f);  // (appended: GCC 12 -Wrestrict)
  return o;
}

// ---- a file read through a sliding window (read_ply_file) -------------------------------------

// What a read gave: the mesh and report, or the error's text.
std::string outcome(const std::function<LoadedMesh()>& read) {
  try {
    const LoadedMesh lm = read();
    std::string o = "ok " + std::to_string(lm.mesh.vertex_count()) + " " + std::to_string(lm.mesh.triangle_count());
    for (const Vec3& p : lm.mesh.positions()) o.append(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double));
    for (std::size_t t = 0; t < lm.mesh.triangle_count(); ++t)
      for (std::uint32_t v : lm.mesh.triangle(t)) (o += ' ') += std::to_string(v);  // (appended: GCC 12 -Wrestrict)
    const ReadReport& r = lm.report;
    o += fmt_report(r);
    return o;
  } catch (const InputError& e) {
    return std::string("error ") + e.what();
  }
}

class IoPlyFile : public test::TempDirTest {
 protected:
  // The outcome of reading `bytes` from a file through a window of `window` bytes; `claimed_size`
  // stands for a file that shrank after its size was taken.
  std::string from_file(std::string_view bytes, std::size_t window, std::uint64_t claimed_size = ~std::uint64_t{0}) {
    const auto path = dir_ / "t.ply";
    test::spit(path, bytes);
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    EXPECT_GE(fd, 0);
    const std::uint64_t size = claimed_size == ~std::uint64_t{0} ? bytes.size() : claimed_size;
    std::string o = outcome([&] { return io::read_ply_file(fd, size, "t.ply", window); });
    ::close(fd);
    return o;
  }
};

// A binary file of n vertices and about n faces: skipped scalar and list properties on both, faces
// of 0 to 7 corners, and an index list long enough to cross several windows.
std::string big_binary_file(bool big, int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\nelement vertex " + std::to_string(n) +
                  "\nproperty float x\nproperty list uchar short junk\nproperty double y\nproperty int16 z\n"
                  "element face " + std::to_string(n + 1) +
                  "\nproperty uchar flags\nproperty list ushort int vertex_indices\nproperty list uchar float q\n"
                  "end_header\n";
  Bytes b{big, {}};
  for (int i = 0; i < n; ++i) {
    b.put(static_cast<float>(rng() % 1000) / 7.0f).put<std::uint8_t>(static_cast<std::uint8_t>(rng() % 3));
    b.s.append(2 * static_cast<std::size_t>(static_cast<unsigned char>(b.s.back())), 'j');
    b.put(static_cast<double>(rng()) / 3.0).put<std::int16_t>(static_cast<std::int16_t>(rng()));
  }
  for (int i = 0; i <= n; ++i) {
    const int corners = i == n / 2 ? 3000 : static_cast<int>(rng() % 8);
    b.put<std::uint8_t>(7).put<std::uint16_t>(static_cast<std::uint16_t>(corners));
    for (int k = 0; k < corners; ++k) b.put<std::int32_t>(static_cast<std::int32_t>(rng() % n));
    b.put<std::uint8_t>(1).put(0.5f);
  }
  return s + b.s;
}

TEST_F(IoPlyFile, WindowedReadAgreesWithTheWholeFileInMemory) {
  std::vector<std::string> files = {binary_file(false), binary_file(true), kAsciiFile,
                                    big_binary_file(false, 2000, 1), big_binary_file(true, 2000, 2)};
  // Every cut of the small files, and cuts of the large ones (in the header, the vertices, the
  // long list, the last face).
  for (bool big : {false, true}) {
    const std::string full = binary_file(big);
    for (std::size_t cut = 0; cut < full.size(); ++cut) files.push_back(full.substr(0, cut));
  }
  for (std::size_t i : {3u, 4u}) {
    const std::string full = files[i];
    const std::size_t data = full.find("end_header\n") + 11;
    for (std::size_t cut : {std::size_t{40}, data - 1, data, data + 1, data + 20000, full.size() / 2,
                            full.size() / 2 + 5001, full.size() - 1})
      files.push_back(full.substr(0, cut));
  }
  // Random damage: bytes of the body overwritten (bad counts, indices, NaNs, truncation claims).
  std::mt19937 rng(7);
  for (int k = 0; k < 200; ++k) {
    std::string f = k % 2 ? binary_file(k % 4 == 1) : big_binary_file(false, 300, static_cast<std::uint32_t>(k));
    const std::size_t data = f.find("end_header\n") + 11;
    for (int j = 0; j < 3; ++j) f[data + rng() % (f.size() - data)] = static_cast<char>(rng());
    files.push_back(f);
  }
  std::size_t loaded = 0, refused = 0;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::string want = outcome([&] { return io_test::read(files[i], MeshFormat::Ply); });
    (want.rfind("ok", 0) == 0 ? loaded : refused)++;
    const bool large = files[i].size() > 20000;
    for (std::size_t window : large ? std::vector<std::size_t>{1, 4093, io::kPlyWindowBytes}
                                    : std::vector<std::size_t>{1, 2, 3, 5, 8, 64, io::kPlyWindowBytes})
      ASSERT_EQ(from_file(files[i], window), want) << "file " << i << ", window " << window;
  }
  // Both kinds occur, so the comparison covers meshes and errors alike.
  EXPECT_GT(loaded, 10u);
  EXPECT_GT(refused, 100u);
}

TEST_F(IoPlyFile, AFileThatShrankAfterItsSizeWasTakenIsRefused) {
  const std::string full = big_binary_file(false, 2000, 3);
  const std::size_t data = full.find("end_header\n") + 11;
  // (Cuts where the reader needs bytes: skipped values at the very end are never read, so a file
  // cut there may still load.)
  for (std::size_t cut : {std::size_t{20}, data + 100, full.size() / 2}) {
    const std::string o = from_file(full.substr(0, cut), 4096, full.size());
    EXPECT_EQ(o.rfind("error t.ply", 0), 0u) << cut << ": " << o.substr(0, 200);
    if (cut > data) {
      EXPECT_NE(o.find("file ends after"), std::string::npos) << o;
    }
  }
}

TEST_F(IoPlyFile, ReadMeshReadsALargeBinaryFileThroughTheWindow) {
  // Public entry: more than one window of body, the same mesh as from memory.
  const std::string full = big_binary_file(true, 60000, 4);
  ASSERT_GT(full.size(), 2 * io::kPlyWindowBytes);
  test::spit(dir_ / "big.ply", full);
  const std::string want = outcome([&] { return read_mesh_from_memory(full, MeshFormat::Ply, (dir_ / "big.ply").string()); });
  EXPECT_EQ(want.rfind("ok", 0), 0u) << want.substr(0, 200);
  EXPECT_EQ(outcome([&] { return read_mesh(dir_ / "big.ply"); }), want);
}

}  // namespace
}  // namespace ptc
