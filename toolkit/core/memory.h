// Resident memory of this process (Linux /proc/self/status) and of the machine (/proc/meminfo),
// for the per-stage figures of the run manifests, the per-frame columns of bench.csv and
// trace.csv, and the memory estimate of `ptc info`.
#pragma once

#include <string>

namespace ptc {

/// Resident and peak resident memory (VmRSS, VmHWM) in MB (2^20 bytes), read together: the kernel
/// computes both for one snapshot, so peak_mb >= rss_mb. 0 when /proc is not readable. The peak
/// is never reset here, so it agrees with /usr/bin/time's maximum resident size.
struct RssSample {
  double rss_mb = 0, peak_mb = 0;
};
[[nodiscard]] RssSample rss_sample();
/// The machine's memory (/proc/meminfo MemTotal) in MB; 0 when unknown.
[[nodiscard]] double machine_memory_mb();

/// The kernel's transparent huge page mode ("always", "madvise", "never"), the bracketed entry
/// of /sys/kernel/mm/transparent_hugepage/enabled; "" when unknown.
[[nodiscard]] std::string transparent_huge_page_mode();

/// Whether this process's malloc was started with transparent huge pages (glibc's
/// glibc.malloc.hugetlb=1 or 2): said once at start-up by the program that arranged it (the ptc
/// command, commands/process.h); false in a program that says nothing. For the manifests.
void set_malloc_huge_pages(bool on);
[[nodiscard]] bool malloc_huge_pages();

}  // namespace ptc
