#include "sim/mesh/mesh_io.h"

#include <algorithm>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <string_view>

#include "sim/base/file_io.h"

namespace sb::mesh {

namespace {

using std::string_view;

// Thrown inside the parsers; readMesh/parseMesh prefix the name.
struct ParseFail {
  std::string reason;
};
[[noreturn]] void fail(const std::string& reason) { throw ParseFail{reason}; }
std::string lineText(int line) { return "line " + std::to_string(line) + ": "; }

std::string numberText(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// A coordinate every part of the program can hold: finite and within float range.
void checkCoordinate(double c, const std::string& where) {
  if (!std::isfinite(c)) fail(where + "coordinate " + numberText(c) + " is not finite");
  if (std::abs(c) > double(FLT_MAX))
    fail(where + "coordinate " + numberText(c) + " is beyond float range (|c| ≤ 3.4e38)");
}

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// Splits text into lines ('\n'; a trailing '\r' is dropped with the other blanks).
class Lines {
 public:
  explicit Lines(string_view text, size_t start = 0) : text_(text), pos_(start) {}
  bool next(string_view& line) {
    if (pos_ >= text_.size()) return false;
    const size_t end = text_.find('\n', pos_);
    const size_t stop = end == string_view::npos ? text_.size() : end;
    line = text_.substr(pos_, stop - pos_);
    pos_ = end == string_view::npos ? text_.size() : end + 1;
    ++number_;
    return true;
  }
  int number() const { return number_; }
  size_t position() const { return pos_; }

 private:
  string_view text_;
  size_t pos_;
  int number_ = 0;
};

// Whitespace-separated tokens of one line (or of a whole text).
class Tokens {
 public:
  explicit Tokens(string_view text) : text_(text) {}
  bool next(string_view& token) {
    while (pos_ < text_.size() && (isSpace(text_[pos_]) || text_[pos_] == '\n')) ++pos_;
    if (pos_ >= text_.size()) return false;
    const size_t start = pos_;
    while (pos_ < text_.size() && !isSpace(text_[pos_]) && text_[pos_] != '\n') ++pos_;
    token = text_.substr(start, pos_ - start);
    return true;
  }
  bool empty() {
    size_t p = pos_;
    while (p < text_.size() && (isSpace(text_[p]) || text_[p] == '\n')) ++p;
    return p >= text_.size();
  }

 private:
  string_view text_;
  size_t pos_ = 0;
};

std::string quoted(string_view token) {
  std::string t(token.substr(0, 40));
  for (char& c : t)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  return "'" + t + (token.size() > 40 ? "...'" : "'");
}

bool parseDouble(string_view token, double& out) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto r = std::from_chars(token.data(), token.data() + token.size(), out);
  if (r.ec == std::errc::result_out_of_range) {
    out = token[0] == '-' ? -std::numeric_limits<double>::infinity()
                          : std::numeric_limits<double>::infinity();
    return r.ptr == token.data() + token.size();
  }
  return r.ec == std::errc() && r.ptr == token.data() + token.size();
}

bool parseInteger(string_view token, long long& out) {
  if (!token.empty() && token[0] == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto r = std::from_chars(token.data(), token.data() + token.size(), out);
  return r.ec == std::errc() && r.ptr == token.data() + token.size();
}

// A count from a header: 0 ≤ n ≤ INT32_MAX.
int parseCount(string_view token, const std::string& what) {
  long long n = 0;
  if (!parseInteger(token, n)) fail(what + " must be a whole number, got " + quoted(token));
  if (n < 0 || n > std::numeric_limits<int>::max())
    fail(what + " " + std::string(token) + " is out of range");
  return int(n);
}

void addFace(TriangleMesh& mesh, const std::vector<int>& face) {
  for (size_t k = 1; k + 1 < face.size(); ++k) mesh.triangles.push_back({face[0], face[k], face[k + 1]});
}

// ---------------------------------------------------------------------------------------------
// OBJ: "v x y z [w | r g b]" and "f i[/t[/n]] ..." (1-based, negative = relative); other
// statements (vt, vn, o, g, s, usemtl, ...) are ignored.

TriangleMesh parseObj(string_view text) {
  TriangleMesh mesh;
  Lines lines(text);
  string_view line, tok;
  std::vector<int> face;
  while (lines.next(line)) {
    const size_t hash = line.find('#');
    if (hash != string_view::npos) line = line.substr(0, hash);
    Tokens t(line);
    if (!t.next(tok)) continue;
    const std::string where = lineText(lines.number());
    if (tok == "v") {
      double c[3];
      for (double& v : c) {
        if (!t.next(tok)) fail(where + "a vertex needs three numbers");
        if (!parseDouble(tok, v)) fail(where + "not a number: " + quoted(tok));
        checkCoordinate(v, where);
      }
      while (t.next(tok)) {  // w or a colour
        double extra;
        if (!parseDouble(tok, extra)) fail(where + "not a number: " + quoted(tok));
      }
      mesh.vertices.emplace_back(c[0], c[1], c[2]);
    } else if (tok == "f") {
      face.clear();
      const long long count = static_cast<long long>(mesh.vertices.size());
      while (t.next(tok)) {
        const string_view index = tok.substr(0, tok.find('/'));
        long long i = 0;
        if (!parseInteger(index, i) || i == 0) fail(where + "bad face index " + quoted(tok));
        const long long resolved = i > 0 ? i : count + i + 1;
        if (resolved < 1 || resolved > count)
          fail(where + "face index " + std::string(index) + " out of range (" +
               std::to_string(count) + " vertices so far)");
        face.push_back(int(resolved - 1));
      }
      if (face.size() < 3) fail(where + "a face needs at least 3 vertices, got " + std::to_string(face.size()));
      addFace(mesh, face);
    }
  }
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// OFF, ASCII: "[ST][C][N]OFF", then "nv nf [ne]", nv vertex lines (x y z, extra numbers such as
// colours allowed), nf face lines "k i1 .. ik [colour]"; '#' starts a comment. Binary ("OFF
// BINARY"): big-endian int32 nv nf ne, nv × 3 float32, per face int32 k, k int32 indices,
// int32 colour count and that many float32.

// Big-endian / little-endian readers over the remaining bytes.
class Bytes {
 public:
  Bytes(string_view data, size_t pos, bool bigEndian) : d_(data), pos_(pos), big_(bigEndian) {}
  size_t left() const { return d_.size() - pos_; }
  size_t position() const { return pos_; }
  template <typename T>
  T get(const char* what) {
    if (left() < sizeof(T)) fail(std::string("the file ends inside ") + what);
    unsigned char b[sizeof(T)];
    std::memcpy(b, d_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    const bool hostLittle = true;  // x86-64 and every target the project builds for
    if (big_ == hostLittle) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }

 private:
  string_view d_;
  size_t pos_;
  bool big_;
};

bool offKeyword(string_view tok, bool& binaryCapable) {
  if (tok.size() < 3 || tok.substr(tok.size() - 3) != "OFF") return false;
  for (char c : tok.substr(0, tok.size() - 3))
    if (c != 'S' && c != 'T' && c != 'C' && c != 'N') return false;
  binaryCapable = tok == "OFF";
  return true;
}

TriangleMesh parseOffBinary(string_view text, size_t start) {
  Bytes in(text, start, /*bigEndian=*/true);
  const int nv = in.get<std::int32_t>("the counts"), nf = in.get<std::int32_t>("the counts");
  (void)in.get<std::int32_t>("the counts");
  if (nv < 0 || nf < 0) fail("binary OFF: negative vertex or face count");
  if (std::uint64_t(nv) * 12 > in.left())
    fail("binary OFF: the header declares " + std::to_string(nv) + " vertices but only " +
         std::to_string(in.left()) + " bytes follow");
  TriangleMesh mesh;
  mesh.vertices.reserve(size_t(nv));
  for (int i = 0; i < nv; ++i) {
    double c[3];
    for (double& v : c) {
      v = in.get<float>("the vertices");
      checkCoordinate(v, "vertex " + std::to_string(i) + ": ");
    }
    mesh.vertices.emplace_back(c[0], c[1], c[2]);
  }
  std::vector<int> face;
  for (int f = 0; f < nf; ++f) {
    const std::string where = "face " + std::to_string(f) + ": ";
    const std::int32_t k = in.get<std::int32_t>("the faces");
    if (k < 3) fail(where + "a face needs at least 3 vertices, got " + std::to_string(k));
    if (std::uint64_t(k) * 4 > in.left()) fail(where + "the file ends inside the face");
    face.clear();
    for (int c = 0; c < k; ++c) {
      const std::int32_t i = in.get<std::int32_t>("the faces");
      if (i < 0 || i >= nv)
        fail(where + "vertex index " + std::to_string(i) + " out of range (" + std::to_string(nv) + " vertices)");
      face.push_back(i);
    }
    const std::int32_t colours = in.get<std::int32_t>("the faces");
    if (colours < 0 || colours > 4) fail(where + "bad colour count " + std::to_string(colours));
    for (int c = 0; c < colours; ++c) (void)in.get<float>("the faces");
    addFace(mesh, face);
  }
  if (in.left() != 0)
    fail("binary OFF: " + std::to_string(in.left()) + " bytes after the " + std::to_string(nf) +
         " faces the header declares");
  return mesh;
}

TriangleMesh parseOff(string_view text) {
  Lines lines(text);
  string_view line, tok;
  // Non-empty lines with comments removed.
  auto nextLine = [&](Tokens& t) {
    while (lines.next(line)) {
      const size_t hash = line.find('#');
      if (hash != string_view::npos) line = line.substr(0, hash);
      t = Tokens(line);
      if (!t.empty()) return true;
    }
    return false;
  };
  Tokens t{string_view()};
  if (!nextLine(t) || !t.next(tok)) fail("empty OFF file");
  bool binaryCapable = false;
  if (!offKeyword(tok, binaryCapable)) fail("not an OFF file (first word " + quoted(tok) + ", expected OFF)");
  if (t.next(tok)) {
    if (tok == "BINARY" && binaryCapable && t.empty()) return parseOffBinary(text, lines.position());
    if (tok == "BINARY") fail("only plain binary OFF ('OFF BINARY') is supported");
  } else if (!nextLine(t) || !t.next(tok)) {
    fail("the file ends before the vertex and face counts");
  }
  const std::string countLine = lineText(lines.number());
  const int nv = parseCount(tok, countLine + "the vertex count");
  if (!t.next(tok)) fail(countLine + "the face count is missing");
  const int nf = parseCount(tok, countLine + "the face count");
  if (t.next(tok)) (void)parseCount(tok, countLine + "the edge count");
  if (t.next(tok)) fail(countLine + "unexpected " + quoted(tok) + " after the counts");
  TriangleMesh mesh;
  for (int i = 0; i < nv; ++i) {
    if (!nextLine(t))
      fail("the header declares " + std::to_string(nv) + " vertices, the file ends after " + std::to_string(i));
    const std::string where = lineText(lines.number());
    double c[3];
    for (double& v : c) {
      if (!t.next(tok)) fail(where + "a vertex needs three numbers");
      if (!parseDouble(tok, v)) fail(where + "not a number: " + quoted(tok));
      checkCoordinate(v, where);
    }
    while (t.next(tok)) {
      double extra;
      if (!parseDouble(tok, extra)) fail(where + "not a number: " + quoted(tok));
    }
    mesh.vertices.emplace_back(c[0], c[1], c[2]);
  }
  std::vector<int> face;
  for (int f = 0; f < nf; ++f) {
    if (!nextLine(t))
      fail("the header declares " + std::to_string(nf) + " faces, the file ends after " + std::to_string(f));
    const std::string where = lineText(lines.number());
    t.next(tok);
    long long k = 0;
    if (!parseInteger(tok, k)) fail(where + "a face starts with its corner count, got " + quoted(tok));
    if (k < 3) fail(where + "a face needs at least 3 vertices, got " + std::to_string(k));
    face.clear();
    for (long long c = 0; c < k; ++c) {
      long long i = 0;
      if (!t.next(tok)) fail(where + "the face declares " + std::to_string(k) + " corners but lists " + std::to_string(c));
      if (!parseInteger(tok, i)) fail(where + "bad vertex index " + quoted(tok));
      if (i < 0 || i >= nv)
        fail(where + "vertex index " + std::to_string(i) + " out of range (" + std::to_string(nv) + " vertices)");
      face.push_back(int(i));
    }
    while (t.next(tok)) {  // a colour
      double extra;
      if (!parseDouble(tok, extra)) fail(where + "not a number: " + quoted(tok));
    }
    addFace(mesh, face);
  }
  if (nextLine(t))
    fail(lineText(lines.number()) + "data after the " + std::to_string(nv) + " vertices and " +
         std::to_string(nf) + " faces the header declares");
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// PLY: "ply", "format ascii|binary_little_endian|binary_big_endian 1.0", "comment"/"obj_info"
// lines, "element NAME COUNT", "property TYPE NAME", "property list COUNTTYPE TYPE NAME",
// "end_header". Vertices need x, y, z; faces a list vertex_indices (or vertex_index); other
// elements and properties are read and skipped.

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool plyType(string_view name, PlyType& type) {
  static const std::pair<const char*, PlyType> names[] = {
      {"char", PlyType::Int8},     {"int8", PlyType::Int8},      {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},   {"short", PlyType::Int16},    {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16}, {"uint16", PlyType::UInt16},  {"int", PlyType::Int32},
      {"int32", PlyType::Int32},   {"uint", PlyType::UInt32},    {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32}, {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const auto& [n, t] : names)
    if (name == n) {
      type = t;
      return true;
    }
  return false;
}

size_t plySize(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
      return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
      return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
      return 4;
    case PlyType::Float64:
      return 8;
  }
  return 8;
}

bool plyInteger(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct PlyProperty {
  std::string name;
  bool list = false;
  PlyType countType = PlyType::UInt8, type = PlyType::Float32;
};
struct PlyElement {
  std::string name;
  int count = 0;
  std::vector<PlyProperty> properties;
};

// Reads one value of a property, ASCII or binary.
class PlyValues {
 public:
  PlyValues(string_view text, size_t start, int format)  // 0 ascii, 1 little, 2 big
      : tokens_(text.substr(start)), bytes_(text, start, format == 2), ascii_(format == 0) {}
  double get(PlyType t, const std::string& where) {
    if (ascii_) {
      string_view tok;
      if (!tokens_.next(tok)) fail(where + "the file ends early");
      double v = 0;
      if (plyInteger(t)) {
        long long i = 0;
        if (!parseInteger(tok, i)) fail(where + "not an integer: " + quoted(tok));
        v = double(i);
      } else if (!parseDouble(tok, v)) {
        fail(where + "not a number: " + quoted(tok));
      }
      return t == PlyType::Float32 && std::isfinite(v) && std::abs(v) <= double(FLT_MAX) ? double(float(v)) : v;
    }
    const char* what = "the element data";
    switch (t) {
      case PlyType::Int8: return bytes_.get<std::int8_t>(what);
      case PlyType::UInt8: return bytes_.get<std::uint8_t>(what);
      case PlyType::Int16: return bytes_.get<std::int16_t>(what);
      case PlyType::UInt16: return bytes_.get<std::uint16_t>(what);
      case PlyType::Int32: return bytes_.get<std::int32_t>(what);
      case PlyType::UInt32: return bytes_.get<std::uint32_t>(what);
      case PlyType::Float32: return bytes_.get<float>(what);
      case PlyType::Float64: return bytes_.get<double>(what);
    }
    return 0;
  }
  size_t bytesLeft() const { return bytes_.left(); }
  bool atEnd() { return ascii_ ? tokens_.empty() : bytes_.left() == 0; }
  bool ascii() const { return ascii_; }

 private:
  Tokens tokens_;
  Bytes bytes_;
  bool ascii_;
};

TriangleMesh parsePly(string_view text) {
  Lines lines(text);
  string_view line, tok;
  {
    Tokens first(string_view{});
    if (lines.next(line)) first = Tokens(line);
    if (!first.next(tok) || tok != "ply" || first.next(tok)) fail("not a PLY file (no 'ply' line)");
  }
  int format = -1;
  std::vector<PlyElement> elements;
  bool ended = false;
  while (lines.next(line)) {
    const std::string where = lineText(lines.number());
    Tokens t(line);
    if (!t.next(tok)) continue;
    if (tok == "comment" || tok == "obj_info") continue;
    if (tok == "end_header") {
      ended = true;
      break;
    }
    if (tok == "format") {
      if (format >= 0) fail(where + "a second format line");
      if (!t.next(tok)) fail(where + "format needs a type");
      if (tok == "ascii") format = 0;
      else if (tok == "binary_little_endian") format = 1;
      else if (tok == "binary_big_endian") format = 2;
      else fail(where + "unknown format " + quoted(tok));
      if (!t.next(tok) || tok != "1.0") fail(where + "only PLY version 1.0 is supported");
    } else if (tok == "element") {
      PlyElement e;
      if (!t.next(tok)) fail(where + "element needs a name");
      e.name = std::string(tok);
      if (!t.next(tok)) fail(where + "element needs a count");
      e.count = parseCount(tok, where + "the " + e.name + " count");
      elements.push_back(std::move(e));
    } else if (tok == "property") {
      if (elements.empty()) fail(where + "a property before any element");
      PlyProperty p;
      if (!t.next(tok)) fail(where + "property needs a type");
      if (tok == "list") {
        p.list = true;
        if (!t.next(tok) || !plyType(tok, p.countType) || !plyInteger(p.countType))
          fail(where + "bad list count type");
        if (!t.next(tok) || !plyType(tok, p.type)) fail(where + "bad list item type");
      } else if (!plyType(tok, p.type)) {
        fail(where + "unknown property type " + quoted(tok));
      }
      if (!t.next(tok)) fail(where + "property needs a name");
      p.name = std::string(tok);
      elements.back().properties.push_back(std::move(p));
    } else {
      fail(where + "unknown header line " + quoted(tok));
    }
    if (t.next(tok)) fail(where + "unexpected " + quoted(tok));
  }
  if (!ended) fail("the header has no end_header line");
  if (format < 0) fail("the header has no format line");

  TriangleMesh mesh;
  int vertexCount = -1;
  PlyValues in(text, lines.position(), format);
  std::vector<int> face;
  for (const PlyElement& e : elements) {
    if (e.count > 0 && e.properties.empty()) fail("element " + e.name + " has no properties");
    // Every element takes at least one byte (binary) or two (ASCII: a digit and a blank), so
    // a count the remaining bytes cannot hold fails here, before any work.
    size_t minBytes = 0;
    for (const PlyProperty& p : e.properties) minBytes += in.ascii() ? 2 : plySize(p.list ? p.countType : p.type);
    if (in.ascii()) minBytes -= 1;  // the last value's blank may be the end of the file
    const size_t available = in.ascii() ? text.size() - lines.position() : in.bytesLeft();
    if (std::uint64_t(e.count) * minBytes > available)
      fail("the header declares " + std::to_string(e.count) + " " + e.name + " elements, more than the " +
           std::to_string(available) + " bytes after it can hold");
    const bool isVertex = e.name == "vertex", isFace = e.name == "face";
    int axis[3] = {-1, -1, -1}, indices = -1;
    for (size_t k = 0; k < e.properties.size(); ++k) {
      const PlyProperty& p = e.properties[k];
      for (int a = 0; a < 3; ++a)
        if (isVertex && !p.list && p.name == std::string(1, char('x' + a))) axis[a] = int(k);
      if (isFace && p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) indices = int(k);
    }
    if (isVertex) {
      if (vertexCount >= 0) fail("two vertex elements");
      if (axis[0] < 0 || axis[1] < 0 || axis[2] < 0) fail("the vertex element needs properties x, y and z");
      vertexCount = e.count;
      mesh.vertices.reserve(size_t(e.count));
    }
    if (isFace) {
      if (vertexCount < 0) fail("the face element comes before the vertex element");
      if (indices < 0) fail("the face element needs a list property vertex_indices");
      if (!plyInteger(e.properties[size_t(indices)].type)) fail("vertex_indices must be integers");
    }
    for (int i = 0; i < e.count; ++i) {
      const std::string where = e.name + " " + std::to_string(i) + ": ";
      double c[3] = {0, 0, 0};
      for (size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        if (!p.list) {
          const double v = in.get(p.type, where);
          for (int a = 0; a < 3; ++a)
            if (int(k) == axis[a]) c[a] = v;
          continue;
        }
        const double n = in.get(p.countType, where);
        if (!(n >= 0) || n > 1e6) fail(where + "bad list length " + numberText(n));
        const size_t len = size_t(n);
        if (!in.ascii() && len * plySize(p.type) > in.bytesLeft()) fail(where + "the file ends inside a list");
        const bool faceList = int(k) == indices;
        if (faceList) {
          if (len < 3) fail(where + "a face needs at least 3 vertices, got " + std::to_string(len));
          face.clear();
        }
        for (size_t q = 0; q < len; ++q) {
          const double v = in.get(p.type, where);
          if (!faceList) continue;
          if (!(v >= 0) || v >= double(vertexCount))
            fail(where + "vertex index " + numberText(v) + " out of range (" + std::to_string(vertexCount) + " vertices)");
          face.push_back(int(v));
        }
        if (faceList) addFace(mesh, face);
      }
      if (isVertex) {
        for (double v : c) checkCoordinate(v, where);
        mesh.vertices.emplace_back(c[0], c[1], c[2]);
      }
    }
  }
  if (vertexCount < 0) fail("no vertex element");
  if (!in.atEnd()) fail("data after the elements the header declares");
  return mesh;
}

// ---------------------------------------------------------------------------------------------
// STL: binary (80-byte header, uint32 count, 50 bytes per triangle: normal, 3 corners as
// little-endian float32, uint16) when the size matches its count exactly, else ASCII
// ("solid", "facet normal", "outer loop", 3 × "vertex x y z", "endloop", "endfacet",
// "endsolid"). Corners are checked, then merged where exactly equal.

TriangleMesh mergeCorners(const std::vector<Eigen::Vector3d>& corners) {
  TriangleMesh mesh;
  std::map<std::array<double, 3>, int> unique;
  std::vector<int> index(corners.size());
  for (size_t i = 0; i < corners.size(); ++i) {
    const auto& v = corners[i];
    auto it = unique.find({v.x(), v.y(), v.z()});
    if (it == unique.end()) {
      it = unique.emplace(std::array<double, 3>{v.x(), v.y(), v.z()}, int(mesh.vertices.size())).first;
      mesh.vertices.push_back(v);
    }
    index[i] = it->second;
  }
  for (size_t t = 0; t + 2 < index.size(); t += 3) mesh.triangles.push_back({index[t], index[t + 1], index[t + 2]});
  return mesh;
}

TriangleMesh parseStl(string_view text) {
  if (text.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, text.data() + 80, 4);  // little-endian host
    if (84 + 50 * std::uint64_t(n) == text.size()) {
      std::vector<Eigen::Vector3d> corners;
      corners.reserve(size_t(n) * 3);
      for (std::uint32_t t = 0; t < n; ++t) {
        const char* rec = text.data() + 84 + 50 * size_t(t) + 12;
        for (int k = 0; k < 3; ++k) {
          float c[3];
          std::memcpy(c, rec + 12 * k, 12);
          const std::string where = "triangle " + std::to_string(t) + ": ";
          for (float v : c) checkCoordinate(v, where);
          corners.emplace_back(c[0], c[1], c[2]);
        }
      }
      return mergeCorners(corners);
    }
  }
  Lines lines(text);
  string_view line, tok;
  std::vector<Eigen::Vector3d> corners;
  enum { Outside, InSolid, InFacet, InLoop, LoopDone } state = Outside;
  int loopCorners = 0;
  bool anySolid = false;
  while (lines.next(line)) {
    Tokens t(line);
    if (!t.next(tok)) continue;
    const std::string where = lineText(lines.number());
    auto expect = [&](bool ok, const char* what) {
      if (!ok) fail(where + "expected " + what + ", got " + quoted(tok));
    };
    if (tok == "solid") {
      expect(state == Outside, "'endsolid' before a new 'solid'");
      state = InSolid;
      anySolid = true;
      continue;  // the rest is the name
    }
    if (!anySolid) fail("not an STL file (neither 'solid' nor a binary STL of matching size)");
    if (tok == "endsolid") {
      expect(state == InSolid, "'endfacet'");
      state = Outside;
      continue;  // the rest is the name
    }
    if (tok == "facet") {
      expect(state == InSolid, "'endsolid' or 'facet'");
      string_view n;
      if (!t.next(n) || n != "normal") fail(where + "expected 'facet normal'");
      for (int a = 0; a < 3; ++a) {
        double v;
        if (!t.next(tok) || !parseDouble(tok, v)) fail(where + "the normal needs three numbers");
      }
      state = InFacet;
    } else if (tok == "outer") {
      expect(state == InFacet, "'outer loop' inside a facet");
      if (!t.next(tok) || tok != "loop") fail(where + "expected 'outer loop'");
      state = InLoop;
      loopCorners = 0;
    } else if (tok == "vertex") {
      expect(state == InLoop && loopCorners < 3, "three 'vertex' lines inside 'outer loop'");
      double c[3];
      for (double& v : c) {
        if (!t.next(tok) || !parseDouble(tok, v)) fail(where + "a vertex needs three numbers");
        checkCoordinate(v, where);
      }
      corners.emplace_back(c[0], c[1], c[2]);
      ++loopCorners;
    } else if (tok == "endloop") {
      if (state != InLoop || loopCorners != 3)
        fail(where + "a facet needs exactly 3 vertices, got " + std::to_string(loopCorners));
      state = LoopDone;
    } else if (tok == "endfacet") {
      expect(state == LoopDone, "'endloop' before 'endfacet'");
      state = InSolid;
    } else {
      fail(where + "unexpected " + quoted(tok));
    }
    if (t.next(tok)) fail(where + "unexpected " + quoted(tok));
  }
  if (state != Outside) fail("the file ends inside a solid (no 'endsolid')");
  return mergeCorners(corners);
}

std::string lowerExtension(const std::string& path) {
  const auto dot = path.find_last_of('.');
  const auto slash = path.find_last_of('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

MeshFormat meshFormatOf(const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (ext == "obj") return MeshFormat::Obj;
  if (ext == "off") return MeshFormat::Off;
  if (ext == "ply") return MeshFormat::Ply;
  if (ext == "stl") return MeshFormat::Stl;
  throw MeshError(path + ": unsupported mesh format '" + ext + "' (expected .obj, .off, .ply or .stl)");
}

TriangleMesh parseMesh(const std::string& bytes, MeshFormat format, const std::string& name) {
  if (bytes.empty()) throw MeshError(name + ": empty file");
  TriangleMesh mesh;
  try {
    switch (format) {
      case MeshFormat::Obj: mesh = parseObj(bytes); break;
      case MeshFormat::Off: mesh = parseOff(bytes); break;
      case MeshFormat::Ply: mesh = parsePly(bytes); break;
      case MeshFormat::Stl: mesh = parseStl(bytes); break;
    }
  } catch (const ParseFail& f) {
    throw MeshError(name + ": " + f.reason);
  }
  if (mesh.vertices.empty()) throw MeshError(name + ": no vertices");
  if (mesh.vertices.size() > size_t(std::numeric_limits<int>::max()))
    throw MeshError(name + ": too many vertices");
  return mesh;
}

TriangleMesh readMesh(const std::string& path) {
  const MeshFormat format = meshFormatOf(path);
  std::string bytes;
  try {
    bytes = readFileBounded(path, kMaxMeshFileBytes);
  } catch (const FileError& e) {
    throw MeshError(e.what());
  }
  return parseMesh(bytes, format, path);
}

void writeObj(const std::string& path, const TriangleMesh& mesh) {
  try {
    writeFileAtomic(path, [&](std::ostream& out) {
      char line[96];
      out << "# written by softbody\n";
      for (const auto& v : mesh.vertices) {
        std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", v.x(), v.y(), v.z());
        out << line;
      }
      for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
    });
  } catch (const FileError& e) {
    throw MeshError(e.what());
  }
}

}  // namespace sb::mesh
