#include "toolkit/anim/skinning.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "toolkit/anim/frame_sequence.h"
#include "toolkit/anim/weld.h"

namespace ptc {

namespace {

[[noreturn]] void bad(const std::string& what) { throw std::invalid_argument("SkinRig: " + what); }

void check_times(const std::vector<double>& t, std::size_t keys, const std::string& what) {
  if (t.size() != keys) bad(what + ": times and keys differ in number");
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t[i])) bad(fmt::format("{}: key {} has a non-finite time", what, i));
    if (i > 0 && t[i] < t[i - 1]) bad(fmt::format("{}: key {} is earlier than key {}", what, i, i - 1));
  }
}

// Index i with times[i] <= t < times[i+1] and the blend factor; clamps outside the keys.
struct KeyPos {
  std::size_t i = 0, j = 0;
  double a = 0.0;
};
KeyPos find_key(const std::vector<double>& times, double t) {
  KeyPos k;
  if (times.size() <= 1 || t <= times.front()) return k;
  if (t >= times.back()) {
    k.i = k.j = times.size() - 1;
    return k;
  }
  const auto it = std::upper_bound(times.begin(), times.end(), t);  // first time > t
  k.j = static_cast<std::size_t>(it - times.begin());
  k.i = k.j - 1;
  const double span = times[k.j] - times[k.i];
  k.a = span > 0.0 ? (t - times[k.i]) / span : 0.0;
  return k;
}

Vec3 sample(const std::vector<double>& times, const std::vector<Vec3>& keys, const Vec3& fallback, double t) {
  if (keys.empty()) return fallback;
  const KeyPos k = find_key(times, t);
  return k.a == 0.0 ? keys[k.i] : Vec3((1.0 - k.a) * keys[k.i] + k.a * keys[k.j]);
}

Eigen::Quaterniond sample(const std::vector<double>& times, const std::vector<Eigen::Quaterniond>& keys,
                          const Eigen::Quaterniond& fallback, double t) {
  if (keys.empty()) return fallback;
  const KeyPos k = find_key(times, t);
  if (k.a == 0.0) return keys[k.i];
  return keys[k.i].slerp(k.a, keys[k.j]);  // Eigen takes the shorter arc
}

}  // namespace

void validate(const SkinRig& rig) {
  for (std::size_t n = 0; n < rig.nodes.size(); ++n) {
    const auto& nd = rig.nodes[n];
    if (nd.parent >= static_cast<std::int32_t>(n) || nd.parent < -1)
      bad(fmt::format("node {} ('{}'): parent {} is not an earlier node", n, nd.name, nd.parent));
    if (nd.track >= static_cast<std::int32_t>(rig.tracks.size()) || nd.track < -1)
      bad(fmt::format("node {} ('{}'): track {} out of range", n, nd.name, nd.track));
    if (!nd.rest.matrix().allFinite()) bad(fmt::format("node {} ('{}'): non-finite rest transform", n, nd.name));
  }
  for (std::size_t i = 0; i < rig.tracks.size(); ++i) {
    const auto& tr = rig.tracks[i];
    const std::string w = fmt::format("track {}", i);
    check_times(tr.t_times, tr.t_keys.size(), w + " translation");
    check_times(tr.r_times, tr.r_keys.size(), w + " rotation");
    check_times(tr.s_times, tr.s_keys.size(), w + " scaling");
  }
  if (!(rig.ticks_per_second > 0.0) || !std::isfinite(rig.ticks_per_second)) bad("ticks_per_second must be > 0");
  if (!(rig.duration_ticks >= 0.0) || !std::isfinite(rig.duration_ticks)) bad("duration must be >= 0");
  if (rig.palette_node.size() != rig.palette_offset.size()) bad("palette_node and palette_offset differ in size");
  for (std::size_t j = 0; j < rig.palette_node.size(); ++j)
    if (rig.palette_node[j] >= rig.nodes.size()) bad(fmt::format("palette entry {}: node out of range", j));
  const std::size_t nv = rig.bind_positions.size();
  if (rig.influence_begin.size() != nv + 1) bad("influence_begin must have vertex_count + 1 entries");
  if (rig.influence_begin.front() != 0 || rig.influence_begin.back() != rig.influences.size())
    bad("influence_begin does not span the influences");
  for (std::size_t v = 0; v < nv; ++v) {
    if (!rig.bind_positions[v].allFinite()) bad(fmt::format("vertex {}: non-finite position", v));
    const auto b = rig.influence_begin[v], e = rig.influence_begin[v + 1];
    if (e <= b) bad(fmt::format("vertex {}: no influence", v));
    double sum = 0.0;
    for (auto i = b; i < e; ++i) {
      const auto& in = rig.influences[i];
      if (in.palette >= rig.palette_node.size()) bad(fmt::format("vertex {}: palette index out of range", v));
      if (!(in.weight >= 0.0) || !std::isfinite(in.weight)) bad(fmt::format("vertex {}: bad weight {}", v, in.weight));
      sum += in.weight;
    }
    if (!(sum > 0.0)) bad(fmt::format("vertex {}: weights sum to 0", v));
  }
  for (std::size_t t = 0; t < rig.triangles.size(); ++t)
    for (auto c : rig.triangles[t])
      if (c >= nv) bad(fmt::format("triangle {}: vertex index out of range", t));
}

