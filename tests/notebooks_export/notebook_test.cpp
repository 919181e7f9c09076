// The notebook generator without Python: which figures a set of studies gives, the notebook's
// nbformat 4.5 structure (cell ids unique and well-formed, code cells without outputs), and the
// script made of exactly the notebook's code cells (so the PNGs and the notebook cannot disagree).
#include <gtest/gtest.h>

#include <regex>
#include <set>

#include <nlohmann/json.hpp>

#include "notebooks_export/notebook.h"

namespace ptc::notebooks {
namespace {

std::vector<std::string> names(const std::vector<Figure>& f) {
  std::vector<std::string> n;
  for (const auto& x : f) n.push_back(x.name);
  return n;
}

TEST(NotebookExport, FiguresFollowTheStudiesGiven) {
  StudyInputs in;
  EXPECT_TRUE(figures_for(in).empty());
  in.dirs["compare"] = "../compare";
  EXPECT_EQ(names(figures_for(in)), std::vector<std::string>{"fig7_compare"});
  in.dirs["sweep"] = "../sweep";
  in.dirs["drift"] = "/abs/drift";
  in.dirs["accuracy"] = "acc";
  EXPECT_EQ(names(figures_for(in)), (std::vector<std::string>{"fig6_sweep", "fig7_compare", "drift_frames",
                                                              "drift_correlation", "cost_fit", "speed_vs_error"}));
}

TEST(NotebookExport, NotebookIsNbformat45AndTheScriptIsItsCodeCells) {
  StudyInputs in;
  in.dirs = {{"sweep", "../sweep"}, {"drift", "../dir with \"quotes\""}};
  in.scenes = {{"sweep", "armadillo"}};
  const auto figs = figures_for(in);
  const nlohmann::json nb = nlohmann::json::parse(notebook_json(in, figs));
  EXPECT_EQ(nb["nbformat"], 4);
  EXPECT_EQ(nb["nbformat_minor"], 5);
  EXPECT_EQ(nb["metadata"]["kernelspec"]["name"], "python3");
  ASSERT_EQ(nb["cells"].size(), 2 + 2 * figs.size());
  std::set<std::string> ids;
  const std::string script = figures_script(in, figs);
  for (const auto& c : nb["cells"]) {
    const std::string id = c["id"];
    EXPECT_TRUE(ids.insert(id).second) << id;
    EXPECT_TRUE(std::regex_match(id, std::regex("[a-zA-Z0-9_-]{1,64}"))) << id;
    EXPECT_TRUE(c["metadata"].is_object());
    std::string src;
    for (const auto& l : c["source"]) src += l.get<std::string>();
    if (c["cell_type"] == "code") {
      EXPECT_TRUE(c["outputs"].is_array() && c["outputs"].empty());
      EXPECT_TRUE(c["execution_count"].is_null());
      const std::string body = id == "setup" ? src.substr(src.find('\n') + 1) : src;  // the script has no %matplotlib
      EXPECT_NE(script.find(body), std::string::npos) << "the script holds cell " << id;
    } else {
      EXPECT_EQ(c["cell_type"], "markdown");
    }
  }
  // The directories are Python string literals (quotes escaped), relative as given.
  EXPECT_NE(script.find(R"("drift": "../dir with \"quotes\"")"), std::string::npos);
  EXPECT_NE(script.find("matplotlib.use(\"Agg\")"), std::string::npos);
}

}  // namespace
}  // namespace ptc::notebooks
