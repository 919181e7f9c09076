#include "toolkit/clustering/clustering.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

namespace ptc {

namespace {

/// Edge-connected pieces of one set of triangles at a time, from the set alone: two triangles
/// of the set are connected when they share a side with the same two (distinct) vertex ids,
/// which is exactly when they share a mesh edge of topology.h's EdgeMap (a collapsed side is no
/// edge). Each side's vertex pair goes into a small open-addressing table (per call, sized for
/// the set); a pair met again unites its triangle with the first one on it. O(n) for n triangles,
/// nothing of size T: no edge map is needed (at 13M triangles one costs 0.6 GB and seconds to
/// build), and one finder per thread can run beside others.
class PieceFinder {
 public:
  explicit PieceFinder(std::span<const Tri> triangles) : tris_(triangles) {}

  /// piece[i] = piece of ids[i], pieces numbered 0.. in order of their first position. Every id
  /// must be < T (callers filter). A repeated id is connected to its other occurrences (it shares
  /// its own edges). Returns the number of pieces (0 for an empty set).
  std::uint32_t find(std::span<const std::uint32_t> ids, std::vector<std::uint32_t>& piece) {
    const auto n = static_cast<std::uint32_t>(ids.size());
    int bits = 4;
    while ((std::size_t{1} << bits) < 4 * std::size_t{n}) ++bits;  // at most 3n pairs: load <= 3/4
    const std::size_t mask = (std::size_t{1} << bits) - 1;
    keys_.assign(mask + 1, kEmpty);  // no pair is kEmpty: its smaller vertex is below 2^32 - 1
    at_.resize(mask + 1);
    parent_.resize(n);
    std::iota(parent_.begin(), parent_.end(), 0u);
    for (std::uint32_t i = 0; i < n; ++i) {
      const Tri& f = tris_[ids[i]];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = f[k], b = f[(k + 1) % 3];
        if (a == b) continue;  // a collapsed side is no edge
        const std::uint64_t key = (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
        std::size_t h = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits));
        while (keys_[h] != kEmpty && keys_[h] != key) h = (h + 1) & mask;
        if (keys_[h] == kEmpty) {
          keys_[h] = key;
          at_[h] = i;
        } else {
          unite(i, at_[h]);
        }
      }
    }
    piece.assign(n, 0);
    std::uint32_t count = 0;
    std::vector<std::uint32_t>& root_piece = scratch_;
    root_piece.assign(n, kNoCluster);
    for (std::uint32_t i = 0; i < n; ++i) {
      const std::uint32_t r = root(i);
      if (root_piece[r] == kNoCluster) root_piece[r] = count++;
      piece[i] = root_piece[r];
    }
    return count;
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  std::uint32_t root(std::uint32_t x) {
    while (parent_[x] != x) x = parent_[x] = parent_[parent_[x]];
    return x;
  }
  void unite(std::uint32_t a, std::uint32_t b) {
    a = root(a);
    b = root(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

  std::span<const Tri> tris_;
  std::vector<std::uint64_t> keys_;
  std::vector<std::uint32_t> at_, parent_, scratch_;
};

/// Sorted distinct vertices of the triangles `ids` (all < triangles.size()), appended to `out`.
void append_distinct_vertices(std::span<const std::uint32_t> ids, std::span<const Tri> triangles,
                              std::vector<std::uint32_t>& out) {
  const std::size_t first = out.size();
  for (const std::uint32_t t : ids) out.insert(out.end(), triangles[t].begin(), triangles[t].end());
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end());
  out.erase(std::unique(out.begin() + static_cast<std::ptrdiff_t>(first), out.end()), out.end());
}

/// Checks one offset array; returns false (after reporting) when its ranges are unusable.
bool check_offsets(const std::vector<std::uint32_t>& off, std::size_t data_size, const char* name,
                   const char* data_name, std::vector<std::string>& issues, std::size_t max_issues) {
  auto report = [&](std::string s) {
    if (issues.size() < max_issues) issues.push_back(std::move(s));
  };
  if (off.empty()) {
    report(fmt::format("{} is empty (needs cluster_count + 1 entries, the first 0)", name));
    return false;
  }
  bool ok = true;
  if (off.front() != 0) {
    report(fmt::format("{}[0] = {}, expected 0", name, off.front()));
    ok = false;
  }
  for (std::size_t c = 0; c + 1 < off.size(); ++c)
    if (off[c + 1] < off[c]) {
      report(fmt::format("cluster {}: {} decrease ({} -> {})", c, name, off[c], off[c + 1]));
      ok = false;
    }
  if (off.back() != data_size) {
    report(fmt::format("{} ends at {} but {} has {} entries", name, off.back(), data_name, data_size));
    ok = false;
  }
  return ok;
}

}  // namespace

std::vector<std::uint32_t> Clustering::cluster_of_triangle() const {
  const std::size_t T = triangle_order.size();
  std::vector<std::uint32_t> out(T, kNoCluster);
  for (std::size_t c = 0; c + 1 < triangle_offsets.size(); ++c) {
    const std::size_t lo = std::min<std::size_t>(triangle_offsets[c], T);
    const std::size_t hi = std::min<std::size_t>(triangle_offsets[c + 1], T);
    for (std::size_t i = lo; i < hi; ++i)
      if (triangle_order[i] < T) out[triangle_order[i]] = static_cast<std::uint32_t>(c);
  }
  return out;
}

Clustering clustering_from_labels(std::span<const std::uint32_t> labels, std::span<const Tri> triangles) {
  if (labels.size() != triangles.size())
    throw std::invalid_argument(fmt::format("clustering_from_labels: {} labels for {} triangles", labels.size(),
                                            triangles.size()));
  const std::size_t T = labels.size();
  if (T > 0xffffffffu) throw std::invalid_argument("clustering_from_labels: more than 2^32 - 1 triangles");

  // The triangles ordered by (label, triangle): each label's run starts with its smallest
  // triangle id. Labels of the algorithms are dense (0 .. clusters - 1): a counting sort, O(T);
  // arbitrary ones: a sort of (label, triangle) keys. Both give the one sorted order.
  struct Run {
    std::uint32_t first_triangle, begin, end;  // [begin, end) in order
  };
  std::vector<std::uint32_t> order(T);
  std::vector<Run> runs;
  const std::uint32_t max_label = T ? *std::max_element(labels.begin(), labels.end()) : 0;
  if (std::uint64_t{max_label} < 2 * std::uint64_t{T} + 1024) {
    std::vector<std::uint32_t> start(std::size_t{max_label} + 2, 0);
    for (const std::uint32_t l : labels) ++start[std::size_t{l} + 1];
    for (std::size_t l = 0; l <= max_label; ++l) start[l + 1] += start[l];
    {
      std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
      for (std::size_t t = 0; t < T; ++t) order[fill[labels[t]]++] = static_cast<std::uint32_t>(t);
    }
    for (std::size_t l = 0; l <= max_label; ++l)
      if (start[l + 1] > start[l]) runs.push_back({order[start[l]], start[l], start[l + 1]});
  } else {
    std::vector<std::uint64_t> key(T);
    for (std::size_t t = 0; t < T; ++t) key[t] = (std::uint64_t{labels[t]} << 32) | t;
    tbb::parallel_sort(key.begin(), key.end());  // distinct keys: one sorted order, whatever the threads
    for (std::size_t i = 0; i < T; ++i) order[i] = static_cast<std::uint32_t>(key[i]);
    for (std::size_t i = 0; i < T;) {
      std::size_t j = i + 1;
      while (j < T && (key[j] >> 32) == (key[i] >> 32)) ++j;
      runs.push_back({order[i], static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)});
      i = j;
    }
  }
  std::sort(runs.begin(), runs.end(), [](const Run& a, const Run& b) { return a.first_triangle < b.first_triangle; });

