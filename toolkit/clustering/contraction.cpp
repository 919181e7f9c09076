#include "toolkit/clustering/contraction.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <sys/mman.h>
#include <unistd.h>

#include <boost/pending/container_traits.hpp>

#include "toolkit/clustering/small_arcs.h"
#include "toolkit/core/cancel.h"

namespace ptc {
namespace {
/// The selector of SmallArcs for Boost's container_gen.
struct SmallArcsS {};
}  // namespace

// SmallArcs is a vector for Boost's generic container functions (push, erase_if; found by
// argument-dependent lookup).
template <class T>
boost::graph_detail::vector_tag container_category(const SmallArcs<T>&) {
  return {};
}
template <class T>
boost::graph_detail::unstable_tag iterator_stability(const SmallArcs<T>&) {
  return {};
}
}  // namespace ptc

namespace boost {
namespace graph_detail {
template <class T>
struct container_traits<ptc::SmallArcs<T>> {
  typedef vector_tag category;
  typedef unstable_tag iterator_stability;
};
}  // namespace graph_detail
}  // namespace boost

#include <boost/graph/adjacency_list.hpp>

namespace boost {
template <class ValueType>
struct container_gen<ptc::SmallArcsS, ValueType> {
  typedef ptc::SmallArcs<ValueType> type;
};
template <>
struct parallel_edge_traits<ptc::SmallArcsS> {
  typedef allow_parallel_edge_tag type;
};
}  // namespace boost

#include "toolkit/core/isa.h"

namespace ptc {

namespace {

/// What an entry's key is (in its stamp's two top bits): the exact score, or an upper bound from
/// Precision::SupportBound; neither: from Precision::UpperBoundAllowed. Push times stay below 2^30
/// (a push time counts merges, and the contraction takes fewer than 2^30 triangles).
constexpr std::uint32_t kExactBit = 0x80000000u;
constexpr std::uint32_t kSupportBit = 0x40000000u;
constexpr std::uint32_t kKeyBits = kExactBit | kSupportBit;

/// A queue entry: the key (score, pair (lo << 32) | hi, lo < hi) and its stamp: the number of
/// merges done when it was pushed, with the key's kind (kKeyBits). It is current while neither
/// cluster has changed since (contract_impl's `changed`): 4 bytes where two version numbers took 8.
struct Entry {
  double score;
  std::uint64_t pair;
  std::uint32_t stamp;
};

/// Queue order: higher score first, equal scores by the smaller pair.
inline bool ranks_below(double s1, std::uint64_t p1, double s2, std::uint64_t p2) {
  return s1 < s2 || (s1 == s2 && p1 > p2);
}

/// Max-heap of entries, 4-ary, with the 16-byte keys apart from the stamps: a sift reads four
/// children from one or two cache lines and half as many levels as a binary heap (the queue
/// holds millions of entries on large meshes; measured ~2x faster than std::push/pop_heap).
class EntryHeap {
 public:
  [[nodiscard]] bool empty() const { return keys_.empty(); }
  [[nodiscard]] std::size_t size() const { return keys_.size(); }
  void reserve(std::size_t n) {
    keys_.reserve(n);
    stamps_.reserve(n);
  }
  /// Appends without ordering; call heapify() before the next push/pop.
  void append(const Entry& e) {
    keys_.push_back({e.score, e.pair});
    stamps_.push_back(e.stamp);
  }
  void heapify() {
    const std::size_t n = keys_.size();
    if (n < 2) return;
    for (std::size_t i = (n - 2) / 4 + 1; i-- > 0;) sift_down(i);
  }
  void push(const Entry& e) {
    append(e);
    sift_up(keys_.size() - 1);
  }
  [[nodiscard]] Entry top() const { return {keys_[0].score, keys_[0].pair, stamps_[0]}; }
  void pop() {
    keys_[0] = keys_.back();
    stamps_[0] = stamps_.back();
    keys_.pop_back();
    stamps_.pop_back();
    if (!keys_.empty()) sift_down(0);
  }
  /// Removes every entry for which `stale` is true, then restores the heap (O(n)). The pages of
  /// the storage beyond `room` entries go back to the system (release_beyond).
  template <class F>
  void purge(F&& stale, std::size_t room) {
    std::size_t w = 0;
    for (std::size_t r = 0; r < keys_.size(); ++r) {
      const Entry e{keys_[r].score, keys_[r].pair, stamps_[r]};
      if (stale(e)) continue;
      keys_[w] = keys_[r];
      stamps_[w++] = stamps_[r];
    }
    keys_.resize(w);
    stamps_.resize(w);
    heapify();
    release_beyond(keys_, room);
    release_beyond(stamps_, room);
  }

