// OBJ reader against hand-written files: corner forms, relative indices, ignored keywords.
#include <gtest/gtest.h>

#include <string>

#include "toolkit/core/error.h"
#include "io_helpers.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

LoadedMesh obj(std::string_view bytes) { return io_test::read(bytes, MeshFormat::Obj); }
InputError obj_error(std::string_view bytes) { return io_test::read_error(bytes, MeshFormat::Obj); }

TEST(IoObj, CornerFormsAndIgnoredKeywords) {
  const auto lm = obj(
      "# comment\nmtllib scene.mtl\no thing\ng group\ns 1\nusemtl red\n"
      "v 0 0 0\nv 1 0 0 1.0\nv 0 1 0\nv 0 0 1 0.5 0.5 0.5\n"
      "vt 0 0\nvt 1 0\nvn 0 0 1\nvp 0.5\n"
      "f 1 2 3\n"
      "f 1/1 2/2 4/1\n"
      "f 1/1/1 3/2/1 4/1/1 # trailing comment\n"
      "f 2//1 3//1 4//1\n"
      "l 1 2\np 3\ncurv 0 1 1 2\nfoo bar\n");
  const Mesh& m = lm.mesh;
  ASSERT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.position(0), Vec3(0, 0, 0));
  EXPECT_EQ(m.position(1), Vec3(1, 0, 0));
  EXPECT_EQ(m.position(2), Vec3(0, 1, 0));
  EXPECT_EQ(m.position(3), Vec3(0, 0, 1));
  ASSERT_EQ(m.triangle_count(), 4u);
  EXPECT_EQ(m.triangle(0), (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangle(1), (Tri{0, 1, 3}));
  EXPECT_EQ(m.triangle(2), (Tri{0, 2, 3}));
  EXPECT_EQ(m.triangle(3), (Tri{1, 2, 3}));
  EXPECT_EQ(lm.report.format, MeshFormat::Obj);
  EXPECT_EQ(lm.report.faces, 4u);
  EXPECT_TRUE(lm.report.source_face.empty());  // triangle t is face t
  for (std::size_t t = 0; t < 4; ++t) EXPECT_EQ(lm.report.source_face_of(t), t);
}

