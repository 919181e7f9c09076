#include "toolkit/anim/md3.h"
#include "toolkit/core/cancel.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "toolkit/anim/frame_sequence.h"
#include "toolkit/anim/weld.h"
#include "toolkit/core/error.h"
#include "toolkit/io/atomic_file.h"
#include "toolkit/core/input_log.h"

namespace ptc {

namespace {

constexpr std::size_t kHeaderSize = 108, kFrameSize = 56, kTagSize = 112, kSurfaceHeaderSize = 108;
constexpr std::size_t kTriangleSize = 12, kShaderSize = 68, kStSize = 8, kXyzSize = 8;
constexpr int kVersion = 15;
constexpr double kXyzScale = 1.0 / 64.0;

// Bounds-checked little-endian reads; every failure names the file, offset and field.
class Bytes {
 public:
  Bytes(std::string_view b, const std::string& name) : b_(b), name_(name) {}
  std::size_t size() const { return b_.size(); }
  void need(std::uint64_t off, std::uint64_t len, const std::string& field) const {
    if (off > b_.size() || len > b_.size() - off)
      throw InputError(name_, byte_loc(off), field,
                       fmt::format("truncated: needs {} bytes, the file ends at byte {}", len, b_.size()));
  }
  std::int32_t i32(std::uint64_t off, const std::string& field) const {
    need(off, 4, field);
    std::uint32_t v = 0;
    for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(b_[off + static_cast<unsigned>(i)]);
    return static_cast<std::int32_t>(v);
  }
  // A count or offset: must be >= 0.
  std::uint32_t u31(std::uint64_t off, const std::string& field) const {
    const std::int32_t v = i32(off, field);
    if (v < 0) throw InputError(name_, byte_loc(off), field, fmt::format("negative value {}", v));
    return static_cast<std::uint32_t>(v);
  }
  std::int16_t i16(std::uint64_t off, const std::string& field) const {
    need(off, 2, field);
    const auto lo = static_cast<unsigned char>(b_[off]), hi = static_cast<unsigned char>(b_[off + 1]);
    return static_cast<std::int16_t>(static_cast<std::uint16_t>(lo | (hi << 8)));
  }
  std::string str(std::uint64_t off, std::size_t len, const std::string& field) const {
    need(off, len, field);
    std::string s(b_.substr(off, len));
    s.resize(std::strlen(s.c_str()));
    return s;
  }
  [[noreturn]] void fail(std::uint64_t off, const std::string& field, const std::string& reason) const {
    throw InputError(name_, byte_loc(off), field, reason);
  }

