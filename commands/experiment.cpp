// `ptc experiment` and `ptc merge`.
#include "commands/experiment.h"

#include <algorithm>
#include <charconv>
#include <fstream>
#include <map>
#include <ostream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "analysis/schema/json.h"
#include "analysis/schema/manifest.h"
#include "commands/args.h"
#include "commands/cluster_files.h"
#include "commands/commands.h"
#include "commands/inputs.h"
#include "commands/output_dir.h"
#include "commands/progress.h"
#include "commands/scene_args.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/core/strings.h"

namespace ptc {

namespace {

constexpr const char* kManifestSchema = "ptc-experiment/1";

study::Shard parse_shard(const std::string& s) {
  const auto slash = s.find('/');
  auto bad = [&] { return UsageError("--shard", fmt::format("'{}' is not K/N with 1 <= K <= N <= 100000", s)); };
  if (slash == std::string::npos) throw bad();
  const std::string k = s.substr(0, slash), n = s.substr(slash + 1);
  auto digits = [](const std::string& x) {
    return !x.empty() && x.size() <= 6 && std::all_of(x.begin(), x.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  if (!digits(k) || !digits(n)) throw bad();
  const long kk = std::stol(k), nn = std::stol(n);
  if (kk < 1 || nn < 1 || kk > nn || nn > 100000) throw bad();
  return {static_cast<std::uint32_t>(kk - 1), static_cast<std::uint32_t>(nn)};
}

// A comma-separated flag value: every item non-empty.
std::vector<std::string> flag_list(const std::string& s, const char* flag) {
  if (s.empty() || s.front() == ',' || s.back() == ',' || s.find(",,") != std::string::npos)
    throw UsageError(flag, fmt::format("'{}' has an empty item (a comma-separated list)", s));
  return split_list(s);
}

bool is_structure(std::string_view s) {
  for (const char* n : kCompareStructures)
    if (s == n) return true;
  return false;
}
bool is_clustering(std::string_view s) { return study::clustering_config(s, {}).has_value(); }
std::string names_list(bool structures) {
  std::string s;
  for (const char* n : study::kClusteringNames) s += std::string(s.empty() ? "" : ", ") + n;
  s += ", given";
  if (structures)
    for (const char* n : kCompareStructures) s += std::string(", ") + n;
  return s;
}

// The clusterings (ClusterConfigs) the experiment's items make, to check the flags against.
std::vector<ClusterConfig> item_clusterings(const ExperimentParams& p, const std::vector<std::string>& items) {
  std::vector<ClusterConfig> out;
  if (p.kind == ExperimentKind::Sweep) {
    for (std::uint32_t n : p.max_counts) {
      ClusterConfig c = p.cluster;
      c.max_count = n, c.max_size = n;
      if (n > 0) out.push_back(c);
    }
    return out;
  }
  if (p.kind == ExperimentKind::Accuracy) {
    ClusterConfig c = p.cluster;
    c.method = ClusterMethod::Contraction, c.objective = ObjectiveKind::Acc;
    out.push_back(c);
    return out;
  }
  for (const auto& i : items)
    if (auto c = study::clustering_config(i, p.cluster)) out.push_back(*c);
  return out;
}

nlohmann::json cluster_parameters(const ClusterConfig& c) {
  return {{"max_count", c.max_count},           {"max_size", c.max_size},
          {"size_bound", to_string(c.size_bound_mode)}, {"sphere", to_string(c.sphere)},
          {"start", to_string(c.start)},         {"gwh_a1", c.gwh.a1},
          {"gwh_a2", c.gwh.a2},                  {"gwh_weight", to_string(c.gwh.weight)},
          {"target_clusters", c.target_clusters}, {"max_triangles", c.max_triangles},
          {"method", to_string(c.method)},       {"objective", to_string(c.objective)},
          {"adjacency", to_string(c.adjacency)}, {"regions", c.regions}};
}

// The clustering parameters of the manifest: those that some clustering of the run read
// (used_parameters), as `ptc cluster` records only what its method read. Sweep's MaxCount and
// MaxSize are its --max-counts values (recorded as max_counts); compare's and drift's methods
// and objectives are named by their items.
nlohmann::json used_cluster_parameters(const ClusterConfig& base, const std::vector<ClusterConfig>& made,
                                       ExperimentKind kind) {
  const nlohmann::json all = cluster_parameters(base);
  std::set<std::string, std::less<>> used;
  for (const ClusterConfig& c : made)
    for (std::string_view u : used_parameters(c)) used.emplace(u);
  if (kind == ExperimentKind::Sweep && !made.empty()) used.insert("method");  // (every sweep clustering's)
  if (kind == ExperimentKind::Sweep) used.erase("max_count"), used.erase("max_size");
  if (kind != ExperimentKind::Sweep) used.erase("method"), used.erase("objective");
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [key, value] : all.items())
    if (used.count(key)) out[key] = value;
  return out;
}

nlohmann::json item_rows_json(const std::vector<FileRows>& files) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& f : files) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& [item, rows] : f.item_rows) a.push_back({item, rows});
    j[f.file] = a;
  }
  return j;
}

