// Jupyter notebooks (nbformat 4.5, with cell ids) and a plain Python script that redraw the
// paper's figures from the tables of `ptc experiment` (docs/experiments.md): Figure 6 (stage
// times per MaxCount, from sweep), Figure 7 (performance factor per frame, one line per
// configuration, from compare), the drift plots (per-frame summaries per clustering; connectivity
// against box-area drift with the rank correlation), SAH / EPO against the measured cost with
// the fit (from drift), and speed against error (from accuracy). Each figure is one markdown
// cell (what it shows, where the numbers come from) and one code cell; the script is the same
// code cells in a row, run with matplotlib's Agg back end, so the notebook and the PNG/SVG files
// cannot disagree. Both load the CSVs with pandas by paths relative to where they are written.
//
// Every figure records in figures.json how many series it drew (the tests compare that with
// the CSVs and count the series' colours in the PNG).
#pragma once

#include <map>
#include <string>
#include <vector>

namespace ptc::notebooks {

/// The experiment kinds a figure can come from.
inline constexpr const char* kKinds[] = {"sweep", "compare", "drift", "accuracy"};

struct StudyInputs {
  /// kind -> the experiment's output directory, as the notebook will open it (relative to the
  /// directory the notebook is written to, or absolute).
  std::map<std::string, std::string> dirs;
  /// kind -> the scene it ran on (titles) and a note such as "shard 1/3".
  std::map<std::string, std::string> scenes, notes;
};

struct Figure {
  std::string name;      ///< file stem of the PNG / SVG ("fig7_compare")
  std::string kind;      ///< the experiment it reads
  std::string markdown;  ///< the explanation cell
  std::string code;      ///< the code cell (draws and calls save(fig, name, series))
};

/// The figures the given kinds allow, in the paper's order.
[[nodiscard]] std::vector<Figure> figures_for(const StudyInputs& in);

/// The notebook: a title cell, the set-up cell (imports, paths, save()), then each figure.
[[nodiscard]] std::string notebook_json(const StudyInputs& in, const std::vector<Figure>& figures);

/// The same cells as a script (matplotlib's Agg back end; writes NAME.png, NAME.svg per figure
/// and figures.json into the current directory).
[[nodiscard]] std::string figures_script(const StudyInputs& in, const std::vector<Figure>& figures);

}  // namespace ptc::notebooks
