#include "analysis/schema/json.h"

namespace ptc {

std::string dump_json(const nlohmann::json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

nlohmann::json summary_json(const Summary& s) {
  return {{"count", s.count}, {"min", s.min}, {"mean", s.mean}, {"p5", s.p5},
          {"p50", s.p50},     {"p95", s.p95}, {"max", s.max}};
}

nlohmann::json vec_json(const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

}  // namespace ptc