// Writes the assembled files and the summary; lists them in the manifest.
void write_assembled(OutputDir& dir, RunManifest& manifest, const Assembled& a) {
  for (const auto& f : a.files) {
    const std::string text = f.rows.str();
    dir.write(f.file, text);
    manifest.add_output(f.file, f.schema.id());
    manifest.add_output_hash(f.file, text.size(), bytes_fnv1a64(text));
  }
  dir.write("summary.txt", a.text);
  manifest.add_output("summary.txt");
  manifest.add_output_hash("summary.txt", a.text.size(), bytes_fnv1a64(a.text));
}

// A CSV cell as JSON: a number when the whole cell is one (nan and inf: null, as JSON has none),
// else the text.
nlohmann::json cell_json(const std::string& c) {
  if (c == "nan" || c == "inf" || c == "-inf") return nullptr;
  std::int64_t n = 0;
  if (const auto ri = std::from_chars(c.data(), c.data() + c.size(), n); !c.empty() && ri.ec == std::errc() &&
                                                                         ri.ptr == c.data() + c.size())
    return n;
  double v = 0;
  const auto res = std::from_chars(c.data(), c.data() + c.size(), v);
  if (!c.empty() && res.ec == std::errc() && res.ptr == c.data() + c.size()) return v;
  return c;
}

nlohmann::json summary_json(const Assembled& a, std::string_view schema) {
  nlohmann::json files = nlohmann::json::object();
  for (const auto& f : a.files) {
    // The summary tables: the sweep's and compare's summaries; drift's per-frame table (its
    // printed first -> last rows come from it), Spearman and fits; accuracy's table. Not the
    // per-frame, per-cluster or per-ray rows.
    static const std::set<std::string, std::less<>> kSummaries = {
        "sweep_summary.csv", "compare_summary.csv", "frames.csv", "correlation.csv", "regression.csv", "accuracy.csv"};
    if (!kSummaries.count(f.file)) continue;
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& r : f.rows.rows) {
      nlohmann::json o = nlohmann::json::object();
      for (std::size_t i = 0; i < r.size(); ++i) o[f.rows.header[i]] = cell_json(r[i]);
      rows.push_back(o);
    }
    files[f.file] = rows;
  }
  return {{"schema", schema}, {"tables", files}};
}

}  // namespace

