// The cluster-quality metrics of one frame at the issue-12 target size (armadillo subdivided
// twice, 832k triangles, ~27k growth/Acc clusters, MaxCount = MaxSize = 50), each timed on ONE
// thread: per-cluster metrics with their spheres, SAH shares, the end-point overlap of the
// triangle and the cluster BVH, meshoptimizer's statistics and SAH overhead, and the per-ray
// counters (nodes visited, triangles tested) of primary, shadow and AO rays (512^2 camera rays,
// one AO ray per hit) on both BVHs. Target (issue 12, "Speed"): all of it under 10 s. Prints ms
// per metric and the total.
//
//   build/bin/metrics_bench [MESH] [--levels 2] [--max-count 50] [--width 512]
#include <oneapi/tbb/global_control.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "analysis/metrics/cluster_table.h"
#include "analysis/metrics/epo.h"
#include "analysis/metrics/meshlet_stats.h"
#include "analysis/metrics/sah_overhead.h"
#include "analysis/metrics/sah_share.h"
#include "bvh/trace_scene.h"
#include "render/camera.h"
#include "render/rays.h"
#include "render/view.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"

using namespace ptc;

int main(int argc, char** argv) {
  std::string path = std::string(PTC_TEST_DATA) + "/meshes/armadillo.off";
  int levels = 2;
  std::uint32_t max_count = 50;
  int width = 512;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("usage: metrics_bench [MESH] [--levels N] [--width N] [--max-count N]\n");
      return 0;
    }
    if (a == "--levels" && i + 1 < argc) levels = std::atoi(argv[++i]);
    else if (a == "--width" && i + 1 < argc) width = std::atoi(argv[++i]);
    else if (a == "--max-count" && i + 1 < argc) max_count = static_cast<std::uint32_t>(std::atoi(argv[++i]));
    else if (a[0] != '-') path = a;
    else {
      std::fprintf(stderr, "metrics_bench: unknown option %s (%s)\n", a.c_str(), "usage: metrics_bench [MESH] [--levels N] [--width N] [--max-count N]");
      return 2;
    }
  }
  try {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    Mesh mesh = read_mesh(path).mesh;
    if (levels > 0) mesh = subdivide(mesh, SubdivisionScheme::Midpoint, levels);
    ClusterConfig cc;
    cc.method = ClusterMethod::Growth;
    cc.max_count = max_count;
    cc.max_size = max_count;
    Stopwatch sw;
    const Clustering c = cluster_mesh(mesh, cc);
    const double cluster_ms = sw.lap_ms();
    const bvh::TriangleScene ts(mesh);
    bvh::SceneConfig csc = bvh::cluster_scene_defaults();
    csc.leaf_format = bvh::LeafFormatChoice::Blocks;  // (as the metrics' own trees: only the tree is read)
    const bvh::ClusterScene cs(mesh, bvh::view_of(c), csc);
    const double scenes_ms = sw.lap_ms();
    std::printf("%s, %d levels: %zu triangles, %zu clusters (clustered in %.0f ms, BVHs %.0f ms), one thread\n",
                path.c_str(), levels, mesh.triangle_count(), c.cluster_count(), cluster_ms, scenes_ms);

    double total = 0;
    auto row = [&](const char* what, double ms, const std::string& value) {
      total += ms;
      std::printf("%-34s %10.1f ms   %s\n", what, ms, value.c_str());
    };
    sw.restart();
    const auto rows = cluster_rows(mesh, c, cc);
    row("per-cluster metrics (CGAL spheres)", sw.lap_ms(), std::to_string(rows.size()) + " rows");
    const bvh::SahCostModel cost = bvh::cluster_scene_defaults().build.cost;
    const bvh::Bvh ctree = cs.cluster_tree();  // over the clusters (bvh() is over the groups with fixed group trees)
    const SahShares shares = sah_shares(ctree, cs.boxes(), cs.weights(), cost);
    row("SAH shares of the cluster BVH", sw.lap_ms(), "cost " + std::to_string(shares.cost));
    const EpoResult et = end_point_overlap(ts.bvh(), mesh.triangles(), mesh.positions(), {}, {}, cost);
    row("EPO, triangle BVH", sw.lap_ms(), "epo " + std::to_string(et.epo));
    // The cluster BVH's primitives are the scene's clusters: scene cluster i = cluster_ids()[i].
    std::vector<std::uint32_t> offsets{0}, ids;
    for (std::uint32_t k : cs.cluster_ids()) {
      const auto t = c.triangles_of(k);
      ids.insert(ids.end(), t.begin(), t.end());
      offsets.push_back(static_cast<std::uint32_t>(ids.size()));
    }
    const EpoResult ec = end_point_overlap(ctree, mesh.triangles(), mesh.positions(), offsets, ids, cost);
    row("EPO, cluster BVH", sw.lap_ms(), "epo " + std::to_string(ec.epo));
    const auto shapes = meshlet_shapes(c, mesh.triangles(), mesh.vertex_count(), max_count);
    const MeshletReport mr = meshlet_report(c, shapes);
    row("meshoptimizer statistics", sw.lap_ms(),
        "avg boundary " + std::to_string(mr.avg_boundary) + ", avg connected " + std::to_string(mr.avg_connected));
    const SahOverhead so = sah_overhead(mesh, c);
    row("meshoptimizer SAH overhead", sw.lap_ms(), "overhead " + std::to_string(so.overhead));
    // The counters: every pass traced with them on (as the drift experiment's untimed trace).
    const bvh::PinholeCamera cam = make_camera({}, mesh.referenced_bounds(), width, width);
    const bvh::RayBatch rays = camera_rays(cam, width, width);
    const Vec3 light = default_light(cam, mesh.referenced_bounds());
    bvh::TraceOptions with;
    with.threads = 1;
    with.counters = true;
    sw.restart();
    for (const bvh::TraceData* d : {&ts.data(), &cs.data()}) {
      bvh::HitBatch hits;
      const bvh::TraceTotals p = bvh::trace(*d, rays, hits, with);
      const SurfaceHits sh = surface_hits(mesh, rays, hits);
      const RayFrame frame{mesh.referenced_bounds(), d->origin};
      const TraceTarget counting = with_counters(target_of(*d));
      const PassStats shadow = trace_shadows(counting, sh, light, frame, 1).stats;
      AoConfig ao;
      ao.samples = 1;
      const PassStats occ = trace_ao(counting, sh, ao, frame, 1).stats;
      row(d == &ts.data() ? "counters, triangle BVH" : "counters, cluster BVH", sw.lap_ms(),
          "nodes/ray primary " + std::to_string(p.rays ? double(p.nodes_visited) / double(p.rays) : 0.0) + ", shadow " +
              std::to_string(shadow.rays ? double(shadow.nodes_visited) / double(shadow.rays) : 0.0) + ", ao " +
              std::to_string(occ.rays ? double(occ.nodes_visited) / double(occ.rays) : 0.0));
    }
    std::printf("%-34s %10.1f ms   (issue 12 target: < 10000 ms)\n", "total", total);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "metrics_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
