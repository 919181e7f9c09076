// PLY reader: ascii 1.0, binary_little_endian 1.0 and binary_big_endian 1.0 with every scalar
// type of the format (char uchar short ushort int uint float double and their int8 ... float64
// aliases). Positions come from the "vertex" element's x, y, z (any scalar type); faces from the
// "face" element's list "vertex_indices" (or "vertex_index") of any integer types. Every other
// property and element (edge, material, ...) is skipped, list properties included.
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstring>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "toolkit/io/readers.h"
#include "toolkit/io/text_scan.h"

namespace ptc::io {
namespace {

enum class Scalar : std::uint8_t { I8, U8, I16, U16, I32, U32, F32, F64 };

std::optional<Scalar> scalar_from_name(std::string_view s) {
  if (s == "char" || s == "int8") return Scalar::I8;
  if (s == "uchar" || s == "uint8") return Scalar::U8;
  if (s == "short" || s == "int16") return Scalar::I16;
  if (s == "ushort" || s == "uint16") return Scalar::U16;
  if (s == "int" || s == "int32") return Scalar::I32;
  if (s == "uint" || s == "uint32") return Scalar::U32;
  if (s == "float" || s == "float32") return Scalar::F32;
  if (s == "double" || s == "float64") return Scalar::F64;
  return std::nullopt;
}
std::size_t size_of(Scalar t) {
  switch (t) {
    case Scalar::I8:
    case Scalar::U8: return 1;
    case Scalar::I16:
    case Scalar::U16: return 2;
    case Scalar::I32:
    case Scalar::U32:
    case Scalar::F32: return 4;
    case Scalar::F64: return 8;
  }
  return 0;
}
bool is_integer(Scalar t) { return t != Scalar::F32 && t != Scalar::F64; }

enum class Role : std::uint8_t { Skip, X, Y, Z, Indices };

struct Property {
  std::string name;
  Scalar type = Scalar::F32;  // the item type of a list
  bool list = false;
  Scalar count_type = Scalar::U8;
  Role role = Role::Skip;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> props;
  std::unordered_set<std::string> prop_names;  // duplicate check in O(1) (headers can be huge)
  std::uint64_t line = 0;                      // header line declaring it
};

enum class Encoding { Ascii, BinaryLittle, BinaryBig };

std::string plural(const Element& e) {
  if (e.name == "vertex") return "vertices";
  if (e.name == "face") return "faces";
  return quote(e.name) + " elements";
}

template <class T>
T byteswap(T v) {
  static_assert(std::is_trivially_copyable_v<T>);
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  std::memcpy(&v, b, sizeof(T));
  return v;
}

// Reads up to n bytes at file offset `at` into dst (fewer only at the end of the file).
std::size_t pread_full(int fd, char* dst, std::size_t n, std::uint64_t at, const std::string& name) {
  std::size_t got = 0;
  while (got < n) {
    const ssize_t r = ::pread(fd, dst + got, n - got, static_cast<off_t>(at + got));
    if (r < 0) {
      if (errno == EINTR) continue;
      throw InputError(name, byte_loc(at + got), "", std::string("cannot read: ") + std::strerror(errno));
    }
    if (r == 0) break;
    got += static_cast<std::size_t>(r);
  }
  return got;
}

class PlyParser {
 public:
  /// The whole file in memory.
  PlyParser(std::string_view bytes, const std::string& name) : bytes_(bytes), size_(bytes.size()), name_(name) {}
  /// A regular file of `size` bytes, read through a window; `first` holds its first bytes, the
  /// whole header among them.
  PlyParser(int fd, std::uint64_t size, std::string first, std::size_t window, const std::string& name)
      : buf_(std::move(first)), bytes_(buf_), fd_(fd), window_(window), size_(size), name_(name) {}

  LoadedMesh parse() {
    parse_header();
    report_.format = MeshFormat::Ply;
    report_.binary = enc_ != Encoding::Ascii;
    if (!report_.binary && bytes_.size() < size_) {  // ascii is parsed from the whole file
      buf_.resize(size_);
      buf_.resize(bytes_.size() + pread_full(fd_, buf_.data() + bytes_.size(), size_ - bytes_.size(), bytes_.size(), name_));
      bytes_ = buf_;
      size_ = buf_.size();
    }
    if (report_.binary) {
      swap_ = (enc_ == Encoding::BinaryBig) != (std::endian::native == std::endian::big);
      read_binary();
    } else {
      read_ascii();
    }
    return finish(std::move(sink_.take()), std::move(pos_), std::move(report_), name_);
  }

