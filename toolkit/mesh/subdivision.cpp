#include "toolkit/mesh/subdivision.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/enumerable_thread_specific.h>
#include <oneapi/tbb/parallel_for.h>

#include "toolkit/core/cancel.h"
#include "toolkit/core/error.h"
#include "toolkit/mesh/topology.h"

namespace ptc {

std::optional<SubdivisionScheme> parse_subdivision_scheme(std::string_view name) {
  auto iequals = [](std::string_view a, std::string_view b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
             auto lower = [](char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; };
             return lower(x) == lower(y);
           });
  };
  if (iequals(name, "midpoint")) return SubdivisionScheme::Midpoint;
  if (iequals(name, "loop")) return SubdivisionScheme::Loop;
  return std::nullopt;
}

std::string_view to_string(SubdivisionScheme scheme) {
  switch (scheme) {
    case SubdivisionScheme::Midpoint: return "midpoint";
    case SubdivisionScheme::Loop: return "loop";
  }
  return "?";
}

namespace {

constexpr std::uint32_t kNone = 0xffffffffu;

// A sparse matrix in CSR form. Rows are small (at most a few dozen entries).
struct Csr {
  std::vector<std::size_t> offsets{0};
  std::vector<std::uint32_t> columns;
  std::vector<double> weights;

  [[nodiscard]] std::size_t rows() const { return offsets.size() - 1; }
  void push(std::uint32_t c, double w) {
    columns.push_back(c);
    weights.push_back(w);
  }
  void end_row() { offsets.push_back(columns.size()); }
};

Csr identity(std::size_t n) {
  Csr m;
  m.offsets.resize(n + 1);
  m.columns.resize(n);
  m.weights.assign(n, 1.0);
  for (std::size_t i = 0; i <= n; ++i) m.offsets[i] = i;
  for (std::size_t i = 0; i < n; ++i) m.columns[i] = static_cast<std::uint32_t>(i);
  return m;
}

// Accumulates one row of a sparse product: distinct columns in order of first appearance (so
// the result does not depend on scheduling), found through an open-addressing table whose
// slots are invalidated by bumping a stamp instead of clearing.
class RowAccumulator {
 public:
  void begin(std::size_t upper_bound) {
    std::size_t cap = 16;
    while (cap < 2 * upper_bound) cap *= 2;
    if (cap > keys_.size() || ++stamp_ == 0) {
      keys_.assign(std::max(cap, keys_.size()), 0);
      stamps_.assign(keys_.size(), 0);
      stamp_ = 1;
      shift_ = 32;
      for (std::size_t c = keys_.size(); c > 1; c /= 2) --shift_;
    }
    cols_.clear();
    ws_.clear();
  }
  void add(std::uint32_t col, double w) {
    const std::size_t mask = keys_.size() - 1;
    // Fibonacci hashing; shift_ = 32 - log2(capacity).
    for (std::size_t s = (col * 0x9E3779B1u) >> shift_;; s = (s + 1) & mask) {
      if (stamps_[s] != stamp_) {
        stamps_[s] = stamp_;
        keys_[s] = static_cast<std::uint32_t>(cols_.size());
        cols_.push_back(col);
        ws_.push_back(w);
        return;
      }
      if (cols_[keys_[s]] == col) {
        ws_[keys_[s]] += w;
        return;
      }
    }
  }
  /// Moves the largest weight to the front (the anchor of the evaluation, see the header).
  void finish() {
    std::size_t best = 0;
    for (std::size_t k = 1; k < ws_.size(); ++k)
      if (ws_[k] > ws_[best]) best = k;
    if (best != 0) {
      std::swap(cols_[0], cols_[best]);
      std::swap(ws_[0], ws_[best]);
    }
  }
  [[nodiscard]] std::size_t size() const { return cols_.size(); }
  [[nodiscard]] const std::vector<std::uint32_t>& columns() const { return cols_; }
  [[nodiscard]] const std::vector<double>& weights() const { return ws_; }

