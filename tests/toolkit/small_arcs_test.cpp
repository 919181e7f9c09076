// SmallArcs (the contraction's out-edge list) against std::vector, operation by operation: random
// sequences of the operations Boost and the contraction use, across the switch from the three
// arcs in place to a heap block and back.
#include "toolkit/clustering/small_arcs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

namespace ptc {
namespace {

using Arcs = SmallArcs<std::uint32_t>;

void expect_same(const Arcs& a, const std::vector<std::uint32_t>& v, int step) {
  ASSERT_EQ(a.size(), v.size()) << "step " << step;
  EXPECT_EQ(a.empty(), v.empty()) << "step " << step;
  EXPECT_GE(a.capacity(), a.size()) << "step " << step;
  EXPECT_EQ(static_cast<std::size_t>(a.end() - a.begin()), v.size()) << "step " << step;
  for (std::size_t i = 0; i < v.size(); ++i) ASSERT_EQ(a.begin()[i], v[i]) << "step " << step << ", arc " << i;
}

TEST(SmallArcs, FreshListIsEmptyAndKeepsThreeArcsInPlace) {
  Arcs a;
  EXPECT_TRUE(a.empty());
  EXPECT_EQ(a.size(), 0u);
  EXPECT_EQ(a.begin(), a.end());
  EXPECT_EQ(a.capacity(), 3u);
  for (std::uint32_t x : {7u, 0u, 0xffffffffu}) a.push_back(x);
  EXPECT_EQ(a.capacity(), 3u);  // still in place
  const auto* inside = reinterpret_cast<const unsigned char*>(&a);
  const auto* first = reinterpret_cast<const unsigned char*>(a.begin());
  EXPECT_TRUE(first >= inside && first < inside + sizeof a) << "three arcs are kept in the object";
  a.push_back(9);
  EXPECT_GE(a.capacity(), 4u);
  expect_same(a, {7u, 0u, 0xffffffffu, 9u}, 0);
  a.erase(a.begin() + 1, a.begin() + 3);
  a.shrink_to_fit();  // two arcs: back in place
  EXPECT_EQ(a.capacity(), 3u);
  expect_same(a, {7u, 9u}, 1);
  a.clear();
  a.shrink_to_fit();
  EXPECT_TRUE(a.empty());
}

TEST(SmallArcs, RandomOperationsMatchStdVector) {
  std::mt19937 rng(12345);
  for (int trial = 0; trial < 200; ++trial) {
    Arcs a;
    std::vector<std::uint32_t> v;
    std::vector<std::pair<Arcs, std::vector<std::uint32_t>>> kept;  // copies and moves, checked later
    const int steps = 1 + static_cast<int>(rng() % 300);
    for (int step = 0; step < steps; ++step) {
      switch (rng() % 10) {
        case 0: case 1: case 2: case 3: {  // push_back (the most frequent)
          const auto x = static_cast<std::uint32_t>(rng());
          a.push_back(x);
          v.push_back(x);
          break;
        }
        case 4: {  // erase a range (Boost's remove_if + erase)
          if (v.empty()) break;
          const std::size_t i = rng() % v.size(), j = i + rng() % (v.size() - i + 1);
          const auto it = a.erase(a.begin() + i, a.begin() + j);
          EXPECT_EQ(it, a.begin() + i);
          v.erase(v.begin() + static_cast<std::ptrdiff_t>(i), v.begin() + static_cast<std::ptrdiff_t>(j));
          break;
        }
        case 5: {  // remove every arc with a given target, as boost::remove_edge does
          if (v.empty()) break;
          const std::uint32_t x = v[rng() % v.size()];
          a.erase(std::remove(a.begin(), a.end(), x), a.end());
          v.erase(std::remove(v.begin(), v.end(), x), v.end());
          break;
        }
        case 6:
          if (rng() % 8 == 0) {
            a.clear();
            v.clear();
          }
          break;
        case 7: {
          const std::size_t n = rng() % 40;
          a.reserve(n);
          EXPECT_GE(a.capacity(), n);
          break;
        }
        case 8:
          a.shrink_to_fit();
          EXPECT_EQ(a.capacity(), std::max<std::size_t>(v.size(), 3));
          break;
        case 9: {
          if (rng() % 2) {
            kept.emplace_back(a, v);  // copy
          } else {
            Arcs moved(std::move(a));
            EXPECT_TRUE(a.empty());  // NOLINT(bugprone-use-after-move): moved-from is empty by contract
            kept.emplace_back(std::move(moved), v);
            a = kept.back().first;  // copy assignment back
          }
          break;
        }
      }
      expect_same(a, v, step);
    }
    for (std::size_t k = 0; k < kept.size(); ++k) expect_same(kept[k].first, kept[k].second, -static_cast<int>(k));
    Arcs assigned;
    assigned.push_back(1);
    assigned = std::move(a);
    expect_same(assigned, v, -1);
  }
}

}  // namespace
}  // namespace ptc
