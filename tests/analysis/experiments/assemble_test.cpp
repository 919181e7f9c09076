// assemble(): the derived columns and tables of the experiments, from rows whose answer is known
// by construction (medians of chosen values, an exactly linear cost, a missing reference).
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "analysis/experiments/experiments.h"

namespace ptc {
namespace {

FileRows file(std::string name, std::vector<std::string> header, std::vector<std::vector<std::string>> rows) {
  FileRows f;
  f.file = std::move(name);
  f.schema = {"test", 1};
  f.rows.header = std::move(header);
  f.rows.rows = std::move(rows);
  return f;
}

const FileRows& find(const Assembled& a, const std::string& name) {
  for (const auto& f : a.files)
    if (f.file == name) return f;
  throw std::runtime_error("no " + name);
}

std::map<std::string, std::string> row_map(const FileRows& f, std::size_t r) {
  std::map<std::string, std::string> m;
  for (std::size_t i = 0; i < f.rows.header.size(); ++i) m[f.rows.header[i]] = f.rows.rows.at(r)[i];
  return m;
}

TEST(Assemble, SweepMediansLeaveOutTheWarmupAndCompareWithMaxCountZero) {
  std::vector<std::vector<std::string>> rows;
  // MaxCount 0: build 100 (warm-up), then 10, 30, 20 -> median 20; MaxCount 50: 1000 (warm-up), 2, 4, 3 -> 3.
  const std::pair<const char*, std::vector<const char*>> series[] = {{"0", {"100", "10", "30", "20"}},
                                                                     {"50", {"1000", "2", "4", "3"}}};
  for (const auto& [n, ms] : series)
    for (int f = 0; f < 4; ++f)
      rows.push_back({"s", n, n, n[0] == '0' ? "1000" : "40", std::to_string(f), f == 0 ? "1" : "0", "build", ms[f]});
  const Assembled a = assemble(
      ExperimentKind::Sweep,
      {file("sweep.csv", {"scene", "max_count", "max_size", "primitives", "frame", "warmup", "stage", "ms"}, rows)}, "");
  const FileRows& s = find(a, "sweep_summary.csv");
  ASSERT_EQ(s.rows.rows.size(), 4u);  // the build rows, then update+build's (here the build alone)
  auto r0 = row_map(s, 0), r1 = row_map(s, 1);
  for (std::size_t k : {2u, 3u}) {
    auto u = row_map(s, k), b = row_map(s, k - 2);
    EXPECT_EQ(u["stage"], "update+build");
    EXPECT_EQ(u["max_count"], b["max_count"]);
    EXPECT_EQ(u["median_ms"], b["median_ms"]);
    EXPECT_EQ(u["speedup_vs_max_count_0"], b["speedup_vs_max_count_0"]);
  }
  EXPECT_EQ(r0["max_count"], "0");
  EXPECT_EQ(r0["frames"], "3");
  EXPECT_EQ(std::stod(r0["median_ms"]), 20.0);
  EXPECT_EQ(std::stod(r0["speedup_vs_max_count_0"]), 1.0);
  EXPECT_EQ(std::stod(r1["median_ms"]), 3.0);
  EXPECT_DOUBLE_EQ(std::stod(r1["speedup_vs_max_count_0"]), 20.0 / 3.0);
  EXPECT_NE(a.text.find("MaxCount"), std::string::npos);
}

TEST(Assemble, VerdictNumbersFallOnTheirVerdictsSide) {
  EXPECT_EQ(verdict_number(0.7969, 2, {0.8, 1.25}), "0.797");  // 0.80 would read as inside
  EXPECT_EQ(verdict_number(0.7999996, 2, {0.8}), "0.800000");  // at most 6 decimals
  EXPECT_EQ(verdict_number(0.8, 2, {0.8, 1.25}), "0.80");      // on the bound: as it is
  EXPECT_EQ(verdict_number(0.83, 2, {0.8, 1.25}), "0.83");
  EXPECT_EQ(verdict_number(1.2504, 2, {0.8, 1.25}), "1.2504");
  EXPECT_EQ(verdict_number(31.62, 1, {3.16, 31.6}), "31.62");
  EXPECT_EQ(verdict_number(-0.2996, 3, {-0.3, 0.0}), "-0.2996");
  EXPECT_EQ(verdict_number(std::nan(""), 2, {0.8}), "nan");
}

// The sweep's verdicts from rows with known medians: the trace time at MaxCount 0 over that at
// 50 is 7969 / 10000, just outside 0.8..1.25, and printed so; with every row's hits 0 the trace
// verdicts are left out and the run says why.
TEST(Assemble, SweepVerdictsAndTheirValuesAgree) {
  for (const char* hits : {"5", "0"}) {
    std::vector<std::vector<std::string>> rows;
    const std::pair<const char*, std::vector<std::pair<const char*, const char*>>> series[] = {
        {"0", {{"update", "40"}, {"build", "60"}, {"trace", "7969"}}},
        {"50", {{"update", "4"}, {"build", "6"}, {"trace", "10000"}}}};
    for (const auto& [n, stages] : series)
      for (int f = 0; f < 2; ++f)
        for (const auto& [stage, ms] : stages)
          rows.push_back({"s", n, n, "9", std::to_string(f), f == 0 ? "1" : "0", hits, stage, ms});
    const Assembled a = assemble(ExperimentKind::Sweep,
                                 {file("sweep.csv",
                                       {"scene", "max_count", "max_size", "primitives", "frame", "warmup", "hits", "stage",
                                        "ms"},
                                       rows)},
                                 "");
    EXPECT_NE(a.text.find("paper: update+build about an order of magnitude faster at MaxCount 50 -> 10.0x: agrees"),
              std::string::npos)
        << a.text;
    if (std::string(hits) == "5") {
      EXPECT_NE(a.text.find("trace time about unchanged at MaxCount 50 -> 0.797x of MaxCount 0: DISAGREES"),
                std::string::npos)
          << a.text;
      EXPECT_EQ(a.text.find("no verdicts"), std::string::npos) << a.text;
    } else {
      EXPECT_EQ(a.text.find("trace time about unchanged"), std::string::npos) << a.text;
      EXPECT_NE(a.text.find("paper: no verdicts on the trace time: no primary ray hit the mesh"), std::string::npos)
          << a.text;
    }
  }
}

TEST(Assemble, ComparePerfFactorIsFrameByFrameAndNanWithoutTheReference) {
  const std::vector<std::string> h = {"scene", "frame", "warmup", "config", "update_ms", "build_ms", "trace_ms",
                                      "total_ms", "perf_factor"};
  std::vector<std::vector<std::string>> rows = {
      {"s", "0", "1", "method", "1", "1", "2", "4", "nan"}, {"s", "0", "1", "other", "1", "1", "10", "12", "nan"},
      {"s", "1", "0", "method", "1", "1", "3", "5", "nan"}, {"s", "1", "0", "other", "1", "1", "18", "20", "nan"}};
  Assembled a = assemble(ExperimentKind::Compare, {file("compare.csv", h, rows)}, "method");
  const FileRows& c = find(a, "compare.csv");
  const std::size_t pf = c.rows.column("perf_factor");
  EXPECT_EQ(c.rows.number(0, pf), 1.0);
  EXPECT_EQ(c.rows.number(1, pf), 3.0);
  EXPECT_EQ(c.rows.number(2, pf), 1.0);
  EXPECT_EQ(c.rows.number(3, pf), 4.0);
  const FileRows& s = find(a, "compare_summary.csv");
  ASSERT_EQ(s.rows.rows.size(), 2u);
  EXPECT_EQ(std::stod(row_map(s, 1)["perf_factor"]), 4.0);  // the warm-up frame left out
  EXPECT_EQ(row_map(s, 1)["frames"], "1");

  a = assemble(ExperimentKind::Compare, {file("compare.csv", h, rows)}, "absent");
  for (std::size_t r = 0; r < 4; ++r) EXPECT_TRUE(std::isnan(find(a, "compare.csv").rows.number(r, pf)));
  EXPECT_NE(a.text.find("is not among these rows"), std::string::npos) << a.text;
}

// Compare's verdicts on naive and gwh01 against the method, by the rows: printed with hits;
// replaced by the no-hit line without any; neither where no verdict applies (the reference is not
// the method, or neither baseline was compared).
TEST(Assemble, CompareVerdictsOnlyWhereTheyApply) {
  const std::vector<std::string> h = {"scene", "frame", "warmup", "config", "update_ms", "build_ms", "trace_ms",
                                      "total_ms", "perf_factor", "hits"};
  auto rows = [](const char* hits, std::vector<const char*> configs) {
    std::vector<std::vector<std::string>> r;
    for (int f = 0; f < 5; ++f)
      for (const char* c : configs) r.push_back({"s", std::to_string(f), f == 0 ? "1" : "0", c, "1", "1", "2", "4", "nan", hits});
    return r;
  };
  const std::string no_hits = "paper: no verdicts on the clusterings' whole frames";
  Assembled a = assemble(ExperimentKind::Compare, {file("compare.csv", h, rows("7", {"acc_growth", "naive"}))}, "acc_growth");
  EXPECT_NE(a.text.find("paper: naive clusters close to the method early"), std::string::npos) << a.text;
  a = assemble(ExperimentKind::Compare, {file("compare.csv", h, rows("0", {"acc_growth", "naive"}))}, "acc_growth");
  EXPECT_NE(a.text.find(no_hits), std::string::npos) << a.text;
  EXPECT_EQ(a.text.find("clusters close to the method"), std::string::npos) << a.text;
  for (const auto& [ref, configs] :
       {std::pair<const char*, std::vector<const char*>>{"standard", {"standard", "naive"}}, {"acc_growth", {"acc_growth", "standard"}}}) {
    a = assemble(ExperimentKind::Compare, {file("compare.csv", h, rows("0", configs))}, ref);
    EXPECT_EQ(a.text.find("paper:"), std::string::npos) << ref << "\n" << a.text;
  }
}

TEST(Assemble, DriftRegressionRecoversExactlyLinearCosts) {
  // cost_per_ray = 0.5 SAH + 2 EPO + 1 and ns_per_ray = 10 nodes + 0.5 triangles + 3, exactly,
  // over points where SAH and EPO (and nodes and triangles) are not collinear.
  std::vector<std::vector<std::string>> rays, frames;
  for (int i = 0; i < 12; ++i) {
    const double sah = 20.0 + i, epo = 3.0 + (i * 7 % 5), nodes = 4.0 + (i * 5 % 7), tris = 10.0 + 3 * i;
    const double cost = 0.5 * sah + 2.0 * epo + 1.0, ns = 10.0 * nodes + 0.5 * tris + 3.0;
    rays.push_back({"c", std::to_string(i), "0", "shadow", "100", format_double(nodes), format_double(tris),
                    format_double(cost), format_double(sah), format_double(epo), "1", format_double(ns)});
    frames.push_back({"s", "c", std::to_string(i), "0", "10", format_double(sah), "20", "1.2", format_double(epo), "3",
                      "1", "1.5", "1.1", "", "2"});
  }
  // A warm-up row far off both lines: counted, it would spoil the exact fits.
  rays.push_back({"c", "99", "1", "shadow", "100", "50", "50", "1000", "30", "5", "1", "99999"});
  const std::vector<std::string> fh = {"scene", "clustering", "frame", "warmup", "clusters", "sah_cost",
                                       "sah_cost_triangles", "sah_overhead", "epo", "nodes_per_ray", "triangles_per_ray",
                                       "box_area_ratio_max", "box_area_ratio_p95", "worst_clusters", "metrics_ms"};
  const Assembled a = assemble(
      ExperimentKind::Drift,
      {file("rays.csv",
            {"clustering", "frame", "warmup", "ray_type", "rays", "nodes_per_ray", "triangles_per_ray", "cost_per_ray",
             "sah_cost", "epo", "trace_ms", "ns_per_ray"},
            rays),
       file("frames.csv", fh, frames),
       file("correlation.csv", {"scene", "clustering", "x", "y", "clusters", "frames", "spearman", "pearson"},
            {{"s", "c", "connectivity", "box_area_drift", "10", "11", "-0.5", "-0.4"}})},
      "");
  const FileRows& r = find(a, "regression.csv");
  // cost_per_ray: sah, epo, sah+epo, sah+0.71epo; ns_per_ray: the same and nodes+triangles.
  ASSERT_EQ(r.rows.rows.size(), 9u);
  std::map<std::string, std::map<std::string, std::string>> by;
  for (std::size_t i = 0; i < r.rows.rows.size(); ++i) {
    auto m = row_map(r, i);
    EXPECT_EQ(m["ray_type"], "shadow");
    EXPECT_EQ(m["points"], "12");
    by[m["target"] + "/" + m["model"]] = m;
  }
  auto& both = by["cost_per_ray/sah+epo"];
  EXPECT_NEAR(std::stod(both["coef_sah"]), 0.5, 1e-9);
  EXPECT_NEAR(std::stod(both["coef_epo"]), 2.0, 1e-9);
  EXPECT_NEAR(std::stod(both["intercept"]), 1.0, 1e-8);
  EXPECT_NEAR(std::stod(both["r2"]), 1.0, 1e-12);
  EXPECT_NEAR(std::stod(both["epo_weight"]), 4.0, 1e-8);
  EXPECT_LT(std::stod(by["cost_per_ray/sah"]["r2"]), 0.99);  // SAH alone does not explain it
  auto& counters = by["ns_per_ray/nodes+triangles"];
  EXPECT_NEAR(std::stod(counters["coef_nodes"]), 10.0, 1e-9);
  EXPECT_NEAR(std::stod(counters["coef_triangles"]), 0.5, 1e-9);
  EXPECT_NEAR(std::stod(counters["triangle_weight"]), 0.05, 1e-10);
  EXPECT_NEAR(std::stod(counters["r2"]), 1.0, 1e-12);
  EXPECT_NE(a.text.find("-0.500"), std::string::npos) << a.text;  // the Spearman in the summary
  EXPECT_NE(a.text.find("a triangle test = 0.05 node visits"), std::string::npos) << a.text;
}

// Why drift gives no Spearman, by the rows: one frame; fewer than three clusters; three or more
// clusters of which fewer than three have a finite drift; no variance.
TEST(Assemble, DriftSaysWhyThereIsNoSpearman) {
  const std::vector<std::string> fh = {"scene", "clustering", "frame", "warmup", "clusters", "sah_cost",
                                       "sah_cost_triangles", "sah_overhead", "epo", "nodes_per_ray", "triangles_per_ray",
                                       "box_area_ratio_max", "box_area_ratio_p95", "worst_clusters", "metrics_ms"};
  struct Case {
    int frames;
    const char *clusters, *usable, *why;
  };
  for (const Case& c : {Case{1, "40", "40", "one frame only"}, Case{3, "1", "1", "1 cluster: a rank correlation needs 3"},
                        Case{3, "2", "2", "2 clusters: a rank correlation needs 3"},
                        Case{3, "40", "2", "2 of its 40 clusters with a finite drift"},
                        Case{3, "40", "40", "no variance"}}) {
    std::vector<std::vector<std::string>> frames;
    for (int f = 0; f < c.frames; ++f)
      frames.push_back({"s", "c", std::to_string(f), f == 0 ? "1" : "0", c.clusters, "20", "20", "1.2", "3", "3", "1",
                        "1.5", "1.1", "", "2"});
    const Assembled a = assemble(
        ExperimentKind::Drift,
        {file("rays.csv",
              {"clustering", "frame", "warmup", "ray_type", "rays", "nodes_per_ray", "triangles_per_ray", "cost_per_ray",
               "sah_cost", "epo", "trace_ms", "ns_per_ray"},
              {}),
         file("frames.csv", fh, frames),
         file("correlation.csv", {"scene", "clustering", "x", "y", "clusters", "frames", "spearman", "pearson"},
              {{"s", "c", "connectivity", "box_area_drift", c.usable, std::to_string(c.frames), "nan", "nan"}})},
        "");
    EXPECT_NE(a.text.find(std::string("paper: connectivity predicts drift (c) -> no Spearman: ") + c.why),
              std::string::npos)
        << c.why << "\n" << a.text;
  }
}

}  // namespace
}  // namespace ptc
