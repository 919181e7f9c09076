#include "commands/cluster_files.h"

#include <algorithm>
#include <charconv>
#include <span>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "toolkit/clustering/cluster.h"
#include "toolkit/core/error.h"
#include "toolkit/mesh/topology.h"

namespace ptc {
namespace {

bool parse_u64(std::string_view tok, std::uint64_t& out) {
  while (!tok.empty() && (tok.front() == ' ' || tok.front() == '\t')) tok.remove_prefix(1);
  while (!tok.empty() && (tok.back() == ' ' || tok.back() == '\t')) tok.remove_suffix(1);
  if (tok.empty()) return false;
  const auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), out);
  return ec == std::errc() && p == tok.data() + tok.size();
}

std::string shown(std::string_view s) {
  std::string q(s.substr(0, 32));
  for (char& c : q)
    if (static_cast<unsigned char>(c) < 0x20) c = '?';
  return "'" + q + (s.size() > 32 ? "...'" : "'");
}

}  // namespace

Clustering read_clusters(const std::filesystem::path& dir, const Mesh& mesh) {
  std::error_code ec;
  const std::filesystem::path file = std::filesystem::is_directory(dir, ec) ? dir / "triangles.csv" : dir;
  const std::string name = file.string();
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(name, "", "", std::filesystem::exists(file, ec) ? "cannot be read" : "no such file");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();

  const std::size_t T = mesh.triangle_count();
  std::vector<std::uint32_t> label(T, 0);
  std::vector<std::uint64_t> line_of(T, 0);  // 0 = not seen yet
  std::size_t pos = 0, line = 0, rows = 0;
  while (pos < text.size()) {
    std::size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view l(text.data() + pos, end - pos);
    pos = end + 1;
    ++line;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    if (line == 1) {
      if (l != "triangle_id,cluster_id")
        throw InputError(name, line_loc(1), "header", "expected 'triangle_id,cluster_id', got " + shown(l));
      continue;
    }
    if (l.empty()) {
      if (pos >= text.size()) break;  // the final newline
      throw InputError(name, line_loc(line), "", "empty line");
    }
    const std::size_t comma = l.find(',');
    std::uint64_t t = 0, c = 0;
    if (comma == std::string_view::npos || l.find(',', comma + 1) != std::string_view::npos)
      throw InputError(name, line_loc(line), "", "expected 2 comma-separated fields, got " + shown(l));
    if (!parse_u64(l.substr(0, comma), t))
      throw InputError(name, line_loc(line), "", "triangle id " + shown(l.substr(0, comma)) + " is not a non-negative integer");
    if (!parse_u64(l.substr(comma + 1), c) || c > 0xffffffffull)
      throw InputError(name, line_loc(line), "triangle " + std::to_string(t),
                       "cluster id " + shown(l.substr(comma + 1)) + " is not an integer in 0..4294967295");
    if (t >= T)
      throw InputError(name, line_loc(line), "triangle " + std::to_string(t),
                       "out of range: the mesh has " + std::to_string(T) + " triangles (clusters of another mesh?)");
    if (line_of[t])
      throw InputError(name, line_loc(line), "triangle " + std::to_string(t),
                       "listed twice (first on line " + std::to_string(line_of[t]) + ")");
    line_of[t] = line;
    label[t] = static_cast<std::uint32_t>(c);
    ++rows;
  }
  if (line == 0) throw InputError(name, "", "", "empty file");
  if (rows != T) {
    std::size_t missing = 0;
    while (missing < T && line_of[missing]) ++missing;
    throw InputError(name, line_loc(line), "triangle " + std::to_string(missing),
                     "missing: the file lists " + std::to_string(rows) + " triangles, the mesh has " + std::to_string(T) +
                         " (clusters of another mesh?)");
  }

  Clustering c = clustering_from_labels(label, mesh.triangles());
  // Connectivity through shared sides, cluster by cluster (breadth-first from its first
  // triangle): by the mesh's edges, or else by sides whose corner positions coincide (a
  // clustering made with --adjacency positions, cluster.h). The first cluster connected by
  // neither, or 0xffffffff.
  std::vector<std::uint8_t> seen(T, 0);
  std::vector<std::uint32_t> queue;
  auto first_unconnected = [&](std::span<const Tri> tris_of_mesh) -> std::uint32_t {
    const EdgeMap edges = EdgeMap::build(tris_of_mesh, mesh.vertex_count());
    std::fill(seen.begin(), seen.end(), 0);
    for (std::size_t k = 0; k < c.cluster_count(); ++k) {
      const auto tris = c.triangles_of(k);
      queue.assign(1, tris[0]);
      seen[tris[0]] = 1;
      for (std::size_t q = 0; q < queue.size(); ++q)
        for (int side = 0; side < 3; ++side) {
          const std::uint32_t e = edges.side_edge(queue[q], side);
          if (e == kNoEdge) continue;
          for (std::uint32_t n : edges.triangles_of(e))
            if (!seen[n] && label[n] == label[tris[0]]) seen[n] = 1, queue.push_back(n);
        }
      if (queue.size() != tris.size()) return static_cast<std::uint32_t>(k);
    }
    return 0xffffffffu;
  };
  if (first_unconnected(mesh.triangles()) != 0xffffffffu) {
    const std::vector<Tri> welded = adjacency_triangles(mesh, ClusterAdjacency::Positions);
    const std::uint32_t k = first_unconnected(welded);
    if (k != 0xffffffffu) {
      const auto tris = c.triangles_of(k);
      std::uint32_t bad = tris[0];
      for (std::uint32_t t : tris)
        if (!seen[t]) {
          bad = t;
          break;
        }
      throw InputError(name, line_loc(line_of[bad]), "triangle " + std::to_string(bad),
                       "cluster " + std::to_string(label[bad]) +
                           " is not connected through shared sides, not even by coincident corners (triangle " +
                           std::to_string(tris[0]) + " of the same cluster cannot be reached; clusters of another mesh?)");
    }
  }
  return c;
}

