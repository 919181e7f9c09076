// Recording the files a run read, for its manifest: the one place that hashes an input.
#pragma once

#include "toolkit/mesh/mesh.h"

#include <filesystem>
#include <string>
#include <string_view>

#include "analysis/schema/manifest.h"
#include "toolkit/io/mesh_io.h"

namespace ptc {

/// FNV-1a 64-bit hash of a file's bytes, as 16 hex digits (a cheap identity check, not a
/// cryptographic one). Throws InputError when the file cannot be read.
[[nodiscard]] std::string file_fnv1a64(const std::filesystem::path& path);
/// The same hash over bytes in memory (an output as it is written).
[[nodiscard]] std::string bytes_fnv1a64(std::string_view bytes);
/// The same hash over a mesh as loaded: its triangles' indices and its positions' bits (what a
/// scene built from assets or data files really holds, whatever files it came from).
[[nodiscard]] std::string mesh_fnv1a64(const Mesh& mesh);

/// Adds {path, absolute_path, bytes, fnv1a64} of `path` to the manifest's inputs.
void record_input(RunManifest& manifest, const std::filesystem::path& path);

/// read_mesh(path), recording the read time ("read") and the input in the manifest.
[[nodiscard]] LoadedMesh read_mesh_recorded(const std::filesystem::path& path, RunManifest& manifest);

}  // namespace ptc
