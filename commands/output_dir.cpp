#include "commands/output_dir.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <iostream>
#include <vector>
#include <system_error>

#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "toolkit/core/error.h"
#include "toolkit/io/atomic_file.h"

namespace ptc {
namespace fs = std::filesystem;

namespace {
constexpr const char* kMarkerHeader =
    "written by ptc: a later run with the same --out replaces the files listed below and keeps any other\n";

std::string unique_suffix() {
  static std::atomic<unsigned> counter{0};
  return std::to_string(::getpid()) + "-" + std::to_string(counter++);
}
}  // namespace

nlohmann::json commit_with_manifest(OutputDir& dir, RunManifest& manifest) {
  manifest.add_output("manifest.json");
  nlohmann::json j = manifest.to_json();
  dir.write("manifest.json", dump_json(j));
  dir.commit();
  return j;
}

void refuse_overwriting_input(const fs::path& out, const fs::path& input, std::string_view out_flag) {
  std::error_code ec;
  if (out.empty() || input.empty() || !fs::exists(input, ec)) return;
  const fs::path o = fs::weakly_canonical(out, ec), in = fs::weakly_canonical(input, ec);
  if (ec) return;
  const auto [a, b] = std::mismatch(o.begin(), o.end(), in.begin(), in.end());
  if (a == o.end())  // `out` is `input` or one of its parent directories
    throw UsageError(std::string(out_flag), "'" + out.string() + "' would overwrite the input '" + input.string() +
                                                "'; choose another output");
}

OutputDir::OutputDir(fs::path target) : target_(std::move(target)) {
  if (target_.empty()) throw UsageError("--out", "the output directory name is empty");
  target_ = target_.lexically_normal();
  if (!target_.has_filename()) target_ = target_.parent_path();  // "dir/" -> "dir"
  const std::string leaf = target_.filename().string();
  if (leaf.empty() || leaf == "." || leaf == "..")
    throw InputError(target_.string(), "", "", "not usable as an output directory name");
  std::error_code ec;
  if (fs::exists(target_, ec)) {
    if (!fs::is_directory(target_, ec)) throw InputError(target_.string(), "", "", "exists and is not a directory");
    if (!fs::is_empty(target_, ec) && !fs::exists(target_ / kMarker, ec))
      throw InputError(target_.string(), "", "",
                       "exists and is not a ptc output directory (no .ptc-output marker); refusing to replace it");
  }
  fs::path parent = target_.parent_path();
  if (!parent.empty()) {
    fs::create_directories(parent, ec);
    if (ec) throw InputError(parent.string(), "", "", "cannot create directory: " + ec.message());
  }
  tmp_ = (parent.empty() ? fs::path(".") : parent) / ("." + leaf + ".tmp-" + unique_suffix());
  fs::create_directory(tmp_, ec);
  if (ec) throw InputError(target_.string(), "", "", "cannot create the output directory: " + ec.message());
  try {
    write(kMarker, kMarkerHeader);
  } catch (...) {
    fs::remove_all(tmp_, ec);
    throw;
  }
}

OutputDir::~OutputDir() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(tmp_, ec);
  }
}

fs::path OutputDir::path(std::string_view name) const { return tmp_ / fs::path(name); }

void OutputDir::write(std::string_view name, std::string_view bytes) const {
  AtomicFile f(path(name));
  f.write(bytes);
  f.commit();
}

namespace {

// The files a previous run listed in its marker (one name a line after the header; a marker
// without the list, from an older ptc, lists nothing).
std::vector<std::string> listed_files(const fs::path& marker) {
  std::vector<std::string> names;
  std::ifstream in(marker);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line))
    if (!line.empty()) names.push_back(line);
  return names;
}

}  // namespace

void OutputDir::commit() {
  if (committed_) return;
  std::error_code ec;
  // The marker lists what this run wrote, so that a later run can tell its files from the user's.
  std::vector<std::string> written;
  for (const auto& e : fs::directory_iterator(tmp_, ec))
    if (e.path().filename() != kMarker) written.push_back(e.path().filename().string());
  std::sort(written.begin(), written.end());
  {
    std::string m = kMarkerHeader;
    for (const auto& w : written) m += w + "\n";
    write(kMarker, m);
  }
  // Files the user put into the previous output (neither written now nor listed by the run that
  // wrote it) move into the new directory; one that this run also wrote is kept as NAME.kept.
  kept_.clear();
  if (fs::is_directory(target_, ec)) {
    const std::vector<std::string> listed = listed_files(target_ / kMarker);
    for (const auto& e : fs::directory_iterator(target_, ec)) {
      const std::string name = e.path().filename().string();
      if (name == kMarker) continue;
      if (std::find(listed.begin(), listed.end(), name) != listed.end()) continue;  // ptc's own, stale or replaced
      const bool clash = std::binary_search(written.begin(), written.end(), name);
      // A marker without a list (an older ptc): a name this run writes again was ptc's too.
      if (clash && listed.empty()) continue;
      fs::path dest = tmp_ / (clash ? name + ".kept" : name);
      std::error_code rc;
      fs::rename(e.path(), dest, rc);
      if (rc) throw InputError(e.path().string(), "", "", "cannot keep this file in the new output: " + rc.message());
      kept_.push_back(dest.filename().string());
    }
    std::sort(kept_.begin(), kept_.end());
    if (!kept_.empty()) {
      std::string m = kMarkerHeader;  // the kept files are not ptc's: the marker lists only what it wrote
      for (const auto& w : written) m += w + "\n";
      write(kMarker, m);
    }
  }
  fs::path old;
  if (fs::exists(target_, ec)) {
    old = tmp_;
    old += ".old";
    fs::rename(target_, old, ec);
    if (ec) throw InputError(target_.string(), "", "", "cannot move the previous output aside: " + ec.message());
  }
  fs::rename(tmp_, target_, ec);
  if (ec) {
    std::error_code ignore;
    if (!old.empty()) fs::rename(old, target_, ignore);  // put the user's directory back
    throw InputError(target_.string(), "", "", "cannot move the output into place: " + ec.message());
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
  if (!kept_.empty()) {
    std::string list;
    for (std::size_t i = 0; i < kept_.size() && i < 8; ++i) list += (i ? ", " : "") + kept_[i];
    if (kept_.size() > 8) list += ", ...";
    std::cerr << "ptc: note: kept " << kept_.size() << " file(s) that ptc did not write in " << target_.string()
              << ": " << list << "\n";
  }
}

}  // namespace ptc