void cmd_experiment(const ExperimentCommandOptions& opt, std::ostream& out) {
  const auto kind = parse_experiment_kind(opt.kind);
  if (!kind) throw UsageError("KIND", fmt::format("'{}' is not an experiment (sweep, compare, drift or accuracy)", opt.kind));
  if (opt.out_dir.empty()) throw UsageError("--out", "an output directory is required");
  check_image_size(opt.width, opt.height);
  const char* k = to_string(*kind);
  auto only = [&](bool present, ExperimentKind for_kind, const char* flag) {
    if (present && *kind != for_kind)
      throw UsageError(flag, fmt::format("is for `ptc experiment {}`, not {}", to_string(for_kind), k));
  };
  only(opt.max_counts.has_value(), ExperimentKind::Sweep, "--max-counts");
  only(opt.configs.has_value(), ExperimentKind::Compare, "--configs");
  only(opt.reference.has_value(), ExperimentKind::Compare, "--reference");
  only(opt.clusterings.has_value(), ExperimentKind::Drift, "--clusterings");
  only(opt.ao_samples.has_value(), ExperimentKind::Drift, "--ao-samples");
  only(opt.reference_rays.has_value(), ExperimentKind::Accuracy, "--reference-rays");
  if (opt.method_given && *kind != ExperimentKind::Sweep)
    throw UsageError(std::find(opt.given.begin(), opt.given.end(), "objective") != opt.given.end() ? "--objective"
                                                                                                  : "--method",
                     *kind == ExperimentKind::Compare ? "compare names its clusterings in --configs (acc_growth, "
                                                        "acc_contraction, naive, gwh01, meshopt, sah_split, given)"
                     : *kind == ExperimentKind::Drift ? "drift names its clusterings in --clusterings (acc_growth, "
                                                        "acc_contraction, naive, gwh01, meshopt, sah_split, given)"
                                                      : "accuracy measures contraction with Acc (or --clusters DIR)");

  ExperimentParams p;
  p.kind = *kind;
  p.scene = opt.input.string();
  p.cluster = opt.cluster;
  p.ao_samples = opt.ao_samples.value_or(1);
  // Checked against the image: never more rays than its pixels (the default 512 takes them all
  // in a smaller image, and the manifest records the count used).
  const std::size_t pixels = static_cast<std::size_t>(opt.width) * static_cast<std::size_t>(opt.height);
  if (opt.reference_rays && *opt.reference_rays > pixels)
    throw UsageError("--reference-rays", fmt::format("asks for {} rays, but the {}x{} image has {} (give at most {})",
                                                     *opt.reference_rays, opt.width, opt.height, pixels, pixels));
  p.reference_rays = opt.reference_rays.value_or(std::min<std::size_t>(512, pixels));
  if (*kind == ExperimentKind::Sweep) {
    if (!opt.clusters.empty())
      throw UsageError("--clusters", "sweep makes its own clustering per --max-counts value (compare, drift and "
                                     "accuracy take one)");
    for (const char* f : {"max_count", "max_size"})
      if (std::find(opt.given.begin(), opt.given.end(), f) != opt.given.end())
        throw UsageError(flag_of(f), "sweep sets MaxCount = MaxSize to each --max-counts value");
    if (opt.max_counts) {
      p.max_counts.clear();
      for (const std::string& v : flag_list(*opt.max_counts, "--max-counts")) {
        const bool digits = v.size() <= 7 && std::all_of(v.begin(), v.end(), [](char c) { return c >= '0' && c <= '9'; });
        if (!digits || std::stoul(v) > (1u << 20))
          throw UsageError("--max-counts", fmt::format("'{}' is not a whole number 0..{}", v, 1u << 20));
        p.max_counts.push_back(static_cast<std::uint32_t>(std::stoul(v)));
      }
    }
  }
  const bool given = !opt.clusters.empty();
  p.clusters_given = given;
  if (opt.configs) {
    p.configs = flag_list(*opt.configs, "--configs");
    for (const auto& c : p.configs)
      if (!is_clustering(c) && !is_structure(c) && c != "given")
        throw UsageError("--configs", fmt::format("'{}' is not a configuration ({})", c, names_list(true)));
  }
  if (opt.clusterings) {
    p.clusterings = flag_list(*opt.clusterings, "--clusterings");
    for (const auto& c : p.clusterings)
      if (!is_clustering(c) && c != "given")
        throw UsageError("--clusterings", fmt::format("'{}' is not a clustering ({})", c, names_list(false)));
  }
  const std::vector<std::string> items = experiment_items(p);
  {
    std::set<std::string> seen;
    for (const auto& i : items)
      if (!seen.insert(i).second)
        throw UsageError(*kind == ExperimentKind::Sweep ? "--max-counts" : *kind == ExperimentKind::Compare ? "--configs"
                                                                                                           : "--clusterings",
                         // (a sweep's items are named max_count=N: the user wrote N)
                         fmt::format("'{}' is listed twice", *kind == ExperimentKind::Sweep && i.rfind("max_count=", 0) == 0
                                                                 ? i.substr(10)
                                                                 : i));
    if (!given && seen.count("given"))
      throw UsageError("--clusters", "configuration 'given' needs --clusters DIR (a `ptc cluster` output)");
    if (given && *kind != ExperimentKind::Accuracy && !seen.count("given"))
      throw UsageError("--clusters", "--clusters is used by the configuration 'given': list it");
  }
  if (*kind == ExperimentKind::Compare) {
    // Default: the method (the given clustering, else contraction with Acc), else the first listed.
    const auto listed = [&](const std::string& c) { return std::find(items.begin(), items.end(), c) != items.end(); };
    p.reference = opt.reference                        ? *opt.reference
                  : listed("given")                    ? "given"
                  : listed("acc_contraction")          ? "acc_contraction"
                                                       : items.front();
    if (std::find(items.begin(), items.end(), p.reference) == items.end())
      throw UsageError("--reference", fmt::format("'{}' is not among the configurations compared", p.reference));
  }
  // Every clustering flag the user set must be used by one of the clusterings.
  const std::vector<ClusterConfig> made = item_clusterings(p, items);
  for (const std::string& g : opt.given) {
    bool used = false;
    for (const ClusterConfig& c : made) {
      const auto u = used_parameters(c);
      used = used || std::find(u.begin(), u.end(), g) != u.end();
    }
    if (!used) throw UsageError(flag_of(g), fmt::format("not used by any clustering of this {}", k));
  }
  // The cluster BVH's flags need a configuration that builds one (a clustering or 'given').
  const bool cluster_bvh = !made.empty() || std::find(items.begin(), items.end(), "given") != items.end();
  if (!cluster_bvh && !opt.structure_flags.empty())
    throw UsageError(opt.structure_flags.front(),
                     fmt::format("not used: no configuration of this {} builds a cluster BVH{}", k,
                                 *kind == ExperimentKind::Sweep ? " (--max-counts 0 is the triangle BVH)" : ""));
  for (const ClusterConfig& c : made)
    if (const auto problem = check(c)) {
      // sweep's MaxCount and MaxSize come from --max-counts
      const bool swept = *kind == ExperimentKind::Sweep && (problem->parameter == "max_count" || problem->parameter == "max_size");
      throw UsageError(swept ? "--max-counts" : flag_of(problem->parameter),
                       swept ? fmt::format("MaxCount {}: {}", c.max_count, problem->reason) : problem->reason);
    }

  study::StudySetup setup;
  if (opt.shard) setup.shard = parse_shard(*opt.shard);
  if (setup.shard.count > items.size())
    throw UsageError("--shard", fmt::format("{} shards for {} work items ({}): at most one shard per item",
                                            setup.shard.count, items.size(), fmt::join(items, ", ")));
  setup.width = opt.width;
  setup.height = opt.height;
  setup.threads = resolve_threads(opt.threads);
  setup.cluster_leaf = opt.cluster_leaf;
  setup.cluster_group_size = opt.cluster_group_size;
  setup.min_cluster_groups = opt.min_cluster_groups;
  setup.group_trees = opt.group_trees;
  setup.vertex_order = opt.vertex_order;

  refuse_overwriting_input(opt.out_dir, opt.input);
  refuse_overwriting_input(opt.out_dir, opt.clusters);
  RunManifest manifest("experiment", opt.argv, kManifestSchema);
  MovingScene ms = open_moving_scene(opt.input, opt.scene_options, opt.deform, opt.frames, opt.extend_frames, manifest);
  setup.frames = ms.range;
  setup.camera = camera_for(opt.camera, ms.scene);
  const Box3 bounds = ms.scene.rest().referenced_bounds();  // (the camera's and the light's)
  const bvh::PinholeCamera cam = make_camera(setup.camera, bounds, setup.width, setup.height, opt.input.string());
  check_eye_reach(cam, opt.camera, ms.scene, opt.input.string());
  const LightChoice light = light_for(opt.light, ms.scene, cam, bounds, opt.input.string());
  setup.light = light.position;
  OutputDir dir(opt.out_dir);  // a refused target fails before the (long) run
  Clustering clusters;
  if (given) clusters = read_clusters_recorded(opt.clusters, ms.scene.rest(), manifest);
  p.given = given ? &clusters : nullptr;
  if (given) {  // its own parameters for its metrics (acc): as ptc viz reads them
    const ClusteringInfo ci = clustering_info_recorded(opt.clusters, manifest);
    if (ci.from_manifest) p.given_cluster = ci.cfg;
    manifest.set_parameter("given_parameters_from",
                           ci.from_manifest ? ci.from : "the clustering flags (no manifest.json beside triangles.csv)");
  }

  // The rest mesh as loaded (before any renumbering): what merge compares, whatever the files.
  const std::string rest_hash = mesh_fnv1a64(ms.scene.rest());
  Stopwatch sw;
  ExperimentRun run;
  {
    ProgressBar bar{std::string(k)};
    if (!opt.quiet) setup.progress = [&bar](double f) { bar.update(f); };
    try {
      run = run_experiment(ms.scene, p, setup);
    } catch (const bvh::FrameRangeError& e) {
      throw InputError(p.scene, "", e.frame ? fmt::format("frame {}", *e.frame) : std::string(), e.what());
    } catch (const std::invalid_argument& e) {
      throw InputError(p.scene, "", "", e.what());
    }
  }
  manifest.add_timing_ms("experiment", sw.ms());
  for (const auto& [key, ms_] : run.timings_ms) manifest.add_timing_ms(key, ms_);
  const nlohmann::json rows = item_rows_json(run.files);
  std::vector<std::string> primaries;
  for (const auto& f : run.files) primaries.push_back(f.file);
  const Assembled a = assemble(p.kind, std::move(run.files), p.reference);

  manifest.set_parameter("experiment", k);
  manifest.set_parameter("scene", p.scene);
  manifest.set_parameter("frames", {setup.frames.first, setup.frames.last});
  manifest.set_parameter("motion", ms.motion);
  manifest.set_parameter("width", setup.width);
  manifest.set_parameter("height", setup.height);
  manifest.set_parameter("camera", {{"eye", vec_json(cam.eye)}, {"forward", vec_json(cam.forward)},
                                    {"up", vec_json(cam.up)}, {"fov_y_deg", cam.fov_y_deg}});
  manifest.set_parameter("light", {{"position", vec_json(setup.light)}, {"from", light.from}});
  manifest.set_parameter("threads", setup.threads);
  manifest.set_parameter("cluster", used_cluster_parameters(p.cluster, made, *kind));
  manifest.set_parameter("clusters_given", given);
  manifest.set_parameter("cluster_leaf", bvh::to_string(setup.cluster_leaf));
  manifest.set_parameter("cluster_group_size", setup.cluster_group_size);  // (at most: see min_cluster_groups)
  manifest.set_parameter("min_cluster_groups", setup.min_cluster_groups);
  manifest.set_parameter("group_trees", bvh::to_string(setup.group_trees));
  manifest.set_parameter("vertex_order", bvh::to_string(setup.vertex_order));
  const bvh::SahCostModel model = bvh::cluster_scene_defaults().build.cost;
  manifest.set_parameter("sah_cost_model", {{"traversal", model.traversal}, {"intersection", model.intersection}});
  if (*kind == ExperimentKind::Sweep) manifest.set_parameter("max_counts", p.max_counts);
  if (*kind == ExperimentKind::Compare) manifest.set_parameter("reference", p.reference);
  if (*kind == ExperimentKind::Drift) manifest.set_parameter("ao_samples", p.ao_samples);
  if (*kind == ExperimentKind::Accuracy) manifest.set_parameter("reference_rays", p.reference_rays);
  manifest.set_parameter("items", items);
  manifest.set_parameter("shard", {{"index", setup.shard.index + 1}, {"count", setup.shard.count}});
  manifest.set_result("items_done", run.done);
  manifest.set_result("primary_files", primaries);
  manifest.set_result("item_rows", rows);
  manifest.set_result("triangles", run.triangles);
  manifest.set_result("vertices", run.vertices);
  manifest.set_result("rays", run.rays);
  manifest.set_result("rest_mesh_fnv1a64", rest_hash);
  write_assembled(dir, manifest, a);
  (void)commit_with_manifest(dir, manifest);

  if (opt.json) {
    out << dump_json(summary_json(a, "ptc-experiment-summary/1"));
    return;
  }
  out << fmt::format("{} {}: {}, frames {}..{} ({}), {} per frame, {}{}\n", k, p.scene,
                     counted(run.triangles, "triangle"), setup.frames.first, setup.frames.last, ms.motion,
                     counted(run.rays, "ray"), counted(setup.threads, "thread"),
                     setup.shard.whole() ? std::string()
                                         : fmt::format(", shard {} ({} of {} items)", setup.shard.str(), run.done.size(),
                                                       items.size()));
  out << a.text;
  out << "wrote " << opt.out_dir.string() << "/ (" << a.files.size() << (a.files.size() == 1 ? " CSV file" : " CSV files")
      << ", summary.txt, manifest.json)\n";
}

