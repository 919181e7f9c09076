#include "fuzz/seeds.h"

#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "toolkit/anim/md3.h"
#include "toolkit/io/mesh_io.h"

namespace ptc::fuzz {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
template <class T>
void put(std::string& s, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  s.append(b, sizeof(T));
}

const std::vector<Tri> kTris{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
const std::vector<Vec3> kPos{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};

// A two-frame MD2 of the tetrahedron (no skins, no texture coordinates, no GL commands).
std::string tiny_md2() {
  const std::uint32_t nv = 4, nt = 4, nf = 2, frame_size = 40 + 4 * nv;
  // One GL command (the list's terminating 0) after the frames, as real files have: assimp
  // refuses a file whose frames end at its last byte.
  const std::uint32_t ofs_tris = 68, ofs_frames = ofs_tris + 12 * nt, ofs_gl = ofs_frames + nf * frame_size,
                      ofs_end = ofs_gl + 4;
  std::string s = "IDP2";
  for (std::uint32_t v : {8u, 8u, 8u, frame_size, 0u, nv, 0u, nt, 1u, nf, 68u, 68u, ofs_tris, ofs_frames, ofs_gl, ofs_end})
    put(s, v);
  for (const Tri& t : kTris) {
    for (std::uint32_t c : t) put(s, static_cast<std::uint16_t>(c));
    for (int c = 0; c < 3; ++c) put(s, std::uint16_t{0});
  }
  for (std::uint32_t f = 0; f < nf; ++f) {
    for (float v : {1.f / 255, 1.f / 255, 1.f / 255}) put(s, v);   // scale
    for (float v : {0.f, 0.f, static_cast<float>(f)}) put(s, v);  // translate
    std::string name = "frame" + std::to_string(f);
    name.resize(16, '\0');
    s += name;
    for (const Vec3& p : kPos) {
      for (int k = 0; k < 3; ++k) s += static_cast<char>(static_cast<unsigned char>(p[k] * 255));
      s += '\0';  // normal index
    }
  }
  put(s, std::int32_t{0});  // the GL command list's end
  return s;
}

std::string binary_stl() {
  std::string s(80, ' ');
  put(s, static_cast<std::uint32_t>(kTris.size()));
  for (const Tri& t : kTris) {
    for (int k = 0; k < 3; ++k) put(s, 0.f);
    for (std::uint32_t c : t)
      for (int k = 0; k < 3; ++k) put(s, static_cast<float>(kPos[c][k]));
    put(s, std::uint16_t{0});
  }
  return s;
}

// A mesh as ptc's writer writes it (through a file: write_mesh writes files).
std::string written(const Mesh& m, const char* ext, const WriteOptions& opt = {}) {
  const fs::path p = fs::temp_directory_path() / ("ptc-seed-" + std::to_string(::getpid()) + "." + ext);
  write_mesh(p, m, opt);
  std::string b = slurp(p);
  fs::remove(p);
  return b;
}

}  // namespace

std::vector<Seed> generated_seeds() {
  std::vector<Seed> s;
  const Mesh tet(kTris, kPos);
  // Meshes: ptc's writers (binary and ascii PLY with a face value, OFF, OBJ), hand-made STL.
  s.push_back({"ply", "tet_binary.ply", written(tet, "ply")});
  WriteOptions ascii;
  ascii.ply_binary = false;
  const std::vector<std::int32_t> ids{0, 0, 1, 1};
  ascii.face_values = ids;
  s.push_back({"ply", "tet_ascii.ply", written(tet, "ply", ascii)});
  s.push_back({"off", "tet.off", written(tet, "off")});
  s.push_back({"obj", "tet.obj", written(tet, "obj")});
  s.push_back({"stl", "tet_binary.stl", binary_stl()});
  s.push_back({"stl", "tet_ascii.stl",
               "solid t\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n"
               " endfacet\nendsolid t\n"});
  // Animations.
  s.push_back({"md2", "tet.md2", tiny_md2()});
  std::vector<std::vector<Vec3>> frames{kPos, kPos};
  for (Vec3& p : frames[1]) p *= 2.0;
  s.push_back({"md3", "tet.md3", encode_md3({{"tet", kTris, frames}, {"tet2", kTris, frames}}, "tiny")});
  // Frame directories: first byte = format (0 off, 1 obj, 2 ply, 3 stl), frames split at "@@" lines.
  const std::string off = written(tet, "off"), ply = written(tet, "ply");
  s.push_back({"frame_dir", "three_off", std::string(1, '\0') + off + "\n@@\n" + off + "\n@@\n" + off});
  s.push_back({"frame_dir", "two_ply", std::string(1, '\2') + ply + "\n@@\n" + ply});
  // triangles.csv of the two-tetrahedra mesh of fuzz/targets.cpp.
  s.push_back({"triangles_csv", "two", "triangle_id,cluster_id\n0,0\n1,0\n2,0\n3,0\n4,1\n5,1\n6,1\n7,1\n"});
  s.push_back({"triangles_csv", "crlf",
               "triangle_id,cluster_id\r\n0,1\r\n1,1\r\n2,1\r\n3,1\r\n4,0\r\n5,0\r\n6,0\r\n7,0\r\n"});
  // Scenes over the stand-in data directory of fuzz/targets.cpp.
  s.push_back({"scene_json", "parts.json", R"({"schema": "ptc-scene/1", "name": "mine", "frames": [2, 5],
  "camera": {"eye": [0, 1, 5], "look_at": [0, 0, 0], "fov": 30}, "light": {"position": [3, 3, 3], "intensity": 2},
  "meshes": [{"name": "floor", "file": "m.off"},
    {"name": "spin", "file": "m.off", "subdivide": {"scheme": "loop", "levels": 1}, "deform": {"kind": "rigid", "axis": "z", "period": 10}},
    {"name": "ball", "sphere": {"center": [0, 3, 0], "radius": 0.5, "levels": 1}},
    {"name": "sheet", "cloth": {"resolution": 5, "substeps": 2}},
    {"name": "arm", "file": "${data}/meshes/armadillo.off", "deform": {"kind": "wave", "axis": "x", "direction": "y", "amplitude": 0.1}}]})"});
  s.push_back({"scene_json", "twist.json", R"({"schema": "ptc-scene/1", "frames": [0, 60],
  "meshes": [{"name": "a", "file": "${data}/meshes/armadillo.off", "subdivide": {"scheme": "midpoint", "levels": 2},
  "deform": {"kind": "twist", "axis": "y", "amplitude": 1.57, "period": 240}}]})"});
  return s;
}

}  // namespace ptc::fuzz
