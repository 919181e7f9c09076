// FNV-1a 64 of bytes, written out here as the tests' own answer to compare the manifests' hashes
// with (commands/inputs.h computes them in the program).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace ptc::test {

inline std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t h = 14695981039346656037ull;
  for (const char c : bytes) h = (h ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  return h;
}

/// As the manifests spell it: 16 lower-case hex digits.
inline std::string fnv1a64_hex(std::string_view bytes) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a64(bytes)));
  return hex;
}

}  // namespace ptc::test