 private:
  // ---- header --------------------------------------------------------------------------------
  [[noreturn]] void header_error(std::uint64_t line, const std::string& reason) const {
    throw InputError(name_, line_loc(line == 0 ? 1 : line), "header", reason);
  }

  Scalar scalar_or_fail(std::string_view tok, std::uint64_t line) const {
    if (tok.empty()) header_error(line, "property type missing");
    if (auto t = scalar_from_name(tok)) return *t;
    header_error(line, "unknown property type " + quote(tok));
  }

  void parse_header() {
    LineReader lines(bytes_);
    std::string_view line;
    if (!lines.next(line)) header_error(1, "file is empty");
    if (Fields(line).next() != "ply") header_error(1, "missing 'ply' magic line");
    bool have_format = false, ended = false;
    while (!ended && lines.next(line)) {
      const std::uint64_t ln = lines.line();
      Fields f(line);
      const std::string_view kw = f.next();
      if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
      if (kw == "format") {
        const std::string_view enc = f.next();
        if (enc == "ascii")
          enc_ = Encoding::Ascii;
        else if (enc == "binary_little_endian")
          enc_ = Encoding::BinaryLittle;
        else if (enc == "binary_big_endian")
          enc_ = Encoding::BinaryBig;
        else
          header_error(ln, "unknown format " + quote(enc));
        const std::string_view version = f.next();
        if (version != "1.0" && version != "1") header_error(ln, "unsupported format version " + quote(version));
        have_format = true;
      } else if (kw == "element") {
        Element e;
        e.name = std::string(f.next());
        e.line = ln;
        if (e.name.empty()) header_error(ln, "element name missing");
        const std::string_view c = f.next();
        std::int64_t n = 0;
        if (parse_int(c, n) != NumStatus::Ok || n < 0)
          header_error(ln, "element " + quote(e.name) + " count " + quote(c) + " is not a non-negative integer");
        e.count = static_cast<std::uint64_t>(n);
        if (e.count > kMaxElements)
          header_error(ln, "element " + quote(e.name) + " count " + std::to_string(e.count) +
                               " exceeds the 32-bit limit");
        if (!element_names_.insert(e.name).second) header_error(ln, "element " + quote(e.name) + " declared twice");
        elements_.push_back(std::move(e));
      } else if (kw == "property") {
        if (elements_.empty()) header_error(ln, "property before any element");
        Property p;
        std::string_view t = f.next();
        if (t == "list") {
          p.list = true;
          p.count_type = scalar_or_fail(f.next(), ln);
          if (!is_integer(p.count_type)) header_error(ln, "list count type must be an integer type");
          t = f.next();
        }
        p.type = scalar_or_fail(t, ln);
        p.name = std::string(f.next());
        if (p.name.empty()) header_error(ln, "property name missing");
        Element& e = elements_.back();
        if (!e.prop_names.insert(p.name).second) header_error(ln, "property " + quote(p.name) + " declared twice");
        if (e.name == "vertex" && (p.name == "x" || p.name == "y" || p.name == "z")) {
          if (p.list) header_error(ln, "vertex property " + quote(p.name) + " must not be a list");
          p.role = p.name == "x" ? Role::X : p.name == "y" ? Role::Y : Role::Z;
        }
        if (e.name == "face" && (p.name == "vertex_indices" || p.name == "vertex_index")) {
          for (const Property& o : e.props)
            if (o.role == Role::Indices) header_error(ln, "face has both vertex_indices and vertex_index");
          if (!p.list) header_error(ln, "face property " + quote(p.name) + " must be a list");
          if (!is_integer(p.type)) header_error(ln, "face property " + quote(p.name) + " must have an integer type");
          p.role = Role::Indices;
        }
        e.props.push_back(std::move(p));
      } else if (kw == "end_header") {
        ended = true;
      } else {
        header_error(ln, "unknown header keyword " + quote(kw));
      }
    }
    if (!ended) header_error(lines.line(), "header has no end_header line");
    if (!have_format) header_error(lines.line(), "header has no format line");
    data_offset_ = bytes_.size() - lines.remaining();  // (the window starts at byte 0)
    data_line_ = lines.line() + 1;

    // The vertex and face elements, and whether they have what we need.
    for (std::size_t i = 0; i < elements_.size(); ++i) {
      if (elements_[i].name == "vertex") vertex_el_ = i;
      if (elements_[i].name == "face") face_el_ = i;
    }
    if (vertex_el_ == kNone) header_error(lines.line(), "no vertex element");
    {
      const Element& v = elements_[vertex_el_];
      for (const auto& [role, axis] : {std::pair{Role::X, "x"}, std::pair{Role::Y, "y"}, std::pair{Role::Z, "z"}}) {
        bool found = false;
        for (const Property& p : v.props) found = found || p.role == role;
        if (!found) header_error(v.line, std::string("vertex element has no ") + axis + " property");
      }
      if (v.count > kMaxElements)
        header_error(v.line, "vertex count " + std::to_string(v.count) + " exceeds the 32-bit limit");
    }
    if (face_el_ != kNone) {
      const Element& fe = elements_[face_el_];
      bool found = false;
      for (const Property& p : fe.props) found = found || p.role == Role::Indices;
      if (!found) header_error(fe.line, "face element has no vertex_indices list");
      if (fe.count > kMaxElements)
        header_error(fe.line, "face count " + std::to_string(fe.count) + " exceeds the 32-bit limit");
    }

    // Every claimed element needs some minimum number of bytes; check all claims against the
    // bytes left before anything of their size is allocated. The minimum is that of a malformed
    // item (a list of length 0, a one-character token), so that a short item is reported as what
    // it is; reservations use the minimum of a valid item.
    const bool ascii = enc_ == Encoding::Ascii;
    const std::uint64_t after_header = size_ - data_offset_;
    std::uint64_t left = after_header + (ascii ? 1 : 0);  // ascii: the last token needs no separator
    for (const Element& e : elements_) {
      std::uint64_t min = 0;
      for (const Property& p : e.props) min += ascii ? 2 : p.list ? size_of(p.count_type) : size_of(p.type);
      if (min == 0 || e.count == 0) continue;
      if (e.count > left / min)
        header_error(e.line, "header claims " + std::to_string(e.count) + " " + plural(e) + " (at least " +
                                 std::to_string(min) + " bytes each) but the file has only " +
                                 std::to_string(after_header) + " bytes after the header");
      left -= e.count * min;
    }
    const Element& ve = elements_[vertex_el_];
    pos_.reserve(ve.count);  // bounded above: every vertex has x, y and z
    if (face_el_ != kNone) {
      const Element& fe = elements_[face_el_];
      std::uint64_t min_face = ascii ? 8 : 0;  // "3 0 1 2" and a separator
      for (const Property& p : fe.props)
        if (p.role == Role::Indices && !ascii) min_face = size_of(p.count_type) + 3 * size_of(p.type);
      const std::uint64_t n = std::min<std::uint64_t>(fe.count, after_header / min_face);
      sink_.reserve(n);
    }
  }

