#include "toolkit/clustering/regions.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>

#include "toolkit/clustering/objectives.h"
#include "toolkit/core/cancel.h"
#include "toolkit/geometry/morton.h"

namespace ptc {

std::vector<std::uint32_t> cluster_regions(const Mesh& mesh, std::uint32_t regions) {
  const std::size_t T = mesh.triangle_count();
  std::vector<std::uint32_t> region(T, 0);
  const std::uint64_t n = std::min<std::uint64_t>(std::max<std::uint32_t>(regions, 1), std::max<std::size_t>(T, 1));
  if (n <= 1) return region;
  const std::vector<std::uint32_t> order = morton_order(mesh.positions(), mesh.triangles());
  for (std::size_t rank = 0; rank < T; ++rank) region[order[rank]] = static_cast<std::uint32_t>(rank * n / T);
  return region;
}

namespace {

// One region's triangles (ascending ids) as a mesh of its own: the vertices they use, ascending.
// `scratch` (the whole mesh's vertex count, one per thread): a stamp, then the local index, of
// every vertex the region uses; entries of other vertices are never read.
Mesh region_mesh(const Mesh& mesh, const std::vector<std::uint32_t>& tris, std::uint32_t stamp,
                 std::vector<std::uint32_t>& seen, std::vector<std::uint32_t>& local) {
  std::vector<std::uint32_t> verts;
  verts.reserve(tris.size() / 2 + 16);
  for (std::uint32_t t : tris)
    for (std::uint32_t v : mesh.triangles()[t])
      if (seen[v] != stamp) seen[v] = stamp, verts.push_back(v);
  std::sort(verts.begin(), verts.end());
  std::vector<Vec3> pos(verts.size());
  for (std::size_t i = 0; i < verts.size(); ++i) {
    local[verts[i]] = static_cast<std::uint32_t>(i);
    pos[i] = mesh.positions()[verts[i]];
  }
  std::vector<Tri> sub(tris.size());
  for (std::size_t i = 0; i < tris.size(); ++i) {
    const Tri& t = mesh.triangles()[tris[i]];
    sub[i] = {local[t[0]], local[t[1]], local[t[2]]};
  }
  return Mesh(std::move(sub), std::move(pos));
}

}  // namespace

Clustering cluster_in_regions(const Mesh& mesh, const ClusterConfig& config, double avg_sa,
                              const ProgressFn& progress) {
  ClusterConfig as_regions = config;  // check()'s rules of regions, also for regions <= 1
  as_regions.regions = std::max<std::uint32_t>(config.regions, 2);
  if (const std::optional<ConfigProblem> p = check(as_regions))
    throw std::invalid_argument("cluster_in_regions: " + p->reason);
  const std::size_t T = mesh.triangle_count();
  if (T == 0) {
    if (progress) progress(1.0);
    return Clustering{};
  }

  const std::vector<std::uint32_t> region = cluster_regions(mesh, config.regions);
  const std::uint32_t R = *std::max_element(region.begin(), region.end()) + 1;
  std::vector<std::vector<std::uint32_t>> members(R);
  for (std::uint32_t t = 0; t < T; ++t) members[region[t]].push_back(t);

  std::vector<std::vector<std::uint32_t>> labels(R);  // per region: its triangles' cluster labels (< its size)
  // Progress: every region adds its triangles done to one total; only the caller's thread calls
  // `progress` (a progress bar is not for TBB tasks, and may throw Interrupted), and every
  // region's report polls the stop request, so an interrupt ends the running regions promptly.
  std::mutex progress_lock;
  std::vector<double> done(R, 0.0);  // triangles of each region taken so far
  double total_done = 0.0;
  const std::thread::id caller = std::this_thread::get_id();
  auto report = [&](std::uint32_t r, double fraction) {
    throw_if_cancelled();
    double total;
    {
      const std::lock_guard<std::mutex> lock(progress_lock);
      const double now = fraction * static_cast<double>(members[r].size());
      if (now > done[r]) total_done += now - done[r], done[r] = now;
      total = total_done;
    }
    if (progress && std::this_thread::get_id() == caller) progress(std::min(1.0, total / static_cast<double>(T)));
  };

  struct Scratch {
    std::vector<std::uint32_t> seen, local;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  // Lean tables by the whole mesh's size, as one run's (several regions' tables are alive at once).
  const bool lean = detail::lean_tables_for(config.method, mesh.triangle_count());
  tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, R, 1), [&](const tbb::blocked_range<std::uint32_t>& range) {
    for (std::uint32_t r = range.begin(); r < range.end(); ++r) {
      if (tbb::is_current_task_group_canceling()) return;  // another region threw
      // Isolated: while this region waits in a nested parallel loop (the Morton sort of its
      // start rule), its thread takes no other region, so a thread holds one region's state.
      tbb::this_task_arena::isolate([&] {
        Scratch& sc = scratch.local();
        if (sc.seen.empty()) sc.seen.assign(mesh.vertex_count(), 0), sc.local.resize(mesh.vertex_count());
        const Mesh sub = region_mesh(mesh, members[r], r + 1, sc.seen, sc.local);
        const ClusterTables tables =
            ClusterTables::build(sub, /*with_edges=*/false, false, lean);
        const ProgressFn region_progress = [&, r](double f) { report(r, f); };
        labels[r] = detail::run_objective(tables, config, avg_sa, region_progress).labels;
      });
    }
  });
  if (progress) progress(1.0);

  // Region by region, each region's clusters after the ones before (unique labels; the
  // clustering renames them densely by their smallest triangle).
  std::vector<std::uint32_t> global(T);
  std::uint32_t offset = 0;
  for (std::uint32_t r = 0; r < R; ++r) {
    std::uint32_t count = 0;
    for (std::size_t i = 0; i < members[r].size(); ++i) {
      global[members[r][i]] = offset + labels[r][i];
      count = std::max(count, labels[r][i] + 1);
    }
    offset += count;
  }
  return clustering_from_labels(global, mesh.triangles());
}

}  // namespace ptc
