// Writers for OFF, OBJ and PLY (ascii or binary little endian). Doubles are printed with
// std::to_chars' shortest round-trip form, so a written file reads back bit-identical; binary
// PLY stores them as they are. Output goes through AtomicFile in chunks of about 1 MiB.
#include <bit>
#include <charconv>
#include <cstring>
#include <string>

#include "toolkit/core/error.h"
#include "toolkit/io/atomic_file.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {
namespace {

class ChunkedWriter {
 public:
  explicit ChunkedWriter(AtomicFile& f) : file_(f) { buf_.reserve(kChunk + 256); }
  void put(std::string_view s) {
    buf_.append(s);
    spill();
  }
  void put(char c) { buf_.push_back(c); }
  void put_double(double v) {
    char tmp[32];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
    buf_.append(tmp, r.ptr);
  }
  template <class T>
  void put_int(T v) {
    char tmp[24];
    const auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
    buf_.append(tmp, r.ptr);
  }
  template <class T>
  void put_le(T v) {  // binary little endian
    static_assert(std::is_trivially_copyable_v<T>);
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if constexpr (std::endian::native == std::endian::big)
      for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
    buf_.append(b, sizeof(T));
  }
  /// Call after each record.
  void spill() {
    if (buf_.size() >= kChunk) {
      file_.write(buf_);
      buf_.clear();
    }
  }
  void finish() {
    file_.write(buf_);
    buf_.clear();
    file_.commit();
  }

 private:
  static constexpr std::size_t kChunk = 1 << 20;
  AtomicFile& file_;
  std::string buf_;
};

void write_xyz(ChunkedWriter& w, const Vec3& p) {
  w.put_double(p.x());
  w.put(' ');
  w.put_double(p.y());
  w.put(' ');
  w.put_double(p.z());
}

void write_off(ChunkedWriter& w, const Mesh& m) {
  w.put("OFF\n");
  w.put_int(m.vertex_count());
  w.put(' ');
  w.put_int(m.triangle_count());
  w.put(" 0\n");
  for (const Vec3& p : m.positions()) {
    write_xyz(w, p);
    w.put('\n');
    w.spill();
  }
  for (const Tri& t : m.triangles()) {
    w.put("3 ");
    w.put_int(t[0]);
    w.put(' ');
    w.put_int(t[1]);
    w.put(' ');
    w.put_int(t[2]);
    w.put('\n');
    w.spill();
  }
}

void write_obj(ChunkedWriter& w, const Mesh& m) {
  for (const Vec3& p : m.positions()) {
    w.put("v ");
    write_xyz(w, p);
    w.put('\n');
    w.spill();
  }
  for (const Tri& t : m.triangles()) {
    w.put("f ");
    w.put_int(std::uint64_t{t[0]} + 1);
    w.put(' ');
    w.put_int(std::uint64_t{t[1]} + 1);
    w.put(' ');
    w.put_int(std::uint64_t{t[2]} + 1);
    w.put('\n');
    w.spill();
  }
}

void write_ply(ChunkedWriter& w, const Mesh& m, const WriteOptions& opt) {
  const bool values = !opt.face_values.empty();
  w.put("ply\nformat ");
  w.put(opt.ply_binary ? "binary_little_endian" : "ascii");
  w.put(" 1.0\ncomment written by ptc\nelement vertex ");
  w.put_int(m.vertex_count());
  w.put("\nproperty double x\nproperty double y\nproperty double z\nelement face ");
  w.put_int(m.triangle_count());
  w.put("\nproperty list uchar int vertex_indices\n");
  if (values) {
    w.put("property int ");
    w.put(opt.face_value_name);
    w.put('\n');
  }
  w.put("end_header\n");
  const auto tris = m.triangles();
  if (opt.ply_binary) {
    for (const Vec3& p : m.positions()) {
      w.put_le(p.x());
      w.put_le(p.y());
      w.put_le(p.z());
      w.spill();
    }
    for (std::size_t i = 0; i < tris.size(); ++i) {
      w.put_le(std::uint8_t{3});
      for (std::uint32_t v : tris[i]) w.put_le(static_cast<std::int32_t>(v));
      if (values) w.put_le(opt.face_values[i]);
      w.spill();
    }
    return;
  }
  for (const Vec3& p : m.positions()) {
    write_xyz(w, p);
    w.put('\n');
    w.spill();
  }
  for (std::size_t i = 0; i < tris.size(); ++i) {
    w.put("3 ");
    w.put_int(tris[i][0]);
    w.put(' ');
    w.put_int(tris[i][1]);
    w.put(' ');
    w.put_int(tris[i][2]);
    if (values) {
      w.put(' ');
      w.put_int(opt.face_values[i]);
    }
    w.put('\n');
    w.spill();
  }
}

}  // namespace

void write_mesh(const std::filesystem::path& path, const Mesh& mesh, const WriteOptions& opt) {
  const std::string name = path.string();
  const std::optional<MeshFormat> f = format_from_extension(path);
  if (!f || *f == MeshFormat::Stl)
    throw InputError(name, "", "",
                     (f ? std::string("writing STL is not supported")
                        : "unknown mesh format " + (path.extension().empty() ? std::string("(no extension)")
                                                                             : "'" + path.extension().string() + "'")) +
                         " (use .off, .obj or .ply)");
  if (!opt.face_values.empty()) {
    if (*f != MeshFormat::Ply) throw InputError(name, "", "", "face values can only be written to PLY");
    if (opt.face_values.size() != mesh.triangle_count())
      throw InputError(name, "", "",
                       "face values have " + std::to_string(opt.face_values.size()) + " entries for " +
                           std::to_string(mesh.triangle_count()) + " triangles");
    const std::string& n = opt.face_value_name;
    bool word = !n.empty();
    for (char c : n) word = word && static_cast<unsigned char>(c) > ' ' && c != 0x7f;
    if (!word) throw InputError(name, "", "", "face value name '" + n + "' is not a single word");
    if (n == "vertex_indices" || n == "vertex_index")
      throw InputError(name, "", "", "face value name '" + n + "' clashes with the face's index list");
  }
  if (*f == MeshFormat::Ply && mesh.vertex_count() > static_cast<std::size_t>(INT32_MAX))
    throw InputError(name, "", "",
                     "PLY 'int' indices cannot number " + std::to_string(mesh.vertex_count()) + " vertices");

  AtomicFile file(path);
  ChunkedWriter w(file);
  switch (*f) {
    case MeshFormat::Off: write_off(w, mesh); break;
    case MeshFormat::Obj: write_obj(w, mesh); break;
    case MeshFormat::Ply: write_ply(w, mesh, opt); break;
    case MeshFormat::Stl: break;
  }
  w.finish();
}

}  // namespace ptc
