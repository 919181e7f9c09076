// Writers: exact round trips through every format, PLY face values decoded independently of the
// reader, write options, and the atomic replacement of files.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "common/temp_dir.h"
#include "toolkit/core/error.h"
#include "toolkit/io/atomic_file.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

namespace fs = std::filesystem;

class IoWrite : public test::TempDirTest {};

using test::slurp;
using test::spit;
std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Coordinates that a careless printer gets wrong, and defects that must survive unchanged.
Mesh tricky_mesh() {
  std::vector<Vec3> p{{0.1, 1.0 / 3.0, -0.0},
                      {1e-300, 5e-324, 1e300},  // 5e-324: the smallest subnormal
                      {123456789.123456789, M_PI, -2.5e-7},
                      {std::nextafter(1.0, 2.0), DBL_MAX, -DBL_MIN},
                      {-1e7 + 1e-3, 0.30000000000000004, 1e23},
                      {0.1, 1.0 / 3.0, -0.0}};  // duplicate of vertex 0
  std::vector<Tri> t{{0, 1, 2}, {2, 3, 4}, {0, 0, 1}, {0, 1, 2}, {5, 4, 3}};  // repeated index, duplicate
  return Mesh(std::move(t), std::move(p));
}

void expect_identical(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.vertex_count(), b.vertex_count());
  for (std::size_t v = 0; v < a.vertex_count(); ++v)
    for (int k = 0; k < 3; ++k)
      EXPECT_TRUE(same_bits(a.position(v)[k], b.position(v)[k]))
          << "vertex " << v << " coordinate " << k << ": " << a.position(v)[k] << " vs " << b.position(v)[k];
  ASSERT_EQ(a.triangle_count(), b.triangle_count());
  for (std::size_t t = 0; t < a.triangle_count(); ++t) EXPECT_EQ(a.triangle(t), b.triangle(t)) << "triangle " << t;
}

TEST_F(IoWrite, RoundTripsAreBitExactInEveryFormat) {
  const Mesh m = tricky_mesh();
  const std::pair<const char*, bool> cases[] = {{"m.off", true}, {"m.obj", true}, {"m.ply", true},
                                                {"ascii.ply", false}, {"UPPER.OFF", true}};
  for (const auto& [file, binary] : cases) {
    WriteOptions opt;
    opt.ply_binary = binary;
    write_mesh(dir_ / file, m, opt);
    const LoadedMesh back = read_mesh(dir_ / file);
    SCOPED_TRACE(file);
    expect_identical(m, back.mesh);
    EXPECT_EQ(back.report.faces, m.triangle_count());
    EXPECT_EQ(back.report.binary, std::string(file) == "m.ply");
  }
}

TEST_F(IoWrite, RandomBitPatternsRoundTrip) {
  std::mt19937_64 rng(12345);
  std::vector<Vec3> p;
  while (p.size() < 3000) {
    Vec3 v;
    for (int k = 0; k < 3; ++k) {
      double d;
      do {
        const std::uint64_t bits = rng();
        std::memcpy(&d, &bits, sizeof d);
      } while (!std::isfinite(d));
      v[k] = d;
    }
    p.push_back(v);
  }
  std::vector<Tri> t;
  for (std::uint32_t i = 0; i + 2 < p.size(); i += 3) t.push_back({i, i + 1, i + 2});
  const Mesh m(std::move(t), std::move(p));
  for (const char* file : {"r.off", "r.obj", "r.ply"}) {
    write_mesh(dir_ / file, m);
    SCOPED_TRACE(file);
    expect_identical(m, read_mesh(dir_ / file).mesh);
  }
  WriteOptions ascii;
  ascii.ply_binary = false;
  write_mesh(dir_ / "ra.ply", m, ascii);
  expect_identical(m, read_mesh(dir_ / "ra.ply").mesh);
}