  Clustering c;
  c.triangle_order.reserve(T);
  c.triangle_offsets.reserve(runs.size() + 1);
  c.vertex_offsets.reserve(runs.size() + 1);
  c.vertices.reserve(T);  // about 0.7 T for closed meshes; untouched capacity costs no memory
  // Each cluster's distinct vertices: a corner is listed the first time the cluster meets it
  // (seen[v] = the cluster), then the list is sorted -- the same ascending list as sorting all
  // corners and dropping repeats (append_distinct_vertices), with a third of the sorting
  // (clustering_bench --sections stages, from_labels_cpu_s; docs/scale.md).
  std::uint32_t max_vertex = 0;
  for (const Tri& f : triangles) max_vertex = std::max({max_vertex, f[0], f[1], f[2]});
  std::vector<std::uint32_t> seen(T ? std::size_t{max_vertex} + 1 : 0, kNoCluster);
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const Run& r = runs[k];
    const std::size_t first = c.triangle_order.size(), first_vertex = c.vertices.size();
    c.triangle_order.insert(c.triangle_order.end(), order.begin() + r.begin, order.begin() + r.end);
    c.triangle_offsets.push_back(static_cast<std::uint32_t>(c.triangle_order.size()));
    for (std::size_t i = first; i < c.triangle_order.size(); ++i)
      for (const std::uint32_t v : triangles[c.triangle_order[i]])
        if (seen[v] != k) {
          seen[v] = static_cast<std::uint32_t>(k);
          c.vertices.push_back(v);
        }
    std::sort(c.vertices.begin() + static_cast<std::ptrdiff_t>(first_vertex), c.vertices.end());
    c.vertex_offsets.push_back(static_cast<std::uint32_t>(c.vertices.size()));
  }
  return c;
}

