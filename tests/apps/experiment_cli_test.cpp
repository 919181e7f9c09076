// `ptc experiment` and `ptc merge` end to end: shards merged give the single run's files row by
// row (timings aside), merge refuses shards that do not belong together, the derived columns
// recomputed independently from the rows, and the flags' usage errors.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>

#include "apps/cli_harness.h"
#include "common/csv_rows.h"
#include "common/fnv.h"
#include "viz/vtp.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tuple>

namespace ptc::test {
namespace {

class Experiment : public CliTest {};

// A timing (or derived from one) column: not reproducible between runs.
bool timing_column(const std::string& c) {
  return c == "ms" || c == "ns_per_ray" || (c.size() > 3 && c.substr(c.size() - 3) == "_ms") || c.rfind("speedup", 0) == 0 ||
         c.rfind("perf_factor", 0) == 0;
}

// Every row and every non-timing cell of two CSV files equal, item by item.
void expect_same_rows(const fs::path& a, const fs::path& b) {
  const auto ta = csv_table(slurp(a)), tb = csv_table(slurp(b));
  ASSERT_FALSE(ta.empty()) << a;
  ASSERT_EQ(ta.size(), tb.size()) << a << " vs " << b;
  ASSERT_EQ(ta[0], tb[0]) << "headers of " << a;
  for (std::size_t r = 1; r < ta.size(); ++r) {
    ASSERT_EQ(ta[r].size(), tb[r].size());
    // A derived row of timings (regression.csv's fits of ns_per_ray): not reproducible either.
    if (std::find(ta[r].begin(), ta[r].end(), "ns_per_ray") != ta[r].end()) {
      EXPECT_EQ(ta[r][0], tb[r][0]);
      continue;
    }
    for (std::size_t c = 0; c < ta[0].size(); ++c)
      if (!timing_column(ta[0][c])) {
        EXPECT_EQ(ta[r][c], tb[r][c]) << a.filename() << " row " << r << " column " << ta[0][c];
      }
  }
}

TEST_F(Experiment, SweepAsThreeShardsMergesToTheSingleRun) {
  const std::vector<std::string> base = {"experiment", "sweep", "armadillo-twist", "--frames", "0:2", "--width", "48",
                                         "--height", "48", "--quiet", "--threads", "2"};
  auto with = [&](std::vector<std::string> extra) {
    auto a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  };
  const RunResult one = ptc(with({"--out", (dir_ / "one").string()}));
  ASSERT_EQ(one.code, 0) << one.err;
  std::vector<std::string> merge = {"merge"};
  for (int k = 3; k >= 1; --k) {  // shards given out of order
    const std::string d = (dir_ / std::to_string(k)).string() + "s";  // (s1 would trip GCC 12's -Wrestrict)
    const RunResult s = ptc(with({"--shard", std::to_string(k) + "/3", "--out", d}));
    ASSERT_EQ(s.code, 0) << s.err;
    merge.push_back(d);
  }
  merge.insert(merge.end(), {"--out", (dir_ / "merged").string()});
  const RunResult m = ptc(merge);
  ASSERT_EQ(m.code, 0) << m.err;
  for (const char* f : {"configs.csv", "sweep.csv", "sweep_summary.csv"}) expect_same_rows(dir_ / "one" / f, dir_ / "merged" / f);
  // The merged manifest records every file merge read (the shards' manifests and tables), with
  // their sizes and hashes, and its stages' times.
  {
    const auto mm = nlohmann::json::parse(slurp(dir_ / "merged" / "manifest.json"));
    std::set<std::string> inputs;
    for (const auto& in : mm["inputs"]) {
      const fs::path p = in["path"].get<std::string>();
      inputs.insert(p.filename().string() + "@" + p.parent_path().filename().string());
      EXPECT_EQ(in["bytes"].get<std::uint64_t>(), fs::file_size(p)) << p;
      EXPECT_EQ(in["fnv1a64"].get<std::string>(), test::fnv1a64_hex(slurp(p))) << p;
    }
    for (const char* d : {"1s", "2s", "3s"})
      for (const char* f : {"manifest.json", "configs.csv", "sweep.csv"})
        EXPECT_TRUE(inputs.count(std::string(f) + "@" + d)) << f << " of " << d;
    EXPECT_TRUE(mm["timings_ms"].contains("read"));
    EXPECT_TRUE(mm["timings_ms"].contains("assemble"));
  }
  // The shards split the 4 items 2 + 1 + 1 (items 0 and 3 in shard 1).
  const auto s1 = csv_rows(slurp(dir_ / "1s" / "configs.csv"));
  ASSERT_EQ(s1.size(), 2u);
  EXPECT_EQ(s1[0].at("config"), "max_count=0");
  EXPECT_EQ(s1[1].at("config"), "max_count=100");
  EXPECT_NE(m.out.find("MaxCount"), std::string::npos);

  // The rows themselves: 4 stages per (MaxCount, frame), total = update + build + trace, the
  // primitives are the triangles at MaxCount 0 and the clusters of configs.csv otherwise.
  const auto rows = csv_rows(slurp(dir_ / "one" / "sweep.csv"));
  const auto configs = csv_rows(slurp(dir_ / "one" / "configs.csv"));
  ASSERT_EQ(rows.size(), 4u * 3u * 4u);
  std::map<std::string, std::string> clusters;
  for (const auto& c : configs) clusters[c.at("max_count")] = c.at("clusters");
  for (std::size_t i = 0; i < rows.size(); i += 4) {
    EXPECT_EQ(rows[i].at("stage"), "update");
    EXPECT_EQ(rows[i + 1].at("stage"), "build");
    EXPECT_EQ(rows[i + 2].at("stage"), "trace");
    EXPECT_EQ(rows[i + 3].at("stage"), "total");
    const double sum = std::stod(rows[i].at("ms")) + std::stod(rows[i + 1].at("ms")) + std::stod(rows[i + 2].at("ms"));
    EXPECT_NEAR(std::stod(rows[i + 3].at("ms")), sum, 1e-9 * sum);
    EXPECT_EQ(rows[i].at("warmup"), rows[i].at("frame") == "0" ? "1" : "0");
    const std::string& n = rows[i].at("max_count");
    EXPECT_EQ(rows[i].at("primitives"), n == "0" ? "52000" : clusters.at(n)) << n;
  }
  // hits: the frame's primary rays that hit, the same on its four stage rows and, as every
  // structure traces the same rays through the same frame, the same over the MaxCount values
  // (the triangle BVH at 0 against three cluster BVHs); some rays hit, some pass the mesh.
  std::map<std::string, std::string> hits_of_frame;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].at("hits"), rows[i - i % 4].at("hits")) << i;
    const auto [it, fresh] = hits_of_frame.emplace(rows[i].at("frame"), rows[i].at("hits"));
    EXPECT_EQ(it->second, rows[i].at("hits")) << "frame " << rows[i].at("frame") << " MaxCount " << rows[i].at("max_count");
    const long h = std::stol(rows[i].at("hits"));
    EXPECT_GT(h, 0);
    EXPECT_LT(h, 48 * 48);
  }
  EXPECT_EQ(hits_of_frame.size(), 3u);
  EXPECT_NE(one.out.find("paper: trace time about unchanged"), std::string::npos) << one.out;
  // The summary's update + build ratio is in sweep_summary.csv: per MaxCount, a row of stage
  // update+build whose median is the update's plus the build's and whose speedup is MaxCount 0's
  // sum over it (printed only, once).
  std::map<std::string, std::map<std::string, std::pair<double, double>>> sum;  // count -> stage -> (ms, speedup)
  for (const auto& r : csv_rows(slurp(dir_ / "one" / "sweep_summary.csv")))
    sum[r.at("max_count")][r.at("stage")] = {std::stod(r.at("median_ms")), std::stod(r.at("speedup_vs_max_count_0"))};
  ASSERT_EQ(sum.size(), 4u);
  const double ub0 = sum["0"]["update"].first + sum["0"]["build"].first;
  for (auto& [n, st] : sum) {
    ASSERT_TRUE(st.count("update+build")) << n;
    const double ub = st["update"].first + st["build"].first;
    EXPECT_NEAR(st["update+build"].first, ub, 1e-12 * ub) << n;
    EXPECT_NEAR(st["update+build"].second, ub0 / ub, 1e-9 * ub0 / ub) << n;
  }
}

