#include "sim/world/world.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <stdexcept>
#include <type_traits>

#include "sim/mesh/closed_surface.h"
#include "sim/world/body.h"
#include "sim/world/contact_phase.h"
#include "sim/world/external_phase.h"
#include "sim/world/goals_phase.h"
#include "sim/world/integrate_phase.h"
#include "sim/world/mass_properties.h"
#include "sim/world/param_ranges.h"
#include "sim/world/sleep_phase.h"
#include "sim/world/substep_material.h"
#include "sim/world/work_layout.h"

namespace sb {

// Views of a body's arrays (World::positions and the like, handed to Python as NumPy views)
// stay valid while other bodies are added: growing the slot table moves each body's Eigen
// arrays, whose heap buffers stay where they are, instead of copying them.
static_assert(std::is_nothrow_move_constructible_v<BodySlot>);

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

void requireRange(const std::string& field, const ParamRange& range, double v) {
  const std::string violation = rangeViolation(range, v);
  if (!violation.empty()) throw std::invalid_argument(field + ": " + violation);
}

void validateParams(const BodyParams& p) {
  requireRange("alpha", limits::alpha, p.alpha);
  requireRange("beta", limits::beta, p.beta);
  requireRange("damping", limits::damping, p.damping);
  requireRange("restitution", limits::restitution, p.restitution);
  requireRange("plasticity.yield", limits::plasticYield, p.plasticity.yield);
  requireRange("plasticity.creep", limits::plasticCreep, p.plasticity.creep);
  requireRange("plasticity.max", limits::plasticMax, p.plasticity.max);
}

PointColumns columns(const MatX3f& m) {
  return PointColumns{{m.col(0).data(), m.col(1).data(), m.col(2).data()}};
}

}  // namespace

struct World::Data {
  WorldSettings settings;
  std::vector<Collider> colliders;
  std::vector<BodySlot> slots;
  std::vector<int> order;  // alive slots in creation order
  std::vector<int> awake;  // alive slots not asleep, in creation order (what the phases step)
  bool awakeDirty = true;  // a body fell asleep, woke, came or went: rebuild `awake`
  std::map<int, DragDef> drags;
  int nextDragId = 1;
  std::vector<QueuedForce> forces;
  double time = 0;
  StepProfile profile;
  std::vector<WorldEvent> events;
  WorkLayout layout;
  bool layoutDirty = true;  // bodies or clusters changed: the work lists must be rebuilt
  int contactCount = 0;
  ContactWork contactWork;  // summed over the last step()'s sub-steps
  // Scratch of the phases, reused every sub-step (no allocations in the loop).
  GoalsScratch goalsScratch;
  ContactScratch contactScratch;
  SleepScratch sleepScratch;
  std::vector<char> blockBad, bad, held;

  BodySlot& slot(BodyHandle h) {
    if (h.index >= slots.size() || !slots[h.index].alive ||
        slots[h.index].generation != h.generation)
      throw std::invalid_argument("unknown body handle");
    return slots[h.index];
  }
  BodyHandle handleOf(int s) const {
    return BodyHandle{static_cast<std::uint32_t>(s), slots[size_t(s)].generation};
  }

  void substep(double h, StepProfile& prof);
  void resetFailedBodies();
  // Wakes the body in slot s with its island (sleep_phase.h).
  void wake(int s) {
    if (wakeIsland(slots, order, s)) awakeDirty = true;
  }
  void wakeAll() {
    for (int s : order) wake(s);
  }
};

// ---------------------------------------------------------------------------------------------
// One sub-step: the pipeline (docs/design.md §3).

