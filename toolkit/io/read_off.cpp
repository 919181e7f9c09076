// OFF reader. Line-based: a vertex line's first three numbers are x y z (colours, normals and
// texture coordinates of COFF/NOFF/STOFF... follow and are ignored); a face line is
// "n i0 ... i(n-1)" followed by optional colour values. '#' starts a comment anywhere, including
// before the header keyword (CGAL's sample files have such lines).
#include <algorithm>
#include <string>
#include <vector>

#include "toolkit/io/readers.h"
#include "toolkit/io/text_scan.h"

namespace ptc::io {
namespace {

// Every vertex and face line takes at least 2 bytes (a character and a line break; the last line
// may lack its break). Claims beyond that are rejected before anything is allocated; the bound is
// loose on purpose so that a short, malformed line is reported as what it is. Reservations use the
// shortest valid lines, "0 0 0" and "3 0 1 2".
constexpr std::size_t kMinLineBytes = 2;
constexpr std::size_t kMinVertexBytes = 6;
constexpr std::size_t kMinFaceBytes = 8;

struct OffParser {
  std::string_view bytes;
  const std::string& name;
  LineReader lines{bytes};

  [[noreturn]] void fail(const std::string& element, const std::string& reason) const {
    throw InputError(name, line_loc(lines.line()), element, reason);
  }
  [[noreturn]] void fail_at_end(const std::string& element, const std::string& reason) const {
    // Past the last line: name the line the file ends on (line 1 for an empty file).
    throw InputError(name, line_loc(lines.line() == 0 ? 1 : lines.line()), element, reason);
  }

  // "OFF", "COFF", "NOFF", "CNOFF", "STOFF", "STCNOFF", ...; "4OFF"/"nOFF" are not supported.
  void check_keyword(std::string_view kw) const {
    const auto bad = [&] { fail("header", "missing OFF header (found " + quote(kw) + ")"); };
    if (kw.size() < 3 || kw.substr(kw.size() - 3) != "OFF") bad();
    std::string_view prefix = kw.substr(0, kw.size() - 3);
    auto take = [&](std::string_view p) {
      if (prefix.substr(0, p.size()) == p) {
        prefix.remove_prefix(p.size());
        return true;
      }
      return false;
    };
    take("ST");
    take("C");
    take("N");
    const bool four = take("4");
    const bool ndim = take("n");
    if (!prefix.empty()) bad();
    if (four) fail("header", quote(kw) + " (homogeneous 4D coordinates) is not supported");
    if (ndim) fail("header", quote(kw) + " (n-dimensional OFF) is not supported");
  }

  std::uint64_t count(std::string_view tok, const char* what) const {
    std::int64_t v = 0;
    switch (parse_int(tok, v)) {
      case NumStatus::Ok: break;
      case NumStatus::OutOfRange: fail("header", std::string(what) + " count " + quote(tok) + " is too large");
      case NumStatus::Garbled: fail("header", std::string(what) + " count " + quote(tok) + " is not an integer");
    }
    if (v < 0) fail("header", std::string(what) + " count " + std::to_string(v) + " is negative");
    return static_cast<std::uint64_t>(v);
  }

