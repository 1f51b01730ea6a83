#include "sim/cage/bind.h"

#include <memory>
#include <stdexcept>

#include "sim/base/hasher.h"
#include "sim/base/parallel.h"
#include "sim/cage/green.h"
#include "sim/mesh/closed_surface.h"

namespace sb::cage {
namespace {

// The mean value key (points, cage, format version, storage options) extended by the kind and
// the options that change the weights of the other methods (not threads or progress).
std::array<std::uint64_t, 2> methodCacheKey(const std::vector<Vec3>& points,
                                            const mesh::TriangleMesh& cage,
                                            const EmbeddingMethod& method,
                                            const BindOptions& options) {
  std::array<std::uint64_t, 2> key = bindCacheKey(points, cage, options);
  for (std::uint64_t& k : key) {
    Hasher h(k);
    h.value(static_cast<std::uint64_t>(method.kind));
    if (method.kind == EmbeddingKind::Harmonic) {
      h.value(static_cast<std::int64_t>(method.harmonic.resolution));
      h.value(static_cast<std::uint64_t>(method.harmonic.boundary));
      h.value(static_cast<std::uint64_t>(method.harmonic.ordering));  // round-off differs
      h.value(static_cast<std::uint64_t>(method.harmonic.solver));    // so does the solver's
      h.value(method.harmonic.cgTolerance);
    } else if (method.kind == EmbeddingKind::Rbf) {
      h.value(method.rbf.shape);
    }
    k = h.digest();
  }
  return key;
}

}  // namespace

Embedding bindToCage(const std::vector<Vec3>& points, const mesh::TriangleMesh& cage,
                     const EmbeddingMethod& method, const BindOptions& options) {
  switch (method.kind) {
    case EmbeddingKind::MeanValue:
      return bindMeanValue(points, cage, options);  // its own cache key, unchanged
    case EmbeddingKind::Harmonic:
    case EmbeddingKind::Rbf:
    case EmbeddingKind::Green:
      break;
    case EmbeddingKind::FfdBernstein:
    case EmbeddingKind::FfdBSpline:
      throw std::invalid_argument(std::string("bind: '") + embeddingKindName(method.kind) +
                                  "' is driven by a lattice, not a cage (bindFfd)");
  }
  mesh::validateClosedSurface(cage, "cage");
  std::array<std::uint64_t, 2> key{};
  std::string path;
  // Green weights have a column per cage vertex and one per face (their scaled normals).
  const bool green = method.kind == EmbeddingKind::Green;
  const int columns = int(cage.vertices.size() + (green ? cage.triangles.size() : 0));
  if (!options.cacheDir.empty()) {
    key = methodCacheKey(points, cage, method, options);
    path = bindCachePath(options.cacheDir, key);
    if (std::optional<Embedding> cached =
            loadCachedBind(path, key, method.kind, int(points.size()), columns, options)) {
      if (green) cached->attachGreenCage(std::make_shared<const mesh::TriangleMesh>(cage));
      return std::move(*cached);
    }
  }
  Embedding e;
  if (green) {
    GreenOptions g;
    g.threads = options.threads;
    g.keepDoublePrecision = options.keepDoublePrecision;
    e = bindGreen(points, cage, g);  // attaches the cage
  } else if (method.kind == EmbeddingKind::Harmonic) {
    HarmonicOptions h = method.harmonic;
    if (h.threads <= 0) h.threads = options.threads;
    e = bindHarmonic(points, cage, h);
  } else {
    RbfOptions r = method.rbf;
    if (r.threads <= 0) r.threads = options.threads;
    e = bindRbf(points, cage.vertices, r);
  }
  if (!path.empty()) saveCachedBind(e, path, key, options);
  return e;
}

}  // namespace sb::cage