void World::Data::substep(double h, StepProfile& prof) {
  // A drag holds its body awake; bodies an awake body touched in the last sub-step wake.
  held.assign(slots.size(), 0);
  for (const auto& [id, drag] : drags) {
    held[drag.body.index] = 1;
    wake(int(drag.body.index));
  }
  for (int s : contactScratch.wake) wake(s);
  contactScratch.wake.clear();
  if (awakeDirty) {
    awake.clear();
    for (int s : order)
      if (!slots[size_t(s)].sleep.asleep) awake.push_back(s);
    awakeDirty = false;
    layoutDirty = true;
  }
  // Each body's clusters on the path its parameters call for; work lists for those paths.
  for (int s : awake) {
    BodySlot& b = slots[size_t(s)];
    if (b.state.clusters.selectPath(*b.model, b.stepParams)) layoutDirty = true;
  }
  if (layoutDirty) {
    layout = buildWorkLayout(slots, awake);
    layoutDirty = false;
  }
  auto timed = [&](Phase phase, const auto& run) {
    const auto t0 = Clock::now();
    run();
    prof[phase] += secondsSince(t0);
  };
  bad.assign(slots.size(), 0);

  timed(Phase::External, [&] { runExternalPhase(forces, drags, h, slots); });
  timed(Phase::Predict, [&] { runPredictPhase(layout, settings.gravity, h, slots, awake); });
  const GoalsTimes goals = runGoalsPhase(layout, h, slots, goalsScratch, bad);
  prof[Phase::Goals] += goals.goals;
  prof[Phase::Plasticity] += goals.plasticity;
  timed(Phase::Project,
        [&] { runProjectPhase(layout, settings.gravity, h, slots, awake, blockBad, bad); });
  timed(Phase::WholeBody, [&] { runWholeBodyPhase(layout, slots, awake, bad); });
  timed(Phase::Velocities, [&] { runVelocitiesPhase(layout, settings.gravity, h, slots, awake); });
  const ContactSettings contact{settings.bodyContact, float(settings.contactFriction),
                                float(settings.restitutionThreshold),
                                float(settings.rollingResistance), settings.gravity};
  timed(Phase::Contacts,
        [&] { runContactsPhase(layout, contact, h, slots, order, colliders, contactScratch); });
  contactWork.triangleTests += contactScratch.triangleTests;
  contactWork.triangleTestsOfAllPairs += contactScratch.triangleTestsOfAllPairs;
  timed(Phase::Solve, [&] {
    contactCount = runSolvePhase(layout, contact, h, slots, order, colliders, contactScratch);
  });
  contactWork.sweepVisits += contactScratch.sweepVisits;
  contactWork.skippedVisits += contactScratch.skippedVisits;
  // Damping after the contacts: the velocity the contact solve leaves relative to a body's
  // rigid motion (its impulses act on single particles) is damped in the same sub-step.
  timed(Phase::Damping, [&] { runDampingPhase(layout, slots, awake); });
  timed(Phase::Check, [&] { resetFailedBodies(); });
  timed(Phase::Sleep, [&] {
    if (runSleepPhase(h, settings.sleep, slots, awake, contactScratch.touching, held, sleepScratch))
      awakeDirty = true;
  });
}

// The Check phase: bodies that produced NaN/Inf go back to their start state, with an event.
void World::Data::resetFailedBodies() {
  for (int s : order) {
    if (!bad[size_t(s)]) continue;
    BodySlot& b = slots[size_t(s)];
    resetBodyState(*b.model, b.state);
    events.push_back({handleOf(s), "body '" + b.model->name + "' produced NaN/Inf (time " +
                                       formatNumber(time) +
                                       " s); it was reset to its start state"});
  }
}

// ---------------------------------------------------------------------------------------------
// Public API.

World::World(const WorldSettings& settings) : d_(std::make_unique<Data>()) {
  setSettings(settings);
}
World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;
World::World(const World& o) : d_(std::make_unique<Data>(*o.d_)) {}
World& World::operator=(const World& o) {
  if (this != &o) d_ = std::make_unique<Data>(*o.d_);
  return *this;
}

const WorldSettings& World::settings() const {
  return d_->settings;
}