ClusteringInfo clustering_info(const std::filesystem::path& clusters) {
  ClusteringInfo ci;
  std::error_code ec;
  const std::filesystem::path dir = std::filesystem::is_directory(clusters, ec) ? clusters : clusters.parent_path();
  const std::filesystem::path mpath = dir / "manifest.json";
  ci.from = "defaults (no manifest.json beside triangles.csv)";
  ci.title = "clusters of " + clusters.string();
  std::ifstream in(mpath);
  if (!in) return ci;
  const nlohmann::json m = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (m.is_discarded() || !m.contains("parameters") || !m["parameters"].is_object()) return ci;
  const nlohmann::json& p = m["parameters"];
  auto str = [&](const char* k) { return p.contains(k) && p[k].is_string() ? p[k].get<std::string>() : std::string(); };
  if (p.contains("max_count") && p["max_count"].is_number_unsigned()) ci.cfg.max_count = p["max_count"].get<std::uint32_t>();
  if (p.contains("max_size") && p["max_size"].is_number()) ci.cfg.max_size = p["max_size"].get<double>();
  if (const auto s = parse_size_bound_mode(str("size_bound"))) ci.cfg.size_bound_mode = *s;
  if (const auto s = parse_sphere_method(str("sphere"))) ci.cfg.sphere = *s;
  if (const auto s = parse_cluster_method(str("method"))) ci.cfg.method = *s;
  if (const auto s = parse_objective(str("objective"))) ci.cfg.objective = *s;
  // The adjacency the clustering used: as resolved by that run, else as it was asked for.
  if (const auto s = parse_cluster_adjacency(str("adjacency"))) ci.cfg.adjacency = *s;
  if (m.contains("results") && m["results"].is_object() && m["results"].contains("adjacency") &&
      m["results"]["adjacency"].is_string())
    if (const auto s = parse_cluster_adjacency(m["results"]["adjacency"].get<std::string>())) ci.cfg.adjacency = *s;
  ci.from = mpath.string();
  ci.from_manifest = true;
  const std::string method = str("method"), objective = str("objective");
  ci.title = fmt::format("{}{}{}, MaxCount {}, MaxSize {:g}", method.empty() ? "clusters" : method,
                         objective.empty() ? "" : " / ", objective, ci.cfg.max_count, ci.cfg.max_size);
  return ci;
}

}  // namespace ptc