 private:
  std::string_view b_;
  const std::string& name_;
};

}  // namespace

Md3Model parse_md3(std::string_view bytes, const std::string& name) {
  const Bytes b(bytes, name);
  b.need(0, kHeaderSize, "header");
  if (bytes.substr(0, 4) != "IDP3") b.fail(0, "header ident", "not an MD3 file (magic is not IDP3)");
  const std::int32_t version = b.i32(4, "header version");
  if (version != kVersion) b.fail(4, "header version", fmt::format("version {} (expected {})", version, kVersion));
  Md3Model m;
  m.name = b.str(8, 64, "header name");
  const std::uint32_t num_frames = b.u31(76, "header num_frames");
  const std::uint32_t num_tags = b.u31(80, "header num_tags");
  const std::uint32_t num_surfaces = b.u31(84, "header num_surfaces");
  const std::uint32_t ofs_frames = b.u31(92, "header ofs_frames");
  const std::uint32_t ofs_tags = b.u31(96, "header ofs_tags");
  const std::uint32_t ofs_surfaces = b.u31(100, "header ofs_surfaces");
  if (num_frames == 0) b.fail(76, "header num_frames", "no frames");
  if (num_surfaces == 0) b.fail(84, "header num_surfaces", "no surfaces");
  b.need(ofs_frames, std::uint64_t{num_frames} * kFrameSize, "frames (header ofs_frames/num_frames)");
  b.need(ofs_tags, std::uint64_t{num_frames} * num_tags * kTagSize, "tags (header ofs_tags/num_tags)");
  for (std::uint32_t k = 0; k < num_frames; ++k)
    m.frame_names.push_back(b.str(ofs_frames + std::uint64_t{k} * kFrameSize + 40, 16, fmt::format("frame {} name", k)));

  // First pass: surface headers, counts and ranges (nothing allocated by a count the file cannot hold).
  struct S {
    std::uint64_t start;
    std::uint32_t verts, tris, ofs_tris, ofs_xyz;
  };
  std::vector<S> ss;
  std::uint64_t total_verts = 0, total_tris = 0;
  std::uint64_t at = ofs_surfaces;
  for (std::uint32_t s = 0; s < num_surfaces; ++s) {
    const std::string sf = fmt::format("surface {} ", s);
    b.need(at, kSurfaceHeaderSize, sf + "header");
    if (bytes.substr(at, 4) != "IDP3") b.fail(at, sf + "ident", "surface magic is not IDP3");
    Md3Surface info;
    info.name = b.str(at + 4, 64, sf + "name");
    const std::uint32_t sframes = b.u31(at + 72, sf + "num_frames");
    const std::uint32_t shaders = b.u31(at + 76, sf + "num_shaders");
    const std::uint32_t verts = b.u31(at + 80, sf + "num_verts");
    const std::uint32_t tris = b.u31(at + 84, sf + "num_triangles");
    const std::uint32_t ofs_tris = b.u31(at + 88, sf + "ofs_triangles");
    const std::uint32_t ofs_shaders = b.u31(at + 92, sf + "ofs_shaders");
    const std::uint32_t ofs_st = b.u31(at + 96, sf + "ofs_st");
    const std::uint32_t ofs_xyz = b.u31(at + 100, sf + "ofs_xyznormal");
    const std::uint32_t ofs_end = b.u31(at + 104, sf + "ofs_end");
    if (sframes != num_frames)
      b.fail(at + 72, sf + "num_frames", fmt::format("{} frames, the header has {}", sframes, num_frames));
    b.need(at + ofs_tris, std::uint64_t{tris} * kTriangleSize, sf + "triangles (ofs_triangles/num_triangles)");
    b.need(at + ofs_shaders, std::uint64_t{shaders} * kShaderSize, sf + "shaders (ofs_shaders/num_shaders)");
    b.need(at + ofs_st, std::uint64_t{verts} * kStSize, sf + "st (ofs_st/num_verts)");
    b.need(at + ofs_xyz, std::uint64_t{verts} * num_frames * kXyzSize, sf + "xyznormal (ofs_xyznormal/num_verts/num_frames)");
    if (s + 1 < num_surfaces) {
      if (ofs_end < kSurfaceHeaderSize) b.fail(at + 104, sf + "ofs_end", fmt::format("{} is inside the surface header", ofs_end));
      b.need(at, ofs_end, sf + "ofs_end");
    }
    info.first_vertex = static_cast<std::uint32_t>(total_verts);
    info.vertex_count = verts;
    info.triangle_count = tris;
    m.surfaces.push_back(info);
    ss.push_back({at, verts, tris, ofs_tris, ofs_xyz});
    total_verts += verts;
    total_tris += tris;
    if (total_verts > std::numeric_limits<std::uint32_t>::max())
      b.fail(at + 80, sf + "num_verts", "more than 2^32-1 vertices in all");
    at += ofs_end;
  }
  if (total_tris == 0) b.fail(84, "header num_surfaces", "no triangles in any surface");

  m.triangles.reserve(total_tris);
  for (std::size_t s = 0; s < ss.size(); ++s) {
    const S& x = ss[s];
    for (std::uint32_t t = 0; t < x.tris; ++t) {
      Tri tri;
      for (unsigned c = 0; c < 3; ++c) {
        const std::uint64_t off = x.start + x.ofs_tris + std::uint64_t{t} * kTriangleSize + 4u * c;
        const std::string field = fmt::format("surface {} triangle {} index {}", s, t, c);
        const std::int32_t v = b.i32(off, field);
        if (v < 0 || static_cast<std::uint32_t>(v) >= x.verts)
          b.fail(off, field, fmt::format("vertex index {} outside [0, {})", v, x.verts));
        tri[c] = m.surfaces[s].first_vertex + static_cast<std::uint32_t>(v);
      }
      m.triangles.push_back(tri);
    }
  }
  m.frames.assign(num_frames, std::vector<Vec3>(total_verts));
  for (std::size_t s = 0; s < ss.size(); ++s) {
    const S& x = ss[s];
    for (std::uint32_t k = 0; k < num_frames; ++k)
      for (std::uint32_t v = 0; v < x.verts; ++v) {
        const std::uint64_t off = x.start + x.ofs_xyz + (std::uint64_t{k} * x.verts + v) * kXyzSize;
        const std::string field = "xyznormal";  // ranges were checked above; reads cannot fail
        m.frames[k][m.surfaces[s].first_vertex + v] =
            Vec3(b.i16(off, field), b.i16(off + 2, field), b.i16(off + 4, field)) * kXyzScale;
      }
  }
  return m;
}

Md3Model read_md3(const std::filesystem::path& path) {
  const BlockingWaitFor waiting(path);  // (a FIFO: a stop request ends the run at once meanwhile)
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string(), "", "", std::string("cannot open: ") + std::strerror(errno));
  std::stringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path.string(), "", "", "read error");
  return parse_md3(ss.str(), path.string());
}

