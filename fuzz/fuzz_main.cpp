// The libFuzzer entry of one target (PTC_FUZZ_TARGET, set per binary by fuzz/CMakeLists.txt).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz/targets.h"

#define PTC_STR2(x) #x
#define PTC_STR(x) PTC_STR2(x)

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ptc::fuzz::run_target(PTC_STR(PTC_FUZZ_TARGET), std::string_view(reinterpret_cast<const char*>(data), size));
  return 0;
}
