#include "toolkit/core/isa.h"

namespace ptc {

const char* clustering_isa() {
#if PTC_HAS_ISA_CLONES
  // The test GCC's dispatcher makes for an "arch=x86-64-v3" clone.
  __builtin_cpu_init();
  return __builtin_cpu_supports("x86-64-v3") ? "x86-64-v3" : "x86-64";
#else
  return "x86-64";
#endif
}

}  // namespace ptc