 private:
  std::vector<std::uint32_t> keys_;    // index into cols_/ws_
  std::vector<std::uint32_t> stamps_;  // slot is live when == stamp_
  std::uint32_t stamp_ = 0;
  int shift_ = 32;
  std::vector<std::uint32_t> cols_;
  std::vector<double> ws_;
};

// Runs fill(first_row, last_row, columns, weights) over blocks of rows in parallel; fill appends
// the block's rows to the two vectors and sets R.offsets[i + 1] to row i's length. The blocks
// are then concatenated: one pass of work, a transient copy of the result.
template <class Fill>
Csr build_rows_in_blocks(std::size_t n, Fill fill) {
  constexpr std::size_t kBlock = 2048;
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::vector<std::uint32_t>> cols(blocks);
  std::vector<std::vector<double>> ws(blocks);
  Csr R;
  R.offsets.assign(n + 1, 0);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t k) {
    fill(k * kBlock, std::min(n, (k + 1) * kBlock), cols[k], ws[k], R.offsets);
  });
  for (std::size_t i = 0; i < n; ++i) R.offsets[i + 1] += R.offsets[i];
  R.columns.resize(R.offsets[n]);
  R.weights.resize(R.offsets[n]);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t k) {
    const auto at = static_cast<std::ptrdiff_t>(R.offsets[k * kBlock]);
    std::copy(cols[k].begin(), cols[k].end(), R.columns.begin() + at);
    std::copy(ws[k].begin(), ws[k].end(), R.weights.begin() + at);
    std::vector<std::uint32_t>().swap(cols[k]);
    std::vector<double>().swap(ws[k]);
  });
  return R;
}

// S * C: row i is sum over entries (j, s) of S's row i of s * (row j of C).
Csr compose(const Csr& S, const Csr& C) {
  tbb::enumerable_thread_specific<RowAccumulator> accumulators;
  return build_rows_in_blocks(S.rows(), [&](std::size_t first, std::size_t last, std::vector<std::uint32_t>& cols,
                                            std::vector<double>& ws, std::vector<std::size_t>& offsets) {
    RowAccumulator& acc = accumulators.local();
    for (std::size_t i = first; i < last; ++i) {
      std::size_t bound = 0;
      for (std::size_t k = S.offsets[i]; k < S.offsets[i + 1]; ++k)
        bound += C.offsets[S.columns[k] + 1] - C.offsets[S.columns[k]];
      acc.begin(bound);
      for (std::size_t k = S.offsets[i]; k < S.offsets[i + 1]; ++k) {
        const std::uint32_t j = S.columns[k];
        const double s = S.weights[k];
        for (std::size_t q = C.offsets[j]; q < C.offsets[j + 1]; ++q) acc.add(C.columns[q], s * C.weights[q]);
      }
      acc.finish();
      cols.insert(cols.end(), acc.columns().begin(), acc.columns().end());
      ws.insert(ws.end(), acc.weights().begin(), acc.weights().end());
      offsets[i + 1] = acc.size();
    }
  });
}

std::string edge_name(std::uint32_t a, std::uint32_t b) {
  return "edge (" + std::to_string(std::min(a, b)) + ", " + std::to_string(std::max(a, b)) + ")";
}

// Loop's preconditions (see the header): every edge on at most two triangles, then no triangle
// with a repeated corner, then no two triangles on the same corners. They hold again for the
// refined mesh: a half edge lies on the children of its parent's triangles; an inner edge
// (m_e1, m_e2) of triangle t lies on two children of t and on a child of any other triangle
// with both edges e1 and e2, i.e. on the same corners.
void check_loop_input(std::span<const Tri> tris, const EdgeMap& em) {
  for (std::size_t e = 0; e < em.edge_count(); ++e) {
    if (em.valence(e) <= 2) continue;
    std::string list;
    const auto ts = em.triangles_of(e);
    for (std::size_t k = 0; k < ts.size() && k < 4; ++k) list += (k ? ", " : "") + std::to_string(ts[k]);
    if (ts.size() > 4) list += ", ...";
    throw InputError("", "", edge_name(em.edge(e).v0, em.edge(e).v1),
                     "non-manifold edge on " + std::to_string(ts.size()) + " triangles (" + list +
                         "); Loop subdivision needs every edge on at most two triangles");
  }
  auto corners = [](const Tri& f) {
    return "(" + std::to_string(f[0]) + ", " + std::to_string(f[1]) + ", " + std::to_string(f[2]) + ")";
  };
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const Tri& f = tris[t];
    if (f[0] == f[1] || f[1] == f[2] || f[2] == f[0])
      throw InputError("", "", "triangle " + std::to_string(t),
                       "repeated vertex index " + corners(f) + "; Loop subdivision needs three distinct corners");
  }
  // Two triangles on the same three corners (a duplicate, or a two-sided "pillow") share all
  // three edges; after one level their children's inner edges lie on four triangles.
  auto sorted = [](Tri f) {
    std::sort(f.begin(), f.end());
    return f;
  };
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (std::uint32_t u : em.triangles_of(em.side_edge(t, 0)))
      if (u < t && sorted(tris[u]) == sorted(tris[t]))
        throw InputError("", "", "triangle " + std::to_string(t),
                         "same corners " + corners(tris[t]) + " as triangle " + std::to_string(u) +
                             "; Loop subdivision needs distinct triangles");
}