std::vector<std::string> validate(const Clustering& c, std::span<const Tri> triangles, const ClusterLimits& limits,
                                  std::size_t max_issues, std::span<const Tri> adjacency) {
  std::vector<std::string> issues;
  auto full = [&] { return issues.size() >= max_issues; };
  auto report = [&](std::string s) {
    if (!full()) issues.push_back(std::move(s));
  };
  const std::size_t T = triangles.size();
  const bool own_adjacency = adjacency.empty();
  if (own_adjacency) {
    adjacency = triangles;
  } else if (adjacency.size() != T) {
    report(fmt::format("the adjacency has {} triangles, the mesh {}", adjacency.size(), T));
    return issues;
  }

  // 1. Structure of the offset arrays.
  const bool tri_ok = check_offsets(c.triangle_offsets, c.triangle_order.size(), "triangle_offsets",
                                    "triangle_order", issues, max_issues);
  bool vert_ok = check_offsets(c.vertex_offsets, c.vertices.size(), "vertex_offsets", "vertices", issues, max_issues);
  if (c.vertex_offsets.size() != c.triangle_offsets.size()) {
    report(fmt::format("vertex_offsets has {} entries, triangle_offsets {} (both must be cluster_count + 1)",
                       c.vertex_offsets.size(), c.triangle_offsets.size()));
    vert_ok = false;
  }

  // 2. Every triangle exactly once. Without usable offsets, positions stand in for clusters.
  std::vector<std::uint32_t> seen_in(T, kNoCluster);  // first cluster (or position) holding t
  auto check_id = [&](std::uint32_t t, std::size_t where, const char* what) {
    if (t >= T) {
      report(fmt::format("{} {}: triangle id {} out of range (the mesh has {} triangles)", what, where, t, T));
    } else if (seen_in[t] != kNoCluster) {
      if (tri_ok && seen_in[t] == where)
        report(fmt::format("triangle {} appears twice in cluster {}", t, where));
      else
        report(fmt::format("triangle {} appears in {}s {} and {}", t, what, seen_in[t], where));
    } else {
      seen_in[t] = static_cast<std::uint32_t>(where);
    }
  };
  if (tri_ok) {
    for (std::size_t k = 0; k + 1 < c.triangle_offsets.size() && !full(); ++k)
      for (std::uint32_t i = c.triangle_offsets[k]; i < c.triangle_offsets[k + 1]; ++i)
        check_id(c.triangle_order[i], k, "cluster");
  } else {
    for (std::size_t i = 0; i < c.triangle_order.size() && !full(); ++i) check_id(c.triangle_order[i], i, "position");
  }
  for (std::size_t t = 0; t < T && !full(); ++t)
    if (seen_in[t] == kNoCluster) report(fmt::format("triangle {} is in no cluster", t));
  if (!tri_ok || full()) return issues;

  // 3. Per cluster: not empty, ascending, vertex list, connectivity, limits. Fixed chunks of
  // clusters in parallel, each keeping its first max_issues messages; joined in chunk order and
  // cut to max_issues, they are the messages a pass in cluster order gives, at any thread count.
  constexpr std::size_t kChunk = 4096;
  const std::size_t K = c.triangle_offsets.size() - 1;
  std::vector<std::vector<std::string>> chunk_issues((K + kChunk - 1) / kChunk);
  tbb::parallel_for(std::size_t{0}, chunk_issues.size(), [&](std::size_t chunk) {
    std::vector<std::string>& mine = chunk_issues[chunk];
    auto note = [&](std::string s) {
      if (mine.size() < max_issues) mine.push_back(std::move(s));
    };
    PieceFinder pieces(adjacency);
    std::vector<std::uint32_t> ids, expected, piece, welded;
    std::vector<std::uint8_t> used;
    for (std::size_t k = chunk * kChunk; k < std::min(K, (chunk + 1) * kChunk) && mine.size() < max_issues; ++k) {
      const auto tris = c.triangles_of(k);
      if (tris.empty()) {
        note(fmt::format("cluster {}: empty", k));
        continue;
      }
      if (!std::is_sorted(tris.begin(), tris.end())) note(fmt::format("cluster {}: triangles not in ascending order", k));
      ids.clear();
      for (const std::uint32_t t : tris)
        if (t < T) ids.push_back(t);
      // The distinct vertices of the cluster's triangles. A strictly ascending vertex list that
      // holds every corner and whose every vertex is a corner IS that list (no sort needed);
      // otherwise (or without usable vertex offsets) it is made by sorting the corners.
      const auto listed = vert_ok ? c.vertices_of(k) : std::span<const std::uint32_t>();
      const bool ascending =
          vert_ok && std::adjacent_find(listed.begin(), listed.end(), std::greater_equal<>()) == listed.end();
      bool same = ascending;
      if (same && listed.empty()) {
        same = ids.empty();  // no corners: only the empty list is theirs
      } else if (same) {
        used.assign(listed.size(), 0);
        for (std::size_t i = 0; i < ids.size() && same; ++i)
          for (const std::uint32_t v : triangles[ids[i]]) {
            // Branch-free lower bound in the (short) list: the position of v, if v is there.
            const std::uint32_t* at = listed.data();
            for (std::size_t n = listed.size(); n > 1;) {
              const std::size_t half = n / 2;
              at = at[half] <= v ? at + half : at;
              n -= half;
            }
            if (*at != v) {
              same = false;
              break;
            }
            used[static_cast<std::size_t>(at - listed.data())] = 1;
          }
        same = same && std::find(used.begin(), used.end(), 0) == used.end();
      }
      std::size_t vertex_count = listed.size();
      if (!same) {
        expected.clear();
        append_distinct_vertices(ids, triangles, expected);
        vertex_count = expected.size();
      }
      if (vert_ok) {
        if (!ascending) {
          note(fmt::format("cluster {}: vertex list not strictly ascending", k));
        } else if (!same) {
          std::vector<std::uint32_t> extra, missing;
          std::set_difference(listed.begin(), listed.end(), expected.begin(), expected.end(),
                              std::back_inserter(extra));
          std::set_difference(expected.begin(), expected.end(), listed.begin(), listed.end(),
                              std::back_inserter(missing));
          note(fmt::format("cluster {}: vertex list has {} vertices, its triangles use {} ({} missing{}, {} extra{})",
                           k, listed.size(), expected.size(), missing.size(),
                           missing.empty() ? "" : fmt::format(" e.g. {}", missing.front()), extra.size(),
                           extra.empty() ? "" : fmt::format(" e.g. {}", extra.front())));
        }
      }
      if (!ids.empty()) {
        const std::uint32_t n = pieces.find(ids, piece);
        if (n > 1) note(fmt::format("cluster {}: not {}-connected ({} pieces)", k, own_adjacency ? "edge" : "side", n));
      }
      if (limits.max_triangles > 0 && tris.size() > limits.max_triangles)
        note(fmt::format("cluster {}: {} triangles > limit {}", k, tris.size(), limits.max_triangles));
      if (limits.max_vertices > 0 && !own_adjacency) {  // the vertices the clustering counted
        welded.clear();
        append_distinct_vertices(ids, adjacency, welded);
        vertex_count = welded.size();
      }
      if (limits.max_vertices > 0 && vertex_count > limits.max_vertices)
        note(fmt::format("cluster {}: {} vertices > limit {}", k, vertex_count, limits.max_vertices));
    }
  });
  for (std::vector<std::string>& mine : chunk_issues)
    for (std::string& s : mine) report(std::move(s));
  return issues;
}