// The manifest's clustering parameters are those some clustering of the run read, as `ptc
// cluster` records them: a meshopt sweep has no objective nor MaxSize, and its MaxCount values
// are max_counts; an Acc sweep has the sphere but no GWH01 weights.
TEST_F(Experiment, ManifestRecordsTheClusteringParametersUsed) {
  const std::vector<std::string> base = {"experiment", "sweep", "armadillo-twist", "--frames", "0:1", "--width", "16",
                                         "--height", "16", "--quiet"};
  auto params = [&](std::vector<std::string> extra, const char* out) {
    auto a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    a.insert(a.end(), {"--out", (dir_ / out).string()});
    const RunResult r = ptc(a);
    EXPECT_EQ(r.code, 0) << r.err;
    return nlohmann::json::parse(slurp(dir_ / out / "manifest.json"))["parameters"];
  };
  auto keys = [](const nlohmann::json& j) {
    std::set<std::string> k;
    for (const auto& [key, v] : j.items()) k.insert(key);
    return k;
  };
  nlohmann::json p = params({"--method", "meshopt", "--max-counts", "20"}, "meshopt");
  EXPECT_EQ(keys(p["cluster"]), (std::set<std::string>{"adjacency", "max_triangles", "method"})) << p.dump();
  EXPECT_EQ(p["cluster"]["method"], "meshopt");
  EXPECT_EQ(p["max_counts"], nlohmann::json::array({20}));
  p = params({"--method", "contraction", "--objective", "acc", "--max-counts", "0,20"}, "acc");
  EXPECT_EQ(keys(p["cluster"]), (std::set<std::string>{"adjacency", "method", "objective", "regions", "size_bound",
                                                       "sphere", "target_clusters"}))
      << p.dump();
  p = params({"--max-counts", "0"}, "none");  // the triangle BVH alone: no clustering
  EXPECT_TRUE(p["cluster"].empty()) << p.dump();
}

// A camera that sees no part of the mesh: the trace times time rays through empty space, so the
// paper's verdicts on them are left out, in sweep and in compare, and the run says why.
TEST_F(Experiment, NoVerdictsOnTraceTimesWhereNoRayHits) {
  // The armadillo lies within |z| < 58: from z = 1000 looking further out along +z, every ray misses.
  const std::vector<std::string> away = {"--eye", "0,0,1000", "--look-at", "0,0,2000", "--frames", "0:2", "--width",
                                         "24", "--height", "24", "--quiet"};
  auto with = [&](std::vector<std::string> a) {
    a.insert(a.end(), away.begin(), away.end());
    return a;
  };
  const RunResult s = ptc(with({"experiment", "sweep", "armadillo-twist", "--max-counts", "0,50,100", "--out",
                                (dir_ / "sweep").string()}));
  ASSERT_EQ(s.code, 0) << s.err;
  for (const auto& r : csv_rows(slurp(dir_ / "sweep" / "sweep.csv"))) EXPECT_EQ(r.at("hits"), "0");
  EXPECT_NE(s.out.find("paper: no verdicts on the trace time: no primary ray hit the mesh in any measured frame"),
            std::string::npos)
      << s.out;
  EXPECT_EQ(s.out.find("paper: trace time"), std::string::npos) << s.out;
  EXPECT_EQ(s.out.find("paper: trace worse"), std::string::npos) << s.out;
  EXPECT_NE(s.out.find("paper: update+build"), std::string::npos) << s.out;  // (no rays in it)
  const RunResult c = ptc(with({"experiment", "compare", "armadillo-twist", "--configs", "acc_growth,naive,gwh01",
                                "--max-count", "20", "--max-size", "20", "--out", (dir_ / "compare").string()}));
  ASSERT_EQ(c.code, 0) << c.err;
  for (const auto& r : csv_rows(slurp(dir_ / "compare" / "compare.csv"))) EXPECT_EQ(r.at("hits"), "0");
  EXPECT_NE(c.out.find("paper: no verdicts on the clusterings' whole frames"), std::string::npos) << c.out;
  EXPECT_EQ(c.out.find("clusters close to the method"), std::string::npos) << c.out;
  // The same compare seeing the mesh gives the verdicts.
  const RunResult seen = ptc({"experiment", "compare", "armadillo-twist", "--configs", "acc_growth,naive,gwh01",
                              "--max-count", "20", "--max-size", "20", "--frames", "0:2", "--width", "24", "--height",
                              "24", "--quiet", "--out", (dir_ / "seen").string()});
  ASSERT_EQ(seen.code, 0) << seen.err;
  EXPECT_NE(seen.out.find("paper: naive clusters close to the method"), std::string::npos) << seen.out;
  EXPECT_EQ(seen.out.find("no verdicts"), std::string::npos) << seen.out;
}

