// assemble(): the derived columns and tables of every experiment and its printed summary, from
// the primary files' rows (CSV text). The same code serves a single run, a shard and `ptc merge`.
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "analysis/experiments/accuracy.h"
#include "analysis/experiments/experiments.h"
#include "toolkit/core/stats.h"
#include "toolkit/core/strings.h"

namespace ptc {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

FileRows& file_of(std::vector<FileRows>& files, std::string_view name) {
  for (auto& f : files)
    if (f.file == name) return f;
  throw std::invalid_argument("no " + std::string(name) + " among the experiment's files");
}

// Rows grouped by the values of some columns, groups in order of first appearance.
struct Groups {
  std::vector<std::vector<std::string>> keys;
  std::vector<std::vector<std::size_t>> rows;
};
Groups group_by(const CsvText& t, const std::vector<std::string>& columns,
                const std::function<bool(std::size_t)>& keep = nullptr) {
  std::vector<std::size_t> idx;
  for (const auto& c : columns) idx.push_back(t.column(c));
  Groups g;
  std::map<std::vector<std::string>, std::size_t> at;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    if (keep && !keep(r)) continue;
    std::vector<std::string> k;
    for (std::size_t i : idx) k.push_back(t.rows[r][i]);
    auto [it, fresh] = at.emplace(k, g.keys.size());
    if (fresh) g.keys.push_back(k), g.rows.emplace_back();
    g.rows[it->second].push_back(r);
  }
  return g;
}

double median_of(const CsvText& t, const std::vector<std::size_t>& rows, std::size_t col) {
  std::vector<double> v;
  for (std::size_t r : rows) {
    const double x = t.number(r, col);
    if (!std::isnan(x)) v.push_back(x);
  }
  return v.empty() ? kNaN : median(v);
}

// Rows that summaries use: not the warm-up frame.
std::function<bool(std::size_t)> measured(const CsvText& t) {
  const std::size_t w = t.column("warmup");
  return [&t, w](std::size_t r) { return t.rows[r][w] != "1"; };
}

std::string num(double x) { return format_double(x); }

// Whether no primary ray hit the mesh in any measured row (a camera that sees past the mesh or
// from inside it): the trace times then time rays through empty space, and the paper's verdicts
// on trace times are left out. A table without hits (a shard of ptc-sweep/1) and one without
// measured rows count as hit.
bool nothing_hit(const CsvText& t, const std::function<bool(std::size_t)>& keep) {
  if (!t.has_column("hits")) return false;
  const std::size_t h = t.column("hits");
  bool any = false;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    if (!keep(r)) continue;
    if (t.number(r, h) > 0) return false;
    any = true;
  }
  return any;
}

constexpr const char* kNoHitVerdicts =
    "no primary ray hit the mesh in any measured frame, so the trace times time rays through empty space (the "
    "camera sees past the mesh or from inside it: --eye, --look-at, --fov)";

std::string ratio_text(double x) { return std::isfinite(x) ? fmt::format("{:.2f}x", x) : std::string("-"); }

// ---------------------------------------------------------------- sweep

