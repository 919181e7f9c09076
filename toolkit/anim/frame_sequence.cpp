#include "toolkit/anim/frame_sequence.h"

#include <fnmatch.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "toolkit/core/error.h"
#include "toolkit/io/mesh_io.h"
#include "toolkit/core/input_log.h"

namespace ptc {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// KeyframeAnimation

KeyframeAnimation::KeyframeAnimation(std::vector<Tri> triangles, std::vector<std::vector<Vec3>> frames,
                                     double fps, std::string description)
    : frames_(frames.size()), fps_(fps), description_(std::move(description)) {
  if (frames.empty()) throw std::invalid_argument("KeyframeAnimation: no frames");
  if (!(fps > 0.0) || !std::isfinite(fps)) throw std::invalid_argument("KeyframeAnimation: fps must be > 0");
  verts_ = frames.front().size();
  data_.reserve(frames_ * verts_);
  for (auto& f : frames) {
    if (f.size() != verts_) throw std::invalid_argument("KeyframeAnimation: frames differ in size");
    data_.insert(data_.end(), f.begin(), f.end());
    std::vector<Vec3>().swap(f);  // release as we go: peak memory ~ one copy
  }
  rest_ = Mesh(std::move(triangles), std::vector<Vec3>(data_.begin(), data_.begin() + static_cast<std::ptrdiff_t>(verts_)));
}

std::span<const Vec3> KeyframeAnimation::frame(std::size_t k) const {
  if (k >= frames_) throw std::out_of_range(fmt::format("KeyframeAnimation::frame: {} >= {}", k, frames_));
  return std::span<const Vec3>(data_).subspan(k * verts_, verts_);
}

void KeyframeAnimation::positions(double frame_time, std::span<Vec3> out) {
  if (out.size() != verts_)
    throw std::invalid_argument(fmt::format("positions: out has {} entries, the mesh {} vertices", out.size(), verts_));
  const FrameTime ft = split_frame_time(frame_time, frames_);
  lerp_frames(frame(ft.k), ft.a > 0.0 ? frame(ft.k + 1) : frame(ft.k), ft.a, out);
}

FrameTime split_frame_time(double t, std::size_t frame_count) {
  if (frame_count == 0) throw std::out_of_range("frame time: the source has no frames");
  if (frame_count == 1 && std::isfinite(t)) return {};  // a single frame is static: any time shows it
  const double last = static_cast<double>(frame_count - 1);
  if (!(t >= 0.0 && t <= last))  // also rejects NaN
    throw std::out_of_range(fmt::format("frame time {} outside [0, {}]", t, last));
  FrameTime ft;
  const double k = std::floor(t);
  ft.k = static_cast<std::size_t>(k);
  ft.a = t - k;
  if (ft.k + 1 >= frame_count) ft.a = 0.0;  // t == last exactly
  return ft;
}

void lerp_frames(std::span<const Vec3> f0, std::span<const Vec3> f1, double a, std::span<Vec3> out) {
  const std::size_t n = out.size();
  if (f0.size() != n || f1.size() != n) throw std::invalid_argument("lerp_frames: sizes differ");
  constexpr std::size_t kGrain = 16384;
  if (a == 0.0) {
    if (n < kGrain) {
      std::copy(f0.begin(), f0.end(), out.begin());
      return;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain), [&](const auto& r) {
      std::copy(f0.begin() + static_cast<std::ptrdiff_t>(r.begin()), f0.begin() + static_cast<std::ptrdiff_t>(r.end()),
                out.begin() + static_cast<std::ptrdiff_t>(r.begin()));
    });
    return;
  }
  const double b = 1.0 - a;
  auto body = [&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) out[i] = b * f0[i] + a * f1[i];
  };
  if (n < kGrain) {
    body(0, n);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, kGrain),
                    [&](const auto& r) { body(r.begin(), r.end()); });
}

// ---------------------------------------------------------------------------------------------
// File lists

bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  auto digit = [](char c) { return c >= '0' && c <= '9'; };
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      std::size_t i1 = i, j1 = j;
      while (i1 < a.size() && a[i1] == '0') ++i1;  // leading zeros do not change the value
      while (j1 < b.size() && b[j1] == '0') ++j1;
      std::size_t i2 = i1, j2 = j1;
      while (i2 < a.size() && digit(a[i2])) ++i2;
      while (j2 < b.size() && digit(b[j2])) ++j2;
      if (i2 - i1 != j2 - j1) return i2 - i1 < j2 - j1;  // fewer significant digits = smaller
      const int c = a.compare(i1, i2 - i1, b, j1, j2 - j1);
      if (c != 0) return c < 0;
      i = i2;
      j = j2;
      continue;
    }
    if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
    ++i;
    ++j;
  }
  if ((a.size() - i) != (b.size() - j)) return (a.size() - i) < (b.size() - j);
  return a < b;  // equal by value ("f01" vs "f1"): bytewise, so the order is total
}