  // ---- shared by both encodings ------------------------------------------------------------
  [[noreturn]] void element_error(const std::string& location, const Element& e, std::uint64_t item,
                                  const std::string& reason) const {
    throw InputError(name_, location, e.name + " " + std::to_string(item), reason);
  }
  std::string truncated(const Element& e, std::uint64_t item) const {
    std::string s = "file ends after " + std::to_string(item) + " of " + std::to_string(e.count) + " " + plural(e);
    if (report_.surplus_lines > 0)  // ascii, one element per line: did a writer put several on one?
      s += " (" + std::to_string(report_.surplus_lines) + (report_.surplus_lines == 1 ? " line" : " lines") +
           " carried more values than the header declares, first: " + report_.first_surplus + ")";
    return s;
  }
  // Checks one face index; returns it as a vertex id.
  std::uint32_t checked_index(std::int64_t v, const std::string& loc, const Element& e, std::uint64_t item) const {
    const std::uint64_t nv = elements_[vertex_el_].count;
    if (v < 0) element_error(loc, e, item, "index " + std::to_string(v) + " is negative");
    if (static_cast<std::uint64_t>(v) >= nv)
      element_error(loc, e, item, "index " + std::to_string(v) + " out of range [0, " + std::to_string(nv) + ")");
    return static_cast<std::uint32_t>(v);
  }
  // `loc` makes the element's location; it is called only for an error or a skipped face (the
  // string costs more than the element itself in a binary file).
  template <class Loc>
  void add_face(const Loc& loc, const Element& e, std::uint64_t item) {
    if (corners_.size() < 3) {  // skipped and counted (docs/mesh_policy.md)
      sink_.skip_face(loc);
      return;
    }
    // Counts were checked against the 32-bit limit, but polygons can give more triangles.
    if (sink_.full(corners_.size())) element_error(loc(), e, item, "more triangles than 32-bit ids can number");
    sink_.add_face(corners_);
  }
  template <class Loc>
  void add_vertex(const Vec3& p, const Loc& loc, const Element& e, std::uint64_t item) {
    for (int k = 0; k < 3; ++k)
      if (const char* why = non_finite(p[k])) element_error(loc(), e, item, std::string(1, "xyz"[k]) + " " + why);
    pos_.push_back(p);
  }

