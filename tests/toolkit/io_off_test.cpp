// OFF reader against hand-written files whose every coordinate and face is known.
#include <gtest/gtest.h>

#include <algorithm>

#include <string>

#include "toolkit/core/error.h"
#include "io_helpers.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

LoadedMesh off(std::string_view bytes) { return io_test::read(bytes, MeshFormat::Off); }
InputError off_error(std::string_view bytes) { return io_test::read_error(bytes, MeshFormat::Off); }

void expect_tri(const Mesh& m, std::size_t t, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  ASSERT_LT(t, m.triangle_count());
  EXPECT_EQ(m.triangle(t), (Tri{a, b, c})) << "triangle " << t;
}

TEST(IoOff, TetrahedronElementByElement) {
  const auto lm = off("OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  const Mesh& m = lm.mesh;
  ASSERT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.position(0), Vec3(0, 0, 0));
  EXPECT_EQ(m.position(1), Vec3(1, 0, 0));
  EXPECT_EQ(m.position(2), Vec3(0, 1, 0));
  EXPECT_EQ(m.position(3), Vec3(0, 0, 1));
  ASSERT_EQ(m.triangle_count(), 4u);
  expect_tri(m, 0, 0, 2, 1);
  expect_tri(m, 1, 0, 1, 3);
  expect_tri(m, 2, 0, 3, 2);
  expect_tri(m, 3, 1, 2, 3);
  EXPECT_EQ(lm.report.format, MeshFormat::Off);
  EXPECT_FALSE(lm.report.binary);
  EXPECT_EQ(lm.report.faces, 4u);
  EXPECT_EQ(lm.report.polygons, 0u);
  EXPECT_EQ(lm.report.triangles_from_polygons, 0u);
  EXPECT_EQ(lm.report.welded_vertices, 0u);
  EXPECT_TRUE(lm.report.source_face.empty());  // triangle t is face t
  for (std::size_t t = 0; t < 4; ++t) EXPECT_EQ(lm.report.source_face_of(t), t);
}

TEST(IoOff, CommentsBeforeHeaderBlankLinesTrailingCommentsAndCrLf) {
  const auto lm = off(
      "# written by a CGAL tool\n#CBP\n\n  # indented comment\nOFF # keyword comment\r\n"
      "# counts next\n3 1 0\r\n\n"
      "0.5 -1.25 2e3 # first\r\n"
      "# between vertices\n"
      "+1 .5 -0\n"
      "\t7 8 9\n"
      "3 0 1 2 # the face\n# trailing\n");
  const Mesh& m = lm.mesh;
  ASSERT_EQ(m.vertex_count(), 3u);
  EXPECT_EQ(m.position(0), Vec3(0.5, -1.25, 2000));
  EXPECT_EQ(m.position(1), Vec3(1, 0.5, 0));
  EXPECT_TRUE(std::signbit(m.position(1).z()));  // "-0" is read as -0.0
  EXPECT_EQ(m.position(2), Vec3(7, 8, 9));
  ASSERT_EQ(m.triangle_count(), 1u);
  expect_tri(m, 0, 0, 1, 2);
}

// Lines that end in a carriage return alone (classic Mac OS text): each CR ends a line, in OFF
// and in OBJ, with comments (which end at the line's end) in both. Text with any '\n' is read as
// it is (a lone CR there stays a blank).
TEST(IoOff, LinesEndingInACarriageReturnAlone) {
  const std::string unix_off = "OFF # counts next\n4 4 6\n0 0 0 # a comment\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  std::string mac = unix_off;
  std::replace(mac.begin(), mac.end(), '\n', '\r');
  const auto a = off(unix_off), b = off(mac);
  ASSERT_EQ(b.mesh.vertex_count(), 4u);
  ASSERT_EQ(b.mesh.triangle_count(), 4u);
  for (std::uint32_t v = 0; v < 4; ++v) EXPECT_EQ(b.mesh.position(v), a.mesh.position(v)) << v;
  for (std::size_t t = 0; t < 4; ++t) EXPECT_EQ(b.mesh.triangle(t), a.mesh.triangle(t)) << t;
  std::string obj = "# a comment\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\n";
  const auto c = io_test::read(obj, MeshFormat::Obj);
  std::replace(obj.begin(), obj.end(), '\n', '\r');
  const auto d = io_test::read(obj, MeshFormat::Obj);
  ASSERT_EQ(d.mesh.triangle_count(), 2u);
  for (std::size_t t = 0; t < 2; ++t) EXPECT_EQ(d.mesh.triangle(t), c.mesh.triangle(t)) << t;
  for (std::uint32_t v = 0; v < 4; ++v) EXPECT_EQ(d.mesh.position(v), c.mesh.position(v)) << v;
}

