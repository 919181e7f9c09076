#include "notebooks_export/notebook.h"

#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace ptc::notebooks {
namespace {

std::string py_str(const std::string& s) { return nlohmann::json(s).dump(); }  // a JSON string is a Python literal

std::string setup_code(const StudyInputs& in) {
  std::string study = "{";
  for (const auto& [k, d] : in.dirs) study += fmt::format("{}{}: {}", study.size() > 1 ? ", " : "", py_str(k), py_str(d));
  study += "}";
  std::string notes = "{";
  for (const auto& [k, n] : in.notes)
    if (!n.empty()) notes += fmt::format("{}{}: {}", notes.size() > 1 ? ", " : "", py_str(k), py_str(n));
  notes += "}";
  return fmt::format(R"PY(import json, math, os
import numpy as np
import pandas as pd
import matplotlib.pyplot as plt
from matplotlib.ticker import MaxNLocator

# The experiment outputs this notebook reads (written by `ptc experiment KIND ... --out DIR`),
# relative to the notebook's own directory.
STUDY = {}
STUDY_NOTES = {}  # experiment -> what a figure from it should say (a shard: part of the study)
FIGURES = {{}}  # name -> what the figure drew (figures.json)
COLOURS = plt.get_cmap("tab10").colors
STYLES = ["-", "--", ":", "-."]

def study_csv(kind, name, **kw):
    return pd.read_csv(os.path.join(STUDY[kind], name), **kw)

def after_warmup(df):
    """Rows after the first (warm-up) frame, as every summary of ptc leaves it out."""
    return df[df["warmup"] == 0] if "warmup" in df.columns else df

def line_style(i, points=2):
    """Colour and dash of series i; a marker where the series has one point (a line of one point
    draws nothing)."""
    s = dict(color=COLOURS[i % 10], linestyle=STYLES[(i // 10) % 4])
    if points < 2:
        s["marker"] = "o"
    return s

def save(fig, name, series, note="", kind=None):
    note = "; ".join(n for n in (note, STUDY_NOTES.get(kind, "")) if n)
    if note:
        fig.suptitle(note, fontsize=8, color="darkred", y=1.02)
        print(f"note: {{name}}: {{note}}")
    fig.savefig(name + ".png", dpi=100, bbox_inches="tight")
    fig.savefig(name + ".svg", bbox_inches="tight")
    FIGURES[name] = {{"series": int(series), "png": name + ".png", "svg": name + ".svg", "note": note}}
    with open("figures.json", "w") as f:
        json.dump(FIGURES, f, indent=1, sort_keys=True)
)PY",
                     study, notes);
}

const char* kFig6 = R"PY(s = study_csv("sweep", "sweep_summary.csv")
stages = ["update", "build", "trace"]
scenes = list(dict.fromkeys(s["scene"]))
fig, axes = plt.subplots(1, len(scenes), figsize=(6 * len(scenes), 4.2), squeeze=False)
for ax, scene in zip(axes[0], scenes):
    d = s[s["scene"] == scene]
    counts = sorted(d["max_count"].unique())
    x = np.arange(len(counts))
    w = 0.8 / len(stages)
    for i, st in enumerate(stages):
        ms = [d[(d["max_count"] == c) & (d["stage"] == st)]["median_ms"].median() for c in counts]
        ax.bar(x + (i - (len(stages) - 1) / 2) * w, ms, w, label=st, color=COLOURS[i])
    total = [d[(d["max_count"] == c) & (d["stage"] == "total")]["median_ms"].median() for c in counts]
    ax.plot(x, total, "k-o", label="total (whole frame)")
    ax.set_xticks(x)
    ax.set_xticklabels(["0 (triangles)" if c == 0 else str(c) for c in counts])
    ax.set_xlabel("MaxCount = MaxSize")
    ax.set_ylabel("median ms per frame")
    ax.set_title(f"Figure 6: {scene}")
    ax.legend()
save(fig, "fig6_sweep", len(stages) + 1, kind="sweep")
plt.show()
)PY";

const char* kFig7 = R"PY(c_all = study_csv("compare", "compare.csv")
c = after_warmup(c_all)
one_frame = c_all["frame"].nunique() == 1  # (ptc measures that one frame: no warm-up is left out)
summary = study_csv("compare", "compare_summary.csv")
configs = list(dict.fromkeys(c["config"]))
scenes = list(dict.fromkeys(c["scene"]))
finite = set()  # configurations with a performance factor to draw
fig, axes = plt.subplots(len(scenes), 1, figsize=(9, 4.5 * len(scenes)), squeeze=False)
for ax, scene in zip(axes[:, 0], scenes):
    d = c[c["scene"] == scene]
    for i, cfg in enumerate(configs):
        e = d[d["config"] == cfg].sort_values("frame")
        ax.plot(e["frame"], e["perf_factor"], label=cfg, **line_style(i, len(e)))
        if e["perf_factor"].notna().any():
            finite.add(cfg)
    ax.axhline(1.0, color="black", linestyle=":", linewidth=0.8)
    ref = summary[summary["scene"] == scene]["reference"].iloc[0]
    ax.set_xlabel("frame")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel(f"whole-frame time / {ref}'s")
    ax.set_title(f"Figure 7: {scene} (performance factor, " + ("its one frame" if one_frame else "frames after the warm-up") + ")")
    ax.legend(fontsize=8, ncol=2)
missing = len(configs) - len(finite)
save(fig, "fig7_compare", len(finite),
     f"{missing} of {len(configs)} configuration(s) without a performance factor (the reference configuration is "
     "not in this output: merge the shards first)" if missing else "", kind="compare")
plt.show()
)PY";

const char* kDriftFrames = R"PY(fr = study_csv("drift", "frames.csv")
clusterings = list(dict.fromkeys(fr["clustering"]))
fig, (a, b) = plt.subplots(1, 2, figsize=(13, 4.2))
drawn = 0
for i, cl in enumerate(clusterings):
    e = fr[fr["clustering"] == cl].sort_values("frame")
    if e["box_area_ratio_p95"].notna().any():
        a.plot(e["frame"], e["box_area_ratio_p95"], label=cl, **line_style(i, len(e)))
    b.plot(e["frame"], e["sah_cost"], label=cl, **line_style(i, len(e)))
    drawn += 1
a.axhline(1.0, color="black", linestyle=":", linewidth=0.8)
a.xaxis.set_major_locator(MaxNLocator(integer=True)); b.xaxis.set_major_locator(MaxNLocator(integer=True))
a.set_xlabel("frame"); a.set_ylabel("p95 over clusters of box area / the first frame's"); a.set_title("box-area drift per clustering (every frame)")
b.set_xlabel("frame"); b.set_ylabel("SAH cost of the frame's BVH"); b.set_title("SAH cost per frame (triangles: the triangle BVH)")
a.legend(fontsize=8); b.legend(fontsize=8)
save(fig, "drift_frames", drawn, kind="drift")
plt.show()
)PY";

