#include "sim/scene/scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "sim/base/file_io.h"
#include "sim/base/parallel_for.h"
#include "sim/cage/cage_cache.h"
#include "sim/cage/embedding.h"
#include "sim/cage/interior_points.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "sim/world/param_ranges.h"

namespace sb {

namespace fs = std::filesystem;
using nlohmann::json;

// Largest scene file read (a scene lists bodies and settings; its meshes are separate files).
constexpr std::uint64_t kMaxSceneBytes = 64ull << 20;

namespace {

// An integer JSON number as int64; false when it does not fit (2^63 and above).
bool jsonInt64(const json& v, long long& out) {
  if (v.is_number_unsigned()) {
    const std::uint64_t u = v.get<std::uint64_t>();
    if (u > std::uint64_t(std::numeric_limits<long long>::max())) return false;
    out = static_cast<long long>(u);
    return true;
  }
  if (!v.is_number_integer()) return false;
  out = v.get<std::int64_t>();
  return true;
}

// A particle index from a scene (pinned, explicit clusters): an integer in [0, 2^31 − 1], read
// without truncation; whether it names a particle of the body the World checks.
bool particleIndex(const json& v, int& out) {
  long long i = 0;
  if (!jsonInt64(v, i) || i < 0 || i > std::numeric_limits<int>::max()) return false;
  out = static_cast<int>(i);
  return true;
}

// Reads one JSON object, remembering which keys were used so unknown (mistyped) keys can be
// reported instead of silently ignored.
class Fields {
 public:
  Fields(const json& j, std::string where, std::string file)
      : j_(j), where_(std::move(where)), file_(std::move(file)) {
    if (!j_.is_object()) fail("", "must be a JSON object");
  }
  [[noreturn]] void fail(const std::string& key, const std::string& reason) const {
    std::string field = where_;
    if (!key.empty()) field += (field.empty() ? "" : ".") + key;
    throw SceneError(file_ + ": " + (field.empty() ? "" : field + ": ") + reason);
  }
  bool has(const std::string& key) {
    used_.insert(key);
    return j_.contains(key);
  }
  double number(const std::string& key, double fallback, const ParamRange& range) {
    if (!has(key)) return fallback;
    const json& v = j_.at(key);
    if (!v.is_number()) fail(key, "must be a number");
    const double d = v.get<double>();
    const std::string violation = rangeViolation(range, d);
    if (!violation.empty()) fail(key, violation);
    return d;
  }
  int integer(const std::string& key, int fallback, const ParamRange& range) {
    if (!has(key)) return fallback;
    const json& v = j_.at(key);
    long long d = 0;
    if (!v.is_number_integer()) fail(key, "must be an integer");
    if (!jsonInt64(v, d) || !range.contains(double(d)))
      fail(key, "must be in " + describe(range) + ", got " + v.dump());
    return static_cast<int>(d);
  }
  bool boolean(const std::string& key, bool fallback) {
    if (!has(key)) return fallback;
    if (!j_.at(key).is_boolean()) fail(key, "must be true or false");
    return j_.at(key).get<bool>();
  }
  std::string text(const std::string& key, const std::string* fallback) {
    if (!has(key)) {
      if (!fallback) fail(key, "is required");
      return *fallback;
    }
    if (!j_.at(key).is_string()) fail(key, "must be a string");
    return j_.at(key).get<std::string>();
  }
  Vec3 vec3(const std::string& key, const Vec3& fallback, double limit = limits::coordinateLimit) {
    if (!has(key)) return fallback;
    const json& v = j_.at(key);
    if (!v.is_array() || v.size() != 3) fail(key, "must be an array of 3 numbers");
    Vec3 out;
    for (int a = 0; a < 3; ++a) {
      if (!v[size_t(a)].is_number()) fail(key, "must be an array of 3 numbers");
      out[a] = v[size_t(a)].get<double>();
      if (!(std::abs(out[a]) <= limit))
        fail(key, "components must be finite and within ±" + formatNumber(limit));
    }
    return out;
  }
  const json& raw(const std::string& key) {
    used_.insert(key);
    return j_.at(key);
  }
  std::string where(const std::string& key) const {
    return where_ + (where_.empty() ? "" : ".") + key;
  }
  const std::string& file() const { return file_; }
  // Call after reading every known key.
  void rejectUnknown() const {
    for (auto it = j_.begin(); it != j_.end(); ++it)
      if (!used_.count(it.key())) fail(it.key(), "unknown field");
  }