  // ---- binary ----------------------------------------------------------------------------------
  // The next n bytes from at_ (n <= size_ - at_) are in the window; false when the file ended
  // before them (it shrank while being read).
  bool ensure(std::uint64_t n) {
    if (at_ >= base_ && at_ + n <= base_ + bytes_.size()) return true;
    return slide(n);
  }
  bool slide(std::uint64_t n) {
    const std::uint64_t end = base_ + bytes_.size();
    const std::size_t kept = at_ < end ? static_cast<std::size_t>(end - at_) : 0;  // read, not yet used
    const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(std::max<std::uint64_t>(window_, n), size_ - at_));
    if (kept > 0) std::memmove(buf_.data(), buf_.data() + (at_ - base_), kept);
    if (buf_.size() < want) buf_.resize(want);
    const std::size_t got = kept + pread_full(fd_, buf_.data() + kept, want - kept, at_ + kept, name_);
    base_ = at_;
    bytes_ = std::string_view(buf_.data(), got);
    return got >= n;
  }

  template <class T>
  T raw() {
    T v;
    std::memcpy(&v, bytes_.data() + (at_ - base_), sizeof(T));
    at_ += sizeof(T);
    return swap_ ? byteswap(v) : v;
  }
  double read_double(Scalar t) {
    switch (t) {
      case Scalar::I8: return raw<std::int8_t>();
      case Scalar::U8: return raw<std::uint8_t>();
      case Scalar::I16: return raw<std::int16_t>();
      case Scalar::U16: return raw<std::uint16_t>();
      case Scalar::I32: return raw<std::int32_t>();
      case Scalar::U32: return raw<std::uint32_t>();
      case Scalar::F32: return raw<float>();
      case Scalar::F64: return raw<double>();
    }
    return 0;
  }
  std::int64_t read_int(Scalar t) {  // t is an integer type
    switch (t) {
      case Scalar::I8: return raw<std::int8_t>();
      case Scalar::U8: return raw<std::uint8_t>();
      case Scalar::I16: return raw<std::int16_t>();
      case Scalar::U16: return raw<std::uint16_t>();
      case Scalar::I32: return raw<std::int32_t>();
      case Scalar::U32: return raw<std::uint32_t>();
      default: return 0;
    }
  }

