// AlignedAllocator: the alignment asked for below kHugePageFrom, whole 2 MiB pages from it on,
// every byte usable, and (where the kernel offers transparent huge pages at all) the large
// arrays' memory eligible for them, read back from /proc/self/smaps, the kernel's own answer.
#include "bvh/aligned.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>

namespace ptc::bvh {
namespace {

bool aligned_to(const void* p, std::size_t a) { return reinterpret_cast<std::uintptr_t>(p) % a == 0; }

// The "THPeligible:" value of the smaps entry holding address p, or -1 if none says.
int thp_eligible(const void* p) {
  std::ifstream in("/proc/self/smaps");
  const auto addr = reinterpret_cast<std::uintptr_t>(p);
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-' && line.find(':') > line.find('-')) {
      inside = lo <= addr && addr < hi;
      continue;
    }
    if (inside && line.rfind("THPeligible:", 0) == 0) return std::stoi(line.substr(12));
  }
  return -1;
}

std::string thp_setting() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string s;
  std::getline(in, s);
  return s;
}

TEST(AlignedAllocator, SmallArraysKeepTheirAlignment) {
  for (std::size_t n : {std::size_t(1), std::size_t(7), std::size_t(1000), kHugePageFrom / 4 - 1}) {
    AlignedVector<float> v(n);
    EXPECT_TRUE(aligned_to(v.data(), 64)) << n;
    std::iota(v.begin(), v.end(), 0.0f);
    EXPECT_EQ(v.back(), float(n - 1)) << n;
  }
}

TEST(AlignedAllocator, LargeArraysSitOnWholeHugePages) {
  // At the threshold, just above it, and across several huge pages (not a multiple of one).
  for (std::size_t bytes : {kHugePageFrom, kHugePageFrom + 4, 3 * kHugePageBytes + 12}) {
    AlignedVector<std::uint32_t> v(bytes / 4);
    ASSERT_TRUE(aligned_to(v.data(), kHugePageBytes)) << bytes;
    std::iota(v.begin(), v.end(), 0u);  // every byte writable
    for (std::size_t i = 0; i < v.size(); i += 4093) ASSERT_EQ(v[i], i) << bytes;
    ASSERT_EQ(v.back(), v.size() - 1);
    // Regrowth copies into another huge-page block and frees the first with its own size.
    v.resize(v.size() * 2 + 1, 7u);
    ASSERT_TRUE(aligned_to(v.data(), kHugePageBytes)) << bytes;
    EXPECT_EQ(v[bytes / 4 - 1], bytes / 4 - 1);
    EXPECT_EQ(v.back(), 7u);
  }
}

TEST(AlignedAllocator, LargeArraysAreEligibleForTransparentHugePages) {
  const std::string setting = thp_setting();
  if (setting.find("[never]") != std::string::npos || setting.empty())
    GTEST_SKIP() << "transparent huge pages are off on this machine (" << setting << ")";
  AlignedVector<float> big(2 * kHugePageBytes / 4);
  big.assign(big.size(), 1.0f);
  const int e = thp_eligible(big.data());
  if (e < 0) GTEST_SKIP() << "this kernel's smaps has no THPeligible field";
  EXPECT_EQ(e, 1);
}

TEST(AlignedAllocator, RefusesASizeThatOverflows) {
  AlignedAllocator<double> a;
  EXPECT_THROW((void)a.allocate(std::size_t(-1) / 4), std::bad_array_new_length);
}

}  // namespace
}  // namespace ptc::bvh