void assemble_sweep(std::vector<FileRows>& files, std::string& text) {
  const CsvText& s = file_of(files, "sweep.csv").rows;
  FileRows out = file_rows("sweep_summary.csv", {"ptc-sweep-summary", 1},
                         {"scene", "max_count", "primitives", "stage", "frames", "median_ms", "speedup_vs_max_count_0"});
  const Groups g = group_by(s, {"scene", "max_count", "primitives", "stage"}, measured(s));
  const std::size_t ms = s.column("ms");
  std::map<std::pair<std::string, std::string>, double> standard;  // (scene, stage) -> median at MaxCount 0
  std::vector<double> med(g.keys.size());
  for (std::size_t i = 0; i < g.keys.size(); ++i) {
    med[i] = median_of(s, g.rows[i], ms);
    if (g.keys[i][1] == "0") standard[{g.keys[i][0], g.keys[i][3]}] = med[i];
  }
  std::map<std::string, std::map<std::string, double>> by_count;  // max_count -> stage -> median
  std::map<std::string, std::string> clusters_of, scene_of;
  std::map<std::string, std::size_t> frames_of;
  std::vector<std::string> counts;
  for (std::size_t i = 0; i < g.keys.size(); ++i) {
    const auto it = standard.find({g.keys[i][0], g.keys[i][3]});
    const double speedup = it != standard.end() && med[i] > 0 ? it->second / med[i] : kNaN;
    out.rows.rows.push_back({g.keys[i][0], g.keys[i][1], g.keys[i][2], g.keys[i][3], std::to_string(g.rows[i].size()),
                             num(med[i]), num(speedup)});
    if (!by_count.count(g.keys[i][1])) counts.push_back(g.keys[i][1]);
    by_count[g.keys[i][1]][g.keys[i][3]] = med[i];
    clusters_of[g.keys[i][1]] = g.keys[i][2];
    scene_of[g.keys[i][1]] = g.keys[i][0];
    frames_of[g.keys[i][1]] = g.rows[i].size();
  }
  text += "sweep (the paper's Figure 6): medians per MaxCount = MaxSize, ms; ratios against MaxCount 0 (> 1: faster)\n";
  text += fmt::format("{:>9} {:>9} {:>10} {:>10} {:>10} {:>10} {:>13} {:>11} {:>11}\n", "MaxCount", "prims", "update",
                      "build", "trace", "total", "upd+build vs0", "trace vs0", "total vs0");
  const auto zero = by_count.find("0");
  for (const auto& c : counts) {
    auto& st = by_count[c];
    const double ub = st["update"] + st["build"];
    double ub0 = kNaN, tr0 = kNaN, to0 = kNaN;
    if (zero != by_count.end()) {
      ub0 = zero->second["update"] + zero->second["build"];
      tr0 = zero->second["trace"];
      to0 = zero->second["total"];
    }
    // The printed update + build ratio is in the CSV too: a row of stage update+build (the sum of
    // the two medians, and MaxCount 0's sum over it).
    out.rows.rows.push_back({scene_of[c], c, clusters_of[c], "update+build", std::to_string(frames_of[c]), num(ub),
                             num(ub > 0 ? ub0 / ub : kNaN)});
    text += fmt::format("{:>9} {:>9} {:>10.2f} {:>10.2f} {:>10.2f} {:>10.2f} {:>13} {:>11} {:>11}\n", c, clusters_of[c],
                        st["update"], st["build"], st["trace"], st["total"], ratio_text(ub > 0 ? ub0 / ub : kNaN),
                        ratio_text(st["trace"] > 0 ? tr0 / st["trace"] : kNaN),
                        ratio_text(st["total"] > 0 ? to0 / st["total"] : kNaN));
  }
  // Against the paper (Garanzha 2009, "Expected results" of issue 12), with the criterion stated.
  const auto at = [&](const char* n) -> std::map<std::string, double>* { return by_count.count(n) ? &by_count[n] : nullptr; };
  if (auto *z = at("0"), *f = at("50"); z && f) {
    const double ub = ((*z)["update"] + (*z)["build"]) / ((*f)["update"] + (*f)["build"]);
    text += fmt::format("paper: update+build about an order of magnitude faster at MaxCount 50 -> {}x: {} (criterion "
                        "3.16x..31.6x)\n",
                        verdict_number(ub, 1, {3.16, 31.6}), ub >= 3.16 && ub <= 31.6 ? "agrees" : "DISAGREES");
    const double tr = (*z)["trace"] / (*f)["trace"];
    if (nothing_hit(s, measured(s))) {
      text += fmt::format("paper: no verdicts on the trace time: {}\n", kNoHitVerdicts);
    } else {
      text += fmt::format("paper: trace time about unchanged at MaxCount 50 -> {}x of MaxCount 0: {} (criterion "
                          "0.8x..1.25x)\n",
                          verdict_number(tr, 2, {0.8, 1.25}), tr >= 0.8 && tr <= 1.25 ? "agrees" : "DISAGREES");
      if (auto* h = at("100")) {
        const double tr100 = (*z)["trace"] / (*h)["trace"];
        text += fmt::format("paper: trace worse at MaxCount 100 than at 50 -> {}x vs {}x: {}\n", verdict_number(tr100, 2, {tr}),
                            verdict_number(tr, 2, {tr100}), tr100 < tr ? "agrees" : "DISAGREES");
      }
    }
  }
  files.push_back(std::move(out));
}

// ---------------------------------------------------------------- compare

