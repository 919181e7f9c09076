#include "commands/output_dir.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <atomic>
#include <fstream>
#include <regex>
#include <iostream>
#include <stdexcept>
#include <vector>
#include <system_error>

#include <fmt/format.h>

#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "commands/process.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/io/atomic_file.h"
#include "toolkit/core/strings.h"

namespace ptc {
namespace fs = std::filesystem;

namespace {
constexpr const char* kMarkerHeader =
    "written by ptc: a later run with the same --out replaces the files listed below and keeps any other\n";

std::string unique_suffix() {
  static std::atomic<unsigned> counter{0};
  return std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

// Temporaries of this output left by a run that could not remove them (kill -9, a crash, a power
// cut: no handler ran) are said once, not removed: a run killed while it moved the user's files
// into its new output left them there.
void note_killed_runs(const fs::path& dir, const std::string& prefix, const fs::path& target) {
  std::error_code ec;
  std::vector<std::string> stale;
  std::size_t seen = 0;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end && seen < 100000; it.increment(ec), ++seen) {
    const std::string name = it->path().filename().string();
    if (!name.starts_with(prefix)) continue;
    const std::string rest = name.substr(prefix.size());  // PID-N or PID-N.old
    const std::size_t dash = rest.find('-');
    if (dash == 0 || dash == std::string::npos || rest.find_first_not_of("0123456789") != dash) continue;
    const long pid = std::strtol(rest.c_str(), nullptr, 10);
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == -1 && errno == ESRCH)
      stale.push_back(dir == fs::path(".") ? name : (dir / name).string());
  }
  if (stale.empty()) return;
  std::sort(stale.begin(), stale.end());
  std::string list;
  for (std::size_t i = 0; i < stale.size() && i < 3; ++i) list += (i ? ", " : "") + stale[i];
  if (stale.size() > 3) list += fmt::format(", ... ({} of them)", stale.size());
  std::cerr << "ptc: note: " << list << (stale.size() == 1 ? " is" : " are")
            << " left from an earlier run into " << target.string()
            << " that was killed (kill -9, a crash); ptc leaves " << (stale.size() == 1 ? "it" : "them")
            << " alone: files you had in " << target.string() << " may be inside\n";
}

}  // namespace

std::string readable_bytes(double b) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (b >= 1000.0 && u < 6) b /= 1000.0, ++u;
  return u == 0 ? fmt::format("{:.0f} B", b) : fmt::format("{:.1f} {}", b, units[u]);
}

void OutputDir::check_room(double bytes, std::string_view flag, std::string_view what) const {
  std::error_code ec;
  const fs::space_info room = fs::space(tmp_, ec);
  if (ec || !(bytes > static_cast<double>(room.available))) return;  // (unknown room: no refusal)
  throw UsageError(std::string(flag),
                   fmt::format("{} would take at least {} in {}, whose file system has {} free", what,
                               readable_bytes(bytes), target_.string(), readable_bytes(double(room.available))));
}

nlohmann::json commit_with_manifest(OutputDir& dir, RunManifest& manifest) {
  manifest.add_output("manifest.json");
  nlohmann::json j = manifest.to_json();
  dir.write("manifest.json", dump_json(j));
  dir.commit();
  return j;
}