 private:
  struct Key {
    double score;
    std::uint64_t pair;
  };
  using Stamps = std::uint32_t;
  static bool below(const Key& x, const Key& y) { return ranks_below(x.score, x.pair, y.score, y.pair); }
  /// The live pairs only decrease, and with them the heap after each purge: the whole pages of
  /// v's storage past its first `room` elements (never written before the next purge) are
  /// returned with madvise(MADV_DONTNEED), which keeps the reservation (a page written again
  /// comes back zeroed). The queue's pages then make room for the merged clusters' summaries,
  /// whose count peaks later (docs/scale.md, "Contraction in one run: the memory").
  template <class V>
  static void release_beyond(V& v, std::size_t room) {
    room = std::max(room, v.size());  // (never the entries in use)
    if (room >= v.capacity()) return;
    static const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
    const auto from = reinterpret_cast<std::uintptr_t>(v.data() + room);
    const auto to = reinterpret_cast<std::uintptr_t>(v.data() + v.capacity());
    const std::uintptr_t lo = (from + page - 1) / page * page, hi = to / page * page;
    if (hi > lo) (void)madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_DONTNEED);
  }
  void sift_up(std::size_t i) {
    const Key k = keys_[i];
    const Stamps st = stamps_[i];
    while (i > 0) {
      const std::size_t parent = (i - 1) / 4;
      if (!below(keys_[parent], k)) break;
      keys_[i] = keys_[parent];
      stamps_[i] = stamps_[parent];
      i = parent;
    }
    keys_[i] = k;
    stamps_[i] = st;
  }
  void sift_down(std::size_t i) {
    const std::size_t n = keys_.size();
    const Key k = keys_[i];
    const Stamps st = stamps_[i];
    for (;;) {
      const std::size_t first = 4 * i + 1;
      if (first >= n) break;
      const std::size_t last = std::min(first + 4, n);
      std::size_t best = first;
      for (std::size_t c = first + 1; c < last; ++c)
        if (below(keys_[best], keys_[c])) best = c;
      if (!below(k, keys_[best])) break;
      keys_[i] = keys_[best];
      stamps_[i] = stamps_[best];
      i = best;
    }
    keys_[i] = k;
    stamps_[i] = st;
  }
  std::vector<Key> keys_;
  std::vector<Stamps> stamps_;
};

/// The summaries of the merged clusters, in chunks of 4096 slots: no copy of the whole store
/// when it grows (a vector of them held 1.5x its live size while it doubled) and no slack beyond
/// one chunk (heaptrack figures in docs/scale.md).
template <class S>
class SlotStore {
 public:
  static constexpr std::uint32_t kShift = 12;
  S& operator[](std::uint32_t i) { return chunks_[i >> kShift][i & ((1u << kShift) - 1)]; }
  std::uint32_t add() {
    if ((size_ >> kShift) == chunks_.size()) chunks_.push_back(std::make_unique<S[]>(std::size_t{1} << kShift));
    return size_++;
  }

 private:
  std::vector<std::unique_ptr<S[]>> chunks_;
  std::uint32_t size_ = 0;
};

/// What the contraction keeps of a merged cluster's summary when the objective says it keeps it
/// whole (stores_whole()): O::Stored where the objective has one, else the summary itself.
template <class O>
struct StoredOf {
  using type = typename O::Summary;
};
template <class O>
  requires requires { typename O::Stored; }
struct StoredOf<O> {
  using type = typename O::Stored;
};

/// Edge property of the cluster graph for objectives that measure the boundary: 2 x the length
/// of the manifold mesh edges the two clusters share (kept equal on both arcs of a pair).
struct SharedLength {
  double shared2 = 0;
};

/// Edge property of the cluster graph for the other objectives: nothing. A type of this file's
/// own, so that the specialization below concerns the cluster graph alone.
struct NoEdgeData {};

}  // namespace
}  // namespace ptc

namespace boost::detail {
/// Boost 1.74 stores an arc of a directedS adjacency_list with vecS out-edge lists as its target
/// and a std::unique_ptr to its edge property, which add_edge allocates with new even for an
/// empty property: a pointer and a heap block per arc (docs/scale.md, "Boost's empty edge
/// properties"). Without a property the arc is its target alone.
/// Every arc then reports the same property address, so edge descriptors of this graph must not
/// be compared or removed by descriptor (the contraction removes arcs by target only).
/// The target is kept in 4 bytes (the contraction takes fewer than 2^30 triangles).
template <class Vertex>
class stored_edge_property<Vertex, ptc::NoEdgeData> {
 public:
  using property_type = ptc::NoEdgeData;
  stored_edge_property() = default;  // trivial (SmallArcs keeps arcs in a union)
  stored_edge_property(Vertex target, const ptc::NoEdgeData& = {}) : target_(static_cast<std::uint32_t>(target)) {}
  [[nodiscard]] Vertex get_target() const { return target_; }
  ptc::NoEdgeData& get_property() { return none_; }
  const ptc::NoEdgeData& get_property() const { return none_; }
  bool operator==(const stored_edge_property& x) const { return target_ == x.target_; }
  bool operator<(const stored_edge_property& x) const { return target_ < x.target_; }