 private:
  const json& j_;
  std::string where_, file_;
  std::set<std::string> used_;
};

std::string cacheDirectory() {
  if (const char* env = std::getenv("SOFTBODY_CACHE_DIR")) return env;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME")) return std::string(xdg) + "/softbody";
  if (const char* home = std::getenv("HOME")) return std::string(home) + "/.cache/softbody";
  return "";
}

// Offsets and coordinates of colliders.
constexpr ParamRange kCoordinates{-limits::coordinateLimit, limits::coordinateLimit};

Collider parseCollider(Fields& f) {
  const std::string type = f.text("type", nullptr);
  const double friction = f.number("friction", 0.5, limits::friction);
  Collider c;
  if (type == "plane") {
    const Vec3 n = f.vec3("normal", Vec3::UnitY());
    if (!(n.norm() > 0.0)) f.fail("normal", "must not be zero");
    c = Collider::plane(n, f.number("offset", 0.0, kCoordinates), friction);
  } else if (type == "box") {
    const Vec3 half = f.vec3("halfExtents", Vec3::Constant(0.5));
    if ((half.array() <= 0.0).any()) f.fail("halfExtents", "must be positive");
    c = Collider::box(f.vec3("centre", Vec3::Zero()), half,
                      eulerDegrees(f.vec3("rotationDegrees", Vec3::Zero(), limits::angleLimit)),
                      friction);
  } else if (type == "sphere") {
    c = Collider::sphere(f.vec3("centre", Vec3::Zero()), f.number("radius", 0.5, limits::radius),
                         friction);
  } else if (type == "capsule") {
    c = Collider::capsule(f.vec3("a", Vec3::Zero()), f.vec3("b", Vec3::UnitY()),
                          f.number("radius", 0.5, limits::radius), friction);
  } else {
    f.fail("type", "must be plane, box, sphere or capsule, got '" + type + "'");
  }
  c.restitution = f.number("restitution", c.restitution, limits::restitution);
  f.rejectUnknown();
  return c;
}

// Lattice region half-width in nodes (a region spans up to 2w + 1 nodes per axis).
constexpr ParamRange kLatticeRegionHalfWidth{1, 16};

// "clusters" of a body; `lattice` says whether it is a lattice body, which may also take
// {"kind": "lattice", "halfWidth": w} (its regions are filled in once the lattice is made;
// *regionHalfWidth receives w, else stays 0).
ClusterDef parseClusters(Fields& f, bool lattice, int* regionHalfWidth) {
  ClusterDef d;
  const std::string single = "single";
  const std::string kind = f.text("kind", &single);
  if (kind == "single") {
    d.kind = ClusterDef::Kind::Single;
  } else if (kind == "grid") {
    d.kind = ClusterDef::Kind::Grid;
    d.cellSize = f.number("cellSize", d.cellSize, limits::cellSize);
    d.overlap = f.number("overlap", d.overlap, limits::overlap);
  } else if (kind == "explicit") {
    d.kind = ClusterDef::Kind::Explicit;
    if (!f.has("clusters")) f.fail("clusters", "is required for explicit clusters");
    const json& list = f.raw("clusters");
    if (!list.is_array()) f.fail("clusters", "must be an array of arrays of particle indices");
    for (const json& c : list) {
      if (!c.is_array()) f.fail("clusters", "must be an array of arrays of particle indices");
      std::vector<int> members;
      for (const json& i : c) {
        if (!i.is_number_integer()) f.fail("clusters", "particle indices must be integers");
        int index = 0;
        if (!particleIndex(i, index))
          f.fail("clusters", "particle index " + i.dump() + " is out of range [0, 2147483647]");
        members.push_back(index);
      }
      d.clusters.push_back(std::move(members));
    }
  } else if (kind == "lattice") {
    if (!lattice) f.fail("kind", "'lattice' regions need a lattice body (\"lattice\": {...})");
    d.kind = ClusterDef::Kind::Explicit;  // the regions, once the lattice is made
    *regionHalfWidth = f.integer("halfWidth", 1, kLatticeRegionHalfWidth);
  } else {
    f.fail("kind", "must be single, grid, explicit or lattice, got '" + kind + "'");
  }
  f.rejectUnknown();
  return d;
}

// Render meshes already bound while loading one scene, by (cage file, render file, render path
// as written): bodies that use the same pair share one embedding, so 50 copies of a bunny hold
// one weight matrix (and the deform reads it from cache instead of memory).
using BoundMeshes = std::map<std::array<std::string, 3>, std::shared_ptr<RenderMesh>>;

// The bounds of a scene's automatic cage settings: makeCage's own (sim/cage/auto_cage.h), and
// a budget beyond which a cage is no longer coarse.
constexpr ParamRange kCageVertices{4, 100000};
constexpr ParamRange kCageTightness{0.0, 1.0};
// Interior lattice spacing, metres (interiorLattice bounds the count).
constexpr ParamRange kInteriorSpacing{0.0, limits::coordinateLimit};
// Harmonic grid cells along the cage's longest side; RBF shape (sim/cage/rbf.h).
constexpr ParamRange kHarmonicResolution{kSceneHarmonicResolutionMin,
                                         kSceneHarmonicResolutionMax};  // ~5 s at 64 (harmonic.h)
constexpr ParamRange kRbfShape{kSceneRbfShapeMin, kSceneRbfShapeMax};
constexpr ParamRange kLatticeMargin{0.0, 1.0};

// "embedding": a method name, or {"method": name, options}. FFD is what "lattice" bodies use.
cage::EmbeddingMethod parseEmbedding(Fields& f) {
  cage::EmbeddingMethod m;
  const json& raw = f.raw("embedding");
  std::string name;
  std::optional<Fields> options;
  if (raw.is_string()) {
    name = raw.get<std::string>();
  } else if (raw.is_object()) {
    options.emplace(raw, f.where("embedding"), f.file());
    name = options->text("method", nullptr);
  } else {
    f.fail("embedding", "must be a method name or an object with \"method\"");
  }
  const std::string field = options ? "embedding.method" : "embedding";
  if (!cage::parseEmbeddingKind(name, &m.kind))
    f.fail(field, "must be mvc, harmonic, rbf or green, got '" + name + "'");
  if (m.kind == cage::EmbeddingKind::FfdBernstein || m.kind == cage::EmbeddingKind::FfdBSpline)
    f.fail(field, "'" + name +
                      "' is how a lattice body's render mesh follows it: give the body a "
                      "\"lattice\" instead, or use mvc, harmonic, rbf or green");
  if (options) {
    if (m.kind == cage::EmbeddingKind::Harmonic)
      m.harmonic.resolution =
          options->integer("resolution", m.harmonic.resolution, kHarmonicResolution);
    if (m.kind == cage::EmbeddingKind::Rbf)
      m.rbf.shape = options->number("shape", m.rbf.shape, kRbfShape);
    options->rejectUnknown();
  }
  return m;
}

// The method and its options as text (part of the key that shares render-mesh binds).
std::string embeddingText(const cage::EmbeddingMethod& m) {
  std::string t = cage::embeddingKindName(m.kind);
  if (m.kind == cage::EmbeddingKind::Harmonic) t += " " + std::to_string(m.harmonic.resolution);
  if (m.kind == cage::EmbeddingKind::Rbf) t += " " + formatNumber(m.rbf.shape);
  return t;
}

mesh::TriangleMesh readMeshField(Fields& f, const std::string& field, const std::string& path,
                                 const std::string& baseDir) {
  mesh::TriangleMesh m;
  try {
    m = mesh::readMesh(resolveScenePath(baseDir, path));
  } catch (const std::exception& e) {
    f.fail(field, e.what());
  }
  if (m.vertices.empty()) f.fail(field, "'" + path + "' has no vertices");
  return m;
}

SceneBody parseBody(Fields& f, const std::string& baseDir, BodyDef& def, BoundMeshes& bound) {
  SceneBody sb;
  const std::string defaultName = "body";
  def.name = f.text("name", &defaultName);
  const std::string none;
  if (f.has("lattice")) {
    Fields l(f.raw("lattice"), f.where("lattice"), f.file());
    LatticeSettings lat;
    if (l.has("nodes")) {
      const json& n = l.raw("nodes");
      if (!n.is_array() || n.size() != 3)
        l.fail("nodes", "must be three integers [l, m, n], got " + n.dump());
      for (size_t a = 0; a < 3; ++a) {
        if (!n[a].is_number_integer() || n[a].get<long long>() < 2 || n[a].get<long long>() > 64)
          l.fail("nodes", "each must be an integer in [2, 64], got " + n[a].dump());
        lat.nodes[a] = n[a].get<int>();
      }
    }
    const std::string bernstein = "bernstein";
    const std::string basis = l.text("basis", &bernstein);
    if (basis != "bspline" && basis != "bernstein")
      l.fail("basis", "must be bspline or bernstein, got '" + basis + "'");
    lat.basis = basis == "bernstein" ? cage::FfdBasis::Bernstein : cage::FfdBasis::BSpline;
    lat.margin = l.number("margin", lat.margin, kLatticeMargin);
    l.rejectUnknown();
    for (const char* other : {"mesh", "cage", "interior", "embedding"})
      if (f.has(other))
        f.fail(other,
               "a lattice body's particles are its lattice's nodes and its render mesh "
               "follows them with the lattice's weights: no '" +
                   std::string(other) + "'");
    if (!f.has("renderMesh"))
      f.fail("renderMesh", "is required with a lattice (the mesh the lattice deforms)");
    sb.lattice = lat;
  }
  if (f.has("cage")) {
    Fields c(f.raw("cage"), f.where("cage"), f.file());
    if (!c.has("auto") || !c.boolean("auto", false))
      c.fail("auto", "must be true (a hand-made cage is given as the body's 'mesh')");
    AutoCageSettings a;
    a.vertices = c.integer("vertices", a.vertices, kCageVertices);
    a.tightness = c.number("tightness", a.tightness, kCageTightness);
    c.rejectUnknown();
    sb.autoCage = a;
  }
  // With an automatic cage the detailed mesh is named once, as renderMesh or as mesh.
  std::string renderPath = f.text("renderMesh", &none);
  std::string renderField = "renderMesh";  // the field that named the detailed mesh
  if (sb.lattice) {
    // the render mesh alone (checked above)
  } else if (!sb.autoCage) {
    sb.meshPath = f.text("mesh", nullptr);
  } else if (f.has("mesh")) {
    if (!renderPath.empty())
      f.fail("cage",
             "an automatic cage replaces 'mesh'; name the detailed mesh once, as renderMesh");
    renderPath = f.text("mesh", nullptr);
    renderField = "mesh";
  } else if (renderPath.empty()) {
    f.fail("renderMesh", "is required with an automatic cage (the mesh the cage is made of)");
  }
  sb.translation = f.vec3("translation", Vec3::Zero());
  sb.rotationDegrees = f.vec3("rotationDegrees", Vec3::Zero(), limits::angleLimit);
  sb.scale = f.number("scale", 1.0, limits::scale);
  sb.totalMass = f.number("mass", 1.0, limits::bodyMass);
  def.totalMass = sb.totalMass;
  sb.velocity = f.vec3("velocity", Vec3::Zero(), limits::speedLimit);
  def.velocity = sb.velocity;
  Mode mode = Mode::Linear;
  const std::string linear = "linear";
  const std::string modeText = f.text("mode", &linear);
  if (!parseMode(modeText, &mode))
    f.fail("mode", "must be rigid, linear or quadratic, got '" + modeText + "'");
  def.params.mode = mode;
  def.params.alpha = f.number("alpha", def.params.alpha, limits::alpha);
  def.params.beta = f.number("beta", def.params.beta, limits::beta);
  def.params.preserveVolume = f.boolean("preserveVolume", def.params.preserveVolume);
  def.params.damping = f.number("damping", def.params.damping, limits::damping);
  def.params.restitution = f.number("restitution", def.params.restitution, limits::restitution);
  sb.contact = f.boolean("contact", true);
  if (f.has("plasticity")) {
    Fields p(f.raw("plasticity"), f.where("plasticity"), f.file());
    def.params.plasticity.yield = p.number("yield", 0.0, limits::plasticYield);
    def.params.plasticity.creep = p.number("creep", 0.0, limits::plasticCreep);
    def.params.plasticity.max = p.number("max", 0.5, limits::plasticMax);
    p.rejectUnknown();
  }
  if (f.has("clusters")) {
    Fields c(f.raw("clusters"), f.where("clusters"), f.file());
    def.clusters = parseClusters(c, sb.lattice.has_value(), &sb.latticeRegionHalfWidth);
  }
  if (f.has("interior")) {
    Fields in(f.raw("interior"), f.where("interior"), f.file());
    sb.interiorSpacing = in.number("spacing", 0.0, kInteriorSpacing);
    if (!(sb.interiorSpacing > 0.0)) in.fail("spacing", "is required and must be positive");
    in.rejectUnknown();
  }
  if (f.has("embedding")) {
    sb.embedding = parseEmbedding(f);
    if (renderPath.empty())
      f.fail("embedding", "needs a render mesh to embed (renderMesh, or an automatic cage's mesh)");
  }
  if (f.has("pinned")) {
    const json& p = f.raw("pinned");
    if (!p.is_array()) f.fail("pinned", "must be an array of particle indices");
    for (const json& i : p) {
      if (!i.is_number_integer()) f.fail("pinned", "particle indices must be integers");
      int index = 0;
      if (!particleIndex(i, index))
        f.fail("pinned", "particle index " + i.dump() + " is out of range [0, 2147483647]");
      def.pinned.push_back(index);
    }
    sb.pinned = def.pinned;
  }
  f.rejectUnknown();

  // Particles: the vertices of the mesh file or of the automatic cage, scaled, rotated and placed.
  mesh::TriangleMesh mesh, detail;
  // The method is part of the key: the same pair bound two ways is two embeddings.
  std::array<std::string, 3> renderKey{resolveScenePath(baseDir, sb.meshPath),
                                       resolveScenePath(baseDir, renderPath),
                                       renderPath + "\n" + embeddingText(sb.embedding)};
  if (sb.lattice) {
    detail = readMeshField(f, renderField, renderPath, baseDir);
    try {
      // In file coordinates, as every bind: the weights serve every placement of the mesh.
      const cage::FfdLattice lattice = cage::ffdLatticeAround(
          detail.vertices, sb.lattice->nodes, sb.lattice->basis, sb.lattice->margin);
      const cage::FfdNodes nodes = lattice.restNodes();
      for (Eigen::Index n = 0; n < nodes.rows(); ++n)
        mesh.vertices.push_back(nodes.row(n).transpose());
      mesh.triangles = lattice.boundaryTriangles();
      sb.latticeFrame = lattice;
      if (sb.latticeRegionHalfWidth > 0)
        def.clusters.clusters = lattice.regions(sb.latticeRegionHalfWidth);
    } catch (const std::exception& e) {
      f.fail("lattice", e.what());
    }
    const auto& n = sb.lattice->nodes;
    renderKey[0] = "lattice " + std::to_string(n[0]) + " " + std::to_string(n[1]) + " " +
                   std::to_string(n[2]) + " " +
                   (sb.lattice->basis == cage::FfdBasis::BSpline ? "bspline " : "bernstein ") +
                   formatNumber(sb.lattice->margin);
  } else if (sb.autoCage) {
    detail = readMeshField(f, renderField, renderPath, baseDir);
    cage::CageOptions options;
    options.vertexBudget = sb.autoCage->vertices;
    options.tightness = sb.autoCage->tightness;
    try {
      // In file coordinates, as the bind: one cage serves every placement of the mesh.
      mesh = cage::cachedCage(detail, options, cacheDirectory()).cage;
    } catch (const std::exception& e) {
      f.fail("cage", "cannot make a cage of '" + renderPath + "': " + e.what());
    }
    renderKey[0] = "automatic cage " + std::to_string(options.vertexBudget) + " " +
                   formatNumber(options.tightness);
  } else {
    mesh = readMeshField(f, "mesh", sb.meshPath, baseDir);
  }
  const Mat3 R = eulerDegrees(sb.rotationDegrees);
  def.positions.clear();
  for (const Vec3& v : mesh.vertices) def.positions.push_back(R * (sb.scale * v) + sb.translation);
  sb.cageVertexCount = static_cast<int>(mesh.vertices.size());
  if (sb.interiorSpacing > 0.0) {
    try {
      mesh::validateClosedSurface(mesh, "the cage");
      // In file coordinates (the lattice is centred on the cage's box), then placed.
      for (const Vec3& v : cage::interiorLattice(mesh, sb.interiorSpacing / sb.scale))
        def.positions.push_back(R * (sb.scale * v) + sb.translation);
    } catch (const std::exception& e) {
      f.fail("interior", e.what());
    }
  }
  sb.cageTriangles = mesh.triangles;
  sb.cagePolygonOf = mesh.polygonOf;
  // The cage is the body's surface for body–body contact (the World checks it is closed).
  if (sb.contact) def.surface = mesh.triangles;

  if (!renderPath.empty() && bound.count(renderKey)) {
    sb.render = bound.at(renderKey);
  } else if (!renderPath.empty()) {
    if (!sb.autoCage && !sb.lattice) detail = readMeshField(f, "renderMesh", renderPath, baseDir);
    cage::BindOptions options;
    options.cacheDir = cacheDirectory();
    options.warning = [](const std::string&) {};  // a cache problem only costs a rebind
    auto render = std::make_shared<RenderMesh>();
    render->path = renderPath;
    render->triangles = detail.triangles;
    try {
      // Bound in file coordinates, so every placement of the same mesh shares the bind and its
      // cache. Mean value, RBF (shape relative to the handle spacing) and Green coordinates
      // (their face frames' stretch is taken against the cage in file coordinates, so a
      // placement's scale enters as it) do not depend on the placement's similarity; harmonic
      // ones (an axis-aligned grid) do, and are those of the mesh as it lies in its file.
      render->embedding = std::make_shared<cage::Embedding>(
          sb.latticeFrame ? cage::bindFfd(detail.vertices, *sb.latticeFrame)
                          : cage::bindToCage(detail.vertices, mesh, sb.embedding, options));
    } catch (const std::exception& e) {
      f.fail("mesh", std::string("cannot bind the render mesh to this cage: ") + e.what());
    }
    if (!sb.latticeFrame) prepareRigidFollow(*render, detail.vertices, mesh.vertices);
    bound[renderKey] = render;
    sb.render = std::move(render);
  }
  return sb;
}

// Builds the DOM like json::parse, and also refuses duplicate keys (JSON leaves them undefined;
// nlohmann keeps the last silently) and reports every error with its line and field path.
class CheckedSax {
 public:
  // keyOrder (may be null) receives the order of the keys per kind of object (SceneKeyOrder).
  CheckedSax(json& root, const char* begin, const char* const* cursor, SceneKeyOrder* keyOrder)
      : dom_(root, true), begin_(begin), cursor_(cursor), keyOrder_(keyOrder) {}
  bool null() { return value() && dom_.null(); }
  bool boolean(bool v) { return value() && dom_.boolean(v); }
  bool number_integer(json::number_integer_t v) { return value() && dom_.number_integer(v); }
  bool number_unsigned(json::number_unsigned_t v) { return value() && dom_.number_unsigned(v); }
  bool number_float(json::number_float_t v, const std::string& s) {
    return value() && dom_.number_float(v, s);
  }
  bool string(std::string& v) { return value() && dom_.string(v); }
  bool binary(json::binary_t& v) { return value() && dom_.binary(v); }
  bool start_object(std::size_t n) {
    value();
    frames_.push_back({false, -1, "", {}});
    return dom_.start_object(n);
  }
  bool key(std::string& k) {
    Frame& f = frames_.back();
    const std::string previous = f.key;  // the key before k in this object ("" for the first)
    f.key = k;
    if (!f.keys.insert(k).second) {
      error_ = "line " + std::to_string(lineAt(size_t(*cursor_ - begin_))) + ": " + path() +
               ": duplicate key (each key may appear once per object)";
      return false;
    }
    if (keyOrder_) {
      // A key new to this kind of object goes right after the key before it in this object
      // (the first at the front): every object's keys stay in their order, so saving and
      // loading again keeps the same order, and the same bytes.
      std::vector<std::string>& keys = (*keyOrder_)[objectKind()];
      if (std::find(keys.begin(), keys.end(), k) == keys.end()) {
        const auto after = std::find(keys.begin(), keys.end(), previous);
        keys.insert(after == keys.end() ? keys.begin() : after + 1, k);
      }
    }
    return dom_.key(k);
  }
  bool end_object() {
    frames_.pop_back();
    return dom_.end_object();
  }
  bool start_array(std::size_t n) {
    value();
    frames_.push_back({true, -1, "", {}});
    return dom_.start_array(n);
  }
  bool end_array() {
    frames_.pop_back();
    return dom_.end_array();
  }
  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& e) {
    const std::string field = path();
    error_ = "line " + std::to_string(lineAt(position)) + ": " +
             (field.empty() ? "" : field + ": ") + "invalid JSON (" + e.what() + ")";
    return false;
  }
  const std::string& error() const { return error_; }

