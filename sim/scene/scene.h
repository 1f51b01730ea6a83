// Scene files (JSON) <-> a World plus the render meshes that follow its bodies.
//
// A scene file names world settings, static colliders and bodies. Each body's particles are
// the vertices of a mesh file (normally a coarse closed cage); optionally a detailed render
// mesh is bound to that cage (mean value, harmonic or RBF coordinates) and follows the particles.
// The format is documented in assets/scenes/README.md.
#pragma once

#include <array>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sim/cage/auto_cage.h"
#include "sim/cage/bind.h"
#include "sim/cage/ffd_lattice.h"
#include "sim/cage/rigid_follow.h"
#include "sim/world/world.h"

namespace sb {

namespace cage {
class Embedding;
}

// Invalid scene input. what() reads "FILE: FIELD: REASON", e.g.
// "scenes/x.json: bodies[1].alpha: must be in [0, 1], got 3".
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A detailed mesh that follows a body's particles (the cage) through a weight matrix.
struct RenderMesh {
  std::string path;                                  // as written in the scene file
  std::vector<std::array<int, 3>> triangles;         // indices into the mesh vertices
  std::shared_ptr<const cage::Embedding> embedding;  // #mesh vertices × #particles
  // Moves the rest mesh instead of applying the weights when a body's cage moved as a whole
  // (sim/cage/rigid_follow.h); none when the embedding does not reproduce its rest mesh.
  std::optional<cage::RigidFollow> rigidFollow;
};

// Sets render.rigidFollow from the mesh's and the cage's vertices the embedding was bound to
// (the same frame).
void prepareRigidFollow(RenderMesh& render, const std::vector<Vec3>& meshVertices,
                        const std::vector<Vec3>& cageVertices);

// "cage": {"auto": true, ...}: the particles are an automatic cage of the render mesh
// (sim/cage/auto_cage.h), made on load and cached (sim/cage/cage_cache.h).
struct AutoCageSettings {
  int vertices = cage::CageOptions{}.vertexBudget;   // most cage vertices, [4, 100000]
  double tightness = cage::CageOptions{}.tightness;  // [0, 1], CageOptions::tightness
};

// "lattice": {"nodes": [l, m, n], "basis": "bernstein" | "bspline", "margin": m}: the body is a
// free-form deformation lattice around its render mesh (sim/cage/ffd_lattice.h): the lattice's
// nodes are the particles, its outer layer the contact surface, and the render mesh follows the
// nodes with the lattice's weights — any mesh, no cage. Bernstein by default: its outer nodes
// lie on the mesh's (grown) bounding box, so the body touches things there; a B-spline
// lattice's outer nodes lie a spacing outside the box, and so does its contact surface.
struct LatticeSettings {
  std::array<int, 3> nodes{4, 4, 4};  // per axis, [2, 64]: bernstein ≤ 32, bspline ≥ 4
  cage::FfdBasis basis = cage::FfdBasis::Bernstein;
  double margin = 0.01;  // the box: the mesh's bounding box grown by margin × its diagonal, [0, 1]
};

// The "embedding" options a scene file accepts (assets/scenes/README.md): the parser's ranges,
// and those of a binding the viewer makes, so that it saves to a file that loads again. The cage
// library itself takes more (any harmonic resolution ≥ 4).
inline constexpr int kSceneHarmonicResolutionMin = 4, kSceneHarmonicResolutionMax = 64;  // cells
inline constexpr double kSceneRbfShapeMin = 0.0, kSceneRbfShapeMax = 10.0;  // nearest-handle units

struct SceneBody {
  BodyHandle handle;
  // Particles = this mesh's vertices (as written in the file); empty with an automatic cage.
  std::string meshPath;
  std::optional<AutoCageSettings> autoCage;
  std::optional<LatticeSettings> lattice;
  // With a lattice: the lattice in the render mesh file's coordinates (its nodes, placed like
  // every body's vertices, are the particles).
  std::optional<cage::FfdLattice> latticeFrame;
  // "clusters": {"kind": "lattice", "halfWidth": w} on a lattice body: one cluster per node, the
  // nodes within w steps of it (FfdLattice::regions, FastLSM's lattice shape matching), given
  // to the World as explicit clusters; 0 for any other clusters.
  int latticeRegionHalfWidth = 0;
  // "interior": {"spacing": s}: lattice particles s metres apart inside the cage follow its
  // vertices (sim/cage/interior_points.h); 0 = none. The particles are the cage's vertices
  // first, then the interior ones; the render mesh follows the first cageVertexCount.
  double interiorSpacing = 0.0;
  int cageVertexCount = 0;
  std::vector<std::array<int, 3>> cageTriangles;  // the particle mesh's faces (may be empty)
  // The polygon of each cage triangle when the cage file had faces of more than 3 corners
  // (mesh::TriangleMesh::polygonOf; empty otherwise): re-binds use polygon coordinates as the
  // load did.
  std::vector<int> cagePolygonOf;
  std::shared_ptr<RenderMesh> render;  // null when the body has no render mesh
  // "embedding": how the render mesh follows the cage: "mvc" (the default), "harmonic", "rbf" or
  // "green" (the render mesh must lie inside the cage), or an object {"method": …,
  // "resolution": n (harmonic), "shape": s (rbf)} (sim/cage/bind.h).
  cage::EmbeddingMethod embedding;
  // The transform and scale applied to the file's vertices, kept so the scene can be saved.
  Vec3 translation = Vec3::Zero();
  Vec3 rotationDegrees = Vec3::Zero();  // XYZ Euler angles, degrees
  double scale = 1.0;
  double totalMass = 1.0;
  Vec3 velocity = Vec3::Zero();  // initial velocity of every particle, m/s
  std::vector<int> pinned;       // particle indices held in place, as written in the file
  bool contact = true;           // the cage is the body's surface for body–body contact
};

// The order of the keys in the file a scene came from, per kind of object: "" the top level,
// "world", "colliders[]", "bodies[]", "bodies[].clusters", … (array indices dropped), each in
// first-seen order. Saving writes an object's keys in this order first, then the keys the file
// did not have in the shipped scenes' order, so a saved file reads like the one it came from.
using SceneKeyOrder = std::map<std::string, std::vector<std::string>>;

struct Scene {
  std::string path;  // the file it was loaded from, or empty
  // The folder its relative mesh paths (SceneBody::meshPath, RenderMesh::path) are written
  // against: the scene file's (loadScene) or parseScene's baseDir; empty: the working folder.
  std::string meshFolder;
  SceneKeyOrder keyOrder;  // of that file (empty: the shipped scenes' order)
  World world;
  std::vector<SceneBody> bodies;  // in file order; handles refer into world