const char* kDriftCorrelation = R"PY(frames = study_csv("drift", "frames.csv")
first = frames.groupby("clustering")["frame"].min()
parts = []
cols = ["clustering", "frame", "cluster_id", "connectivity", "box_area_ratio"]
for ch in pd.read_csv(os.path.join(STUDY["drift"], "clusters_frames.csv"), usecols=cols, chunksize=2_000_000):
    ch = ch[ch["frame"] > ch["clustering"].map(first)]
    d = np.abs(np.log(ch["box_area_ratio"]))
    ch = ch.assign(d=d.where(~(d < 1e-12), 0.0))  # rounding, not motion: as correlation.csv counts it
    parts.append(ch.groupby(["clustering", "cluster_id"]).agg(conn=("connectivity", "max"), s=("d", "sum"), n=("d", "count")))
per = pd.concat(parts).groupby(level=[0, 1]).agg(conn=("conn", "max"), s=("s", "sum"), n=("n", "sum"))
per["drift"] = per["s"] / per["n"]
corr = study_csv("drift", "correlation.csv")
corr = corr[(corr["x"] == "connectivity") & (corr["y"] == "box_area_drift")]
clusterings = [c for c in dict.fromkeys(per.index.get_level_values(0))]
structures = list(dict.fromkeys(frames["clustering"]))  # (each one's colour as in drift_frames)
fig, ax = plt.subplots(figsize=(7.5, 5))
rng = np.random.default_rng(1)
for i, cl in enumerate(clusterings):
    p = per.loc[cl]
    if len(p) > 3000:
        p = p.iloc[np.sort(rng.choice(len(p), 3000, replace=False))]
    rho = corr[corr["clustering"] == cl]["spearman"]
    label = f"{cl} (Spearman {rho.iloc[0]:+.2f})" if len(rho) and np.isfinite(rho.iloc[0]) else f"{cl} (no Spearman: see summary.txt)"
    ax.scatter(p["conn"], p["drift"], s=4, color=COLOURS[structures.index(cl) % 10] if cl in structures else COLOURS[i % 10], label=label)
