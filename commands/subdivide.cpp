// `ptc subdivide`.
#include "commands/commands.h"

#include <filesystem>
#include <iostream>
#include <ostream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/schema/json.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"
#include "commands/output_dir.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/core/strings.h"

namespace ptc {

void cmd_subdivide(const SubdivideOptions& opt, std::ostream& out) {
  {
    std::error_code dir_ec;
    if (std::filesystem::is_directory(opt.output, dir_ec))
      throw UsageError("--out", "'" + opt.output.string() + "' is a directory: give the output mesh's file name (.off, .obj or .ply)");
    // The file is written whole under a temporary name and renamed over the target: a FIFO, a
    // device or a socket there would be replaced by a regular file, not written to.
    namespace fs = std::filesystem;
    const fs::file_status st = fs::symlink_status(opt.output, dir_ec);
    if (fs::exists(st) && !fs::is_regular_file(st) && !fs::is_symlink(st)) {
      const char* kind = fs::is_fifo(st) ? "a FIFO" : fs::is_socket(st) ? "a socket"
                         : fs::is_character_file(st) || fs::is_block_file(st) ? "a device" : "not a regular file";
      throw UsageError("--out", "'" + opt.output.string() + "' is " + kind +
                                    ": ptc writes a mesh whole and renames it into place, which would replace it; give a file name");
    }
  }
  if (const auto f = format_from_extension(opt.output); !f || *f == MeshFormat::Stl)
    throw UsageError("--out", "'" + opt.output.string() + "': cannot write this format (use .off, .obj or .ply)");
  refuse_overwriting_input(opt.output, opt.input);
  Stopwatch t0;
  const LoadedMesh lm = read_mesh(opt.input);
  const double read_ms = t0.ms();
  throw_if_cancelled();  // between stages; write_mesh polls per chunk
  t0.restart();
  // The subdivider's errors name the element (edge, triangle, levels) but not the file.
  const Subdivider sub = [&] {
    try {
      return Subdivider::build(lm.mesh.triangles(), lm.mesh.vertex_count(), opt.scheme, opt.levels);
    } catch (const InputError& e) {
      if (!e.file().empty()) throw;
      throw InputError(opt.input.string(), e.location(), e.element() == "levels" ? "--levels" : e.element(), e.reason());
    }
  }();
  throw_if_cancelled();
  const Mesh refined = sub.apply(lm.mesh);
  const double sub_ms = t0.ms();
  t0.restart();
  std::error_code ec;
  // A symbolic link is replaced by the file (the rename replaces the link, not what it points to).
  const bool link = std::filesystem::is_symlink(opt.output, ec);
  const std::filesystem::path pointed = link ? std::filesystem::read_symlink(opt.output, ec) : std::filesystem::path();
  const bool replaced = !link && std::filesystem::is_regular_file(opt.output, ec);
  write_mesh(opt.output, refined);  // whole or not at all (a temporary file renamed)
  if (replaced) std::cerr << "ptc: note: replaced the existing " << opt.output.string() << "\n";
  if (link)
    std::cerr << "ptc: note: replaced the symbolic link " << opt.output.string() << " (to " << pointed.string()
              << ", which is untouched) by the file\n";
  const double write_ms = t0.ms();
  if (opt.json) {
    nlohmann::json j{{"input", opt.input.string()},       {"output", opt.output.string()},
                     {"scheme", to_string(opt.scheme)},   {"levels", opt.levels},
                     {"triangles_in", lm.mesh.triangle_count()}, {"vertices_in", lm.mesh.vertex_count()},
                     {"triangles_out", refined.triangle_count()}, {"vertices_out", refined.vertex_count()},
                     {"read_ms", read_ms},                {"subdivide_ms", sub_ms},
                     {"write_ms", write_ms}};
    out << dump_json(j);
  } else {
    out << fmt::format("{}: {}, {} -> {} x{} -> {}: {}, {} ({:.0f} ms)\n", opt.input.string(),
                       counted(lm.mesh.triangle_count(), "triangle"), counted(lm.mesh.vertex_count(), "vertex", "vertices"),
                       to_string(opt.scheme), opt.levels, opt.output.string(), counted(refined.triangle_count(), "triangle"),
                       counted(refined.vertex_count(), "vertex", "vertices"), sub_ms);
  }
}

}  // namespace ptc