 private:
  struct Frame {
    bool array;
    long index;
    std::string key;
    std::set<std::string> keys;
  };
  bool value() {
    if (!frames_.empty() && frames_.back().array) ++frames_.back().index;
    return true;
  }
  std::string path() const {
    std::string p;
    for (const Frame& f : frames_) {
      if (f.array) {
        if (f.index >= 0) p += "[" + std::to_string(f.index) + "]";
      } else if (!f.key.empty()) {
        p += (p.empty() ? "" : ".") + f.key;
      }
    }
    return p;
  }
  // The kind of the object whose key is being read: its path with array indices dropped.
  std::string objectKind() const {
    std::string p;
    for (size_t i = 0; i + 1 < frames_.size(); ++i) {
      const Frame& f = frames_[i];
      if (f.array)
        p += "[]";
      else
        p += (p.empty() ? "" : ".") + f.key;
    }
    return p;
  }
  long lineAt(size_t offset) const {
    const char* end = begin_ + offset;
    return 1 + std::count(begin_, end, '\n');
  }
  nlohmann::detail::json_sax_dom_parser<json> dom_;
  const char* begin_;
  const char* const* cursor_;
  std::vector<Frame> frames_;
  std::string error_;
  SceneKeyOrder* keyOrder_;
};

// A char iterator that tells how far the parser has read (for the line of a duplicate key).
struct TrackingIterator {
  using iterator_category = std::forward_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;
  const char* p;
  const char** cursor;
  reference operator*() const { return *p; }
  TrackingIterator& operator++() {
    *cursor = ++p;
    return *this;
  }
  TrackingIterator operator++(int) {
    TrackingIterator old = *this;
    ++*this;
    return old;
  }
  bool operator==(const TrackingIterator& o) const { return p == o.p; }
  bool operator!=(const TrackingIterator& o) const { return p != o.p; }
};

json parseJson(const std::string& text, const std::string& name,
               SceneKeyOrder* keyOrder = nullptr) {
  json root;
  const char* cursor = text.data();
  CheckedSax sax(root, text.data(), &cursor, keyOrder);
  const bool ok = json::sax_parse(TrackingIterator{text.data(), &cursor},
                                  TrackingIterator{text.data() + text.size(), &cursor}, &sax);
  if (!ok || !sax.error().empty())
    throw SceneError(name + ": " + (sax.error().empty() ? "invalid JSON" : sax.error()));
  return root;
}

// A path as written in the scene, re-expressed relative to another folder (a saved file's, or
// the scene's mesh folder for an added body).
std::string rebase(const std::string& path, const std::string& fromDir, const std::string& toDir) {
  if (fs::path(path).is_absolute()) return path;
  const fs::path absolute = fs::absolute(fs::path(fromDir.empty() ? "." : fromDir) / path);
  std::error_code ec;
  const fs::path rel = fs::relative(absolute, fs::absolute(toDir.empty() ? "." : toDir), ec);
  return ec || rel.empty() ? absolute.string() : rel.string();
}

}  // namespace