int corner_of(const Tri& f, std::uint32_t v) { return f[0] == v ? 0 : (f[1] == v ? 1 : 2); }

// Per vertex: 1 when Loop keeps it fixed, i.e. when its triangles form two or more
// edge-connected fans (a non-manifold vertex); 0 otherwise, including unreferenced vertices.
// Preconditions checked by check_loop_input.
std::vector<std::uint8_t> loop_corners(std::span<const Tri> tris, std::size_t V, const EdgeMap& em) {
  std::vector<std::uint32_t> tri_count(V, 0), some_tri(V, kNone);
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (std::uint32_t v : tris[t]) {
      ++tri_count[v];
      some_tri[v] = static_cast<std::uint32_t>(t);
    }
  // Size of the edge-connected fan of v through t0 (walk both ways around v; each edge has at
  // most two triangles, so the fan is a path or a cycle).
  auto fan_size = [&](std::uint32_t v, std::uint32_t t0) {
    const int c = corner_of(tris[t0], v);
    const std::uint32_t first_edges[2] = {em.side_edge(t0, c), em.side_edge(t0, (c + 2) % 3)};
    std::size_t n = 1;
    for (std::uint32_t e : first_edges) {
      std::uint32_t t = t0;
      for (;;) {
        const auto ts = em.triangles_of(e);
        if (ts.size() != 2) break;
        const std::uint32_t next = ts[0] == t ? ts[1] : ts[0];
        if (next == t0) return n;  // closed fan
        ++n;
        const int k = corner_of(tris[next], v);
        const std::uint32_t e1 = em.side_edge(next, k), e2 = em.side_edge(next, (k + 2) % 3);
        e = e1 == e ? e2 : e1;
        t = next;
      }
    }
    return n;
  };
  std::vector<std::uint8_t> corner(V, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, V, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v)
      corner[v] = tri_count[v] != 0 && fan_size(static_cast<std::uint32_t>(v), some_tri[v]) != tri_count[v];
  });
  return corner;
}

// One Loop step as a (V + E) x V matrix; its rows have distinct columns and the largest weight
// first. corner: see loop_corners.
Csr loop_step(std::span<const Tri> tris, std::size_t V, const EdgeMap& em, const std::vector<std::uint8_t>& corner) {
  const std::size_t E = em.edge_count();

  // Per vertex: incident edges (CSR).
  std::vector<std::uint32_t> vedge_off(V + 1, 0);
  for (const Edge& e : em.edges()) {
    ++vedge_off[e.v0 + 1];
    ++vedge_off[e.v1 + 1];
  }
  for (std::size_t v = 0; v < V; ++v) vedge_off[v + 1] += vedge_off[v];
  std::vector<std::uint32_t> vedges(vedge_off[V]);
  {
    std::vector<std::uint32_t> fill(vedge_off.begin(), vedge_off.end() - 1);
    for (std::size_t e = 0; e < E; ++e) {
      vedges[fill[em.edge(e).v0]++] = static_cast<std::uint32_t>(e);
      vedges[fill[em.edge(e).v1]++] = static_cast<std::uint32_t>(e);
    }
  }

  auto other_end = [&](std::uint32_t e, std::uint32_t v) {
    const Edge& ed = em.edge(e);
    return ed.v0 == v ? ed.v1 : ed.v0;
  };
  // Valences below this come from a table (OpenMesh's LoopT tabulates 0..49 the same way).
  constexpr std::size_t kTable = 64;
  std::vector<std::pair<double, double>> table(kTable);
  auto loop_weights = [](std::size_t n) {
    // Exactly OpenMesh LoopT's compute_weight, so results agree to rounding: (1 - alpha, alpha / n).
    const double inv_v = 1.0 / static_cast<double>(n);
    const double t = 3.0 + 2.0 * std::cos(2.0 * std::numbers::pi * inv_v);
    const double alpha = (40.0 - t * t) / 64.0;
    return std::pair{1.0 - alpha, inv_v * alpha};
  };
  for (std::size_t n = 1; n < kTable; ++n) table[n] = loop_weights(n);

  return build_rows_in_blocks(V + E, [&](std::size_t first, std::size_t last, std::vector<std::uint32_t>& cols,
                                         std::vector<double>& ws, std::vector<std::size_t>& offsets) {
    auto push = [&](std::uint32_t c, double w) {
      cols.push_back(c);
      ws.push_back(w);
    };
    for (std::size_t i = first; i < last; ++i) {
      const std::size_t before = cols.size();
      if (i < V) {  // the vertex rule
        const auto v = static_cast<std::uint32_t>(i);
        const std::uint32_t b = vedge_off[v], e = vedge_off[v + 1];
        if (b == e || corner[v]) {
          push(v, 1.0);  // unreferenced (no edge: Loop's triangles have distinct corners), or a corner
        } else {
          std::uint32_t boundary[2] = {kNone, kNone};
          int nb = 0;
          for (std::uint32_t k = b; k < e; ++k)
            if (em.valence(vedges[k]) == 1) boundary[nb++ & 1] = other_end(vedges[k], v);  // a single open fan has two
          if (nb != 0) {
            push(v, 0.75);
            push(boundary[0], 0.125);
            push(boundary[1], 0.125);
          } else {
            const std::size_t n = e - b;
            const auto [self, each] = n < kTable ? table[n] : loop_weights(n);
            push(v, self);
            for (std::uint32_t k = b; k < e; ++k) push(other_end(vedges[k], v), each);
          }
        }
      } else {  // the edge rule
        const Edge& ed = em.edge(i - V);
        const auto ts = em.triangles_of(i - V);
        if (ts.size() == 1) {
          push(ed.v0, 0.5);
          push(ed.v1, 0.5);
        } else {
          push(ed.v0, 0.375);
          push(ed.v1, 0.375);
          for (std::uint32_t t : ts) {
            const Tri& f = tris[t];
            push(f[0] != ed.v0 && f[0] != ed.v1 ? f[0] : (f[1] != ed.v0 && f[1] != ed.v1 ? f[1] : f[2]), 0.125);
          }
        }
      }
      offsets[i + 1] = cols.size() - before;
    }
  });
}