ax.set_xlabel("connectivity (triangles / vertices)")
ax.set_ylabel("mean |ln(box area / the first frame's)| over the frames after it")
ax.set_title("connectivity against box-area drift (up to 3000 clusters per clustering)")
ax.legend(fontsize=8, markerscale=3)
save(fig, "drift_correlation", len(clusterings),
     "" if len(clusterings) else "no frame after the first: drift needs --frames A:B with B > A", kind="drift")
plt.show()
)PY";

const char* kCostFit = R"PY(rays = after_warmup(study_csv("drift", "rays.csv"))
rays = rays[rays["ray_type"] == "primary"]
reg = study_csv("drift", "regression.csv")
reg = reg[(reg["ray_type"] == "primary") & (reg["target"] == "cost_per_ray")]
clusterings = list(dict.fromkeys(rays["clustering"]))
fig, axes = plt.subplots(1, 2, figsize=(13, 4.8))
fits = 0
unfitted = []
why = []
for ax, col, model in zip(axes, ["sah_cost", "epo"], ["sah", "epo"]):
    for i, cl in enumerate(clusterings):
        e = rays[rays["clustering"] == cl]
        ax.scatter(e[col], e["cost_per_ray"], s=10, color=COLOURS[i % 10], label=cl)
    f = reg[reg["model"] == model]
    coef = np.nan
    if len(f):
        f = f.iloc[0]
        coef = f["coef_sah"] if model == "sah" else f["coef_epo"]
    if len(f) and rays[col].notna().any() and np.isfinite([coef, f["intercept"]]).all():
        x = np.linspace(rays[col].min(), rays[col].max(), 50)
        ax.plot(x, coef * x + f["intercept"], "k-", label=f"fit: {coef:.3f} {model.upper()} {f['intercept']:+.2f}, R^2 {f['r2']:.3f}")
        fits = 1
    else:
        unfitted.append(model.upper())
        pts = rays[[col, "cost_per_ray"]].dropna()
        if len(pts) < 3:
            why.append(f"{len(pts)} points for {model.upper()} (a fit needs at least 3: --frames A:B with B > A, or more structures)")
        elif pts[col].nunique() < 2:
            why.append(f"every point has the same {model.upper()} ({pts[col].iloc[0]:.6g}): nothing varies to fit")
        else:
            why.append(f"{len(pts)} points for {model.upper()} but no fit in regression.csv")
    ax.set_xlabel("SAH cost of the frame's BVH" if model == "sah" else "EPO of the frame's BVH")
    ax.set_ylabel("measured cost per primary ray (nodes + weighted triangles)")
    ax.set_title(f"{model.upper()} against the measured cost (primary rays)")
    ax.legend(fontsize=8)
save(fig, "cost_fit", len(clusterings) + fits,
     f"no fit of {' and '.join(unfitted)}: " + "; ".join(why) if unfitted else "", kind="drift")
plt.show()
)PY";