  LoadedMesh parse() {
    std::string_view line;
    if (!lines.next_content(line)) {
      if (bytes.empty()) fail_at_end("header", "file is empty");
      fail_at_end("header", "missing OFF header (the file has only comments and blank lines)");
    }
    Fields head(line);
    std::string_view kw = head.next(), glued;
    // "OFF8 6 12": the vertex count glued to the keyword (written by some exporters) is read as
    // if a space separated them (docs/mesh_policy.md).
    if (const std::size_t at = kw.find("OFF"); at != std::string_view::npos && at + 3 < kw.size() &&
                                               kw[at + 3] >= '0' && kw[at + 3] <= '9') {
      glued = kw.substr(at + 3);
      kw = kw.substr(0, at + 3);
    }
    check_keyword(kw);
    std::string_view tok = glued.empty() ? head.next() : glued;
    if (tok == "BINARY") fail("header", "binary OFF is not supported");
    if (tok.empty()) {  // counts on the next content line
      if (!lines.next_content(line)) fail_at_end("header", "file ends before the vertex and face counts");
      head = Fields(line);
      tok = head.next();
    }
    const std::uint64_t nv = count(tok, "vertex");
    tok = head.next();
    if (tok.empty()) fail("header", "expected vertex, face and edge counts, found only the vertex count");
    const std::uint64_t nf = count(tok, "face");
    if (tok = head.next(); !tok.empty()) (void)count(tok, "edge");  // optional, unused

    // Check the claims against the bytes left before anything of their size is allocated.
    const std::size_t left = lines.remaining();
    if (nv > kMaxElements) fail("header", "vertex count " + std::to_string(nv) + " exceeds the 32-bit limit");
    if (nf > kMaxElements) fail("header", "face count " + std::to_string(nf) + " exceeds the 32-bit limit");
    if (nv * kMinLineBytes > left + 1)
      fail("header", "header claims " + std::to_string(nv) + " vertices but the file has only " + std::to_string(left) +
                         " bytes left");
    if ((nv + nf) * kMinLineBytes > left + 1)
      fail("header", "header claims " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                         " faces but the file has only " + std::to_string(left) + " bytes left");

    ReadReport report;
    report.format = MeshFormat::Off;
    std::vector<Vec3> pos;
    pos.reserve(std::min<std::uint64_t>(nv, left / kMinVertexBytes + 1));
    for (std::uint64_t i = 0; i < nv; ++i) {
      if (!lines.next_content(line))
        fail_at_end("vertex " + std::to_string(i),
                    "file ends after " + std::to_string(i) + " of " + std::to_string(nv) + " vertices");
      Fields f(line);
      Vec3 p;
      for (int k = 0; k < 3; ++k) {
        const std::string_view t = f.next();
        if (t.empty()) fail("vertex " + std::to_string(i), "expected 3 coordinates, found " + std::to_string(k));
        double v = 0;
        const NumStatus st = parse_double(t, v);
        if (st != NumStatus::Ok)
          fail("vertex " + std::to_string(i), "coordinate " + std::to_string(k) + " " + quote(t) +
                                                  (st == NumStatus::Garbled ? " is not a number" : " is out of range"));
        if (const char* why = non_finite(v))
          fail("vertex " + std::to_string(i), "coordinate " + std::to_string(k) + " " + why);
        p[k] = v;
      }
      pos.push_back(p);
    }

    TriangleSink sink(report);
    sink.reserve(std::min<std::uint64_t>(nf, left / kMinFaceBytes + 1));
    std::vector<std::uint32_t> corners;
    for (std::uint64_t i = 0; i < nf; ++i) {
      if (!lines.next_content(line))
        fail_at_end("face " + std::to_string(i),
                    "file ends after " + std::to_string(i) + " of " + std::to_string(nf) + " faces");
      Fields f(line);
      std::string_view t = f.next();
      std::int64_t n = 0;
      if (parse_int(t, n) != NumStatus::Ok)
        fail("face " + std::to_string(i), "corner count " + quote(t) + " is not an integer");
      if (n < 0) fail("face " + std::to_string(i), "corner count " + std::to_string(n) + " is negative");
      corners.clear();
      for (std::int64_t k = 0; k < n; ++k) {
        t = f.next();
        if (t.empty())
          fail("face " + std::to_string(i),
               "expected " + std::to_string(n) + " vertex indices, found " + std::to_string(k));
        std::int64_t idx = 0;
        const NumStatus st = parse_int(t, idx);
        if (st != NumStatus::Ok && st != NumStatus::OutOfRange)
          fail("face " + std::to_string(i), "index " + quote(t) + " is not an integer");
        if (st == NumStatus::Ok && idx < 0)
          fail("face " + std::to_string(i), "index " + std::string(t) + " is negative");
        if (st == NumStatus::OutOfRange || static_cast<std::uint64_t>(idx) >= nv)
          fail("face " + std::to_string(i),
               "index " + std::string(t) + " out of range [0, " + std::to_string(nv) + ")");
        corners.push_back(static_cast<std::uint32_t>(idx));
      }
      if (corners.size() < 3) {  // skipped and counted (docs/mesh_policy.md)
        sink.skip_face([&] { return line_loc(lines.line()); });
        continue;
      }
      if (sink.full(corners.size())) fail("face " + std::to_string(i), "more triangles than 32-bit ids can number");
      sink.add_face(corners);
    }
    // Anything after the last face (more faces than claimed, a trailing comment) is ignored.
    return finish(std::move(sink.take()), std::move(pos), std::move(report), name);
  }
};

}  // namespace

LoadedMesh read_off(std::string_view bytes, const std::string& name) { return OffParser{bytes, name}.parse(); }

}  // namespace ptc::io