bool is_glob_pattern(const std::string& s) {
  return s.find_first_of("*?[") != std::string::npos;
}

namespace {

bool is_frame_extension(const fs::path& p) {
  const auto f = format_from_extension(p);
  return f && (*f == MeshFormat::Obj || *f == MeshFormat::Ply || *f == MeshFormat::Off);
}

// The runs of decimal digits in a name, in order, as numbers (nothing for a run of more than 18
// digits: such a name is not numbered by a counter here).
std::optional<std::vector<std::uint64_t>> digit_runs(const std::string& name) {
  std::vector<std::uint64_t> runs;
  for (std::size_t i = 0; i < name.size();) {
    if (!std::isdigit(static_cast<unsigned char>(name[i]))) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j < name.size() && std::isdigit(static_cast<unsigned char>(name[j]))) ++j;
    if (j - i > 18) return std::nullopt;
    runs.push_back(std::stoull(name.substr(i, j - i)));
    i = j;
  }
  return runs;
}

// Frames are the files in name order, whatever numbers their names carry. The counter of two
// neighbouring names is the one run of digits in which they differ (frame_0001_v2 and
// frame_0002_v2: the first); when a counter skips (frame_0000, frame_0002), a note says which
// file a frame index then reads, so that a missing file is not taken for a frame. Names shaped
// differently, or differing in more than one run, carry no counter to check.
void note_numbering_gap(const std::string& input, const std::vector<std::pair<std::string, fs::path>>& sorted) {
  for (std::size_t k = 1; k < sorted.size(); ++k) {
    const auto a = digit_runs(sorted[k - 1].first), b = digit_runs(sorted[k].first);
    if (!a || !b || a->size() != b->size()) return;
    std::size_t differing = 0, at = 0;
    for (std::size_t i = 0; i < a->size(); ++i)
      if ((*a)[i] != (*b)[i]) ++differing, at = i;
    if (differing != 1) return;
    if ((*b)[at] != (*a)[at] + 1) {
      read_note(input, fmt::format("the frame files' numbers are not consecutive ({} is followed by {}): frames are the "
                                   "files in name order, so frame {} reads {}",
                                   sorted[k - 1].first, sorted[k].first, k, sorted[k].first));
      return;
    }
  }
}

}  // namespace

std::vector<fs::path> list_frame_files(const std::string& dir_or_glob) {
  std::error_code ec;
  fs::path dir;
  std::string pattern;
  if (is_glob_pattern(dir_or_glob)) {
    const fs::path p(dir_or_glob);
    dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    pattern = p.filename().string();
    if (is_glob_pattern(dir.string()))
      throw InputError(dir_or_glob, "", "pattern", "wildcards are only supported in the file name, not in folders");
  } else {
    dir = dir_or_glob;
  }
  if (!fs::is_directory(dir, ec))
    throw InputError(dir.string(), "", "", pattern.empty() ? "no such directory" : "the pattern's folder does not exist");
  std::vector<std::pair<std::string, fs::path>> found;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    const std::string name = it->path().filename().string();
    if (!pattern.empty()) {
      if (::fnmatch(pattern.c_str(), name.c_str(), FNM_PERIOD) != 0) continue;
    } else if (!is_frame_extension(it->path())) {
      continue;
    }
    found.emplace_back(name, it->path());
  }
  if (ec) throw InputError(dir.string(), "", "", "cannot list directory: " + ec.message());
  if (found.empty())
    throw InputError(dir_or_glob, "", "",
                     pattern.empty() ? "no .obj/.ply/.off frame files in the directory" : "no file matches the pattern");
  std::sort(found.begin(), found.end(), [](const auto& x, const auto& y) { return natural_less(x.first, y.first); });
  note_numbering_gap(dir_or_glob, found);
  std::vector<fs::path> files;
  files.reserve(found.size());
  for (auto& f : found) files.push_back(std::move(f.second));
  return files;
}

// ---------------------------------------------------------------------------------------------
// FrameSequence

namespace {

// Checks a frame's topology against the first frame's; InputError naming the first difference.
void check_topology(const fs::path& file, const Mesh& m, std::span<const Tri> first_tris, std::size_t first_verts,
                    const fs::path& first_file) {
  if (m.vertex_count() != first_verts)
    throw InputError(file.string(), "", "vertex count",
                     fmt::format("{} vertices, the first frame {} has {}", m.vertex_count(), first_file.string(), first_verts));
  if (m.triangle_count() != first_tris.size())
    throw InputError(file.string(), "", "triangle count",
                     fmt::format("{} triangles, the first frame {} has {}", m.triangle_count(), first_file.string(),
                                 first_tris.size()));
  const auto tris = m.triangles();
  for (std::size_t t = 0; t < tris.size(); ++t)
    if (tris[t] != first_tris[t])
      throw InputError(file.string(), "", fmt::format("triangle {}", t),
                       fmt::format("vertices ({}, {}, {}) differ from ({}, {}, {}) in the first frame {}", tris[t][0],
                                   tris[t][1], tris[t][2], first_tris[t][0], first_tris[t][1], first_tris[t][2],
                                   first_file.string()));
}

}  // namespace

