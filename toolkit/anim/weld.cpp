#include "toolkit/anim/weld.h"

#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <stdexcept>
#include <unordered_map>

namespace ptc {

namespace {

struct Key {
  std::uint32_t cls;
  std::uint64_t x, y, z;
  bool operator==(const Key&) const = default;
};

struct KeyHash {
  std::size_t operator()(const Key& k) const noexcept {
    // splitmix-style mixing of the four words
    auto mix = [](std::uint64_t h) {
      h ^= h >> 33;
      h *= 0xff51afd7ed558ccdULL;
      h ^= h >> 33;
      h *= 0xc4ceb9fe1a85ec53ULL;
      h ^= h >> 33;
      return h;
    };
    std::uint64_t h = mix(k.cls + 0x9e3779b97f4a7c15ULL);
    h = mix(h ^ k.x);
    h = mix(h ^ k.y);
    h = mix(h ^ k.z);
    return static_cast<std::size_t>(h);
  }
};

// Bits of a coordinate with -0.0 folded onto +0.0, so that bit equality is == equality.
std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v == 0.0 ? 0.0 : v); }

}  // namespace

std::vector<Tri> WeldMap::apply(std::span<const Tri> triangles) const {
  std::vector<Tri> out(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) out[t][c] = remap.at(triangles[t][c]);
  return out;
}

void WeldMap::gather(std::span<const Vec3> in, std::span<Vec3> out) const {
  if (in.size() != remap.size() || out.size() != representative.size())
    throw std::invalid_argument("WeldMap::gather: frame size does not match the weld map");
  for (std::size_t w = 0; w < representative.size(); ++w) out[w] = in[representative[w]];
}

std::vector<Vec3> WeldMap::gather(std::span<const Vec3> in) const {
  std::vector<Vec3> out(representative.size());
  gather(in, out);
  return out;
}

VertexWelder::VertexWelder(std::size_t vertex_count) : cls_(vertex_count, 0) {
  if (vertex_count > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("VertexWelder: more than 2^32-1 vertices");
  classes_ = vertex_count == 0 ? 0 : 1;
}

void VertexWelder::add_frame(std::span<const Vec3> positions) {
  if (positions.size() != cls_.size())
    throw std::invalid_argument("VertexWelder::add_frame: frame has " + std::to_string(positions.size()) +
                                " vertices, expected " + std::to_string(cls_.size()));
  ++frames_;
  if (classes_ == cls_.size()) return;  // every vertex is alone already: nothing can split further
  std::unordered_map<Key, std::uint32_t, KeyHash> ids;
  ids.reserve(cls_.size());
  std::uint32_t next = 0;
  for (std::size_t v = 0; v < cls_.size(); ++v) {
    const Vec3& p = positions[v];
    if (std::isnan(p.x()) || std::isnan(p.y()) || std::isnan(p.z())) {  // NaN equals nothing
      cls_[v] = next++;
      continue;
    }
    const Key k{cls_[v], bits(p.x()), bits(p.y()), bits(p.z())};
    auto [it, inserted] = ids.try_emplace(k, next);
    if (inserted) ++next;
    cls_[v] = it->second;
  }
  classes_ = next;
}

WeldMap VertexWelder::finish() const {
  if (frames_ == 0) throw std::logic_error("VertexWelder::finish: no frame was added");
  WeldMap m;
  m.remap = cls_;  // class ids are numbered by first occurrence (see add_frame)
  m.representative.assign(classes_, std::numeric_limits<std::uint32_t>::max());
  for (std::size_t v = 0; v < cls_.size(); ++v)
    if (m.representative[cls_[v]] == std::numeric_limits<std::uint32_t>::max())
      m.representative[cls_[v]] = static_cast<std::uint32_t>(v);
  return m;
}

WeldMap weld_frames(std::span<const std::vector<Vec3>> frames) {
  if (frames.empty()) throw std::invalid_argument("weld_frames: no frames");
  VertexWelder w(frames.front().size());
  for (const auto& f : frames) w.add_frame(f);
  return w.finish();
}

}  // namespace ptc
