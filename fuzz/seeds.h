// The seeds ptc writes for its fuzz targets (docs/fuzzing.md): small valid files of every format a
// target reads, made by ptc's own writers (PLY, OFF, OBJ, MD3) or by hand (MD2, binary STL).
// make_fuzz_seeds writes them; the test suite checks that every one loads.
#pragma once

#include <string>
#include <vector>

namespace ptc::fuzz {

struct Seed {
  std::string target;  ///< fuzz/targets.h target_names()
  std::string name;    ///< file name
  std::string bytes;
};
[[nodiscard]] std::vector<Seed> generated_seeds();

}  // namespace ptc::fuzz