void assemble_compare(std::vector<FileRows>& files, std::string& text, const std::string& reference) {
  CsvText& c = file_of(files, "compare.csv").rows;
  const std::size_t total = c.column("total_ms"), pf = c.column("perf_factor"), cfg = c.column("config"),
                    frame = c.column("frame"), scene = c.column("scene");
  std::map<std::pair<std::string, std::string>, double> ref;  // (scene, frame) -> the reference's total
  for (const auto& r : c.rows)
    if (r[cfg] == reference) ref[{r[scene], r[frame]}] = c.number(&r - c.rows.data(), total);
  for (std::size_t i = 0; i < c.rows.size(); ++i) {
    const auto it = ref.find({c.rows[i][scene], c.rows[i][frame]});
    const double t = c.number(i, total);
    c.rows[i][pf] = num(it != ref.end() && it->second > 0 ? t / it->second : kNaN);
  }
  FileRows out = file_rows("compare_summary.csv", {"ptc-compare-summary", 1},
                         {"scene", "config", "reference", "frames", "update_ms", "build_ms", "trace_ms", "total_ms",
                          "perf_factor", "perf_factor_first", "perf_factor_last", "perf_factor_early", "perf_factor_late",
                          "perf_factor_min", "perf_factor_max"});
  const Groups g = group_by(c, {"scene", "config"}, measured(c));
  std::map<std::string, std::pair<double, double>> early_late;
  std::map<std::string, std::size_t> measured_frames;  // frames with a factor, per configuration
  text += fmt::format("compare (the paper's Figure 7): medians per configuration, ms; perf_factor = total / total of {} "
                      "(> 1: slower than it)\n",
                      reference);
  text += fmt::format("{:<16} {:>9} {:>9} {:>9} {:>9} {:>11} {:>11} {:>11}\n", "config", "update", "build", "trace",
                      "total", "perf_factor", "pf first", "pf last");
  for (std::size_t i = 0; i < g.keys.size(); ++i) {
    const auto& rows = g.rows[i];
    std::vector<double> pfs;  // the measured frames' factors in frame order (NaN ones left out)
    for (std::size_t r : rows)
      if (const double x = c.number(r, pf); !std::isnan(x)) pfs.push_back(x);
    const double u = median_of(c, rows, c.column("update_ms")), b = median_of(c, rows, c.column("build_ms")),
                 t = median_of(c, rows, c.column("trace_ms")), to = median_of(c, rows, total),
                 p = median_of(c, rows, pf);
    const double first = pfs.empty() ? kNaN : pfs.front(), last = pfs.empty() ? kNaN : pfs.back();
    double lo = kNaN, hi = kNaN;
    for (double x : pfs)
      if (std::isfinite(x)) lo = std::isnan(lo) ? x : std::min(lo, x), hi = std::isnan(hi) ? x : std::max(hi, x);
    // Early and late: the medians over the first and the last quarter of the measured frames.
    const std::size_t q = std::max<std::size_t>(1, pfs.size() / 4);
    std::vector<double> e(pfs.begin(), pfs.begin() + long(std::min(q, pfs.size()))),
        l(pfs.end() - long(std::min(q, pfs.size())), pfs.end());
    const double early = pfs.empty() ? kNaN : median(e), late = pfs.empty() ? kNaN : median(l);
    early_late[g.keys[i][1]] = {early, late};
    measured_frames[g.keys[i][1]] = pfs.size();
    out.rows.rows.push_back({g.keys[i][0], g.keys[i][1], reference, std::to_string(rows.size()), num(u), num(b), num(t),
                             num(to), num(p), num(first), num(last), num(early), num(late), num(lo), num(hi)});
    text += fmt::format("{:<16} {:>9.2f} {:>9.2f} {:>9.2f} {:>9.2f} {:>11} {:>11} {:>11}\n", g.keys[i][1], u, b, t, to,
                        ratio_text(p), ratio_text(first), ratio_text(last));
  }
  const bool verdicts = (reference == "given" || reference.rfind("acc_", 0) == 0) &&  // the paper's claim is against the method
                        (early_late.count("naive") || early_late.count("gwh01"));
  if (ref.empty()) text += fmt::format("(the reference {} is not among these rows: perf_factor is nan)\n", reference);
  else if (verdicts && nothing_hit(c, measured(c)))
    text += fmt::format("paper: no verdicts on the clusterings' whole frames: {}\n", kNoHitVerdicts);
  else if (verdicts)
    for (const char* b : {"naive", "gwh01"}) {
      const auto it = early_late.find(b);
      if (it == early_late.end()) continue;
      const auto [e, l] = it->second;
      if (measured_frames[b] < 2) {  // early and late would be one frame
        text += fmt::format("paper: no verdict on {} clusters early and later: {} measured frame{} (early and late "
                            "need two; the first frame is the warm-up: --frames A:B with B >= A + 2)\n",
                            b, measured_frames[b], measured_frames[b] == 1 ? "" : "s");
        continue;
      }
      const bool close = e >= 0.9 && e <= 1.1, behind = l > e * 1.05;  // (the bounds verdict_number is given)
      text += fmt::format("paper: {} clusters close to the method early and behind it later -> perf_factor {} over "
                          "the first quarter of the frames, {} over the last: {} (criterion: early within 10% of 1, "
                          "late 5% above early)\n",
                          b, verdict_number(e, 2, {0.9, 1.1, l / 1.05}), verdict_number(l, 2, {e * 1.05}), close && behind ? "agrees" : close ? "DISAGREES (not behind later)" : "DISAGREES (not close early)");
    }
  files.push_back(std::move(out));
}

