#include "commands/inputs.h"

#include <cstdio>
#include <fstream>
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
  nlohmann::json in;
  in["path"] = path.string();
  in["absolute_path"] = fs::absolute(path, ec).string();
  in["bytes"] = fs::file_size(path, ec);
  in["fnv1a64"] = file_fnv1a64(path);
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