  // Current render-mesh vertices of body i (#V×3 rows): W · particle positions, or, when the
  // cage moved as a whole, the rest mesh moved the same way (RenderMesh::rigidFollow: within
  // 1e-5 of the cage's size of W · positions). Falls back to the particle positions when the
  // body has no render mesh.
  void renderVertices(int body, PointsRowMajor& out) const;
  // renderVertices for several bodies at once (outs[k] for bodies[k], all distinct): bodies
  // whose render meshes share a binding are deformed together (cage::Embedding::deformMany:
  // the weights stream once), each result bit-identical to renderVertices.
  void renderVertices(const std::vector<int>& bodies,
                      const std::vector<PointsRowMajor*>& outs) const;
  // Whether body i's render vertices must be computed again, for a caller that keeps them: not
  // when it sleeps and they were computed since it fell asleep (a sleeping body does not move;
  // anything that moves it wakes it first), so resting scenes cost no deform.
  // `currentWhileAsleep` is the caller's record of that for this body (false at first); it is
  // updated as if the caller computes them when told to.
  bool renderVerticesStale(int body, bool& currentWhileAsleep) const;
  // Triangles to draw for body i: the render mesh's, else the particle mesh's.
  const std::vector<std::array<int, 3>>& renderTriangles(int body) const;
};

// Loads a scene. Relative mesh paths are resolved against the scene file's folder. Throws
// SceneError naming the file, field and reason; nothing is returned half-loaded. Reads only a
// regular file of at most 64 MB (sim/base/file_io.h: folders, FIFOs and devices are refused);
// its meshes are read by sim/mesh/mesh_io.h (512 MB each), bind caches by sim/cage/embedding.h.
Scene loadScene(const std::string& path);
// The rotation of a placement given as Euler angles in degrees (a body's or collider's
// "rotationDegrees", SceneBody::rotationDegrees): about X, then Y, then Z. A body's particles
// are R · (scale · v) + translation for the vertices v of its mesh file.
Mat3 eulerDegrees(const Vec3& degrees);
// A mesh path as written in a scene file, resolved against baseDir (the scene file's folder;
// empty: as written). Absolute paths are returned as they are.
std::string resolveScenePath(const std::string& baseDir, const std::string& path);
// Parses a scene from JSON text; `name` is used in messages and `baseDir` resolves mesh paths
// (it becomes the scene's meshFolder).
// Strict JSON: a key given twice in one object, a number beyond double range or an integer
// index beyond int range is an error naming the line and the field (bodies[2].scale).
Scene parseScene(const std::string& jsonText, const std::string& name, const std::string& baseDir);
// Adds one body to the scene, given as the JSON text of a body object of a scene file (the same
// fields, defaults and checks; relative mesh paths resolved against baseDir, and kept relative
// to the scene's meshFolder). Returns its index in scene.bodies. Throws SceneError ("NAME:
// FIELD: REASON"); the scene is unchanged then.
int addSceneBody(Scene& scene, const std::string& bodyJson, const std::string& name,
                 const std::string& baseDir);
// addSceneBody in two parts, for callers that must not wait for the slow one (the viewer adds a
// dropped mesh while the scene keeps running). prepareSceneBody does what takes time — reads the
// meshes, makes an automatic cage, binds the render mesh — and touches no Scene, so it may run on
// another thread while a scene steps; addPreparedBody then adds the result to a scene (quick).
struct PreparedBody {
  SceneBody body;       // handle not yet valid; mesh paths relative to baseDir
  BodyDef def;          // what the World gets
  std::string name;     // for messages, as given to prepareSceneBody
  std::string baseDir;  // the folder its relative mesh paths were read against
};
// Throws SceneError ("NAME: FIELD: REASON") as addSceneBody.
PreparedBody prepareSceneBody(const std::string& bodyJson, const std::string& name,
                              const std::string& baseDir);
// Adds the body to the scene's World and bodies, its paths made relative to scene.meshFolder.
// Returns its index. Throws SceneError ("NAME: REASON") when the World refuses it; the scene is
// unchanged then.
int addPreparedBody(Scene& scene, PreparedBody prepared);
// Removes body i from the scene and its World; the bodies after it move down one index.
void removeSceneBody(Scene& scene, int body);
// Writes the scene with the world's current settings and body parameters. Atomic: writes a
// temporary file beside the target and renames it. Throws SceneError when it cannot write.
void saveScene(const Scene& scene, const std::string& path);
// The text saveScene writes to `path` (mesh paths relative to path's folder). Two scenes with
// the same text have the same settings and parameters (the state of the bodies is not in it).
std::string sceneText(const Scene& scene, const std::string& path);

// The scene opened when none is given.
std::string defaultScenePath();
// Whether `path` names a file in the folder of the shipped scenes (the viewer saves those only
// when told to, so one click cannot rewrite them). Symlinks and ".." are resolved first.
bool isShippedScene(const std::string& path);

}  // namespace sb