// ---------------------------------------------------------------- merge

namespace {

struct ShardIn {
  std::filesystem::path dir;
  nlohmann::json manifest;
};

// What must agree between the shards of one study: the command and its schema, every parameter
// but the shard, the inputs' contents (sizes and hashes, not their paths), the rest mesh as
// loaded (built-in and asset scenes have no input file), and the ptc build (version, commit,
// uncommitted changes). A scene given as a file is compared by its contents, not its path, so
// shards may name it differently on different machines.
nlohmann::json identity(const nlohmann::json& m) {
  nlohmann::json id;
  id["command"] = m.value("command", "");
  id["schema"] = m.value("schema", "");
  nlohmann::json p = m.value("parameters", nlohmann::json::object());
  p.erase("shard");
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& i : m.value("inputs", nlohmann::json::array()))
    inputs.push_back({{"bytes", i.value("bytes", nlohmann::json())}, {"fnv1a64", i.value("fnv1a64", nlohmann::json())}});
  if (!inputs.empty()) p.erase("scene");
  // Where the given clustering's parameters came from is a path (as typed, relative to where the
  // shard ran); its files are among the inputs, compared by their bytes: only whether they came
  // from a manifest.json is the study's.
  if (p.contains("given_parameters_from") && p["given_parameters_from"].is_string() && !inputs.empty()) {
    if (p["given_parameters_from"].get<std::string>().ends_with("manifest.json"))
      p["given_parameters_from"] = "the clustering's manifest.json";
  }
  id["parameters"] = p;
  id["inputs"] = inputs;
  id["rest_mesh_fnv1a64"] = m.value("results", nlohmann::json::object()).value("rest_mesh_fnv1a64", nlohmann::json());
  const nlohmann::json b = m.value("build", nlohmann::json::object());
  id["ptc"] = b.value("ptc", "");
  id["git_commit"] = b.value("git_commit", "");
  id["git_dirty"] = b.value("git_dirty", nlohmann::json());
  return id;
}

