// The side-by-side benchmark of `ptc bench` as a stand-alone program (the same code:
// analysis/experiments/bench.h over the one frame loop), with the target setup as its
// default: armadillo subdivided twice (832k triangles), 1024 x 1024 primary rays, ONE thread,
// growth/Acc clusters with MaxCount = MaxSize = 32 (ptc bench's default), frames 0..7 of the
// built-in scenes' twist deformer (frame 0 out of the medians).
//
//   build/bin/peer_bench [MESH] [--levels 2] [--frames 8] [--size 1024] [--threads 1]
//                        [--max-count 32] [--deform twist|bend|wave|rigid|explode] [--cluster-fallback auto|off|X]
//                        [--fallback-refit auto|off|X] [--fallback-sah eye|directions|plain] [--csv FILE]
// --cluster-fallback: ptc bench's (auto: 64, the default; off: the cluster BVH on every frame; X: the swelling threshold).
// --fallback-refit: ptc bench's (auto: 0.2, the default; off: the fallback rebuilt every frame; X: the cost growth allowed).
// --fallback-sah: ptc bench's (directions, the default: the fallback built for the primary rays' mean directions;
// eye: for rays from the camera's eye; plain: the plain SAH).
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>

#include "analysis/experiments/bench.h"
#include "commands/args.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/static_source.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"

int main(int argc, char** argv) {
  using namespace ptc;
  std::string mesh_path = std::string(PTC_TEST_DATA) + "/meshes/armadillo.off", csv;
  int levels = 2, frames = 8;
  DeformKind kind = DeformKind::Twist;
  PeerBenchConfig cfg;
  bool refit_given = false, sah_given = false;
  for (int i = 1; i < argc; ++i) {
    auto value = [&](const char* what) -> std::string {
      if (i + 1 >= argc) {
        std::cerr << "peer_bench: " << what << " needs a value\n";
        std::exit(2);
      }
      return argv[++i];
    };
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf(
          "usage: peer_bench [MESH] [--levels 2] [--frames 8] [--size 1024] [--threads 1] [--max-count 32]\n"
          "                  [--deform twist|bend|wave|rigid|explode] [--cluster-fallback auto|off|X]\n"
          "                  [--fallback-refit auto|off|X] [--fallback-sah eye|directions|plain] [--csv FILE]\n"
          "(ptc bench's code with the issue's target set-up; the flags as ptc bench's: docs/tracing.md)\n");
      return 0;
    }
    try {
      if (a == "--levels") levels = std::stoi(value("--levels"));
      else if (a == "--frames") frames = std::stoi(value("--frames"));
      else if (a == "--size") cfg.width = cfg.height = std::stoi(value("--size"));
      else if (a == "--threads") cfg.threads = static_cast<unsigned>(std::stoi(value("--threads")));
      else if (a == "--max-count") cfg.max_count = static_cast<std::uint32_t>(std::stoul(value("--max-count")));
      else if (a == "--csv") csv = value("--csv");
      else if (a == "--cluster-fallback") {
        const std::optional<double> x = parse_cluster_fallback(value("--cluster-fallback"));
        if (!x) throw std::invalid_argument("--cluster-fallback: auto, off or a number above 1");
        cfg.cluster_fallback = *x;
      } else if (a == "--fallback-refit") {
        const std::optional<double> x = parse_fallback_refit(value("--fallback-refit"));
        if (!x) throw std::invalid_argument("--fallback-refit: auto, off or a number above 0");
        cfg.fallback_refit = *x;
        refit_given = true;
      } else if (a == "--fallback-sah") {
        const std::optional<bvh::FallbackSah> x = bvh::parse_fallback_sah(value("--fallback-sah"));
        if (!x) throw std::invalid_argument("--fallback-sah: eye, directions or plain");
        cfg.fallback_sah = *x;
        sah_given = true;
      }
      else if (a == "--deform") {
        const auto d = parse_deform_kind(value("--deform"));
        if (!d) throw std::invalid_argument("--deform: twist, bend, wave, rigid or explode");
        kind = *d;
      } else if (a[0] != '-') mesh_path = a;
      else throw std::invalid_argument("unknown option " + a);
    } catch (const std::exception& e) {
      std::cerr << "peer_bench: " << e.what() << "\n";
      return 2;
    }
  }
  for (const auto& [given, flag] : {std::pair{refit_given, "--fallback-refit"}, std::pair{sah_given, "--fallback-sah"}})
    if (given && !(cfg.cluster_fallback > 0)) {
      std::cerr << "peer_bench: " << flag << ": needs the triangle fallback (--cluster-fallback auto or X)\n";
      return 2;
    }
  if (levels < 0 || levels > 6 || cfg.threads < 1 || frames < 1) {
    std::cerr << "peer_bench: --levels 0..6, --threads >= 1, --frames >= 1\n";
    return 2;
  }
  try {
    Mesh mesh = read_mesh(mesh_path).mesh;
    if (levels > 0) mesh = subdivide(mesh, SubdivisionScheme::Midpoint, levels);
    std::vector<ScenePart> parts;
    parts.push_back({"mesh", make_deformer(std::move(mesh), deform_preset(kind))});
    Scene scene("peer_bench", std::move(parts), std::nullopt, std::nullopt, FrameRange{0, frames - 1});
    cfg.frames = {0, frames - 1};
    const PeerBenchResult r = run_peer_bench(scene, std::nullopt, cfg);
    std::printf("%s, %d midpoint subdivision levels: %zu triangles; %zu clusters (%s, clustered in %.0f ms, cluster "
                "scene setup %.1f ms); %d frames of the %s deformer; %u thread(s); cluster leaves %s\n",
                mesh_path.c_str(), levels, r.triangles, r.clusters, r.clustering.c_str(), r.cluster_ms,
                r.cluster_scene_setup_ms, frames, std::string(to_string(kind)).c_str(), cfg.threads,
                bvh::to_string(cfg.cluster_leaf));
    std::fputs(bench_text(r).c_str(), stdout);
    if (!csv.empty()) std::ofstream(csv) << bench_table(r).csv.str();
  } catch (const std::exception& e) {
    std::cerr << "peer_bench: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
