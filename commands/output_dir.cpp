#include "commands/output_dir.h"

#include <unistd.h>

#include <atomic>
#include <system_error>

#include "toolkit/core/error.h"
#include "toolkit/io/atomic_file.h"

namespace ptc {
namespace fs = std::filesystem;

namespace {
std::string unique_suffix() {
  static std::atomic<unsigned> counter{0};
  return std::to_string(::getpid()) + "-" + std::to_string(counter++);
}
}  // namespace

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
    write(kMarker, "written by ptc; a later run with the same --out replaces this directory\n");
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

void OutputDir::commit() {
  if (committed_) return;
  std::error_code ec;
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
}

}  // namespace ptc
