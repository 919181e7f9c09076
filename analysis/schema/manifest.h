// The JSON run manifest written next to every CSV, so that every number a user sees can be
// traced to its run: command line, inputs (size, hash), parameters, versions of ptc and of
// every library, machine, timings, the files the run wrote and the schema of every table.
// Data only: the inputs' hashes are computed where files are opened (commands/inputs.h).
#pragma once

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "analysis/schema/json.h"
#include "toolkit/core/stopwatch.h"

namespace ptc {

/// Versions of ptc (with the git commit it was built from) and of every library it links.
[[nodiscard]] nlohmann::json build_info();
/// Host name, CPU model, logical cores, memory, kernel.
[[nodiscard]] nlohmann::json machine_info();

class RunManifest {
 public:
  /// `command`: the subcommand ("spheres"); `argv`: the full command line as given.
  /// `schema`: the manifest's own schema, one per command ("ptc-bench/3"): what its parameters
  /// and results hold (docs/tables.md).
  RunManifest(std::string command, std::vector<std::string> argv, std::string schema = "ptc-manifest/1");

  /// An input's record (commands/inputs.h record_input: path, absolute path, bytes, FNV-1a hash).
  void add_input(nlohmann::json entry) { inputs_.push_back(std::move(entry)); }
  void set_parameter(const std::string& key, nlohmann::json value) { parameters_[key] = std::move(value); }
  /// A stage's time; also records the process's peak resident memory so far at the stage's end
  /// (peak_rss_mb[key], Linux VmHWM: a stage that raised it reached that peak) and its resident
  /// memory then (rss_mb[key], VmRSS). The peak is never reset, so /usr/bin/time agrees.
  void add_timing_ms(const std::string& key, double ms);
  /// A file the run wrote; `schema` ("ptc-bench/1") for a table (listed under output_schemas).
  void add_output(const std::string& file, const std::string& schema = "");
  /// The bytes and FNV-1a hash of an output (listed under output_hashes): what `ptc merge` checks
  /// a shard's tables against, so that an edited table is refused.
  void add_output_hash(const std::string& file, std::size_t bytes, const std::string& fnv1a64) {
    output_hashes_[file] = {{"bytes", bytes}, {"fnv1a64", fnv1a64}};
  }
  void set_result(const std::string& key, nlohmann::json value) { results_[key] = std::move(value); }

  [[nodiscard]] nlohmann::json to_json() const;

 private:
  std::string command_, schema_;
  std::vector<std::string> argv_;
  std::string started_utc_;
  Stopwatch since_start_;
  nlohmann::json inputs_ = nlohmann::json::array();
  nlohmann::json parameters_ = nlohmann::json::object();
  nlohmann::json timings_ = nlohmann::json::object();
  nlohmann::json peak_rss_mb_ = nlohmann::json::object();
  nlohmann::json rss_mb_ = nlohmann::json::object();
  nlohmann::json results_ = nlohmann::json::object();
  std::vector<std::string> outputs_;
  nlohmann::json schemas_ = nlohmann::json::object();
  nlohmann::json output_hashes_ = nlohmann::json::object();
};

}  // namespace ptc