Scene parseScene(const std::string& text, const std::string& name, const std::string& baseDir) {
  SceneKeyOrder keyOrder;
  const json root = parseJson(text, name, &keyOrder);
  Fields top(root, "", name);
  WorldSettings settings;
  if (top.has("world")) {
    Fields w(top.raw("world"), "world", name);
    settings.gravity = w.vec3("gravity", settings.gravity, limits::gravityNorm.hi);
    if (!limits::gravityNorm.contains(settings.gravity.norm()))
      w.fail("gravity", "must be at most " + formatNumber(limits::gravityNorm.hi) +
                            " m/s² long, got " + formatNumber(settings.gravity.norm()));
    settings.timeStep = w.number("timeStep", settings.timeStep, limits::timeStep);
    settings.substeps = w.integer("substeps", settings.substeps, limits::substeps);
    settings.maxSubstep = w.number("maxSubstep", settings.maxSubstep, limits::maxSubstep);
    settings.bodyContact = w.boolean("bodyContact", settings.bodyContact);
    settings.contactFriction =
        w.number("contactFriction", settings.contactFriction, limits::friction);
    settings.restitutionThreshold = w.number("restitutionThreshold", settings.restitutionThreshold,
                                             limits::restitutionThreshold);
    settings.rollingResistance =
        w.number("rollingResistance", settings.rollingResistance, limits::rollingResistance);
    settings.sleep = w.boolean("sleep", settings.sleep);
    w.rejectUnknown();
  }
  Scene scene;
  scene.meshFolder = baseDir;
  scene.keyOrder = std::move(keyOrder);
  scene.world = World(settings);
  if (top.has("colliders")) {
    const json& list = top.raw("colliders");
    if (!list.is_array()) top.fail("colliders", "must be an array");
    for (size_t i = 0; i < list.size(); ++i) {
      Fields c(list[i], "colliders[" + std::to_string(i) + "]", name);
      const Collider collider = parseCollider(c);
      try {
        scene.world.addCollider(collider);
      } catch (const std::invalid_argument& e) {
        c.fail("", e.what());
      }
    }
  }
  if (!top.has("bodies")) top.fail("bodies", "is required (an array of bodies)");
  const json& bodies = top.raw("bodies");
  if (!bodies.is_array()) top.fail("bodies", "must be an array");
  top.rejectUnknown();
  BoundMeshes bound;
  for (size_t i = 0; i < bodies.size(); ++i) {
    const std::string where = "bodies[" + std::to_string(i) + "]";
    Fields b(bodies[i], where, name);
    BodyDef def;
    SceneBody body = parseBody(b, baseDir, def, bound);
    try {
      body.handle = scene.world.addBody(def);
    } catch (const std::invalid_argument& e) {
      b.fail("", e.what());  // the World names the field
    }
    scene.bodies.push_back(std::move(body));
  }
  return scene;
}

