// The Python module `softbody` (pybind11): worlds, bodies, colliders, drags, scenes with their
// render meshes, binding meshes to cages, and the take exports. What Python users rely on:
//
// - Arrays come back as NumPy views of the simulation's own memory, without copies
//   (np.shares_memory holds): World.positions / velocities / rest_positions and
//   Scene.render_vertices are read-only float32 (N, 3) views (column-major for the World's
//   arrays, row-major for render vertices). They show the current values after every step and
//   stay valid until the body they belong to is removed or its clusters are rebuilt; both are
//   refused with a RuntimeError while a view of that body is alive (del it or copy it with
//   np.array(view) first), so a stale view can never read freed memory. A view keeps its world
//   (or scene) alive.
// - step() releases the GIL: other Python threads run while the world steps. A world is not
//   for two threads at once: any call on a world that is stepping in another thread raises
//   RuntimeError instead of racing.
// - Errors from C++ arrive with the same messages: ValueError for bad values and shapes (the
//   field and the reason), softbody.SceneError (a ValueError) for scene files, softbody.FileError
//   (an OSError) for files that cannot be read or written.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "sim/base/parallel.h"
#include "sim/cage/bind.h"
#include "sim/cage/embedding.h"
#include "sim/mesh/closed_surface.h"
#include "sim/mesh/mesh_io.h"
#include "sim/scene/frame_export.h"
#include "sim/scene/gltf_take.h"
#include "sim/scene/point_cache.h"
#include "sim/scene/scene.h"
#include "sim/scene/scene_runner.h"
#include "sim/world/world.h"

namespace py = pybind11;
using namespace py::literals;

namespace sb::python {
namespace {

using BodyKey = std::pair<std::uint32_t, std::uint32_t>;  // handle index, generation
BodyKey keyOf(BodyHandle h) {
  return {h.index, h.generation};
}

// A World as Python holds it: owned, or a scene's (then the scene owns it and `scene` keeps
// the owner alive for views). Counts the live NumPy views per body.
struct PyWorld : std::enable_shared_from_this<PyWorld> {
  std::unique_ptr<World> owned;
  World* world = nullptr;
  std::weak_ptr<void> scene;  // the PyScene that owns `world`, if any
  std::map<BodyKey, int> liveViews;
  std::atomic<bool> stepping{false};