TEST_F(IoWrite, PlyFaceValuesBinaryDecodedByHand) {
  const Mesh m = tricky_mesh();
  const std::vector<std::int32_t> values{7, -1, 2147483647, -2147483647 - 1, 0};
  WriteOptions opt;
  opt.face_values = values;
  opt.face_value_name = "segment";
  write_mesh(dir_ / "v.ply", m, opt);
  const std::string s = slurp(dir_ / "v.ply");
  const std::size_t data = s.find("end_header\n") + 11;
  const std::string header = s.substr(0, data);
  EXPECT_NE(header.find("format binary_little_endian 1.0\n"), std::string::npos) << header;
  EXPECT_NE(header.find("element vertex 6\nproperty double x\nproperty double y\nproperty double z\n"),
            std::string::npos)
      << header;
  EXPECT_NE(header.find("element face 5\nproperty list uchar int vertex_indices\nproperty int segment\n"),
            std::string::npos)
      << header;
  ASSERT_EQ(s.size(), data + 6 * 24 + 5 * (1 + 12 + 4));
  for (std::size_t v = 0; v < 6; ++v)
    for (int k = 0; k < 3; ++k) {
      double d;
      std::memcpy(&d, s.data() + data + 24 * v + 8 * k, 8);
      EXPECT_TRUE(same_bits(d, m.position(v)[k]));
    }
  for (std::size_t f = 0; f < 5; ++f) {
    const char* rec = s.data() + data + 6 * 24 + 17 * f;
    EXPECT_EQ(rec[0], 3);
    std::int32_t idx[3], value;
    std::memcpy(idx, rec + 1, 12);
    std::memcpy(&value, rec + 13, 4);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(static_cast<std::uint32_t>(idx[k]), m.triangle(f)[k]);
    EXPECT_EQ(value, values[f]) << "face " << f;
  }
  // And our reader skips the extra face property.
  expect_identical(m, read_mesh(dir_ / "v.ply").mesh);
}

TEST_F(IoWrite, PlyFaceValuesAsciiDecodedByHand) {
  const Mesh m = tricky_mesh();
  const std::vector<std::int32_t> values{3, 1, 4, 1, -5};
  WriteOptions opt;
  opt.face_values = values;
  opt.ply_binary = false;
  write_mesh(dir_ / "v.ply", m, opt);
  std::istringstream in(slurp(dir_ / "v.ply"));
  std::string line;
  bool has_property = false;
  while (std::getline(in, line) && line != "end_header") has_property |= line == "property int cluster_id";
  EXPECT_TRUE(has_property);
  for (int v = 0; v < 6; ++v) std::getline(in, line);
  for (std::size_t f = 0; f < 5; ++f) {
    int n = 0;
    long a = 0, b = 0, c = 0, value = 0;
    in >> n >> a >> b >> c >> value;
    EXPECT_EQ(n, 3);
    EXPECT_EQ((Tri{static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b), static_cast<std::uint32_t>(c)}),
              m.triangle(f));
    EXPECT_EQ(value, values[f]) << "face " << f;
  }
  expect_identical(m, read_mesh(dir_ / "v.ply").mesh);
}

TEST_F(IoWrite, BadOptionsThrowAndLeaveTheExistingFileAlone) {
  const Mesh m = tricky_mesh();
  const std::vector<std::int32_t> five(5, 1), four(4, 1);
  const auto expect_error = [&](const fs::path& p, const WriteOptions& opt, const std::string& part) {
    spit(p, "old content");
    try {
      write_mesh(p, m, opt);
      ADD_FAILURE() << "no InputError for " << p;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), p.string());
      EXPECT_NE(e.reason().find(part), std::string::npos) << e.what();
    }
    EXPECT_EQ(slurp(p), "old content");
  };
  WriteOptions off_values;
  off_values.face_values = five;
  expect_error(dir_ / "a.off", off_values, "face values can only be written to PLY");
  expect_error(dir_ / "a.obj", off_values, "face values can only be written to PLY");
  WriteOptions mismatch;
  mismatch.face_values = four;
  expect_error(dir_ / "a.ply", mismatch, "face values have 4 entries for 5 triangles");
  WriteOptions bad_name;
  bad_name.face_values = five;
  bad_name.face_value_name = "cluster id";
  expect_error(dir_ / "a.ply", bad_name, "not a single word");
  bad_name.face_value_name = "vertex_indices";
  expect_error(dir_ / "a.ply", bad_name, "clashes");
  expect_error(dir_ / "a.xyz", {}, "unknown mesh format '.xyz'");
  expect_error(dir_ / "a", {}, "unknown mesh format (no extension)");
  expect_error(dir_ / "a.stl", {}, "writing STL is not supported");
  EXPECT_EQ(entries(dir_), (std::vector<std::string>{"a", "a.obj", "a.off", "a.ply", "a.stl", "a.xyz"}));
}

