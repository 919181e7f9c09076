#include "toolkit/clustering/growth.h"
#include "toolkit/core/cancel.h"

#include <algorithm>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "toolkit/core/isa.h"
#include "toolkit/geometry/morton.h"

namespace ptc {

namespace {

constexpr std::uint32_t kNone = 0xffffffffu;
/// During the run an untaken triangle's label holds kNone, or kFrontier | c while it is in cluster
/// c's frontier; a taken one holds its cluster (< kFrontier). One array where a label array and
/// a frontier stamp array were two: the neighbour checks of a step read one cache line, not two
/// (at 13M triangles both were 53 MB, far beyond the caches).
constexpr std::uint32_t kFrontier = 0x80000000u;
[[nodiscard]] inline bool untaken(std::uint32_t label) { return label >= kFrontier; }

/// The start rules of growth.h. FewestFree keeps the untaken triangles in an indexed binary
/// min-heap on (free count, Morton rank): a taken triangle leaves it, a neighbour's key drops in
/// place (8 bytes a triangle with the position table; a lazy heap that pushed a new entry per
/// change grew to 4 entries of 8 bytes per triangle at 13M triangles). Ranks are distinct, so
/// the minimum, and with it the order of starts, is the same as any heap's.
class StartPicker {
 public:
  StartPicker(const ClusterTables& tb, StartRule rule) : tb_(&tb), rule_(rule) {
    const std::uint32_t T = tb.triangle_count();
    if (rule == StartRule::IndexOrder) return;
    order_ = morton_order(tb.positions, tb.triangles, MortonGrid::Cube, tb.with_sums ? &tb.centroid_bounds : nullptr);
    if (rule != StartRule::FewestFree) return;
    rank_.resize(T);
    free_.resize(T);
    for (std::uint32_t r = 0; r < T; ++r) rank_[order_[r]] = r;
    for (std::uint32_t t = 0; t < T; ++t) free_[t] = static_cast<std::uint32_t>(tb.neighbours_of(t).size());
    std::vector<std::uint32_t>().swap(order_);  // FewestFree needs the ranks only
    heap_.resize(T);
    pos_.resize(T);
    for (std::uint32_t t = 0; t < T; ++t) heap_[t] = t;
    std::make_heap(heap_.begin(), heap_.end(), [&](std::uint32_t a, std::uint32_t b) { return key(b) < key(a); });
    for (std::uint32_t i = 0; i < T; ++i) pos_[heap_[i]] = i;
  }

  /// The next start triangle, or kNone when every triangle is taken.
  std::uint32_t next(const std::vector<std::uint32_t>& label) {
    const std::uint32_t T = tb_->triangle_count();
    switch (rule_) {
      case StartRule::IndexOrder:
        while (cursor_ < T && !untaken(label[cursor_])) ++cursor_;
        return cursor_ < T ? cursor_ : kNone;
      case StartRule::SpatialOrder:
        while (cursor_ < T && !untaken(label[order_[cursor_]])) ++cursor_;
        return cursor_ < T ? order_[cursor_] : kNone;
      case StartRule::FewestFree:
        return heap_.empty() ? kNone : heap_.front();  // every triangle in the heap is untaken
    }
    return kNone;
  }

  /// Triangle t was just taken (label[t] set): it leaves the heap, and its untaken neighbours
  /// lose a free neighbour.
  void taken(std::uint32_t t, const std::vector<std::uint32_t>& label) {
    if (rule_ != StartRule::FewestFree) return;
    remove(t);
    for (std::uint32_t u : tb_->neighbours_of(t)) {
      if (!untaken(label[u])) continue;
      --free_[u];
      sift_up(pos_[u]);
    }
  }