// One Midpoint step as a (V + E) x V matrix.
Csr midpoint_step(std::size_t V, const EdgeMap& em) {
  const std::size_t E = em.edge_count();
  Csr S = identity(V);
  S.offsets.reserve(V + E + 1);
  S.columns.reserve(V + 2 * E);
  S.weights.reserve(V + 2 * E);
  for (const Edge& ed : em.edges()) {
    S.push(ed.v0, 0.5);
    S.push(ed.v1, 0.5);
    S.end_row();
  }
  return S;
}

// The 1-to-4 split (numbering in the header).
std::vector<Tri> split_triangles(std::span<const Tri> tris, std::size_t V, const EdgeMap& em) {
  std::vector<Tri> out(4 * tris.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tris.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const Tri& f = tris[t];
      std::uint32_t m[3];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t e = em.side_edge(t, k);
        m[k] = e == kNoEdge ? f[k] : static_cast<std::uint32_t>(V + e);
      }
      out[4 * t + 0] = {f[0], m[0], m[2]};
      out[4 * t + 1] = {m[0], f[1], m[1]};
      out[4 * t + 2] = {m[2], m[1], f[2]};
      out[4 * t + 3] = {m[0], m[1], m[2]};
    }
  });
  return out;
}

}  // namespace

Subdivider::Subdivider() : row_offsets_{0} {}