  World& get() {
    if (stepping.load())
      throw std::runtime_error(
          "the world is stepping in another thread; wait for step() to return");
    return *world;
  }
  std::shared_ptr<void> owner() {
    if (auto s = scene.lock()) return s;
    return shared_from_this();
  }
  void refuseIfViewed(BodyHandle h, const char* what) {
    const auto it = liveViews.find(keyOf(h));
    if (it != liveViews.end() && it->second > 0)
      throw std::runtime_error(std::string(what) + ": " + std::to_string(it->second) +
                               " NumPy view(s) of body '" + world->name(h) +
                               "' are still alive and would point at freed memory; delete "
                               "them (del) or copy them (np.array(view)) first");
  }
};

// What a view's capsule holds: the owner kept alive, and the count to give back.
struct ViewKeeper {
  std::shared_ptr<void> owner;
  PyWorld* world = nullptr;  // null for scene render vertices (never invalidated)
  BodyKey body{};
};

// A read-only float32 (rows, 3) NumPy view of memory at `data` with the given strides (bytes).
py::array readOnlyView(const float* data, Eigen::Index rows, py::ssize_t rowStride,
                       py::ssize_t columnStride, ViewKeeper* keeper) {
  py::capsule base(keeper, [](void* p) {
    auto* k = static_cast<ViewKeeper*>(p);
    if (k->world != nullptr) --k->world->liveViews[k->body];
    delete k;
  });
  py::array view(py::dtype::of<float>(), {py::ssize_t(rows), py::ssize_t(3)},
                 {rowStride, columnStride}, data, base);
  view.attr("setflags")("write"_a = false);
  return view;
}

py::array worldView(PyWorld& w, BodyHandle h, ConstPointsRef points) {
  auto* keeper = new ViewKeeper{w.owner(), &w, keyOf(h)};
  ++w.liveViews[keyOf(h)];
  return readOnlyView(points.data(), points.rows(), sizeof(float),
                      py::ssize_t(sizeof(float)) * points.outerStride(), keeper);
}

// Any array-like of shape (rows, 3) as doubles; ValueError naming the argument and the shape.
Eigen::MatrixX3d pointsArgument(const py::handle& value, Eigen::Index rows, const char* name) {
  const auto a = py::array_t<double, py::array::forcecast | py::array::c_style>::ensure(value);
  if (!a) throw py::value_error(std::string(name) + " must be a numeric array");
  if (a.ndim() != 2 || a.shape(1) != 3 || (rows >= 0 && a.shape(0) != rows)) {
    std::ostringstream s;
    s << name << " must have shape (" << (rows >= 0 ? std::to_string(rows) : "N") << ", 3), got (";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
    s << (a.ndim() == 1 ? ",)" : ")");
    throw py::value_error(s.str());
  }
  Eigen::MatrixX3d m(a.shape(0), 3);
  const auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    for (int c = 0; c < 3; ++c) m(i, c) = r(i, c);
  return m;
}

std::vector<Vec3> vec3List(const Eigen::MatrixX3d& m) {
  std::vector<Vec3> out(size_t(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) out[size_t(i)] = m.row(i).transpose();
  return out;
}

std::vector<std::array<int, 3>> trianglesArgument(const py::handle& value, const char* name) {
  const auto a = py::array_t<long long, py::array::forcecast | py::array::c_style>::ensure(value);
  if (!a || a.ndim() != 2 || a.shape(1) != 3)
    throw py::value_error(std::string(name) + " must be an integer array of shape (T, 3)");
  std::vector<std::array<int, 3>> out(size_t(a.shape(0)));
  const auto r = a.unchecked<2>();
  for (py::ssize_t t = 0; t < a.shape(0); ++t)
    for (int c = 0; c < 3; ++c) {
      if (r(t, c) < 0 || r(t, c) > (1ll << 30))
        throw py::value_error(std::string(name) + "[" + std::to_string(t) + "]: index " +
                              std::to_string(r(t, c)) + " out of range");
      out[size_t(t)][size_t(c)] = int(r(t, c));
    }
  return out;
}

py::array_t<int> trianglesArray(const std::vector<std::array<int, 3>>& tris) {
  py::array_t<int> a({py::ssize_t(tris.size()), py::ssize_t(3)});
  auto w = a.mutable_unchecked<2>();
  for (size_t t = 0; t < tris.size(); ++t)
    for (int c = 0; c < 3; ++c) w(py::ssize_t(t), c) = tris[t][size_t(c)];
  return a;
}

// Runs `n` steps with the GIL released, refusing a second concurrent stepper.
template <typename StepOnce>
void stepReleased(PyWorld& w, int n, StepOnce&& once) {
  if (n < 0) throw py::value_error("n must be ≥ 0, got " + std::to_string(n));
  if (w.stepping.exchange(true))
    throw std::runtime_error("the world is already stepping in another thread");
  struct Clear {
    std::atomic<bool>& flag;
    ~Clear() { flag.store(false); }
  } clear{w.stepping};
  py::gil_scoped_release release;
  for (int i = 0; i < n; ++i) once();
}

// A scene with its render meshes following the bodies (SceneRunner).
struct PyScene : std::enable_shared_from_this<PyScene> {
  Scene scene;
  std::unique_ptr<SceneRunner> runner;
  std::shared_ptr<PyWorld> world;
  void check(int body) const {
    if (body < 0 || body >= int(scene.bodies.size()))
      throw py::index_error("body " + std::to_string(body) + " out of range [0, " +
                            std::to_string(scene.bodies.size()) + ")");
  }
};

std::shared_ptr<PyScene> openScene(const std::string& path) {
  auto s = std::make_shared<PyScene>();
  s->scene = loadScene(path);
  s->runner = std::make_unique<SceneRunner>(s->scene, /*deform=*/true);
  s->world = std::make_shared<PyWorld>();
  s->world->world = &s->scene.world;
  s->world->scene = s;
  return s;
}

}  // namespace
}  // namespace sb::python

PYBIND11_MODULE(softbody, m) {
  using namespace sb;
  using namespace sb::python;
  m.doc() =
      "softbody: real-time soft bodies by shape matching (Müller et al. 2005), with detailed "
      "meshes following through cage coordinates. Units are SI (metres, seconds, kilograms). "
      "Arrays from the simulation are read-only zero-copy float32 (N, 3) NumPy views; see "
      "World.positions.";

  static py::exception<SceneError> sceneError(m, "SceneError", PyExc_ValueError);
  static py::exception<FileError> fileError(m, "FileError", PyExc_OSError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const SceneError& e) {
      sceneError(e.what());
    } catch (const FileError& e) {
      fileError(e.what());
    } catch (const FrameError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const mesh::MeshError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const mesh::SurfaceError& e) {  // an open, non-manifold or inverted cage
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  m.def("set_thread_count", &setThreadCount, "threads"_a,
        "Threads every world steps with (0: all cores). Results are bit-identical at any count.");
  m.def("thread_count", &threadCount, "Threads the worlds step with.");

  py::enum_<Mode>(m, "Mode", "How a cluster's goal follows its particles.")
      .value("RIGID", Mode::Rigid)
      .value("LINEAR", Mode::Linear)
      .value("QUADRATIC", Mode::Quadratic);

  py::class_<WorldSettings>(m, "WorldSettings",
                            "World-wide settings; ranges are checked by World.settings = ...")
      .def(py::init<>())
      .def_readwrite("gravity", &WorldSettings::gravity, "m/s², (3,)")
      .def_readwrite("time_step", &WorldSettings::timeStep, "s per step(), [1e-7, 10]")
      .def_readwrite("substeps", &WorldSettings::substeps, "sub-steps per step(), [1, 1000]")
      .def_readwrite("max_substep", &WorldSettings::maxSubstep, "longest sub-step, s, [1e-4, 1]")
      .def_readwrite("body_contact", &WorldSettings::bodyContact)
      .def_readwrite("contact_friction", &WorldSettings::contactFriction, "μ, [0, 1000]")
      .def_readwrite("restitution_threshold", &WorldSettings::restitutionThreshold, "m/s")
      .def_readwrite("rolling_resistance", &WorldSettings::rollingResistance, "[0, 1]")
      .def_readwrite("sleep", &WorldSettings::sleep, "bodies at rest sleep");

  py::class_<PlasticityParams>(m, "PlasticityParams")
      .def(py::init<>())
      .def_readwrite("yield_", &PlasticityParams::yield, "c_yield, ≥ 0")
      .def_readwrite("creep", &PlasticityParams::creep, "c_creep, 1/s, ≥ 0 (0: off)")
      .def_readwrite("max", &PlasticityParams::max, "c_max, [0, 2]");

  py::class_<BodyParams>(m, "BodyParams", "Material of a body; may change while it runs.")
      .def(py::init<>())
      .def_readwrite("mode", &BodyParams::mode)
      .def_readwrite("alpha", &BodyParams::alpha, "stiffness α, [0, 1] per 1/240 s sub-step")
      .def_readwrite("beta", &BodyParams::beta, "β, [0, 1]: rotation (0) to linear/quadratic fit")
      .def_readwrite("preserve_volume", &BodyParams::preserveVolume)
      .def_readwrite("damping", &BodyParams::damping, "[0, 1] per 1/240 s sub-step")
      .def_readwrite("restitution", &BodyParams::restitution, "e, [0, 1]")
      .def_readwrite("plasticity", &BodyParams::plasticity);

  py::class_<ClusterDef> clusterDef(m, "ClusterDef", "How a body's particles form clusters.");
  py::enum_<ClusterDef::Kind>(clusterDef, "Kind")
      .value("SINGLE", ClusterDef::Kind::Single)
      .value("GRID", ClusterDef::Kind::Grid)
      .value("EXPLICIT", ClusterDef::Kind::Explicit);
  clusterDef.def(py::init<>())
      .def_readwrite("kind", &ClusterDef::kind)
      .def_readwrite("cell_size", &ClusterDef::cellSize, "m, grid cells")
      .def_readwrite("overlap", &ClusterDef::overlap, "m, grid cells")
      .def_readwrite("clusters", &ClusterDef::clusters, "explicit: particle index lists");

  py::class_<BodyDef>(m, "BodyDef", "Everything needed to create a body (world space, SI).")
      .def(py::init<>())
      .def_readwrite("name", &BodyDef::name)
      .def_property(
          "positions",
          [](const BodyDef& d) {
            Eigen::MatrixX3d out(Eigen::Index(d.positions.size()), 3);
            for (size_t i = 0; i < d.positions.size(); ++i)
              out.row(Eigen::Index(i)) = d.positions[i].transpose();
            return out;
          },
          [](BodyDef& d, const py::object& v) {
            d.positions = vec3List(pointsArgument(v, -1, "positions"));
          },
          "particle rest positions, m, (P, 3)")
      .def_readwrite("masses", &BodyDef::masses, "kg per particle, or empty")
      .def_readwrite("total_mass", &BodyDef::totalMass, "kg, when masses is empty")
      .def_readwrite("velocity", &BodyDef::velocity, "m/s, (3,)")
      .def_readwrite("pinned", &BodyDef::pinned, "particle indices held in place")
      .def_property(
          "surface", [](const BodyDef& d) { return trianglesArray(d.surface); },
          [](BodyDef& d, const py::object& v) { d.surface = trianglesArgument(v, "surface"); },
          "closed outward surface for contact, particle indices (T, 3)")
      .def_readwrite("clusters", &BodyDef::clusters)
      .def_readwrite("params", &BodyDef::params);

  py::class_<Collider>(m, "Collider", "A static collider with friction μ and restitution e.")
      .def_static("plane", &Collider::plane, "normal"_a, "offset"_a, "friction"_a = 0.5)
      .def_static("box", &Collider::box, "centre"_a, "half_extents"_a,
                  "rotation"_a = Mat3::Identity().eval(), "friction"_a = 0.5)
      .def_static("sphere", &Collider::sphere, "centre"_a, "radius"_a, "friction"_a = 0.5)
      .def_static("capsule", &Collider::capsule, "a"_a, "b"_a, "radius"_a, "friction"_a = 0.5)
      .def_readwrite("friction", &Collider::friction)
      .def_readwrite("restitution", &Collider::restitution)
      .def_property_readonly(
          "shape", [](const Collider& c) { return std::string(colliderShapeName(c.shape)); });

  py::class_<BodyHandle>(m, "Body", "A body of a world; invalid once the body is removed.")
      .def("__eq__", &BodyHandle::operator==)
      .def("__hash__",
           [](const BodyHandle& h) { return (std::size_t(h.index) << 32) ^ h.generation; })
      .def("__repr__", [](const BodyHandle& h) {
        return "<softbody.Body " + std::to_string(h.index) + "/" + std::to_string(h.generation) +
               ">";
      });

  py::class_<PyWorld, std::shared_ptr<PyWorld>>(m, "World", "Owns bodies and colliders; steps.")
      .def(py::init([](const WorldSettings& s) {
             auto w = std::make_shared<PyWorld>();
             w->owned = std::make_unique<World>(s);
             w->world = w->owned.get();
             return w;
           }),
           "settings"_a = WorldSettings{})
      .def_property(
          "settings", [](PyWorld& w) { return w.get().settings(); },
          [](PyWorld& w, const WorldSettings& s) { w.get().setSettings(s); },
          "a copy; assign a changed WorldSettings to apply it (ValueError when out of range)")
      .def(
          "add_collider", [](PyWorld& w, const Collider& c) { w.get().addCollider(c); },
          "collider"_a, "Adds a static collider; wakes sleeping bodies.")
      .def(
          "clear_colliders", [](PyWorld& w) { w.get().clearColliders(); },
          "Removes every collider.")
      .def(
          "add_body",
          [](PyWorld& w, const BodyDef& d) {
            if (!w.scene.expired())
              throw std::runtime_error(
                  "a scene's bodies come from its file: add bodies to a World of your own");
            return w.get().addBody(d);
          },
          "definition"_a, "Creates a body; ValueError naming the field when invalid.")
      .def(
          "remove_body",
          [](PyWorld& w, BodyHandle h) {
            if (!w.scene.expired())
              throw std::runtime_error("a scene's bodies cannot be removed through its world");
            w.get();
            w.refuseIfViewed(h, "remove_body");
            w.world->removeBody(h);
            w.liveViews.erase(keyOf(h));
          },
          "body"_a,
          "Removes a body; RuntimeError while NumPy views of it are alive (they would point at "
          "freed memory).")
      .def(
          "bodies", [](PyWorld& w) { return w.get().bodies(); }, "The bodies in creation order.")
      .def(
          "contains", [](PyWorld& w, BodyHandle h) { return w.get().contains(h); }, "body"_a,
          "Whether the body is still in the world.")
      .def(
          "name", [](PyWorld& w, BodyHandle h) { return w.get().name(h); }, "body"_a)
      .def(
          "params", [](PyWorld& w, BodyHandle h) { return w.get().params(h); }, "body"_a,
          "A copy of the body's BodyParams; change it and pass it to set_params.")
      .def(
          "set_params",
          [](PyWorld& w, BodyHandle h, const BodyParams& p) { w.get().setParams(h, p); }, "body"_a,
          "params"_a, "Applies new material parameters (ValueError naming the field).")
      .def(
          "set_clusters",
          [](PyWorld& w, BodyHandle h, const ClusterDef& c) {
            w.get();
            w.refuseIfViewed(h, "set_clusters");
            w.world->setClusters(h, c);
          },
          "body"_a, "clusters"_a,
          "Rebuilds the body's clusters (plasticity cleared); refused while views of it live.")
      .def(
          "cluster_count", [](PyWorld& w, BodyHandle h) { return w.get().clusterCount(h); },
          "body"_a)
      .def(
          "particle_count", [](PyWorld& w, BodyHandle h) { return w.get().particleCount(h); },
          "body"_a)
      .def(
          "positions",
          [](PyWorld& w, BodyHandle h) { return worldView(w, h, w.get().positions(h)); }, "body"_a,
          "Read-only zero-copy view of the particle positions, m, float32 (P, 3).")
      .def(
          "velocities",
          [](PyWorld& w, BodyHandle h) { return worldView(w, h, w.get().velocities(h)); }, "body"_a,
          "Read-only zero-copy view of the velocities, m/s, float32 (P, 3).")
      .def(
          "rest_positions",
          [](PyWorld& w, BodyHandle h) { return worldView(w, h, w.get().restPositions(h)); },
          "body"_a, "Read-only zero-copy view of the start positions, m, float32 (P, 3).")
      .def(
          "goals", [](PyWorld& w, BodyHandle h) { return w.get().goals(h); }, "body"_a,
          "The goal positions of the last step (P, 3), float64: a copy (they are formed on "
          "demand).")
      .def(
          "masses", [](PyWorld& w, BodyHandle h) { return w.get().masses(h); }, "body"_a,
          "kg per particle, float32 (P,) (a copy)")
      .def(
          "mass", [](PyWorld& w, BodyHandle h) { return w.get().mass(h); }, "body"_a, "kg")
      .def(
          "centre_of_mass", [](PyWorld& w, BodyHandle h) { return w.get().centreOfMass(h); },
          "body"_a, "m, (3,)")
      .def(
          "set_state",
          [](PyWorld& w, BodyHandle h, const py::object& x, const py::object& v) {
            World& world = w.get();
            const Eigen::Index p = world.particleCount(h);
            // One after the other: the message names the first bad argument.
            const Eigen::MatrixX3d positions = pointsArgument(x, p, "positions");
            const Eigen::MatrixX3d velocities = pointsArgument(v, p, "velocities");
            world.setState(h, positions, velocities);
          },
          "body"_a, "positions"_a, "velocities"_a,
          "Overwrites positions (m) and velocities (m/s), any numeric arrays of shape (P, 3).")
      .def(
          "add_force",
          [](PyWorld& w, BodyHandle h, int particle, const Vec3& f) {
            w.get().addForce(h, particle, f);
          },
          "body"_a, "particle"_a, "force"_a, "A force (N, (3,)) on one particle for the next step.")
      .def(
          "add_drag",
          [](PyWorld& w, BodyHandle h, std::vector<int> particles, std::vector<double> weights,
             const Vec3& target, double stiffness) {
            return w.get().addDrag(
                DragDef{h, std::move(particles), std::move(weights), target, stiffness});
          },
          "body"_a, "particles"_a, "weights"_a, "target"_a, "stiffness"_a = 0.2,
          "Pulls the point Σ wⱼ xⱼ of the listed particles toward target (m) by the fraction "
          "stiffness (0, 1] of the gap per step, as the viewer's mouse drag; returns its id.")
      .def(
          "set_drag_target",
          [](PyWorld& w, int id, const Vec3& t) { w.get().setDragTarget(id, t); }, "id"_a,
          "target"_a)
      .def(
          "remove_drag", [](PyWorld& w, int id) { w.get().removeDrag(id); }, "id"_a)
      .def(
          "step",
          [](PyWorld& w, int n) {
            World* world = w.world;
            stepReleased(w, n, [world] { world->step(); });
          },
          "n"_a = 1,
          "Advances n steps of settings.time_step. Releases the GIL; views show the new state "
          "after it returns.")
      .def(
          "reset", [](PyWorld& w) { w.get().reset(); },
          "Every body back to its start state; plasticity and drags cleared; time 0.")
      .def_property_readonly(
          "time", [](PyWorld& w) { return w.get().time(); }, "s simulated")
      .def(
          "is_sleeping", [](PyWorld& w, BodyHandle h) { return w.get().isSleeping(h); }, "body"_a)
      .def(
          "wake", [](PyWorld& w, BodyHandle h) { w.get().wake(h); }, "body"_a,
          "Wakes the body and every body that fell asleep with it.")
      .def(
          "take_events",
          [](PyWorld& w) {
            std::vector<std::string> out;
            for (const WorldEvent& e : w.get().takeEvents()) out.push_back(e.message);
            return out;
          },
          "Messages of what happened since the last call (a body that went NaN was reset, …).")
      .def(
          "state_hash", [](PyWorld& w) { return w.get().stateHash(); },
          "64-bit hash of positions, velocities and plastic state (as `softbody run` prints)");

  py::class_<PyScene, std::shared_ptr<PyScene>>(
      m, "Scene", "A scene file's world plus the render meshes that follow its bodies.")
      .def_property_readonly(
          "world", [](PyScene& s) { return s.world; }, py::keep_alive<0, 1>())
      .def_property_readonly("path", [](PyScene& s) { return s.scene.path; })
      .def_property_readonly("body_count", [](PyScene& s) { return int(s.scene.bodies.size()); })
      .def(
          "body",
          [](PyScene& s, int i) {
            s.check(i);
            return s.scene.bodies[size_t(i)].handle;
          },
          "index"_a)
      .def(
          "step",
          [](PyScene& s, int n) {
            SceneRunner* runner = s.runner.get();
            stepReleased(*s.world, n, [runner] { runner->step(); });
          },
          "n"_a = 1, "Steps the world and deforms every render mesh; releases the GIL.")
      .def(
          "render_vertices",
          [](PyScene& s, int i) {
            s.world->get();
            s.check(i);
            const PointsRowMajor& v = s.runner->renderMeshes()[size_t(i)];
            auto* keeper = new ViewKeeper{s.shared_from_this(), nullptr, {}};
            return readOnlyView(v.data(), v.rows(), 3 * sizeof(float), sizeof(float), keeper);
          },
          "index"_a,
          "Read-only zero-copy view of body i's render-mesh vertices after the last Scene.step "
          "(the particles for a body without a render mesh), m, float32 (V, 3), row-major.")
      .def(
          "render_triangles",
          [](PyScene& s, int i) {
            s.check(i);
            return trianglesArray(s.scene.renderTriangles(i));
          },
          "index"_a, "Body i's render triangles, vertex indices (T, 3) int32 (a copy).")
      .def(
          "save", [](PyScene& s, const std::string& path) { saveScene(s.scene, path); }, "path"_a,
          "Writes the scene file (settings and parameters as they are now), atomically.");

  m.def("load_scene", &openScene, "path"_a,
        "Loads a scene file; SceneError names the file, field and reason.");

  py::enum_<PointCacheFormat>(m, "PointCacheFormat")
      .value("PC2", PointCacheFormat::Pc2)
      .value("MDD", PointCacheFormat::Mdd);

  // A point cache of a scene's render meshes (all bodies in scene order), as `softbody run
  // --export-pc2/--export-mdd`.
  py::class_<PointCacheWriter>(m, "PointCache",
                               "A PC2 or MDD point cache, written frame by frame and published "
                               "whole by finish() (nothing appears before).")
      .def(py::init([](PyScene& s, const std::string& path, PointCacheFormat format, int frames,
                       double frameInterval) {
             long long points = 0;
             for (const PointsRowMajor& v : s.runner->renderMeshes()) points += v.rows();
             return std::make_unique<PointCacheWriter>(path, format, int(points), frames,
                                                       s.scene.world.time(), frameInterval);
           }),
           "scene"_a, "path"_a, "format"_a, "frames"_a, "frame_interval"_a)
      .def(
          "add_frame",
          [](PointCacheWriter& c, PyScene& s) {
            s.world->get();  // not while it steps in another thread
            c.addFrame(s.runner->renderMeshes());
          },
          "scene"_a, "Appends the scene's render meshes as they are now.")
      .def("finish", &PointCacheWriter::finish,
           "Publishes the cache; RuntimeError when frames are missing (nothing is written).");

  py::class_<GltfTakeWriter>(m, "GltfTake",
                             "A glTF 2.0 binary take of a scene's render meshes (morph "
                             "targets), written frame by frame, published by finish().")
      .def(py::init([](PyScene& s, const std::string& path, int frames, double frameInterval) {
             std::vector<int> counts;
             for (const PointsRowMajor& v : s.runner->renderMeshes())
               counts.push_back(int(v.rows()));
             return std::make_unique<GltfTakeWriter>(path, s.scene, counts, frames, frameInterval);
           }),
           "scene"_a, "path"_a, "frames"_a, "frame_interval"_a)
      .def(
          "add_frame",
          [](GltfTakeWriter& g, PyScene& s) {
            s.world->get();  // not while it steps in another thread
            g.addFrame(s.runner->renderMeshes());
          },
          "scene"_a, "Appends the scene's render meshes as they are now.")
      .def("finish", &GltfTakeWriter::finish,
           "Publishes the take; RuntimeError when frames are missing (nothing is written).");

  m.def(
      "write_render_obj",
      [](PyScene& s, const std::string& path, bool oneObject) {
        s.world->get();  // not while it steps in another thread
        writeRenderMeshesObj(s.scene, s.runner->renderMeshes(), path,
                             oneObject ? ObjObjects::One : ObjObjects::PerBody);
      },
      "scene"_a, "path"_a, "one_object"_a = false,
      "Writes the render meshes as OBJ: an object per body, or one object (the mesh a point "
      "cache moves).");

  m.def(
      "read_mesh",
      [](const std::string& path) {
        const mesh::TriangleMesh t = mesh::readMesh(path);
        Eigen::MatrixX3d v(Eigen::Index(t.vertices.size()), 3);
        for (size_t i = 0; i < t.vertices.size(); ++i) v.row(Eigen::Index(i)) = t.vertices[i];
        return py::make_tuple(v, trianglesArray(t.triangles));
      },
      "path"_a, "Reads OBJ, OFF, PLY or STL: (vertices (V, 3) float64, triangles (T, 3) int32).");

  py::class_<cage::Embedding>(m, "Embedding",
                              "A mesh bound to a cage: mesh = W · cage (mean value, harmonic or "
                              "RBF coordinates).")
      .def_property_readonly("mesh_vertex_count", &cage::Embedding::meshVertexCount)
      .def_property_readonly(
          "method", [](const cage::Embedding& e) { return cage::embeddingKindName(e.kind()); },
          "'mvc', 'harmonic' or 'rbf'")
      .def_property_readonly("cage_vertex_count", &cage::Embedding::cageVertexCount)
      .def(
          "deform",
          [](const cage::Embedding& e, const py::object& cagePositions) {
            const Eigen::MatrixX3d c =
                pointsArgument(cagePositions, e.cageVertexCount(), "cage_positions");
            const Eigen::Matrix<float, Eigen::Dynamic, 3> cf = c.cast<float>();
            PointsRowMajor out;
            e.deform(cf, out);
            return out;
          },
          "cage_positions"_a, "Mesh positions (V, 3) float32 for cage positions (C, 3).");
  m.def(
      "bind",
      [](const py::object& points, const py::object& cageVertices, const py::object& cageTriangles,
         const std::string& method, int resolution, double shape) {
        cage::EmbeddingMethod how;
        if (!cage::parseEmbeddingKind(method, &how.kind) ||
            how.kind == cage::EmbeddingKind::FfdBernstein ||
            how.kind == cage::EmbeddingKind::FfdBSpline)
          throw py::value_error("method must be 'mvc', 'harmonic', 'rbf' or 'green', got '" +
                                method + "'");
        if (resolution < 4 || resolution > 64)  // ~5 s at 64 (harmonic.h)
          throw py::value_error("resolution must be in [4, 64], got " + std::to_string(resolution));
        how.harmonic.resolution = resolution;
        how.rbf.shape = shape;  // bindRbf checks its range
        mesh::TriangleMesh cageMesh;
        cageMesh.vertices = vec3List(pointsArgument(cageVertices, -1, "cage_vertices"));
        cageMesh.triangles = trianglesArgument(cageTriangles, "cage_triangles");
        const std::vector<Vec3> p = vec3List(pointsArgument(points, -1, "points"));
        py::gil_scoped_release release;
        return cage::bindToCage(p, cageMesh, how);
      },
      "points"_a, "cage_vertices"_a, "cage_triangles"_a, "method"_a = "mvc",
      "resolution"_a = cage::HarmonicOptions{}.resolution, "shape"_a = cage::RbfOptions{}.shape,
      "Coordinates of points (V, 3) in a closed cage: method 'mvc' (mean value), 'harmonic' "
      "(grid of `resolution` cells along the cage's longest side, in [4, 64]), 'rbf' "
      "(multiquadric, shape in [0, 10]) or 'green' (Green coordinates, shape-preserving; "
      "every point inside the cage); deform takes the cage's vertices for every method. "
      "ValueError for an open or inverted cage, a point outside the cage (green) or a bad "
      "option.");
}
