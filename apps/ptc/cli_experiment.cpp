// `ptc experiment KIND SCENE [clustering flags] [--frames A:B] ... --out DIR` and
// `ptc merge DIR... --out DIR` (commands/experiment.h).
#include <iostream>

#include "commands/experiment.h"
#include "apps/ptc/cli.h"

namespace ptc::cli {

namespace {
struct ExperimentArgs {
  ExperimentCommandOptions opt;
  SceneArg scene;
  CameraArgs camera;
  ClusterFlags flags;
  std::string frames, deform, max_counts, configs, reference, clusterings, shard, cluster_leaf = "linear",
      vertex_order = "clusters";
  GroupTreesArg group_trees;
  int ao_samples = 1;
  std::size_t reference_rays = 512;
  CLI::App* app = nullptr;
};
}  // namespace

void register_experiment(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<ExperimentArgs>();
  auto* c = ctx.add(
      app, "experiment",
      "the paper's experiments over a scene's frames: sweep (Figure 6), compare (Figure 7), drift, accuracy",
      [a, &ctx] {
        auto& o = a->opt;
        auto given = [&](const char* flag) { return a->app->count(flag) > 0; };
        if (given("--frames")) o.frames = a->frames;
        if (given("--deform")) o.deform = a->deform;
        if (given("--max-counts")) o.max_counts = a->max_counts;
        if (given("--configs")) o.configs = a->configs;
        if (given("--reference")) o.reference = a->reference;
        if (given("--clusterings")) o.clusterings = a->clusterings;
        if (given("--shard")) o.shard = a->shard;
        if (given("--ao-samples")) o.ao_samples = a->ao_samples;
        if (given("--reference-rays")) o.reference_rays = a->reference_rays;
        o.method_given = given("--method") || given("--objective");
        for (const char* f : {"--cluster-leaf", "--cluster-groups", "--group-trees", "--vertex-order"})
          if (given(f)) o.structure_flags.push_back(f);
        a->flags.apply(o.cluster, o.given);
        o.cluster_leaf = *bvh::parse_cluster_leaf(a->cluster_leaf);
        o.vertex_order = *bvh::parse_vertex_order(a->vertex_order);
        if (given("--cluster-groups")) o.min_cluster_groups = 0;  // (given: exact)
        o.group_trees = a->group_trees.get(o.cluster_group_size > 1, "the two-level build (--cluster-groups N, N > 1)");
        o.threads = static_cast<unsigned>(ctx.threads);
        o.input = a->scene.input;
        a->scene.apply(o.scene_options);
        o.camera = a->camera.spec();
        o.light = a->camera.light_position();
        o.argv = ctx.args;
        cmd_experiment(o, std::cout);
      });
  a->app = c;
  c->add_option("KIND", a->opt.kind, "sweep, compare, drift or accuracy")
      ->required()
      ->check(CLI::IsMember({"sweep", "compare", "drift", "accuracy"}));
  a->scene.add_to(c);
  c->add_option("--frames", a->frames, "scene frames A:B (default: an animated scene's range, else 0:4 of --deform)");
  c->add_flag("--extend-frames", a->opt.extend_frames, "allow frames outside the scene's listed range");
  c->add_option("--deform", a->deform, "stand-in motion of a static scene: twist (default), bend, wave, rigid, explode or none")
      ->check(CLI::IsMember({"twist", "bend", "wave", "rigid", "explode", "none"}));
  c->add_option("--clusters", a->opt.clusters,
                "the method's clustering from DIR/triangles.csv (ptc cluster --out DIR): compare's and drift's "
                "configuration 'given', accuracy's clusters");
  a->flags.add_to(c, a->opt.cluster, /*with_method=*/true);
  c->add_option("--max-counts", a->max_counts, "sweep: MaxCount = MaxSize values, comma-separated (default 0,10,50,100)");
  c->add_option("--configs", a->configs,
                "compare: configurations, comma-separated (default: acc_growth, acc_contraction (or given), standard, "
                "naive, gwh01, meshopt, sah_split, embree_low, embree_refit, embree_medium)");
  c->add_option("--reference", a->reference, "compare: the configuration perf_factor divides by (default: given, else "
                                             "acc_contraction, else the first of --configs)");
  c->add_option("--clusterings", a->clusterings,
                "drift: clusterings, comma-separated (default: acc_growth, acc_contraction (or given), naive, gwh01, "
                "meshopt, sah_split); the triangle BVH is always measured beside them");
  c->add_option("--ao-samples", a->ao_samples, "drift: AO rays per primary hit for the ray counters (0: no AO pass)")
      ->check(whole_in(0, 64))
      ->capture_default_str();
  c->add_option("--reference-rays", a->reference_rays,
                "accuracy: primary rays checked against the double-precision brute force")
      ->check(whole_in(1, 1 << 20))
      ->capture_default_str();
  c->add_option("--width", a->opt.width, "primary rays per image row")->check(whole_in(1, kMaxImageSide))->capture_default_str();
  c->add_option("--height", a->opt.height, "image rows")->check(whole_in(1, kMaxImageSide))->capture_default_str();
  a->camera.add_to(c, /*with_light=*/true);
  c->add_option("--cluster-leaf", a->cluster_leaf, "cluster leaves: linear (the paper's, default) or block-tree")
      ->check(enum_validator("cluster leaf", bvh::parse_cluster_leaf))
      ->capture_default_str();
  c->add_option("--cluster-groups", a->opt.cluster_group_size,
                "two-level cluster BVH build over groups of at most N clusters; 0 = the plain build; unset: N = 32, "
                "but at least 1024 groups (smaller groups under 32,768 clusters, the plain build under 2,048)")
      ->check(whole_in(0, 1 << 20))
      ->capture_default_str();
  a->group_trees.add_to(c);
  c->add_option("--vertex-order", a->vertex_order, "clusters (renumber once per clustering) or input")
      ->check(enum_validator("vertex order", bvh::parse_vertex_order))
      ->capture_default_str();
  c->add_option("--shard", a->shard,
                "run shard K of N (the work items i with i mod N = K - 1); join the shards with ptc merge");
  add_threads_option(c, ctx.threads);
  c->add_flag("--quiet", a->opt.quiet, "no progress bar");
  c->add_option("--out", a->opt.out_dir, "output directory: the experiment's CSV files, summary.txt, manifest.json")
      ->required();
  c->add_flag("--json", a->opt.json, "print the summary tables as JSON");
}

void register_merge(CLI::App& app, Context& ctx) {
  auto o = std::make_shared<MergeOptions>();
  auto* c = ctx.add(app, "merge", "join the shards of one experiment (ptc experiment --shard K/N) into one output",
                    [o, &ctx] {
                      o->argv = ctx.args;
                      cmd_merge(*o, std::cout);
                    });
  c->add_option("DIR", o->shards, "the shards' output directories")->required();
  c->add_option("--out", o->out_dir, "output directory: the files one run of the whole experiment writes")->required();
  c->add_flag("--json", o->json, "print the summary tables as JSON");
}

}  // namespace ptc::cli