  void read_binary() {
    at_ = data_offset_;
    const std::uint64_t size = size_;
    for (const Element& e : elements_) {
      const bool is_vertex = &e == &elements_[vertex_el_];
      const bool is_face = face_el_ != kNone && &e == &elements_[face_el_];
      bool fixed = true;
      std::size_t item_size = 0;
      for (const Property& p : e.props) {
        fixed = fixed && !p.list;
        item_size += size_of(p.type);
      }
      if (!is_vertex && !is_face && fixed) {  // skip the whole element at once
        if (item_size == 0) continue;
        if (e.count > (size - at_) / item_size)
          element_error(byte_loc(at_), e, (size - at_) / item_size, truncated(e, (size - at_) / item_size));
        at_ += e.count * item_size;
        continue;
      }
      for (std::uint64_t i = 0; i < e.count; ++i) {
        const std::size_t item_at = at_;
        const auto need = [&](std::uint64_t n) {
          if (n > size - at_ || !ensure(n)) element_error(byte_loc(at_), e, i, truncated(e, i));
        };
        Vec3 p(0, 0, 0);
        corners_.clear();
        for (const Property& prop : e.props) {
          if (!prop.list) {
            need(size_of(prop.type));
            switch (prop.role) {
              case Role::X: p.x() = read_double(prop.type); break;
              case Role::Y: p.y() = read_double(prop.type); break;
              case Role::Z: p.z() = read_double(prop.type); break;
              default: at_ += size_of(prop.type);
            }
            continue;
          }
          need(size_of(prop.count_type));
          const std::size_t count_at = at_;
          const std::int64_t n = read_int(prop.count_type);
          if (n < 0) element_error(byte_loc(count_at), e, i, "list length " + std::to_string(n) + " is negative");
          const std::size_t unit = size_of(prop.type);
          if (static_cast<std::uint64_t>(n) > (size - at_) / unit) element_error(byte_loc(at_), e, i, truncated(e, i));
          if (prop.role != Role::Indices) {
            at_ += static_cast<std::size_t>(n) * unit;
            continue;
          }
          need(static_cast<std::uint64_t>(n) * unit);
          const std::uint64_t nv = elements_[vertex_el_].count;
          for (std::int64_t k = 0; k < n; ++k) {
            const std::size_t idx_at = at_;
            const std::int64_t v = read_int(prop.type);
            if (v < 0 || static_cast<std::uint64_t>(v) >= nv) (void)checked_index(v, byte_loc(idx_at), e, i);
            corners_.push_back(static_cast<std::uint32_t>(v));
          }
        }
        const auto loc = [&] { return byte_loc(item_at); };
        if (is_vertex) add_vertex(p, loc, e, i);
        if (is_face) add_face(loc, e, i);
      }
    }
    // Bytes after the last element are ignored.
  }

  // ---- ascii -----------------------------------------------------------------------------------
  // One element per line (as the format has it); an element whose values run past its line goes
  // on on the next one, and values left on a line after its element are surplus: counted and
  // ignored (MeshLab/VCG write face lines with more values than their header declares).
  class ElementLines {
   public:
    ElementLines(std::string_view data, std::uint64_t first_line) : lines_(data), first_line_(first_line) {}
    /// The next value of the current element, or an empty view at the end of the data.
    std::string_view next() {
      for (;;) {
        if (const std::string_view t = fields_.next(); !t.empty()) return t;
        std::string_view l;
        if (!lines_.next(l)) return {};
        fields_ = Fields(l);
      }
    }
    /// The element is complete: how many values its line has left (then the next element starts
    /// on a new line).
    std::size_t end_element() {
      std::size_t extra = 0;
      while (!fields_.next().empty()) ++extra;
      fields_ = Fields({});
      return extra;
    }
    /// The file's line of the value last returned.
    [[nodiscard]] std::uint64_t line() const { return first_line_ + (lines_.line() == 0 ? 0 : lines_.line() - 1); }

   private:
    LineReader lines_;
    Fields fields_{std::string_view{}};
    std::uint64_t first_line_;
  };