 private:
  std::uint32_t target_;
  static inline ptc::NoEdgeData none_{};
};
}  // namespace boost::detail

namespace ptc {
namespace {

/// The cluster graph (contraction.h, "Graph"): a Boost.Graph adjacency_list whose vertices are the
/// clusters (vertex c = the cluster whose id is c; a dead cluster is an isolated vertex) and whose
/// arcs come in pairs (c -> x and x -> c for every adjacent pair). directedS with vector-like
/// out-edge lists: no global edge list (undirectedS keeps one in a std::list, a node allocation
/// per edge). Without an edge property (Acc, Naive) an arc is its target in 4 bytes (NoEdgeData)
/// and the out-edge list a SmallArcs (three arcs in place); with one (GWH01) a std::vector.
template <bool kBoundary>
using ClusterGraph =
    boost::adjacency_list<std::conditional_t<kBoundary, boost::vecS, SmallArcsS>, boost::vecS, boost::directedS,
                          boost::no_property, std::conditional_t<kBoundary, SharedLength, NoEdgeData>>;
static_assert(sizeof(typename decltype(std::declval<ClusterGraph<false>::stored_vertex&>().m_out_edges)::value_type) ==
                  sizeof(std::uint32_t),
              "an arc of the cluster graph without a boundary term is its target alone, in 4 bytes (NoEdgeData)");
static_assert(sizeof(ClusterGraph<false>::stored_vertex) == 20, "a vertex of the cluster graph: SmallArcs in place");

}  // namespace

// The whole run, inlined into contract_clusters, or for Acc into each of contract_clusters_acc's
// instruction-set clones (toolkit/core/isa.h).
template <ClusterObjective O>
[[gnu::always_inline]] inline ClusterRun contract_impl(const ClusterTables& tb, O& objective,
                                                       const ContractionOptions& options, const ProgressFn& progress) {
  using Summary = typename O::Summary;
  using Evaluation = typename O::Evaluation;
  const std::uint32_t T = tb.triangle_count();
  ClusterRun run;
  if (T == 0) {
    if (progress) progress(1.0);
    return run;
  }
  if (T >= (1u << 30))
    throw std::invalid_argument("contraction: at most 2^30 - 1 triangles (" + std::to_string(T) + " given)");

  // ---- Clusters: one per triangle. A singleton {t} has no stored lists (its member is t, its
  // vertices those of triangle t, made when needed); a merged cluster owns one block [member
  // count, vertex count, summary slot, members..., vertices...] (8 bytes a triangle for the
  // handles, where two vectors each were 48, and one allocation per merge instead of two or three).
  constexpr std::size_t kHead = 3;
  std::vector<std::unique_ptr<std::uint32_t[]>> lists(T);
  // changed[c]: the number of merges done when cluster c last changed (0: never), kDead once it
  // is merged into another. An entry is current while both its clusters are unchanged since it
  // was pushed (one array for what a version count and an alive flag per cluster did).
  constexpr std::uint32_t kDead = 0xffffffffu;
  std::vector<std::uint32_t> changed(T, 0);
  std::uint32_t alive_count = T;
  // Summaries: a merged cluster's is kept in a slot; a singleton's is made when it is needed
  // (objective.single gives the same values every time), and the last ones made are kept in a
  // small direct-mapped cache: half of the singletons a contraction evaluates were evaluated a
  // few merges before (their neighbours merge one after the other), and an Acc singleton's
  // summary (its 26-DOP rounded to floats, its box) costs more than a copy. One per triangle
  // would be 3.4 GB at 13M triangles (256 bytes each). The pair in use never shares a cache entry
  // (pair_summaries); the other of two colliding singletons goes to the scratch summary.
  // A merged summary is kept whole, or in the objective's smaller Stored form when that keeps it
  // whole (Acc without the DOP bound: 176 bytes instead of 256; made whole again in `expanded`,
  // one per role of pair_summaries).
  constexpr std::uint32_t kNoSlot = 0xffffffffu;
  std::vector<std::uint32_t> free_slots;
  constexpr bool kHasStored = requires { typename O::Stored; };
  bool use_stored = false;
  if constexpr (kHasStored) use_stored = objective.stores_whole();
  SlotStore<Summary> merged;                           // unless use_stored
  SlotStore<typename StoredOf<O>::type> merged_stored;  // if use_stored
  Summary expanded[2];
  constexpr int kSingleCacheBits = 10;  // 1024 summaries (264 KiB for Acc)
  std::vector<Summary> single_cache(std::size_t{1} << kSingleCacheBits);
  std::vector<std::uint32_t> single_tag(single_cache.size(), kNoSlot);
  Summary scratch;
  // The summary of cluster c; `pinned` is a cache entry that must not be overwritten (in use);
  // `role` picks the buffer of a stored summary made whole.
  auto summary_ptr = [&](std::uint32_t c, std::size_t pinned, int role) -> std::pair<const Summary*, std::size_t> {
    if (const std::uint32_t* l = lists[c].get()) {
      if constexpr (kHasStored) {
        if (use_stored) {
          O::expand(merged_stored[l[2]], expanded[role]);
          return {&expanded[role], ~std::size_t{0}};
        }
      }
      return {&merged[l[2]], ~std::size_t{0}};
    }
    const std::size_t h = (c * 2654435761u) >> (32 - kSingleCacheBits);
    if (single_tag[h] == c) return {&single_cache[h], h};
    if (h == pinned) {
      scratch = objective.single(c);
      return {&scratch, ~std::size_t{0}};
    }
    single_cache[h] = objective.single(c);
    single_tag[h] = c;
    return {&single_cache[h], h};
  };
  auto pair_summaries = [&](std::uint32_t a, std::uint32_t b) -> std::pair<const Summary&, const Summary&> {
    const auto [sa, ha] = summary_ptr(a, ~std::size_t{0}, 0);
    const Summary* sb = summary_ptr(b, ha, 1).first;
    return {*sa, *sb};
  };
  // The member and vertex lists of cluster c; a singleton's are written into `s`, which must
  // outlive the spans (make_ctx keeps one per cluster of the pair; no per-triangle arrays for them).
  struct SingleLists {
    std::uint32_t member = 0;
    std::uint32_t verts[3] = {0, 0, 0};
  };
  using Ids = std::span<const std::uint32_t>;
  auto lists_of = [&](std::uint32_t c, SingleLists& s, Ids& members, Ids& verts) {
    if (const std::uint32_t* l = lists[c].get()) {
      members = Ids(l + kHead, l[0]);
      verts = Ids(l + kHead + l[0], l[1]);
    } else {
      s.member = c;
      members = Ids(&s.member, 1);
      verts = Ids(s.verts, static_cast<std::size_t>(tb.distinct_vertices(c, s.verts)));
    }
  };

  // ---- Adjacency: the dual graph (ClusterTables' CSR; the same pairs as build_dual_graph,
  // tested) as the Boost.Graph cluster graph, with 2 x the length of the manifold mesh edges
  // shared when the objective measures the boundary.
  // Lean tables (ClusterTables::build lean) have no neighbour lists: they are made here for the
  // graph and freed before the queue and the summaries take their room.
  std::vector<std::uint32_t> own_offsets, own_neighbours;
  if (tb.lean) build_neighbours(tb.triangles, tb.positions.size(), own_offsets, own_neighbours);
  const std::vector<std::uint32_t>& nb_offsets = tb.lean ? own_offsets : tb.neighbour_offsets;
  const std::vector<std::uint32_t>& nbrs = tb.lean ? own_neighbours : tb.neighbours;
  using Graph = ClusterGraph<O::kUsesBoundary>;
  Graph g(T);
  std::size_t adj_total = 0;  // arcs in g = 2 x live pairs
  for (std::uint32_t t = 0; t < T; ++t) {
    const std::span<const std::uint32_t> ns(nbrs.data() + nb_offsets[t], nbrs.data() + nb_offsets[t + 1]);
    // Exactly the room for t's arcs (growth by doubling left room for four: heaptrack, docs/scale.md).
    g.out_edge_list(t).reserve(ns.size());
    for (std::uint32_t u : ns) boost::add_edge(t, u, g);  // symmetric: both arcs
    adj_total += ns.size();
    if constexpr (O::kUsesBoundary) {
      std::uint32_t es[3];
      const int ne = tb.distinct_edges(t, es);
      for (int i = 0; i < ne; ++i) {
        if (tb.edges.valence(es[i]) != 2) continue;  // non-manifold edges: counted per merge (nm lists)
        const auto ts = tb.edges.triangles_of(es[i]);
        const std::uint32_t u = ts[0] == t ? ts[1] : ts[0];
        const auto [e, found] = boost::edge(t, u, g);
        if (found) g[e].shared2 += 2.0 * tb.edge_length[es[i]];
      }
    }
  }
  std::vector<std::uint32_t>().swap(own_offsets);
  std::vector<std::uint32_t>().swap(own_neighbours);
  // Non-manifold edges (valence >= 3) per cluster, and a union-find to count their triangles per
  // cluster (only needed by objectives that measure the boundary, and only on such meshes).
  std::vector<std::vector<std::uint32_t>> nm;
  std::vector<std::uint32_t> parent;
  bool any_nm = false;
  if constexpr (O::kUsesBoundary) {
    for (std::uint32_t e = 0; e < tb.edges.edge_count(); ++e)
      if (tb.edges.valence(e) >= 3) {
        if (!any_nm) nm.resize(T);
        any_nm = true;
        for (std::uint32_t t : tb.edges.triangles_of(e)) nm[t].push_back(e);
      }
    if (any_nm) {
      parent.resize(T);
      for (std::uint32_t t = 0; t < T; ++t) parent[t] = t;
    }
  }
  auto find = [&](std::uint32_t t) {
    while (parent[t] != t) t = parent[t] = parent[parent[t]];  // path halving
    return t;
  };

  // ---- MergeContext with vertex stamps (the stamped cluster is cached across calls).
  std::vector<std::uint32_t> vstamp(tb.positions.size(), 0);
  std::uint32_t stamp = 0, stamped = 0xffffffffu, stamped_changed = 0;
  std::vector<std::uint32_t> added, shared;
  auto shared2_of = [&](std::uint32_t a, std::uint32_t b) {
    if constexpr (O::kUsesBoundary) {
      const auto [e, found] = boost::edge(a, b, g);
      return found ? g[e].shared2 : 0.0;
    } else {
      return 0.0;
    }
  };
  // The context of the pair (x, y) in its canonical roles, returned as {a, b}: `a` is the
  // cluster with more vertices (ties: the smaller id), so that a pair is always evaluated the
  // same way (bit-identical scores at push and at pop).
  SingleLists single_x, single_y;  // the lists of make_ctx's x and y when they are singletons
  auto make_ctx = [&](std::uint32_t x, std::uint32_t y, MergeContext& ctx) -> std::pair<std::uint32_t, std::uint32_t> {
    Ids mx, vx, my, vy;
    lists_of(x, single_x, mx, vx);
    lists_of(y, single_y, my, vy);
    const bool x_is_a = vx.size() > vy.size() || (vx.size() == vy.size() && x < y);
    const std::uint32_t a = x_is_a ? x : y, b = x_is_a ? y : x;
    const Ids ma = x_is_a ? mx : my, va = x_is_a ? vx : vy, mb = x_is_a ? my : mx, vb = x_is_a ? vy : vx;
    if (stamped != a || stamped_changed != changed[a]) {
      if (++stamp == 0) {  // wrapped: clear
        std::fill(vstamp.begin(), vstamp.end(), 0u);
        stamp = 1;
      }
      for (std::uint32_t v : va) vstamp[v] = stamp;
      stamped = a;
      stamped_changed = changed[a];
    }
    added.clear();
    shared.clear();
    for (std::uint32_t v : vb) (vstamp[v] == stamp ? shared : added).push_back(v);
    double removed = 0;
    if constexpr (O::kUsesBoundary) {
      removed = shared2_of(a, b);
      if (any_nm && !nm[a].empty() && !nm[b].empty()) {
        auto ia = nm[a].begin(), ib = nm[b].begin();
        while (ia != nm[a].end() && ib != nm[b].end()) {
          if (*ia < *ib) {
            ++ia;
          } else if (*ib < *ia) {
            ++ib;
          } else {  // an edge of valence >= 3 used by both: count its triangles in a and in b
            int na = 0, nb = 0;
            for (std::uint32_t t : tb.edges.triangles_of(*ia)) {
              const std::uint32_t r = find(t);
              na += r == a;
              nb += r == b;
            }
            removed += tb.edge_length[*ia] * ((na == 1 ? 1.0 : 0.0) + (nb == 1 ? 1.0 : 0.0));
            ++ia;
            ++ib;
          }
        }
      }
    }
    ctx.a_triangles = ma;
    ctx.b_triangles = mb;
    ctx.a_vertices = va;
    ctx.added = added;
    ctx.shared = shared;
    ctx.vertex_count = static_cast<std::uint32_t>(va.size() + added.size());
    ctx.boundary_removed = removed;
    return {a, b};
  };

  // ---- The queue.
  EntryHeap heap;
  // Live pairs = adj_total / 2, and a live pair has at most one current entry; stale entries are
  // purged once the heap holds 1.25x the live pairs (below), so this capacity is never exceeded
  // (live pairs only decrease) and the heap is never copied to grow.
  auto purge_above = [&] { return options.purge_often ? adj_total / 2 + 8 : adj_total / 2 + adj_total / 8 + 1024; };
  const std::size_t push_room = options.purge_often ? 8 : 65536;  // + the pushes of the merge before a purge
  heap.reserve(purge_above() + push_room);
  std::uint32_t merges = 0;  // merges done (the push time of the entries made now)
  auto make_entry = [&](std::uint32_t x, std::uint32_t y, double score, std::uint32_t key_kind) {
    const std::uint32_t lo = std::min(x, y), hi = std::max(x, y);
    return Entry{score, (std::uint64_t{lo} << 32) | hi, merges | key_kind};
  };
  // Evaluates the pair (x, y) cheaply; false when it deserves no entry (illegal, or never positive).
  auto entry_of = [&](std::uint32_t x, std::uint32_t y, Entry& out) {
    MergeContext ctx;
    const auto [a, b] = make_ctx(x, y, ctx);
    if (!objective.legal(ctx)) return false;
    const auto [sa, sb] = pair_summaries(a, b);
    const Evaluation ev = objective.evaluate(sa, sb, ctx, Precision::UpperBoundAllowed);
    ++(ev.exact ? run.exact_evaluations : run.bound_evaluations);
    if (O::kMergeOnlyPositive && !(ev.score > 0.0)) return false;
    std::uint32_t kind = ev.exact ? kExactBit : 0u;
    if constexpr (requires { ev.settled; })
      if (ev.settled) kind = kSupportBit;  // SupportBound would give the same key
    out = make_entry(a, b, ev.score, kind);
    return true;
  };
  for (std::uint32_t t = 0; t < T; ++t)
    for (const auto arc : boost::make_iterator_range(boost::out_edges(t, g))) {
      const auto x = static_cast<std::uint32_t>(boost::target(arc, g));
      Entry e;
      if (x > t && entry_of(t, x, e)) heap.append(e);
    }
  heap.heapify();
  auto current = [&](const Entry& e) {
    const auto lo = static_cast<std::uint32_t>(e.pair >> 32), hi = static_cast<std::uint32_t>(e.pair);
    const std::uint32_t pushed = e.stamp & ~kKeyBits;  // (kDead is above every push time)
    return changed[lo] <= pushed && changed[hi] <= pushed;
  };

  // ---- A direct-mapped cache of the exact evaluations of re-inserted entries, so that an entry
  // that waited does not pay for its evaluation twice when it comes back to the top. An
  // objective that says which part of an evaluation is dear (Acc: the sphere, O::Known) has
  // only that kept, and the rest made again (evaluate_with): 48-byte entries, so many more of
  // them, one per eight triangles up to 2^20 (docs/scale.md, "Contraction time on one thread").
  constexpr bool kKnown = requires(const Evaluation& e) { O::known_of(e); };
  auto cache_value = [](const Evaluation& ev) {  // what the cache keeps: the objective's Known, or all of it
    if constexpr (kKnown) return O::known_of(ev);
    else return ev;
  };
  using CacheValue = decltype(cache_value(std::declval<const Evaluation&>()));
  struct CacheSlot {
    std::uint64_t pair = ~std::uint64_t{0};
    std::uint32_t stamp = 0;
    CacheValue value{};
  };
  const int cache_bits = kKnown ? std::clamp(static_cast<int>(std::bit_width(T / 8u)), 12, 20) : 14;
  std::vector<CacheSlot> cache(std::size_t{1} << cache_bits);

  // ---- Contract.
  const std::uint64_t report_every = std::max<std::uint64_t>(1, T / 256);
  // During a merge, bit 30 of changed[x] marks the neighbours x of lo (push times stay below
  // 2^30, and a neighbour is alive), which spares an array per cluster.
  constexpr std::uint32_t kNeighbourOfLo = 0x40000000u;
  std::uint64_t pops = 0;
  while (!heap.empty()) {
    if (options.target_clusters > 0 && alive_count <= options.target_clusters) break;
    // Ctrl-C between the progress steps too: a step of T/256 merges takes minutes where the
    // clusters grow large (each merge evaluates the merged cluster against all its neighbours).
    if ((++pops & 63) == 0) throw_if_cancelled();
    const Entry top = heap.top();
    heap.pop();
    if (!current(top)) continue;  // stale: lazy deletion
    const auto lo = static_cast<std::uint32_t>(top.pair >> 32), hi = static_cast<std::uint32_t>(top.pair);
    MergeContext ctx;
    const auto [a, b] = make_ctx(lo, hi, ctx);
    if (!objective.legal(ctx)) continue;  // re-check after the pop
    const bool exact_key = (top.stamp & kExactBit) != 0;
    CacheSlot& slot = cache[(top.pair * 0x9E3779B97F4A7C15ull) >> (64 - cache_bits)];
    Evaluation ev;
    bool have = false;
    if (exact_key && slot.pair == top.pair && slot.stamp == top.stamp) {
      // evaluated when it was re-inserted (the same value evaluate() gives again)
      if constexpr (kKnown) {
        const auto [sa, sb] = pair_summaries(a, b);
        ev = objective.evaluate_with(sa, sb, ctx, slot.value);
      } else {
        ev = slot.value;
      }
      have = true;
    } else if (options.support_level && (top.stamp & kKeyBits) == 0) {
      // The key is the O(1) bound: first the bound from three points of the union
      // (Precision::SupportBound). Most such pairs rank below the next entry with it and wait
      // without their exact sphere (docs/scale.md, "Contraction time on one thread"). Which pair
      // merges does not depend on the bounds: it is the one whose exact score ranks first.
      const auto [sa, sb] = pair_summaries(a, b);
      ev = objective.evaluate(sa, sb, ctx, Precision::SupportBound);
      ++(ev.exact ? run.exact_evaluations : run.bound_evaluations);
      have = ev.exact;
      if (!ev.exact) {
        if (O::kMergeOnlyPositive && !(ev.score > 0.0)) continue;
        const Entry bound = make_entry(a, b, ev.score, kSupportBit);
        if (!heap.empty() && ranks_below(bound.score, bound.pair, heap.top().score, heap.top().pair)) {
          heap.push(bound);
          continue;
        }
      }
    }
    if (!have) {
      const auto [sa, sb] = pair_summaries(a, b);
      ev = objective.evaluate(sa, sb, ctx, Precision::Exact);
      ++run.exact_evaluations;
    }
    if (!exact_key) {  // the key was an upper bound
      if (O::kMergeOnlyPositive && !(ev.score > 0.0)) continue;
      const Entry exact = make_entry(a, b, ev.score, kExactBit);
      if (!heap.empty() && ranks_below(exact.score, exact.pair, heap.top().score, heap.top().pair)) {
        heap.push(exact);  // another entry ranks higher: wait
        slot = {exact.pair, exact.stamp, cache_value(ev)};
        continue;
      }
    }

    // Merge hi into lo (the smaller id survives).
    const std::uint32_t keep = lo, gone = hi;
    std::uint32_t slot_keep = kNoSlot;  // the merged summary's slot (in keep's new block)
    {
      const auto [sa, sb] = pair_summaries(a, b);
      Summary m = objective.merge(sa, sb, ctx, ev);
      slot_keep = lists[keep] ? lists[keep][2] : kNoSlot;
      std::uint32_t slot_gone = lists[gone] ? lists[gone][2] : kNoSlot;
      if (slot_keep == kNoSlot) std::swap(slot_keep, slot_gone);  // reuse gone's slot, if it had one
      if (slot_gone != kNoSlot) free_slots.push_back(std::exchange(slot_gone, kNoSlot));
      if (slot_keep == kNoSlot) {
        if (free_slots.empty()) {
          slot_keep = use_stored ? merged_stored.add() : merged.add();
        } else {
          slot_keep = free_slots.back();
          free_slots.pop_back();
        }
      }
      if constexpr (kHasStored) {
        if (use_stored) merged_stored[slot_keep] = O::stored(m);
        else merged[slot_keep] = std::move(m);
      } else {
        merged[slot_keep] = std::move(m);
      }
    }
    {
      // Members and vertices ascending (members: the union of two ascending lists, so the
      // objective's sums in triangle order merge them instead of sorting; AccObjective's
      // recomputed normal sums of large closed clusters spent most of a run in that sort).
      const Ids mk = ctx.a_triangles, mg = ctx.b_triangles;
      const Ids va = ctx.a_vertices;
      const std::size_t nm_total = mk.size() + mg.size(), nv_total = va.size() + added.size();
      auto block = std::make_unique_for_overwrite<std::uint32_t[]>(kHead + nm_total + nv_total);
      block[0] = static_cast<std::uint32_t>(nm_total);
      block[1] = static_cast<std::uint32_t>(nv_total);
      block[2] = slot_keep;
      std::uint32_t* out = std::merge(mk.begin(), mk.end(), mg.begin(), mg.end(), block.get() + kHead);
      std::merge(va.begin(), va.end(), added.begin(), added.end(), out);
      for (std::uint32_t v : added) vstamp[v] = stamp;  // the stamps now mark the union
      lists[keep] = std::move(block);
      lists[gone].reset();
    }
    if (any_nm) {
      if (!nm[gone].empty()) {
        std::vector<std::uint32_t> u;
        std::set_union(nm[keep].begin(), nm[keep].end(), nm[gone].begin(), nm[gone].end(), std::back_inserter(u));
        nm[keep].swap(u);
        std::vector<std::uint32_t>().swap(nm[gone]);
      }
      parent[gone] = keep;
    }

    // Adjacency, on the Boost graph: lo's arcs to hi and hi's arcs go; every other neighbour x of
    // hi becomes a neighbour of lo (shared lengths summed when x already was one).
    ++merges;  // entries pushed from here on are younger than this merge
    for (const auto arc : boost::make_iterator_range(boost::out_edges(lo, g)))
      changed[boost::target(arc, g)] |= kNeighbourOfLo;
    boost::remove_edge(lo, hi, g);
    --adj_total;
    for (const auto arc : boost::make_iterator_range(boost::out_edges(hi, g))) {
      const auto x = static_cast<std::uint32_t>(boost::target(arc, g));
      if (x == lo) continue;
      boost::remove_edge(x, hi, g);
      if (changed[x] & kNeighbourOfLo) {  // already adjacent to lo
        if constexpr (O::kUsesBoundary) {
          const double w = g[arc].shared2;
          g[boost::edge(lo, x, g).first].shared2 += w;
          g[boost::edge(x, lo, g).first].shared2 += w;
        }
        --adj_total;  // x -> hi went (hi -> x: below)
      } else {
        if constexpr (O::kUsesBoundary) {
          boost::add_edge(lo, x, SharedLength{g[arc].shared2}, g);
          boost::add_edge(x, lo, SharedLength{g[arc].shared2}, g);
        } else {
          boost::add_edge(lo, x, g);
          boost::add_edge(x, lo, g);
        }
        ++adj_total;  // x -> hi went, lo -> x and x -> lo came
      }
    }
    for (const auto arc : boost::make_iterator_range(boost::out_edges(lo, g)))
      changed[boost::target(arc, g)] &= ~kNeighbourOfLo;
    adj_total -= boost::out_degree(hi, g);
    boost::clear_out_edges(hi, g);
    g.out_edge_list(hi).shrink_to_fit();  // a dead cluster keeps no storage
    changed[gone] = kDead;
    changed[keep] = merges;
    stamped = keep;  // the stamps mark V(keep) (see above)
    stamped_changed = changed[keep];
    --alive_count;
    if (options.record_merges) run.merges.push_back({keep, gone, ev.score});
    if (merges % report_every == 0 && progress) progress(static_cast<double>(merges) / T);

    for (const auto arc : boost::make_iterator_range(boost::out_edges(keep, g))) {
      Entry e;
      if (entry_of(keep, static_cast<std::uint32_t>(boost::target(arc, g)), e)) heap.push(e);
    }
    // Purge stale entries once the heap holds 1.25x the live pairs (memory O(live pairs)). After a
    // purge at most the live pairs are left, so at least a quarter as many pushes come before the
    // next one: O(1) amortised per push.
    if (heap.size() > purge_above()) heap.purge([&](const Entry& e) { return !current(e); }, purge_above() + push_room);
  }

  run.labels.assign(T, 0);
  for (std::uint32_t c = 0; c < T; ++c) {
    if (changed[c] == kDead) continue;
    if (const std::uint32_t* l = lists[c].get()) {
      for (std::uint32_t t : Ids(l + kHead, l[0])) run.labels[t] = c;
    } else {
      run.labels[c] = c;
    }
  }
  if (progress) progress(1.0);
  return run;
}

namespace detail {
[[gnu::flatten]] PTC_ISA_CLONES
ClusterRun contract_clusters_acc(const ClusterTables& tb, AccObjective& objective, const ContractionOptions& options,
                                 const ProgressFn& progress) {
  return contract_impl(tb, objective, options, progress);
}
}  // namespace detail

template <ClusterObjective O>
ClusterRun contract_clusters(const ClusterTables& tb, O& objective, const ContractionOptions& options,
                             const ProgressFn& progress) {
  if constexpr (std::is_same_v<O, AccObjective>)
    return detail::contract_clusters_acc(tb, objective, options, progress);
  else
    return contract_impl(tb, objective, options, progress);
}

template ClusterRun contract_clusters<AccObjective>(const ClusterTables&, AccObjective&, const ContractionOptions&,
                                                    const ProgressFn&);
template ClusterRun contract_clusters<NaiveObjective>(const ClusterTables&, NaiveObjective&,
                                                      const ContractionOptions&, const ProgressFn&);
template ClusterRun contract_clusters<Gwh01Objective>(const ClusterTables&, Gwh01Objective&,
                                                      const ContractionOptions&, const ProgressFn&);

}  // namespace ptc