TEST(IoOff, CountsOnTheHeaderLineAndNoEdgeCount) {
  const auto a = off("OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(a.mesh.vertex_count(), 3u);
  EXPECT_EQ(a.mesh.triangle_count(), 1u);
  const auto b = off("OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 2 1 0\n");
  expect_tri(b.mesh, 0, 2, 1, 0);
}

TEST(IoOff, VertexCountGluedToTheKeyword) {
  // "OFF8 6 12" (seen in files from the wild) reads as "OFF 8 6 12", also for the variants.
  const std::string cube = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
                           "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n";
  const auto glued = off("OFF8 6 12\n" + cube), spaced = off("OFF 8 6 12\n" + cube);
  ASSERT_EQ(glued.mesh.vertex_count(), 8u);
  ASSERT_EQ(glued.mesh.triangle_count(), 12u);
  for (std::size_t t = 0; t < 12; ++t) EXPECT_EQ(glued.mesh.triangle(t), spaced.mesh.triangle(t));
  EXPECT_EQ(off("COFF3 1\n0 0 0 1 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n").mesh.triangle_count(), 1u);
  // Not a count: still a bad header, named as before.
  EXPECT_NE(off_error("OFFx 3 1\n").reason().find("missing OFF header"), std::string::npos);
  EXPECT_NE(off_error("OFF3x 1\n").reason().find("vertex count"), std::string::npos);
}

TEST(IoOff, ColoredAndOtherVariantsIgnoreExtraFields) {
  // COFF: RGBA after xyz, and a face color after the indices.
  const auto c = off("COFF\n3 1 0\n1 2 3 255 0 0 255\n4 5 6 0 255 0 255\n7 8 9 0.1 0.2 0.3 1\n3 0 1 2 255 0 0\n");
  ASSERT_EQ(c.mesh.vertex_count(), 3u);
  EXPECT_EQ(c.mesh.position(0), Vec3(1, 2, 3));
  EXPECT_EQ(c.mesh.position(1), Vec3(4, 5, 6));
  EXPECT_EQ(c.mesh.position(2), Vec3(7, 8, 9));
  expect_tri(c.mesh, 0, 0, 1, 2);
  // NOFF (normals), STOFF (texture coordinates), CNOFF, STCNOFF.
  for (std::string kw : {"NOFF", "STOFF", "CNOFF", "STCNOFF"}) {
    const auto m = off(kw + "\n3 1 0\n1 2 3 9 9 9\n4 5 6 9 9 9\n7 8 9 9 9 9\n3 0 1 2\n");
    ASSERT_EQ(m.mesh.vertex_count(), 3u) << kw;
    EXPECT_EQ(m.mesh.position(2), Vec3(7, 8, 9)) << kw;
  }
}

TEST(IoOff, QuadAndPentagonAreFanTriangulatedFromCornerZero) {
  const auto lm = off(
      "OFF\n7 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 0\n2 1 0\n1.5 2 0\n"
      "4 0 1 2 3\n3 1 4 2\n5 4 5 6 3 2\n");
  const Mesh& m = lm.mesh;
  ASSERT_EQ(m.triangle_count(), 2u + 1u + 3u);
  expect_tri(m, 0, 0, 1, 2);  // quad
  expect_tri(m, 1, 0, 2, 3);
  expect_tri(m, 2, 1, 4, 2);  // triangle
  expect_tri(m, 3, 4, 5, 6);  // pentagon
  expect_tri(m, 4, 4, 6, 3);
  expect_tri(m, 5, 4, 3, 2);
  EXPECT_EQ(lm.report.faces, 3u);
  EXPECT_EQ(lm.report.polygons, 2u);
  EXPECT_EQ(lm.report.triangles_from_polygons, 5u);
  EXPECT_EQ(lm.report.source_face, (std::vector<std::uint32_t>{0, 0, 1, 2, 2, 2}));
}

TEST(IoOff, DefectsAreKeptInFileOrder) {
  // Repeated index, duplicate vertex (3 == 0), unreferenced vertex 4, the same triangle twice and
  // a non-manifold edge (0,1) shared by three triangles.
  const auto lm = off(
      "OFF\n6 6 0\n0 0 0\n1 0 0\n0 1 0\n0 0 0\n9 9 9\n0 -1 0\n"
      "3 0 0 1\n3 0 1 2\n3 0 1 2\n3 1 0 5\n3 0 1 3\n3 3 1 2\n");
  const Mesh& m = lm.mesh;
  EXPECT_EQ(m.vertex_count(), 6u);
  ASSERT_EQ(m.triangle_count(), 6u);
  expect_tri(m, 0, 0, 0, 1);
  expect_tri(m, 1, 0, 1, 2);
  expect_tri(m, 2, 0, 1, 2);
  expect_tri(m, 3, 1, 0, 5);
  expect_tri(m, 4, 0, 1, 3);
  expect_tri(m, 5, 3, 1, 2);
  EXPECT_EQ(m.position(3), m.position(0));
}

TEST(IoOff, MoreFacesThanClaimedAreIgnored) {
  const auto lm = off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n");
  EXPECT_EQ(lm.mesh.triangle_count(), 1u);
}

// ---- errors --------------------------------------------------------------------------------------

TEST(IoOff, MissingOrUnsupportedHeader) {
  auto e = off_error("3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(e.location(), "line 1");
  EXPECT_EQ(e.element(), "header");
  EXPECT_NE(e.reason().find("missing OFF header"), std::string::npos) << e.what();
  e = off_error("# only a comment\n\n");
  EXPECT_NE(e.reason().find("missing OFF header"), std::string::npos) << e.what();
  e = off_error("# c\n4OFF\n1 1 0\n0 0 0 1\n3 0 0 0\n");
  EXPECT_EQ(e.location(), "line 2");
  EXPECT_NE(e.reason().find("not supported"), std::string::npos) << e.what();
  e = off_error("nOFF\n3\n");
  EXPECT_NE(e.reason().find("not supported"), std::string::npos) << e.what();
  e = off_error("OFF BINARY\n");
  EXPECT_NE(e.reason().find("binary OFF is not supported"), std::string::npos) << e.what();
  e = off_error("OFFX\n");
  EXPECT_NE(e.reason().find("missing OFF header"), std::string::npos) << e.what();
}

TEST(IoOff, EmptyFileAndFileWithoutFaces) {
  auto e = off_error("");
  EXPECT_EQ(e.element(), "header");
  EXPECT_EQ(e.reason(), "file is empty");
  e = off_error("OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_EQ(e.reason(), "mesh has no triangles");
  e = off_error("OFF\n");
  EXPECT_NE(e.reason().find("counts"), std::string::npos) << e.what();
}

TEST(IoOff, BadCounts) {
  auto e = off_error("OFF\n-3 1 0\n");
  EXPECT_EQ(e.location(), "line 2");
  EXPECT_NE(e.reason().find("negative"), std::string::npos) << e.what();
  e = off_error("OFF\n3x 1 0\n");
  EXPECT_NE(e.reason().find("'3x' is not an integer"), std::string::npos) << e.what();
  e = off_error("OFF\n3\n");
  EXPECT_NE(e.reason().find("only the vertex count"), std::string::npos) << e.what();
  e = off_error("OFF\n99999999999999999999999 1 0\n");
  EXPECT_NE(e.reason().find("too large"), std::string::npos) << e.what();
}

TEST(IoOff, HeaderClaiming2To40VerticesThrowsBeforeAllocating) {
  const auto e = off_error("OFF\n1099511627776 1 0\n0 0 0\n3 0 0 0\n");
  EXPECT_EQ(e.location(), "line 2");
  EXPECT_EQ(e.element(), "header");
  EXPECT_NE(e.reason().find("1099511627776"), std::string::npos) << e.what();
  // Within 32 bits but far more than the file holds.
  const auto f = off_error("OFF\n1000000000 1 0\n0 0 0\n3 0 0 0\n");
  EXPECT_NE(f.reason().find("header claims 1000000000 vertices but the file has only 14 bytes left"),
            std::string::npos)
      << f.what();
  const auto g = off_error("OFF\n3 4000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_NE(g.reason().find("4000000000 faces"), std::string::npos) << g.what();
}

TEST(IoOff, NanAndInfiniteCoordinates) {
  auto e = off_error("OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(e.location(), "line 4");
  EXPECT_EQ(e.element(), "vertex 1");
  EXPECT_EQ(e.reason(), "coordinate 1 is NaN");
  e = off_error("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 -inf\n3 0 1 2\n");
  EXPECT_EQ(e.location(), "line 5");
  EXPECT_EQ(e.element(), "vertex 2");
  EXPECT_EQ(e.reason(), "coordinate 2 is infinite");
  e = off_error("OFF\n3 1 0\n0 0 1e999\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(e.element(), "vertex 0");
  EXPECT_NE(e.reason().find("out of range"), std::string::npos) << e.what();
  for (const char* big : {"0.001e312", "1e+400", "-123456e304"}) {
    e = off_error(std::string("OFF\n3 1 0\n0 0 ") + big + "\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_NE(e.reason().find("out of range"), std::string::npos) << big;
  }
  // Numbers below the smallest subnormal are the nearest double, 0 with their sign (they were
  // refused as out of range); subnormals themselves keep their value.
  const std::pair<const char*, double> tiny[] = {{"1e-400", 0.0},        {"-2e-324", -0.0},
                                                 {"1000e-327", 0.0},     {"0.0000001e-320", 0.0},
                                                 {"+1e-99999999999999999999", 0.0}, {"3e-320", 3e-320}};
  for (const auto& [text, value] : tiny) {
    const LoadedMesh m = off(std::string("OFF\n3 1 0\n0 0 ") + text + "\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_EQ(m.mesh.position(0).z(), value) << text;
    EXPECT_EQ(std::signbit(m.mesh.position(0).z()), std::signbit(value)) << text;
  }
}

TEST(IoOff, GarbledTokens) {
  auto e = off_error("OFF\n3 1 0\n0 0 0\n1 0x 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(e.location(), "line 4");
  EXPECT_EQ(e.element(), "vertex 1");
  EXPECT_EQ(e.reason(), "coordinate 1 '0x' is not a number");
  e = off_error("OFF\n3 1 0\n0 0 0\n1,5 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(e.reason(), "coordinate 0 '1,5' is not a number");
  e = off_error("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1\n3 0 1 2\n");
  EXPECT_EQ(e.location(), "line 5");
  EXPECT_EQ(e.reason(), "expected 3 coordinates, found 2");
  e = off_error("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n");
  EXPECT_EQ(e.location(), "line 6");
  EXPECT_EQ(e.element(), "face 0");
  EXPECT_EQ(e.reason(), "index '1.5' is not an integer");
  e = off_error("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\nthree 0 1 2\n");
  EXPECT_EQ(e.reason(), "corner count 'three' is not an integer");
}

TEST(IoOff, BadIndicesAndShortFaces) {
  auto e = off_error("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 -1 2\n");
  EXPECT_EQ(e.location(), "line 7");
  EXPECT_EQ(e.element(), "face 1");
  EXPECT_EQ(e.reason(), "index -1 is negative");
  e = off_error("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 57\n");
  EXPECT_EQ(e.reason(), "index 57 out of range [0, 3)");
  e = off_error("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  EXPECT_EQ(e.reason(), "index 3 out of range [0, 3)");
  e = off_error("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n");
  EXPECT_EQ(e.reason(), "expected 4 vertex indices, found 3");
  e = off_error("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n-3 0 1 2\n");
  EXPECT_EQ(e.reason(), "corner count -3 is negative");
}

// Faces with 0, 1 or 2 corners among good ones (issue 15): skipped, counted, face numbers kept;
// their indices are still checked, and their declared corners must be there.
TEST(IoOff, FacesWithFewerThanThreeCornersAreSkippedAndCounted) {
  const auto lm = off("OFF\n4 5 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n2 0 1\n0\n1 3 255 0 0\n3 0 2 3\n");
  ASSERT_EQ(lm.mesh.triangle_count(), 2u);
  EXPECT_EQ(lm.mesh.triangle(1), (Tri{0, 2, 3}));
  EXPECT_EQ(lm.report.faces, 5u);
  EXPECT_EQ(lm.report.short_faces, 3u);
  EXPECT_EQ(lm.report.source_face, (std::vector<std::uint32_t>{0, 4}));
  EXPECT_EQ(lm.report.first_short_face, "face 1 (line 8)");
  auto e = off_error("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n2 0 7\n");
  EXPECT_EQ(e.location(), "line 7");
  EXPECT_EQ(e.reason(), "index 7 out of range [0, 3)");
  e = off_error("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n2 0\n");
  EXPECT_EQ(e.reason(), "expected 2 vertex indices, found 1");
  e = off_error("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n");
  EXPECT_EQ(e.reason(), "mesh has no triangles (its 1 face has fewer than 3 corners)");
}

TEST(IoOff, TruncatedFiles) {
  const std::string full = "OFF\n4 2 0\n0.25 0.5 0.75\n1 0 0\n1 1 0\n0.125 1 0\n3 0 1 2\n3 0 2 3\n";
  // Cut inside the vertex block: after 2 whole vertex lines.
  auto e = off_error(full.substr(0, full.find("1 1 0")));
  EXPECT_EQ(e.element(), "vertex 2");
  EXPECT_EQ(e.reason(), "file ends after 2 of 4 vertices");
  EXPECT_EQ(e.location(), "line 4");
  // Cut in the middle of the first number of vertex 3 ("0.12").
  e = off_error(full.substr(0, full.find("5 1 0")));
  EXPECT_EQ(e.element(), "vertex 3");
  EXPECT_EQ(e.location(), "line 6");
  EXPECT_EQ(e.reason(), "expected 3 coordinates, found 1");
  // Cut inside the face block.
  e = off_error(full.substr(0, full.find("3 0 2 3")));
  EXPECT_EQ(e.element(), "face 1");
  EXPECT_EQ(e.reason(), "file ends after 1 of 2 faces");
  e = off_error(full.substr(0, full.size() - 4));  // "3 0 " of the last face
  EXPECT_EQ(e.element(), "face 1");
  EXPECT_EQ(e.reason(), "expected 3 vertex indices, found 1");
  // Every cut before the last face's final index fails with an InputError naming the file.
  const std::size_t last = full.rfind(' ');
  for (std::size_t cut = 0; cut <= last; ++cut) {
    try {
      (void)off(full.substr(0, cut));
      ADD_FAILURE() << "loaded a file cut at byte " << cut;
    } catch (const InputError& err) {
      EXPECT_EQ(err.file(), "t.off");
      EXPECT_FALSE(err.location().empty()) << "cut " << cut << ": " << err.what();
    }
  }
}

}  // namespace
}  // namespace ptc
