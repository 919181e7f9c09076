// How many threads a parallel pass of the caller can use: the fewer of its arena's concurrency
// and the process's limit (`ptc --threads N` sets a tbb::global_control, which does not change
// an arena's max_concurrency()). The passes whose bytes do not depend on the thread count take
// their sequential form at 1.
#pragma once

#include <algorithm>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

namespace ptc::bvh {

[[nodiscard]] inline int usable_threads() {
  const auto limit = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  return std::max(1, std::min(tbb::this_task_arena::max_concurrency(), static_cast<int>(std::min<std::size_t>(limit, 1u << 20))));
}

}  // namespace ptc::bvh
