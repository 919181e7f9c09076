// The inputs of the hand-built probes in bench/scale/ and their grouping of a cluster's triangles (leaf_tables_probe.cpp, leaf_test_probe.cpp;
// not part of the build): a binary little-endian PLY of double positions and triangles, as
// `ptc subdivide` writes it, and a clustering's `triangles.csv` from `ptc cluster`.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace probe {

struct Input {
  std::size_t V = 0, T = 0;                        // vertices, triangles
  std::vector<double> P;                           // x y z per vertex
  std::vector<std::uint32_t> tri;                  // three corners per triangle
  std::uint32_t C = 0;                             // clusters
  std::vector<std::vector<std::uint32_t>> clusters;  // each cluster's triangles, ascending
};

// argv[1] MESH.ply, argv[2] TRIANGLES.csv. Bad usage: a usage line and exit 2; a file that is
// not of that shape: one line naming it and exit 1.
inline Input read_input(int argc, char** argv) {
  using u32 = std::uint32_t;
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s MESH.ply TRIANGLES.csv\n", argv[0]);
    std::exit(2);
  }
  auto fail = [](const char* file, const char* why) {
    std::fprintf(stderr, "%s: %s\n", file, why);
    std::exit(1);
  };
  Input in;
  FILE* f = std::fopen(argv[1], "rb");
  if (!f) fail(argv[1], "cannot open");
  char line[256];
  while (std::fgets(line, sizeof line, f)) {
    if (std::sscanf(line, "element vertex %zu", &in.V) == 1 || std::sscanf(line, "element face %zu", &in.T) == 1)
      continue;
    if (!std::strncmp(line, "end_header", 10)) break;
  }
  in.P.resize(3 * in.V);
  in.tri.resize(3 * in.T);
  bool ok = std::fread(in.P.data(), 8, 3 * in.V, f) == 3 * in.V;
  for (std::size_t t = 0; ok && t < in.T; ++t) {
    unsigned char n = 0;
    int x[3];
    ok = std::fread(&n, 1, 1, f) == 1 && n == 3 && std::fread(x, 4, 3, f) == 3;
    for (int k = 0; k < 3; ++k) in.tri[3 * t + k] = static_cast<u32>(x[k]);
  }
  std::fclose(f);
  if (!ok) fail(argv[1], "not a binary PLY of double positions and triangles");
  std::ifstream lf(argv[2]);
  if (!lf) fail(argv[2], "cannot open");
  std::string s;
  std::getline(lf, s);  // header
  std::vector<u32> label(in.T, 0);
  while (std::getline(lf, s)) {
    u32 a = 0, b = 0;
    if (std::sscanf(s.c_str(), "%u,%u", &a, &b) != 2 || a >= in.T) fail(argv[2], "bad row");
    label[a] = b, in.C = std::max(in.C, b + 1);
  }
  in.clusters.resize(in.C);
  for (u32 t = 0; t < in.T; ++t) in.clusters[label[t]].push_back(t);
  return in;
}

// One cluster's triangles split greedily into groups of at most 16 triangles on at most 16
// distinct vertices: each step takes the remaining triangle that adds the fewest new vertices
// (the first of equals). verts: the group's distinct vertices in first-use order; tris: its
// triangles in the order taken.
struct Group {
  std::vector<std::uint32_t> verts, tris;
};
inline std::vector<Group> greedy_groups(std::vector<std::uint32_t> rem, const std::vector<std::uint32_t>& tri) {
  std::vector<Group> out;
  while (!rem.empty()) {
    Group g;
    auto has = [&](std::uint32_t v) { return std::find(g.verts.begin(), g.verts.end(), v) != g.verts.end(); };
    while (g.tris.size() < 16) {
      int best = -1, best_new = 4;
      for (std::size_t i = 0; i < rem.size() && best_new > 0; ++i) {
        int fresh = 0;
        for (int k = 0; k < 3; ++k) fresh += !has(tri[3 * rem[i] + k]);
        if (fresh < best_new && g.verts.size() + fresh <= 16) best_new = fresh, best = static_cast<int>(i);
      }
      if (best < 0) break;
      const std::uint32_t t = rem[best];
      rem.erase(rem.begin() + best);
      g.tris.push_back(t);
      for (int k = 0; k < 3; ++k)
        if (!has(tri[3 * t + k])) g.verts.push_back(tri[3 * t + k]);
    }
    out.push_back(std::move(g));
  }
  return out;
}

}  // namespace probe