void refuse_overwriting_input(const fs::path& out, const fs::path& input, std::string_view out_flag) {
  if (out.empty() || input.empty()) return;
  // A glob of frame files ("frames/*.ply") reads what is in the directory before its first
  // wildcard.
  fs::path read = input;
  if (const std::string s = input.string(); s.find_first_of("*?[") != std::string::npos) {
    const std::size_t cut = s.find_first_of("*?[");
    const std::size_t slash = s.rfind('/', cut);
    read = slash == std::string::npos ? fs::path(".") : fs::path(s.substr(0, slash == 0 ? 1 : slash));
  }
  std::error_code ec_in, ec_out;
  if (!fs::exists(read, ec_in)) return;
  const fs::path in = fs::weakly_canonical(read, ec_in), o = fs::weakly_canonical(out, ec_out);
  if (ec_in || ec_out || o.empty() || in.empty()) return;
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
    throw UsageError("--out", "'" + target_.string() + "' is not usable as an output directory name");
  std::error_code ec;
  if (fs::is_symlink(target_, ec)) {
    // (the link's text may be relative to its folder: the path it resolves to, as the user can type it)
    const fs::file_status st = fs::status(target_, ec);  // (of what the link points to)
    const fs::path text = fs::read_symlink(target_, ec);
    const std::string to = fs::exists(st) ? fs::weakly_canonical(target_, ec).string()
                                          : (fs::absolute(target_.parent_path(), ec) / text).lexically_normal().string();
    if (fs::is_directory(st))
      throw InputError(target_.string(), "", "", "is a symbolic link; give the directory it points to (" + to + ") instead");
    throw InputError(target_.string(), "", "",
                     "is a symbolic link to " + to + (fs::exists(st) ? ", which is not a directory" : ", which does not exist") +
                         "; give another output directory");
  }
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
  const std::string tmp_prefix = temporary_prefix(leaf);
  tmp_ = (parent.empty() ? fs::path(".") : parent) / (tmp_prefix + unique_suffix());
  note_killed_runs(tmp_.parent_path(), tmp_prefix, target_);
  fs::create_directory(tmp_, ec);
  if (ec)  // (the directory ptc writes into first is a sibling: its parent is what refuses)
    throw InputError(target_.string(), "", "",
                     "cannot write into its directory '" + tmp_.parent_path().string() + "': " +
                         (ec == std::errc::no_such_file_or_directory ? std::string("it takes no new entries") : ec.message()));
  slot_ = register_temporary(tmp_, true);
  try {
    write(kMarker, kMarkerHeader);
  } catch (...) {
    fs::remove_all(tmp_, ec);
    unregister_temporary(slot_);
    throw;
  }
}

OutputDir::~OutputDir() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(tmp_, ec);
  }
  unregister_temporary(slot_);
}

fs::path OutputDir::path(std::string_view name) const { return tmp_ / fs::path(name); }

void OutputDir::write(std::string_view name, std::string_view bytes) const {
  AtomicFile f(path(name));
  f.write(bytes);
  f.commit();
}

namespace {

// What the previous run's marker says: the files it wrote (a marker from a ptc before the lists
// has only its header: `legacy`), or that there is no marker at all.
struct PreviousMarker {
  bool present = false, legacy = false;
  std::vector<std::string> listed;
};

// What wrote a manifest.json, as a user would name it: the command and, for experiment and viz,
// its kind ("experiment sweep", "viz export"); "" when there is none or it cannot be read.
std::string manifest_command(const fs::path& file) {
  std::ifstream in(file);
  if (!in) return "";
  const nlohmann::json m = nlohmann::json::parse(in, nullptr, false);
  if (!m.is_object() || !m.contains("command") || !m["command"].is_string()) return "";
  std::string c = m["command"].get<std::string>();
  if (m.contains("parameters") && m["parameters"].is_object()) {
    const nlohmann::json& p = m["parameters"];
    for (const char* k : {"experiment", "kind"})
      if (p.contains(k) && p[k].is_string()) {
        c += " " + p[k].get<std::string>();
        break;
      }
  }
  return c;
}

constexpr const char* kLegacyHeader = "written by ptc; a later run with the same --out replaces this directory";

PreviousMarker read_marker(const fs::path& marker) {
  PreviousMarker m;
  std::ifstream in(marker);
  std::string line;
  if (!in || !std::getline(in, line)) return m;
  m.present = true;
  m.legacy = line == kLegacyHeader;
  while (std::getline(in, line))
    if (!line.empty()) m.listed.push_back(line);
  return m;
}

// A free name for a kept file in `dir`: NAME.kept, NAME.kept.2, ...
fs::path free_name(const fs::path& dir, const std::string& name) {
  std::error_code ec;
  fs::path p = dir / (name + ".kept");
  for (int k = 2; fs::exists(p, ec) || fs::is_symlink(p, ec); ++k) p = dir / (name + ".kept." + std::to_string(k));
  return p;
}

// The outputs committed in this process (output_was_committed).
std::vector<std::filesystem::path>& committed_outputs() {
  static std::vector<std::filesystem::path> paths;
  return paths;
}

}  // namespace

