// Per-sphere time of every bounding-sphere method on point sets of a real mesh: armadillo.off,
// its triangles cut into connected patches of 96 (see patches()), each patch's distinct vertices
// one point set (~60 points; patches under 48 triangles, the leftovers, are skipped). Each benchmark also reports the radius error against the exact minimal
// sphere over all point sets (counters rel_err_mean / rel_err_max, (r - r_exact) / r_exact).
//
//   spheres_bench [--benchmark_filter=...]   ("s_per_sphere" is the per-sphere time)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <fstream>
#include <iostream>
#include <sstream>
#include <cstdint>
#include <string>
#include <vector>

#include "toolkit/geometry/sphere.h"

namespace {

using ptc::Vec3;

constexpr std::size_t kRunTriangles = 96;

struct OffMesh {
  std::vector<Vec3> positions;
  std::vector<ptc::Tri> triangles;
};

/// A tiny OFF reader (the project's reader is elsewhere): header "OFF", counts, vertices,
/// faces; '#' starts a comment; polygons are fanned into triangles.
OffMesh read_off(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::stringstream tokens;
  for (std::string line; std::getline(in, line);) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    tokens << line << '\n';
  }
  std::string magic;
  std::size_t nv = 0, nf = 0, ne = 0;
  tokens >> magic >> nv >> nf >> ne;
  if (magic != "OFF" || !tokens) throw std::runtime_error(path + ": not an OFF file");
  OffMesh m;
  m.positions.resize(nv);
  for (Vec3& p : m.positions) tokens >> p.x() >> p.y() >> p.z();
  for (std::size_t f = 0; f < nf; ++f) {
    std::size_t k = 0;
    tokens >> k;
    std::vector<std::uint32_t> idx(k);
    for (auto& i : idx) tokens >> i;
    for (std::size_t j = 1; j + 1 < k; ++j) m.triangles.push_back({idx[0], idx[j], idx[j + 1]});
  }
  if (!tokens) throw std::runtime_error(path + ": truncated");
  return m;
}

struct Data {
  std::vector<std::vector<Vec3>> sets;
  std::vector<double> exact;
};

/// Cuts the mesh into patches of kRunTriangles triangles: breadth-first over triangles sharing
/// a vertex, seeded by the first untaken triangle in file order. (Plain runs in file order do
/// not work on armadillo.off: its faces are not stored in a local order, so 96 consecutive
/// triangles have ~240 distinct vertices, and the point sets should look like clusters.)
std::vector<std::vector<std::uint32_t>> patches(const OffMesh& m) {
  std::vector<std::vector<std::uint32_t>> vertex_tris(m.positions.size());
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
    for (auto v : m.triangles[t]) vertex_tris[v].push_back(t);
  std::vector<char> taken(m.triangles.size(), 0);
  std::vector<std::vector<std::uint32_t>> out;
  for (std::uint32_t seed = 0; seed < m.triangles.size(); ++seed) {
    if (taken[seed]) continue;
    std::vector<std::uint32_t> patch{seed};
    taken[seed] = 1;
    for (std::size_t head = 0; head < patch.size() && patch.size() < kRunTriangles; ++head)
      for (auto v : m.triangles[patch[head]])
        for (auto t : vertex_tris[v])
          if (!taken[t] && patch.size() < kRunTriangles) taken[t] = 1, patch.push_back(t);
    out.push_back(std::move(patch));
  }
  return out;
}

const Data& data() {
  static const Data d = [] {
    const OffMesh m = read_off(std::string(PTC_TEST_DATA) + "/meshes/armadillo.off");
    Data r;
    for (const auto& patch : patches(m)) {
      if (patch.size() < kRunTriangles / 2) continue;  // leftovers between finished patches
      std::vector<std::uint32_t> ids;
      for (auto t : patch) ids.insert(ids.end(), m.triangles[t].begin(), m.triangles[t].end());
      std::sort(ids.begin(), ids.end());
      ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
      std::vector<Vec3> pts;
      for (auto i : ids) pts.push_back(m.positions[i]);
      r.sets.push_back(std::move(pts));
    }
    for (const auto& s : r.sets) r.exact.push_back(ptc::min_sphere_exact(s).radius);
    return r;
  }();
  return d;
}

void BM_Sphere(benchmark::State& state, ptc::SphereMethod method) {
  const Data& d = data();
  for (auto _ : state) {
    for (const auto& s : d.sets) benchmark::DoNotOptimize(ptc::bounding_sphere(method, s));
  }
  double err_sum = 0.0, err_max = 0.0;
  std::size_t points = 0, not_containing = 0;
  for (std::size_t i = 0; i < d.sets.size(); ++i) {
    const ptc::Sphere s = ptc::bounding_sphere(method, d.sets[i]);
    const double err = (s.radius - d.exact[i]) / d.exact[i];
    err_sum += err;
    err_max = std::max(err_max, std::abs(err));
    points += d.sets[i].size();
    const double tol = method == ptc::SphereMethod::Exact ? ptc::exact_containment_tol(s, d.sets[i])
                                                          : ptc::kSphereContainmentTol;
    not_containing += !ptc::contains_all(s, d.sets[i], tol);
  }
  const auto n = static_cast<double>(d.sets.size());
  state.counters["s_per_sphere"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["sets"] = n;
  state.counters["points_mean"] = static_cast<double>(points) / n;
  state.counters["rel_err_mean"] = err_sum / n;
  state.counters["rel_err_max"] = err_max;
  state.counters["not_containing"] = static_cast<double>(not_containing);
}

const bool registered = [] {
  for (ptc::SphereMethod m : ptc::kAllSphereMethods)
    benchmark::RegisterBenchmark(("BM_Sphere/" + std::string(ptc::to_string(m))).c_str(), BM_Sphere, m)
        ->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
