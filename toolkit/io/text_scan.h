// Internal to toolkit/io: cursors over text held in memory and strict number parsing.
// Numbers are parsed with std::from_chars (locale-independent, fast); a token that is not wholly
// a number is "garbled" (so "1.5x", "1,5" and "--1" are errors, not 1.5, 1 and nothing).
#pragma once

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace ptc::io {

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }
inline bool is_space(char c) { return is_blank(c) || c == '\n'; }

enum class NumStatus { Ok, Garbled, OutOfRange };

/// Whether a decimal number that from_chars found out of range lies below 1 in magnitude (it
/// underflowed to zero) rather than beyond double's range: its decimal exponent, the place of its
/// first non-zero digit plus the exponent after 'e', is negative. `b` .. `e` is the number.
inline bool decimal_exponent_negative(const char* b, const char* e) {
  if (b != e && (*b == '-' || *b == '+')) ++b;
  std::int64_t place = 0;  // the first non-zero digit's place: 10^place
  bool found = false, point = false;
  std::int64_t int_digits = 0, frac_zeros = 0;
  for (; b != e && *b != 'e' && *b != 'E'; ++b) {
    if (*b == '.') {
      point = true;
    } else if (!found && *b == '0') {
      if (point) ++frac_zeros;
    } else if (!found) {
      found = true;
      place = point ? -(frac_zeros + 1) : 0;
      int_digits = point ? 0 : 1;
    } else if (!point) {
      ++int_digits;
    }
  }
  if (found && int_digits > 0) place = int_digits - 1;
  std::int64_t exp = 0;
  bool neg = false;
  if (b != e) ++b;  // 'e'
  if (b != e && (*b == '-' || *b == '+')) neg = *b++ == '-';
  for (; b != e; ++b) exp = std::min<std::int64_t>(exp * 10 + (*b - '0'), std::int64_t(1) << 40);  // (saturates)
  return place + (neg ? -exp : exp) < 0;
}

/// The whole token must be a decimal number ("1", "-2.5e3", "+.5", "nan", "inf"). A number too
/// small for a double (below its smallest subnormal, as "1e-400") is 0 with its sign, the nearest
/// double; one too large is OutOfRange.
inline NumStatus parse_double(std::string_view tok, double& out) {
  const char* b = tok.data();
  const char* e = b + tok.size();
  if (b != e && *b == '+' && e - b > 1 && b[1] != '-' && b[1] != '+') ++b;  // from_chars rejects '+'
  const auto [p, ec] = std::from_chars(b, e, out);
  if (ec == std::errc::result_out_of_range) {
    if (p != e) return NumStatus::Garbled;
    if (!decimal_exponent_negative(b, e)) return NumStatus::OutOfRange;
    out = *b == '-' ? -0.0 : 0.0;
    return NumStatus::Ok;
  }
  if (ec != std::errc() || p != e) return NumStatus::Garbled;
  return NumStatus::Ok;
}

/// The whole token must be a decimal integer.
inline NumStatus parse_int(std::string_view tok, std::int64_t& out) {
  const char* b = tok.data();
  const char* e = b + tok.size();
  if (b != e && *b == '+' && e - b > 1 && b[1] != '-' && b[1] != '+') ++b;
  const auto [p, ec] = std::from_chars(b, e, out);
  if (ec == std::errc::result_out_of_range) return NumStatus::OutOfRange;
  if (ec != std::errc() || p != e) return NumStatus::Garbled;
  return NumStatus::Ok;
}

/// A token quoted for an error message: at most 24 characters, non-printable bytes as \xNN.
inline std::string quote(std::string_view tok) {
  std::string s = "'";
  const std::size_t n = tok.size() < 24 ? tok.size() : 24;
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(tok[i]);
    if (c >= 0x20 && c < 0x7f) {
      s += static_cast<char>(c);
    } else {
      static constexpr char hex[] = "0123456789abcdef";
      s += "\\x";
      s += hex[c >> 4];
      s += hex[c & 15];
    }
  }
  if (tok.size() > n) s += "...";
  return s + "'";
}

/// Why a coordinate is unusable, or nullptr: "is NaN", "is infinite".
inline const char* non_finite(double v) {
  if (std::isnan(v)) return "is NaN";
  if (std::isinf(v)) return "is infinite";
  return nullptr;
}

/// Whitespace-separated fields of one line.
class Fields {
 public:
  explicit Fields(std::string_view line) : p_(line.data()), e_(line.data() + line.size()) {}
  /// Next field, or an empty view at the end of the line.
  std::string_view next() {
    while (p_ != e_ && is_blank(*p_)) ++p_;
    const char* b = p_;
    while (p_ != e_ && !is_blank(*p_)) ++p_;
    return {b, static_cast<std::size_t>(p_ - b)};
  }
  /// The rest of the line, leading blanks removed.
  std::string_view rest() {
    while (p_ != e_ && is_blank(*p_)) ++p_;
    return {p_, static_cast<std::size_t>(e_ - p_)};
  }

 private:
  const char* p_;
  const char* e_;
};

/// Lines of a text, 1-based line numbers. A line excludes its '\n'; a trailing '\r' is a blank.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : p_(text.data()), e_(text.data() + text.size()) {
    if (text.size() >= 3 && std::memcmp(p_, "\xEF\xBB\xBF", 3) == 0) p_ += 3;  // UTF-8 byte order mark
  }
  /// Next line; false at the end of the text.
  bool next(std::string_view& line) {
    if (p_ == e_) return false;
    const char* nl = static_cast<const char*>(std::memchr(p_, '\n', static_cast<std::size_t>(e_ - p_)));
    const char* end = nl ? nl : e_;
    line = {p_, static_cast<std::size_t>(end - p_)};
    p_ = nl ? nl + 1 : e_;
    ++line_;
    return true;
  }
  /// Next line that is not blank once a '#' comment is cut off; the comment is removed from it.
  bool next_content(std::string_view& line) {
    while (next(line)) {
      if (const void* hash = std::memchr(line.data(), '#', line.size()))
        line = line.substr(0, static_cast<std::size_t>(static_cast<const char*>(hash) - line.data()));
      for (char c : line)
        if (!is_blank(c)) return true;
    }
    return false;
  }
  /// Number of the line last returned (0 before the first).
  [[nodiscard]] std::uint64_t line() const { return line_; }
  /// Bytes after the line last returned.
  [[nodiscard]] std::size_t remaining() const { return static_cast<std::size_t>(e_ - p_); }

 private:
  const char* p_;
  const char* e_;
  std::uint64_t line_ = 0;
};

/// Whitespace-separated tokens across lines (ascii PLY and STL), with the line of each token.
class TokenReader {
 public:
  TokenReader(std::string_view text, std::uint64_t first_line)
      : p_(text.data()), e_(text.data() + text.size()), line_(first_line) {}
  /// Next token, or an empty view at the end of the text.
  std::string_view next() {
    while (p_ != e_ && is_space(*p_)) {
      if (*p_ == '\n') ++line_;
      ++p_;
    }
    const char* b = p_;
    while (p_ != e_ && !is_space(*p_)) ++p_;
    return {b, static_cast<std::size_t>(p_ - b)};
  }
  /// Skips to the start of the next line.
  void skip_line() {
    while (p_ != e_ && *p_ != '\n') ++p_;
  }
  /// Line of the token last returned (or of the end of the text).
  [[nodiscard]] std::uint64_t line() const { return line_; }
  [[nodiscard]] std::size_t remaining() const { return static_cast<std::size_t>(e_ - p_); }

 private:
  const char* p_;
  const char* e_;
  std::uint64_t line_;
};

}  // namespace ptc::io
