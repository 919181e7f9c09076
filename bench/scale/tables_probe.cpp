// The clustering's set-up stages alone at one thread (docs/scale.md, growth at 13.3M): the sorted
// sides of the neighbour lists (SortedSides::build), the tables with the sums (ClusterTables::
// build, which builds the sides again inside), and the Morton order (morton_order) from the
// tables' box, each timed twice, wall clock. A probe, not part of the build; it links the
// toolkit library of a `./run.sh build`:
//     g++ -std=c++20 -O2 -march=x86-64-v3 -I. -Ibuild -I/usr/include/eigen3 bench/scale/tables_probe.cpp \
//         build/toolkit/libptc_toolkit.a -ltbb -lfmt -lgmp -lmpfr -lmeshoptimizer -lboost_graph -o /tmp/tables_probe
//     GLIBC_TUNABLES=glibc.malloc.hugetlb=1 taskset -c 1 /tmp/tables_probe a13.ply
// (GLIBC_TUNABLES as `ptc` sets it for itself; a13.ply from `ptc subdivide armadillo.off --levels 4`.)
// To compare two versions of the code, build the probe against each checkout's library and
// alternate the runs.
#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>

#include "toolkit/clustering/objectives.h"
#include "toolkit/geometry/morton.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/topology.h"

namespace {
double now_s() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: tables_probe MESH\n");
    return 2;
  }
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const ptc::LoadedMesh lm = ptc::read_mesh(argv[1]);
  std::printf("%zu triangles\n", lm.mesh.triangle_count());
  for (int rep = 1; rep <= 2; ++rep) {
    double t = now_s();
    {
      const ptc::SortedSides s = ptc::SortedSides::build(lm.mesh.triangles(), lm.mesh.vertex_count());
      std::printf("run %d: sorted sides %.3f s (%zu sides)\n", rep, now_s() - t, s.sides.size());
    }
    t = now_s();
    const ptc::ClusterTables tb = ptc::ClusterTables::build(lm.mesh, /*with_edges=*/false, /*with_sums=*/true);
    std::printf("run %d: tables with sums %.3f s\n", rep, now_s() - t);
    t = now_s();
    const auto order = ptc::morton_order(tb.positions, tb.triangles, ptc::MortonGrid::Cube, &tb.centroid_bounds);
    std::printf("run %d: morton order %.3f s (%zu ids)\n", rep, now_s() - t, order.size());
  }
  return 0;
}
