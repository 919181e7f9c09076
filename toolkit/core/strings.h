// Small string helpers shared by the command line and the benchmark programs.
#pragma once

#include <cstdint>
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

/// The last line of `text` that holds more than blanks, without its line end ("" when none):
/// the one-line reason of a program's error output.
[[nodiscard]] inline std::string last_nonblank_line(std::string_view text) {
  std::string_view last;
  for (std::size_t b = 0; b < text.size();) {
    std::size_t e = text.find('\n', b);
    if (e == std::string_view::npos) e = text.size();
    std::string_view line = text.substr(b, e - b);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.remove_suffix(1);
    if (line.find_first_not_of(" \t") != std::string_view::npos) last = line;
    b = e + 1;
  }
  return std::string(last);
}

/// A count with its noun in the right number: counted(1, "triangle") is "1 triangle",
/// counted(0, "triangle") "0 triangles", counted(2, "vertex", "vertices") "2 vertices".
[[nodiscard]] inline std::string counted(std::uint64_t n, std::string_view singular, std::string_view plural = {}) {
  std::string out = std::to_string(n);
  out += ' ';
  if (n == 1) {
    out += singular;
  } else if (plural.empty()) {
    out += singular;
    out += 's';
  } else {
    out += plural;
  }
  return out;
}

}  // namespace ptc