FrameSequence::FrameSequence(const std::string& dir_or_glob, const FrameSequenceOptions& opt)
    : FrameSequence(list_frame_files(dir_or_glob), opt) {}

FrameSequence::FrameSequence(std::vector<fs::path> files, const FrameSequenceOptions& opt)
    : files_(std::move(files)), opt_(opt) {
  if (files_.empty()) throw InputError("", "", "", "a frame sequence needs at least one file");
  for (const fs::path& f : files_) note_input_file(f);  // (read lazily, per frame, later)
  if (!(opt_.fps > 0.0) || !std::isfinite(opt_.fps)) throw InputError("", "", "fps", "frames per second must be > 0");
  LoadedMesh first = read_mesh(files_[0]);
  raw_tris_ = first.mesh.shared_triangles();
  raw_vertices_ = first.mesh.vertex_count();
  const bool all_now = opt_.loading == FrameLoading::Eager || opt_.weld;
  std::vector<std::vector<Vec3>> frames;  // only when Eager
  if (opt_.loading == FrameLoading::Eager) frames.reserve(files_.size());
  if (all_now) {
    std::optional<VertexWelder> welder;
    if (opt_.weld) welder.emplace(raw_vertices_);
    for (std::size_t k = 0; k < files_.size(); ++k) {
      std::vector<Vec3> pos;
      if (k == 0) {
        pos.assign(first.mesh.positions().begin(), first.mesh.positions().end());
      } else {
        LoadedMesh m = read_mesh(files_[k]);
        check_topology(files_[k], m.mesh, *raw_tris_, raw_vertices_, files_[0]);
        pos.assign(m.mesh.positions().begin(), m.mesh.positions().end());
      }
      if (welder) welder->add_frame(pos);
      if (opt_.loading == FrameLoading::Eager) frames.push_back(std::move(pos));
    }
    if (welder) weld_ = welder->finish();
  }
  std::vector<Tri> tris = weld_ ? weld_->apply(*raw_tris_) : std::vector<Tri>(raw_tris_->begin(), raw_tris_->end());
  if (opt_.loading == FrameLoading::Eager) {
    if (weld_)
      for (auto& f : frames) f = weld_->gather(f);
    eager_ = std::make_unique<KeyframeAnimation>(std::move(tris), std::move(frames), opt_.fps, "");
    rest_ = eager_->rest();
  } else {
    std::vector<Vec3> p0(first.mesh.positions().begin(), first.mesh.positions().end());
    if (weld_) p0 = weld_->gather(p0);
    rest_ = Mesh(std::move(tris), p0);
    slot_[0].k = 0;
    slot_[0].pos = std::move(p0);
    next_slot_ = 1;
  }
}

std::vector<Vec3> FrameSequence::load(std::size_t k) const {
  LoadedMesh m = read_mesh(files_[k]);
  check_topology(files_[k], m.mesh, *raw_tris_, raw_vertices_, files_[0]);
  std::vector<Vec3> pos(m.mesh.positions().begin(), m.mesh.positions().end());
  return weld_ ? weld_->gather(pos) : pos;
}

const std::vector<Vec3>& FrameSequence::cached(std::size_t k) {
  for (auto& s : slot_)
    if (s.k == k) return s.pos;
  Slot& s = slot_[next_slot_];
  s.k = SIZE_MAX;  // stays invalid if load() throws
  s.pos = load(k);
  s.k = k;
  next_slot_ ^= 1;
  return s.pos;
}

void FrameSequence::positions(double frame_time, std::span<Vec3> out) {
  if (eager_) {
    eager_->positions(frame_time, out);
    return;
  }
  if (out.size() != rest_.vertex_count())
    throw std::invalid_argument(
        fmt::format("positions: out has {} entries, the mesh {} vertices", out.size(), rest_.vertex_count()));
  const FrameTime ft = split_frame_time(frame_time, files_.size());
  if (ft.a == 0.0) {
    const auto& f0 = cached(ft.k);
    lerp_frames(f0, f0, 0.0, out);
    return;
  }
  // Both frames must be in the cache at once: load k, then k+1 into the other slot.
  const auto& f0 = cached(ft.k);
  if (slot_[next_slot_].k == ft.k) next_slot_ ^= 1;  // never evict the frame just fetched
  const auto& f1 = cached(ft.k + 1);
  lerp_frames(f0, f1, ft.a, out);
}

std::string FrameSequence::describe() const {
  return fmt::format("frame sequence {} .. {} ({} frames, {} vertices, {} triangles, {}{})",
                     files_.front().string(), files_.back().filename().string(), files_.size(), rest_.vertex_count(),
                     rest_.triangle_count(), opt_.loading == FrameLoading::Eager ? "eager" : "lazy",
                     opt_.weld ? fmt::format(", welded {} vertices", merged_vertices()) : std::string());
}

}  // namespace ptc
