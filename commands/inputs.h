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

/// The bytes of `f`; InputError naming it ("cannot read it (`why`)") when it cannot be read.
[[nodiscard]] std::string read_text(const std::filesystem::path& f, const char* why);
/// DIR/manifest.json of a `ptc experiment` run (merge's shards, the notebook's studies), parsed;
/// InputError naming DIR when it does not exist or is a file, the manifest when it cannot be read
/// or is not JSON.
[[nodiscard]] nlohmann::json read_experiment_manifest(const std::filesystem::path& dir);

/// Throws InputError naming `path` when `manifest` (a run's manifest.json) records an
/// output_hashes entry for `name` whose FNV-1a hash is not `fnv1a64` (the file as read now).
/// Manifests without the entry (written before 2026-12-04) pass.
void check_output_hash(const nlohmann::json& manifest, const std::string& name, const std::string& fnv1a64,
                       const std::filesystem::path& path);

/// Adds {path, absolute_path, bytes, fnv1a64} of `path` to the manifest's inputs.
void record_input(RunManifest& manifest, const std::filesystem::path& path);
/// The same for a file already read whole: its size and hash (bytes_fnv1a64) as given.
void record_input(RunManifest& manifest, const std::filesystem::path& path, std::uint64_t bytes, const std::string& fnv1a64);

/// read_mesh(path), recording the read time ("read") and the input in the manifest.
[[nodiscard]] LoadedMesh read_mesh_recorded(const std::filesystem::path& path, RunManifest& manifest);

}  // namespace ptc