// Every field merge reads, present and of its type (an edited or foreign manifest is bad input,
// named, not a crash).
void check_shard_manifest(const nlohmann::json& m, const std::filesystem::path& file) {
  auto bad = [&](const std::string& what) { return InputError(file.string(), "", what, "missing or of the wrong type"); };
  if (m.is_object() && m.value("command", "") == "merge")
    throw InputError(file.string(), "", "",
                     "is the output of `ptc merge`, not a shard: merge the shards it was made from (all of them, once)");
  if (!m.is_object() || m.value("command", "") != "experiment")
    throw InputError(file.string(), "", "", "not the manifest of a `ptc experiment` run");
  const auto get = [&](const nlohmann::json& j, const char* key) -> const nlohmann::json& {
    if (!j.is_object() || !j.contains(key)) throw bad(key);
    return j.at(key);
  };
  const auto& params = get(m, "parameters");
  const auto& shard = get(params, "shard");
  for (const char* k : {"index", "count"})
    if (!get(shard, k).is_number_unsigned() || get(shard, k).get<std::uint64_t>() < 1) throw bad(std::string("parameters.shard.") + k);
  if (get(shard, "index").get<std::uint64_t>() > get(shard, "count").get<std::uint64_t>()) throw bad("parameters.shard.index");
  if (!get(params, "experiment").is_string() || !parse_experiment_kind(get(params, "experiment").get<std::string>()))
    throw bad("parameters.experiment");
  const auto& results = get(m, "results");
  const auto& files = get(results, "primary_files");
  if (!files.is_array()) throw bad("results.primary_files");
  const auto& rows = get(results, "item_rows");
  const auto& schemas = get(m, "output_schemas");
  for (const auto& f : files) {
    if (!f.is_string()) throw bad("results.primary_files");
    const std::string name = f.get<std::string>();
    if (name.find('/') != std::string::npos || name.find("..") != std::string::npos) throw bad("results.primary_files");
    if (!get(schemas, name.c_str()).is_string()) throw bad("output_schemas." + name);
    const auto& ir = get(rows, name.c_str());
    if (!ir.is_array()) throw bad("results.item_rows." + name);
    for (const auto& e : ir)
      if (!e.is_array() || e.size() != 2 || !e[0].is_number_unsigned() || !e[1].is_number_unsigned())
        throw bad("results.item_rows." + name);
  }
}