TEST_F(Experiment, DriftShardsMergeWithTheDerivedTablesOfTheSingleRun) {
  // Frames 40..43: the cloth drapes over the sphere (before it falls rigidly: no drift at all).
  const std::vector<std::string> base = {"experiment", "drift", "cloth-sphere-32", "--frames", "40:43", "--width", "32",
                                         "--height", "32", "--clusterings", "acc_growth,naive,meshopt", "--quiet"};
  auto run = [&](std::vector<std::string> extra) {
    auto a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    return ptc(a);
  };
  ASSERT_EQ(run({"--out", (dir_ / "one").string()}).code, 0);
  ASSERT_EQ(run({"--shard", "1/2", "--out", (dir_ / "a").string()}).code, 0);
  ASSERT_EQ(run({"--shard", "2/2", "--out", (dir_ / "b").string()}).code, 0);
  const RunResult m = ptc({"merge", (dir_ / "a").string(), (dir_ / "b").string(), "--out", (dir_ / "m").string()});
  ASSERT_EQ(m.code, 0) << m.err;
  // The merged manifest says where each shard ran and what it read, and every item done.
  {
    const auto one = nlohmann::json::parse(slurp(dir_ / "one" / "manifest.json"));
    const auto merged = nlohmann::json::parse(slurp(dir_ / "m" / "manifest.json"));
    EXPECT_EQ(merged["results"]["items_done"], one["results"]["items_done"]);
    EXPECT_EQ(merged["results"]["rest_mesh_fnv1a64"], one["results"]["rest_mesh_fnv1a64"]);
    ASSERT_EQ(merged["results"]["shard_runs"].size(), 2u);
    EXPECT_EQ(merged["results"]["shard_runs"][0]["shard"], 1);
    EXPECT_EQ(merged["results"]["shard_runs"][1]["machine"], one["machine"]);
    EXPECT_EQ(merged["results"]["shard_runs"][1]["build"], one["build"]);
  }
  // No timing enters these (counters, SAH, EPO, drift): the merged files equal the single run's.
  for (const char* f : {"clusters_frames.csv", "frames.csv", "rays.csv", "correlation.csv", "regression.csv"})
    expect_same_rows(dir_ / "one" / f, dir_ / "m" / f);

  // The correlation recomputed from clusters_frames.csv: per clustering, Spearman over clusters of
  // connectivity against the mean |ln box_area_ratio| of the frames after the first.
  const auto cf = csv_rows(slurp(dir_ / "one" / "clusters_frames.csv"));
  // Every cluster is a leaf of the cluster BVH, so its SAH share is positive, and a frame's shares
  // sum to 1 (a share read from a tree over other primitives, such as the fixed group trees'
  // top over the groups, leaves most clusters at 0).
  std::map<std::string, double> share_sum;  // clustering/frame -> sum
  for (const auto& r : cf) {
    EXPECT_GT(std::stod(r.at("sah_share")), 0.0) << r.at("clustering") << " frame " << r.at("frame") << " cluster "
                                                  << r.at("cluster_id");
    share_sum[r.at("clustering") + "/" + r.at("frame")] += std::stod(r.at("sah_share"));
  }
  for (const auto& [k, s] : share_sum) EXPECT_NEAR(s, 1.0, 1e-9) << k;
  std::map<std::string, std::map<std::string, std::pair<double, double>>> acc;  // clustering -> cluster -> (conn, sum)
  for (const auto& r : cf) {
    auto& e = acc[r.at("clustering")][r.at("cluster_id")];
    e.first = std::stod(r.at("connectivity"));
    // |ln ratio| below 1e-12 is rounding, not motion (docs/experiments.md): 0.
    const double moved = std::abs(std::log(std::stod(r.at("box_area_ratio"))));
    if (r.at("frame") != "40") e.second += moved < 1e-12 ? 0.0 : moved;
  }
  for (const auto& c : csv_rows(slurp(dir_ / "one" / "correlation.csv"))) {
    if (c.at("y") != "box_area_drift") continue;
    std::vector<std::pair<double, double>> v;
    for (const auto& [id, e] : acc.at(c.at("clustering")))
      if (std::isfinite(e.second)) v.emplace_back(e.first, e.second / 3.0);
    // Spearman = Pearson of the average ranks.
    auto ranks = [](std::vector<double> x) {
      std::vector<std::size_t> idx(x.size());
      for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
      std::sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) { return x[a] < x[b]; });
      std::vector<double> r(x.size());
      for (std::size_t i = 0; i < idx.size();) {
        std::size_t j = i;
        while (j + 1 < idx.size() && x[idx[j + 1]] == x[idx[i]]) ++j;
        for (std::size_t k = i; k <= j; ++k) r[idx[k]] = 0.5 * double(i + j) + 1.0;
        i = j + 1;
      }
      return r;
    };
    std::vector<double> xs, ys;
    for (const auto& [x, y] : v) xs.push_back(x), ys.push_back(y);
    const auto rx = ranks(xs), ry = ranks(ys);
    double mx = 0, my = 0;
    for (std::size_t i = 0; i < rx.size(); ++i) mx += rx[i], my += ry[i];
    mx /= double(rx.size()), my /= double(ry.size());
    double sxy = 0, sxx = 0, syy = 0;
    for (std::size_t i = 0; i < rx.size(); ++i)
      sxy += (rx[i] - mx) * (ry[i] - my), sxx += (rx[i] - mx) * (rx[i] - mx), syy += (ry[i] - my) * (ry[i] - my);
    EXPECT_EQ(std::stoul(c.at("clusters")), v.size());
    EXPECT_NEAR(std::stod(c.at("spearman")), sxy / std::sqrt(sxx * syy), 1e-9) << c.at("clustering");
  }
  // --json of a merge: drift's summary tables (the per-frame table, Spearman, the fits), row for
  // row the merged files' rows, numbers as numbers.
  const RunResult j = ptc({"merge", (dir_ / "a").string(), (dir_ / "b").string(), "--json", "--out", (dir_ / "mj").string()});
  ASSERT_EQ(j.code, 0) << j.err;
  const auto js = nlohmann::json::parse(j.out);
  for (const char* f : {"frames.csv", "correlation.csv", "regression.csv"}) {
    const auto rows = csv_rows(slurp(dir_ / "mj" / f));
    ASSERT_TRUE(js.at("tables").contains(f)) << f;
    const auto& t = js.at("tables").at(f);
    ASSERT_EQ(t.size(), rows.size()) << f;
    for (std::size_t i = 0; i < rows.size(); ++i)
      for (const auto& [col, cell] : rows[i]) {
        const auto& x = t[i].at(col);
        if (x.is_number()) EXPECT_EQ(x.get<double>(), std::stod(cell)) << f << " " << col;
        else if (x.is_null()) EXPECT_TRUE(cell == "nan" || cell == "inf" || cell == "-inf") << f << " " << col;
        else EXPECT_EQ(x.get<std::string>(), cell) << f << " " << col;
      }
  }
  EXPECT_FALSE(js.at("tables").contains("clusters_frames.csv"));  // (the per-cluster rows stay in the file)
}