TEST(IoObj, StatementsContinuedWithABackslash) {
  // "f 1 2 \\" + "3 4" is one face; a vertex may be split too; comments and CRLF on the way.
  const auto lm = obj("v 0 0 0\nv 1 0 \\\n  0\nv 1 1 0 # c\nv 0 1 0\nf 1 2 \\ \r\n3 4 # quad\nf 1 \\\n2 \\\n3\n");
  ASSERT_EQ(lm.mesh.vertex_count(), 4u);
  EXPECT_EQ(lm.mesh.position(1), Vec3(1, 0, 0));
  ASSERT_EQ(lm.mesh.triangle_count(), 3u);  // the quad's fan and the triangle
  EXPECT_EQ(lm.mesh.triangle(0), (Tri{0, 1, 2}));
  EXPECT_EQ(lm.mesh.triangle(1), (Tri{0, 2, 3}));
  EXPECT_EQ(lm.mesh.triangle(2), (Tri{0, 1, 2}));
  // A backslash on the last line ends the statement; an error names the statement's last line.
  EXPECT_EQ(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 \\").mesh.triangle_count(), 1u);
  const InputError e = obj_error("v 0 0 0\nv 1 \\\nx 0\n");
  EXPECT_EQ(e.location(), "line 3");
  EXPECT_EQ(e.element(), "vertex 1");
}

TEST(IoObj, NegativeIndicesAreRelativeToTheVerticesDefinedSoFar) {
  const auto lm = obj(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
      "f -3 -2 -1\n"         // 0 1 2
      "v 1 1 0\n"
      "f -3/-1 -1/-1 -2\n"   // 1 3 2
      "v 2 2 2\nv 3 3 3\n"
      "f -1//-1 -2//-1 1\n"  // 5 4 0
      "f 6 -5 -2\n");        // 5 1 4 (absolute and relative mixed)
  const Mesh& m = lm.mesh;
  ASSERT_EQ(m.triangle_count(), 4u);
  EXPECT_EQ(m.triangle(0), (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangle(1), (Tri{1, 3, 2}));
  EXPECT_EQ(m.triangle(2), (Tri{5, 4, 0}));
  EXPECT_EQ(m.triangle(3), (Tri{5, 1, 4}));
}

TEST(IoObj, ForwardReferencesPolygonsAndCrLf) {
  const auto lm = obj("f 1 2 3 4 5\r\nv 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\nv -1 0.5 0\r\n");
  const Mesh& m = lm.mesh;
  ASSERT_EQ(m.triangle_count(), 3u);
  EXPECT_EQ(m.triangle(0), (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangle(1), (Tri{0, 2, 3}));
  EXPECT_EQ(m.triangle(2), (Tri{0, 3, 4}));
  EXPECT_EQ(lm.report.polygons, 1u);
  EXPECT_EQ(lm.report.triangles_from_polygons, 3u);
  EXPECT_EQ(m.position(4), Vec3(-1, 0.5, 0));
}

TEST(IoObj, BadIndices) {
  auto e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 0 3\n");
  EXPECT_EQ(e.location(), "line 5");
  EXPECT_EQ(e.element(), "face 1");
  EXPECT_EQ(e.reason(), "index 0 is invalid (OBJ indices start at 1)");
  e = obj_error("v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n");
  EXPECT_EQ(e.location(), "line 3");
  EXPECT_EQ(e.element(), "face 0");
  EXPECT_EQ(e.reason(), "relative index -3 refers before the first vertex (2 vertices defined so far)");
  e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 57\nf 1 2 4\n");
  EXPECT_EQ(e.location(), "line 5");
  EXPECT_EQ(e.element(), "face 1");
  EXPECT_EQ(e.reason(), "index 57 out of range [1, 3] (the file defines 3 vertices)");
  e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -9223372036854775808\n");
  EXPECT_NE(e.reason().find("refers before the first vertex"), std::string::npos) << e.what();
  // Beyond what ptc numbers (32 bits) or beyond 64 bits: the same words (a positive index is
  // checked against the whole file, not the vertices so far, which the message once said)
  e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999999999999\n");
  EXPECT_EQ(e.reason(), "index 99999999999999999999 out of range (ptc numbers at most 4294967295 vertices)");
  e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4294967297\n");
  EXPECT_EQ(e.reason(), "index 4294967297 out of range (ptc numbers at most 4294967295 vertices)");
  e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -99999999999999999999\n");
  EXPECT_EQ(e.reason(), "relative index -99999999999999999999 refers before the first vertex (3 vertices defined so far)");
}

TEST(IoObj, GarbledAndShortLines) {
  auto e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x/3 2 3\n");
  EXPECT_EQ(e.location(), "line 4");
  EXPECT_EQ(e.reason(), "corner '1/x/3' is not of the form i, i/t, i/t/n or i//n");
  e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/4/5/6\n");  // (four parts: accepted before)
  EXPECT_EQ(e.reason(), "corner '3/4/5/6' is not of the form i, i/t, i/t/n or i//n");
  e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3a\n");
  EXPECT_EQ(e.reason(), "corner '3a' is not an integer index");
  e = obj_error("v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(e.location(), "line 2");
  EXPECT_EQ(e.element(), "vertex 1");
  EXPECT_EQ(e.reason(), "expected 3 coordinates, found 2");
  e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0..5\nf 1 2 3\n");
  EXPECT_EQ(e.element(), "vertex 2");
  EXPECT_EQ(e.reason(), "coordinate 2 '0..5' is not a number");
}

// A face with fewer than three corners among good ones (issue 15, seen in exported files): it is
// skipped and counted, keeps its face number, and the rest loads. Its indices are still checked.
TEST(IoObj, FacesWithFewerThanThreeCornersAreSkippedAndCounted) {
  const auto lm = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2\nf\nf 4/1 -2\nf 1 3 4\n");
  ASSERT_EQ(lm.mesh.triangle_count(), 2u);
  EXPECT_EQ(lm.mesh.triangle(0), (Tri{0, 1, 2}));
  EXPECT_EQ(lm.mesh.triangle(1), (Tri{0, 2, 3}));
  EXPECT_EQ(lm.report.faces, 5u);
  EXPECT_EQ(lm.report.short_faces, 3u);
  EXPECT_EQ(lm.report.source_face, (std::vector<std::uint32_t>{0, 4}));
  EXPECT_EQ(lm.report.first_short_face, "face 1 (line 6)");
  const auto notes = read_notes(lm.report);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0], "3 faces have fewer than 3 corners and were skipped (first: face 1 (line 6))");
  // Still checked: a bad index in a short face is an error, and so is a file of short faces only.
  auto e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 9\n");
  EXPECT_EQ(e.reason(), "index 9 out of range [1, 3] (the file defines 3 vertices)");
  e = obj_error("v 0 0 0\nv 1 0 0\nf 1 2\n");
  EXPECT_EQ(e.reason(), "mesh has no triangles (its 1 face has fewer than 3 corners)");
  EXPECT_TRUE(read_notes(obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").report).empty());
}

TEST(IoObj, NanInfEmptyAndNoFaces) {
  auto e = obj_error("v 0 0 0\nv 1 NaN 0\nv 0 1 0\nf 1 2 3\n");
  EXPECT_EQ(e.location(), "line 2");
  EXPECT_EQ(e.element(), "vertex 1");
  EXPECT_EQ(e.reason(), "coordinate 1 is NaN");
  e = obj_error("v 0 0 0\nv 1 0 0\nv inf 1 0\nf 1 2 3\n");
  EXPECT_EQ(e.reason(), "coordinate 0 is infinite");
  e = obj_error("");
  EXPECT_EQ(e.reason(), "mesh has no triangles");
  e = obj_error("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\n");
  EXPECT_EQ(e.reason(), "mesh has no triangles");
}

TEST(IoObj, TruncatedFiles) {
  const std::string full = "v 0.5 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\n";
  // Mid-number in the last vertex: the face refers to a vertex that no longer exists.
  auto e = obj_error(full.substr(0, full.find("v 0 0 1") + 4) + "\n");
  EXPECT_EQ(e.location(), "line 4");
  EXPECT_EQ(e.reason(), "expected 3 coordinates, found 1");
  // Cut in the last face's index list: "f 1 3" is a short face, skipped and counted.
  const auto cut = obj(full.substr(0, full.size() - 3));
  EXPECT_EQ(cut.mesh.triangle_count(), 1u);
  EXPECT_EQ(cut.report.short_faces, 1u);
  // Cut before any face.
  e = obj_error(full.substr(0, full.find('f')));
  EXPECT_EQ(e.reason(), "mesh has no triangles");
}

}  // namespace
}  // namespace ptc

namespace ptc {
namespace {
// UTF-16 text (the byte order mark, then a NUL after every ASCII character): said so, where the
// readers found no line to parse and said only "no triangles" (assimp's box_UTF16BE.obj).
TEST(IoObj, Utf16TextIsNamedAsSuch) {
  auto utf16 = [](std::string_view text, bool big_endian) {
    std::string s = big_endian ? std::string("\xFE\xFF", 2) : std::string("\xFF\xFE", 2);
    for (char c : text) {
      if (big_endian) s.push_back('\0');
      s.push_back(c);
      if (!big_endian) s.push_back('\0');
    }
    return s;
  };
  for (MeshFormat f : {MeshFormat::Obj, MeshFormat::Off, MeshFormat::Ply})
    for (bool be : {true, false}) {
      const std::string text = f == MeshFormat::Obj ? "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n" : "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
      const InputError e = io_test::read_error(utf16(text, be), f);
      EXPECT_EQ(e.location(), "byte 0");  // (offsets count from 0, as everywhere)
      EXPECT_NE(std::string(e.what()).find("UTF-16 text is not supported"), std::string::npos) << e.what();
    }
}
}  // namespace
}  // namespace ptc