Clustering split_disconnected(const Clustering& c, std::span<const Tri> triangles) {
  const std::size_t T = triangles.size();
  const auto& off = c.triangle_offsets;
  bool ok = !off.empty() && off.front() == 0 && off.back() == c.triangle_order.size() && c.triangle_order.size() == T &&
            std::is_sorted(off.begin(), off.end());
  std::vector<std::uint32_t> label(T, kNoCluster);
  if (ok)
    for (const std::uint32_t t : c.triangle_order) {
      if (t >= T || label[t] != kNoCluster) {
        ok = false;
        break;
      }
      label[t] = 0;
    }
  if (!ok)
    throw std::invalid_argument(
        "split_disconnected: the clustering is not a partition of the triangles with consistent offsets");

  PieceFinder pieces(triangles);
  std::vector<std::uint32_t> piece;
  std::uint32_t next = 0;
  for (std::size_t k = 0; k + 1 < off.size(); ++k) {
    const auto tris = c.triangles_of(k);
    const std::uint32_t n = pieces.find(tris, piece);
    for (std::size_t i = 0; i < tris.size(); ++i) label[tris[i]] = next + piece[i];
    next += n;
  }
  return clustering_from_labels(label, triangles);
}

Clustering renumber_vertices(Clustering&& c, std::span<const std::uint32_t> to_new) {
  // Checked before anything changes (the caller may still hold on to a refused clustering).
  for (const std::uint32_t v : c.vertices)
    if (v >= to_new.size())
      throw std::invalid_argument("renumber_vertices: vertex " + std::to_string(v) + " of the clustering is outside the " +
                                  std::to_string(to_new.size()) + " renumbered vertices");
  for (std::size_t k = 0; k + 1 < c.vertex_offsets.size(); ++k)
    if (c.vertex_offsets[k] > c.vertex_offsets[k + 1] || c.vertex_offsets[k + 1] > c.vertices.size())
      throw std::invalid_argument("renumber_vertices: vertex offsets of cluster " + std::to_string(k) +
                                  " decrease or run past the vertex list");
  for (std::uint32_t& v : c.vertices) v = to_new[v];
  for (std::size_t k = 0; k + 1 < c.vertex_offsets.size(); ++k)
    std::sort(c.vertices.begin() + c.vertex_offsets[k], c.vertices.begin() + c.vertex_offsets[k + 1]);
  return std::move(c);
}

Clustering renumber_vertices(const Clustering& c, std::span<const std::uint32_t> to_new) {
  return renumber_vertices(Clustering(c), to_new);
}

}  // namespace ptc
