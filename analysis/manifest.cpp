#include "analysis/manifest.h"

#include <sys/utsname.h>
#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <fstream>
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

std::string dump_json(const nlohmann::json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string file_fnv1a64(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "", "", "cannot open file");
  std::uint64_t h = 14695981039346656037ull;  // FNV-1a 64 offset basis
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    const auto n = in.gcount();
    for (std::streamsize i = 0; i < n; ++i) {
      h ^= static_cast<unsigned char>(buf[static_cast<std::size_t>(i)]);
      h *= 1099511628211ull;
    }
  }
  char out[17];
  std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(h));
  return out;
}

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
  std::ifstream mem("/proc/meminfo");
  for (std::string line; std::getline(mem, line);)
    if (line.rfind("MemTotal:", 0) == 0) {
      j["memory_kib"] = std::stoull(line.substr(9));
      break;
    }
  struct utsname u {};
  if (::uname(&u) == 0) j["kernel"] = std::string(u.sysname) + " " + u.release + " " + u.machine;
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

RunManifest::RunManifest(std::string command, std::vector<std::string> argv)
    : command_(std::move(command)), argv_(std::move(argv)), started_utc_(utc_now()), t0_(std::chrono::steady_clock::now()) {}

void RunManifest::add_input(const fs::path& path) {
  std::error_code ec;
  nlohmann::json in;
  in["path"] = path.string();
  in["absolute_path"] = fs::absolute(path, ec).string();
  in["bytes"] = fs::file_size(path, ec);
  in["fnv1a64"] = file_fnv1a64(path);
  inputs_.push_back(std::move(in));
}

nlohmann::json RunManifest::to_json() const {
  nlohmann::json j;
  j["schema"] = "ptc-manifest/1";
  j["command"] = command_;
  j["argv"] = argv_;
  j["started_utc"] = started_utc_;
  j["wall_ms"] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
  j["inputs"] = inputs_;
  j["parameters"] = parameters_;
  j["timings_ms"] = timings_;
  j["results"] = results_;
  j["outputs"] = outputs_;
  j["build"] = build_info();
  j["machine"] = machine_info();
  return j;
}

}  // namespace ptc
