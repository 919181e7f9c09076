// Small string helpers shared by the command line and the benchmark programs.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace ptc {

/// The non-empty items of a `sep`-separated list ("acc,,meshopt" -> {"acc", "meshopt"}); blanks
/// are kept (an item " acc" is not "acc").
[[nodiscard]] inline std::vector<std::string> split_list(std::string_view s, char sep = ',') {
  std::vector<std::string> out;
  for (std::size_t b = 0; b <= s.size();) {
    std::size_t e = s.find(sep, b);
    if (e == std::string_view::npos) e = s.size();
    if (e > b) out.emplace_back(s.substr(b, e - b));
    b = e + 1;
  }
  return out;
}

}  // namespace ptc
