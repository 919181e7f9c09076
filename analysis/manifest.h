// The JSON run manifest written next to every CSV, so that every number a user sees can be
// traced to its run: command line, inputs (size, hash), parameters, versions of ptc and of
// every library, machine, timings and the files the run wrote.
#pragma once

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace ptc {

/// JSON text for files and stdout: indented, and invalid UTF-8 (file names are bytes on Linux)
/// replaced by U+FFFD instead of throwing.
[[nodiscard]] std::string dump_json(const nlohmann::json& j);

/// FNV-1a 64-bit hash of a file's bytes, as 16 hex digits (a cheap identity check, not a
/// cryptographic one). Throws InputError when the file cannot be read.
[[nodiscard]] std::string file_fnv1a64(const std::filesystem::path& path);

/// Versions of ptc (with the git commit it was built from) and of every library it links.
[[nodiscard]] nlohmann::json build_info();
/// Host name, CPU model, logical cores, memory, kernel.
[[nodiscard]] nlohmann::json machine_info();

class RunManifest {
 public:
  /// `command`: the subcommand ("spheres"); `argv`: the full command line as given.
  RunManifest(std::string command, std::vector<std::string> argv);

  void add_input(const std::filesystem::path& path);
  void set_parameter(const std::string& key, nlohmann::json value) { parameters_[key] = std::move(value); }
  void add_timing_ms(const std::string& key, double ms) { timings_[key] = ms; }
  void add_output(const std::string& file) { outputs_.push_back(file); }
  void set_result(const std::string& key, nlohmann::json value) { results_[key] = std::move(value); }

  [[nodiscard]] nlohmann::json to_json() const;

 private:
  std::string command_;
  std::vector<std::string> argv_;
  std::string started_utc_;
  std::chrono::steady_clock::time_point t0_;
  nlohmann::json inputs_ = nlohmann::json::array();
  nlohmann::json parameters_ = nlohmann::json::object();
  nlohmann::json timings_ = nlohmann::json::object();
  nlohmann::json results_ = nlohmann::json::object();
  std::vector<std::string> outputs_;
};

}  // namespace ptc
