#include "toolkit/io/mesh_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>

#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/io/readers.h"
#include "toolkit/core/input_log.h"

namespace ptc {

std::string_view to_string(MeshFormat f) {
  switch (f) {
    case MeshFormat::Off: return "off";
    case MeshFormat::Obj: return "obj";
    case MeshFormat::Ply: return "ply";
    case MeshFormat::Stl: return "stl";
  }
  return "?";
}

std::optional<MeshFormat> parse_mesh_format(std::string_view s) {
  for (MeshFormat f : {MeshFormat::Off, MeshFormat::Obj, MeshFormat::Ply, MeshFormat::Stl})
    if (to_string(f) == s) return f;
  return std::nullopt;
}

namespace {

// A path's extension in lower case (".OFF" -> ".off").
std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return ext;
}

// Extensions of the animated assets other commands read (toolkit/anim: MD2, MD3 and Assimp's).
bool is_animated_asset_extension(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  for (const char* e : {".md2", ".md3", ".md5mesh", ".x", ".3ds", ".fbx", ".dae", ".gltf", ".glb", ".b3d", ".ms3d", ".smd", ".bvh"})
    if (ext == e) return true;
  return false;
}

struct OpenFile {
  int fd = -1;
  struct stat st {};
  OpenFile() = default;
  OpenFile(const OpenFile&) = delete;
  OpenFile& operator=(const OpenFile&) = delete;
  ~OpenFile() {
    if (fd >= 0) ::close(fd);
  }
};

void open_input(const std::filesystem::path& path, OpenFile& f) {
  const std::string name = path.string();
  f.fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (f.fd < 0) throw InputError(name, "", "", std::string("cannot open: ") + std::strerror(errno));
  if (::fstat(f.fd, &f.st) != 0) throw InputError(name, "", "", std::string("cannot stat: ") + std::strerror(errno));
  if (S_ISDIR(f.st.st_mode)) throw InputError(name, "", "", "is a directory");
}

// The whole file in memory (one read; the parsers index into it).
std::string read_file(const std::string& name, int fd, const struct stat& st) {
  std::string data;
  if (S_ISREG(st.st_mode)) data.reserve(static_cast<std::size_t>(st.st_size));
  char buf[1 << 16];
  for (;;) {
    // Regular files: read straight into the string; pipes and the like: through a buffer.
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputError(name, byte_loc(data.size()), "", std::string("cannot read: ") + std::strerror(errno));
    }
    if (n == 0) break;
    data.append(buf, static_cast<std::size_t>(n));
  }
  return data;
}

std::atomic<ReadNoteHandler> g_note_handler{nullptr};

}  // namespace

std::optional<MeshFormat> format_from_extension(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".off") return MeshFormat::Off;
  if (ext == ".obj") return MeshFormat::Obj;
  if (ext == ".ply") return MeshFormat::Ply;
  if (ext == ".stl") return MeshFormat::Stl;
  return std::nullopt;
}

namespace io {
void check_not_utf16(std::string_view first_bytes, const std::string& name) {
  // A UTF-16 text file read as bytes has a NUL after every character: no line of it parses, and
  // the readers said only "no triangles". Its byte order mark says what it is.
  const std::string_view b = first_bytes;
  if (b.size() >= 2 && ((b[0] == '\xFE' && b[1] == '\xFF') || (b[0] == '\xFF' && b[1] == '\xFE')))
    throw InputError(name, "byte 0", "", "UTF-16 text is not supported (save the file as UTF-8 or ASCII)");
}
}  // namespace io

