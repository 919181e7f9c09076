#include "commands/cluster_files.h"
#include "toolkit/core/cancel.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <span>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "toolkit/anim/scene.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"

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

// Calls on_line(number, line) for every line of `in` (numbers from 1, '\n' ends a line, a final
// line without one counts), reading in blocks of 1 MiB: the file is never held whole (it is
// 200 MB at 13.3M triangles; held whole and copied, it took three times that in fresh memory).
// on_line returns false to stop. A line longer than a block is kept whole.
template <class F>
void for_each_line(std::istream& in, F&& on_line) {
  std::string buf(std::size_t{1} << 20, '\0'), carry;
  std::uint64_t number = 0;
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    const auto got = static_cast<std::size_t>(in.gcount());
    std::size_t p = 0;
    while (p < got) {
      const char* nl = static_cast<const char*>(std::memchr(buf.data() + p, '\n', got - p));
      if (!nl) {
        carry.append(buf.data() + p, got - p);
        break;
      }
      const std::size_t e = static_cast<std::size_t>(nl - buf.data());
      bool go;
      if (carry.empty()) {
        go = on_line(++number, std::string_view(buf.data() + p, e - p));
      } else {
        carry.append(buf.data() + p, e - p);
        go = on_line(++number, std::string_view(carry));
        carry.clear();
      }
      if (!go) return;
      p = e + 1;
    }
  }
  if (!carry.empty() && !in.bad()) on_line(++number, std::string_view(carry));  // (a failed read: no line)
}