const char* kSpeedError = R"PY(acc = study_csv("accuracy", "accuracy.csv")
groups = list(dict.fromkeys(acc["group"]))
cols = 2 if len(groups) > 1 else 1
rows = math.ceil(len(groups) / cols)
fig, axes = plt.subplots(rows, cols, figsize=(6.5 * cols, 4.4 * rows), squeeze=False, constrained_layout=True)
for i, g in enumerate(groups):
    ax = axes[i // cols][i % cols]
    d = acc[acc["group"] == g]
    e = d.groupby("choice", sort=False).agg(speedup=("speedup", "median"), err=("error_mean", "median")).reset_index()
    ax.scatter(e["speedup"], e["err"], s=36, color=COLOURS[i % 10], label=g)
    for _, r in e.iterrows():
        ax.annotate(r["choice"], (r["speedup"], r["err"]), fontsize=7, xytext=(3, 3), textcoords="offset points")
    # Log axes only where the values span more than a decade (within one, a log axis shows one
    # tick or none, and a symlog axis none inside its linear range).
    sp = e["speedup"].dropna()
    if len(sp) and (sp > 0).all() and sp.max() > 10 * sp.min():
        ax.set_xscale("log")
    # Errors spanning decades: log when all are positive; else symlog, linear below the decade of
    # the smallest non-zero one, and no negative range when there are no negative errors.
    err = e["err"].dropna()
    small = err.abs()[err != 0]
    wide = len(small) > 0 and small.max() > 10 * small.min()
    if wide and (err > 0).all():
        ax.set_yscale("log")
    elif wide:
        ax.set_yscale("symlog", linthresh=float(10.0 ** np.floor(np.log10(small.min()))))
        if (err >= 0).all():
            ax.set_ylim(bottom=0.0)
    ax.set_xlabel(f"speed-up over {d['reference'].iloc[0]} (median over frames)")
    ax.set_ylabel(f"{d['error'].iloc[0]} (mean, median over frames)")
    ax.set_title(f"speed against error: {g}")
for j in range(len(groups), rows * cols):
    axes[j // cols][j % cols].axis("off")
save(fig, "speed_vs_error", len(groups), kind="accuracy")
plt.show()
)PY";

std::vector<std::string> lines_of(const std::string& s) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start < s.size()) {
    const std::size_t nl = s.find('\n', start);
    if (nl == std::string::npos) {
      out.push_back(s.substr(start));
      break;
    }
    out.push_back(s.substr(start, nl + 1 - start));
    start = nl + 1;
  }
  if (!out.empty() && out.back().ends_with('\n')) out.back().pop_back();  // nbformat: no final newline
  return out;
}

nlohmann::json cell(const std::string& type, const std::string& id, const std::string& source) {
  nlohmann::json c = {{"cell_type", type}, {"id", id}, {"metadata", nlohmann::json::object()}, {"source", lines_of(source)}};
  if (type == "code") c["execution_count"] = nullptr, c["outputs"] = nlohmann::json::array();
  return c;
}

std::string title_markdown(const StudyInputs& in) {
  std::string s = "# The paper's figures from ptc's experiment tables\n\n"
                  "Garanzha 2009, *The use of precomputed triangle clusters for accelerated ray tracing in dynamic "
                  "scenes*, redrawn from the CSVs of `ptc experiment` (docs/experiments.md says what every column "
                  "holds and how it is measured). Times and costs leave out the first frame of every run (its "
                  "warm-up), as ptc's own summaries do; the drift plots show every frame, the first being the "
                  "reference of their ratios.\n\n| experiment | directory | scene |\n|---|---|---|\n";
  for (const auto& [k, d] : in.dirs) {
    const auto sc = in.scenes.find(k);
    const auto no = in.notes.find(k);
    s += fmt::format("| {} | `{}` | {}{} |\n", k, d, sc == in.scenes.end() ? "" : sc->second,
                     no == in.notes.end() || no->second.empty() ? "" : " (" + no->second + ")");
  }
  return s;
}

}  // namespace