 private:
  [[nodiscard]] std::uint64_t key(std::uint32_t t) const { return (std::uint64_t{free_[t]} << 32) | rank_[t]; }
  void place(std::uint32_t i, std::uint32_t t) {
    heap_[i] = t;
    pos_[t] = i;
  }
  void sift_up(std::uint32_t i) {
    const std::uint32_t t = heap_[i];
    const std::uint64_t k = key(t);
    while (i > 0) {
      const std::uint32_t parent = (i - 1) / 2;
      if (key(heap_[parent]) <= k) break;
      place(i, heap_[parent]);
      i = parent;
    }
    place(i, t);
  }
  void sift_down(std::uint32_t i) {
    const auto n = static_cast<std::uint32_t>(heap_.size());
    const std::uint32_t t = heap_[i];
    const std::uint64_t k = key(t);
    for (;;) {
      std::uint32_t child = 2 * i + 1;
      if (child >= n) break;
      if (child + 1 < n && key(heap_[child + 1]) < key(heap_[child])) ++child;
      if (k <= key(heap_[child])) break;
      place(i, heap_[child]);
      i = child;
    }
    place(i, t);
  }
  void remove(std::uint32_t t) {
    const std::uint32_t i = pos_[t];
    const std::uint32_t last = heap_.back();
    heap_.pop_back();
    if (last == t) return;
    place(i, last);
    sift_down(i);
    sift_up(pos_[last]);
  }

