// `ptc notebook`: the paper's figures as a notebook and a script, and their PNG/SVG.
#include "commands/notebook.h"

#include <fstream>
#include <iostream>
#include <ostream>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "commands/child_process.h"
#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "notebooks_export/notebook.h"
#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/core/strings.h"

namespace ptc {
namespace {

namespace fs = std::filesystem;


}  // namespace

void cmd_notebook(const NotebookCommandOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw UsageError("--out", "an output directory is required");
  if (opt.studies.empty()) throw UsageError("DIR", "name at least one `ptc experiment` output directory");
  RunManifest manifest("notebook", opt.argv, "ptc-notebook/1");
  notebooks::StudyInputs in;
  std::error_code ec;
  // Symbolic links resolved on both sides, so the relative path holds in the real directories.
  const fs::path out_abs = fs::weakly_canonical(fs::absolute(opt.out_dir));
  for (const fs::path& d : opt.studies) {
    refuse_overwriting_input(opt.out_dir, d);
    const fs::path m = d / "manifest.json";
    const nlohmann::json j = read_experiment_manifest(d);
    if (!j.is_object() || !j.contains("parameters") || !j["parameters"].contains("experiment") ||
        !j["parameters"]["experiment"].is_string())
      throw InputError(m.string(), "", "", "not the manifest of `ptc experiment` (no parameters.experiment)");
    const std::string kind = j["parameters"]["experiment"];
    if (in.dirs.count(kind))
      throw InputError(d.string(), "", "", fmt::format("a second {} study (one directory per experiment kind)", kind));
    // Paths as the notebook opens them: relative to the output directory (they move together).
    const fs::path abs = fs::weakly_canonical(fs::absolute(d));
    const fs::path rel = abs.lexically_relative(out_abs);
    in.dirs[kind] = rel.empty() ? abs.string() : rel.string();
    if (j["parameters"].contains("scene") && j["parameters"]["scene"].is_string()) in.scenes[kind] = j["parameters"]["scene"];
    if (j["parameters"].contains("shard") && j["parameters"]["shard"].is_object()) {
      const nlohmann::json& sh = j["parameters"]["shard"];
      const auto k = sh.value("index", 0), n = sh.value("count", 0);
      if (n > 1) in.notes[kind] = fmt::format("shard {} of {}: part of the study (ptc merge joins the shards)", k, n);
    }
    record_input(manifest, m);
    // The tables the figures read, as the run wrote them: present, and (manifests since
    // 2026-12-04) with the bytes and hash it recorded, checked here rather than by a Python error.
    if (j.contains("output_schemas") && j["output_schemas"].is_object())
      for (auto it = j["output_schemas"].begin(); it != j["output_schemas"].end(); ++it) {
        const fs::path table = d / it.key();
        if (!fs::is_regular_file(table, ec))
          throw InputError(table.string(), "", "", "missing (its manifest lists it): an incomplete experiment output");
        check_output_hash(j, it.key(), file_fnv1a64(table), table);
      }
  }
  const std::vector<notebooks::Figure> figures = notebooks::figures_for(in);

  // The programs first (an error should come before any work), as paths that work from the
  // temporary directory they run in.
  const std::string python = opt.figures ? resolve_program(opt.python) : "";
  if (opt.figures && python.empty())
    throw InputError("", "", "--python",
                     fmt::format("{} is not an executable Python: install Debian's python3 (or give --python PATH, or --no-figures)",
                                 opt.python));
  const std::string jupyter = opt.execute ? resolve_program(opt.jupyter) : "";
  if (opt.execute && jupyter.empty())
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
    const ChildResult probe = run_child({python, "-c", "import pandas, matplotlib, numpy"}, tmp, dir.path(".probe.log"));
    if (!probe.started) throw InputError("", "", "--python", fmt::format("{} could not be started", python));
    if (probe.code != 0)
      throw InputError("", "", "--python",
                       fmt::format("{} cannot import pandas and matplotlib: install Debian's python3-pandas and "
                                   "python3-matplotlib (or --no-figures)", opt.python));
    const ChildResult r = run_child({python, "paper_figures.py"}, tmp, dir.path(".figures.log"));
    if (r.code != 0)
      throw InputError(dir.target().string() + "/paper_figures.py", "", "", "the figure script failed: " + last_nonblank_line(r.output));
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
    const ChildResult r = run_child({jupyter, "nbconvert", "--to", "notebook", "--execute", "--inplace",
                         "--ExecutePreprocessor.timeout=1800", "paper_figures.ipynb"},
                        dir.path(""), dir.path(".nbconvert.log"));
    if (r.code != 0)
      throw InputError(dir.target().string() + "/paper_figures.ipynb", "", "",
                       "executing the notebook failed: " + last_nonblank_line(r.output));
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
  manifest.set_parameter("python", python);
  manifest.set_parameter("jupyter", jupyter);
  manifest.set_parameter("executed", opt.execute);
  nlohmann::json names = nlohmann::json::array();
  for (const auto& f : figures) names.push_back(f.name);
  manifest.set_result("figures", names);
  manifest.set_result("drawn", drawn);
  (void)commit_with_manifest(dir, manifest);
  // What a figure could not draw (figures.json's notes: a shard, a missing reference, one frame).
  if (drawn.is_object())
    for (auto it = drawn.begin(); it != drawn.end(); ++it)
      if (it->is_object() && it->contains("note") && (*it)["note"].is_string() && !(*it)["note"].get<std::string>().empty())
        std::cerr << "ptc: note: " << it.key() << ": " << (*it)["note"].get<std::string>() << "\n";
  if (opt.json) {
    out << dump_json({{"schema", "ptc-notebook-summary/1"}, {"figures", names}, {"drawn", drawn}, {"outputs", written}});
    return;
  }
  out << fmt::format("{} from {}: {}\n", counted(figures.size(), "figure"), [&] {
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
