#include "fuzz/targets.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands/cluster_files.h"
#include "toolkit/anim/assimp_source.h"
#include "toolkit/anim/load_animation.h"
#include "toolkit/anim/md3.h"
#include "toolkit/anim/scene_file.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/mesh_report.h"

namespace ptc::fuzz {
namespace {

namespace fs = std::filesystem;

fs::path scratch_path() { return fs::temp_directory_path() / ("ptc-fuzz-" + std::to_string(::getpid())); }

// The process's own scratch directory (created on first use, removed at exit).
const fs::path& scratch() {
  static const fs::path dir = [] {
    const fs::path d = scratch_path();
    fs::remove_all(d);
    fs::create_directories(d);
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(scratch_path(), ec);
    });
    return d;
  }();
  return dir;
}

void spit(const fs::path& p, std::string_view bytes) {
  std::ofstream(p, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Evaluates an animation at its first, middle and last frame.
void sample(Animation& a) {
  std::vector<Vec3> pos(a.rest().vertex_count());
  const double last = double(a.frame_count() - 1);
  for (double f : {0.0, 0.5 * last, last}) a.positions(f, pos);
}

// The mesh readers; a mesh that loads is also analysed (edges, non-manifold counts, components),
// since a reader's output is every other module's input.
void mesh(std::string_view bytes, MeshFormat f) {
  const LoadedMesh lm = read_mesh_from_memory(bytes, f, "fuzz." + std::string(to_string(f)));
  (void)read_notes(lm.report);
  (void)analyze_mesh(lm.mesh);
}

// MD2: ptc's header checks, then assimp's importer behind them. A file the checks pass must
// import without a crash: assimp trusts the header, so a crash there is a check we miss.
void md2(std::string_view bytes) {
  const fs::path path = scratch() / "model.md2";
  spit(path, bytes);
  AnimationPtr a = load_md2(path);
  sample(*a);
}

// MD3: ptc's own parser, then the keyframe animation made of it (welding, interpolation).
void md3(std::string_view bytes) {
  try {
    (void)parse_md3(bytes, "fuzz.md3");
  } catch (const InputError&) {
  }
  const fs::path path = scratch() / "model.md3";
  spit(path, bytes);
  AnimationPtr a = load_md3(path);
  sample(*a);
}

// Scene files over a stand-in data directory: small meshes under the names the built-in scenes
// and scenes/ use (meshes/armadillo.off is a tetrahedron), so that real scene files parse in
// microseconds; a scene that builds is evaluated at three frames.
void scene_json(std::string_view text) {
  static const fs::path data = [] {
    const char* tetra = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
    const fs::path d = scratch() / "data";
    fs::create_directories(d / "meshes");
    for (const char* m : {"armadillo.off", "bunny.off", "elephant.off", "camel.off", "cube.off", "m.off"})
      spit(d / "meshes" / m, tetra);
    spit(d / "m.off", tetra);
    spit(d / "cube.off", tetra);
    return d;
  }();
  SceneOptions opt;
  opt.data_dir = data;
  opt.assets_dir = data;
  Scene s = parse_scene_json(text, "fuzz.json", data, opt);
  std::vector<Vec3> pos(s.rest().vertex_count());
  const double first = double(s.frames().first);
  for (double f : {first, first + 0.5, first + 1}) s.positions(f, pos);
}

// Frame directories: the input is split into up to 8 frame files at each line "@@"; its first
// byte picks their format (off, obj, ply, stl).
void frame_dir(std::string_view bytes) {
  if (bytes.empty()) return;
  static const char* kExt[] = {"off", "obj", "ply", "stl"};
  const std::string ext = kExt[static_cast<unsigned char>(bytes[0]) % 4];
  std::string_view rest = bytes.substr(1);
  const fs::path dir = scratch() / "frames";
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (int k = 0; k < 8 && (k == 0 || !rest.empty()); ++k) {
    const std::size_t cut = rest.find("\n@@\n");
    spit(dir / ("frame_" + std::to_string(k) + "." + ext), rest.substr(0, cut));
    rest = cut == std::string_view::npos ? std::string_view{} : rest.substr(cut + 4);
  }
  AnimationPtr a = load_animation(dir.string());
  std::vector<Vec3> pos(a->rest().vertex_count());
  for (std::size_t f = 0; f < a->frame_count(); ++f) a->positions(double(f), pos);
  if (a->frame_count() > 1) a->positions(0.5, pos);
}

// A clustering read back from triangles.csv (what ptc viz, trace --clusters and the studies read),
// against two tetrahedra (8 triangles, two components).
void triangles_csv(std::string_view bytes) {
  static const Mesh two(
      {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}, {4, 6, 5}, {4, 5, 7}, {5, 6, 7}, {4, 7, 6}},
      {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(5, 0, 0), Vec3(6, 0, 0), Vec3(5, 1, 0),
       Vec3(5, 0, 1)});
  spit(scratch() / "triangles.csv", bytes);
  (void)read_clusters(scratch(), two);
}

}  // namespace

const std::vector<std::string>& target_names() {
  static const std::vector<std::string> names{"off", "obj", "ply", "stl", "md2", "md3", "scene_json", "frame_dir",
                                              "triangles_csv"};
  return names;
}

void run_target(std::string_view name, std::string_view bytes, bool input_errors) {
  try {
    if (const auto f = parse_mesh_format(name))
      mesh(bytes, *f);
    else if (name == "md2")
      md2(bytes);
    else if (name == "md3")
      md3(bytes);
    else if (name == "scene_json")
      scene_json(bytes);
    else if (name == "frame_dir")
      frame_dir(bytes);
    else if (name == "triangles_csv")
      triangles_csv(bytes);
    else
      throw std::invalid_argument("unknown fuzz target '" + std::string(name) + "'");
  } catch (const InputError&) {
    if (!input_errors) throw;
  }
}

}  // namespace ptc::fuzz
