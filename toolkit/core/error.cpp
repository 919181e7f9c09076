#include "toolkit/core/error.h"

namespace ptc {
namespace {
std::string compose(const std::string& file, const std::string& location, const std::string& element,
                    const std::string& reason) {
  // One line: "file:line 12: vertex 3: coordinate is NaN". Parts that are empty are left out.
  std::string s;
  auto add = [&](const std::string& part) {
    if (part.empty()) return;
    if (!s.empty()) s += ": ";
    s += part;
  };
  add(file);
  add(location);
  add(element);
  add(reason);
  // Keep the message on one line whatever the reason text contains.
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}
}  // namespace

InputError::InputError(std::string file, std::string location, std::string element, std::string reason)
    : std::runtime_error(compose(file, location, element, reason)),
      file_(std::move(file)),
      location_(std::move(location)),
      element_(std::move(element)),
      reason_(std::move(reason)) {}

std::string line_loc(std::uint64_t line) { return "line " + std::to_string(line); }
std::string byte_loc(std::uint64_t offset) { return "byte " + std::to_string(offset); }
std::string json_byte_loc(std::uint64_t nlohmann_byte) { return byte_loc(nlohmann_byte > 0 ? nlohmann_byte - 1 : 0); }

}  // namespace ptc
