// `ptc info`: the mesh report as JSON (stable keys, schema "ptc-info/1") and as text.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "toolkit/io/mesh_io.h"
#include "toolkit/mesh/mesh_report.h"

namespace ptc {

[[nodiscard]] nlohmann::json mesh_info_json(const std::filesystem::path& file, const ReadReport& read,
                                            const MeshReport& report);
[[nodiscard]] std::string mesh_info_text(const std::filesystem::path& file, const ReadReport& read,
                                         const MeshReport& report);
[[nodiscard]] std::string_view to_string(MeshFormat f);
/// {"count", "min", "mean", "p5", "p50", "p95", "max"}.
[[nodiscard]] nlohmann::json summary_json(const Summary& s);

}  // namespace ptc
