#include "sim/mesh/mesh_reading.h"

namespace sb::mesh::reading {

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
      if (face.size() < 3)
        fail(where + "a face needs at least 3 vertices, got " + std::to_string(face.size()));
      addFace(mesh, face, where);
    }
  }
  return mesh;
}

}  // namespace sb::mesh::reading