// ---------------------------------------------------------------------------------------------
// Writer

namespace {

void put_i32(std::string& s, std::int32_t v) {
  const auto u = static_cast<std::uint32_t>(v);
  for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>((u >> (8 * i)) & 0xffu));
}
void put_f32(std::string& s, float f) {
  std::uint32_t u = 0;
  std::memcpy(&u, &f, 4);
  put_i32(s, static_cast<std::int32_t>(u));
}
void put_i16(std::string& s, std::int16_t v) {
  const auto u = static_cast<std::uint16_t>(v);
  s.push_back(static_cast<char>(u & 0xffu));
  s.push_back(static_cast<char>(u >> 8));
}
void put_str(std::string& s, const std::string& v, std::size_t len) {
  std::string x = v.substr(0, len - 1);
  x.resize(len, '\0');
  s += x;
}

}  // namespace

std::string encode_md3(const std::vector<Md3SurfaceData>& surfaces, const std::string& model_name) {
  if (surfaces.empty()) throw InputError(model_name, "", "surfaces", "an MD3 file needs at least one surface");
  const std::size_t frames = surfaces.front().frames.size();
  if (frames == 0) throw InputError(model_name, "", "frames", "an MD3 file needs at least one frame");
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    if (surfaces[s].frames.size() != frames)
      throw InputError(model_name, "", fmt::format("surface {}", s), "surfaces differ in frame count");
    for (const auto& f : surfaces[s].frames)
      if (f.size() != surfaces[s].frames.front().size())
        throw InputError(model_name, "", fmt::format("surface {}", s), "frames differ in vertex count");
  }
  std::string out;
  // header
  out += "IDP3";
  put_i32(out, kVersion);
  put_str(out, model_name, 64);
  put_i32(out, 0);  // flags
  put_i32(out, static_cast<std::int32_t>(frames));
  put_i32(out, 0);  // tags
  put_i32(out, static_cast<std::int32_t>(surfaces.size()));
  put_i32(out, 0);  // skins
  const std::size_t ofs_frames = kHeaderSize, ofs_tags = ofs_frames + frames * kFrameSize, ofs_surfaces = ofs_tags;
  put_i32(out, static_cast<std::int32_t>(ofs_frames));
  put_i32(out, static_cast<std::int32_t>(ofs_tags));
  put_i32(out, static_cast<std::int32_t>(ofs_surfaces));
  const std::size_t ofs_end_pos = out.size();
  put_i32(out, 0);  // patched below
  // frames: bounds over all surfaces
  for (std::size_t k = 0; k < frames; ++k) {
    Box3 box;
    for (const auto& s : surfaces)
      for (const auto& p : s.frames[k]) box.extend(p);
    if (box.empty()) box.lo = box.hi = Vec3::Zero();
    for (int i = 0; i < 3; ++i) put_f32(out, static_cast<float>(box.lo[i]));
    for (int i = 0; i < 3; ++i) put_f32(out, static_cast<float>(box.hi[i]));
    for (int i = 0; i < 3; ++i) put_f32(out, 0.0f);
    put_f32(out, static_cast<float>(0.5 * box.extent().norm()));
    put_str(out, fmt::format("frame{}", k), 16);
  }
  for (std::size_t si = 0; si < surfaces.size(); ++si) {
    const auto& s = surfaces[si];
    const std::size_t nv = s.frames.front().size(), nt = s.triangles.size();
    const std::size_t ofs_tris = kSurfaceHeaderSize, ofs_shaders = ofs_tris + nt * kTriangleSize;
    const std::size_t ofs_st = ofs_shaders + kShaderSize, ofs_xyz = ofs_st + nv * kStSize;
    const std::size_t ofs_end = ofs_xyz + frames * nv * kXyzSize;
    out += "IDP3";
    put_str(out, s.name, 64);
    put_i32(out, 0);
    put_i32(out, static_cast<std::int32_t>(frames));
    put_i32(out, 1);  // one shader
    put_i32(out, static_cast<std::int32_t>(nv));
    put_i32(out, static_cast<std::int32_t>(nt));
    put_i32(out, static_cast<std::int32_t>(ofs_tris));
    put_i32(out, static_cast<std::int32_t>(ofs_shaders));
    put_i32(out, static_cast<std::int32_t>(ofs_st));
    put_i32(out, static_cast<std::int32_t>(ofs_xyz));
    put_i32(out, static_cast<std::int32_t>(ofs_end));
    for (const Tri& t : s.triangles)
      for (int c = 0; c < 3; ++c) {
        if (t[c] >= nv) throw InputError(model_name, "", fmt::format("surface {} triangle", si), "vertex index out of range");
        put_i32(out, static_cast<std::int32_t>(t[c]));
      }
    put_str(out, "", 64);
    put_i32(out, 0);
    for (std::size_t v = 0; v < nv; ++v) {
      put_f32(out, 0.0f);
      put_f32(out, 0.0f);
    }
    for (std::size_t k = 0; k < frames; ++k)
      for (std::size_t v = 0; v < nv; ++v) {
        for (int i = 0; i < 3; ++i) {
          const double q = std::round(s.frames[k][v][i] * 64.0);
          if (!(q >= -32768.0 && q <= 32767.0))
            throw InputError(model_name, "", fmt::format("surface {} frame {} vertex {}", si, k, v),
                             "coordinate does not fit MD3's int16 range (|x| < 512)");
          put_i16(out, static_cast<std::int16_t>(q));
        }
        put_i16(out, 0);  // normal (lat/lng), not used
      }
  }
  const std::string end = [&] {
    std::string e;
    put_i32(e, static_cast<std::int32_t>(out.size()));
    return e;
  }();
  out.replace(ofs_end_pos, 4, end);
  return out;
}