void World::setSettings(const WorldSettings& s) {
  if (!s.gravity.allFinite() || !limits::gravityNorm.contains(s.gravity.norm()))
    throw std::invalid_argument("gravity: must be finite and at most " +
                                formatNumber(limits::gravityNorm.hi) + " m/s² long");
  requireRange("timeStep", limits::timeStep, s.timeStep);
  requireRange("substeps", limits::substeps, s.substeps);
  requireRange("maxSubstep", limits::maxSubstep, s.maxSubstep);
  requireRange("contactFriction", limits::friction, s.contactFriction);
  requireRange("restitutionThreshold", limits::restitutionThreshold, s.restitutionThreshold);
  requireRange("rollingResistance", limits::rollingResistance, s.rollingResistance);
  // Gravity, friction, restitution, rolling resistance, contact or sleep changes can set resting
  // bodies moving; waking also restarts the sleep clocks, which do not run while sleep is off
  // (sleep_phase.h).
  const WorldSettings& o = d_->settings;
  const bool same = o.gravity == s.gravity && o.timeStep == s.timeStep &&
                    o.substeps == s.substeps && o.maxSubstep == s.maxSubstep &&
                    o.bodyContact == s.bodyContact && o.contactFriction == s.contactFriction &&
                    o.restitutionThreshold == s.restitutionThreshold &&
                    o.rollingResistance == s.rollingResistance && o.sleep == s.sleep;
  d_->settings = s;
  if (!same) d_->wakeAll();
}

void World::addCollider(const Collider& c) {
  auto finite = [](const Vec3& v) { return v.allFinite(); };
  requireRange("friction", limits::friction, c.friction);
  requireRange("restitution", limits::restitution, c.restitution);
  switch (c.shape) {
    case Collider::Shape::Plane:
      if (!finite(c.normal) || std::abs(c.normal.norm() - 1.0) > 1e-6 || !std::isfinite(c.offset))
        throw std::invalid_argument("plane: normal must be a finite unit vector");
      break;
    case Collider::Shape::Box:
      if (!finite(c.centre) || !finite(c.halfExtents) || (c.halfExtents.array() <= 0.0).any())
        throw std::invalid_argument("box: centre must be finite and half extents positive");
      if (!c.rotation.allFinite() ||
          (c.rotation.transpose() * c.rotation - Mat3::Identity()).norm() > 1e-6 ||
          c.rotation.determinant() < 0.0)
        throw std::invalid_argument("box: rotation must be a proper rotation matrix");
      break;
    case Collider::Shape::Sphere:
    case Collider::Shape::Capsule:
      if (!finite(c.centre) || !finite(c.axis) || !(c.radius > 0.0) || !std::isfinite(c.radius))
        throw std::invalid_argument(std::string(colliderShapeName(c.shape)) +
                                    ": centre/axis must be finite and radius positive");
      break;
  }
  d_->colliders.push_back(c);
  d_->wakeAll();
}

void World::clearColliders() {
  d_->colliders.clear();
  d_->wakeAll();
}
const std::vector<Collider>& World::colliders() const {
  return d_->colliders;
}

