// Mesh readers (OFF, OBJ, PLY, STL) and writers (OFF, OBJ, PLY) with validated input.
//
// Policy (docs/mesh_io.md has the details):
// - every defect of the *file* (truncated, garbled, NaN/Inf, bad indices, lying header counts, no
//   triangles) throws ptc::InputError naming the file, the line (text) or byte offset (binary),
//   the element ("vertex 12", "face 3", "facet 7", "header") and the reason; nothing else is
//   thrown for bad input and nothing is allocated by a count the file could not hold;
// - defects of the *mesh* (degenerate or duplicate triangles, duplicate or unreferenced vertices,
//   non-manifold edges) are kept as they are: triangle ids follow the file's face order so that
//   another module can count and report them;
// - polygons are fan-triangulated from their corner 0; STL corners with bit-identical coordinates
//   (-0.0 == 0.0) are welded into one vertex; OBJ negative indices are relative references.
// Elements are numbered from 0 in file order in every message.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "toolkit/mesh/mesh.h"

namespace ptc {

enum class MeshFormat { Off, Obj, Ply, Stl };
/// "off", "obj", "ply", "stl".
[[nodiscard]] std::string_view to_string(MeshFormat f);
[[nodiscard]] std::optional<MeshFormat> parse_mesh_format(std::string_view s);

/// What the reader found in the file besides the mesh itself.
struct ReadReport {
  MeshFormat format = MeshFormat::Off;
  bool binary = false;                      ///< PLY binary (either endianness) or binary STL
  std::size_t faces = 0;                    ///< faces/polygons/facets as stored in the file
  std::size_t polygons = 0;                 ///< faces with more than 3 corners (fan-triangulated from corner 0)
  std::size_t triangles_from_polygons = 0;  ///< triangles those polygons produced
  std::size_t welded_vertices = 0;          ///< STL: corners merged into shared vertices (corners - vertices)
  /// Per output triangle: the index of the file face it came from; empty when triangle t is face t
  /// for every t (no polygon, no skipped face: most files). `source_face_of` reads either form.
  std::vector<std::uint32_t> source_face;
  /// Faces with fewer than three corners ("f 1 2", "2 0 1", a PLY list of length 0..2): skipped,
  /// the rest of the file loaded. Their indices are still checked. They keep their face number,
  /// so `source_face` still counts faces as the file does.
  std::size_t short_faces = 0;
  std::string first_short_face;  ///< "face 7 (line 12)" of the first one, for the note
  /// ASCII PLY: element lines carrying more values than the header declares (MeshLab/VCG
  /// writers); the extra values are ignored.
  std::size_t surplus_lines = 0;
  std::string first_surplus;  ///< "face 0 (line 13): 4 extra values" of the first one
  /// Binary STL: bytes after the facets its header counts, ignored (exporters pad files; a
  /// header whose count is too small leaves whole facets there, which the note says).
  std::size_t trailing_bytes = 0;

  /// The file face triangle t came from.
  [[nodiscard]] std::size_t source_face_of(std::size_t t) const { return source_face.empty() ? t : source_face[t]; }
};

/// One line per thing a user should know about a file that was read anyway (short faces skipped,
/// surplus values ignored), without the file name; empty for a clean file.
[[nodiscard]] std::vector<std::string> read_notes(const ReadReport& r);

/// Called by read_mesh with each note of a file it read (file name, note). None by default; the
/// `ptc` program prints them on stderr. The handler may be called from several threads at once.
using ReadNoteHandler = void (*)(const std::string& file, const std::string& note);
void set_read_note_handler(ReadNoteHandler h);
/// Passes one note about an input (a file or a directory) to the handler, if one is set.
void read_note(const std::string& file, const std::string& note);

struct LoadedMesh {
  Mesh mesh;
  ReadReport report;
};

/// Reads a mesh; the format is chosen by the extension (.off .obj .ply .stl, case-insensitive).
/// Throws InputError for a missing/unreadable file, an unknown extension or any bad content.
[[nodiscard]] LoadedMesh read_mesh(const std::filesystem::path& path);

/// Same, from bytes already in memory; `name` stands for the file in error messages.
[[nodiscard]] LoadedMesh read_mesh_from_memory(std::string_view bytes, MeshFormat f, const std::string& name);

/// The format for a path's extension (case-insensitive), or nullopt.
[[nodiscard]] std::optional<MeshFormat> format_from_extension(const std::filesystem::path& path);

struct WriteOptions {
  /// Optional per-triangle integer written as a face property (PLY only); when non-empty its size
  /// must equal the mesh's triangle count.
  std::span<const std::int32_t> face_values;
  /// Name of that PLY face property (a non-empty word without whitespace).
  std::string face_value_name = "cluster_id";
  /// PLY encoding: true = binary_little_endian (default), false = ascii.
  bool ply_binary = true;
};

/// Writes .off, .obj or .ply (by extension, case-insensitive). Doubles are written so that they
/// read back bit-identical. The file is replaced atomically (see AtomicFile): a failed write
/// leaves an existing file untouched. Bad options or an unsupported extension -> InputError.
void write_mesh(const std::filesystem::path& path, const Mesh& mesh, const WriteOptions& opt = {});

}  // namespace ptc