PreparedBody prepareSceneBody(const std::string& bodyJson, const std::string& name,
                              const std::string& baseDir) {
  const json root = parseJson(bodyJson, name);
  Fields f(root, "", name);
  PreparedBody prepared;
  BoundMeshes bound;
  prepared.body = parseBody(f, baseDir, prepared.def, bound);
  prepared.name = name;
  prepared.baseDir = baseDir;
  return prepared;
}

int addPreparedBody(Scene& scene, PreparedBody prepared) {
  SceneBody& body = prepared.body;
  // Its paths as the rest of the scene writes them: against the scene's mesh folder.
  const std::string& baseDir = prepared.baseDir;
  if (baseDir != scene.meshFolder) {
    if (!body.meshPath.empty()) body.meshPath = rebase(body.meshPath, baseDir, scene.meshFolder);
    if (body.render)  // its own: prepareSceneBody shares meshes within one call only
      body.render->path = rebase(body.render->path, baseDir, scene.meshFolder);
  }
  try {
    body.handle = scene.world.addBody(prepared.def);
  } catch (const std::invalid_argument& e) {
    throw SceneError(prepared.name + ": " + e.what());
  }
  scene.bodies.push_back(std::move(body));
  return static_cast<int>(scene.bodies.size()) - 1;
}

