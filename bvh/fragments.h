// Parallel tree walks that give the sequential walk's nodes in the same order (internal to bvh/:
// the binned SAH build, the collapse to 4-wide nodes and the regroup to 8-wide ones).
//
// The walks this serves allocate nodes in an order where the descendants of a node (without
// the node itself) are contiguous and follow the node's allocation by the same walk over that
// node's subtree alone: the top-down SAH build emits in pre-order (a node, then its subtree);
// the collapse and the regroup allocate a node's children when they open it and open nodes
// last-in first-out. A parallel form cuts the tree into fragments: a fragment walks the subtree
// of its root alone, numbering its nodes from 0 (the root), and defers some items to new
// fragments; a deferred item's node stays a placeholder. Splicing (splice_fragments) puts a
// fragment's local node i > 0 at desc_start + i - 1, plus the nodes of the deferred subtrees
// whose descendants the sequential walk would have allocated before it (the holes whose `cut`,
// the number of local nodes allocated when the walk met them, is at most i); the deferred root
// lands where its placeholder would, and its descendants right after the nodes allocated before
// its cut. The same nodes in the same order as the sequential walk, at any thread count.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/parallel_for_each.h>

namespace ptc::bvh {

/// A piece of a walk: the subtree of `root` walked alone. `holes` are the items it deferred, in
/// the order the walk met them (their cuts ascend).
template <class Node, class Item>
struct Fragment {
  Item root{};
  std::vector<Node> nodes;  // (not an AlignedVector, which puts arrays of 256 KiB or more on whole 2 MiB pages)
  double cost = 0.0;        // what a walk reports: the SAH build's cost (unused: the tree's is summed after),
  std::uint32_t depth = 0, leaves = 0;  // the wide walks' levels and leaf children
  struct Hole {
    std::uint32_t local, cut;  // the placeholder's local index; the local nodes allocated by then
    Fragment* child;
  };
  std::vector<Hole> holes;
  std::vector<std::uint32_t> hole_locals;  // sorted: the placeholders, which the splice skips
  std::vector<std::uint64_t> shift;        // shift[h]: nodes the holes before h add (size - 1 each)
  std::uint64_t size = 0, root_pos = 0, desc_start = 0;

  /// Final position of local node i (after splice_fragments' positions pass).
  [[nodiscard]] std::uint64_t position(std::uint32_t i) const {
    if (i == 0) return root_pos;
    std::size_t h = 0;
    while (h < holes.size() && holes[h].cut <= i) ++h;
    return desc_start + (i - 1) + shift[h];
  }
};

/// Fragments kept from one walk to the next (their node arrays too), handed out under a lock, in
/// the order they are made: a fragment before those it defers to.
template <class Frag>
struct FragmentPool {
  std::vector<std::unique_ptr<Frag>> all;
  std::size_t used = 0;
  std::mutex mutex;
  Frag* take() {
    const std::lock_guard<std::mutex> lock(mutex);
    if (used == all.size()) all.push_back(std::make_unique<Frag>());
    Frag* f = all[used++].get();
    f->nodes.clear(), f->holes.clear(), f->hole_locals.clear(), f->shift.clear();
    f->cost = 0.0, f->depth = 0, f->leaves = 0;
    return f;
  }
};

/// What a fragment's walk defers through: add(local, cut, root) makes the fragment of `root`,
/// records the hole and feeds the fragment to the parallel loop.
template <class Frag>
struct FragmentFeed {
  FragmentPool<Frag>& pool;
  Frag& f;
  tbb::feeder<Frag*>& feeder;
  template <class Item>
  void add(std::uint32_t local, std::uint32_t cut, const Item& root) {
    Frag* c = pool.take();
    c->root = root;
    f.holes.push_back({local, cut, c});
    feeder.add(c);
  }
};

/// Runs walk(fragment, feed) over the fragment of `root` and every fragment fed from it, on the
/// caller's threads.
template <class Frag, class Item, class Walk>
void walk_fragments(FragmentPool<Frag>& pool, const Item& root, const Walk& walk) {
  pool.used = 0;
  Frag* top = pool.take();
  top->root = root;
  Frag* const start[1] = {top};
  tbb::parallel_for_each(start, start + 1, [&](Frag* f, tbb::feeder<Frag*>& feeder) {
    FragmentFeed<Frag> feed{pool, *f, feeder};
    walk(*f, feed);
  });
}

/// The fragments spliced into out[base ..) (resized to fit); remap(node, fragment) makes a
/// node's child indices final through fragment.position. Returns the nodes written.
template <class Frag, class Out, class Remap>
std::uint64_t splice_fragments(FragmentPool<Frag>& pool, Out& out, std::uint64_t base, const Remap& remap) {
  const std::size_t F = pool.used;
  for (std::size_t i = F; i-- > 0;) {  // sizes, children first
    Frag& f = *pool.all[i];
    f.size = f.nodes.size();
    f.shift.assign(f.holes.size() + 1, 0);
    f.hole_locals.clear();
    for (std::size_t h = 0; h < f.holes.size(); ++h) {
      f.size += f.holes[h].child->size - 1;
      f.shift[h + 1] = f.shift[h] + f.holes[h].child->size - 1;
      f.hole_locals.push_back(f.holes[h].local);
    }
    std::sort(f.hole_locals.begin(), f.hole_locals.end());
  }
  Frag& top = *pool.all[0];
  top.root_pos = base, top.desc_start = base + 1;
  for (std::size_t i = 0; i < F; ++i) {  // positions, parents first
    const Frag& f = *pool.all[i];
    for (std::size_t h = 0; h < f.holes.size(); ++h) {
      Frag& c = *f.holes[h].child;
      c.root_pos = f.position(f.holes[h].local);
      c.desc_start = f.desc_start + (f.holes[h].cut - 1) + f.shift[h];
    }
  }
  out.resize(base + top.size);
  tbb::parallel_for(std::size_t{0}, F, [&](std::size_t i) {
    const Frag& f = *pool.all[i];
    std::size_t skip = 0;
    for (std::uint32_t j = 0; j < f.nodes.size(); ++j) {
      if (skip < f.hole_locals.size() && f.hole_locals[skip] == j) {  // (its subtree's fragment writes it)
        ++skip;
        continue;
      }
      auto nd = f.nodes[j];
      remap(nd, f);
      out[f.position(j)] = nd;
    }
  });
  return top.size;
}

}  // namespace ptc::bvh
