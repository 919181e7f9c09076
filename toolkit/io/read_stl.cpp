// STL reader, ascii and binary. STL stores a triangle soup (three corner positions per facet, no
// indices); corners whose coordinates are bit-identical (treating -0.0 as 0.0) are welded into
// one vertex, which gives the mesh its topology. Nothing else is merged (no tolerance).
//
// Binary or ascii? A binary file may begin with "solid" too. A file is binary when its size is
// exactly 84 + 50 * (facet count at byte 80), unless it begins with "solid" and parses as ascii;
// otherwise it is ascii when it begins with "solid", binary (and then too short or too long for
// its count) when it does not. One more case: a file that begins with "solid", does not parse as
// ascii and holds a NUL byte (no ascii STL does; a binary one's count and zeros do) is binary
// (exporters that write "solid" into the header and pad the file, or write a count of 0).
#include <array>
#include <bit>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "toolkit/io/readers.h"
#include "toolkit/io/text_scan.h"

namespace ptc::io {
namespace {

// Open-addressing hash set of positions, mapping bit-identical corners to one vertex id. A vertex
// keeps the coordinates of its first corner (so a -0.0 seen first stays -0.0).
class Welder {
 public:
  // A closed triangle mesh has about corners / 6 distinct vertices; start with room for that at a
  // load factor below 1/2 and grow when the soup welds less.
  explicit Welder(std::size_t corners) {
    std::size_t cap = 16;
    while (cap < corners / 3) cap *= 2;
    slots_.assign(cap, kEmpty);
    pos_.reserve(corners / 6 + 16);
  }
  std::uint32_t id(const Vec3& p) {
    const Key k = key(p);
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = hash(k) & mask;; i = (i + 1) & mask) {
      const std::uint32_t s = slots_[i];
      if (s == kEmpty) {
        const auto v = static_cast<std::uint32_t>(pos_.size());
        slots_[i] = v;
        pos_.push_back(p);
        if (2 * pos_.size() > slots_.size()) grow();
        return v;
      }
      if (key(pos_[s]) == k) return s;
    }
  }
  [[nodiscard]] std::size_t size() const { return pos_.size(); }
  std::vector<Vec3>& positions() { return pos_; }

 private:
  using Key = std::array<std::uint64_t, 3>;
  static constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;
  static Key key(const Vec3& p) {
    // p[k] + 0.0 turns -0.0 into +0.0 and changes nothing else.
    return {std::bit_cast<std::uint64_t>(p[0] + 0.0), std::bit_cast<std::uint64_t>(p[1] + 0.0),
            std::bit_cast<std::uint64_t>(p[2] + 0.0)};
  }
  // splitmix64's finalizer over each word: float coordinates widened to double have 29 zero low
  // bits, so every bit of the key must reach the low bits used as the slot index.
  static std::uint64_t mix(std::uint64_t x) {
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
  }
  static std::uint64_t hash(const Key& b) { return mix(mix(mix(b[0]) ^ b[1]) ^ b[2]); }
  void grow() {
    std::vector<std::uint32_t> old(slots_.size() * 2, kEmpty);
    old.swap(slots_);
    const std::size_t mask = slots_.size() - 1;
    for (std::uint32_t s : old) {
      if (s == kEmpty) continue;
      std::size_t i = hash(key(pos_[s])) & mask;
      while (slots_[i] != kEmpty) i = (i + 1) & mask;
      slots_[i] = s;
    }
  }

  std::vector<std::uint32_t> slots_;
  std::vector<Vec3> pos_;
};

bool iequals(std::string_view a, std::string_view b);

// The text after a UTF-8 byte-order mark, if it starts with one.
std::string_view without_bom(std::string_view bytes) {
  return bytes.substr(0, 3) == "\xEF\xBB\xBF" ? bytes.substr(3) : bytes;
}

// "solid" in any case (the keywords are case-insensitive), after a UTF-8 byte-order mark and
// white space.
bool starts_with_solid(std::string_view bytes) {
  bytes = without_bom(bytes);
  std::size_t i = 0;
  while (i < bytes.size() && is_space(bytes[i])) ++i;
  return iequals(bytes.substr(i, 5), "solid");
}

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = static_cast<char>(x - 'A' + 'a');
    if (y >= 'A' && y <= 'Z') y = static_cast<char>(y - 'A' + 'a');
    if (x != y) return false;
  }
  return true;
}

LoadedMesh make_mesh(std::vector<Tri>&& tris, Welder& w, ReadReport&& report, const std::string& name) {
  report.welded_vertices = 3 * tris.size() - w.size();
  return finish(std::move(tris), std::move(w.positions()), std::move(report), name);
}

