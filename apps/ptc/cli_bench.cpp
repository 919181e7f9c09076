// `ptc bench MESH [--clusters DIR | --max-count N] [--frames F] [--width W --height H]
// [--threads T] [--deform twist|wave|none] --out DIR` (analysis/peer_bench.h).
#include <iostream>

#include "analysis/trace_command.h"
#include "apps/ptc/cli.h"

namespace ptc::cli {

namespace {
struct BenchArgs {
  BenchCommandOptions opt;
  std::string deform = "twist", cluster_leaf = "block-tree";
  int threads = 1;
};
}  // namespace

void register_bench(CLI::App& app, Context& ctx) {
  auto a = std::make_shared<BenchArgs>();
  auto& cfg = a->opt.config;
  auto* c = ctx.add(app, "bench",
                    "our triangle and cluster BVHs beside Embree MEDIUM/LOW/REFIT over animated frames, same rays",
                    [a, &ctx] {
                      auto& o = a->opt;
                      o.config.deformation = *parse_deformation(a->deform);
                      o.config.cluster_leaf =
                          a->cluster_leaf == "linear" ? bvh::ClusterLeaf::Linear : bvh::ClusterLeaf::BlockTree;
                      o.config.threads = static_cast<unsigned>(a->threads);
                      o.argv = ctx.args;
                      cmd_bench(o, std::cout);
                    });
  c->add_option("MESH", a->opt.input, "mesh file (.off .obj .ply .stl)")->required();
  auto* cl = c->add_option("--clusters", a->opt.clusters, "use the clustering in DIR/triangles.csv (ptc cluster --out DIR)");
  c->add_option("--max-count", cfg.max_count, "otherwise: growth/Acc clustering with MaxCount = MaxSize = N")
      ->check(CLI::Range(1u, 1u << 20))
      ->excludes(cl)
      ->capture_default_str();
  c->add_option("--frames", cfg.frames, "animated frames (frame 0 is left out of the medians)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  c->add_option("--width", cfg.width, "primary rays per image row")->check(CLI::Range(1, 16384))->capture_default_str();
  c->add_option("--height", cfg.height, "image rows")->check(CLI::Range(1, 16384))->capture_default_str();
  c->add_option("--threads", a->threads, "threads of our builder and tracer and of Embree's device (default 1)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  c->add_option("--deform", a->deform, "per-frame deformation: twist, wave or none")
      ->check(CLI::IsMember({"twist", "wave", "none"}))
      ->capture_default_str();
  c->add_option("--cluster-leaf", a->cluster_leaf, "cluster leaves: block-tree or linear (the paper's)")
      ->check(CLI::IsMember({"block-tree", "linear"}))
      ->capture_default_str();
  c->add_option("--out", a->opt.out_dir, "output directory: bench.csv, summary.csv, manifest.json")->required();
}

}  // namespace ptc::cli