void write_md3(const std::filesystem::path& path, const std::vector<Md3SurfaceData>& surfaces) {
  const std::string bytes = encode_md3(surfaces, path.stem().string());
  AtomicFile f(path);
  f.write(bytes);
  f.commit();
}

// ---------------------------------------------------------------------------------------------
// Animation

AnimationPtr load_md3(const std::filesystem::path& path, const Md3Options& opt) {
  note_input_file(path);
  Md3Model m = read_md3(path);
  if (!(opt.fps > 0.0) || !std::isfinite(opt.fps)) throw InputError(path.string(), "", "fps", "must be > 0");
  if (opt.flip_winding)
    for (Tri& t : m.triangles) std::swap(t[1], t[2]);
  if (opt.y_up)
    for (auto& f : m.frames)
      for (Vec3& p : f) p = Vec3(p.x(), p.z(), -p.y());
  std::size_t merged = 0;
  std::vector<Tri> tris = std::move(m.triangles);
  if (opt.weld) {
    const WeldMap w = weld_frames(m.frames);
    merged = w.merged();
    if (!w.identity()) {
      tris = w.apply(tris);
      for (auto& f : m.frames) f = w.gather(f);
    }
  }
  const std::size_t nf = m.frames.size(), nv = m.frames.front().size(), nt = tris.size();
  return std::make_unique<KeyframeAnimation>(
      std::move(tris), std::move(m.frames), opt.fps,
      fmt::format("md3 {} ({} frames, {} surfaces, {} vertices, {} triangles{})", path.string(), nf, m.surfaces.size(),
                  nv, nt, opt.weld ? fmt::format(", welded {} vertices", merged) : std::string()));
}

}  // namespace ptc
