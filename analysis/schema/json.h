// JSON helpers shared by every table and manifest: the one text form of JSON output, and the
// JSON forms of small value types.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "toolkit/core/stats.h"
#include "toolkit/core/types.h"

namespace ptc {

/// JSON text for files and stdout: indented, and invalid UTF-8 (file names are bytes on Linux)
/// replaced by U+FFFD instead of throwing.
[[nodiscard]] std::string dump_json(const nlohmann::json& j);

/// {"count", "min", "mean", "p5", "p50", "p95", "max"} (toolkit/core/stats.h).
[[nodiscard]] nlohmann::json summary_json(const Summary& s);

/// [x, y, z].
[[nodiscard]] nlohmann::json vec_json(const Vec3& v);

}  // namespace ptc
