#include "analysis/schema/manifest.h"

#include <sys/utsname.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <ctime>
#include <fstream>

#include "analysis/schema/json.h"
#include "bvh/tracer.h"
#include "toolkit/core/isa.h"
#include "toolkit/core/memory.h"
#include <thread>

#include <CGAL/version.h>
#include <Eigen/Core>
#include <OpenMesh/Core/System/config.h>
#include <boost/version.hpp>
#include <embree3/rtcore_config.h>
#include <fmt/core.h>
#include <oneapi/tbb/version.h>

#include "ptc_build_info.h"  // generated at build time: PTC_GIT_COMMIT, PTC_GIT_DIRTY
#include "toolkit/core/error.h"

namespace ptc {
namespace fs = std::filesystem;

nlohmann::json build_info() {
  nlohmann::json j;
  j["ptc"] = PTC_VERSION;
  j["git_commit"] = PTC_GIT_COMMIT;
  j["git_dirty"] = PTC_GIT_DIRTY != 0;
  j["compiler"] = std::string("g++ ") + __VERSION__;
#ifdef NDEBUG
  j["build_type"] = "release";
#else
  j["build_type"] = "debug";
#endif
#ifdef __SANITIZE_ADDRESS__
  j["sanitizers"] = "address,undefined";
#endif
#ifdef __AVX2__
  j["simd"] = "avx2";
#elif defined(__SSE4_2__)
  j["simd"] = "sse4.2";
#else
  j["simd"] = "sse2";
#endif
  nlohmann::json libs;
  libs["cgal"] = CGAL_VERSION_STR;
  libs["eigen"] = fmt::format("{}.{}.{}", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION);
  libs["boost"] = fmt::format("{}.{}.{}", BOOST_VERSION / 100000, BOOST_VERSION / 100 % 1000, BOOST_VERSION % 100);
  libs["openmesh"] = fmt::format("{}.{}.{}", OM_GET_VER, OM_GET_MAJ, OM_GET_MIN);
  libs["tbb"] = TBB_VERSION_STRING;
  libs["embree"] = RTC_VERSION_STRING;
  libs["fmt"] = fmt::format("{}.{}.{}", FMT_VERSION / 10000, FMT_VERSION / 100 % 100, FMT_VERSION % 100);
  libs["nlohmann_json"] = fmt::format("{}.{}.{}", NLOHMANN_JSON_VERSION_MAJOR, NLOHMANN_JSON_VERSION_MINOR,
                                      NLOHMANN_JSON_VERSION_PATCH);
  j["libraries"] = libs;
  return j;
}

nlohmann::json machine_info() {
  nlohmann::json j;
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) == 0) j["hostname"] = host;
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      auto p = line.find(':');
      if (p != std::string::npos) j["cpu"] = line.substr(line.find_first_not_of(' ', p + 1));
      break;
    }
  j["logical_cores"] = std::thread::hardware_concurrency();
  if (const double mb = machine_memory_mb(); mb > 0) j["memory_kib"] = static_cast<std::uint64_t>(mb * 1024.0);
  struct utsname u {};
  if (::uname(&u) == 0) j["kernel"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
  // Transparent huge pages: the kernel's mode, and whether this process's malloc was started with
  // them (`ptc` arranges it, commands/process.h; toolkit/core/memory.h).
  if (const std::string mode = transparent_huge_page_mode(); !mode.empty()) j["transparent_hugepages"] = mode;
  j["malloc_hugepages"] = malloc_huge_pages();
  j["clustering_isa"] = clustering_isa();  // which clones of the clustering's hot code run (toolkit/core/isa.h)
  j["trace_isa"] = bvh::to_string(bvh::resolve(bvh::TraceIsa::Auto));  // the tracer's variant by default (bvh/tracer.h)
  return j;
}

namespace {
std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}
}  // namespace

RunManifest::RunManifest(std::string command, std::vector<std::string> argv, std::string schema)
    : command_(std::move(command)), schema_(std::move(schema)), argv_(std::move(argv)), started_utc_(utc_now()) {}

void RunManifest::add_timing_ms(const std::string& key, double ms) {
  timings_[key] = ms;
  if (const RssSample m = rss_sample(); m.peak_mb > 0) {
    rss_mb_[key] = m.rss_mb;
    peak_rss_mb_[key] = m.peak_mb;
  }
}

void RunManifest::add_output(const std::string& file, const std::string& schema) {
  outputs_.push_back(file);
  if (!schema.empty()) schemas_[file] = schema;
}

nlohmann::json RunManifest::to_json() const {
  nlohmann::json j;
  j["schema"] = schema_;
  j["command"] = command_;
  j["argv"] = argv_;
  j["started_utc"] = started_utc_;
  j["wall_ms"] = since_start_.ms();
  j["inputs"] = inputs_;
  j["parameters"] = parameters_;
  j["timings_ms"] = timings_;
  j["peak_rss_mb"] = peak_rss_mb_;
  j["rss_mb"] = rss_mb_;
  j["max_rss_mb"] = rss_sample().peak_mb;
  j["results"] = results_;
  j["outputs"] = outputs_;
  j["output_schemas"] = schemas_;
  if (!output_hashes_.empty()) j["output_hashes"] = output_hashes_;
  j["build"] = build_info();
  j["machine"] = machine_info();
  return j;
}

}  // namespace ptc
