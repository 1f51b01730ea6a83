// Automatic cages made once per mesh and options: a scene that names a detailed mesh with
// "cage": {"auto": true} loads in milliseconds after the first time, as bound render meshes do
// (embedding.h's bind cache).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "sim/cage/auto_cage.h"
#include "sim/mesh/triangle_mesh.h"

namespace sb::cage {

// 128-bit key of the cage makeCage(mesh, options) returns: the mesh's vertices and triangles,
// the options that change the cage (vertex budget, tightness; not threads: the result is the
// same for any thread count) and the cache format version.
std::array<std::uint64_t, 2> cageCacheKey(const mesh::TriangleMesh& mesh,
                                          const CageOptions& options);
// cacheDir/cage-<key as 32 hex digits>.obj
std::string cageCachePath(const std::string& cacheDir, const std::array<std::uint64_t, 2>& key);

struct CachedCage {
  mesh::TriangleMesh cage;
  bool fromCache = false;  // read from the cache (else made now, and written when possible)
  CageReport report;       // of makeCage; only `vertices` and `triangles` when fromCache
};

// The cage of `mesh`: read from cacheDir when a file with its key is there and is a valid
// closed surface, else made by makeCage and written there (atomically; a cache that cannot be
// written only costs the next load another makeCage). An empty cacheDir disables the cache.
// Throws what makeCage throws.
CachedCage cachedCage(const mesh::TriangleMesh& mesh, const CageOptions& options,
                      const std::string& cacheDir);

}  // namespace sb::cage
