// Positions per second of every animation source at ~832k triangles (issue 6, "Performance":
// producing a frame must not dominate the per-frame loop), on one thread and on all threads.
//
// Sources: the five deformers on armadillo Loop-subdivided twice (832k triangles; explode on
// its 2.5M-vertex soup), the twist of the 52k armadillo carried through two midpoint levels
// (SubdividedAnimation), the PBD cloth at 646 x 646 (832k triangles; one frame = 8 substeps x
// 4 iterations), and the asset scenes scaled up by subdivision when assimp-testmodels are
// installed. The peer in the same run: copying the rest positions (StaticSource), the floor
// any source pays to deliver a frame.
//
// usage: anim_bench [data_dir]   (default: PTC_TEST_DATA, the build tree's data/)
// Prints one row per source: median ms per frame over R frames, vertex positions per second,
// the speed-up all/one thread and the time relative to the copy.
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/info.h>

#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "toolkit/anim/cloth.h"
#include "toolkit/anim/deformers.h"
#include "toolkit/anim/load_animation.h"
#include "toolkit/anim/static_source.h"
#include "toolkit/anim/subdivided.h"
#include "toolkit/core/error.h"
#include "toolkit/core/stats.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/subdivision.h"

using namespace ptc;

namespace {

// Median ms of one positions() call over `frames` consecutive frames (after one warm-up frame).
double time_frames(Animation& a, int frames, double start) {
  std::vector<Vec3> out(a.rest().vertex_count());
  a.positions(start, out);  // warm-up (and for the cloth: frame `start` simulated)
  std::vector<double> ms;
  for (int k = 1; k <= frames; ++k) {
    const Stopwatch sw;
    a.positions(start + k, out);
    ms.push_back(sw.ms());
  }
  return median(ms);
}

struct Row {
  std::string name;
  std::size_t tris, verts;
  double ms1, msN;
};

}  // namespace

int run(const std::filesystem::path& data);

int main(int argc, char** argv) {
  std::filesystem::path data = PTC_TEST_DATA;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::printf("usage: anim_bench [DATA_DIR]   (DATA_DIR: holds meshes/armadillo.off; default %s)\n", PTC_TEST_DATA);
      return 0;
    }
    if (a.empty() || a[0] == '-' || i > 1) {
      std::fprintf(stderr, "anim_bench: %s: %s (usage: anim_bench [DATA_DIR])\n", a.c_str(),
                   i > 1 ? "one data directory at most" : "unknown option");
      return 2;
    }
    data = a;
  }
  try {
    return run(data);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "anim_bench: %s\n", e.what());
    return 1;
  }
}

int run(const std::filesystem::path& data) {
  const int all = static_cast<int>(tbb::info::default_concurrency());
  std::printf("anim_bench: data %s, %d threads available\n", data.c_str(), all);

  std::vector<std::pair<std::string, std::function<AnimationPtr()>>> sources;
  const Mesh arm = read_mesh(data / "meshes/armadillo.off").mesh;
  const Mesh arm832 = subdivide(arm, SubdivisionScheme::Loop, 2);
  sources.push_back({"copy (static, peer)", [&] { return AnimationPtr(std::make_unique<StaticSource>(arm832)); }});
  for (DeformKind k : {DeformKind::Twist, DeformKind::Bend, DeformKind::Wave, DeformKind::Rigid, DeformKind::Explode}) {
    DeformParams p;
    p.kind = k;
    p.direction = 2;
    sources.push_back({"deform " + std::string(to_string(k)), [&, p] { return make_deformer(arm832, p); }});
  }
  sources.push_back({"twist(52k) carried x2 midpoint", [&] {
                       DeformParams p;
                       return AnimationPtr(std::make_unique<SubdividedAnimation>(make_deformer(arm, p),
                                                                                 SubdivisionScheme::Midpoint, 2));
                     }});
  sources.push_back({"cloth 646x646 (1 frame)", [] {
                       ClothParams c;
                       c.resolution = 646;
                       return AnimationPtr(std::make_unique<ClothSimulation>(c));
                     }});
  // Real keyframed / skinned assets (toolkit/anim/load_animation.h), scaled up by subdivision.
  const std::pair<const char*, int> assets[] = {{"MD2/faerie.md2", 5}, {"X/BCN_Epileptic.X", 4}};
  for (const auto& [file, levels] : assets) {
    const std::filesystem::path path = std::filesystem::path("/usr/share/assimp/models") / file;
    sources.push_back({std::string(file) + " x" + std::to_string(levels) + " midpoint", [path, levels = levels] {
                         if (!std::filesystem::exists(path)) throw InputError(path.string(), "", "", "missing");
                         return AnimationPtr(std::make_unique<SubdividedAnimation>(load_animation(path.string()),
                                                                                   SubdivisionScheme::Midpoint, levels));
                       }});
  }

  std::vector<Row> rows;
  for (auto& [name, make] : sources) {
    AnimationPtr a;
    try {
      a = make();
    } catch (const InputError& e) {
      std::printf("%-32s skipped: %s\n", name.c_str(), e.what());
      continue;
    }
    const bool cloth = name.rfind("cloth", 0) == 0;
    const int frames = cloth ? 3 : 9;
    Row r{name, a->rest().triangle_count(), a->rest().vertex_count(), 0, 0};
    {
      tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      r.ms1 = time_frames(*a, frames, 10);
    }
    r.msN = time_frames(*a, frames, cloth ? 0 : 20);  // the cloth restarts (frame 0) and steps again
    rows.push_back(r);
  }
  const double copy1 = rows.empty() ? 1 : rows[0].ms1, copyN = rows.empty() ? 1 : rows[0].msN;
  std::printf("\n%-32s %9s %9s %10s %10s %12s %12s %8s %9s %9s\n", "source", "tris", "verts", "ms(1t)", "ms(all)",
              "Mpos/s(1t)", "Mpos/s(all)", "speedup", "xcopy(1t)", "xcopy(all)");
  for (const Row& r : rows)
    std::printf("%-32s %9zu %9zu %10.2f %10.2f %12.1f %12.1f %8.2f %9.1f %9.1f\n", r.name.c_str(), r.tris, r.verts, r.ms1,
                r.msN, double(r.verts) / r.ms1 / 1e3, double(r.verts) / r.msN / 1e3, r.ms1 / r.msN, r.ms1 / copy1,
                r.msN / copyN);
  std::printf("\nmedian over 9 frames (cloth: 3 frames); Mpos/s = million vertex positions per second\n");
  return 0;
}