std::string with_user_paths(const std::string& message) {
  // Only this process's temporaries (their names carry its id): a user's ".cache.tmp-2024-01"
  // stays as it is.
  const std::string mine = ".tmp-" + std::to_string(::getpid()) + "-";
  if (message.find(mine) == std::string::npos) return message;
  static const std::regex temporary(R"((^|[/'"`(])\.([^/\n]+?)\.tmp-)" + std::to_string(::getpid()) +
                                    R"(-[0-9]+(?:\.old)?(?=$|[/\s:'"`),]))");
  return std::regex_replace(message, temporary, "$1$2");
}

bool output_was_committed(const std::filesystem::path& out) {
  const fs::path want = out.lexically_normal();
  for (const fs::path& p : committed_outputs())
    if (p.lexically_normal() == want) return true;
  return false;
}

void OutputDir::commit() {
  if (committed_) return;
  throw_if_cancelled();  // an interrupted run replaces nothing (the destructor removes tmp_)
  std::error_code ec;
  // The marker lists what this run wrote, so that a later run can tell its files from the user's.
  // Outputs are flat: a listed name is one file (a run that writes subdirectories would need
  // relative paths in the marker, so that a user's file inside one is not taken for ptc's).
  std::vector<std::string> written;
  for (const auto& e : fs::directory_iterator(tmp_, ec)) {
    if (e.path().filename() == kMarker) continue;
    if (e.is_directory()) throw std::logic_error("OutputDir: outputs are flat files; '" + e.path().string() + "' is a directory");
    written.push_back(e.path().filename().string());
  }
  std::sort(written.begin(), written.end());
  {
    std::string m = kMarkerHeader;
    for (const auto& w : written) m += w + "\n";
    write(kMarker, m);
  }
  // Files the user put into the previous output (neither written now nor listed by the run that
  // wrote it) move into the new directory; one whose name this run writes too is kept as
  // NAME.kept (NAME.kept.2, ...). Every move is undone if the commit fails, so nothing of the
  // user's is lost whatever happens.
  kept_.clear();
  // From here until the new directory is in place, a Ctrl-C or SIGTERM is looked for before each
  // step: one that came undoes the moves and replaces nothing (Interrupted), and a second one
  // waits for that (StopAtOnceHeld: its handler would remove the temporary directory, by then
  // holding the user's files).
  StopAtOnceHeld held;
  std::vector<std::pair<fs::path, fs::path>> moved;  // (from, to)
  auto undo_moves = [&] {
    for (auto it = moved.rbegin(); it != moved.rend(); ++it) {
      std::error_code ignore;
      fs::rename(it->second, it->first, ignore);
    }
    moved.clear();
  };
  fs::path old;
  std::string replaced_note;  // said once the commit is done: the output of another command replaced
  try {
    if (fs::is_directory(target_, ec)) {
      const PreviousMarker prev = read_marker(target_ / kMarker);
      const std::string before = manifest_command(target_ / "manifest.json"), now = manifest_command(tmp_ / "manifest.json");
      // Said when another command's output is replaced, and whenever files of the previous output
      // that this run does not write again go (a re-run with fewer frames drops the later ones).
      if (prev.present) {
        std::vector<std::string> gone;
        for (const auto& name : prev.listed)
          if (!std::binary_search(written.begin(), written.end(), name) && fs::exists(target_ / name, ec)) gone.push_back(name);
        std::string list;
        for (std::size_t i = 0; i < gone.size() && i < 6; ++i) list += (i ? ", " : "") + gone[i];
        if (gone.size() > 6) list += fmt::format(", ... ({} files)", gone.size());
        const std::string went = gone.empty() ? std::string() : " (its " + list + (gone.size() == 1 ? " is" : " are") + " gone)";
        if (!before.empty() && !now.empty() && before != now)
          replaced_note = "ptc: note: replaced the output of `ptc " + before + "` in " + target_.string() + went + "\n";
        else if (!gone.empty())
          replaced_note = "ptc: note: replaced the previous output in " + target_.string() + went +
                          ": this run did not write " + (gone.size() == 1 ? "it" : "them") + " again\n";
      }
      if (!prev.present && !fs::is_empty(target_, ec))
        throw InputError(target_.string(), "", "",
                         "is no longer a ptc output directory (its .ptc-output marker is gone); nothing was replaced");
      std::vector<std::string> keep, keep_renamed;  // the user's files; those whose name this run writes
      for (const auto& e : fs::directory_iterator(target_, ec)) {
        const std::string name = e.path().filename().string();
        if (name == kMarker) continue;
        if (std::find(prev.listed.begin(), prev.listed.end(), name) != prev.listed.end()) continue;  // ptc's own
        const bool clash = std::binary_search(written.begin(), written.end(), name);
        // A marker of an older ptc lists nothing: a name this run writes again was ptc's too.
        if (clash && prev.legacy) continue;
        (clash ? keep_renamed : keep).push_back(name);
      }
      // Names that clash with nothing move first, so that a free NAME.kept.N chosen after them
      // never lands on one of them.
      std::sort(keep.begin(), keep.end());
      std::sort(keep_renamed.begin(), keep_renamed.end());
      auto move = [&](const std::string& name, const fs::path& dest) {
        throw_if_cancelled();
        std::error_code rc;
        fs::rename(target_ / name, dest, rc);
        if (rc) throw InputError((target_ / name).string(), "", "", "cannot keep this file in the new output: " + rc.message());
        moved.emplace_back(target_ / name, dest);
        kept_.push_back(dest.filename().string());
      };
      for (const auto& name : keep) move(name, tmp_ / name);
      for (const auto& name : keep_renamed) move(name, free_name(tmp_, name));
      std::sort(kept_.begin(), kept_.end());
    }
    throw_if_cancelled();
    if (fs::exists(target_, ec)) {
      old = tmp_;
      old += ".old";
      fs::rename(target_, old, ec);
      if (ec) throw InputError(target_.string(), "", "", "cannot move the previous output aside: " + ec.message());
    }
    fs::rename(tmp_, target_, ec);
    if (ec) {
      std::error_code ignore;
      if (!old.empty()) fs::rename(old, target_, ignore);  // put the previous directory back
      throw InputError(target_.string(), "", "", "cannot move the output into place: " + ec.message());
    }
  } catch (...) {
    undo_moves();  // the user's files go back where they were (the previous directory is in place)
    kept_.clear();
    throw;  // (held's end acts on a second signal: the temporary holds only ptc's files again)
  }
  committed_ = true;
  committed_outputs().push_back(target_);
  unregister_temporary(slot_);
  slot_ = -1;
  // The previous output, now replaced: a second signal during its removal (or held until now)
  // removes it too.
  if (!old.empty()) slot_ = register_temporary(old, true);
  held.release();  // a second signal held back now ends the run (its output is complete)
  if (!old.empty()) {
    fs::remove_all(old, ec);
    unregister_temporary(slot_);
    slot_ = -1;
    if (ec) std::cerr << "ptc: note: could not remove the previous output, left as " << old.string() << "\n";
  }
  std::cerr << replaced_note;
  if (!kept_.empty()) {
    std::string list;
    for (std::size_t i = 0; i < kept_.size() && i < 8; ++i) list += (i ? ", " : "") + kept_[i];
    if (kept_.size() > 8) list += ", ...";
    std::cerr << "ptc: note: kept " << counted(kept_.size(), "file") << " that ptc did not write in " << target_.string()
              << ": " << list << "\n";
  }
}

}  // namespace ptc
