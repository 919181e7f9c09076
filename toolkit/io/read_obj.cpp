// Wavefront OBJ reader: "v x y z [w]" and "f" with i, i/t, i/t/n or i//n corners. Negative
// indices are relative (-1 = the last vertex defined so far, as the OBJ spec says). Positive
// indices may refer to vertices defined further down (common in the wild); they are range-checked
// once the whole file has been read, and the error names the line of the largest one.
// vt, vn, vp, g, o, s, usemtl, mtllib, l, p and unknown keywords are ignored.
#include <algorithm>
#include <string>
#include <vector>

#include "toolkit/io/readers.h"
#include "toolkit/io/text_scan.h"

namespace ptc::io {
namespace {

struct ObjParser {
  std::string_view bytes;
  const std::string& name;
  LineReader lines{bytes};

  // Elements are named only when an error is thrown (no string work per line).
  [[noreturn]] void fail(const char* kind, std::uint64_t index, const std::string& reason) const {
    throw InputError(name, line_loc(lines.line()), kind + std::to_string(index), reason);
  }

  // `line` without its trailing blanks ends in '\\': the statement goes on on the next line
  // (as the OBJ specification allows; "f 1 2 \\" then "3"). The lines are joined with a space in
  // `buf`, comments cut from each; errors then name the statement's last line.
  std::string_view continued(std::string_view line, std::string& buf) {
    auto ends_continued = [](std::string_view l) {
      while (!l.empty() && is_blank(l.back())) l.remove_suffix(1);
      return !l.empty() && l.back() == '\\' ? l.size() : std::string_view::npos;
    };
    std::size_t cut = ends_continued(line);
    if (cut == std::string_view::npos) return line;
    buf.assign(line.substr(0, cut - 1));
    std::string_view next;
    while (cut != std::string_view::npos && lines.next(next)) {
      if (const std::size_t hash = next.find('#'); hash != std::string_view::npos) next = next.substr(0, hash);
      cut = ends_continued(next);
      buf += ' ';
      buf.append(cut == std::string_view::npos ? next : next.substr(0, cut - 1));
    }
    return buf;
  }

  LoadedMesh parse() {
    ReadReport report;
    report.format = MeshFormat::Obj;
    std::vector<Vec3> pos;
    TriangleSink sink(report);
    std::vector<std::uint32_t> corners;
    // The largest positive (forward-allowed) index, for the check at the end.
    std::uint64_t max_index = 0, max_index_line = 0, max_index_face = 0;

    std::string_view line;
    std::string joined;  // a statement continued over lines with a trailing '\\'
    while (lines.next_content(line)) {
      line = continued(line, joined);
      Fields f(line);
      const std::string_view kw = f.next();
      if (kw == "v") {
        const auto fail_here = [&](const std::string& reason) { fail("vertex ", pos.size(), reason); };
        if (pos.size() >= kMaxElements) fail_here("more vertices than 32-bit indices can number");
        Vec3 p;
        for (int k = 0; k < 3; ++k) {
          const std::string_view t = f.next();
          if (t.empty()) fail_here("expected 3 coordinates, found " + std::to_string(k));
          double v = 0;
          const NumStatus st = parse_double(t, v);
          if (st != NumStatus::Ok)
            fail_here("coordinate " + std::to_string(k) + " " + quote(t) +
                      (st == NumStatus::Garbled ? " is not a number" : " is out of range"));
          if (const char* why = non_finite(v)) fail_here("coordinate " + std::to_string(k) + " " + why);
          p[k] = v;
        }
        pos.push_back(p);  // w, or the r g b some writers append, is ignored
      } else if (kw == "f") {
        const auto fail_here = [&](const std::string& reason) { fail("face ", sink.faces(), reason); };
        const auto beyond_numbering = [](std::string_view index) {
          return "index " + std::string(index) + " out of range (ptc numbers at most " + std::to_string(kMaxElements) +
                 " vertices)";
        };
        corners.clear();
        for (std::string_view t = f.next(); !t.empty(); t = f.next()) {
          // The vertex index ends at the first '/'; texture and normal indices are only checked
          // to be made of digits, signs and slashes.
          const std::size_t slash = t.find('/');
          const std::string_view vi = t.substr(0, slash);
          // (and at most two slashes: "3/4/5/6" is no corner either)
          if (slash != std::string_view::npos && (t.find_first_not_of("0123456789-+/", slash) != std::string_view::npos ||
                                                  std::count(t.begin(), t.end(), '/') > 2))
            fail_here("corner " + quote(t) + " is not of the form i, i/t, i/t/n or i//n");
          std::int64_t idx = 0;
          const NumStatus st = parse_int(vi, idx);
          if (st == NumStatus::Garbled) fail_here("corner " + quote(t) + " is not an integer index");
          // (beyond 64 bits: a positive index is out of any file's range, a negative one refers
          // before the first vertex; both as the checks below say them)
          if (st == NumStatus::OutOfRange)
            fail_here(vi.starts_with('-') ? "relative index " + std::string(vi) + " refers before the first vertex (" +
                                                std::to_string(pos.size()) + " vertices defined so far)"
                                          : beyond_numbering(vi));
          if (idx == 0) fail_here("index 0 is invalid (OBJ indices start at 1)");
          std::uint64_t v = 0;
          if (idx < 0) {
            const std::uint64_t back = 0 - static_cast<std::uint64_t>(idx);  // |idx|, also for INT64_MIN
            if (back > pos.size())
              fail_here("relative index " + std::to_string(idx) + " refers before the first vertex (" +
                        std::to_string(pos.size()) + " vertices defined so far)");
            v = pos.size() - back;
          } else {
            v = static_cast<std::uint64_t>(idx) - 1;
            if (v >= kMaxElements) fail_here(beyond_numbering(std::to_string(idx)));
            if (static_cast<std::uint64_t>(idx) > max_index) {
              max_index = static_cast<std::uint64_t>(idx);
              max_index_line = lines.line();
              max_index_face = sink.faces();
            }
          }
          corners.push_back(static_cast<std::uint32_t>(v));
        }
        if (corners.size() < 3) {  // skipped and counted (docs/mesh_policy.md)
          sink.skip_face([&] { return line_loc(lines.line()); });
          continue;
        }
        if (sink.full(corners.size())) fail_here("more triangles than 32-bit ids can number");
        sink.add_face(corners);
      }
    }
    if (max_index > pos.size())
      throw InputError(name, line_loc(max_index_line), "face " + std::to_string(max_index_face),
                       "index " + std::to_string(max_index) + " out of range [1, " + std::to_string(pos.size()) +
                           "] (the file defines " + std::to_string(pos.size()) + " vertices)");
    return finish(std::move(sink.take()), std::move(pos), std::move(report), name);
  }
};

}  // namespace

LoadedMesh read_obj(std::string_view bytes, const std::string& name) { return ObjParser{bytes, name}.parse(); }

}  // namespace ptc::io