BodyHandle World::addBody(const BodyDef& def) {
  const int n = static_cast<int>(def.positions.size());
  if (n == 0) throw std::invalid_argument("positions: a body needs at least one particle");
  if (n > (1 << 28)) throw std::invalid_argument("positions: too many particles");
  for (int i = 0; i < n; ++i)
    if (!def.positions[size_t(i)].allFinite())
      throw std::invalid_argument("positions[" + std::to_string(i) + "]: not finite");
  if (n >= 2) {  // float32 must resolve the body's shape where it is (param_ranges.h)
    Eigen::AlignedBox3d box;
    double farthest = 0;
    for (const Vec3& p : def.positions) {
      box.extend(p);
      farthest = std::max(farthest, p.norm());
    }
    const double extent = box.diagonal().norm();
    if (extent < limits::minBodyExtent || extent < limits::minExtentToDistance * farthest)
      throw std::invalid_argument(
          "positions: the body is " + formatNumber(extent) + " m across with a particle " +
          formatNumber(farthest) + " m from the origin; float32 positions cannot carry its shape " +
          "(needs at least " + formatNumber(limits::minBodyExtent) + " m across and at least " +
          formatNumber(limits::minExtentToDistance) +
          " × its distance from the origin): scale it up or move it towards the origin");
  }
  if (!def.masses.empty()) {
    if (int(def.masses.size()) != n)
      throw std::invalid_argument("masses: " + std::to_string(def.masses.size()) + " values for " +
                                  std::to_string(n) + " particles");
    for (int i = 0; i < n; ++i)
      requireRange("masses[" + std::to_string(i) + "]", limits::particleMass,
                   def.masses[size_t(i)]);
  } else {
    requireRange("mass", limits::bodyMass, def.totalMass);
  }
  if (!def.velocity.allFinite()) throw std::invalid_argument("velocity: not finite");
  for (int p : def.pinned)
    if (p < 0 || p >= n)
      throw std::invalid_argument("pinned: particle index " + std::to_string(p) +
                                  " out of range [0, " + std::to_string(n) + ")");
  validateParams(def.params);
  // The surface is validated, and its adjacency built, once (interior particles, which no
  // triangle uses, are allowed).
  mesh::SurfaceTopology topology;
  if (!def.surface.empty()) {
    for (size_t t = 0; t < def.surface.size(); ++t)
      for (int i : def.surface[t])
        if (i < 0 || i >= n)
          throw std::invalid_argument("surface[" + std::to_string(t) + "]: particle index " +
                                      std::to_string(i) + " out of range [0, " + std::to_string(n) +
                                      ")");
    mesh::TriangleMesh surface{def.positions, def.surface};
    try {
      topology = mesh::validateClosedSurface(surface, def.name, {/*allowUnusedVertices=*/true});
    } catch (const std::exception& e) {
      throw std::invalid_argument(std::string("surface: ") + e.what());
    }
  } else {
    topology = mesh::buildSurfaceTopology({}, n);
  }

  BodySlot slot;
  slot.model = buildBodyModel(def, std::move(topology));  // throws on bad clusters
  slot.params = def.params;
  slot.alive = true;
  resetBodyState(*slot.model, slot.state);

  size_t index = d_->slots.size();
  for (size_t i = 0; i < d_->slots.size(); ++i)
    if (!d_->slots[i].alive) {
      index = i;
      break;
    }
  if (index == d_->slots.size()) d_->slots.emplace_back();
  slot.generation = d_->slots[index].generation;
  d_->slots[index] = std::move(slot);
  d_->order.push_back(static_cast<int>(index));
  d_->awakeDirty = true;
  d_->contactScratch.forgetBodies();
  return d_->handleOf(static_cast<int>(index));
}

void World::removeBody(BodyHandle h) {
  BodySlot& s = d_->slot(h);
  d_->wake(int(h.index));  // what rested on it wakes
  s.sleep = SleepState{};
  s.alive = false;
  ++s.generation;
  s.model.reset();
  s.state = BodyState{};
  d_->order.erase(std::find(d_->order.begin(), d_->order.end(), int(h.index)));
  d_->awakeDirty = true;
  d_->contactScratch.forgetBodies();
  auto& wakes = d_->contactScratch.wake;
  wakes.erase(std::remove(wakes.begin(), wakes.end(), int(h.index)), wakes.end());
  for (auto it = d_->drags.begin(); it != d_->drags.end();)
    it = it->second.body == h ? d_->drags.erase(it) : std::next(it);
  // Forces queued for the removed body die with it (step() must not meet a stale handle).
  auto& forces = d_->forces;
  forces.erase(std::remove_if(forces.begin(), forces.end(),
                              [&](const QueuedForce& f) { return f.body == h; }),
               forces.end());
}

bool World::contains(BodyHandle h) const {
  return h.index < d_->slots.size() && d_->slots[h.index].alive &&
         d_->slots[h.index].generation == h.generation;
}

std::vector<BodyHandle> World::bodies() const {
  std::vector<BodyHandle> out;
  for (int s : d_->order) out.push_back(d_->handleOf(s));
  return out;
}

const std::string& World::name(BodyHandle h) const {
  return d_->slot(h).model->name;
}
const BodyParams& World::params(BodyHandle h) const {
  return d_->slot(h).params;
}

void World::setParams(BodyHandle h, const BodyParams& p) {
  BodySlot& s = d_->slot(h);
  validateParams(p);
  s.params = p;  // a change of cluster path is taken up at the start of the next sub-step
  d_->wake(int(h.index));
}

const ClusterDef& World::clusterDef(BodyHandle h) const {
  return d_->slot(h).model->clusterDef;
}

void World::setClusters(BodyHandle h, const ClusterDef& clusters) {
  BodySlot& s = d_->slot(h);
  auto model = withClusters(*s.model, clusters);  // throws; body unchanged then
  s.model = std::move(model);
  s.state.clusters.reset(*s.model, s.state.x);
  d_->layoutDirty = true;
  d_->wake(int(h.index));
}

