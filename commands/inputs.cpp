#include "commands/inputs.h"

#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"

namespace ptc {
namespace fs = std::filesystem;

namespace {

// FNV-1a, 64 bits, over bytes fed in any number of pieces; hex() is the manifests' spelling.
struct Fnv1a64 {
  std::uint64_t h = 14695981039346656037ull;  // offset basis
  void add(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) h ^= b[i], h *= 1099511628211ull;
  }
  [[nodiscard]] std::string hex() const {
    char out[17];
    std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(h));
    return out;
  }
};

}  // namespace

std::string mesh_fnv1a64(const Mesh& mesh) {
  Fnv1a64 f;
  for (const Tri& t : mesh.triangles()) f.add(t.data(), sizeof(Tri));
  for (const Vec3& v : mesh.positions()) f.add(v.data(), 3 * sizeof(double));
  return f.hex();
}

std::string read_text(const std::filesystem::path& f, const char* why) {
  const BlockingWaitFor waiting(f);  // (a FIFO: a stop request ends the run at once meanwhile)
  std::ifstream in(f, std::ios::binary);
  if (!in) throw InputError(f.string(), "", "", std::string("cannot read it (") + why + ")");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

nlohmann::json read_experiment_manifest(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) throw InputError(dir.string(), "", "", "no such directory");
  if (!fs::is_directory(dir, ec)) throw InputError(dir.string(), "", "", "is a file: give the directory of a `ptc experiment` run");
  const fs::path f = dir / "manifest.json";
  const std::string text = read_text(f, "is the directory an output of `ptc experiment`?");
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // nlohmann's message without its "[json.exception.parse_error.101] " prefix; the byte it stopped at.
    std::string why = e.what();
    if (const auto k = why.find("] "); k != std::string::npos) why = why.substr(k + 2);
    const auto* pe = dynamic_cast<const nlohmann::json::parse_error*>(&e);
    throw InputError(f.string(), pe ? json_byte_loc(pe->byte) : std::string(), "", "not valid JSON: " + why);
  }
}

void check_output_hash(const nlohmann::json& manifest, const std::string& name, const std::string& fnv1a64,
                       const std::filesystem::path& path) {
  if (!manifest.is_object() || !manifest.contains("output_hashes")) return;
  const nlohmann::json& all = manifest.at("output_hashes");
  if (!all.is_object() || !all.contains(name)) return;
  const nlohmann::json& h = all.at(name);
  if (h.is_object() && h.contains("fnv1a64") && h.at("fnv1a64").is_string() && h.at("fnv1a64").get<std::string>() != fnv1a64)
    throw InputError(path.string(), "", "", "its bytes differ from the FNV-1a hash its manifest records (an edited or replaced file)");
}

std::string bytes_fnv1a64(std::string_view bytes) {
  Fnv1a64 f;
  f.add(bytes.data(), bytes.size());
  return f.hex();
}

std::string file_fnv1a64(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "", "", "cannot open file");
  Fnv1a64 f;
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    f.add(buf.data(), static_cast<std::size_t>(in.gcount()));
  }
  return f.hex();
}

void record_input(RunManifest& manifest, const fs::path& path) {
  std::error_code ec;
  record_input(manifest, path, fs::file_size(path, ec), file_fnv1a64(path));  // (size -1 when unknown, as before)
}

void record_input(RunManifest& manifest, const fs::path& path, std::uint64_t bytes, const std::string& fnv1a64) {
  std::error_code ec;
  nlohmann::json in;
  in["path"] = path.string();
  in["absolute_path"] = fs::absolute(path, ec).string();
  in["bytes"] = bytes;
  in["fnv1a64"] = fnv1a64;
  manifest.add_input(std::move(in));
}

LoadedMesh read_mesh_recorded(const fs::path& path, RunManifest& manifest) {
  Stopwatch sw;
  LoadedMesh lm = read_mesh(path);
  manifest.add_timing_ms("read", sw.ms());
  record_input(manifest, path);
  throw_if_cancelled();  // reading a large mesh takes seconds
  return lm;
}

}  // namespace ptc