  void read_ascii() {
    ElementLines tr(bytes_.substr(data_offset_), data_line_);
    for (const Element& e : elements_) {
      if (e.props.empty()) continue;  // an element without properties has no data, whatever its count
      const bool is_vertex = &e == &elements_[vertex_el_];
      const bool is_face = face_el_ != kNone && &e == &elements_[face_el_];
      for (std::uint64_t i = 0; i < e.count; ++i) {
        const auto token = [&] {
          const std::string_view t = tr.next();
          if (t.empty()) element_error(line_loc(tr.line()), e, i, truncated(e, i));
          return t;
        };
        const auto integer = [&](const Property& prop, const char* what) {
          const std::string_view t = token();
          std::int64_t v = 0;
          const NumStatus st = parse_int(t, v);
          if (st == NumStatus::Garbled)
            element_error(line_loc(tr.line()), e, i,
                          std::string(what) + " of " + quote(prop.name) + " " + quote(t) + " is not an integer");
          if (st == NumStatus::OutOfRange)
            element_error(line_loc(tr.line()), e, i,
                          std::string(what) + " of " + quote(prop.name) + " " + quote(t) + " is out of range");
          return v;
        };
        const auto number = [&](const Property& prop) {
          const std::string_view t = token();
          double v = 0;
          const NumStatus st = parse_double(t, v);
          if (st != NumStatus::Ok)
            element_error(line_loc(tr.line()), e, i,
                          "value of " + quote(prop.name) + " " + quote(t) +
                              (st == NumStatus::Garbled ? " is not a number" : " is out of range"));
          return v;
        };
        Vec3 p(0, 0, 0);
        std::uint64_t first_line = 0;
        corners_.clear();
        for (const Property& prop : e.props) {
          if (!prop.list) {
            const double v = is_integer(prop.type) && prop.role != Role::Skip
                                 ? static_cast<double>(integer(prop, "value"))
                                 : number(prop);
            if (first_line == 0) first_line = tr.line();
            if (prop.role == Role::X) p.x() = v;
            if (prop.role == Role::Y) p.y() = v;
            if (prop.role == Role::Z) p.z() = v;
            continue;
          }
          const std::int64_t n = integer(prop, "list length");
          if (first_line == 0) first_line = tr.line();
          if (n < 0) element_error(line_loc(tr.line()), e, i, "list length " + std::to_string(n) + " is negative");
          if (prop.role != Role::Indices) {
            for (std::int64_t k = 0; k < n; ++k) (void)number(prop);
            continue;
          }
          for (std::int64_t k = 0; k < n; ++k) {
            const std::int64_t v = integer(prop, "index");
            corners_.push_back(checked_index(v, line_loc(tr.line()), e, i));
          }
        }
        if (const std::size_t extra = tr.end_element(); extra > 0 && report_.surplus_lines++ == 0)
          report_.first_surplus = e.name + " " + std::to_string(i) + " (" + line_loc(tr.line()) + "): " +
                                  std::to_string(extra) + (extra == 1 ? " extra value" : " extra values");
        const auto loc = [&] { return line_loc(first_line); };
        if (is_vertex) add_vertex(p, loc, e, i);
        if (is_face) add_face(loc, e, i);
      }
    }
  }

  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);

  std::string buf_;       // file mode: the window's bytes
  std::string_view bytes_;  // the window: the file's bytes from base_ on (memory mode: all of them)
  int fd_ = -1;             // file mode: the file
  std::size_t window_ = 0;  // file mode: the bytes read at a time
  std::uint64_t base_ = 0;  // file offset of bytes_[0]
  std::uint64_t size_;      // the file's size
  const std::string& name_;
  Encoding enc_ = Encoding::Ascii;
  std::vector<Element> elements_;
  std::size_t vertex_el_ = kNone, face_el_ = kNone;
  std::size_t data_offset_ = 0;
  std::uint64_t data_line_ = 0;
  bool swap_ = false;
  std::uint64_t at_ = 0;  // binary read position (from the start of the file)

  ReadReport report_;
  std::vector<Vec3> pos_;
  TriangleSink sink_{report_};
  std::vector<std::uint32_t> corners_;
  std::unordered_set<std::string> element_names_;
};

}  // namespace

LoadedMesh read_ply(std::string_view bytes, const std::string& name) { return PlyParser(bytes, name).parse(); }

LoadedMesh read_ply_file(int fd, std::uint64_t size, const std::string& name, std::size_t window) {
  window = std::max<std::size_t>(window, 1);
  // The first window holds the whole header (a line "end_header" ended within it) or the whole
  // file: it doubles until it does.
  std::string first;
  for (std::size_t want = window;; want *= 2) {
    first.resize(static_cast<std::size_t>(std::min<std::uint64_t>(size, want)));
    first.resize(pread_full(fd, first.data(), first.size(), 0, name));
    check_not_utf16(first, name);
    if (first.size() < std::min<std::uint64_t>(size, want)) break;  // the file ended early (it shrank)
    if (first.size() == size) break;
    LineReader lines(first);
    std::string_view line;
    bool whole_header = false;
    while (!whole_header && lines.next(line))
      whole_header = Fields(line).next() == "end_header" && line.data() + line.size() < first.data() + first.size();
    if (whole_header) break;
  }
  return PlyParser(fd, size, std::move(first), window, name).parse();
}

}  // namespace ptc::io
