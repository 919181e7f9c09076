// Positions per second of the file-based animation sources (toolkit/anim: frame sequences, MD2,
// MD3, skinned assets), each against a peer measured in the same run: a plain copy of the same
// number of positions (std::copy of a Vec3 array, the floor of any source that writes every
// vertex per frame). Times are medians over repetitions; each repetition runs enough frames to
// last >= 20 ms. Frame times are fractional (k + 0.37) so keyframed sources interpolate.
//
// Sizes: MD2 / MD3 / BCN_Epileptic are measured at their NATIVE sizes (654 and 5,126 triangles);
// scale-up to ~832k triangles by subdivision is another module's (toolkit/anim/subdivided.h). At
// ~832k triangles this program measures what it can build honestly from its own sources:
//   keyframes_832k      KeyframeAnimation (the MD2/MD3/eager-sequence engine) on a 645x645 grid
//                       (832,050 triangles), 8 stored frames
//   sequence_eager_832k the same frames written as binary PLY and read back by FrameSequence (Eager)
//   sequence_lazy_832k  FrameSequence (Lazy) at integer times cycling 0,1,2: every call reads a file
//   skinned_bcn_tiled   BCN_Epileptic's real rig (54 bones, its weights) with the mesh tiled until
//                       >= 832k triangles (unwelded copies), i.e. LBS cost at that size
//
//   build/bin/anim_sources_bench [--reps N] [--threads N] [--quick]
//   (--threads 0 = all cores (default); --quick = fewer repetitions, smaller lazy test)
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

#include "toolkit/anim/assimp_source.h"
#include "toolkit/anim/frame_sequence.h"
#include "toolkit/anim/md3.h"
#include "toolkit/anim/skinning.h"
#include "toolkit/core/stats.h"
#include "toolkit/core/stopwatch.h"
#include "toolkit/io/mesh_io.h"

