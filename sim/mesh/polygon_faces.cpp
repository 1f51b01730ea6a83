#include <stdexcept>
#include <string>

#include "sim/mesh/triangle_mesh.h"

namespace sb::mesh {

std::vector<std::vector<int>> polygonFaces(const TriangleMesh& mesh) {
  std::vector<std::vector<int>> faces;
  const std::size_t nt = mesh.triangles.size();
  if (mesh.polygonOf.empty()) {
    faces.reserve(nt);
    for (const auto& t : mesh.triangles) faces.push_back({t[0], t[1], t[2]});
    return faces;
  }
  if (mesh.polygonOf.size() != nt)
    throw std::invalid_argument("mesh: " + std::to_string(mesh.polygonOf.size()) +
                                " polygon ids for " + std::to_string(nt) + " triangles");
  for (std::size_t i = 0; i < nt;) {
    const int id = mesh.polygonOf[i];
    const auto& first = mesh.triangles[i];
    std::vector<int> face{first[0], first[1], first[2]};
    std::size_t j = i + 1;
    // The fan's next triangle starts at the same corner and continues from the last one.
    for (; j < nt && mesh.polygonOf[j] == id; ++j) {
      const auto& t = mesh.triangles[j];
      if (t[0] != first[0] || t[1] != face.back())
        throw std::invalid_argument("mesh: triangle " + std::to_string(j) + " of polygon " +
                                    std::to_string(id) + " does not continue its fan");
      face.push_back(t[2]);
    }
    faces.push_back(std::move(face));
    i = j;
  }
  return faces;
}

bool hasPolygonFaces(const TriangleMesh& mesh) {
  for (std::size_t i = 1; i < mesh.polygonOf.size(); ++i)
    if (mesh.polygonOf[i] == mesh.polygonOf[i - 1]) return true;
  return false;
}

}  // namespace sb::mesh