int addSceneBody(Scene& scene, const std::string& bodyJson, const std::string& name,
                 const std::string& baseDir) {
  return addPreparedBody(scene, prepareSceneBody(bodyJson, name, baseDir));
}

void removeSceneBody(Scene& scene, int body) {
  const SceneBody& b = scene.bodies.at(size_t(body));
  scene.world.removeBody(b.handle);
  scene.bodies.erase(scene.bodies.begin() + body);
}

Scene loadScene(const std::string& path) {
  std::string text;
  try {
    text = readFileBounded(path, kMaxSceneBytes);
  } catch (const FileError& e) {
    throw SceneError(e.what());
  }
  Scene scene = parseScene(text, path, fs::path(path).parent_path().string());
  scene.path = path;  // parseScene set meshFolder to its folder
  return scene;
}

namespace {

// Saved files keep their keys in the order of the file the scene came from (Scene::keyOrder), and
// keys that file did not have in the order the shipped scenes use (an ordered object, not
// nlohmann::json's sorted one), so a saved file reads like the one it came from and saving twice
// gives the same bytes.
using ordered_json = nlohmann::ordered_json;

ordered_json vec(const Vec3& v) {
  return ordered_json::array({v.x(), v.y(), v.z()});
}

// JSON text as people write scene files: two-space indents, and arrays of numbers, strings or
// booleans on one line ("translation": [0, 1.2, 0]) instead of one element per line.
void writeJson(std::ostream& out, const ordered_json& j, int indent) {
  const std::string pad(size_t(indent + 2), ' '), end(size_t(indent), ' ');
  if (j.is_object() && !j.empty()) {
    out << "{\n";
    size_t k = 0;
    for (auto it = j.begin(); it != j.end(); ++it, ++k) {
      out << pad << ordered_json(it.key()).dump() << ": ";
      writeJson(out, it.value(), indent + 2);
      out << (k + 1 < j.size() ? ",\n" : "\n");
    }
    out << end << "}";
  } else if (j.is_array() && !j.empty()) {
    const bool flat = std::none_of(
        j.begin(), j.end(), [](const ordered_json& e) { return e.is_structured() && !e.empty(); });
    if (flat) {
      out << "[";
      for (size_t k = 0; k < j.size(); ++k) out << (k ? ", " : "") << j[k].dump();
      out << "]";
      return;
    }
    out << "[\n";
    for (size_t k = 0; k < j.size(); ++k) {
      out << pad;
      writeJson(out, j[k], indent + 2);
      out << (k + 1 < j.size() ? ",\n" : "\n");
    }
    out << end << "]";
  } else {
    out << j.dump();
  }
}

ordered_json colliderJson(const Collider& c) {
  ordered_json j;
  j["type"] = colliderShapeName(c.shape);
  switch (c.shape) {
    case Collider::Shape::Plane:
      j["normal"] = vec(c.normal);
      j["offset"] = c.offset;
      break;
    case Collider::Shape::Box:
      j["centre"] = vec(c.centre);
      j["halfExtents"] = vec(c.halfExtents);
      j["rotationDegrees"] = vec(c.rotation.eulerAngles(2, 1, 0).reverse() * (180.0 / M_PI));
      break;
    case Collider::Shape::Sphere:
      j["centre"] = vec(c.centre);
      j["radius"] = c.radius;
      break;
    case Collider::Shape::Capsule:
      j["a"] = vec(c.centre - c.axis);
      j["b"] = vec(c.centre + c.axis);
      j["radius"] = c.radius;
      break;
  }
  j["friction"] = c.friction;
  j["restitution"] = c.restitution;
  return j;
}

ordered_json bodyJson(const World& w, const SceneBody& b, const std::string& fromDir,
                      const std::string& toDir) {
  const BodyParams& p = w.params(b.handle);
  ordered_json j;
  j["name"] = w.name(b.handle);
  if (b.lattice) {
    j["lattice"] = {
        {"nodes", {b.lattice->nodes[0], b.lattice->nodes[1], b.lattice->nodes[2]}},
        {"basis", b.lattice->basis == cage::FfdBasis::BSpline ? "bspline" : "bernstein"},
        {"margin", b.lattice->margin}};
  } else if (b.autoCage) {
    j["cage"] = {
        {"auto", true}, {"vertices", b.autoCage->vertices}, {"tightness", b.autoCage->tightness}};
  } else {
    j["mesh"] = rebase(b.meshPath, fromDir, toDir);
  }
  if (b.render) j["renderMesh"] = rebase(b.render->path, fromDir, toDir);
  if (b.render && b.embedding.kind != cage::EmbeddingKind::MeanValue) {
    ordered_json e;
    e["method"] = cage::embeddingKindName(b.embedding.kind);
    if (b.embedding.kind == cage::EmbeddingKind::Harmonic)
      e["resolution"] = b.embedding.harmonic.resolution;
    if (b.embedding.kind == cage::EmbeddingKind::Rbf) e["shape"] = b.embedding.rbf.shape;
    j["embedding"] = e;
  }
  if (b.interiorSpacing > 0.0) j["interior"] = {{"spacing", b.interiorSpacing}};
  j["translation"] = vec(b.translation);
  j["rotationDegrees"] = vec(b.rotationDegrees);
  j["scale"] = b.scale;
  j["mass"] = b.totalMass;
  if (b.velocity != Vec3::Zero()) j["velocity"] = vec(b.velocity);
  j["mode"] = modeName(p.mode);
  j["alpha"] = p.alpha;
  j["beta"] = p.beta;
  j["preserveVolume"] = p.preserveVolume;
  j["damping"] = p.damping;
  j["restitution"] = p.restitution;
  j["contact"] = b.contact;
  j["plasticity"] = {
      {"yield", p.plasticity.yield}, {"creep", p.plasticity.creep}, {"max", p.plasticity.max}};
  const ClusterDef& c = w.clusterDef(b.handle);
  ordered_json cj;
  cj["kind"] = clusterKindName(c.kind);
  if (b.latticeFrame && b.latticeRegionHalfWidth > 0 && c.kind == ClusterDef::Kind::Explicit &&
      c.clusters == b.latticeFrame->regions(b.latticeRegionHalfWidth)) {
    // Still the lattice's regions (the viewer may have changed the clusters since).
    cj["kind"] = "lattice";
    cj["halfWidth"] = b.latticeRegionHalfWidth;
  } else if (c.kind == ClusterDef::Kind::Grid) {
    cj["cellSize"] = c.cellSize;
    cj["overlap"] = c.overlap;
  } else if (c.kind == ClusterDef::Kind::Explicit) {
    cj["clusters"] = c.clusters;
  }
  j["clusters"] = cj;
  if (!b.pinned.empty()) j["pinned"] = b.pinned;
  return j;
}

// `j` with every object's keys in the order of SceneKeyOrder `order` for its kind, then the
// keys the file did not have in the order they come in `j`.
ordered_json inFileOrder(const ordered_json& j, const std::string& kind,
                         const SceneKeyOrder& order) {
  if (j.is_array()) {
    ordered_json out = ordered_json::array();
    for (const ordered_json& e : j) out.push_back(inFileOrder(e, kind + "[]", order));
    return out;
  }
  if (!j.is_object()) return j;
  auto kindOf = [&](const std::string& key) { return kind.empty() ? key : kind + "." + key; };
  ordered_json out = ordered_json::object();
  const auto file = order.find(kind);
  if (file != order.end())
    for (const std::string& k : file->second)
      if (j.contains(k)) out[k] = inFileOrder(j[k], kindOf(k), order);
  for (auto e = j.begin(); e != j.end(); ++e)
    if (!out.contains(e.key())) out[e.key()] = inFileOrder(e.value(), kindOf(e.key()), order);
  return out;
}

}  // namespace