// ---------------------------------------------------------------- drift

struct Fit {
  double a = kNaN, b = kNaN, c = kNaN, r2 = kNaN;
  std::string why;  // why r2 is nan ("" when it is not)
};
// Least squares y = X beta (columns of X: the regressors and a 1), R^2 = 1 - SSres / SStot.
Fit least_squares(const std::vector<std::vector<double>>& x, const std::vector<double>& y) {
  Fit f;
  const std::size_t n = y.size(), k = x.size();
  if (n < k + 2) {
    f.why = fmt::format("{} point{}, a fit of {} term{} needs {}", n, n == 1 ? "" : "s", k + 1, k ? "s" : "", k + 2);
    return f;
  }
  Eigen::MatrixXd a(n, k + 1);
  Eigen::VectorXd b(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < k; ++j) a(i, j) = x[j][i];
    a(i, k) = 1.0;
    b(i) = y[i];
  }
  const auto qr = a.colPivHouseholderQr();
  // A regressor that does not vary (or two that vary together) leaves the fit undetermined:
  // no coefficients rather than made-up ones.
  if (qr.rank() < static_cast<Eigen::Index>(k + 1)) {
    f.why = k == 1 ? "the regressor has one value at every point" : "a regressor has one value at every point, or two vary together";
    return f;
  }
  const Eigen::VectorXd beta = qr.solve(b);
  const double mean = b.mean();
  const double ss_tot = (b.array() - mean).square().sum(), ss_res = (a * beta - b).squaredNorm();
  if (k >= 1) f.a = beta(0);
  if (k >= 2) f.b = beta(1);
  f.c = beta(k);
  f.r2 = ss_tot > 0 ? 1.0 - ss_res / ss_tot : kNaN;
  if (!(ss_tot > 0)) f.why = "the measured values are all equal";
  return f;
}

