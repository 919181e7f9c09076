// Internal to toolkit/io: one reader per format (read_off.cpp, read_obj.cpp, read_ply.cpp,
// read_stl.cpp) and the triangle collector they share. Use mesh_io.h from outside.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

namespace ptc::io {

[[nodiscard]] LoadedMesh read_off(std::string_view bytes, const std::string& name);
[[nodiscard]] LoadedMesh read_obj(std::string_view bytes, const std::string& name);
[[nodiscard]] LoadedMesh read_ply(std::string_view bytes, const std::string& name);
[[nodiscard]] LoadedMesh read_stl(std::string_view bytes, const std::string& name);
/// Bytes read_ply_file reads at a time.
inline constexpr std::size_t kPlyWindowBytes = std::size_t{1} << 20;

/// A regular PLY file of `size` bytes open at `fd`: a binary body is read through a window of
/// `window` bytes that slides over it, instead of the whole file in memory (333 MB at 13.3M
/// triangles); the same mesh, report and errors as read_ply. An ascii body is read whole.
[[nodiscard]] LoadedMesh read_ply_file(int fd, std::uint64_t size, const std::string& name,
                                       std::size_t window = kPlyWindowBytes);

/// Throws InputError for text that starts with a UTF-16 byte order mark.
void check_not_utf16(std::string_view first_bytes, const std::string& name);

/// Largest vertex or face count a mesh can have (indices and triangle ids are 32-bit).
inline constexpr std::uint64_t kMaxElements = std::numeric_limits<std::uint32_t>::max();

/// Collects the faces of a file as triangles, fan-triangulating polygons from corner 0, and keeps
/// the counts of the ReadReport. Indices must be range-checked by the caller.
class TriangleSink {
 public:
  explicit TriangleSink(ReadReport& report) : report_(report) {}

  /// Reserve for about n triangles (callers bound n by what the file can hold).
  void reserve(std::size_t n) { tris_.reserve(n); }

  /// One file face with corners.size() >= 3.
  void add_face(std::span<const std::uint32_t> corners) {
    const auto face = static_cast<std::uint32_t>(report_.faces++);
    const std::size_t n = corners.size();
    if (n > 3) spell_out_source_faces();
    for (std::size_t k = 1; k + 1 < n; ++k) {
      tris_.push_back({corners[0], corners[k], corners[k + 1]});
      if (spelled_) report_.source_face.push_back(face);
    }
    if (n > 3) {
      ++report_.polygons;
      report_.triangles_from_polygons += n - 2;
    }
  }
  /// One file face with fewer than 3 corners (its indices checked by the caller): it keeps its
  /// face number and gives no triangle. `location()` ("line 12", "byte 80") is asked for the
  /// first one only, which is named "face 7 (line 12)".
  template <class Location>
  void skip_face(Location&& location) {
    if (report_.short_faces++ == 0) report_.first_short_face = "face " + std::to_string(report_.faces) + " (" + location() + ")";
    spell_out_source_faces();
    ++report_.faces;
  }
  void add_triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    const auto face = static_cast<std::uint32_t>(report_.faces++);
    tris_.push_back({a, b, c});
    if (spelled_) report_.source_face.push_back(face);
  }

  /// True when one more face with this many corners would overflow 32-bit face or triangle ids;
  /// callers check it (and throw with their location) before add_face / add_triangle.
  [[nodiscard]] bool full(std::size_t corners) const {
    return report_.faces >= kMaxElements || tris_.size() + (corners - 2) > kMaxElements;
  }
  [[nodiscard]] std::size_t faces() const { return report_.faces; }
  [[nodiscard]] std::size_t triangles() const { return tris_.size(); }

  std::vector<Tri>& take() { return tris_; }

 private:
  // ReadReport::source_face stays empty while triangle t is face t (a file of triangles, none
  // skipped: 4 bytes a triangle saved); the first polygon or skipped face writes out the faces so far.
  void spell_out_source_faces() {
    if (spelled_) return;
    spelled_ = true;
    report_.source_face.reserve(tris_.capacity());
    for (std::size_t t = 0; t < tris_.size(); ++t) report_.source_face.push_back(static_cast<std::uint32_t>(t));
  }

  ReadReport& report_;
  std::vector<Tri> tris_;
  bool spelled_ = false;
};

/// The loaded mesh; throws InputError "mesh has no triangles" when there are none.
inline LoadedMesh finish(std::vector<Tri>&& tris, std::vector<Vec3>&& positions, ReadReport&& report,
                         const std::string& name) {
  if (tris.empty())
    throw InputError(name, "", "",
                     report.short_faces == 0
                         ? std::string("mesh has no triangles")
                         : "mesh has no triangles (its " + std::to_string(report.short_faces) +
                               (report.short_faces == 1 ? " face has" : " faces have") + " fewer than 3 corners)");
  LoadedMesh out{Mesh(std::move(tris), std::move(positions)), std::move(report)};
  return out;
}

}  // namespace ptc::io