SkinnedAnimation::SkinnedAnimation(SkinRig rig, const SkinOptions& opt, std::string label)
    : rig_(std::move(rig)), opt_(opt), label_(std::move(label)) {
  validate(rig_);
  if (!(opt_.fps > 0.0) || !std::isfinite(opt_.fps)) throw std::invalid_argument("SkinOptions: fps must be > 0");
  const std::size_t nv = rig_.bind_positions.size();
  // Canonical influences: sorted by palette entry, weights normalised to sum 1.
  std::size_t max_inf = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    auto* b = rig_.influences.data() + rig_.influence_begin[v];
    auto* e = rig_.influences.data() + rig_.influence_begin[v + 1];
    std::sort(b, e, [](const SkinInfluence& x, const SkinInfluence& y) {
      return x.palette != y.palette ? x.palette < y.palette : x.weight < y.weight;
    });
    double sum = 0.0;
    for (auto* p = b; p != e; ++p) sum += p->weight;
    for (auto* p = b; p != e; ++p) p->weight /= sum;
    max_inf = std::max<std::size_t>(max_inf, static_cast<std::size_t>(e - b));
  }
  if (opt_.weld && nv > 0) {
    // Key frames for the welder: the bind position, then one pseudo-position per influence slot.
    VertexWelder welder(nv);
    welder.add_frame(rig_.bind_positions);
    std::vector<Vec3> key(nv);
    for (std::size_t slot = 0; slot < max_inf; ++slot) {
      for (std::size_t v = 0; v < nv; ++v) {
        const auto b = rig_.influence_begin[v], e = rig_.influence_begin[v + 1];
        key[v] = b + slot < e ? Vec3(rig_.influences[b + slot].palette, rig_.influences[b + slot].weight, 0.0)
                              : Vec3(-1.0, 0.0, 0.0);
      }
      welder.add_frame(key);
    }
    const WeldMap w = welder.finish();
    merged_ = w.merged();
    if (!w.identity()) {
      std::vector<Vec3> pos = w.gather(rig_.bind_positions);
      std::vector<std::uint32_t> begin{0};
      std::vector<SkinInfluence> inf;
      for (const auto r : w.representative) {
        for (auto i = rig_.influence_begin[r]; i < rig_.influence_begin[r + 1]; ++i) inf.push_back(rig_.influences[i]);
        begin.push_back(static_cast<std::uint32_t>(inf.size()));
      }
      rig_.triangles = w.apply(rig_.triangles);
      rig_.bind_positions = std::move(pos);
      rig_.influence_begin = std::move(begin);
      rig_.influences = std::move(inf);
    }
  }
  global_.resize(rig_.nodes.size());
  palette_.resize(rig_.palette_node.size());
  if (!rig_.tracks.empty()) {
    const double seconds = rig_.duration_ticks / rig_.ticks_per_second;
    frames_ = static_cast<std::size_t>(std::floor(seconds * opt_.fps + 1e-9)) + 1;
  }
  std::vector<Vec3> p(rig_.bind_positions.size());
  // Rest: the nodes' own transforms; for a still "animation" (one frame) its only pose, so that
  // rest() equals every positions() of a static source.
  pose(0.0, frames_ == 1 && !rig_.tracks.empty());
  skin(p);
  rest_ = Mesh(rig_.triangles, std::move(p));
}

