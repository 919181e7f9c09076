// The one error policy (style.md point 6):
// - bad data from outside (files, user input) raises InputError at the boundary, naming the
//   file, the location (line or byte offset) and the element, and the reason;
// - programmer errors are assertions / std::logic_error;
// - library code never calls exit().
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace ptc {

class InputError : public std::runtime_error {
 public:
  /// file: path as given by the user ("" for non-file input such as a command-line value).
  /// location: "line 12", "byte 4096", "" when not applicable.
  /// element: "vertex 12", "face 3", "header", "" when not applicable.
  InputError(std::string file, std::string location, std::string element, std::string reason);

  const std::string& file() const { return file_; }
  const std::string& location() const { return location_; }
  const std::string& element() const { return element_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string file_, location_, element_, reason_;
};

/// Bad usage: a command-line value that is wrong whatever the input files hold (a malformed
/// frame range, an empty --out, flags that contradict each other, a flag the chosen method does
/// not use). An InputError with no file and the flag as the element; the command exits with 2
/// for it (1 for other input errors).
class UsageError : public InputError {
 public:
  UsageError(std::string flag, std::string reason) : InputError("", "", std::move(flag), std::move(reason)) {}
};

/// "line N" helper.
std::string line_loc(std::uint64_t line);
/// "byte N" helper (offsets count from 0, as in every reader's messages).
std::string byte_loc(std::uint64_t offset);
/// "byte N" of a JSON parse error, from nlohmann's position (the count of bytes read: 1-based).
std::string json_byte_loc(std::uint64_t nlohmann_byte);

}  // namespace ptc
