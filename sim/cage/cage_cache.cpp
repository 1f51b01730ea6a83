#include "sim/cage/cage_cache.h"

#include <filesystem>
#include <system_error>

#include "sim/base/hasher.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"

namespace sb::cage {

namespace {
// Bump when makeCage's result for the same input changes, so old cages are not reused.
constexpr std::uint64_t kCageCacheVersion = 2;
}  // namespace

std::array<std::uint64_t, 2> cageCacheKey(const mesh::TriangleMesh& mesh,
                                          const CageOptions& options) {
  std::array<std::uint64_t, 2> key{};
  for (int s = 0; s < 2; ++s) {
    Hasher h(s == 0 ? 0xCA6E0001ull : 0xCA6E0002ull);
    h.value(kCageCacheVersion);
    h.value(static_cast<std::uint64_t>(mesh.vertices.size()));
    if (!mesh.vertices.empty())
      h.bytes(mesh.vertices.data(), mesh.vertices.size() * sizeof(Eigen::Vector3d));
    h.value(static_cast<std::uint64_t>(mesh.triangles.size()));
    if (!mesh.triangles.empty())
      h.bytes(mesh.triangles.data(), mesh.triangles.size() * sizeof(std::array<int, 3>));
    h.value(static_cast<std::int64_t>(options.vertexBudget));
    h.value(options.tightness);
    key[size_t(s)] = h.digest();
  }
  return key;
}

std::string cageCachePath(const std::string& cacheDir, const std::array<std::uint64_t, 2>& key) {
  return keyedCachePath(cacheDir, "cage-", key, ".obj");
}

CachedCage cachedCage(const mesh::TriangleMesh& mesh, const CageOptions& options,
                      const std::string& cacheDir) {
  CachedCage out;
  const std::string path =
      cacheDir.empty() ? "" : cageCachePath(cacheDir, cageCacheKey(mesh, options));
  if (!path.empty()) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(path, ec)) {
      try {
        out.cage = mesh::readMesh(path);
        mesh::validateClosedSurface(out.cage, path);
        out.fromCache = true;
        out.report.vertices = static_cast<int>(out.cage.vertices.size());
        out.report.triangles = static_cast<int>(out.cage.triangles.size());
        return out;
      } catch (const std::exception&) {
        // A damaged or foreign file: make the cage again and replace it.
      }
    }
  }
  CageResult made = makeCage(mesh, options);
  out.cage = std::move(made.cage);
  out.report = made.report;
  if (!path.empty()) {
    try {
      std::error_code ec;
      std::filesystem::create_directories(cacheDir, ec);
      mesh::writeObj(path, out.cage);
    } catch (const std::exception&) {
      // Not writable: the next load makes the cage again.
    }
  }
  return out;
}

}  // namespace sb::cage