int World::clusterCount(BodyHandle h) const {
  return d_->slot(h).model->clusterCount();
}

std::vector<std::vector<int>> World::clusterMembers(BodyHandle h) const {
  const BodyModel& m = *d_->slot(h).model;
  std::vector<std::vector<int>> out(size_t(m.clusterCount()));
  for (int c = 0; c < m.clusterCount(); ++c)
    out[size_t(c)].assign(m.clusterMembers.begin(c), m.clusterMembers.end(c));
  return out;
}

int World::particleCount(BodyHandle h) const {
  return d_->slot(h).model->particleCount();
}

ConstPointsRef World::positions(BodyHandle h) const {
  return d_->slot(h).state.x;
}
ConstPointsRef World::velocities(BodyHandle h) const {
  return d_->slot(h).state.v;
}
ConstPointsRef World::restPositions(BodyHandle h) const {
  return d_->slot(h).model->startPositions;
}

Eigen::VectorXf World::masses(BodyHandle h) const {
  return d_->slot(h).model->mass;
}
double World::mass(BodyHandle h) const {
  return d_->slot(h).model->totalMass;
}

Vec3 World::centreOfMass(BodyHandle h) const {
  const BodySlot& s = d_->slot(h);
  return sb::centreOfMass(columns(s.state.x), s.model->mass.data(), s.model->particleCount());
}

Vec3 World::linearMomentum(BodyHandle h) const {
  const BodySlot& s = d_->slot(h);
  return sb::linearMomentum(columns(s.state.v), s.model->mass.data(), s.model->particleCount());
}

Vec3 World::angularMomentum(BodyHandle h, const Vec3& about) const {
  const BodySlot& s = d_->slot(h);
  return sb::angularMomentum(columns(s.state.x), columns(s.state.v), s.model->mass.data(),
                             s.model->particleCount(), about);
}

void World::setState(BodyHandle h, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v) {
  BodySlot& s = d_->slot(h);
  const int n = s.model->particleCount();
  if (x.rows() != n || v.rows() != n)
    throw std::invalid_argument("setState: expected " + std::to_string(n) + " rows");
  if (!x.allFinite() || !v.allFinite()) throw std::invalid_argument("setState: not finite");
  s.state.x = x.cast<float>();
  s.state.v = v.cast<float>();
  d_->wake(int(h.index));
}

Eigen::MatrixX3d World::goals(BodyHandle h) const {
  const BodySlot& b = d_->slot(h);
  const BodyModel& m = *b.model;
  Eigen::MatrixX3d out(m.particleCount(), 3);
  for (int i = 0; i < m.particleCount(); ++i) {
    Vec3 g = Vec3::Zero();
    const Vec3 r = m.rest.row(i).transpose().cast<double>();
    for (const int* c = m.particleClusters.begin(i); c != m.particleClusters.end(i); ++c) {
      const GoalTransform T = b.state.clusters.goal(*c);
      g += T.L.cast<double>() * r + T.Q.cast<double>() * monomials<double>(r) + T.t.cast<double>();
    }
    out.row(i) = (g * double(m.invCount[i])).transpose();
  }
  return out;
}

Mat3 World::plasticDeformation(BodyHandle h, int cluster) const {
  const BodySlot& b = d_->slot(h);
  if (cluster < 0 || cluster >= b.model->clusterCount())
    throw std::invalid_argument("cluster index out of range");
  return b.state.clusters.plastic(cluster);
}

void World::addForce(BodyHandle h, int particle, const Vec3& force) {
  const BodySlot& b = d_->slot(h);
  if (particle < 0 || particle >= b.model->particleCount())
    throw std::invalid_argument("addForce: particle index out of range");
  if (!force.allFinite()) throw std::invalid_argument("addForce: force not finite");
  d_->forces.push_back({h, particle, force});
  d_->wake(int(h.index));
}