void SkinnedAnimation::pose(double ticks, bool animated) {
  for (std::size_t n = 0; n < rig_.nodes.size(); ++n) {
    const SkeletonNode& nd = rig_.nodes[n];
    Affine3 local = nd.rest;
    if (animated && nd.track >= 0) {
      const NodeTrack& tr = rig_.tracks[static_cast<std::size_t>(nd.track)];
      const Vec3 t = sample(tr.t_times, tr.t_keys, tr.rest_t, ticks);
      const Eigen::Quaterniond r = sample(tr.r_times, tr.r_keys, tr.rest_r, ticks).normalized();
      const Vec3 s = sample(tr.s_times, tr.s_keys, tr.rest_s, ticks);
      local.linear() = r.toRotationMatrix() * s.asDiagonal();
      local.translation() = t;
    }
    global_[n] = nd.parent >= 0 ? global_[static_cast<std::size_t>(nd.parent)] * local : local;
  }
  for (std::size_t j = 0; j < palette_.size(); ++j)
    palette_[j] = (global_[rig_.palette_node[j]] * rig_.palette_offset[j]).matrix().topRows<3>();
}

void SkinnedAnimation::skin(std::span<Vec3> out) const {
  const std::size_t nv = rig_.bind_positions.size();
  auto body = [&](std::size_t lo, std::size_t hi) {
    for (std::size_t v = lo; v < hi; ++v) {
      const auto b = rig_.influence_begin[v], e = rig_.influence_begin[v + 1];
      const Vec3& p = rig_.bind_positions[v];
      if (e - b == 1) {
        const auto& m = palette_[rig_.influences[b].palette];
        out[v] = m.leftCols<3>() * p + m.col(3);
        continue;
      }
      Eigen::Matrix<double, 3, 4> m = Eigen::Matrix<double, 3, 4>::Zero();
      for (auto i = b; i < e; ++i) m += rig_.influences[i].weight * palette_[rig_.influences[i].palette];
      out[v] = m.leftCols<3>() * p + m.col(3);
    }
  };
  constexpr std::size_t kGrain = 4096;
  if (nv < kGrain) {
    body(0, nv);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, kGrain), [&](const auto& r) { body(r.begin(), r.end()); });
}

void SkinnedAnimation::positions_at_ticks(double ticks, std::span<Vec3> out) {
  if (out.size() != rest_.vertex_count())
    throw std::invalid_argument(
        fmt::format("positions: out has {} entries, the mesh {} vertices", out.size(), rest_.vertex_count()));
  if (rig_.tracks.empty() || frames_ == 1) {
    std::copy(rest_.positions().begin(), rest_.positions().end(), out.begin());
    return;
  }
  pose(ticks, true);
  skin(out);
}

void SkinnedAnimation::positions(double frame, std::span<Vec3> out) {
  (void)split_frame_time(frame, frames_);  // range check (std::out_of_range)
  positions_at_ticks(frame / opt_.fps * rig_.ticks_per_second, out);
}

std::string SkinnedAnimation::describe() const {
  return fmt::format("skinned {} ({} frames at {} fps, {} nodes, {} animated, {} palette entries, {} vertices, {} "
                     "triangles{})",
                     label_, frames_, opt_.fps, rig_.nodes.size(), rig_.tracks.size(), rig_.palette_node.size(),
                     rest_.vertex_count(), rest_.triangle_count(),
                     opt_.weld ? fmt::format(", welded {} vertices", merged_) : std::string());
}

}  // namespace ptc
