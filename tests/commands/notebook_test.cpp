// `ptc notebook` on real experiment outputs (four small `ptc experiment` runs in-process): the
// notebook is validated by nbformat's own validator and executed headless by Debian's
// `jupyter nbconvert --execute` (any cell error fails); every figure's series count is checked
// against the CSVs it draws, and its PNG is a real picture with that many series colours in it.
#include <gtest/gtest.h>

#include <regex>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands/experiment.h"
#include "commands/notebook.h"
#include "common/csv_rows.h"
#include "common/temp_dir.h"
#include "toolkit/core/error.h"
#include "viz/png.h"

namespace fs = std::filesystem;

namespace ptc {
namespace {

using test::csv_rows;
using test::slurp;

const fs::path kMeshes = fs::path(PTC_TEST_DATA) / "meshes";

class Notebook : public test::TempDirTest {
 protected:
  void experiment(const std::string& kind, std::function<void(ExperimentCommandOptions&)> more = {}) {
    ExperimentCommandOptions o;
    o.kind = kind;
    o.input = kMeshes / "elephant.off";
    o.frames = "0:3";
    o.width = 48, o.height = 48;
    o.quiet = true;
    o.out_dir = dir_ / "study" / kind;
    if (more) more(o);
    std::ostringstream out;
    cmd_experiment(o, out);
  }
  // A one-frame drift study of acc_growth (frame 2), as two tests need it.
  void one_frame_drift() {
    experiment("drift", [](ExperimentCommandOptions& o) {
      o.frames = "2:2";
      o.clusterings = "acc_growth";
    });
  }
  // The notebook of the compare and drift studies into dir_/nb: its figures.json, and its stderr
  // in `err`.
  nlohmann::json notebook_of_compare_and_drift(std::string& err) {
    NotebookCommandOptions n;
    n.studies = {dir_ / "study" / "compare", dir_ / "study" / "drift"};
    n.out_dir = dir_ / "nb";
    std::ostringstream out;
    testing::internal::CaptureStderr();
    cmd_notebook(n, out);
    err = testing::internal::GetCapturedStderr();
    return nlohmann::json::parse(slurp(n.out_dir / "figures.json"));
  }
  static std::set<std::string> column(const fs::path& csv, const std::string& col, const std::string& skip_col = "",
                                      const std::string& skip_val = "") {
    std::set<std::string> v;
    for (const auto& r : csv_rows(slurp(csv)))
      if (skip_col.empty() || r.at(skip_col) != skip_val) v.insert(r.at(col));
    return v;
  }
};

// matplotlib's tab10 colours (exact: lines and markers are drawn in them, antialiased edges
// aside) present in the picture with at least `min_pixels` pixels; its grey (C7) is left out,
// since antialiased black text and lines produce it too.
std::size_t tab10_colours_in(const RgbImage& img, std::size_t min_pixels = 20) {
  static const Rgb8 tab10[10] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},  {214, 39, 40},  {148, 103, 189},
                                 {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
  std::size_t n = 0;
  for (const Rgb8& c : tab10) {
    if (c == Rgb8{127, 127, 127}) continue;
    std::size_t px = 0;
    for (std::size_t i = 0; i < img.pixel_count(); ++i)
      px += img.rgb[3 * i] == c[0] && img.rgb[3 * i + 1] == c[1] && img.rgb[3 * i + 2] == c[2];
    n += px >= min_pixels;
  }
  return n;
}

TEST_F(Notebook, RedrawsEveryFigureFromTheStudyAndExecutesHeadless) {
  experiment("sweep", [](auto& o) { o.max_counts = "0,10,50"; });
  experiment("compare", [](auto& o) { o.configs = "acc_growth,acc_contraction,standard,naive,embree_refit"; });
  experiment("drift", [](auto& o) { o.clusterings = "acc_growth,naive,meshopt"; });
  experiment("accuracy");

  NotebookCommandOptions n;
  for (const char* k : {"sweep", "compare", "drift", "accuracy"}) n.studies.push_back(dir_ / "study" / k);
  n.out_dir = dir_ / "study" / "notebooks";
  n.execute = true;
  std::ostringstream out;
  cmd_notebook(n, out);
  const fs::path nb = n.out_dir / "paper_figures.ipynb";

  // nbformat's validator (Debian's python3-nbformat) accepts it, cell ids included.
  const std::string cmd = "/usr/bin/python3 -c \"import nbformat, sys; nb = nbformat.read(sys.argv[1], as_version=4); "
                          "nbformat.validate(nb); print(nb.nbformat, nb.nbformat_minor, len(nb.cells))\" " +
                          nb.string() + " > " + (dir_ / "validate.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir_ / "validate.txt");
  EXPECT_EQ(slurp(dir_ / "validate.txt"), "4 5 14\n");  // title, set-up, six figures of two cells

  // Executed in place: every code cell ran (an execution count) and no cell holds an error.
  const nlohmann::json j = nlohmann::json::parse(slurp(nb));
  std::set<std::string> ids;
  std::size_t images = 0;
  for (const auto& c : j["cells"]) {
    EXPECT_TRUE(ids.insert(c["id"].get<std::string>()).second) << "duplicate cell id";
    EXPECT_TRUE(std::regex_match(c["id"].get<std::string>(), std::regex("[a-zA-Z0-9_-]{1,64}")));
    if (c["cell_type"] != "code") continue;
    EXPECT_TRUE(c["execution_count"].is_number()) << c["id"];
    for (const auto& o : c["outputs"]) {
      EXPECT_NE(o["output_type"], "error") << c["id"];
      images += o.contains("data") && o["data"].contains("image/png");
    }
  }
  EXPECT_EQ(images, 6u) << "one inline picture per figure";

  // Series per figure, against the CSVs.
  const nlohmann::json drawn = nlohmann::json::parse(slurp(n.out_dir / "figures.json"));
  const fs::path s = dir_ / "study";
  const std::size_t configs = column(s / "compare" / "compare.csv", "config").size();
  const std::size_t clusterings = column(s / "drift" / "frames.csv", "clustering").size();
  const std::size_t clustered = column(s / "drift" / "clusters_frames.csv", "clustering").size();
  const std::size_t groups = column(s / "accuracy" / "accuracy.csv", "group").size();
  EXPECT_EQ(configs, 5u);
  EXPECT_EQ(clusterings, 4u);  // the triangle BVH and the three clusterings
  EXPECT_EQ(clustered, 3u);
  const std::map<std::string, std::size_t> want = {{"fig6_sweep", 4},           {"fig7_compare", configs},
                                                   {"drift_frames", clusterings}, {"drift_correlation", clustered},
                                                   {"cost_fit", clusterings + 1}, {"speed_vs_error", groups}};
  for (const auto& [name, series] : want) {
    ASSERT_TRUE(drawn.contains(name)) << name;
    EXPECT_EQ(drawn[name]["series"].get<std::size_t>(), series) << name;
    EXPECT_EQ(drawn[name]["note"], "") << name << ": a whole study draws everything";
    const RgbImage img = viz::read_png(n.out_dir / (name + ".png"));
    EXPECT_GT(img.width, 300) << name;
    EXPECT_GT(img.height, 200) << name;
    EXPECT_TRUE(fs::file_size(n.out_dir / (name + ".svg")) > 1000) << name;
    // Line and scatter plots draw series i in tab10 colour i: that many colours are in the picture.
    if (name == "fig7_compare" || name == "drift_frames" || name == "drift_correlation") {
      EXPECT_EQ(tab10_colours_in(img), std::min<std::size_t>(series, 10) - (series > 7 ? 1 : 0)) << name;
    }
    if (name == "fig6_sweep") {
      EXPECT_EQ(tab10_colours_in(img), 3u) << name << ": three stages as bars";
    }
  }
  // A clustering keeps its colour from figure to figure: drift_correlation has no triangle BVH
  // series, and its clusterings take tab10 1, 2 and 3 as in drift_frames (they took 0, 1 and 2).
  {
    const RgbImage img = viz::read_png(n.out_dir / "drift_correlation.png");
    auto pixels = [&](Rgb8 c) {
      std::size_t px = 0;
      for (std::size_t i = 0; i < img.pixel_count(); ++i)
        px += img.rgb[3 * i] == c[0] && img.rgb[3 * i + 1] == c[1] && img.rgb[3 * i + 2] == c[2];
      return px;
    };
    EXPECT_LT(pixels({31, 119, 180}), 20u) << "tab10 0: the triangle BVH's colour";
    for (const Rgb8 c : {Rgb8{255, 127, 14}, Rgb8{44, 160, 44}, Rgb8{214, 39, 40}}) EXPECT_GE(pixels(c), 20u);
  }
  const nlohmann::json m = nlohmann::json::parse(slurp(n.out_dir / "manifest.json"));
  EXPECT_EQ(m["results"]["figures"].size(), 6u);
  EXPECT_EQ(m["parameters"]["studies"]["compare"], "../compare") << "paths relative to the notebook";
}

// What a figure could not draw is said in figures.json and on stderr, and its series count only
// what was drawn (found by a new user: a shard without the reference drew an empty Figure 7
// with "series": 1 and no note): a compare shard without its reference configuration, and a
// drift study of one frame.
TEST_F(Notebook, FiguresSayWhatTheyCouldNotDraw) {
  experiment("compare", [](ExperimentCommandOptions& o) {
    o.configs = "standard,acc_growth";
    o.reference = "standard";
    o.shard = "2/2";  // acc_growth only
  });
  one_frame_drift();
  std::string err;
  const nlohmann::json drawn = notebook_of_compare_and_drift(err);
  EXPECT_EQ(drawn["fig7_compare"]["series"], 0);
  const std::string fig7 = drawn["fig7_compare"]["note"];
  EXPECT_NE(fig7.find("1 of 1 configuration(s) without a performance factor"), std::string::npos) << fig7;
  EXPECT_NE(fig7.find("shard 2 of 2"), std::string::npos) << fig7;
  EXPECT_EQ(drawn["drift_correlation"]["series"], 0);
  EXPECT_EQ(drawn["drift_correlation"]["note"], "no frame after the first: drift needs --frames A:B with B > A");
  EXPECT_NE(err.find("ptc: note: fig7_compare: " + fig7), std::string::npos) << err;
  EXPECT_NE(err.find("ptc: note: drift_correlation: no frame after the first"), std::string::npos) << err;
}

// Studies of one frame draw it (found by a new user: a line of one point draws nothing, so
// Figure 7 of a one-frame compare showed an empty plot), and a fit that regression.csv could not
// make is said, not drawn as "fit: nan".
TEST_F(Notebook, OneFrameStudiesDrawTheirPoints) {
  experiment("compare", [](ExperimentCommandOptions& o) {
    o.frames = "2:2";
    o.configs = "standard,acc_growth";
    o.reference = "standard";
  });
  one_frame_drift();
  std::string err;
  const nlohmann::json drawn = notebook_of_compare_and_drift(err);
  EXPECT_EQ(drawn["fig7_compare"]["series"], 2);
  EXPECT_EQ(drawn["fig7_compare"]["note"], "");
  // Each series a marker in its colour (tab10 0 and 1): a legend entry alone has about 50 pixels
  // of it, with the marker in the plot and in the legend about 110-130 (measured; in
  // drift_frames the triangle BVH has a SAH panel only, its clusters' box drift being nan).
  EXPECT_EQ(tab10_colours_in(viz::read_png(dir_ / "nb" / "fig7_compare.png"), 90), 2u);
  EXPECT_EQ(tab10_colours_in(viz::read_png(dir_ / "nb" / "drift_frames.png"), 90), 2u);  // triangles, acc_growth
  const std::string fit = drawn["cost_fit"]["note"];
  EXPECT_NE(fit.find("no fit of SAH and EPO: 2 points for SAH (a fit needs at least 3"), std::string::npos) << fit;
  EXPECT_EQ(drawn["cost_fit"]["series"], 2);  // the two structures' points, no fit line
  EXPECT_NE(err.find("ptc: note: cost_fit: no fit of SAH and EPO"), std::string::npos) << err;
}

// A fit of points that all have the same SAH cost and EPO (one triangle: every frame's BVH is its
// leaf) is said to have nothing to vary, not to need more frames; the summary says why R^2 is nan.
TEST_F(Notebook, AFitOfEqualPointsSaysWhy) {
  const fs::path tri = dir_ / "tri1.off";
  test::spit(tri, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  ExperimentCommandOptions o;
  o.kind = "drift";
  o.input = tri;
  o.frames = "0:2";
  o.width = 32, o.height = 32;
  o.quiet = true;
  o.out_dir = dir_ / "study" / "drift";
  std::ostringstream summary;
  cmd_experiment(o, summary);
  EXPECT_NE(summary.str().find("(R^2 sah nan: the regressor has one value at every point)"), std::string::npos)
      << summary.str();
  NotebookCommandOptions n;
  n.studies = {dir_ / "study" / "drift"};
  n.out_dir = dir_ / "nb";
  std::ostringstream out;
  testing::internal::CaptureStderr();
  cmd_notebook(n, out);
  (void)testing::internal::GetCapturedStderr();
  const auto drawn = nlohmann::json::parse(test::slurp(dir_ / "nb" / "figures.json"));
  const std::string fit = drawn["cost_fit"]["note"];
  EXPECT_NE(fit.find("every point has the same SAH (0.3): nothing varies to fit"), std::string::npos) << fit;
  EXPECT_EQ(fit.find("needs"), std::string::npos) << fit;
}

TEST_F(Notebook, RefusesWhatIsNotAStudyAndAPythonWithoutPandas) {
  experiment("sweep", [](auto& o) { o.max_counts = "0,10"; });
  NotebookCommandOptions n;
  n.out_dir = dir_ / "nb";
  std::ostringstream out;
  EXPECT_THROW(cmd_notebook(n, out), UsageError);  // no DIR
  n.studies = {dir_};  // no manifest.json
  EXPECT_THROW(cmd_notebook(n, out), InputError);
  for (const auto& [where, why] : {std::pair{dir_ / "nowhere", "no such directory"},
                                   std::pair{dir_ / "study" / "sweep" / "manifest.json", "is a file"}}) {
    n.studies = {where};
    try {
      cmd_notebook(n, out);
      FAIL() << where;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(where.string() + ": " + why), std::string::npos) << e.what();
    }
  }
  n.studies = {dir_ / "study" / "sweep", dir_ / "study" / "sweep"};
  try {
    cmd_notebook(n, out);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a second sweep study"), std::string::npos) << e.what();
  }
  // A table the manifest lists that is missing, or edited: named before any Python runs.
  {
    fs::copy(dir_ / "study" / "sweep", dir_ / "edited", fs::copy_options::recursive);
    const fs::path t = dir_ / "edited" / "sweep_summary.csv";
    std::string text = slurp(t);
    text.back() = text.back() == '\n' ? ' ' : '\n';
    test::spit(t, text);
    n.studies = {dir_ / "edited"};
    try {
      cmd_notebook(n, out);
      FAIL();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(t.string() + ": its bytes differ"), std::string::npos) << e.what();
    }
    fs::remove(t);
    try {
      cmd_notebook(n, out);
      FAIL();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(t.string() + ": missing (its manifest lists it)"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir_ / "nb"));
  }
  n.studies = {dir_ / "study" / "sweep"};
  n.python = "/bin/true-not-there";
  EXPECT_THROW(cmd_notebook(n, out), InputError);
  // A Python that runs but has no pandas: /bin/false fails the import probe.
  n.python = "/bin/false";
  try {
    cmd_notebook(n, out);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("python3-pandas"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "nb"));
  // Without figures nothing needs Python: the notebook and the script are written.
  n.figures = false;
  cmd_notebook(n, out);
  EXPECT_TRUE(fs::exists(dir_ / "nb" / "paper_figures.ipynb"));
  EXPECT_TRUE(fs::exists(dir_ / "nb" / "paper_figures.py"));
  EXPECT_FALSE(fs::exists(dir_ / "nb" / "fig6_sweep.png"));
  // --out through a symbolic link: the notebook's relative path holds from the real directory.
  fs::create_directories(dir_ / "real" / "deeper");
  fs::create_directory_symlink(dir_ / "real" / "deeper", dir_ / "link");
  n.out_dir = dir_ / "link" / "nb";
  cmd_notebook(n, out);
  const nlohmann::json m = nlohmann::json::parse(slurp(dir_ / "real" / "deeper" / "nb" / "manifest.json"));
  const std::string rel = m["parameters"]["studies"]["sweep"];
  EXPECT_TRUE(fs::exists(dir_ / "real" / "deeper" / "nb" / rel / "sweep_summary.csv")) << rel;
}

}  // namespace
}  // namespace ptc