std::string sceneText(const Scene& scene, const std::string& path) {
  const World& w = scene.world;
  const std::string& fromDir = scene.meshFolder;
  const std::string toDir = fs::path(path).parent_path().string();
  const WorldSettings& s = w.settings();
  ordered_json root;
  root["world"] = {{"gravity", vec(s.gravity)},
                   {"timeStep", s.timeStep},
                   {"substeps", s.substeps},
                   {"maxSubstep", s.maxSubstep},
                   {"bodyContact", s.bodyContact},
                   {"contactFriction", s.contactFriction},
                   {"restitutionThreshold", s.restitutionThreshold},
                   {"rollingResistance", s.rollingResistance},
                   {"sleep", s.sleep}};
  root["colliders"] = ordered_json::array();
  for (const Collider& c : w.colliders()) root["colliders"].push_back(colliderJson(c));
  root["bodies"] = ordered_json::array();
  for (const SceneBody& b : scene.bodies)
    if (w.contains(b.handle)) root["bodies"].push_back(bodyJson(w, b, fromDir, toDir));
  std::ostringstream out;
  writeJson(out, scene.keyOrder.empty() ? root : inFileOrder(root, "", scene.keyOrder), 0);
  out << "\n";
  return out.str();
}

void saveScene(const Scene& scene, const std::string& path) {
  const std::string text = sceneText(scene, path);
  try {
    writeFileAtomic(path, [&](std::ostream& out) { out << text; });
  } catch (const FileError& e) {
    throw SceneError(e.what());
  }
}

