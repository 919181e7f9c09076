// `ptc notebook`: the paper's figures as a notebook and a script, and their PNG/SVG.
#include "commands/notebook.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <ostream>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "notebooks_export/notebook.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"

extern char** environ;

namespace ptc {
namespace {

namespace fs = std::filesystem;

struct Run {
  int code = -1;
  std::string output;  // stdout + stderr
};

// Runs argv in `cwd` with stdout and stderr into a file, waiting for it (a Ctrl-C reaches the child
// too, through the terminal's process group; the run then reports the interrupt).
Run run_program(const std::vector<std::string>& args, const fs::path& cwd, const fs::path& log) {
  Run r;
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addchdir_np(&fa, cwd.c_str());
  std::vector<std::string> a = args;
  std::vector<char*> argv;
  for (auto& s : a) argv.push_back(s.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, a[0].c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) return r;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  std::ifstream in(log);
  r.output.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  std::error_code ec;
  fs::remove(log, ec);
  return r;
}

std::string last_error_line(const std::string& text) {
  std::string last;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t nl = text.find('\n', start);
    if (nl == std::string::npos) nl = text.size();
    const std::string line = text.substr(start, nl - start);
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
    start = nl + 1;
  }
  return last;
}

}  // namespace

void cmd_notebook(const NotebookCommandOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw UsageError("--out", "an output directory is required");
  if (opt.studies.empty()) throw UsageError("DIR", "name at least one `ptc experiment` output directory");
  RunManifest manifest("notebook", opt.argv, "ptc-notebook/1");
  notebooks::StudyInputs in;
  std::error_code ec;
  const fs::path out_abs = fs::absolute(opt.out_dir).lexically_normal();
  for (const fs::path& d : opt.studies) {
    refuse_overwriting_input(opt.out_dir, d);
    const fs::path m = d / "manifest.json";
    std::ifstream f(m);
    if (!f) throw InputError(d.string(), "", "", "no manifest.json: not an output of `ptc experiment`");
    const nlohmann::json j = nlohmann::json::parse(f, nullptr, false);
    if (j.is_discarded() || !j.contains("parameters") || !j["parameters"].contains("experiment") ||
        !j["parameters"]["experiment"].is_string())
      throw InputError(m.string(), "", "", "not the manifest of `ptc experiment` (no parameters.experiment)");
    const std::string kind = j["parameters"]["experiment"];
    if (in.dirs.count(kind))
      throw InputError(d.string(), "", "", fmt::format("a second {} study (one directory per experiment kind)", kind));
    // Paths as the notebook opens them: relative to the output directory (they move together).
    const fs::path abs = fs::absolute(d).lexically_normal();
    in.dirs[kind] = abs.lexically_relative(out_abs).string();
    if (in.dirs[kind].empty()) in.dirs[kind] = abs.string();
    if (j["parameters"].contains("scene") && j["parameters"]["scene"].is_string()) in.scenes[kind] = j["parameters"]["scene"];
    if (j["parameters"].contains("shard") && !j["parameters"]["shard"].is_null())
      in.notes[kind] = "shard " + j["parameters"]["shard"].dump() + ": part of the study";
    record_input(manifest, m);
  }
  const std::vector<notebooks::Figure> figures = notebooks::figures_for(in);

  if (opt.figures) {  // the Python first: an error should come before any work
    if (access(opt.python.c_str(), X_OK) != 0)
      throw InputError("", "", "--python", fmt::format("{} is not an executable Python: install Debian's python3 (or give --python PATH, or --no-figures)", opt.python));
  }
  if (opt.execute && access(opt.jupyter.c_str(), X_OK) != 0)
    throw InputError("", "", "--execute",
                     fmt::format("{} is missing: install Debian's jupyter-nbconvert and python3-ipykernel", opt.jupyter));

  OutputDir dir(opt.out_dir);
  const std::string nb = notebooks::notebook_json(in, figures), py = notebooks::figures_script(in, figures);
  dir.write("paper_figures.ipynb", nb);
  dir.write("paper_figures.py", py);
  manifest.add_output("paper_figures.ipynb", "nbformat/4.5");
  manifest.add_output("paper_figures.py");
  // The relative paths hold from the final directory; the temporary one is its sibling, so they
  // hold from there too.
  std::vector<std::string> written = {"paper_figures.ipynb", "paper_figures.py"};
  nlohmann::json drawn = nlohmann::json::object();
  Stopwatch sw;
  if (opt.figures) {
    const fs::path tmp = dir.path("");
    Run probe = run_program({opt.python, "-c", "import pandas, matplotlib, numpy"}, tmp, dir.path(".probe.log"));
    if (probe.code != 0)
      throw InputError("", "", "--python",
                       fmt::format("{} cannot import pandas and matplotlib: install Debian's python3-pandas and "
                                   "python3-matplotlib (or --no-figures)", opt.python));
    throw_if_cancelled();
    Run r = run_program({opt.python, "paper_figures.py"}, tmp, dir.path(".figures.log"));
    throw_if_cancelled();
    if (r.code != 0)
      throw InputError(dir.target().string() + "/paper_figures.py", "", "", "the figure script failed: " + last_error_line(r.output));
    std::ifstream fj(dir.path("figures.json"));
    drawn = nlohmann::json::parse(fj, nullptr, false);
    if (drawn.is_discarded()) throw InputError("paper_figures.py", "", "", "the figure script wrote no figures.json");
    manifest.add_output("figures.json");
    written.push_back("figures.json");
    for (const notebooks::Figure& f : figures)
      for (const char* ext : {".png", ".svg"}) {
        manifest.add_output(f.name + ext);
        written.push_back(f.name + ext);
      }
    manifest.add_timing_ms("figures", sw.ms());
  }
  if (opt.execute) {
    sw.restart();
    Run r = run_program({opt.jupyter, "nbconvert", "--to", "notebook", "--execute", "--inplace",
                         "--ExecutePreprocessor.timeout=1800", "paper_figures.ipynb"},
                        dir.path(""), dir.path(".nbconvert.log"));
    throw_if_cancelled();
    if (r.code != 0)
      throw InputError(dir.target().string() + "/paper_figures.ipynb", "", "",
                       "executing the notebook failed: " + last_error_line(r.output));
    if (!opt.figures) {  // the notebook's cells wrote the figures
      std::ifstream fj(dir.path("figures.json"));
      drawn = nlohmann::json::parse(fj, nullptr, false);
      manifest.add_output("figures.json");
      for (const notebooks::Figure& f : figures)
        for (const char* ext : {".png", ".svg"}) manifest.add_output(f.name + ext), written.push_back(f.name + ext);
    }
    manifest.add_timing_ms("execute", sw.ms());
  }
  nlohmann::json studies = nlohmann::json::object();
  for (const auto& [k, d] : in.dirs) studies[k] = d;
  manifest.set_parameter("studies", studies);
  manifest.set_parameter("python", opt.figures ? opt.python : "");
  manifest.set_parameter("executed", opt.execute);
  nlohmann::json names = nlohmann::json::array();
  for (const auto& f : figures) names.push_back(f.name);
  manifest.set_result("figures", names);
  manifest.set_result("drawn", drawn);
  (void)commit_with_manifest(dir, manifest);
  if (opt.json) {
    out << dump_json({{"schema", "ptc-notebook-summary/1"}, {"figures", names}, {"drawn", drawn}, {"outputs", written}});
    return;
  }
  out << fmt::format("{} figure(s) from {}: {}\n", figures.size(), [&] {
    std::string s;
    for (const auto& [k, d] : in.dirs) s += (s.empty() ? "" : ", ") + k;
    return s;
  }(), [&] {
    std::string s;
    for (const auto& f : figures) s += (s.empty() ? "" : ", ") + f.name;
    return s;
  }());
  out << "wrote " << opt.out_dir.string() << "/{paper_figures.ipynb,paper_figures.py"
      << (opt.figures || opt.execute ? ",figures.json,*.png,*.svg" : "") << ",manifest.json}\n";
}

}  // namespace ptc
