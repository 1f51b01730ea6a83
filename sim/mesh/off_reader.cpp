#include "sim/mesh/mesh_reading.h"

namespace sb::mesh::reading {

// OFF, ASCII: "[ST][C][N]OFF", then "nv nf [ne]", nv vertex lines (x y z, extra numbers such as
// colours allowed), nf face lines "k i1 .. ik [colour]"; '#' starts a comment. Binary ("OFF
// BINARY"): big-endian int32 nv nf ne, nv × 3 float32, per face int32 k, k int32 indices,
// int32 colour count and that many float32.

namespace {

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
        fail(where + "vertex index " + std::to_string(i) + " out of range (" + std::to_string(nv) +
             " vertices)");
      face.push_back(i);
    }
    const std::int32_t colours = in.get<std::int32_t>("the faces");
    if (colours < 0 || colours > 4) fail(where + "bad colour count " + std::to_string(colours));
    for (int c = 0; c < colours; ++c) (void)in.get<float>("the faces");
    addFace(mesh, face, where);
  }
  if (in.left() != 0)
    fail("binary OFF: " + std::to_string(in.left()) + " bytes after the " + std::to_string(nf) +
         " faces the header declares");
  return mesh;
}

}  // namespace

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
  if (!offKeyword(tok, binaryCapable))
    fail("not an OFF file (first word " + quoted(tok) + ", expected OFF)");
  if (t.next(tok)) {
    if (tok == "BINARY" && binaryCapable && t.empty())
      return parseOffBinary(text, lines.position());
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
      fail("the header declares " + std::to_string(nv) + " vertices, the file ends after " +
           std::to_string(i));
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
      fail("the header declares " + std::to_string(nf) + " faces, the file ends after " +
           std::to_string(f));
    const std::string where = lineText(lines.number());
    t.next(tok);
    long long k = 0;
    if (!parseInteger(tok, k))
      fail(where + "a face starts with its corner count, got " + quoted(tok));
    if (k < 3) fail(where + "a face needs at least 3 vertices, got " + std::to_string(k));
    face.clear();
    for (long long c = 0; c < k; ++c) {
      long long i = 0;
      if (!t.next(tok))
        fail(where + "the face declares " + std::to_string(k) + " corners but lists " +
             std::to_string(c));
      if (!parseInteger(tok, i)) fail(where + "bad vertex index " + quoted(tok));
      if (i < 0 || i >= nv)
        fail(where + "vertex index " + std::to_string(i) + " out of range (" + std::to_string(nv) +
             " vertices)");
      face.push_back(int(i));
    }
    while (t.next(tok)) {  // a colour
      double extra;
      if (!parseDouble(tok, extra)) fail(where + "not a number: " + quoted(tok));
    }
    addFace(mesh, face, where);
  }
  if (nextLine(t))
    fail(lineText(lines.number()) + "data after the " + std::to_string(nv) + " vertices and " +
         std::to_string(nf) + " faces the header declares");
  return mesh;
}

}  // namespace sb::mesh::reading