void assemble_drift(std::vector<FileRows>& files, std::string& text) {
  const CsvText& rays = file_of(files, "rays.csv").rows;
  const CsvText& frames = file_of(files, "frames.csv").rows;
  const CsvText& corr = file_of(files, "correlation.csv").rows;
  FileRows reg = file_rows("regression.csv", {"ptc-drift-regression", 1},
                         {"ray_type", "target", "model", "points", "coef_sah", "coef_epo", "coef_nodes", "coef_triangles",
                          "intercept", "r2", "epo_weight", "triangle_weight"});
  const Groups g = group_by(rays, {"ray_type"}, measured(rays));  // the warm-up frame left out, as everywhere
  const std::size_t sah = rays.column("sah_cost"), epo = rays.column("epo"), nodes = rays.column("nodes_per_ray"),
                    tris = rays.column("triangles_per_ray");
  constexpr double kTinyBvhEpoWeight = 0.71;
  std::string fits;
  // The measured cost per ray: the counters weighted by the SAH model (cost_per_ray), and the
  // time (ns_per_ray); the second also against the counters themselves, which gives what a
  // triangle test costs relative to a node visit in this tracer (triangle_weight).
  for (const char* target : {"cost_per_ray", "ns_per_ray"}) {
    const std::size_t y = rays.column(target);
    for (std::size_t i = 0; i < g.keys.size(); ++i) {
      std::vector<double> ys, ss, es, combined, ns, ts;
      for (std::size_t r : g.rows[i]) {
        const double yy = rays.number(r, y), s = rays.number(r, sah), e = rays.number(r, epo),
                     n = rays.number(r, nodes), t = rays.number(r, tris);
        if (!std::isfinite(yy) || !std::isfinite(s) || !std::isfinite(e) || !std::isfinite(n) || !std::isfinite(t)) continue;
        ys.push_back(yy), ss.push_back(s), es.push_back(e), combined.push_back(s + kTinyBvhEpoWeight * e);
        ns.push_back(n), ts.push_back(t);
      }
      const std::string& type = g.keys[i][0];
      auto row = [&](const char* model, const Fit& f, double cs, double ce, double cn, double ct) {
        reg.rows.rows.push_back({type, target, model, std::to_string(ys.size()), num(cs), num(ce), num(cn), num(ct),
                                 num(f.c), num(f.r2),
                                 num(std::isfinite(cs) && std::isfinite(ce) && cs != 0 ? ce / cs : kNaN),
                                 num(std::isfinite(cn) && std::isfinite(ct) && cn != 0 ? ct / cn : kNaN)});
      };
      const Fit fs = least_squares({ss}, ys), fe = least_squares({es}, ys), fse = least_squares({ss, es}, ys),
                ft = least_squares({combined}, ys);
      row("sah", fs, fs.a, kNaN, kNaN, kNaN);
      row("epo", fe, kNaN, fe.a, kNaN, kNaN);
      row("sah+epo", fse, fse.a, fse.b, kNaN, kNaN);
      row("sah+0.71epo", ft, ft.a, ft.a * kTinyBvhEpoWeight, kNaN, kNaN);
      std::string counters;
      if (std::string_view(target) == "ns_per_ray") {
        const Fit fc = least_squares({ns, ts}, ys);
        row("nodes+triangles", fc, kNaN, kNaN, fc.a, fc.b);
        counters = fmt::format(", nodes+triangles {:.3f} (a triangle test = {:.3g} node visits)", fc.r2,
                               fc.a != 0 ? fc.b / fc.a : kNaN);
      }
      fits += fmt::format("  {:<12} {:<8} {:>4} points: R^2 sah {:.3f}, epo {:.3f}, sah+epo {:.3f} (EPO weight {:.3g}), "
                          "sah+0.71 epo {:.3f}{}\n",
                          target, type, ys.size(), fs.r2, fe.r2, fse.r2, fse.a != 0 ? fse.b / fse.a : kNaN, ft.r2, counters);
      for (const auto& [model, f] : {std::pair<const char*, const Fit*>{"sah", &fs}, {"epo", &fe}, {"sah+epo", &fse}})
        if (!f->why.empty()) {  // (the first model's reason: the others' follow from it)
          fits += fmt::format("    (R^2 {} nan: {})\n", model, f->why);
          break;
        }
    }
  }
  // Per clustering: the first and last frame.
  text += "drift: per clustering, first -> last frame (box_area_ratio against the first frame)\n";
  text += fmt::format("{:<16} {:>9} {:>17} {:>17} {:>15} {:>15} {:>12} {:>12} {:>10}\n", "clustering", "clusters",
                      "SAH cost", "SAH triangles", "EPO", "nodes/ray", "box max", "box p95", "spearman");
  const Groups fg = group_by(frames, {"clustering"});
  std::map<std::string, std::pair<double, double>> rho;  // clustering -> (Spearman, the clusters it could use)
  for (std::size_t r = 0; r < corr.rows.size(); ++r)
    if (corr.rows[r][corr.column("y")] == "box_area_drift")
      rho[corr.rows[r][corr.column("clustering")]] = {corr.number(r, corr.column("spearman")),
                                                      corr.number(r, corr.column("clusters"))};
  auto cell = [&](std::size_t r, const char* col) { return frames.number(r, frames.column(col)); };
  for (std::size_t i = 0; i < fg.keys.size(); ++i) {
    const std::size_t a = fg.rows[i].front(), b = fg.rows[i].back();
    const auto it = rho.find(fg.keys[i][0]);
    text += fmt::format("{:<16} {:>9} {:>7.2f} -> {:>6.2f} {:>7.2f} -> {:>6.2f} {:>6.2f} -> {:>5.2f} {:>6.1f} -> {:>5.1f} "
                        "{:>12.3f} {:>12.3f} {:>10}\n",
                        fg.keys[i][0], frames.rows[a][frames.column("clusters")], cell(a, "sah_cost"), cell(b, "sah_cost"),
                        cell(a, "sah_cost_triangles"), cell(b, "sah_cost_triangles"), cell(a, "epo"), cell(b, "epo"),
                        cell(a, "nodes_per_ray"), cell(b, "nodes_per_ray"), cell(b, "box_area_ratio_max"),
                        cell(b, "box_area_ratio_p95"),
                        it != rho.end() && std::isfinite(it->second.first) ? fmt::format("{:.3f}", it->second.first) : "-");
  }
  text += "spearman: rank correlation over clusters of connectivity (N_T/N_V) with box-area drift (mean |ln box area "
          "ratio| over the frames after the first); < 0: denser clusters deform less\n";
  std::map<std::string, std::pair<std::size_t, double>> size_of;  // clustering -> (its frames, its clusters)
  for (std::size_t i = 0; i < fg.keys.size(); ++i)
    size_of[fg.keys[i][0]] = {fg.rows[i].size(), frames.number(fg.rows[i].front(), frames.column("clusters"))};
  for (const auto& [name, rn] : rho) {
    const auto [r, n] = rn;
    if (!std::isfinite(r)) {  // say why there is no number
      const auto sz = size_of.find(name);
      const double total = sz != size_of.end() ? sz->second.second : kNaN;
      std::string why;
      if (sz != size_of.end() && sz->second.first < 2)
        why = "one frame only: drift is measured over the frames after the first (--frames A:B with B > A)";
      else if (total < 3)
        why = fmt::format("{}: a rank correlation needs 3 or more", counted(std::uint64_t(total), "cluster"));
      else if (n < 3)
        why = fmt::format("{} with a finite drift (a box of zero area at some frame makes |ln ratio| infinite or "
                          "undefined)",
                          std::isfinite(total) ? fmt::format("{} of its {} clusters", n, total)
                                               : counted(std::uint64_t(n), "cluster"));
      else
        why = "no variance (every cluster drifts alike, e.g. not at all)";
      text += fmt::format("paper: connectivity predicts drift ({}) -> no Spearman: {}\n", name, why);
      continue;
    }
    text += fmt::format("paper: connectivity predicts drift ({}) -> Spearman {}: {} (criterion <= -0.3)\n", name,
                        verdict_number(r, 3, {-0.3, 0.0}),
                        r <= -0.3 ? "agrees" : r < 0 ? "DISAGREES (weak)" : "DISAGREES");
  }
  // The per-frame cost of the experiment itself, over the frames after the warm-up as every other
  // median (the warm-up frame alone when it is the only one).
  std::string cost;
  const auto keep = measured(frames);
  for (std::size_t i = 0; i < fg.keys.size(); ++i) {
    std::vector<std::size_t> rows;
    for (std::size_t r : fg.rows[i])
      if (keep(r)) rows.push_back(r);
    if (rows.empty()) rows = fg.rows[i];
    cost += fmt::format("{}{} {:.0f} ms", i ? ", " : "", fg.keys[i][0], median_of(frames, rows, frames.column("metrics_ms")));
  }
  text += "metrics per frame (median after the warm-up frame): " + cost + "\n";
  text += "fits of the measured cost per ray (cost_per_ray = traversal x nodes + intersection x triangles; ns_per_ray = "
          "trace time) to SAH and EPO:\n" + fits;
  files.push_back(std::move(reg));
}

}  // namespace

std::string verdict_number(double x, int least, std::initializer_list<double> bounds) {
  int d = least;
  for (; d < 6 && std::isfinite(x); ++d) {
    const double r = std::stod(fmt::format("{:.{}f}", x, d));
    bool same = true;
    for (double b : bounds) same = same && (r < b) == (x < b) && (r > b) == (x > b);
    if (same) break;
  }
  return fmt::format("{:.{}f}", x, d);
}

Assembled assemble(ExperimentKind kind, std::vector<FileRows> primaries, const std::string& reference) {
  Assembled a;
  a.files = std::move(primaries);
  switch (kind) {
    case ExperimentKind::Sweep: assemble_sweep(a.files, a.text); break;
    case ExperimentKind::Compare: assemble_compare(a.files, a.text, reference); break;
    case ExperimentKind::Drift: assemble_drift(a.files, a.text); break;
    case ExperimentKind::Accuracy: a.text = accuracy_text(file_of(a.files, "accuracy.csv").rows); break;
  }
  return a;
}

}  // namespace ptc
