// `ptc notebook DIR... --out DIR [--no-figures] [--execute] [--python PATH] [--jupyter PATH]`
// (commands/notebook.h).
#include <iostream>

#include "apps/ptc/cli.h"
#include "commands/notebook.h"

namespace ptc::cli {

namespace {
struct NotebookArgs {
  NotebookCommandOptions opt;
  std::vector<std::string> dirs;
  bool no_figures = false;
};
}  // namespace

void register_notebook(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<NotebookArgs>();
  auto* c = ctx.add(app, "notebook",
                    "Jupyter notebook + figure script (PNG, SVG) redrawing the paper's figures from `ptc experiment` outputs",
                    [a, &ctx] {
                      auto& o = a->opt;
                      o.studies.assign(a->dirs.begin(), a->dirs.end());
                      o.figures = !a->no_figures;
                      o.argv = ctx.args;
                      cmd_notebook(o, std::cout);
                    });
  c->add_option("DIR", a->dirs, "output directories of ptc experiment sweep / compare / drift / accuracy")->required();
  c->add_option("--out", a->opt.out_dir, "output directory (written atomically)")->required();
  auto* no_fig = c->add_flag("--no-figures", a->no_figures, "write the notebook and the script only (no Python run)");
  c->add_flag("--execute", a->opt.execute, "also execute the notebook with jupyter nbconvert (its outputs kept in it)")
      ->excludes(no_fig);  // (executing it draws the figures)
  c->add_option("--python", a->opt.python, "the Python that runs the figure script (needs pandas, matplotlib)")->capture_default_str();
  c->add_option("--jupyter", a->opt.jupyter, "the jupyter command for --execute")->capture_default_str();
  c->add_flag("--json", a->opt.json, "print what was written as JSON");
}

}  // namespace ptc::cli