Subdivider Subdivider::build(std::span<const Tri> triangles, std::size_t vertex_count, SubdivisionScheme scheme,
                             int levels) {
  if (levels < 0) throw InputError("", "", "levels", "must be >= 0, got " + std::to_string(levels));
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (std::uint32_t v : triangles[t])
      if (v >= vertex_count)
        throw std::invalid_argument("Subdivider::build: triangle " + std::to_string(t) + " refers to vertex " +
                                    std::to_string(v) + " of " + std::to_string(vertex_count));
  // Indices are 32-bit and EdgeMap stores 3 T side slots in 32 bits: refuse before allocating.
  // Each level adds at most 3 T_k vertices (one per side) and multiplies T by 4.
  {
    constexpr double kLimit = static_cast<double>(std::numeric_limits<std::uint32_t>::max() - 1);
    double T = static_cast<double>(triangles.size()), V = static_cast<double>(vertex_count);
    for (int l = 0; l < levels && T > 0; ++l) {
      V += 3 * T;
      T *= 4;
      if (3 * T > kLimit || V > kLimit)
        throw InputError("", "", "levels",
                         std::to_string(levels) + " levels of " + std::to_string(triangles.size()) +
                             " triangles exceed 32-bit vertex/triangle indices");
    }
  }

  Subdivider s;
  s.scheme_ = scheme;
  s.levels_ = levels;
  s.source_vertex_count_ = vertex_count;
  s.source_triangles_.assign(triangles.begin(), triangles.end());

  std::vector<Tri> tris(triangles.begin(), triangles.end());
  std::size_t V = vertex_count;
  Csr map = identity(vertex_count);
  std::vector<std::uint8_t> corner;  // Loop only
  for (int l = 0; l < levels; ++l) {
    throw_if_cancelled();  // a level of a 13M-triangle mesh takes seconds (toolkit/core/cancel.h)
    const EdgeMap em = EdgeMap::build(tris, V);
    Csr step;
    if (scheme == SubdivisionScheme::Loop) {
      // Later levels inherit the preconditions (see check_loop_input), and the corners: an old
      // vertex's fans are refined fan by fan, and an edge point has one fan (around its edge).
      if (l == 0) {
        check_loop_input(tris, em);
        corner = loop_corners(tris, V, em);
      } else {
        corner.resize(V, 0);
      }
      step = loop_step(tris, V, em, corner);
    } else {
      step = midpoint_step(V, em);
    }
    // Step rows have distinct columns, largest weight first: the first level needs no product.
    map = l == 0 ? std::move(step) : compose(step, map);
    tris = split_triangles(tris, V, em);
    V += em.edge_count();
  }
  s.row_offsets_ = std::move(map.offsets);
  s.columns_ = std::move(map.columns);
  s.weights_ = std::move(map.weights);
  s.refined_ = Mesh(std::move(tris), std::vector<Vec3>(V, Vec3::Zero()));
  return s;
}

void Subdivider::apply(std::span<const Vec3> in, std::span<Vec3> out) const {
  if (in.size() != source_vertex_count_)
    throw std::invalid_argument("Subdivider::apply: " + std::to_string(in.size()) + " input positions, expected " +
                                std::to_string(source_vertex_count_));
  if (out.size() != vertex_count())
    throw std::invalid_argument("Subdivider::apply: output of " + std::to_string(out.size()) +
                                " positions, expected " + std::to_string(vertex_count()));
  if (!in.empty() && !out.empty()) {
    const auto* ib = reinterpret_cast<const char*>(in.data());
    const auto* ob = reinterpret_cast<const char*>(out.data());
    if (std::less<const char*>{}(ib, ob + out.size_bytes()) && std::less<const char*>{}(ob, ib + in.size_bytes()))
      throw std::invalid_argument("Subdivider::apply: input and output overlap");
  }
  const std::uint32_t* cols = columns_.data();
  const double* ws = weights_.data();
  const std::size_t* offs = row_offsets_.data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::size_t b = offs[i], e = offs[i + 1];
      const Vec3& a = in[cols[b]];
      if (e == b + 1) {  // a carried vertex: a bitwise copy (a + 0 would turn -0 into +0)
        out[i] = a;
        continue;
      }
      double x = 0, y = 0, z = 0;
      for (std::size_t k = b + 1; k < e; ++k) {
        const Vec3& p = in[cols[k]];
        x += ws[k] * (p.x() - a.x());
        y += ws[k] * (p.y() - a.y());
        z += ws[k] * (p.z() - a.z());
      }
      out[i] = Vec3(a.x() + x, a.y() + y, a.z() + z);
      if (!out[i].allFinite()) [[unlikely]] {
        // A difference p - a overflowed (corners near +-1.8e308 on both sides): the same sum on
        // the positions times 2^-8, then back (the weights are convex, so the point is finite).
        constexpr double kDown = 0x1p-8, kUp = 0x1p8;
        const Vec3 as = a * kDown;
        Vec3 d = Vec3::Zero();
        for (std::size_t k = b + 1; k < e; ++k) d += ws[k] * (in[cols[k]] * kDown - as);
        out[i] = (as + d) * kUp;
      }
    }
  });
}

Mesh Subdivider::apply(const Mesh& m) const {
  const auto tris = m.triangles();
  if (m.vertex_count() != source_vertex_count_ || tris.size() != source_triangles_.size() ||
      !std::equal(tris.begin(), tris.end(), source_triangles_.begin()))
    throw std::invalid_argument("Subdivider::apply: the mesh's topology is not the one the map was built for");
  std::vector<Vec3> out(vertex_count());
  apply(m.positions(), out);
  return refined_.with_positions(std::move(out));
}

Mesh subdivide(const Mesh& m, SubdivisionScheme scheme, int levels) {
  return Subdivider::build(m.triangles(), m.vertex_count(), scheme, levels).apply(m);
}

}  // namespace ptc
