// Quake III MD3 models, read by our own parser (assimp's MD3 importer reads one keyframe only).
//
// Format (little endian; offsets in bytes; https://icculus.org/homepages/phaethon/q3a/formats/md3format.html):
//   header (108): "IDP3", version 15, name[64], flags, num_frames, num_tags, num_surfaces,
//                 num_skins, ofs_frames, ofs_tags, ofs_surfaces, ofs_end
//   frame  (56):  bounds min/max, local origin, radius, name[16]
//   tag    (112): name[64], origin, axis[3][3]               (per frame and tag; not used here)
//   surface (at ofs_surfaces, then chained by ofs_end; offsets relative to the surface start):
//     header (108): "IDP3", name[64], flags, num_frames, num_shaders, num_verts, num_triangles,
//                   ofs_triangles, ofs_shaders, ofs_st, ofs_xyznormal, ofs_end
//     triangles (12 each): three int32 vertex indices into the surface
//     xyznormal (8 each, num_frames * num_verts, frame-major): int16 x, y, z (units of 1/64), normal
// All surfaces of frame k form one mesh: surface vertices are concatenated in file order.
//
// Every defect of the file (truncated, bad magic/version, counts or offsets outside the file,
// a surface whose frame count differs from the header's, vertex indices out of range) is an
// InputError naming the file, the byte offset and the field.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "toolkit/anim/animation.h"

namespace ptc {

struct Md3Surface {
  std::string name;
  std::uint32_t first_vertex = 0;  ///< offset of this surface's vertices in the concatenated mesh
  std::uint32_t vertex_count = 0;
  std::uint32_t triangle_count = 0;
};

/// The file's content in its own coordinates (Quake: z up), positions already scaled by 1/64.
struct Md3Model {
  std::string name;
  std::vector<Md3Surface> surfaces;
  std::vector<Tri> triangles;                 ///< corners in file order, indices into the concatenation
  std::vector<std::vector<Vec3>> frames;      ///< frames[k][v]
  std::vector<std::string> frame_names;
};

/// Parses MD3 bytes; `name` stands for the file in error messages.
[[nodiscard]] Md3Model parse_md3(std::string_view bytes, const std::string& name);
/// Reads and parses a file (InputError for a missing or unreadable file, or bad content).
[[nodiscard]] Md3Model read_md3(const std::filesystem::path& path);

/// Writes frames of one or more surfaces as MD3 (positions quantised to 1/64; InputError when a
/// coordinate does not fit int16 after scaling). A converter, and a source of test files (Debian's
/// assimp-testmodels ships no MD3). Each surface: triangles with local indices, frames[k][v].
struct Md3SurfaceData {
  std::string name;
  std::vector<Tri> triangles;
  std::vector<std::vector<Vec3>> frames;
};
[[nodiscard]] std::string encode_md3(const std::vector<Md3SurfaceData>& surfaces, const std::string& model_name);
void write_md3(const std::filesystem::path& path, const std::vector<Md3SurfaceData>& surfaces);

struct Md3Options {
  /// Rotate into assimp's convention (y up): (x, y, z) -> (x, z, -y), as assimp's MD3 importer
  /// does with its root node, so MD3 and MD2/assimp sources share one world. false = file axes.
  bool y_up = true;
  /// Triangle corners (a, c, b) instead of the file's (a, b, c), as assimp does (Quake 3 culls
  /// clockwise faces), so that front faces are counter-clockwise.
  bool flip_winding = true;
  bool weld = true;    ///< weld vertices that coincide in every frame (texture seams split them)
  double fps = 15.0;   ///< MD3 stores no rate (animation.cfg does, per animation); 15 is common
};

/// An MD3 file as a keyframe animation (frames interpolated linearly).
[[nodiscard]] AnimationPtr load_md3(const std::filesystem::path& path, const Md3Options& opt = {});

}  // namespace ptc
