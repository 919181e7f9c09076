// `ptc notebook DIR... --out DIR` as a library call: notebooks and figure PNG/SVG from the outputs
// of `ptc experiment` (notebooks_export/notebook.h).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace ptc {

struct NotebookCommandOptions {
  std::vector<std::filesystem::path> studies;  ///< experiment output directories (one per kind at most)
  std::filesystem::path out_dir;
  bool figures = true;   ///< run the script with `python` (PNG + SVG + figures.json)
  bool execute = false;  ///< also execute the notebook with `jupyter nbconvert --execute` (outputs kept in it)
  std::string python = "/usr/bin/python3";  ///< Debian's (the first python3 on PATH may not see Debian's packages)
  std::string jupyter = "/usr/bin/jupyter";
  bool json = false;
  std::vector<std::string> argv;
};

/// Writes paper_figures.ipynb, paper_figures.py and (with figures) every figure's PNG and SVG and
/// figures.json into out_dir, atomically with a manifest. A study directory without an
/// experiment manifest, two studies of one kind, or a Python without pandas / matplotlib is an
/// InputError (one line, what to install); a failing figure script is an InputError with its
/// last error line.
void cmd_notebook(const NotebookCommandOptions& opt, std::ostream& out);

}  // namespace ptc
