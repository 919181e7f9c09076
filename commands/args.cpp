#include "commands/args.h"

#include <tbb/info.h>

#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "bvh/scene_config.h"
#include "render/camera.h"
#include "toolkit/core/error.h"

namespace ptc {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::string quoted(std::string_view s) {
  std::string q(1, '\'');
  q.append(s.substr(0, 32));
  q.push_back('\'');
  return q;
}

// A decimal integer >= 0, or nullopt.
std::optional<std::int64_t> frame_number(std::string_view s) {
  std::int64_t v = -1;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v < 0) return std::nullopt;
  return v;
}

// A frame number beyond kMaxFrame: said naming the flag.
void check_frame_limit(std::int64_t f, std::string_view flag) {
  if (f > kMaxFrame)
    throw UsageError(std::string(flag), fmt::format("frame {} is beyond the largest frame number, 2^53 = {} ({})", f,
                                                    kMaxFrame, kMaxFrameWhy));
}

}  // namespace

std::int64_t parse_frame(std::string_view s, std::string_view flag) {
  const auto v = frame_number(s);
  if (!v) throw UsageError(std::string(flag), fmt::format("{} is not a frame number (an integer >= 0)", quoted(s)));
  check_frame_limit(*v, flag);
  return *v;
}

FrameRange parse_frame_range(std::string_view s, std::string_view flag) {
  const auto colon = s.find(':');
  const auto a = frame_number(s.substr(0, colon));
  const auto b = colon == std::string_view::npos ? a : frame_number(s.substr(colon + 1));
  if (!a || !b)
    throw UsageError(std::string(flag),
                     fmt::format("{} is not A:B with integers 0 <= A <= B (e.g. 0:59), nor one frame F", quoted(s)));
  if (*b < *a)
    throw UsageError(std::string(flag), fmt::format("{}: the last frame {} is before the first {}", quoted(s), *b, *a));
  check_frame_limit(*b, flag);
  return {*a, *b};
}

std::optional<Vec3> parse_vec3(std::string_view s, std::string* why) {
  auto fail = [&](std::string w) -> std::optional<Vec3> {
    if (why) *why = std::move(w);
    return std::nullopt;
  };
  double v[3];
  for (int k = 0; k < 3; ++k) {
    const std::size_t comma = s.find(',');
    if ((k < 2) != (comma != std::string_view::npos)) return fail("expected 3 comma-separated numbers X,Y,Z");
    std::string_view tok = trim(k < 2 ? s.substr(0, comma) : s);
    if (k < 2) s.remove_prefix(comma + 1);
    if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
    const auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v[k]);
    if (tok.empty() || ec != std::errc() || p != tok.data() + tok.size())
      return fail(quoted(tok).append(" is not a number"));
    if (!std::isfinite(v[k])) return fail(quoted(tok).append(" is not a finite number"));
  }
  return Vec3(v[0], v[1], v[2]);
}

void check_image_size(int width, int height) {
  if (width < 1 || height < 1 || width > kMaxImageSide || height > kMaxImageSide)
    throw UsageError("--width/--height", fmt::format("the image size must be 1..{} pixels per side", kMaxImageSide));
}

unsigned resolve_threads(unsigned threads) {
  return threads ? threads : static_cast<unsigned>(tbb::info::default_concurrency());
}

void check_frames(const Scene& scene, const FrameRange& r, const std::string& scene_arg, std::string_view flag,
                  bool extend) {
  const FrameRange& listed = scene.frames();
  if (!extend && (r.first < listed.first || r.last > listed.last))
    throw UsageError(std::string(flag),
                     fmt::format("{} outside the range {}:{} of '{}' (--extend-frames allows frames that its "
                                 "sources can still give)",
                                 r.count() == 1 ? fmt::format("frame {} is", r.first)
                                                : fmt::format("frames {}:{} are", r.first, r.last),
                                 listed.first, listed.last, scene_arg));
  if (const std::size_t fc = scene.frame_count(); fc > 0 && r.last >= static_cast<std::int64_t>(fc))
    throw UsageError(std::string(flag),
                     fmt::format("frame {} is beyond the last frame of '{}' (frames 0..{})", r.last, scene_arg, fc - 1));
}

std::pair<double, double> parse_value_range(const std::string& s, std::string_view flag) {
  // Split at the first colon after the first character, so that MIN may be negative.
  const std::size_t c = s.size() > 1 ? s.find(':', 1) : std::string::npos;
  const std::string bad = fmt::format("'{}' is not MIN:MAX with two finite numbers", s);
  auto num = [&](const std::string& t) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(t, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (t.empty() || used != t.size() || !std::isfinite(v)) throw UsageError(std::string(flag), bad);
    return v;
  };
  if (c == std::string::npos) throw UsageError(std::string(flag), bad);
  const double lo = num(s.substr(0, c)), hi = num(s.substr(c + 1));
  if (!(lo < hi)) throw UsageError(std::string(flag), fmt::format("'{}': MIN must be below MAX", s));
  return {lo, hi};
}

std::optional<double> parse_auto_off_or_above(const std::string& s, double auto_value, double above) {
  if (s == "auto") return auto_value;
  if (s == "off") return 0.0;
  try {
    std::size_t n = 0;
    const double v = std::stod(s, &n);
    if (n == s.size() && std::isfinite(v) && v > above) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

std::optional<double> parse_cluster_fallback(const std::string& s) {
  return parse_auto_off_or_above(s, bvh::kAutoFallbackSwelling, 1.0);
}

std::optional<double> parse_fallback_refit(const std::string& s) {
  return parse_auto_off_or_above(s, bvh::kAutoFallbackRefitGrowth, 0.0);
}

}  // namespace ptc