LoadedMesh read_mesh_from_memory(std::string_view bytes, MeshFormat f, const std::string& name) {
  if (f != MeshFormat::Stl) io::check_not_utf16(bytes, name);  // (binary STL may begin with any bytes)
  // OFF and OBJ text whose lines end in a carriage return alone (classic Mac OS): read with each
  // CR as a line end, as other loaders do (text with any '\n' is read as it is).
  std::string unix_lines;
  if ((f == MeshFormat::Off || f == MeshFormat::Obj) && bytes.find('\n') == std::string_view::npos &&
      bytes.find('\r') != std::string_view::npos) {
    unix_lines.assign(bytes);
    std::replace(unix_lines.begin(), unix_lines.end(), '\r', '\n');
    bytes = unix_lines;
  }
  switch (f) {
    case MeshFormat::Off: return io::read_off(bytes, name);
    case MeshFormat::Obj: return io::read_obj(bytes, name);
    case MeshFormat::Ply: return io::read_ply(bytes, name);
    case MeshFormat::Stl: return io::read_stl(bytes, name);
  }
  throw std::logic_error("read_mesh_from_memory: bad MeshFormat value");
}

LoadedMesh read_mesh(const std::filesystem::path& path) {
  note_input_file(path);
  if (path.empty()) throw InputError("''", "", "", "an empty file name");
  const std::optional<MeshFormat> f = format_from_extension(path);
  {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
      throw InputError(path.string(), "", "",
                       "is a directory, not a mesh file (a directory of frames is read by ptc trace, bench, viz, "
                       "experiment and animate; give one frame's file here)");
  }
  if (!f)
    throw InputError(
        path.string(), "", "",
        "unknown mesh format " +
            (path.extension().empty() ? std::string("(no extension)") : "'" + path.extension().string() + "'") +
            " (use .off, .obj, .ply or .stl" +
            (is_animated_asset_extension(path) ? "; ptc trace, bench and animate read animated assets, and `ptc animate "
                                                 "FILE --out DIR` writes their frames as .ply meshes)"
                                               : ")"));
  LoadedMesh lm;
  {
    // A FIFO or pipe may block its open and reads: a stop request ends the run at once meanwhile.
    const BlockingWaitFor waiting(path);
    OpenFile file;
    open_input(path, file);
    // A regular binary PLY file is read block by block (its body can be hundreds of MB); every
    // other file whole.
    // (A regular file that reports size 0, as procfs files do, is read to its end instead.)
    lm = *f == MeshFormat::Ply && S_ISREG(file.st.st_mode) && file.st.st_size > 0
             ? io::read_ply_file(file.fd, static_cast<std::uint64_t>(file.st.st_size), path.string())
             : read_mesh_from_memory(read_file(path.string(), file.fd, file.st), *f, path.string());
  }
  if (const ReadNoteHandler h = g_note_handler.load())
    for (const std::string& note : read_notes(lm.report)) h(path.string(), note);
  return lm;
}

std::vector<std::string> read_notes(const ReadReport& r) {
  std::vector<std::string> notes;
  if (r.short_faces > 0)
    notes.push_back(std::to_string(r.short_faces) + (r.short_faces == 1 ? " face has" : " faces have") +
                    " fewer than 3 corners and " + (r.short_faces == 1 ? "was" : "were") + " skipped (first: " +
                    r.first_short_face + ")");
  if (r.surplus_lines > 0)
    notes.push_back(std::to_string(r.surplus_lines) + (r.surplus_lines == 1 ? " line carries" : " lines carry") +
                    " more values than the header declares; the extra values were ignored (first: " +
                    r.first_surplus + ")");
  if (r.trailing_bytes >= 50)  // (room for a facet: less is padding no one would ask about)
    notes.push_back(std::to_string(r.trailing_bytes) + " bytes after the " + std::to_string(r.faces) +
                    (r.faces == 1 ? " facet" : " facets") + " the header counts were ignored (room for " +
                    std::to_string(r.trailing_bytes / 50) + " more; a header with too small a count drops them)");
  return notes;
}

void set_read_note_handler(ReadNoteHandler h) { g_note_handler.store(h); }

void read_note(const std::string& file, const std::string& note) {
  if (const ReadNoteHandler h = g_note_handler.load()) h(file, note);
}

}  // namespace ptc