TEST_F(Experiment, CompareDividesByTheReferenceFrameByFrame) {
  const RunResult r = ptc({"experiment", "compare", "armadillo-twist", "--frames", "0:2", "--width", "32", "--height",
                           "32", "--configs", "acc_growth,standard,embree_refit", "--reference", "standard", "--quiet",
                           "--out", (dir_ / "c").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = csv_rows(slurp(dir_ / "c" / "compare.csv"));
  ASSERT_EQ(rows.size(), 9u);
  std::map<std::string, double> ref;
  for (const auto& x : rows)
    if (x.at("config") == "standard") ref[x.at("frame")] = std::stod(x.at("total_ms"));
  std::set<std::string> configs;
  for (const auto& x : rows) {
    configs.insert(x.at("config"));
    const double total = std::stod(x.at("total_ms"));
    EXPECT_NEAR(total, std::stod(x.at("update_ms")) + std::stod(x.at("build_ms")) + std::stod(x.at("trace_ms")),
                1e-9 * total);
    EXPECT_NEAR(std::stod(x.at("perf_factor")), total / ref.at(x.at("frame")), 1e-12);
    EXPECT_EQ(x.at("rays"), "1024");
  }
  EXPECT_EQ(configs, (std::set<std::string>{"acc_growth", "standard", "embree_refit"}));

  // --json: the summary tables with numbers as numbers (the reference's factor is exactly 1).
  const RunResult j = ptc({"experiment", "compare", "armadillo-twist", "--frames", "0:2", "--width", "16", "--height",
                           "16", "--configs", "acc_growth,standard", "--reference", "standard", "--quiet", "--json",
                           "--out", (dir_ / "j").string()});
  ASSERT_EQ(j.code, 0) << j.err;
  const auto js = nlohmann::json::parse(j.out);
  EXPECT_EQ(js.at("schema"), "ptc-experiment-summary/1");
  const auto& summary = js.at("tables").at("compare_summary.csv");
  ASSERT_EQ(summary.size(), 2u);
  for (const auto& row : summary) {
    EXPECT_TRUE(row.at("frames").is_number_integer());
    if (row.at("config") == "standard") {
      EXPECT_EQ(row.at("perf_factor").get<double>(), 1.0);
    }
  }
}

TEST_F(Experiment, MergeRefusesShardsThatDoNotBelongTogether) {
  // Three items, so that the same study can also be split in three.
  const std::vector<std::string> base = {"experiment", "sweep", "cloth-sphere-32", "--max-counts", "0,10,20", "--width",
                                         "16", "--height", "16", "--quiet"};
  auto run = [&](std::vector<std::string> extra, const std::string& out) {
    auto a = base;
    a.insert(a.end(), extra.begin(), extra.end());
    a.insert(a.end(), {"--out", (dir_ / out).string()});
    return ptc(a);
  };
  ASSERT_EQ(run({"--frames", "0:1", "--shard", "1/2"}, "a").code, 0);
  ASSERT_EQ(run({"--frames", "0:1", "--shard", "2/2"}, "b").code, 0);
  ASSERT_EQ(run({"--frames", "0:2", "--shard", "2/2"}, "other").code, 0);
  ASSERT_EQ(run({"--frames", "0:1", "--shard", "1/3"}, "third").code, 0);
  const std::string a = (dir_ / "a").string(), b = (dir_ / "b").string(), out = (dir_ / "m").string();

  RunResult r = ptc({"merge", a, "--out", out});
  EXPECT_EQ(r.code, 1);  // bad input, named, like a shard given twice
  EXPECT_NE(r.err.find(a + ": shard 2/2 of its split is missing"), std::string::npos) << r.err;
  // A manifest given instead of its directory, and a directory that does not exist.
  r = ptc({"merge", a + "/manifest.json", b, "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find(a + "/manifest.json: is a file: give the directory"), std::string::npos) << r.err;
  r = ptc({"merge", (dir_ / "nowhere").string(), b, "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("nowhere: no such directory"), std::string::npos) << r.err;
  // `a` merged with `other`: refused (bad input), the error holding `needle`.
  auto refused_with = [&](const std::string& other, const std::string& needle) {
    const RunResult rr = ptc({"merge", a, other, "--out", out});
    EXPECT_EQ(rr.code, 1) << rr.err;
    EXPECT_NE(rr.err.find(needle), std::string::npos) << rr.err;
  };
  refused_with(a, "given twice");
  refused_with((dir_ / "other").string(), "parameters.frames");
  // Another --width: named as the width, not as the camera made from it (which sorts first)
  ASSERT_EQ(ptc({"experiment", "sweep", "cloth-sphere-32", "--max-counts", "0,10,20", "--width", "24", "--height", "16",
                 "--quiet", "--frames", "0:1", "--shard", "2/2", "--out", (dir_ / "wide").string()})
                .code,
            0);
  refused_with((dir_ / "wide").string(), ": parameters.width: 16 vs 24");
  refused_with((dir_ / "third").string(), "split into 3");
  // The output of a run without --shard (it records itself as shard 1/1), alone or beside a
  // shard: said in those words (before: "shard 1/1 of a split into 1").
  ASSERT_EQ(run({"--frames", "0:1"}, "whole").code, 0);
  const std::string whole = (dir_ / "whole").string();
  for (const std::vector<std::string>& dirs : {std::vector<std::string>{a, whole}, std::vector<std::string>{whole}}) {
    std::vector<std::string> argv = {"merge"};
    argv.insert(argv.end(), dirs.begin(), dirs.end());
    argv.insert(argv.end(), {"--out", out});
    r = ptc(argv);
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_NE(r.err.find(whole + ": not one shard of a split: it records shard 1/1"),
              std::string::npos)
        << r.err;
  }
  // A shard of another experiment: said in those words (a JSON path of the difference before).
  ASSERT_EQ(ptc({"experiment", "compare", "cloth-sphere-32", "--configs", "acc_growth,naive", "--frames", "0:1", "--width", "16",
                 "--height", "16", "--quiet", "--shard", "2/2", "--out", (dir_ / "cmp").string()})
                .code,
            0);
  refused_with((dir_ / "cmp").string(), "cmp: a shard of `ptc experiment compare`, not of sweep like " + a);
  // Shards of two mesh files: the scenes are named beside their hashes.
  const std::string bunny = std::string(PTC_TEST_DATA) + "/meshes/bunny00.off";
  const std::string elephant = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  for (const auto& [mesh, k, d] : {std::tuple{bunny, "1/2", "m1"}, std::tuple{elephant, "2/2", "m2"}})
    ASSERT_EQ(ptc({"experiment", "sweep", mesh, "--max-counts", "0,10", "--frames", "0:1", "--width", "8", "--height", "8",
                   "--quiet", "--shard", k, "--out", (dir_ / d).string()})
                  .code,
              0);
  r = ptc({"merge", (dir_ / "m1").string(), (dir_ / "m2").string(), "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("not a shard of the same study as " + (dir_ / "m1").string() + ": the scene " + bunny + " vs " +
                       elephant + " (inputs"),
            std::string::npos)
      << r.err;
  fs::create_directories(dir_ / "nothing");  // a directory without a manifest
  r = ptc({"merge", (dir_ / "nothing").string(), "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("manifest.json"), std::string::npos) << r.err;
  // A merged directory is not a shard: said so.
  ASSERT_EQ(ptc({"merge", a, b, "--out", (dir_ / "merged").string()}).code, 0);
  r = ptc({"merge", (dir_ / "merged").string(), a, "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("is the output of `ptc merge`"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  // An edited shard: a row removed. Its bytes no longer have the manifest's hash; with the hash
  // gone from the manifest (a shard of a ptc before 2026-12-04), the row count still tells.
  std::string text = slurp(dir_ / "b" / "sweep.csv");
  text.erase(text.rfind('\n', text.size() - 2) + 1);
  spit(dir_ / "b" / "sweep.csv", text);
  r = ptc({"merge", a, b, "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("differ from the FNV-1a hash"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  {
    auto m = nlohmann::json::parse(slurp(dir_ / "b" / "manifest.json"));
    ASSERT_TRUE(m.contains("output_hashes"));
    m.erase("output_hashes");
    spit(dir_ / "b" / "manifest.json", m.dump(2));
  }
  r = ptc({"merge", a, b, "--out", out});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("fewer rows than its manifest"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out));
  for (const auto& e : {r.err}) EXPECT_EQ(lines(e), 1u) << e;
}

// Shards that name one scene file by different paths (a scheduler starting them from other
// directories) merge into the single run's tables: the rows name the scene as the first shard
// does, so the derived columns join them (perf_factor was nan for the rows named otherwise).
TEST_F(Experiment, ShardsNamingTheSceneByOtherPathsMergeToTheSingleRun) {
  fs::copy_file(std::string(PTC_TEST_DATA) + "/meshes/bunny00.off", dir_ / "bunny.off");
  fs::create_directories(dir_ / "sub");
  const std::vector<std::string> args = {"--configs", "acc_contraction,standard", "--frames", "0:2", "--width", "16",
                                         "--height", "16", "--quiet"};
  auto with = [&](std::vector<std::string> a, const std::vector<std::string>& tail) {
    a.insert(a.end(), args.begin(), args.end());
    a.insert(a.end(), tail.begin(), tail.end());
    return a;
  };
  const std::string mesh = (dir_ / "bunny.off").string();
  ASSERT_EQ(ptc(with({"experiment", "compare", mesh}, {"--out", (dir_ / "one").string()})).code, 0);
  ASSERT_EQ(ptc(with({"experiment", "compare", mesh}, {"--shard", "1/2", "--out", (dir_ / "a").string()})).code, 0);
  const std::vector<std::string> in_sub = {"sh", "-c", "cd \"$0\" && exec \"$@\"", (dir_ / "sub").string(), PTC_BIN};
  const RunResult b = run(in_sub, with({"experiment", "compare", "../bunny.off"}, {"--shard", "2/2", "--out", "../b"}));
  ASSERT_EQ(b.code, 0) << b.err;
  {  // shard 2 as if built against another Embree: merge takes it (same ptc and commit) and says so
    auto mb = nlohmann::json::parse(slurp(dir_ / "b" / "manifest.json"));
    ASSERT_TRUE(mb["build"]["libraries"].contains("embree"));
    mb["build"]["libraries"]["embree"] = "4.0.0";
    spit(dir_ / "b" / "manifest.json", mb.dump(2));
  }
  const RunResult m = ptc({"merge", (dir_ / "a").string(), (dir_ / "b").string(), "--out", (dir_ / "m").string()});
  ASSERT_EQ(m.code, 0) << m.err;
  {
    const auto mm = nlohmann::json::parse(slurp(dir_ / "m" / "manifest.json"));
    ASSERT_EQ(mm["results"]["shard_runs"].size(), 2u);
    EXPECT_EQ(mm["results"]["shard_runs"][1]["build"]["libraries"]["embree"], "4.0.0");
    EXPECT_NE(mm["results"]["shard_runs"][0]["build"]["libraries"]["embree"], "4.0.0");
  }
  for (const char* f : {"configs.csv", "compare.csv", "compare_summary.csv"}) {
    const auto rows = csv_rows(slurp(dir_ / "m" / f));
    ASSERT_FALSE(rows.empty()) << f;
    for (const auto& r : rows) EXPECT_EQ(r.at("scene"), mesh) << f;
  }
  const auto one = csv_rows(slurp(dir_ / "one" / "compare_summary.csv"));
  const auto merged = csv_rows(slurp(dir_ / "m" / "compare_summary.csv"));
  ASSERT_EQ(merged.size(), one.size());
  for (std::size_t i = 0; i < merged.size(); ++i) {
    EXPECT_EQ(merged[i].at("config"), one[i].at("config"));
    EXPECT_EQ(merged[i].at("reference"), "acc_contraction");
    EXPECT_TRUE(std::isfinite(std::stod(merged[i].at("perf_factor")))) << merged[i].at("config");
  }
  EXPECT_EQ(m.out.find(" - "), std::string::npos) << m.out;
}

// Compare's verdict on Naive and GWH01 (close early, behind later) needs two measured frames:
// with one, early and late are that frame, and the verdict is replaced by a line saying so.
TEST_F(Experiment, CompareGivesNoEarlyLateVerdictOnOneMeasuredFrame) {
  const std::string mesh = std::string(PTC_TEST_DATA) + "/meshes/bunny00.off";
  for (const char* frames : {"0:1", "0:2"}) {
    const RunResult r = ptc({"experiment", "compare", mesh, "--frames", frames, "--width", "16", "--height", "16",
                             "--quiet", "--out", (dir_ / (std::string("c") + frames[2])).string()});
    ASSERT_EQ(r.code, 0) << r.err;
    for (const char* b : {"naive", "gwh01"}) {
      const bool one = std::string(frames) == "0:1";
      EXPECT_EQ(r.out.find(std::string("paper: no verdict on ") + b + " clusters early and later: 1 measured frame") !=
                    std::string::npos,
                one)
          << r.out;
      EXPECT_EQ(r.out.find(std::string("paper: ") + b + " clusters close to the method early") != std::string::npos, !one)
          << r.out;
    }
  }
}

// Drift's "metrics per frame" line is the median over the frames after the warm-up, as every
// other median of the summaries (it took the warm-up frame in too), and is frames.csv's.
TEST_F(Experiment, DriftMetricsPerFrameLeaveTheWarmUpOut) {
  const RunResult r = ptc({"experiment", "drift", "cloth-sphere-32", "--frames", "40:44", "--width", "16", "--height",
                           "16", "--clusterings", "acc_growth,meshopt", "--quiet", "--out", (dir_ / "d").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto at = r.out.find("metrics per frame (median after the warm-up frame): ");
  ASSERT_NE(at, std::string::npos) << r.out;
  const std::string line = r.out.substr(at, r.out.find('\n', at) - at);
  std::map<std::string, std::vector<double>> ms;
  for (const auto& row : csv_rows(slurp(dir_ / "d" / "frames.csv")))
    if (row.at("warmup") == "0") ms[row.at("clustering")].push_back(std::stod(row.at("metrics_ms")));
  ASSERT_EQ(ms.size(), 3u);  // triangles and the two clusterings
  for (auto& [name, v] : ms) {
    ASSERT_EQ(v.size(), 4u) << name;
    std::sort(v.begin(), v.end());
    const double median = 0.5 * (v[1] + v[2]);
    EXPECT_NE(line.find(name + " " + fmt::format("{:.0f}", median) + " ms"), std::string::npos) << line << " " << name;
  }
}

// A `ptc cluster` output as the method: compare's and drift's default configurations take it as
// `given` (and perf_factor divides by it); a clustering of another mesh is refused naming it.
TEST_F(Experiment, GivenClustersAreTheMethodByDefault) {
  const std::string mesh = std::string(PTC_TEST_DATA) + "/meshes/bunny00.off";
  const std::string other = std::string(PTC_TEST_DATA) + "/meshes/elephant.off";
  const std::string c = (dir_ / "clusters").string();
  ASSERT_EQ(ptc({"cluster", mesh, "--method", "growth", "--max-count", "30", "--max-size", "30", "--out", c}).code, 0);
  const RunResult r = ptc({"experiment", "compare", mesh, "--clusters", c, "--frames", "0:1", "--width", "16",
                           "--height", "16", "--quiet", "--out", (dir_ / "cmp").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = csv_rows(slurp(dir_ / "cmp" / "compare_summary.csv"));
  std::set<std::string> configs;
  for (const auto& x : rows) {
    configs.insert(x.at("config"));
    EXPECT_EQ(x.at("reference"), "given");
  }
  EXPECT_TRUE(configs.count("given"));
  EXPECT_FALSE(configs.count("acc_growth"));
  const auto cfg = csv_rows(slurp(dir_ / "cmp" / "configs.csv"));
  const auto clusters = csv_rows(slurp(dir_ / "clusters" / "clusters.csv"));
  EXPECT_EQ(cfg.at(0).at("config"), "given");

  EXPECT_EQ(cfg.at(0).at("clusters"), std::to_string(clusters.size()));  // the given clustering, not a new one
  // its own parameters, from its manifest (they read 0 and 0 once)
  EXPECT_EQ(cfg.at(0).at("method"), "given");
  EXPECT_EQ(cfg.at(0).at("objective"), "acc");
  EXPECT_EQ(cfg.at(0).at("max_count"), "30");
  EXPECT_EQ(cfg.at(0).at("max_size"), "30");
  {  // without a manifest they are unknown: MaxCount empty, MaxSize nan
    const fs::path bare = dir_ / "bare";
    fs::create_directories(bare);
    fs::copy_file(dir_ / "clusters" / "triangles.csv", bare / "triangles.csv");
    ASSERT_EQ(ptc({"experiment", "compare", mesh, "--clusters", bare.string(), "--frames", "0:1", "--width", "16",
                   "--height", "16", "--quiet", "--out", (dir_ / "cmp_bare").string()})
                  .code,
              0);
    const auto b = csv_rows(slurp(dir_ / "cmp_bare" / "configs.csv"));
    EXPECT_EQ(b.at(0).at("config"), "given");
    EXPECT_EQ(b.at(0).at("objective"), "");
    EXPECT_EQ(b.at(0).at("max_count"), "");
    EXPECT_EQ(b.at(0).at("max_size"), "nan");
  }

  const RunResult d = ptc({"experiment", "drift", mesh, "--clusters", c, "--frames", "0:1", "--width", "16", "--height",
                           "16", "--clusterings", "given", "--quiet", "--out", (dir_ / "drift").string()});
  ASSERT_EQ(d.code, 0) << d.err;
  const RunResult bad = ptc({"experiment", "drift", other, "--clusters", c, "--frames", "0:1", "--width", "16",
                             "--height", "16", "--quiet", "--out", (dir_ / "bad").string()});
  EXPECT_EQ(bad.code, 1);
  EXPECT_NE(bad.err.find("triangles.csv"), std::string::npos) << bad.err;
  EXPECT_EQ(lines(bad.err), 1u) << bad.err;

  // Shards of one study whose --clusters were typed differently (as by a scheduler starting them
  // from other directories) merge: the clustering's files are compared by their bytes. Shards
  // with another clustering do not.
  auto shard = [&](const std::string& dir, const std::string& k, const std::string& out) {
    return ptc({"experiment", "compare", mesh, "--configs", "given,standard", "--clusters", dir, "--frames", "0:1",
                "--width", "16", "--height", "16", "--quiet", "--shard", k, "--out", (dir_ / out).string()});
  };
  ASSERT_EQ(shard(c, "1/2", "sh1").code, 0);
  ASSERT_EQ(shard(c + "/./", "2/2", "sh2").code, 0);
  const RunResult m = ptc({"merge", (dir_ / "sh1").string(), (dir_ / "sh2").string(), "--out", (dir_ / "m").string()});
  EXPECT_EQ(m.code, 0) << m.err;
  const std::string c2 = (dir_ / "clusters2").string();
  ASSERT_EQ(ptc({"cluster", mesh, "--method", "growth", "--max-count", "20", "--max-size", "20", "--out", c2}).code, 0);
  ASSERT_EQ(shard(c2, "2/2", "sh3").code, 0);
  const RunResult m2 = ptc({"merge", (dir_ / "sh1").string(), (dir_ / "sh3").string(), "--out", (dir_ / "m2").string()});
  EXPECT_EQ(m2.code, 1) << m2.err;
  EXPECT_NE(m2.err.find("not a shard of the same study"), std::string::npos) << m2.err;
}

// `ptc viz export` draws the drift study's values: every cluster's metrics in the .vtp of a frame
// equal that frame's rows of clusters_frames.csv, sah_share included (the study's cluster BVH is
// set up at the rest pose and updated; viz's was once made at each frame, whose fixed group trees
// and cluster order gave other shares from the second frame on).
TEST_F(Experiment, DriftAndVizExportAgreeValueForValue) {
  // The bunny twisted, and the mushroom exploded (the scene's mesh is then a soup of the one
  // clustered: both commands read the clustering by coincident corners, cluster.h adjacency_on;
  // viz once read it by edges there, and found no neighbours, one colour and other vertex counts).
  struct Case {
    const char* mesh;
    const char* deform;
    const char* max;
  };
  for (const Case k : {Case{"bunny00.off", R"({"kind": "twist", "axis": "y", "amplitude": 1.5, "period": 6})", "12"},
                       Case{"mushroom.off", R"({"kind": "explode", "amplitude": 0.05})", "8"}}) {
    SCOPED_TRACE(k.mesh);
    const std::string mesh = std::string(PTC_TEST_DATA) + "/meshes/" + k.mesh;
    const fs::path out = dir_ / k.mesh;
    fs::create_directories(out);
    const fs::path scene = out / "scene.json";
    {
      std::ofstream f(scene);
      f << R"({"schema": "ptc-scene/1", "frames": [0, 2], "meshes": [{"file": ")" << mesh << R"(", "deform": )"
        << k.deform << "}]}";
    }
    const std::string c = (out / "clusters").string();
    ASSERT_EQ(ptc({"cluster", mesh, "--method", "growth", "--max-count", k.max, "--max-size", k.max, "--out", c}).code, 0);
    const RunResult d = ptc({"experiment", "drift", scene.string(), "--clusters", c, "--clusterings", "given", "--width",
                             "16", "--height", "16", "--quiet", "--out", (out / "drift").string()});
    ASSERT_EQ(d.code, 0) << d.err;
    const RunResult v = ptc({"viz", "export", scene.string(), "--clusters", c, "--frames", "0:2", "--out",
                             (out / "vz").string()});
    ASSERT_EQ(v.code, 0) << v.err;
    std::map<std::pair<int, int>, std::map<std::string, std::string>> row;  // (frame, cluster) -> CSV row
    for (const auto& r : csv_rows(slurp(out / "drift" / "clusters_frames.csv")))
      row[{std::stoi(r.at("frame")), std::stoi(r.at("cluster_id"))}] = r;
    ASSERT_GT(row.size(), 3u * 40u);  // more clusters than a group of the two-level build
    for (int f = 0; f <= 2; ++f) {
      const ptc::viz::VtpContents vtp = ptc::viz::read_vtp(out / "vz" / ("clusters_000" + std::to_string(f) + ".vtp"));
      std::map<std::string, std::vector<std::int32_t>> ints(vtp.arrays.cell_int.begin(), vtp.arrays.cell_int.end());
      std::map<std::string, std::vector<double>> cells(vtp.arrays.cell.begin(), vtp.arrays.cell.end());
      const auto& ids = ints.at("cluster_id");
      std::size_t checked = 0;
      for (std::size_t t = 0; t < ids.size(); ++t) {
        const auto& r = row.at({f, ids[t]});
        EXPECT_EQ(cells.at("sah_share")[t], std::stod(r.at("sah_share"))) << "frame " << f << " cluster " << ids[t];
        for (const char* m : {"vertices", "connectivity", "boundary_vertices", "components", "not_full", "reg", "acc",
                              "box_area_ratio", "box_area_ratio_prev", "sphere_radius_ratio", "p_hit"}) {
          const double want = std::stod(r.at(m));
          EXPECT_NEAR(cells.at(m)[t], want, 1e-12 * std::max(1.0, std::abs(want))) << m << " frame " << f;
        }
        ++checked;
      }
      EXPECT_GT(checked, 0u);
    }
  }
}

// A shard's table edited after its run (one number changed, the row count kept) is refused by
// merge, naming the file: each manifest records its tables' bytes and FNV-1a hashes.
TEST_F(Experiment, MergeRefusesAnEditedTableNamingIt) {
  const std::vector<std::string> run = {"experiment", "sweep", "cloth-sphere-32", "--max-counts", "0,10", "--frames",
                                        "0:1", "--width", "8", "--height", "8", "--quiet", "--out"};
  auto a = run, b = run;
  a.insert(a.end(), {(dir_ / "a").string(), "--shard", "1/2"});
  b.insert(b.end(), {(dir_ / "b").string(), "--shard", "2/2"});
  ASSERT_EQ(ptc(a).code, 0);
  ASSERT_EQ(ptc(b).code, 0);
  // Untouched, they merge; the manifest's hash is FNV-1a 64 of the file's bytes (computed here).
  ASSERT_EQ(ptc({"merge", (dir_ / "a").string(), (dir_ / "b").string(), "--out", (dir_ / "m").string()}).code, 0);
  const std::string csv = slurp(dir_ / "a" / "sweep.csv");
  const auto man = nlohmann::json::parse(slurp(dir_ / "a" / "manifest.json"));
  EXPECT_EQ(man["output_hashes"]["sweep.csv"]["fnv1a64"], ptc::test::fnv1a64_hex(csv));
  EXPECT_EQ(man["output_hashes"]["sweep.csv"]["bytes"], csv.size());
  // One digit of the second row changed.
  std::string edited = csv;
  const auto row2 = edited.find('\n') + 1;
  const auto digit = edited.find_first_of("123456789", edited.find(',', row2));
  ASSERT_NE(digit, std::string::npos);
  edited[digit] = edited[digit] == '9' ? '8' : static_cast<char>(edited[digit] + 1);
  spit(dir_ / "a" / "sweep.csv", edited);
  const RunResult r = ptc({"merge", (dir_ / "a").string(), (dir_ / "b").string(), "--out", (dir_ / "m2").string()});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find((dir_ / "a" / "sweep.csv").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("edited"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "m2"));
}

// A translated mesh does not deform: its clusters' box areas and radii move by rounding only
// (ratios 1 +- a few ulps in clusters_frames.csv), and the drift correlations say so (no
// variance: nan) instead of ranking the rounding noise.
TEST_F(Experiment, RoundingIsNoDrift) {
  const std::string mesh = std::string(PTC_TEST_DATA) + "/meshes/bunny00.off";
  const fs::path scene = dir_ / "moved.json";
  {
    std::ofstream f(scene);
    f << R"({"frames": [0, 3], "meshes": [{"file": ")" << mesh
      << R"(", "deform": {"kind": "rigid", "axis": "y", "amplitude": 0, "period": 8, "velocity": [0.1, 0.03, 0]}}]})";
  }
  const RunResult d = ptc({"experiment", "drift", scene.string(), "--clusterings", "acc_growth", "--width", "8",
                           "--height", "8", "--quiet", "--out", (dir_ / "d").string()});
  ASSERT_EQ(d.code, 0) << d.err;
  std::size_t noisy = 0;  // rows whose ratios are not exactly 1: the noise the floor removes
  for (const auto& r : csv_rows(slurp(dir_ / "d" / "clusters_frames.csv"))) {
    const double a = std::stod(r.at("box_area_ratio")), b = std::stod(r.at("sphere_radius_ratio"));
    EXPECT_NEAR(a, 1.0, 1e-13);
    EXPECT_NEAR(b, 1.0, 1e-13);
    noisy += a != 1.0 || b != 1.0;
  }
  EXPECT_GT(noisy, 0u) << "the test needs rounding noise to mean anything";
  const auto corr = csv_rows(slurp(dir_ / "d" / "correlation.csv"));
  ASSERT_EQ(corr.size(), 2u);
  for (const auto& r : corr) {
    EXPECT_EQ(r.at("spearman"), "nan") << r.at("y");
    EXPECT_EQ(r.at("pearson"), "nan") << r.at("y");
  }
  // The summary says why there is no number.
  EXPECT_NE(slurp(dir_ / "d" / "summary.txt").find("no Spearman: no variance"), std::string::npos);
  // One frame: no frame after the first to drift in, said as such (it blamed boxes of zero area).
  const RunResult one = ptc({"experiment", "drift", scene.string(), "--clusterings", "acc_growth", "--frames", "2:2",
                             "--width", "8", "--height", "8", "--quiet", "--out", (dir_ / "one").string()});
  ASSERT_EQ(one.code, 0) << one.err;
  EXPECT_NE(slurp(dir_ / "one" / "summary.txt").find("no Spearman: one frame only"), std::string::npos)
      << slurp(dir_ / "one" / "summary.txt");
}

// configs.csv gives MaxSize only where the method reads it (Acc): nan for the others.
TEST_F(Experiment, ConfigsListMaxSizeOnlyWhereTheMethodReadsIt) {
  const RunResult r = ptc({"experiment", "compare", "cloth-sphere-32", "--configs", "acc_growth,naive,meshopt", "--frames",
                           "0", "--width", "8", "--height", "8", "--max-size", "40", "--quiet", "--out",
                           (dir_ / "c").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  std::map<std::string, std::string> max_size;
  for (const auto& x : csv_rows(slurp(dir_ / "c" / "configs.csv"))) max_size[x.at("config")] = x.at("max_size");
  EXPECT_EQ(max_size.at("acc_growth"), "40");
  EXPECT_EQ(max_size.at("naive"), "nan");
  EXPECT_EQ(max_size.at("meshopt"), "nan");
}

// A frame that collapses every cluster to a point measures no sphere: the accuracy rows say
// count 0 and nan, not a mean error of 0 over nothing.
TEST_F(Experiment, AccuracyOfACollapsedFrameMeasuresNothing) {
  const fs::path seq = dir_ / "seq";
  fs::create_directories(seq);
  std::string grid = "OFF\n25 32 0\n", same = "OFF\n25 32 0\n";
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 5; ++x) grid += std::to_string(x) + " " + std::to_string(y) + " " + std::to_string((x * y) % 3) + "\n";
  for (int i = 0; i < 25; ++i) same += "0.5 0.5 0\n";
  std::string faces;
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      const int v = 5 * y + x;
      faces += "3 " + std::to_string(v) + " " + std::to_string(v + 1) + " " + std::to_string(v + 6) + "\n";
      faces += "3 " + std::to_string(v) + " " + std::to_string(v + 6) + " " + std::to_string(v + 5) + "\n";
    }
  spit(seq / "f0.off", grid + faces);
  spit(seq / "f1.off", same + faces);
  spit(dir_ / "grid.off", grid + faces);
  ASSERT_EQ(ptc({"cluster", (dir_ / "grid.off").string(), "--max-count", "4", "--max-size", "4", "--out",
                 (dir_ / "c").string()})
                .code,
            0);
  const RunResult r = ptc({"experiment", "accuracy", seq.string(), "--clusters", (dir_ / "c").string(), "--frames", "0:1",
                           "--width", "8", "--height", "8", "--quiet", "--out", (dir_ / "a").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  std::size_t checked = 0;
  for (const auto& row : csv_rows(slurp(dir_ / "a" / "accuracy.csv"))) {
    if (row.at("group") != "sphere") continue;
    if (row.at("frame") == "1") {
      EXPECT_EQ(row.at("count"), "0") << row.at("choice");
      EXPECT_EQ(row.at("error_mean"), "nan") << row.at("choice");
      EXPECT_EQ(row.at("error_max"), "nan") << row.at("choice");
      ++checked;
    } else {
      EXPECT_NE(row.at("count"), "0") << row.at("choice");
    }
  }
  EXPECT_GT(checked, 0u);
}

TEST_F(Experiment, MergeRefusesAnEditedManifestNamingIt) {
  const std::vector<std::string> run = {"experiment", "sweep", "cloth-sphere-32", "--max-counts", "0", "--frames", "0",
                                        "--width", "8", "--height", "8", "--quiet", "--out"};
  auto a = run, b = run;
  a.push_back((dir_ / "a").string());
  ASSERT_EQ(ptc(a).code, 0);
  std::string m = slurp(dir_ / "a" / "manifest.json");
  const auto at = m.find("\"item_rows\"");
  ASSERT_NE(at, std::string::npos);
  m.replace(at, 11, "\"item_ruws\"");
  spit(dir_ / "a" / "manifest.json", m);
  const RunResult r = ptc({"merge", (dir_ / "a").string(), "--out", (dir_ / "m").string()});
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("manifest.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("item_rows"), std::string::npos) << r.err;
  EXPECT_EQ(lines(r.err), 1u) << r.err;
  // A manifest cut short: the file and the byte, without nlohmann's exception name.
  spit(dir_ / "a" / "manifest.json", m.substr(0, 40));
  const RunResult cut = ptc({"merge", (dir_ / "a").string(), "--out", (dir_ / "m").string()});
  EXPECT_EQ(cut.code, 1);
  EXPECT_NE(cut.err.find("manifest.json: byte 40: not valid JSON: parse error"), std::string::npos) << cut.err;
  EXPECT_EQ(cut.err.find("json.exception"), std::string::npos) << cut.err;
  EXPECT_EQ(lines(cut.err), 1u) << cut.err;
}

TEST_F(Experiment, UsageErrorsNameTheFlag) {
  const std::string out = (dir_ / "x").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"experiment", "compare", "cloth-sphere-32", "--max-counts", "0,10"}, "--max-counts"},
      {{"experiment", "sweep", "cloth-sphere-32", "--clusters", "somewhere"}, "--clusters"},
      {{"experiment", "sweep", "cloth-sphere-32", "--max-count", "20"}, "--max-count"},
      {{"experiment", "sweep", "cloth-sphere-32", "--max-counts", "0,x"}, "--max-counts"},
      {{"experiment", "sweep", "cloth-sphere-32", "--max-counts", "10,10"}, "--max-counts: '10' is listed twice"},
      {{"experiment", "compare", "cloth-sphere-32", "--configs", "acc_growth,bogus"}, "'bogus' is not a configuration"},
      {{"experiment", "compare", "cloth-sphere-32", "--configs", "given"}, "--clusters"},
      {{"experiment", "compare", "cloth-sphere-32", "--configs", "acc_growth", "--reference", "standard"}, "--reference"},
      {{"experiment", "drift", "cloth-sphere-32", "--clusterings", "standard"}, "--clusterings"},
      {{"experiment", "sweep", "cloth-sphere-32", "--gwh-a1", "0.5"}, "--gwh-a1"},
      {{"experiment", "sweep", "cloth-sphere-32", "--shard", "0/3"}, "--shard"},
      {{"experiment", "sweep", "cloth-sphere-32", "--shard", "4/3"}, "--shard"},
      {{"experiment", "sweep", "cloth-sphere-32", "--max-counts", "0,10", "--shard", "1/3"}, "at most one shard per item"},
      {{"experiment", "sweep", "cloth-sphere-32", "--frames", "5:2"}, "--frames"},
      {{"experiment", "bogus", "cloth-sphere-32"}, "KIND"},
      {{"experiment", "compare", "cloth-sphere-32", "--method", "growth"}, "--method"},
      {{"experiment", "drift", "cloth-sphere-32", "--objective", "naive"}, "--objective"},
      {{"experiment", "sweep", "cloth-sphere-32", "--ao-samples", "2"}, "--ao-samples"},
      {{"experiment", "drift", "cloth-sphere-32", "--reference-rays", "10"}, "--reference-rays"},
      // more rays than the image has pixels (it was clamped silently, the manifest saying 5000)
      {{"experiment", "accuracy", "cloth-sphere-32", "--reference-rays", "5000", "--width", "32", "--height", "32"},
       "--reference-rays: asks for 5000 rays, but the 32x32 image has 1024 (give at most 1024)"},
      {{"experiment", "sweep", "cloth-sphere-32", "--max-counts", "0,,10"}, "empty item"},
      {{"experiment", "sweep", "cloth-sphere-32", "--max-counts", "2000000"}, "--max-counts"},
      {{"experiment", "sweep", "cloth-sphere-32", "--method", "meshopt", "--max-counts", "0,1"}, "--max-counts"},
  };
  for (auto [args, what] : cases) {
    args.insert(args.end(), {"--quiet", "--out", out});
    const RunResult r = ptc(args);
    EXPECT_EQ(r.code, 2) << args[1] << " " << args[3] << ": " << r.err;
    EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
    EXPECT_EQ(lines(r.err), 1u) << r.err;
    EXPECT_FALSE(fs::exists(out));
  }
}

// The cluster BVH's flags need a configuration that builds one: refused, naming the flag, where
// none does (found by a new user: they were recorded in the manifest as if used), and accepted
// beside a clustering.
TEST_F(Experiment, ClusterBvhFlagsWithoutAClusterBvhAreRefused) {
  const std::vector<std::vector<std::string>> flags = {
      {"--cluster-leaf", "block-tree"}, {"--cluster-groups", "4"}, {"--group-trees", "rebuild"}, {"--vertex-order", "input"}};
  for (const auto& f : flags) {
    for (const std::vector<std::string>& run :
         {std::vector<std::string>{"experiment", "compare", "faerie", "--configs", "standard,embree_low"},
          std::vector<std::string>{"experiment", "sweep", "faerie", "--max-counts", "0"}}) {
      std::vector<std::string> args = run;
      args.insert(args.end(), f.begin(), f.end());
      args.insert(args.end(), {"--frames", "0:1", "--width", "8", "--height", "8", "--quiet", "--out", (dir_ / "x").string()});
      const RunResult r = ptc(args);
      EXPECT_EQ(r.code, 2) << f[0] << " " << run[1] << ": " << r.err;
      EXPECT_EQ(lines(r.err), 1u) << r.err;
      EXPECT_NE(r.err.find(f[0] + ": not used: no configuration of this " + run[1] + " builds a cluster BVH"), std::string::npos)
          << r.err;
      EXPECT_FALSE(fs::exists(dir_ / "x"));
    }
  }
  const RunResult ok = ptc({"experiment", "sweep", "faerie", "--max-counts", "0,30", "--cluster-groups", "4", "--frames",
                            "0:1", "--width", "8", "--height", "8", "--quiet", "--out", (dir_ / "ok").string()});
  EXPECT_EQ(ok.code, 0) << ok.err;
  // configs.csv names the method of a structure over triangles `none`, in a sweep (MaxCount 0)
  // and in a compare (standard, Embree) alike (the compare left it empty).
  const RunResult cmp = ptc({"experiment", "compare", "faerie", "--configs", "standard,embree_low,acc_growth", "--frames",
                             "0:1", "--width", "8", "--height", "8", "--quiet", "--out", (dir_ / "cmp").string()});
  ASSERT_EQ(cmp.code, 0) << cmp.err;
  std::map<std::string, std::string> method;
  for (const auto& r : csv_rows(slurp(dir_ / "cmp" / "configs.csv"))) method[r.at("config")] = r.at("method");
  for (const auto& r : csv_rows(slurp(dir_ / "ok" / "configs.csv"))) method[r.at("config")] = r.at("method");
  EXPECT_EQ(method.at("standard"), "none");
  EXPECT_EQ(method.at("embree_low"), "none");
  EXPECT_EQ(method.at("max_count=0"), "none");
  EXPECT_EQ(method.at("acc_growth"), "growth");
  EXPECT_EQ(method.at("max_count=30"), "contraction");  // (the sweep clusters by contraction with Acc)
}

}  // namespace
}  // namespace ptc::test