TEST_F(IoWrite, UnwritableTargets) {
  const Mesh m = tricky_mesh();
  try {
    write_mesh(dir_ / "missing_dir" / "m.off", m);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), (dir_ / "missing_dir" / "m.off").string());
    EXPECT_NE(e.reason().find("cannot write it: the directory '" + (dir_ / "missing_dir").string() + "' does not exist"),
              std::string::npos)
        << e.what();
  }
  fs::create_directory(dir_ / "d.off");
  try {
    write_mesh(dir_ / "d.off", m);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.reason(), "is a directory");
  }
  EXPECT_EQ(entries(dir_), (std::vector<std::string>{"d.off"}));
}

TEST_F(IoWrite, AtomicFileReplacesOnlyOnCommit) {
  const fs::path target = dir_ / "t.txt";
  spit(target, "old");
  ::chmod(target.c_str(), 0640);
  fs::path temp;
  {
    AtomicFile f(target);
    temp = f.temp_path();
    EXPECT_EQ(temp.parent_path(), dir_);
    EXPECT_EQ(temp.filename().string().rfind(".t.txt.tmp-" + std::to_string(::getpid()) + "-", 0), 0u) << temp;
    f.write("new, never committed");
    EXPECT_TRUE(fs::exists(temp));
    EXPECT_EQ(slurp(target), "old");
  }  // destroyed without commit
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_EQ(slurp(target), "old");
  EXPECT_EQ(entries(dir_), (std::vector<std::string>{"t.txt"}));

  {
    AtomicFile a(target), b(target);  // two writers at once get distinct temporaries
    EXPECT_NE(a.temp_path(), b.temp_path());
    a.write("from a");
    b.write("from b");
    a.commit();
    EXPECT_TRUE(a.committed());
    EXPECT_EQ(slurp(target), "from a");
    b.commit();
  }
  EXPECT_EQ(slurp(target), "from b");
  EXPECT_EQ(entries(dir_), (std::vector<std::string>{"t.txt"}));
  struct stat st {};
  ASSERT_EQ(::stat(target.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);  // the replaced file's permissions are kept

  AtomicFile c(target);
  c.commit();
  EXPECT_THROW(c.commit(), InputError);
  EXPECT_THROW(c.write("x"), InputError);
  EXPECT_EQ(slurp(target), "");
}

// Written behind (every 8 MiB the chunk before leaves the page cache): the file holds every byte
// in order, from pieces of every size across the chunk boundaries (1 byte, odd sizes, one piece
// of 20 MiB, a piece ending exactly on a boundary), and a file never committed still goes away.
TEST_F(IoWrite, AtomicFileWrittenBehindHoldsEveryByte) {
  std::mt19937 rng(5);
  std::string all;
  const fs::path target = dir_ / "big.bin";
  {
    AtomicFile f(target);
    auto piece = [&](std::size_t n) {
      std::string b(n, '\0');
      for (char& c : b) c = static_cast<char>(rng());
      f.write(b);
      all += b;
    };
    piece(1);
    piece((std::size_t{8} << 20) - 1);  // ends exactly on the first boundary
    for (int k = 0; k < 40; ++k) piece(1 + rng() % 700000);
    piece(std::size_t{20} << 20);
    piece(3);
    f.commit();
  }
  ASSERT_GT(all.size(), std::size_t{36} << 20);  // several chunks
  EXPECT_TRUE(slurp(target) == all);
  EXPECT_EQ(entries(dir_), (std::vector<std::string>{"big.bin"}));
  fs::path temp;
  {
    AtomicFile g(dir_ / "never.bin");
    temp = g.temp_path();
    g.write(std::string(std::size_t{17} << 20, 'x'));
  }
  EXPECT_FALSE(fs::exists(temp));
  EXPECT_EQ(entries(dir_), (std::vector<std::string>{"big.bin"}));
}

TEST_F(IoWrite, AtomicFileCommitFailureKeepsTheTarget) {
  // The target becomes a non-empty directory between creation and commit: rename fails.
  const fs::path target = dir_ / "x.off";
  AtomicFile f(target);
  f.write("data");
  fs::create_directories(target / "inside");
  try {
    f.commit();
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), target.string());
    EXPECT_NE(e.reason().find("cannot rename"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_directory(target / "inside"));
  EXPECT_EQ(entries(dir_), (std::vector<std::string>{"x.off"}));  // temporary removed
}

}  // namespace
}  // namespace ptc