namespace {

namespace fs = std::filesystem;
using ptc::Vec3;

const std::string kModels = "/usr/share/assimp/models";

// Median seconds per call of f(i) over `reps` repetitions of a batch lasting >= 20 ms.
double time_per_call(const std::function<void(std::size_t)>& f, int reps) {
  std::size_t batch = 1;
  for (;;) {  // calibrate
    const ptc::Stopwatch sw;
    for (std::size_t i = 0; i < batch; ++i) f(i);
    if (sw.ms() >= 20.0 || batch >= (1u << 20)) break;
    batch *= 2;
  }
  std::vector<double> per;
  std::size_t call = 0;
  for (int r = 0; r < reps; ++r) {
    const ptc::Stopwatch sw;
    for (std::size_t i = 0; i < batch; ++i) f(call++);
    per.push_back(sw.ms() * 1e-3 / static_cast<double>(batch));
  }
  return ptc::median(per);
}

struct Row {
  std::string source;
  std::size_t triangles = 0, vertices = 0;
  double s_per_frame = 0, copy_s = 0;
};

Row measure(const std::string& name, ptc::Animation& a, int reps, const std::function<double(std::size_t)>& time_of) {
  const std::size_t nv = a.rest().vertex_count();
  std::vector<Vec3> out(nv), src(a.rest().positions().begin(), a.rest().positions().end());
  Row r{name, a.rest().triangle_count(), nv, 0, 0};
  a.positions(time_of(0), out);  // warm-up
  for (const Vec3& p : out)
    if (!p.allFinite()) throw std::runtime_error(name + ": non-finite position");
  r.s_per_frame = time_per_call([&](std::size_t i) { a.positions(time_of(i), out); }, reps);
  r.copy_s = time_per_call(
      [&](std::size_t i) {
        std::copy(src.begin(), src.end(), out.begin());
        out[i % nv].x() += 1e-300;  // keep the copy observable
      },
      reps);
  return r;
}

ptc::Mesh grid_frame(int n, double t) {
  std::vector<Vec3> p;
  std::vector<ptc::Tri> tris;
  p.reserve(static_cast<std::size_t>((n + 1) * (n + 1)));
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      p.emplace_back(i, j, 5.0 * std::sin(0.05 * i + 0.3 * t) * std::cos(0.04 * j - 0.2 * t));
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      tris.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      tris.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return ptc::Mesh(std::move(tris), std::move(p));
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 11;
  unsigned threads = 0;
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--reps" && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
    else if (a == "--threads" && i + 1 < argc) threads = static_cast<unsigned>(std::atoi(argv[++i]));
    else if (a == "--quick") quick = true;
    else if (a == "--help" || a == "-h") {
      std::cout << "usage: anim_sources_bench [--reps N] [--threads N] [--quick]\n";
      return 0;
    } else {
      std::cerr << "usage: anim_sources_bench [--reps N] [--threads N] [--quick]\n";
      return 2;
    }
  }
  if (quick) reps = 3;
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads ? threads : hw);
  const fs::path tmp = fs::temp_directory_path() / ("ptc_anim_bench_" + std::to_string(::getpid()));
  std::vector<Row> rows;
  try {
    fs::create_directories(tmp);
    auto frac = [](std::size_t count) {
      return [count](std::size_t i) { return static_cast<double>(i % (count - 1)) + 0.37; };
    };
    // Native sizes.
    auto md2 = ptc::load_md2(kModels + "/MD2/faerie.md2");
    rows.push_back(measure("md2_faerie", *md2, reps, frac(md2->frame_count())));
    {
      // MD3: faerie's frames written as MD3 (Debian ships no MD3 model).
      auto* kf = dynamic_cast<ptc::KeyframeAnimation*>(md2.get());
      ptc::Md3SurfaceData sd;
      sd.name = "faerie";
      sd.triangles.assign(kf->rest().triangles().begin(), kf->rest().triangles().end());
      for (std::size_t k = 0; k < kf->frame_count(); ++k)
        sd.frames.emplace_back(kf->frame(k).begin(), kf->frame(k).end());
      ptc::write_md3(tmp / "faerie.md3", {sd});
      auto md3 = ptc::load_md3(tmp / "faerie.md3");
      rows.push_back(measure("md3_faerie", *md3, reps, frac(md3->frame_count())));
    }
    auto bcn = ptc::load_assimp_animation(kModels + "/X/BCN_Epileptic.X");
    rows.push_back(measure("skinned_bcn", *bcn, reps, frac(bcn->frame_count())));

    // ~832k triangles.
    constexpr int kGrid = 645;  // 2 * 645^2 = 832,050 triangles
    {
      std::vector<std::vector<Vec3>> frames;
      std::vector<ptc::Tri> tris;
      for (int k = 0; k < 8; ++k) {
        ptc::Mesh m = grid_frame(kGrid, k);
        if (k == 0) tris.assign(m.triangles().begin(), m.triangles().end());
        if (k < 3) ptc::write_mesh(tmp / ("grid_" + std::to_string(k) + ".ply"), m);
        frames.emplace_back(m.positions().begin(), m.positions().end());
      }
      ptc::KeyframeAnimation kf(std::move(tris), std::move(frames), 30.0, "grid");
      rows.push_back(measure("keyframes_832k", kf, reps, frac(8)));
    }
    {
      ptc::FrameSequenceOptions eager;
      eager.loading = ptc::FrameLoading::Eager;
      ptc::FrameSequence seq((tmp / "grid_*.ply").string(), eager);
      rows.push_back(measure("sequence_eager_832k", seq, reps, frac(3)));
      ptc::FrameSequence lazy((tmp / "grid_*.ply").string());
      rows.push_back(measure("sequence_lazy_832k", lazy, quick ? 1 : std::min(reps, 5),
                             [](std::size_t i) { return static_cast<double>(i % 3); }));
    }
    {
      auto* sk = dynamic_cast<ptc::SkinnedAnimation*>(bcn.get());
      const ptc::SkinRig& base = sk->rig();
      ptc::SkinRig rig = base;
      const std::size_t copies = (832000 + base.triangles.size() - 1) / base.triangles.size();
      const double width = 2.0 * bcn->rest().bounds().extent().norm();
      const auto nv = static_cast<std::uint32_t>(base.bind_positions.size());
      for (std::size_t c = 1; c < copies; ++c) {
        // Copies side by side in bind space; the same bones move them (so they overlap in
        // motion, which does not matter for the cost).
        for (const Vec3& p : base.bind_positions) rig.bind_positions.push_back(p + Vec3(width * static_cast<double>(c), 0, 0));
        for (std::size_t v = 0; v < nv; ++v) {
          for (auto i = base.influence_begin[v]; i < base.influence_begin[v + 1]; ++i) rig.influences.push_back(base.influences[i]);
          rig.influence_begin.push_back(static_cast<std::uint32_t>(rig.influences.size()));
        }
        for (const ptc::Tri& t : base.triangles)
          rig.triangles.push_back({t[0] + nv * static_cast<std::uint32_t>(c), t[1] + nv * static_cast<std::uint32_t>(c),
                                   t[2] + nv * static_cast<std::uint32_t>(c)});
      }
      ptc::SkinOptions o;
      o.weld = false;
      ptc::SkinnedAnimation tiled(std::move(rig), o, "BCN_Epileptic tiled");
      rows.push_back(measure("skinned_bcn_tiled", tiled, reps, frac(tiled.frame_count())));
    }
  } catch (const std::exception& e) {
    std::cerr << "anim_sources_bench: " << e.what() << "\n";
    fs::remove_all(tmp);
    return 1;
  }
  fs::remove_all(tmp);
  std::printf("# anim_sources_bench: threads=%u reps=%d (medians; copy = std::copy of the same positions)\n",
              threads ? threads : hw, reps);
  std::printf("%-22s %10s %10s %12s %14s %12s %10s\n", "source", "triangles", "vertices", "ms_per_frame",
              "Mpositions_s", "copy_ms", "x_copy");
  for (const Row& r : rows)
    std::printf("%-22s %10zu %10zu %12.4f %14.2f %12.4f %10.2f\n", r.source.c_str(), r.triangles, r.vertices,
                r.s_per_frame * 1e3, static_cast<double>(r.vertices) / r.s_per_frame * 1e-6, r.copy_s * 1e3,
                r.s_per_frame / r.copy_s);
  return 0;
}