Clustering read_clusters(const std::filesystem::path& dir, const Mesh& mesh) {
  std::error_code ec;
  const std::filesystem::path file = std::filesystem::is_directory(dir, ec) ? dir / "triangles.csv" : dir;
  const std::string name = file.string();
  std::optional<BlockingWaitFor> waiting(std::in_place, file);  // (a FIFO: a stop request ends the run at once meanwhile)
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(name, "", "", std::filesystem::exists(file, ec) ? "cannot be read" : "no such file");

  const std::size_t T = mesh.triangle_count();
  std::vector<std::uint32_t> label(T, 0);
  std::vector<std::uint8_t> listed(T, 0);  // each triangle's row seen (its line: line_of, on errors only)
  // The line of triangle t's first row, for the error messages: the file read again (a regular
  // file only: a pipe cannot be read twice); 0 when not found again.
  auto line_of = [&](std::size_t t) -> std::uint64_t {
    if (!std::filesystem::is_regular_file(file, ec)) return 0;
    std::ifstream again(file, std::ios::binary);
    std::uint64_t found = 0;
    for_each_line(again, [&](std::uint64_t ln, std::string_view l) {
      std::uint64_t id = 0;
      if (ln > 1 && parse_u64(l.substr(0, l.find(',')), id) && id == t) found = ln;
      return found == 0;
    });
    return found;
  };
  std::uint64_t line = 0, empty_line = 0;  // empty_line: an empty line, an error unless it is the last
  std::size_t rows = 0;
  for_each_line(in, [&](std::uint64_t ln, std::string_view l) {
    line = ln;
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    if (line == 1) {
      if (l.substr(0, 3) == "\xEF\xBB\xBF") l.remove_prefix(3);  // a UTF-8 byte order mark (spreadsheets write one)
      if (l != "triangle_id,cluster_id")
        throw InputError(name, line_loc(1), "header", "expected 'triangle_id,cluster_id', got " + shown(l));
      return true;
    }
    if (empty_line) throw InputError(name, line_loc(empty_line), "", "empty line");
    if (l.empty()) {
      empty_line = line;  // the final newline, unless another line follows
      return true;
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
    if (listed[t])
      throw InputError(name, line_loc(line), "triangle " + std::to_string(t),
                       "listed twice (first on " + [&] {
                         const std::uint64_t first = line_of(t);
                         return first ? "line " + std::to_string(first) : std::string("an earlier line");
                       }() + ")");
    listed[t] = 1;
    label[t] = static_cast<std::uint32_t>(c);
    ++rows;
    return true;
  });
  waiting.reset();
  if (in.bad()) throw InputError(name, line_loc(line + 1), "", "cannot be read");
  if (line == 0) throw InputError(name, "", "", "empty file");
  if (rows != T) {
    std::size_t missing = 0;
    while (missing < T && listed[missing]) ++missing;
    throw InputError(name, line_loc(line), "triangle " + std::to_string(missing),
                     "missing: the file lists " + std::to_string(rows) + " triangles, the mesh has " + std::to_string(T) +
                         " (clusters of another mesh?)");
  }

  Clustering c = clustering_from_labels(label, mesh.triangles());
  // Connectivity through shared sides, cluster by cluster: by the mesh's edges, or else by sides
  // whose corner positions coincide (a clustering made with --adjacency positions, cluster.h).
  // Each cluster alone: its triangles' sides, keyed by their two corners in a hash table, join
  // the triangles of one key (one mesh edge) in a union-find over the cluster's own triangles. The
  // first cluster whose triangles are not all joined to its first one, or 0xffffffff, and the
  // first of its triangles that is not (`unjoined`). Scratch of the largest cluster's size only
  // (a union-find over all triangles and the sides of the whole mesh sorted by vertex took 28
  // bytes a triangle of fresh memory, 370 MB at 13M triangles; docs/scale.md).
  std::uint32_t unjoined = 0;
  // The sides of one cluster in an open-addressing table (key: smaller corner << 32 | larger
  // corner; value: the first triangle of the cluster seen on that side), four slots a triangle or
  // more; a slot is empty unless its stamp is the current cluster's.
  std::vector<std::uint64_t> keys;
  std::vector<std::uint32_t> first_on, stamp;
  std::uint32_t round = 0;
  std::vector<std::uint32_t> parent;
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];  // path halving
    return x;
  };
  // A cluster of more than kHashedLimit triangles (a clustering of a few huge clusters, or one
  // for the whole mesh) sorts its sides instead: 12 bytes a side, where the table would take up
  // to 128 bytes a triangle (at 13M triangles in one cluster: 480 MB against 1.7 GB).
  constexpr std::size_t kHashedLimit = std::size_t{1} << 17;
  struct Side {
    std::uint32_t lo, hi, local;
  };
  std::vector<Side> sides;
  auto join = [&](std::uint32_t x, std::uint32_t y) {
    const std::uint32_t ra = find(x), rb = find(y);
    if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
  };
  // on_side(smaller corner, larger corner, i) for every side of two distinct corners of the
  // cluster's triangles tris[i].
  auto for_each_side = [](std::span<const Tri> tris_of_mesh, std::span<const std::uint32_t> tris, auto&& on_side) {
    for (std::uint32_t i = 0; i < tris.size(); ++i) {
      const Tri& f = tris_of_mesh[tris[i]];
      for (int j = 0; j < 3; ++j) {
        const std::uint32_t a = f[j], b = f[(j + 1) % 3];
        if (a != b) on_side(std::min(a, b), std::max(a, b), i);
      }
    }
  };
  // The sides of one cluster (of at most kHashedLimit triangles) through the table.
  auto hashed = [&](std::span<const Tri> tris_of_mesh, std::span<const std::uint32_t> tris) {
    std::size_t size = 64;
    while (size < 4 * tris.size()) size *= 2;  // at most three quarters full (no side shared)
    if (keys.size() < size || ++round == 0) {  // a larger table, or the stamps wrapped around
      keys.assign(std::max(keys.size(), size), 0);
      first_on.assign(keys.size(), 0);
      stamp.assign(keys.size(), 0);
      round = 1;
    }
    const std::size_t mask = size - 1;
    for_each_side(tris_of_mesh, tris, [&](std::uint32_t lo, std::uint32_t hi, std::uint32_t i) {
      const std::uint64_t key = std::uint64_t{lo} << 32 | hi;
      for (std::size_t h = (key * 0x9E3779B97F4A7C15ull) >> 32;; ++h) {
        const std::size_t slot = h & mask;
        if (stamp[slot] != round) {
          stamp[slot] = round, keys[slot] = key, first_on[slot] = i;
          return;
        }
        if (keys[slot] == key) {  // one mesh edge: join the triangle to the first on it
          join(first_on[slot], i);
          return;
        }
      }
    });
  };
  auto first_unconnected = [&](std::span<const Tri> tris_of_mesh) -> std::uint32_t {
    for (std::size_t k = 0; k < c.cluster_count(); ++k) {
      const auto tris = c.triangles_of(k);
      if (tris.size() < 2) continue;
      parent.resize(tris.size());
      for (std::uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
      if (tris.size() > kHashedLimit) {
        sides.clear();
        for_each_side(tris_of_mesh, tris,
                      [&](std::uint32_t lo, std::uint32_t hi, std::uint32_t i) { sides.push_back({lo, hi, i}); });
        std::sort(sides.begin(), sides.end(),
                  [](const Side& x, const Side& y) { return x.lo != y.lo ? x.lo < y.lo : x.hi < y.hi; });
        for (std::size_t lo = 0, hi; lo < sides.size(); lo = hi)  // one run: one edge
          for (hi = lo + 1; hi < sides.size() && sides[hi].lo == sides[lo].lo && sides[hi].hi == sides[lo].hi; ++hi)
            join(sides[lo].local, sides[hi].local);
        std::vector<Side>().swap(sides);
      } else {
        hashed(tris_of_mesh, tris);
      }
      for (std::uint32_t i = 1; i < tris.size(); ++i)
        if (find(i) != find(0)) {
          unjoined = tris[i];
          return static_cast<std::uint32_t>(k);
        }
    }
    return 0xffffffffu;
  };
  if (first_unconnected(mesh.triangles()) != 0xffffffffu) {
    const std::vector<Tri> welded = adjacency_triangles(mesh, ClusterAdjacency::Positions);
    const std::uint32_t k = first_unconnected(welded);
    if (k != 0xffffffffu) {
      const auto tris = c.triangles_of(k);
      const std::uint32_t bad = unjoined;
      const std::uint64_t bad_line = line_of(bad);
      throw InputError(name, bad_line ? line_loc(bad_line) : std::string(), "triangle " + std::to_string(bad),
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
  // A manifest.json that is not `ptc cluster`'s (another program's, or not JSON at all) gives no
  // parameters, and the defaults' record says so; one of ptc cluster's whose parameters are not
  // what it writes is an edited file: named, with the field.
  const nlohmann::json m = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  const bool ours = m.is_object() && m.contains("schema") && m["schema"].is_string() &&
                    m["schema"].get<std::string>().rfind("ptc-cluster/", 0) == 0;
  if (!ours) {
    ci.from = fmt::format("defaults ({} is not ptc cluster's manifest{})", mpath.string(),
                          m.is_discarded() ? ": not valid JSON" : "");
    read_note(mpath.string(), fmt::format("not ptc cluster's manifest{}: the clustering's parameters are the defaults "
                                          "(MaxCount {}, MaxSize {:g})",
                                          m.is_discarded() ? " (not valid JSON)" : "", ci.cfg.max_count, ci.cfg.max_size));
    return ci;
  }
  const auto bad = [&](const std::string& field, const std::string& want) {
    return InputError(mpath.string(), "", field, want + " (an edited manifest of ptc cluster: its clustering's "
                                                        "parameters are read from it)");
  };
  if (!m.contains("parameters") || !m["parameters"].is_object()) throw bad("parameters", "missing or not an object");
  const nlohmann::json& p = m["parameters"];
  auto str = [&](const char* k) {
    if (!p.contains(k)) return std::string();
    if (!p[k].is_string()) throw bad(std::string("parameters.") + k, "not a string");
    return p[k].get<std::string>();
  };
  if (p.contains("max_count")) {
    if (!p["max_count"].is_number_unsigned() || p["max_count"].get<std::uint64_t>() > kMaxSceneClusterCount)
      throw bad("parameters.max_count", "not an integer in [0, " + std::to_string(kMaxSceneClusterCount) + "]");
    ci.cfg.max_count = p["max_count"].get<std::uint32_t>();
  }
  if (p.contains("max_size")) {
    if (!p["max_size"].is_number() || !(p["max_size"].get<double>() >= 0.0) || !std::isfinite(p["max_size"].get<double>()))
      throw bad("parameters.max_size", "not a finite number >= 0");
    ci.cfg.max_size = p["max_size"].get<double>();
  }
  const auto parsed = [&](const char* k, auto parse, auto& into) {
    const std::string v = str(k);
    if (v.empty()) return;
    const auto x = parse(v);
    if (!x) throw bad(std::string("parameters.") + k, "'" + v + "' is not a value ptc cluster writes");
    into = *x;
  };
  parsed("size_bound", [](const std::string& v) { return parse_size_bound_mode(v); }, ci.cfg.size_bound_mode);
  parsed("sphere", [](const std::string& v) { return parse_sphere_method(v); }, ci.cfg.sphere);
  parsed("method", [](const std::string& v) { return parse_cluster_method(v); }, ci.cfg.method);
  parsed("objective", [](const std::string& v) { return parse_objective(v); }, ci.cfg.objective);
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
