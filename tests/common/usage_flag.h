// The flag a call's UsageError names, for the tests of every command's usage errors.
#pragma once

#include <string>

#include "toolkit/core/error.h"

namespace ptc::test {

/// The element (flag) of the UsageError `f` throws; "" when it throws nothing, "(another error)"
/// for any other exception.
template <class F>
std::string usage_flag(F&& f) {
  try {
    f();
  } catch (const UsageError& e) {
    return e.element();
  } catch (...) {
    return "(another error)";
  }
  return "";
}

}  // namespace ptc::test
