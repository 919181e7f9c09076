// The fuzz targets of ptc by name (docs/fuzzing.md): what each one does with an input. The same
// code runs under libFuzzer (fuzz_main.cpp, one binary per target) and in the test suite, which
// replays every regression input of tests/fuzz_inputs/TARGET/ (tests/apps/fuzz_inputs_test.cpp).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace ptc::fuzz {

/// off obj ply stl md2 md3 scene_json frame_dir triangles_csv.
[[nodiscard]] const std::vector<std::string>& target_names();

/// Runs target `name` on `bytes`. Returns normally for a result and for an InputError, the one
/// answer bad input may get; anything else (another exception, a crash) escapes: a finding.
/// Readers that take paths get the bytes as files in a private scratch directory (removed at
/// exit). std::invalid_argument for an unknown target name. With `input_errors = false` an
/// InputError escapes too (the seeds must load).
void run_target(std::string_view name, std::string_view bytes, bool input_errors = true);

}  // namespace ptc::fuzz