std::vector<Figure> figures_for(const StudyInputs& in) {
  std::vector<Figure> f;
  auto has = [&](const char* k) { return in.dirs.count(k) > 0; };
  if (has("sweep"))
    f.push_back({"fig6_sweep", "sweep",
                 "## Figure 6: the frame's stages per MaxCount\n\nMedian milliseconds per frame of the update "
                 "(positions to primitive boxes), the build (until the BVH is traceable) and the trace (primary + "
                 "shadow rays) for MaxCount = MaxSize in the sweep; 0 is the triangle BVH. From `sweep_summary.csv`.",
                 kFig6});
  if (has("compare"))
    f.push_back({"fig7_compare", "compare",
                 "## Figure 7: performance factor per frame\n\nWhole-frame time (update + build + trace) of every "
                 "configuration divided by the reference's at the same frame (`compare.csv`, column `perf_factor`); "
                 "below 1 is faster than the reference. One line per configuration.",
                 kFig7});
  if (has("drift")) {
    f.push_back({"drift_frames", "drift",
                 "## Drift over the frames\n\nLeft: the 95th percentile over clusters of each cluster's box area "
                 "relative to frame 0 (`frames.csv`, `box_area_ratio_p95`); right: the SAH cost of the frame's BVH "
                 "per clustering (the triangle BVH as `triangles`).",
                 kDriftFrames});
    f.push_back({"drift_correlation", "drift",
                 "## Connectivity against drift\n\nPer cluster: connectivity (triangles / vertices) against the mean "
                 "|ln box-area ratio| over the frames after the first, aggregated from `clusters_frames.csv` in "
                 "chunks (it can be large); the legend gives the Spearman rank correlation of `correlation.csv` over "
                 "all clusters (the scatter shows at most 3000 per clustering).",
                 kDriftCorrelation});
    f.push_back({"cost_fit", "drift",
                 "## SAH and EPO against the measured cost\n\nPer frame and clustering: the SAH cost (left) and the "
                 "end-point overlap EPO (right) of the frame's BVH against the measured cost per primary ray "
                 "(`rays.csv`), each with its least-squares line from `regression.csv` (models `sah` and `epo`, "
                 "their R^2; the file also holds SAH + EPO and the time fits).",
                 kCostFit});
  }
  if (has("accuracy"))
    f.push_back({"speed_vs_error", "accuracy",
                 "## Speed against error\n\nEvery approximation of `ptc experiment accuracy` (`accuracy.csv`): its "
                 "speed-up over its reference and its error (`error` names the measure, `error_mean` is its value), "
                 "medians over the frames, one panel and colour per group.",
                 kSpeedError});
  return f;
}

std::string notebook_json(const StudyInputs& in, const std::vector<Figure>& figures) {
  nlohmann::json cells = nlohmann::json::array();
  cells.push_back(cell("markdown", "title", title_markdown(in)));
  cells.push_back(cell("code", "setup", "%matplotlib inline\n" + setup_code(in)));
  for (const Figure& f : figures) {
    std::string id = f.name;
    for (char& ch : id)
      if (ch == '_') ch = '-';
    cells.push_back(cell("markdown", id + "-text", f.markdown));
    cells.push_back(cell("code", id + "-code", f.code));
  }
  const nlohmann::json nb = {
      {"cells", cells},
      {"metadata",
       {{"kernelspec", {{"display_name", "Python 3 (ipykernel)"}, {"language", "python"}, {"name", "python3"}}},
        {"language_info", {{"name", "python"}}},
        {"ptc", {{"generator", "ptc notebook"}, {"figures", [&] {
                   nlohmann::json a = nlohmann::json::array();
                   for (const Figure& f : figures) a.push_back(f.name);
                   return a;
                 }()}}}}},
      {"nbformat", 4},
      {"nbformat_minor", 5}};
  return nb.dump(1) + "\n";
}

std::string figures_script(const StudyInputs& in, const std::vector<Figure>& figures) {
  std::ostringstream s;
  s << "#!/usr/bin/env python3\n"
       "# The paper's figures from ptc's experiment tables: the code cells of the notebook beside this\n"
       "# script, in a row. Run it with Debian's Python (python3-pandas, python3-matplotlib):\n"
       "#   /usr/bin/python3 " "paper_figures.py   (in this directory; writes NAME.png, NAME.svg, figures.json)\n"
       "import matplotlib\n"
       "matplotlib.use(\"Agg\")\n"
       "import os\n"
       "os.chdir(os.path.dirname(os.path.abspath(__file__)))\n";
  s << setup_code(in) << "\n";
  for (const Figure& f : figures) s << "# ---- " << f.name << "\n" << f.code << "plt.close(\"all\")\n\n";
  s << "print(\"wrote \" + \", \".join(sorted(FIGURES)) + \" (.png, .svg) and figures.json\")\n";
  return s.str();
}

}  // namespace ptc::notebooks
