#include "sim/mesh/mesh_reading.h"

#include <array>
#include <map>

namespace sb::mesh::reading {

// STL: binary (80-byte header, uint32 count, 50 bytes per triangle: normal, 3 corners as
// little-endian float32, uint16) when the size matches its count exactly, else ASCII
// ("solid", "facet normal", "outer loop", 3 × "vertex x y z", "endloop", "endfacet",
// "endsolid"). Corners are checked, then merged where exactly equal.

namespace {

TriangleMesh mergeCorners(const std::vector<Eigen::Vector3d>& corners) {
  TriangleMesh mesh;
  std::map<std::array<double, 3>, int> unique;
  std::vector<int> index(corners.size());
  for (size_t i = 0; i < corners.size(); ++i) {
    const auto& v = corners[i];
    auto it = unique.find({v.x(), v.y(), v.z()});
    if (it == unique.end()) {
      it = unique.emplace(std::array<double, 3>{v.x(), v.y(), v.z()}, int(mesh.vertices.size()))
               .first;
      mesh.vertices.push_back(v);
    }
    index[i] = it->second;
  }
  for (size_t t = 0; t + 2 < index.size(); t += 3)
    mesh.triangles.push_back({index[t], index[t + 1], index[t + 2]});
  return mesh;
}

}  // namespace

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

}  // namespace sb::mesh::reading
