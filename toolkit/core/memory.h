// Resident memory of this process (Linux /proc/self/status), for the per-stage figures of the
// run manifests and the scale benchmark.
#pragma once

namespace ptc {

/// Peak resident set of the process so far (VmHWM), in MB (2^20 bytes); 0 when /proc is not
/// readable. Never reset here, so that it agrees with /usr/bin/time's maximum resident size.
[[nodiscard]] double peak_rss_mb();
/// Current resident set (VmRSS) in MB; 0 when unknown.
[[nodiscard]] double current_rss_mb();
/// The machine's memory (/proc/meminfo MemTotal) in MB; 0 when unknown.
[[nodiscard]] double machine_memory_mb();

}  // namespace ptc