// The first difference between two identities, as "parameters.threads: 1 vs 2". The parameters
// the run derives from others (the camera and light, made from --width, --height and the scene)
// come last, so that the flag the user gave differently is the one named.
std::string first_difference(const nlohmann::json& a, const nlohmann::json& b, const std::string& path = "") {
  if (a.is_object() && b.is_object()) {
    std::set<std::string> keys;
    for (auto it = a.begin(); it != a.end(); ++it) keys.insert(it.key());
    for (auto it = b.begin(); it != b.end(); ++it) keys.insert(it.key());
    std::vector<std::string> ordered;
    const auto derived = [&](const std::string& k) { return path == "parameters" && (k == "camera" || k == "light"); };
    for (const auto& k : keys)
      if (!derived(k)) ordered.push_back(k);
    for (const auto& k : keys)
      if (derived(k)) ordered.push_back(k);
    for (const auto& k : ordered) {
      const std::string sub = path.empty() ? k : path + "." + k;
      if (!a.contains(k) || !b.contains(k)) return sub + ": only in one of them";
      if (a[k] != b[k]) return first_difference(a[k], b[k], sub);
    }
    return "";
  }
  return fmt::format("{}: {} vs {}", path, a.dump(), b.dump());
}

}  // namespace

void cmd_merge(const MergeOptions& opt, std::ostream& out) {
  if (opt.out_dir.empty()) throw UsageError("--out", "an output directory is required");
  if (opt.shards.empty()) throw UsageError("DIR", "no shard directories given");
  std::vector<ShardIn> shards;
  for (const auto& d : opt.shards) {
    refuse_overwriting_input(opt.out_dir, d);
    ShardIn s{d, read_experiment_manifest(d)};
    check_shard_manifest(s.manifest, d / "manifest.json");
    shards.push_back(std::move(s));
  }
  const nlohmann::json id0 = identity(shards[0].manifest);
  const auto& params = shards[0].manifest["parameters"];
  const std::uint32_t n = params["shard"]["count"].get<std::uint32_t>();
  std::map<std::uint32_t, std::filesystem::path> seen;
  for (const auto& s : shards) {
    const nlohmann::json id = identity(s.manifest);
    if (s.manifest["parameters"]["experiment"] != params["experiment"])  // (checked strings: check_shard_manifest)
      throw InputError(s.dir.string(), "", "",
                       fmt::format("a shard of `ptc experiment {}`, not of {} like {}: shards of different experiments "
                                   "do not merge",
                                   s.manifest["parameters"]["experiment"].get<std::string>(),
                                   params["experiment"].get<std::string>(), shards[0].dir.string()));
    if (id != id0) {
      std::string diff = first_difference(id0, id);
      // Inputs differ by bytes and hashes: name the scenes too, as the user gave them.
      auto scene_of = [](const nlohmann::json& m) {
        const auto& p = m["parameters"];
        return p.contains("scene") && p["scene"].is_string() ? p["scene"].get<std::string>() : std::string();
      };
      const std::string a = scene_of(shards[0].manifest), b = scene_of(s.manifest);
      if ((diff.rfind("inputs", 0) == 0 || diff.rfind("rest_mesh", 0) == 0) && a != b)
        diff = fmt::format("the scene {} vs {} ({})", a, b, diff);
      throw InputError(s.dir.string(), "", "",
                       fmt::format("not a shard of the same study as {}: {}", shards[0].dir.string(), diff));
    }
    const auto& sh = s.manifest["parameters"]["shard"];
    const std::uint32_t k = sh["index"].get<std::uint32_t>(), nn = sh["count"].get<std::uint32_t>();
    if (nn == 1)  // (a run without --shard records itself as shard 1/1)
      throw InputError(s.dir.string(), "", "",
                       "not one shard of a split: it records shard 1/1 (a whole run of ptc experiment, or a merge's "
                       "output); ptc merge joins the shards of one split (--shard K/N, N > 1)");
    if (nn != n)
      throw InputError(s.dir.string(), "", "", fmt::format("shard {}/{} of a split into {} (the first is split into {})", k, nn, nn, n));
    if (!seen.emplace(k, s.dir).second)
      throw InputError(s.dir.string(), "", "", fmt::format("shard {}/{} is given twice (also {})", k, n, seen[k].string()));
  }
  for (std::uint32_t k = 1; k <= n; ++k)
    if (!seen.count(k))
      throw InputError(shards[0].dir.string(), "", "",
                       fmt::format("shard {}/{} of its split is missing (got {} of {}): give every shard's directory", k,
                                   n, seen.size(), n));

  const auto kind = parse_experiment_kind(params["experiment"].get<std::string>());
  if (!kind) throw InputError((shards[0].dir / "manifest.json").string(), "", "", "unknown experiment");
  const std::vector<std::string> primaries = shards[0].manifest["results"]["primary_files"].get<std::vector<std::string>>();
  Stopwatch sw;
  struct ReadFile {
    std::filesystem::path path;
    std::uint64_t bytes;
    std::string fnv1a64;
  };
  std::vector<ReadFile> tables_read;  // the shards' tables, recorded as inputs
  std::vector<FileRows> files;
  for (const auto& name : primaries) {
    FileRows f;
    f.file = name;
    const std::string schema = shards[0].manifest["output_schemas"].value(name, "");
    const auto slash = schema.rfind('/');
    int version = 1;
    if (slash != std::string::npos) {
      const std::string v = schema.substr(slash + 1);
      if (v.empty() || v.size() > 6 || !std::all_of(v.begin(), v.end(), [](char c) { return c >= '0' && c <= '9'; }))
        throw InputError((shards[0].dir / "manifest.json").string(), "", "output_schemas." + name, "not NAME/VERSION");
      version = std::stoi(v);
    }
    f.schema = {schema.substr(0, slash), version};
    std::vector<std::pair<std::size_t, std::vector<std::vector<std::string>>>> slices;
    for (const auto& s : shards) {
      const std::filesystem::path path = s.dir / name;
      CsvText t;
      try {
        const std::string text = read_text(path, "the shard's manifest lists it");
        const std::string hash = bytes_fnv1a64(text);
        check_output_hash(s.manifest, name, hash, path);  // a shard's table as its run wrote it
        tables_read.push_back({path, text.size(), hash});
        t = parse_csv(text);
      } catch (const std::invalid_argument& e) {
        throw InputError(path.string(), "", "", e.what());
      }
      if (f.rows.header.empty()) f.rows.header = t.header;
      if (t.header != f.rows.header)
        throw InputError(path.string(), "line 1", "header", "its columns differ from " + (shards[0].dir / name).string());
      // The scene as the first shard names it: shards may name one scene file by other paths
      // (compared by its contents, identity() above), and the derived tables join rows by it.
      const std::string scene = s.manifest["parameters"].value("scene", ""), scene0 = params.value("scene", "");
      if (scene != scene0 && t.has_column("scene"))
        for (auto& row : t.rows)
          if (std::string& v = row[t.column("scene")]; v == scene) v = scene0;
      std::size_t at = 0;
      for (const auto& ir : s.manifest["results"]["item_rows"][name]) {
        const std::size_t item = ir[0].get<std::size_t>(), count = ir[1].get<std::size_t>();
        if (at + count > t.rows.size())
          throw InputError(path.string(), "", "", "fewer rows than its manifest lists (a truncated or edited file)");
        slices.emplace_back(item, std::vector<std::vector<std::string>>(t.rows.begin() + long(at),
                                                                        t.rows.begin() + long(at + count)));
        at += count;
      }
      if (at != t.rows.size())
        throw InputError(path.string(), "", "", "more rows than its manifest lists (an edited file)");
    }
    std::stable_sort(slices.begin(), slices.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (auto& [item, rows] : slices) {
      f.item_rows.emplace_back(item, rows.size());
      for (auto& r : rows) f.rows.rows.push_back(std::move(r));
    }
    files.push_back(std::move(f));
  }
  const double read_ms = sw.ms();
  sw.restart();
  const nlohmann::json rows = item_rows_json(files);
  const std::string reference = params.value("reference", "");
  const Assembled a = assemble(*kind, std::move(files), reference);
  const double assemble_ms = sw.ms();

  OutputDir dir(opt.out_dir);
  RunManifest manifest("merge", opt.argv, "ptc-merge/1");
  for (const auto& s : shards) record_input(manifest, s.dir / "manifest.json");
  for (const ReadFile& f : tables_read) record_input(manifest, f.path, f.bytes, f.fnv1a64);
  manifest.add_timing_ms("read", read_ms);
  manifest.add_timing_ms("assemble", assemble_ms);
  for (auto it = params.begin(); it != params.end(); ++it)
    if (it.key() != "shard") manifest.set_parameter(it.key(), it.value());
  nlohmann::json from = nlohmann::json::array();
  for (std::uint32_t k = 1; k <= n; ++k) from.push_back(seen[k].string());
  manifest.set_parameter("shards", from);
  manifest.set_parameter("shard", {{"index", 1}, {"count", 1}});
  manifest.set_result("primary_files", primaries);
  manifest.set_result("item_rows", rows);
  for (const char* key : {"triangles", "vertices", "rays", "rest_mesh_fnv1a64"})
    manifest.set_result(key, shards[0].manifest["results"].value(key, nlohmann::json()));
  manifest.set_result("source_builds", shards[0].manifest["build"]);
  // Where each shard ran and what it read (its own manifest holds the rest), and the items done.
  nlohmann::json runs = nlohmann::json::array();
  std::vector<std::size_t> done;
  for (std::uint32_t k = 1; k <= n; ++k)
    for (const auto& s : shards)
      if (s.dir == seen[k]) {
        const nlohmann::json& m = s.manifest;
        runs.push_back({{"dir", s.dir.string()},
                        {"shard", k},
                        {"started_utc", m.value("started_utc", nlohmann::json())},
                        {"wall_ms", m.value("wall_ms", nlohmann::json())},
                        {"inputs", m.value("inputs", nlohmann::json::array())},
                        {"machine", m.value("machine", nlohmann::json())},
                        {"build", m.value("build", nlohmann::json())}});
        for (const auto& i : m.at("results").value("items_done", nlohmann::json::array()))
          if (i.is_number_unsigned()) done.push_back(i.get<std::size_t>());
      }
  std::sort(done.begin(), done.end());
  manifest.set_result("shard_runs", runs);
  manifest.set_result("items_done", done);
  write_assembled(dir, manifest, a);
  (void)commit_with_manifest(dir, manifest);
  if (opt.json) {
    out << dump_json(summary_json(a, "ptc-experiment-summary/1"));
    return;
  }
  out << fmt::format("merged {} shards of {} {}\n", n, params["experiment"].get<std::string>(),
                     params["scene"].get<std::string>());
  out << a.text;
  out << "wrote " << opt.out_dir.string() << "/ (" << a.files.size() << (a.files.size() == 1 ? " CSV file" : " CSV files")
      << ", summary.txt, manifest.json)\n";
}

}  // namespace ptc