  const ClusterTables* tb_;
  StartRule rule_;
  std::uint32_t cursor_ = 0;
  std::vector<std::uint32_t> order_, rank_, free_;
  std::vector<std::uint32_t> heap_, pos_;  // heap of untaken triangles; pos_[t] = t's index in it
};

}  // namespace

// The whole run, inlined into grow_clusters, or for Acc into each of grow_clusters_acc's
// instruction-set clones (toolkit/core/isa.h).
template <ClusterObjective O>
[[gnu::always_inline]] inline ClusterRun grow_impl(const ClusterTables& tb, O& objective, const GrowthOptions& options,
                                                   const ProgressFn& progress) {
  // (Checked here, inside the instruction-set clone: GCC 12 compiles a call to a target_clones
  // function as one that cannot throw, so a caller with a landing pad of its own terminates the
  // program when the clone throws.)
  if (tb.lean)  // growth reads the neighbour lists, areas and normals all the time
    throw std::logic_error("grow_clusters: the tables were built lean (ClusterTables::build lean)");
  using Summary = typename O::Summary;
  using Evaluation = typename O::Evaluation;
  const std::uint32_t T = tb.triangle_count();
  ClusterRun run;
  run.labels.assign(T, kNone);
  std::vector<std::uint32_t>& label = run.labels;
  if (T == 0) {
    if (progress) progress(1.0);
    return run;
  }
  if (T >= kFrontier)  // (cluster ids must stay below the frontier bit; 2^31 triangles need 24 GB of indices alone)
    throw std::invalid_argument("growth clusters at most 2^31 - 1 triangles (" + std::to_string(T) + " given)");

  // Acc's O(1) level in two passes (acc.h, growth_prepare / growth_key).
  constexpr bool kFast = requires { objective.growth_bound_applies(); };
  std::vector<std::uint32_t> vstamp(tb.positions.size(), kNone);  // vertex in cluster c <=> vstamp == c
  struct Candidate {  // a frontier triangle with what does not change while it waits
    std::uint32_t t;
    int nv, ne;
    std::uint32_t v[3];  // distinct vertices
    std::uint32_t e[3];  // distinct edges
    std::uint8_t in_k;   // bit i: v[i] is a vertex of the cluster (kept up to date: no stamp lookups)
    // What the candidate keeps of single(t). Acc (kFast): the box of t's vertices,
    // single(t).box; single(t) itself is made when evaluate() or merge() needs it (most
    // candidates only ever get the O(1) level; with an approximate sphere, whose evaluations are
    // all exact and dearer, a summary made per evaluation costs little). Other objectives: single(t).
    std::conditional_t<kFast, Box3, Summary> kept;
  };
  std::vector<Candidate> frontier;
  auto summary_of = [&](const Candidate& c) -> decltype(auto) {
    if constexpr (kFast) return objective.single(c.t);
    else return (c.kept);  // a reference
  };
  std::vector<std::uint32_t> members, verts;
  // The refinement queue: (key, triangle, frontier slot, precision level of the key).
  struct Keyed {
    double score;
    std::uint32_t t, slot;
    std::uint8_t level;
  };
  constexpr Precision kLevels[] = {Precision::UpperBoundAllowed, Precision::RefinedBound, Precision::TightBound,
                                   Precision::Exact};
  constexpr std::uint8_t kExactLevel = 3;
  // Queue order: higher key, then lower id. x (its key and id) ranks below y.
  auto ranks_below = [](double x_score, std::uint32_t x_t, const Keyed& y) {
    return x_score < y.score || (x_score == y.score && x_t > y.t);
  };
  std::vector<Keyed> queue;
  std::vector<Evaluation> evals;
  StartPicker picker(tb, options.start);
  bool fast_bound = false;
  using Query = std::conditional_t<kFast, AccObjective::GrowthQuery, int>;
  using Prepared = std::conditional_t<kFast, AccObjective::GrowthPrepared, int>;
  std::vector<Query> queries;
  std::vector<Prepared> prepared;
  std::vector<std::uint32_t> prep_at;  // frontier slot -> its query, or kNone
  if constexpr (kFast) fast_bound = options.objective_fast_level && objective.growth_bound_applies();
  const std::uint64_t report_every = std::max<std::uint64_t>(1, T / 256);
  std::uint64_t taken = 0;

  std::uint32_t cluster = 0;
  // The MergeContext of k + {c.t}; `added` and `shared` are the caller's buffers. Returned as one
  // aggregate with every field given: a default-constructed context filled in afterwards was
  // zeroed first (a `rep stos` of 96 bytes on every refinement; docs/scale.md).
  auto make_ctx = [&](const Candidate& c, std::uint32_t* added, std::uint32_t* shared) -> MergeContext {
    int na = 0, ns = 0;
    for (int i = 0; i < c.nv; ++i) ((c.in_k >> i) & 1 ? shared[ns++] : added[na++]) = c.v[i];
    double removed = 0;
    if constexpr (O::kUsesBoundary) {
      for (int i = 0; i < c.ne; ++i) {
        int n = 0;  // triangles of k on this edge
        for (std::uint32_t u : tb.edges.triangles_of(c.e[i]))
          if (u != c.t && label[u] == cluster) ++n;
        if (n > 0) removed += tb.edge_length[c.e[i]] * ((n == 1 ? 1.0 : 0.0) + 1.0);  // [n_k == 1] + [n_d == 1]
      }
    }
    return MergeContext{members,
                        {&c.t, 1},
                        verts,
                        {added, static_cast<std::size_t>(na)},
                        {shared, static_cast<std::size_t>(ns)},
                        static_cast<std::uint32_t>(verts.size() + static_cast<std::size_t>(na)),
                        removed};
  };
  // Inlined, so that it is compiled for the instruction set of the grow_clusters clone it is in.
  auto take = [&](std::uint32_t t) __attribute__((always_inline)) {
    label[t] = cluster;
    picker.taken(t, label);
    for (std::uint32_t u : tb.neighbours_of(t))
      if (untaken(label[u]) && label[u] != (kFrontier | cluster)) {
        label[u] = kFrontier | cluster;
        Candidate c{u, 0, 0, {}, {}, 0, {}};
        if constexpr (kFast) {
          c.kept = objective.triangle_box(u);
          // growth_prepare reads the candidate's normal and area at the next step, first from
          // tables far beyond the caches on a large mesh: ask for them now.
          __builtin_prefetch(tb.normal.data() + u);
          __builtin_prefetch(tb.area.data() + u);
        } else {
          c.kept = objective.single(u);
        }
        c.nv = tb.distinct_vertices(u, c.v);
        if constexpr (O::kUsesBoundary) c.ne = tb.distinct_edges(u, c.e);  // the edge map exists only then
        for (int i = 0; i < c.nv; ++i)
          if (vstamp[c.v[i]] == cluster) c.in_k = static_cast<std::uint8_t>(c.in_k | (1u << i));
        if constexpr (kFast)  // growth_key reads the learnt bound of the vertex the candidate adds
          for (int i = 0; i < c.nv; ++i)
            if (!((c.in_k >> i) & 1)) objective.prefetch_vertex(c.v[i]);
        frontier.push_back(std::move(c));
      }
    if (++taken % report_every == 0 && progress) progress(static_cast<double>(taken) / T);
    // Ctrl-C between the progress steps too: with a large MaxCount a step of T/256 triangles
    // can take minutes (each scores the cluster's whole frontier).
    if ((taken & 63) == 0) throw_if_cancelled();
  };

  for (std::uint32_t s; (s = picker.next(label)) != kNone; ++cluster) {
    frontier.clear();
    members.assign(1, s);
    {
      std::uint32_t v[3];
      const int nv = tb.distinct_vertices(s, v);
      verts.assign(v, v + nv);
      for (int i = 0; i < nv; ++i) vstamp[v[i]] = cluster;
    }
    Summary cur = objective.single(s);
    take(s);
    evals.resize(std::max(evals.size(), frontier.size()));

    for (;;) {
      // Best-first refinement: every legal candidate enters with its cheapest bound; the top of
      // the queue is refined one precision level at a time until the top is exact -- then no
      // other candidate can beat it (each key bounds its exact score from above; ties by id).
      queue.clear();
      if constexpr (kFast)
        if (fast_bound) {
          queries.clear();
          prep_at.assign(frontier.size(), kNone);
          for (std::size_t i = 0; i < frontier.size(); ++i) {
            const Candidate& c = frontier[i];
            // |added| = nv - |in_k| (a 3-bit mask; std::popcount is a libgcc call without POPCNT)
            if (c.nv - ((c.in_k & 1) + ((c.in_k >> 1) & 1) + ((c.in_k >> 2) & 1)) != 1) continue;
            int j = 0;
            while ((c.in_k >> j) & 1) ++j;
            prep_at[i] = static_cast<std::uint32_t>(queries.size());
            queries.push_back({c.t, c.v[j], &c.kept});
          }
          prepared.resize(std::max(prepared.size(), queries.size()));
          if (!queries.empty()) objective.growth_prepare(cur, queries, prepared.data());
        }
      // evaluate(cur, single(t), ctx, p) of the candidate in frontier slot i; Acc's candidates
      // that growth_prepare kept (one added vertex, no rare path) through growth_refine.
      auto evaluate_candidate = [&](std::size_t i, const MergeContext& ctx, Precision p) -> Evaluation {
        if constexpr (kFast)
          if (fast_bound && prep_at[i] != kNone && !prepared[prep_at[i]].general)
            return objective.growth_refine(cur, prepared[prep_at[i]], ctx, p);
        return objective.evaluate(cur, summary_of(frontier[i]), ctx, p);
      };
      for (std::size_t i = 0; i < frontier.size(); ++i) {
        if constexpr (kFast) {
          // Acc's O(1) level without evaluate()'s generality, for a candidate that adds one vertex
          // (the common case): the same key, or false for evaluate() to take over. Acc's legal()
          // is always true.
          if (fast_bound && prep_at[i] != kNone) {
            double key;
            if (objective.growth_key(prepared[prep_at[i]], queries[prep_at[i]].v,
                                     static_cast<std::uint32_t>(verts.size() + 1), key)) {
              ++run.bound_evaluations;
              queue.push_back({key, frontier[i].t, static_cast<std::uint32_t>(i), std::uint8_t{0}});
              continue;
            }
          }
        }
        std::uint32_t added[3], shared[3];
        const MergeContext ctx = make_ctx(frontier[i], added, shared);
        if (!objective.legal(ctx)) continue;
        const Evaluation ev = evaluate_candidate(i, ctx, kLevels[0]);
        ++(ev.exact ? run.exact_evaluations : run.bound_evaluations);
        if (ev.exact) evals[i] = ev;  // only an exact evaluation can be the answer (merge() reuses it)
        queue.push_back({ev.score, frontier[i].t, static_cast<std::uint32_t>(i),
                         ev.exact ? kExactLevel : std::uint8_t{0}});
      }
      // The queue is as long as the frontier (a few dozen at most): a linear scan for the top
      // beats a heap here.
      bool has = false;
      std::size_t top_at = 0;
      while (!queue.empty()) {
        // The top's key and id in locals: read back from the queue on every step, they went
        // through a stack slot.
        top_at = 0;
        double top_score = queue[0].score;
        std::uint32_t top_t = queue[0].t;
        for (std::size_t q = 1; q < queue.size(); ++q) {
          const Keyed& k = queue[q];
          if (ranks_below(top_score, top_t, k)) top_at = q, top_score = k.score, top_t = k.t;
        }
        Keyed& top = queue[top_at];
        if (O::kMergeOnlyPositive && !(top.score > 0.0)) break;  // every key, so every score, is <= 0
        if (top.level == kExactLevel) {
          has = true;
          break;
        }
        std::uint32_t added[3], shared[3];
        const MergeContext ctx = make_ctx(frontier[top.slot], added, shared);
        const Evaluation ev = evaluate_candidate(top.slot, ctx, kLevels[top.level + 1]);
        ++(ev.exact ? run.exact_evaluations : run.bound_evaluations);
        if (ev.exact || top.level + 1 == kExactLevel) evals[top.slot] = ev;
        top.score = ev.score;
        top.level = ev.exact || top.level + 1 == kExactLevel ? kExactLevel : static_cast<std::uint8_t>(top.level + 1);
      }
      if (!has) break;
      const std::size_t best_i = queue[top_at].slot;
      const std::uint32_t best_t = queue[top_at].t;
      const double best_score = queue[top_at].score;
      const Evaluation best_ev = evals[best_i];

      // Add best_t to the cluster.
      const std::uint32_t d = best_t;
      std::uint32_t added[3], shared[3];
      const MergeContext ctx = make_ctx(frontier[best_i], added, shared);
      cur = objective.merge(cur, summary_of(frontier[best_i]), ctx, best_ev);
      for (std::uint32_t v : ctx.added) {
        vstamp[v] = cluster;
        verts.insert(std::upper_bound(verts.begin(), verts.end(), v), v);
        for (Candidate& c : frontier)
          for (int i = 0; i < c.nv; ++i)
            if (c.v[i] == v) c.in_k = static_cast<std::uint8_t>(c.in_k | (1u << i));
      }
      members.push_back(d);
      if (options.record_merges) run.merges.push_back({cluster, d, best_score});
      frontier[best_i] = std::move(frontier.back());
      frontier.pop_back();
      take(d);
      if (evals.size() < frontier.size()) evals.resize(2 * frontier.size());
    }
  }
  if (progress) progress(1.0);
  return run;
}

namespace detail {
PTC_ISA_CLONES
ClusterRun grow_clusters_acc(const ClusterTables& tb, AccObjective& objective, const GrowthOptions& options,
                             const ProgressFn& progress) {
  return grow_impl(tb, objective, options, progress);
}
}  // namespace detail

template <ClusterObjective O>
ClusterRun grow_clusters(const ClusterTables& tb, O& objective, const GrowthOptions& options,
                         const ProgressFn& progress) {
  if constexpr (std::is_same_v<O, AccObjective>)
    return detail::grow_clusters_acc(tb, objective, options, progress);
  else
    return grow_impl(tb, objective, options, progress);
}

template ClusterRun grow_clusters<AccObjective>(const ClusterTables&, AccObjective&, const GrowthOptions&,
                                                const ProgressFn&);
template ClusterRun grow_clusters<NaiveObjective>(const ClusterTables&, NaiveObjective&, const GrowthOptions&,
                                                  const ProgressFn&);
template ClusterRun grow_clusters<Gwh01Objective>(const ClusterTables&, Gwh01Objective&, const GrowthOptions&,
                                                  const ProgressFn&);

}  // namespace ptc