void prepareRigidFollow(RenderMesh& render, const std::vector<Vec3>& meshVertices,
                        const std::vector<Vec3>& cageVertices) {
  render.rigidFollow.reset();
  if (!render.embedding) return;
  auto asPoints = [](const std::vector<Vec3>& v) {
    PointsRowMajor p(static_cast<Eigen::Index>(v.size()), 3);
    for (size_t i = 0; i < v.size(); ++i) p.row(Eigen::Index(i)) = v[i].transpose().cast<float>();
    return p;
  };
  render.rigidFollow =
      cage::RigidFollow::make(*render.embedding, asPoints(cageVertices), asPoints(meshVertices));
}

void Scene::renderVertices(int body, PointsRowMajor& out) const {
  renderVertices(std::vector<int>{body}, std::vector<PointsRowMajor*>{&out});
}

void Scene::renderVertices(const std::vector<int>& which,
                           const std::vector<PointsRowMajor*>& outs) const {
  // One group per binding, in order of first appearance.
  struct Group {
    const cage::Embedding* embedding;
    std::vector<ConstPointsRef> cages;
    std::vector<PointsRowMajor*> outs;
  };
  std::vector<Group> groups;
  if (outs.size() != which.size())
    throw std::invalid_argument("Scene::renderVertices: " + std::to_string(which.size()) +
                                " bodies but " + std::to_string(outs.size()) + " outputs");
  // Bodies whose cages moved as a whole first, in parallel (each writes its own output; the
  // look-ups, which may throw, are made before).
  struct Candidate {
    size_t k;
    const cage::RigidFollow* follow;
    ConstPointsRef cage;
  };
  std::vector<Candidate> candidates;
  for (size_t k = 0; k < which.size(); ++k) {
    const SceneBody& b = bodies.at(size_t(which[k]));
    if (b.render && b.render->rigidFollow)
      candidates.push_back(
          {k, &*b.render->rigidFollow, world.positions(b.handle).topRows(b.cageVertexCount)});
  }
  std::vector<char> followed(which.size(), 0);
  parallelFor(static_cast<int>(candidates.size()), 2, [&](int c) {
    const Candidate& cand = candidates[size_t(c)];
    followed[cand.k] = cand.follow->follow(cand.cage, *outs[cand.k]);
  });
  for (size_t k = 0; k < which.size(); ++k) {
    if (followed[k]) continue;
    const SceneBody& b = bodies.at(size_t(which[k]));
    const ConstPointsRef particles = world.positions(b.handle);
    if (!b.render) {
      *outs.at(k) = particles;
      continue;
    }
    const ConstPointsRef cage = particles.topRows(b.cageVertexCount);
    const cage::Embedding* e = b.render->embedding.get();
    auto g = std::find_if(groups.begin(), groups.end(),
                          [&](const Group& group) { return group.embedding == e; });
    if (g == groups.end()) g = groups.insert(groups.end(), Group{e, {}, {}});
    g->cages.push_back(cage);
    g->outs.push_back(outs.at(k));
  }
  for (const Group& g : groups) g.embedding->deformMany(g.cages, g.outs);
}

bool Scene::renderVerticesStale(int body, bool& currentWhileAsleep) const {
  const bool asleep = world.isSleeping(bodies.at(size_t(body)).handle);
  if (asleep && currentWhileAsleep) return false;
  currentWhileAsleep = asleep;
  return true;
}

const std::vector<std::array<int, 3>>& Scene::renderTriangles(int body) const {
  const SceneBody& b = bodies.at(size_t(body));
  return b.render ? b.render->triangles : b.cageTriangles;
}

bool isShippedScene(const std::string& path) {
  if (path.empty()) return false;
  std::error_code ec;
  const fs::path folder = fs::weakly_canonical(fs::path(SOFTBODY_ASSET_DIR) / "scenes", ec);
  if (ec) return false;
  const fs::path file = fs::weakly_canonical(fs::absolute(path, ec), ec);
  return !ec && file.parent_path() == folder;
}

Mat3 eulerDegrees(const Vec3& degrees) {
  const Vec3 r = degrees * (M_PI / 180.0);
  return (Eigen::AngleAxisd(r.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(r.y(), Vec3::UnitY()) *
          Eigen::AngleAxisd(r.x(), Vec3::UnitX()))
      .toRotationMatrix();
}

std::string resolveScenePath(const std::string& baseDir, const std::string& path) {
  const fs::path p(path);
  return p.is_absolute() || baseDir.empty() ? path : (fs::path(baseDir) / p).string();
}

std::string defaultScenePath() {
  return std::string(SOFTBODY_ASSET_DIR) + "/scenes/default.json";
}

}  // namespace sb