// ---- binary ------------------------------------------------------------------------------------
LoadedMesh read_binary(std::string_view bytes, const std::string& name) {
  if (bytes.size() < 84)
    throw InputError(name, byte_loc(bytes.size()), "header",
                     "file has " + std::to_string(bytes.size()) + " bytes; a binary STL needs at least 84");
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + 80, 4);
  if constexpr (std::endian::native == std::endian::big) n = __builtin_bswap32(n);
  const std::uint64_t left = bytes.size() - 84;
  if (n > left / 50)
    throw InputError(name, byte_loc(80), "header",
                     "header claims " + std::to_string(n) + " facets (" + std::to_string(50ull * n) +
                         " bytes) but the file has only " + std::to_string(left) + " bytes left");
  // Bytes after the last facet are ignored (some exporters pad files).
  ReadReport report;
  report.format = MeshFormat::Stl;
  report.binary = true;
  report.trailing_bytes = static_cast<std::size_t>(left - 50ull * n);
  Welder w(3ull * n);
  std::vector<Tri> tris;
  tris.reserve(n);
  // (facet f is triangle f: ReadReport::source_face stays empty)
  for (std::uint32_t f = 0; f < n; ++f) {
    const char* rec = bytes.data() + 84 + 50ull * f;
    Tri t{};
    for (int c = 0; c < 3; ++c) {
      Vec3 p;
      for (int k = 0; k < 3; ++k) {
        const std::size_t off = 12 + 12 * c + 4 * k;
        std::uint32_t u = 0;
        std::memcpy(&u, rec + off, 4);
        if constexpr (std::endian::native == std::endian::big) u = __builtin_bswap32(u);
        const double v = std::bit_cast<float>(u);
        if (const char* why = non_finite(v))
          throw InputError(name, byte_loc(84 + 50ull * f + off), "facet " + std::to_string(f),
                           "vertex " + std::to_string(c) + " coordinate " + std::to_string(k) + " " + why);
        p[k] = v;
      }
      t[c] = w.id(p);
    }
    tris.push_back(t);
  }
  report.faces = n;
  return make_mesh(std::move(tris), w, std::move(report), name);
}

// ---- ascii -------------------------------------------------------------------------------------
class AsciiStl {
 public:
  AsciiStl(std::string_view bytes, const std::string& name)
      : tr_(without_bom(bytes), 1), bytes_(without_bom(bytes)), name_(name) {}

  LoadedMesh parse() {
    ReadReport report;
    report.format = MeshFormat::Stl;
    // A facet takes at least ~60 bytes of text; reserve for about that many.
    Welder w(3 * (bytes_.size() / 64 + 1));
    std::vector<Tri> tris;
    std::string_view t = tr_.next();
    if (t.empty()) fail_header(bytes_.empty() ? "file is empty" : "file has no 'solid' line");
    for (;;) {  // one "solid ... endsolid" block per pass; a file may hold several
      if (!iequals(t, "solid")) fail_header("expected 'solid', found " + quote(t));
      tr_.skip_line();  // the solid's name
      for (;;) {
        t = tr_.next();
        if (iequals(t, "endsolid")) break;
        facet_ = tris.size();
        if (t.empty()) fail("file ends before 'endsolid' (after " + std::to_string(tris.size()) + (tris.size() == 1 ? " facet)" : " facets)"));
        if (!iequals(t, "facet")) fail("expected 'facet' or 'endsolid', found " + quote(t));
        expect("normal");
        for (int k = 0; k < 3; ++k) (void)number("normal", 0, k);  // ignored
        expect("outer");
        expect("loop");
        Tri tri{};
        for (int c = 0; c < 3; ++c) {
          expect("vertex");
          Vec3 p;
          for (int k = 0; k < 3; ++k) {
            p[k] = number("vertex", c, k);
            if (const char* why = non_finite(p[k])) fail(what("vertex", c, k) + " " + why);
          }
          tri[c] = w.id(p);
        }
        expect("endloop");
        expect("endfacet");
        if (tris.size() >= kMaxElements) fail("more facets than 32-bit ids can number");
        tris.push_back(tri);  // (facet f is triangle f: ReadReport::source_face stays empty)
      }
      tr_.skip_line();  // "endsolid name"
      t = tr_.next();
      if (t.empty()) break;
    }
    report.faces = tris.size();
    return make_mesh(std::move(tris), w, std::move(report), name_);
  }

 private:
  [[noreturn]] void fail_header(const std::string& reason) const {
    throw InputError(name_, line_loc(tr_.line()), "header", reason);
  }
  [[noreturn]] void fail(const std::string& reason) const {
    throw InputError(name_, line_loc(tr_.line()), "facet " + std::to_string(facet_), reason);
  }
  static std::string what(const char* kind, int corner, int k) {
    std::string s = kind;
    if (s == "vertex") s.append(" ").append(std::to_string(corner));
    return s.append(" coordinate ").append(std::to_string(k));
  }
  void expect(std::string_view kw) {
    const std::string_view t = tr_.next();
    if (t.empty()) fail("file ends where '" + std::string(kw) + "' was expected");
    if (!iequals(t, kw)) fail("expected '" + std::string(kw) + "', found " + quote(t));
  }
  double number(const char* kind, int corner, int k) {
    const std::string_view t = tr_.next();
    if (t.empty()) fail("file ends where " + what(kind, corner, k) + " was expected");
    double v = 0;
    const NumStatus st = parse_double(t, v);
    if (st != NumStatus::Ok)
      fail(what(kind, corner, k) + " " + quote(t) +
           (st == NumStatus::Garbled ? " is not a number" : " is out of range"));
    return v;
  }

  std::size_t facet_ = 0;
  TokenReader tr_;
  std::string_view bytes_;
  const std::string& name_;
};

}  // namespace

LoadedMesh read_stl(std::string_view bytes, const std::string& name) {
  const bool solid = starts_with_solid(bytes);
  bool size_fits = false;
  if (bytes.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    if constexpr (std::endian::native == std::endian::big) n = __builtin_bswap32(n);
    size_fits = bytes.size() == 84 + 50ull * n;
  }
  if (size_fits) {
    if (!solid) return read_binary(bytes, name);
    try {
      return AsciiStl(bytes, name).parse();
    } catch (const InputError&) {
      return read_binary(bytes, name);  // "solid" in the 80-byte header of a binary file
    }
  }
  if (solid) {
    try {
      return AsciiStl(bytes, name).parse();
    } catch (const InputError&) {
      if (bytes.find('\0') == std::string_view::npos) throw;
      return read_binary(bytes, name);  // binary bytes after a "solid" header (see the top)
    }
  }
  return read_binary(bytes, name);
}

}  // namespace ptc::io
