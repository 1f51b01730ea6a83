#include "sim/mesh/mesh_reading.h"

namespace sb::mesh::reading {

// PLY: "ply", "format ascii|binary_little_endian|binary_big_endian 1.0", "comment"/"obj_info"
// lines, "element NAME COUNT", "property TYPE NAME", "property list COUNTTYPE TYPE NAME",
// "end_header". Vertices need x, y, z; faces a list vertex_indices (or vertex_index); other
// elements and properties are read and skipped.

namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool plyType(string_view name, PlyType& type) {
  static const std::pair<const char*, PlyType> names[] = {
      {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
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

bool plyInteger(PlyType t) {
  return t != PlyType::Float32 && t != PlyType::Float64;
}

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
      return t == PlyType::Float32 && fitsFloat(v) ? double(float(v)) : v;
    }
    const char* what = "the element data";
    switch (t) {
      case PlyType::Int8:
        return bytes_.get<std::int8_t>(what);
      case PlyType::UInt8:
        return bytes_.get<std::uint8_t>(what);
      case PlyType::Int16:
        return bytes_.get<std::int16_t>(what);
      case PlyType::UInt16:
        return bytes_.get<std::uint16_t>(what);
      case PlyType::Int32:
        return bytes_.get<std::int32_t>(what);
      case PlyType::UInt32:
        return bytes_.get<std::uint32_t>(what);
      case PlyType::Float32:
        return bytes_.get<float>(what);
      case PlyType::Float64:
        return bytes_.get<double>(what);
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

}  // namespace

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
      if (tok == "ascii")
        format = 0;
      else if (tok == "binary_little_endian")
        format = 1;
      else if (tok == "binary_big_endian")
        format = 2;
      else
        fail(where + "unknown format " + quoted(tok));
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
    for (const PlyProperty& p : e.properties)
      minBytes += in.ascii() ? 2 : plySize(p.list ? p.countType : p.type);
    if (in.ascii()) minBytes -= 1;  // the last value's blank may be the end of the file
    const size_t available = in.ascii() ? text.size() - lines.position() : in.bytesLeft();
    if (std::uint64_t(e.count) * minBytes > available)
      fail("the header declares " + std::to_string(e.count) + " " + e.name +
           " elements, more than the " + std::to_string(available) + " bytes after it can hold");
    const bool isVertex = e.name == "vertex", isFace = e.name == "face";
    int axis[3] = {-1, -1, -1}, indices = -1;
    for (size_t k = 0; k < e.properties.size(); ++k) {
      const PlyProperty& p = e.properties[k];
      for (int a = 0; a < 3; ++a)
        if (isVertex && !p.list && p.name == std::string(1, char('x' + a))) axis[a] = int(k);
      if (isFace && p.list && (p.name == "vertex_indices" || p.name == "vertex_index"))
        indices = int(k);
    }
    if (isVertex) {
      if (vertexCount >= 0) fail("two vertex elements");
      if (axis[0] < 0 || axis[1] < 0 || axis[2] < 0)
        fail("the vertex element needs properties x, y and z");
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
        if (!in.ascii() && len * plySize(p.type) > in.bytesLeft())
          fail(where + "the file ends inside a list");
        const bool faceList = int(k) == indices;
        if (faceList) {
          if (len < 3) fail(where + "a face needs at least 3 vertices, got " + std::to_string(len));
          face.clear();
        }
        for (size_t q = 0; q < len; ++q) {
          const double v = in.get(p.type, where);
          if (!faceList) continue;
          if (!(v >= 0) || v >= double(vertexCount))
            fail(where + "vertex index " + numberText(v) + " out of range (" +
                 std::to_string(vertexCount) + " vertices)");
          face.push_back(int(v));
        }
        if (faceList) addFace(mesh, face, where);
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

}  // namespace sb::mesh::reading