int World::addDrag(const DragDef& drag) {
  const BodySlot& b = d_->slot(drag.body);
  if (drag.particles.empty() || drag.particles.size() != drag.weights.size())
    throw std::invalid_argument("drag: needs matching, non-empty particles and weights");
  double sumW2 = 0;
  for (size_t k = 0; k < drag.particles.size(); ++k) {
    if (drag.particles[k] < 0 || drag.particles[k] >= b.model->particleCount())
      throw std::invalid_argument("drag: particle index out of range");
    if (!std::isfinite(drag.weights[k])) throw std::invalid_argument("drag: weight not finite");
    sumW2 += drag.weights[k] * drag.weights[k];
  }
  if (!(sumW2 > 0.0)) throw std::invalid_argument("drag: all weights are zero");
  if (!drag.target.allFinite()) throw std::invalid_argument("drag: target not finite");
  requireRange("drag stiffness", limits::dragStiffness, drag.stiffness);
  const int id = d_->nextDragId++;
  d_->drags[id] = drag;
  return id;
}

void World::setDragTarget(int id, const Vec3& target) {
  auto it = d_->drags.find(id);
  if (it == d_->drags.end()) throw std::invalid_argument("drag: unknown id");
  if (!target.allFinite()) throw std::invalid_argument("drag: target not finite");
  it->second.target = target;
}

void World::setDragStiffness(int id, double stiffness) {
  auto it = d_->drags.find(id);
  if (it == d_->drags.end()) throw std::invalid_argument("drag: unknown id");
  requireRange("drag stiffness", limits::dragStiffness, stiffness);
  it->second.stiffness = stiffness;
}

void World::removeDrag(int id) {
  d_->drags.erase(id);
}

void World::step() {
  step(d_->settings.timeStep);
}

void World::step(double dt) {
  requireRange("step: dt", limits::timeStep, dt);
  const int n = substepsFor(dt);
  d_->contactWork = ContactWork{};
  for (int s : d_->order) {
    BodySlot& b = d_->slots[size_t(s)];
    b.stepParams = paramsForSubstep(b.params, dt / n);
  }
  StepProfile prof;
  for (int i = 0; i < n; ++i) d_->substep(dt / n, prof);
  d_->forces.clear();
  d_->profile = prof;
  d_->time += dt;
}

int World::substepsFor(double dt) const {
  const WorldSettings& s = d_->settings;
  // dt ≤ 10 s and maxSubstep ≥ 1e-4 s bound the count by 1e5.
  const double needed = std::ceil(dt / s.maxSubstep * (1.0 - 1e-6));
  return std::max(s.substeps, static_cast<int>(needed));
}

void World::reset() {
  for (int s : d_->order) {
    BodySlot& b = d_->slots[size_t(s)];
    resetBodyState(*b.model, b.state);
    b.sleep = SleepState{};
  }
  d_->awakeDirty = true;
  d_->contactScratch.forgetBodies();
  d_->contactScratch.wake.clear();
  d_->drags.clear();
  d_->forces.clear();
  d_->time = 0;
}

double World::time() const {
  return d_->time;
}
int World::lastContactCount() const {
  return d_->contactCount;
}
World::ContactWork World::lastContactWork() const {
  return d_->contactWork;
}
double World::lastDeepestContact() const {
  return d_->contactScratch.deepestContact;
}

bool World::isSleeping(BodyHandle h) const {
  return d_->slot(h).sleep.asleep;
}

int World::sleepingCount() const {
  int n = 0;
  for (int s : d_->order) n += d_->slots[size_t(s)].sleep.asleep;
  return n;
}

void World::wake(BodyHandle h) {
  d_->slot(h);  // throws on a stale handle
  d_->wake(int(h.index));
}

const StepProfile& World::lastProfile() const {
  return d_->profile;
}

std::vector<WorldEvent> World::takeEvents() {
  std::vector<WorldEvent> out;
  out.swap(d_->events);
  return out;
}

std::uint64_t World::stateHash() const {
  std::uint64_t hash = 1469598103934665603ULL;  // FNV-1a
  auto mix = [&](const void* data, size_t bytes) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ULL;
  };
  for (int s : d_->order) {
    const BodySlot& b = d_->slots[size_t(s)];
    mix(b.state.x.data(), sizeof(float) * size_t(b.state.x.size()));
    mix(b.state.v.data(), sizeof(float) * size_t(b.state.v.size()));
    for (int c = 0; c < b.model->clusterCount(); ++c)
      mix(b.state.clusters.plastic(c).data(), sizeof(double) * 9);
  }
  return hash;
}

}  // namespace sb
