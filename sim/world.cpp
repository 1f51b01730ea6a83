#include "sim/world.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <stdexcept>

#include "sim/body_contact.h"
#include "sim/cage/cage_validation.h"
#include "sim/cluster_batch.h"
#include "sim/cluster_layout.h"
#include "sim/cluster_rest.h"
#include "sim/mass_properties.h"
#include "sim/parallel_for.h"
#include "sim/particle_groups.h"
#include "sim/plasticity.h"
#include "sim/shape_matching.h"

namespace sb {

namespace {

using MatX3f = Eigen::Matrix<float, Eigen::Dynamic, 3>;
using Clock = std::chrono::steady_clock;

constexpr int kMembersPerTask = 8192;             // cluster members per moment task
constexpr int kParticlesPerBlock = 4096;          // particles per integration/collision block
constexpr int kClusteredParticlesPerBlock = 128;  // the same for bodies with several clusters
// Below this many particles (or cluster members) a phase runs on one thread: fork/join would
// cost more than it saves.
constexpr long long kMinParallelWork = 16384;
// Integration forks from this many particles plus cluster memberships: below, the goal sums of
// clustered bodies still gain from reading goals where the Goals phase wrote them.
constexpr long long kMinParallelIntegration = 8192;
// Per-body phases (damping, contacts) fork only in worlds with at least this many particles.
constexpr long long kMinParallelBodyWork = 2048;
// Separation body–body contacts restore, as a fraction of the obstacle's surface spacing: a
// small positive gap keeps resting particles outside despite float round-off.
constexpr float kContactGap = 0.01f;
// An obstacle's contact grid is rebuilt once its surface has moved this many spacings.
constexpr float kGridSlack = 0.25f;
// Gauss–Seidel sweeps over a sub-step's body–body contacts.
constexpr int kContactSweeps = 4;

double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string str(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

void requireRange(const std::string& field, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi))
    throw std::invalid_argument(field + ": must be in [" + str(lo) + ", " + str(hi) + "], got " +
                                str(v));
}

void validateParams(const BodyParams& p) {
  requireRange("alpha", p.alpha, 0.0, 1.0);
  requireRange("beta", p.beta, 0.0, 1.0);
  requireRange("damping", p.damping, 0.0, 1.0);
  requireRange("plasticity.yield", p.plasticity.yield, 0.0, 1e6);
  requireRange("plasticity.creep", p.plasticity.creep, 0.0, 1e6);
  requireRange("plasticity.max", p.plasticity.max, 0.0, 1e6);
}

// A fixed range of one cluster's members whose moments are summed together.
struct MomentTask {
  int cluster;
  int begin, end;  // positions in the cluster-major member list (or particle indices)
};

// What never changes while a body runs (rebuilt only by setClusters).
struct BodyModel {
  std::string name;
  Vec3 origin = Vec3::Zero();  // world position of the body frame's origin: rest centre of mass
  MatX3f rest;                 // r: rest positions in the body frame (#P×3, m)
  Eigen::VectorXf mass;        // #P, kg
  double totalMass = 0;
  std::vector<int> pinned;
  MatX3f startPositions, startVelocities;  // #P×3, the state reset() returns to
  ClusterDef clusterDef;
  // Clusters in both directions (CSR): members of cluster c are
  // members[memberStart[c] .. memberStart[c+1]); clusters of particle i are
  // particleClusters[particleStart[i] .. particleStart[i+1]), ascending.
  std::vector<int> memberStart, members;
  std::vector<int> particleStart, particleClusters;
  // Particles with the same clusters (sim/particle_groups.h); empty when there is little to
  // share. Goal sums are formed per group; so are the moments of non-quadratic bodies.
  ParticleGroups groups;
  Eigen::VectorXf matchWeight;  // wᵢ = mᵢ / (number of clusters of i): conserves momentum
  Eigen::VectorXf invCount;     // 1 / (number of clusters of i)
  std::vector<ClusterRestModel> clusterRest;
  // Per membership (parallel to `members`): q⁰ = r − rc (#M×3) and the member's weight.
  MatX3f memberRest;
  Eigen::VectorXf memberWeight;
  std::vector<MomentTask> tasks;  // in cluster order
  std::vector<int> taskStart;     // tasks of cluster c: taskStart[c] .. taskStart[c+1]
  bool wholeBodyCluster = false;  // exactly one cluster holding every particle in order
  // Clusters of at most kBatchMaxMembers members, eight per batch (cluster_batch.h).
  std::vector<ClusterBatch> batches;
  // Body–body contact: the closed surface (may be empty) and its adjacency, the
  // surface's mean edge length at rest (m) and the inverse masses contacts use (0 = pinned).
  std::vector<Triangle> surface;
  SurfaceTopology surfaceTopology;
  float spacing = 0;
  Eigen::VectorXf contactInvMass;
  int clusterCount() const { return static_cast<int>(clusterRest.size()); }
  int particleCount() const { return static_cast<int>(rest.rows()); }
};

// What changes every step.
struct BodyState {
  MatX3f x, v;                               // positions (m) and velocities (m/s), #P×3
  std::vector<Mat3> plastic;                 // Sᵖ per cluster
  std::vector<ClusterShape> shape;           // derived from Sᵖ
  std::vector<Eigen::Quaterniond> rotation;  // warm start of the rotation extraction
  std::vector<Eigen::Vector3f> ref;          // last centre of mass: reference for float sums
  // Each cluster's goal transform (GoalTransform), written by the Goals phase: the linear part
  // packed as rows [L | t] (12 floats, SIMD-aligned: the per-membership sum in the integration
  // of clustered bodies is three vector adds) and the quadratic part Q (zero outside quadratic
  // mode). Kept apart so the common linear case writes and reads one cache line per cluster.
  std::vector<Eigen::Matrix<float, 12, 1>, Eigen::aligned_allocator<Eigen::Matrix<float, 12, 1>>>
      goalRows;
  std::vector<Eigen::Matrix<float, 3, 6>> goalQuad;
  // Per particle group (BodyModel::groups): the sums of its clusters' goalRows and goalQuad,
  // formed by the integration before it visits the particles.
  std::vector<Eigen::Matrix<float, 12, 1>, Eigen::aligned_allocator<Eigen::Matrix<float, 12, 1>>>
      groupRows;
  std::vector<Eigen::Matrix<float, 3, 6>> groupQuad;
  // Per particle group, for bodies with grouped moments: each group's moments, summed about its
  // reference point groupRef (its first particle's position this sub-step).
  std::vector<ClusterMoments> groupMoments;
  std::vector<Eigen::Vector3f> groupRef;
  // Per batch of the model: Sᵖ-dependent data in lanes, and whether it lags behind Sᵖ.
  std::vector<ClusterBatchShape> batchShape;
  bool batchShapeStale = true;
  // Per batch: the clusters' reference points and rotations in lanes. While the body runs in
  // batches (lanesHoldState) these are the current values and `ref`/`rotation` of its batched
  // clusters lag behind; rebuildLayout hands the state over when that changes.
  std::vector<ClusterBatchLanes> batchLanes;
  bool lanesHoldState = false;
};

// Cluster c's reference point and rotation into lane l, and back.
void clusterToLane(const BodyState& s, size_t c, ClusterBatchLanes& lanes, int l) {
  for (int a = 0; a < 3; ++a) lanes.ref[a][l] = s.ref[c][a];
  const Eigen::Quaterniond& q = s.rotation[c];
  lanes.rotation[0][l] = float(q.w());
  lanes.rotation[1][l] = float(q.x());
  lanes.rotation[2][l] = float(q.y());
  lanes.rotation[3][l] = float(q.z());
}

void laneToCluster(const ClusterBatchLanes& lanes, int l, BodyState& s, size_t c) {
  for (int a = 0; a < 3; ++a) s.ref[c][a] = lanes.ref[a][l];
  s.rotation[c] = Eigen::Quaterniond(lanes.rotation[0][l], lanes.rotation[1][l],
                                     lanes.rotation[2][l], lanes.rotation[3][l])
                      .normalized();
}

// Copies the batched clusters' reference points and rotations from `ref`/`rotation` into the
// batch lanes (every lane, padding included), or back (lanes in use only).
void lanesFromClusters(const BodyModel& m, BodyState& s) {
  s.batchLanes.resize(m.batches.size());
  for (size_t k = 0; k < m.batches.size(); ++k)
    for (int l = 0; l < kBatchLanes; ++l)
      clusterToLane(s, size_t(m.batches[k].cluster[l]), s.batchLanes[k], l);
}

void clustersFromLanes(const BodyModel& m, BodyState& s) {
  for (size_t k = 0; k < m.batches.size(); ++k)
    for (int l = 0; l < m.batches[k].count; ++l)
      laneToCluster(s.batchLanes[k], l, s, size_t(m.batches[k].cluster[l]));
}

// Whether a body's small clusters go through the batched kernel: rigid and linear bodies
// without plastic flow (a plastic update is a per-cluster decision with its own re-fit).
bool usesBatches(const BodyModel& m, const BodyParams& p) {
  return !m.batches.empty() && p.mode != Mode::Quadratic && !p.plasticity.enabled();
}

// Whether the moments of a body's (unbatched) clusters are added up from its particle groups'
// moments (linear moments only: not in quadratic mode).
bool usesGroupedMoments(const BodyModel& m, const BodyParams& p) {
  return !m.groups.empty() && p.mode != Mode::Quadratic;
}

struct BodySlot {
  std::uint32_t generation = 0;
  bool alive = false;
  std::shared_ptr<const BodyModel> model;
  BodyParams params;
  BodyState state;
};

std::shared_ptr<BodyModel> buildModel(const BodyDef& def, const ClusterDef& clusters,
                                      std::shared_ptr<const BodyModel> base) {
  auto m = std::make_shared<BodyModel>();
  if (base) {  // new clusters for an existing body: keep everything but the clusters
    *m = *base;
  } else {
    const int n = static_cast<int>(def.positions.size());
    m->name = def.name;
    m->mass.resize(n);
    for (int i = 0; i < n; ++i)
      m->mass[i] = def.masses.empty() ? float(def.totalMass / n) : float(def.masses[size_t(i)]);
    m->totalMass = 0;
    Vec3 weighted = Vec3::Zero();
    for (int i = 0; i < n; ++i) {
      m->totalMass += m->mass[i];
      weighted += double(m->mass[i]) * def.positions[size_t(i)];
    }
    m->origin = weighted / m->totalMass;
    m->rest.resize(n, 3);
    m->startPositions.resize(n, 3);
    m->startVelocities.resize(n, 3);
    for (int i = 0; i < n; ++i) {
      m->rest.row(i) = (def.positions[size_t(i)] - m->origin).transpose().cast<float>();
      m->startPositions.row(i) = def.positions[size_t(i)].transpose().cast<float>();
      m->startVelocities.row(i) = def.velocity.transpose().cast<float>();
    }
    m->pinned = def.pinned;
    m->surface = def.surface;
    m->surfaceTopology = buildSurfaceTopology(m->surface, n);
    m->spacing = float(meanEdgeLength(m->surface, def.positions));
    m->contactInvMass = m->mass.cwiseInverse();
    for (int p : m->pinned) m->contactInvMass[p] = 0.0f;
  }
  m->clusterDef = clusters;
  std::vector<Vec3> restWorld(static_cast<size_t>(m->particleCount()));
  for (int i = 0; i < m->particleCount(); ++i)
    restWorld[size_t(i)] = m->rest.row(i).transpose().cast<double>() + m->origin;
  const std::vector<std::vector<int>> lists = buildClusterMembers(clusters, restWorld);

  const int n = m->particleCount();
  const int nc = static_cast<int>(lists.size());
  m->memberStart.assign(1, 0);
  m->members.clear();
  std::vector<int> count(size_t(n), 0);
  for (const auto& list : lists) {
    m->members.insert(m->members.end(), list.begin(), list.end());
    m->memberStart.push_back(static_cast<int>(m->members.size()));
    for (int p : list) ++count[size_t(p)];
  }
  m->particleStart.assign(size_t(n) + 1, 0);
  for (int i = 0; i < n; ++i)
    m->particleStart[size_t(i) + 1] = m->particleStart[size_t(i)] + count[size_t(i)];
  m->particleClusters.assign(m->members.size(), 0);
  std::vector<int> fill(m->particleStart.begin(), m->particleStart.end() - 1);
  for (int c = 0; c < nc; ++c)
    for (int k = m->memberStart[size_t(c)]; k < m->memberStart[size_t(c) + 1]; ++k)
      m->particleClusters[size_t(fill[size_t(m->members[size_t(k)])]++)] = c;
  m->matchWeight.resize(n);
  m->invCount.resize(n);
  for (int i = 0; i < n; ++i) {
    m->invCount[i] = 1.0f / float(count[size_t(i)]);
    m->matchWeight[i] = m->mass[i] * m->invCount[i];
  }
  const float* restCols[3] = {m->rest.col(0).data(), m->rest.col(1).data(), m->rest.col(2).data()};
  m->groups = buildParticleGroups(n, m->particleStart, m->particleClusters, nc, restCols,
                                  m->matchWeight.data());
  m->wholeBodyCluster = nc == 1 && int(m->members.size()) == n;
  m->clusterRest.resize(size_t(nc));
  m->tasks.clear();
  m->taskStart.assign(1, 0);
  for (int c = 0; c < nc; ++c) {
    const int b = m->memberStart[size_t(c)], e = m->memberStart[size_t(c) + 1];
    m->clusterRest[size_t(c)] =
        buildClusterRest(m->members.data() + b, e - b, m->rest.col(0).data(), m->rest.col(1).data(),
                         m->rest.col(2).data(), m->matchWeight.data());
    for (int k = b; k < e; k += kMembersPerTask)
      m->tasks.push_back({c, k, std::min(e, k + kMembersPerTask)});
    m->taskStart.push_back(static_cast<int>(m->tasks.size()));
  }
  const int memberCount = static_cast<int>(m->members.size());
  m->memberRest.resize(memberCount, 3);
  m->memberWeight.resize(memberCount);
  for (int c = 0; c < nc; ++c) {
    const Eigen::Vector3f rc = m->clusterRest[size_t(c)].centre;
    for (int k = m->memberStart[size_t(c)]; k < m->memberStart[size_t(c) + 1]; ++k) {
      const int i = m->members[size_t(k)];
      for (int a = 0; a < 3; ++a) m->memberRest(k, a) = m->rest(i, a) - rc[a];  // as the kernels do
      m->memberWeight[k] = m->matchWeight[i];
    }
  }
  const float* memberRest[3] = {m->memberRest.col(0).data(), m->memberRest.col(1).data(),
                                m->memberRest.col(2).data()};
  m->batches = buildClusterBatches(m->memberStart, m->members, memberRest, m->memberWeight.data(),
                                   m->clusterRest);
  return m;
}

void storeGoal(const GoalTransform& T, BodyState& s, size_t c) {
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) s.goalRows[c][4 * a + j] = T.L(a, j);
    s.goalRows[c][4 * a + 3] = T.t[a];
  }
  s.goalQuad[c] = T.Q;
}

GoalTransform goalOf(const BodyState& s, size_t c) {
  GoalTransform T;
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) T.L(a, j) = s.goalRows[c][4 * a + j];
    T.t[a] = s.goalRows[c][4 * a + 3];
  }
  T.Q = s.goalQuad[c];
  return T;
}

// Cluster state for the current positions: identity plastic state, goals = rest shape placed at
// the clusters' current centres.
void resetClusterState(const BodyModel& m, BodyState& s) {
  const size_t nc = size_t(m.clusterCount());
  s.plastic.assign(nc, Mat3::Identity());
  s.shape.resize(nc);
  s.rotation.assign(nc, Eigen::Quaterniond::Identity());
  s.ref.resize(nc);
  s.goalRows.resize(nc);
  s.goalQuad.resize(nc);
  for (size_t c = 0; c < nc; ++c) {
    s.shape[c] = deriveClusterShape(m.clusterRest[c], Mat3::Identity(), false);
    Vec3 centre = Vec3::Zero();
    double mass = 0;
    for (int k = m.memberStart[c]; k < m.memberStart[c + 1]; ++k) {
      const int i = m.members[size_t(k)];
      centre += double(m.matchWeight[i]) * s.x.row(i).transpose().cast<double>();
      mass += m.matchWeight[i];
    }
    s.ref[c] = (centre / mass).cast<float>();
    GoalTransform restGoal;
    restGoal.t = m.origin.cast<float>();
    storeGoal(restGoal, s, c);
  }
  s.batchShape.resize(m.batches.size());
  s.batchShapeStale = true;
  lanesFromClusters(m, s);  // both copies current
}

void resetBodyState(const BodyModel& m, BodyState& s) {
  s.x = m.startPositions;
  s.v = m.startVelocities;
  resetClusterState(m, s);
}

struct Force {
  BodyHandle body;
  int particle;
  Vec3 force;
};

// One unit of per-particle work: particles [begin, end) of a body.
struct ParticleBlock {
  int slot;
  int begin, end;
};

// A moment task of some body, in the world's fixed order.
struct GlobalTask {
  int slot;
  int task;
};

// A cluster of some body and where its tasks start in the world's task list.
struct GlobalCluster {
  int slot;
  int cluster;
  int firstTask;
  bool grouped;  // moments from the body's particle groups (usesGroupedMoments)
};

// A batch of small clusters of some body; the body's tasks start at firstTask in the world's list.
struct GlobalBatch {
  int slot;
  int batch;
  int firstTask;
};

// The work lists of one step, rebuilt only when bodies or clusters change.
struct WorkLayout {
  std::vector<GlobalTask> tasks;
  std::vector<int> splitTasks;  // tasks of clusters with several tasks (summed in a first pass)
  std::vector<GlobalCluster> clusters;  // clusters not in a batch
  std::vector<GlobalBatch> batches;
  std::vector<ParticleBlock> blocks;
  std::vector<ParticleBlock> groupBlocks;  // the same over particle groups (begin, end: groups)
  std::vector<ParticleBlock> momentGroupBlocks;  // group blocks of bodies with grouped moments
  long long members = 0, particles = 0;
};

// Per-body data of the Contacts phase, derived from the positions every sub-step.
struct ContactScratch {
  Eigen::AlignedBox3f box;             // particles' bounding box
  float maxSpeed = 0;                  // m/s
  Vec3f meanVelocity = Vec3f::Zero();  // m/s, of the centre of mass
  float maxRelativeSpeed = 0;          // m/s, fastest particle relative to the centre of mass
  bool obstacle = false;               // has a surface and meets some other body this sub-step
  Eigen::AlignedBox3f region;          // obstacles: bounding box of the probes that meet it
  bool involved = false;               // meets some other body this sub-step
  SurfaceGrid grid;
  ContactBody view;  // set up by prepareContactBody for involved bodies
  // The grid's surface positions and region when it was built, and whose it is (a slot can be
  // reused by another body).
  MatX3f gridPositions;
  Eigen::AlignedBox3f gridRegion;
  const BodyModel* gridModel = nullptr;
  std::vector<std::pair<int, int>> staticContacts;  // (particle, collider) inside a collider
};

// A probe body whose particles are tested against an obstacle body's surface.
struct ContactPair {
  int probe, obstacle;  // slots
};

}  // namespace

struct World::Data {
  WorldSettings settings;
  std::vector<Collider> colliders;
  std::vector<BodySlot> slots;
  std::vector<int> order;  // alive slots in creation order
  std::map<int, DragDef> drags;
  int nextDragId = 1;
  std::vector<Force> forces;
  double time = 0;
  StepProfile profile;
  std::vector<WorldEvent> events;
  WorkLayout layout;
  bool layoutDirty = true;
  // Scratch reused every sub-step (no allocations in the loop).
  std::vector<ClusterMoments> partial;
  std::vector<double> plasticSeconds;
  std::vector<char> clusterBad, batchBad, blockBad, bad;
  std::vector<ContactScratch> contactScratch;  // per slot
  std::vector<ContactPair> contactPairs;
  std::vector<std::vector<Contact>> pairContacts;  // per pair
  // Bodies in sweep order, grown boxes and creation rank per slot, obstacle and involved slots.
  std::vector<int> contactSweep, contactRank, contactObstacles, contactInvolved;
  std::vector<Eigen::AlignedBox3f> contactBoxes;
  int contactCount = 0;

  BodySlot& slot(BodyHandle h) {
    if (h.index >= slots.size() || !slots[h.index].alive ||
        slots[h.index].generation != h.generation)
      throw std::invalid_argument("unknown body handle");
    return slots[h.index];
  }
  BodyHandle handleOf(int s) const {
    return BodyHandle{static_cast<std::uint32_t>(s), slots[size_t(s)].generation};
  }

  void rebuildLayout();
  void substep(double h, StepProfile& prof);
  void applyExternal(double h);
  void computeGoals(double h, std::vector<char>& badBodies, StepProfile& prof);
  void integrate(double h, std::vector<char>& badBodies);
  void damp();
  void collideBodies(double h);
  void collide();
  void prepareContactBody(int s);
};

// ---------------------------------------------------------------------------------------------
// One sub-step.

void World::Data::applyExternal(double h) {
  for (const Force& f : forces) {
    BodySlot& b = slot(f.body);
    const float dv = float(h / b.model->mass[f.particle]);
    for (int a = 0; a < 3; ++a) b.state.v(f.particle, a) += dv * float(f.force[a]);
  }
  for (const auto& [id, drag] : drags) {
    BodySlot& b = slot(drag.body);
    Vec3 point = Vec3::Zero(), pointVelocity = Vec3::Zero();
    double sumW2 = 0;
    for (size_t k = 0; k < drag.particles.size(); ++k) {
      point += drag.weights[k] * b.state.x.row(drag.particles[k]).transpose().cast<double>();
      pointVelocity +=
          drag.weights[k] * b.state.v.row(drag.particles[k]).transpose().cast<double>();
      sumW2 += drag.weights[k] * drag.weights[k];
    }
    // Give the dragged point the velocity that closes `stiffness` of the gap over this sub-step,
    // by the minimum-norm change of the particles' velocities (design.md §6). Replacing the
    // point's velocity, rather than adding to it, keeps the pull from oscillating.
    const Vec3 wanted = (drag.stiffness / h) * (drag.target - point);
    const Vec3 change = (wanted - pointVelocity) / sumW2;
    for (size_t k = 0; k < drag.particles.size(); ++k)
      b.state.v.row(drag.particles[k]) += (drag.weights[k] * change).transpose().cast<float>();
  }
}

void World::Data::computeGoals(double h, std::vector<char>& badBodies, StepProfile& prof) {
  auto t0 = Clock::now();
  const std::vector<GlobalTask>& tasks = layout.tasks;
  const std::vector<GlobalCluster>& clusters = layout.clusters;
  partial.resize(tasks.size());
  // Moments of one task (a fixed range of one cluster's members).
  auto taskMoments = [&](int i) {
    const BodySlot& b = slots[size_t(tasks[size_t(i)].slot)];
    const BodyModel& m = *b.model;
    const MomentTask& task = m.tasks[size_t(tasks[size_t(i)].task)];
    ParticleColumns cols{
        {b.state.x.col(0).data(), b.state.x.col(1).data(), b.state.x.col(2).data()},
        {m.rest.col(0).data(), m.rest.col(1).data(), m.rest.col(2).data()},
        m.matchWeight.data()};
    if (!m.wholeBodyCluster) {
      for (int a = 0; a < 3; ++a) cols.memberQ[a] = m.memberRest.col(a).data();
      cols.memberW = m.memberWeight.data();
    }
    const bool quadratic = b.params.mode == Mode::Quadratic;
    return accumulateMoments(cols, m.wholeBodyCluster ? nullptr : m.members.data(), task.begin,
                             task.end, b.state.ref[size_t(task.cluster)],
                             m.clusterRest[size_t(task.cluster)].centre, quadratic);
  };
  // Large clusters are split into tasks summed first, in parallel; a cluster with one task is
  // summed inside the per-cluster loop below (no second pass over its partial result).
  const std::vector<int>& split = layout.splitTasks;
  const int minParallelTasks = layout.members >= kMinParallelWork ? 2 : INT32_MAX;
  parallelFor(static_cast<int>(split.size()), minParallelTasks,
              [&](int k) { partial[size_t(split[size_t(k)])] = taskMoments(split[size_t(k)]); });
  // Moments of particle groups (bodies with grouped moments), about each group's first particle.
  const std::vector<ParticleBlock>& momentGroupBlocks = layout.momentGroupBlocks;
  parallelFor(static_cast<int>(momentGroupBlocks.size()), minParallelTasks, [&](int i) {
    const ParticleBlock& blk = momentGroupBlocks[size_t(i)];
    BodySlot& b = slots[size_t(blk.slot)];
    const BodyModel& m = *b.model;
    BodyState& s = b.state;
    const ParticleGroups& groups = m.groups;
    ParticleColumns cols{{s.x.col(0).data(), s.x.col(1).data(), s.x.col(2).data()},
                         {m.rest.col(0).data(), m.rest.col(1).data(), m.rest.col(2).data()},
                         m.matchWeight.data()};
    for (int a = 0; a < 3; ++a) cols.memberQ[a] = groups.memberRest.col(a).data();
    cols.memberW = groups.memberWeight.data();
    for (int g = blk.begin; g < blk.end; ++g) {
      const int begin = groups.particleStart[size_t(g)], end = groups.particleStart[size_t(g) + 1];
      s.groupRef[size_t(g)] = s.x.row(groups.particles[size_t(begin)]).transpose();
      s.groupMoments[size_t(g)] =
          accumulateMoments(cols, groups.particles.data(), begin, end, s.groupRef[size_t(g)],
                            groups.restCentre[size_t(g)], false);
    }
  });
  // Per cluster: sum its tasks in order (or its groups' moments), fit, plastic flow, goal
  // transform. Returns true when the cluster produced NaN/Inf; adds the time spent in plastic
  // flow to *plasticTime.
  auto updateCluster = [&](int slotIndex, size_t c, int firstTask, bool grouped,
                           double* plasticTime) {
    BodySlot& b = slots[size_t(slotIndex)];
    const BodyModel& m = *b.model;
    BodyState& s = b.state;
    const int taskCount = m.taskStart[c + 1] - m.taskStart[c];
    ClusterMoments& sum = partial[size_t(firstTask)];  // scratch of this cluster
    if (grouped) {
      sum = clusterMomentsFromGroups(m.groups, int(c), s.groupMoments.data(), s.groupRef.data(),
                                     s.ref[c], m.clusterRest[c].centre);
    } else {
      if (taskCount == 1) sum = taskMoments(firstTask);  // tasks of a cluster summed in order
      for (int t = 1; t < taskCount; ++t) sum += partial[size_t(firstTask + t)];
    }
    const Eigen::Vector3f ref = s.ref[c];
    const bool quadratic = b.params.mode == Mode::Quadratic;
    if (quadratic && !s.shape[c].hasQuadratic)  // switched to quadratic since the last derive
      s.shape[c] = deriveClusterShape(m.clusterRest[c], s.plastic[c], true);
    ClusterFit fit =
        fitCluster(sum, ref, m.clusterRest[c], s.shape[c], s.plastic[c], s.rotation[c]);
    if (!fit.finite) return true;
    if (b.params.plasticity.enabled()) {
      const auto tp = Clock::now();
      const Mat3 R = fit.rotation.matrix();
      const Mat3 stretch = R.transpose() * fit.linear;
      if (updatePlasticDeformation(0.5 * (stretch + stretch.transpose()), h, b.params.plasticity,
                                   s.plastic[c])) {
        s.shape[c] = deriveClusterShape(m.clusterRest[c], s.plastic[c], quadratic);
        fit = fitCluster(sum, ref, m.clusterRest[c], s.shape[c], s.plastic[c], fit.rotation);
      }
      *plasticTime += secondsSince(tp);
    }
    s.rotation[c] = fit.rotation;
    s.ref[c] = fit.centre.cast<float>();
    const GoalTransform goal =
        goalTransform(fit, sum, m.clusterRest[c], s.shape[c], s.plastic[c], b.params);
    storeGoal(goal, s, c);
    return !goal.L.allFinite() || !goal.Q.allFinite() || !goal.t.allFinite();
  };
  plasticSeconds.assign(clusters.size(), 0.0);
  clusterBad.assign(clusters.size(), 0);
  parallelFor(static_cast<int>(clusters.size()), clusters.size() >= 512 ? 2 : INT32_MAX,
              [&](int i) {
                const GlobalCluster& gc = clusters[size_t(i)];
                clusterBad[size_t(i)] = updateCluster(gc.slot, size_t(gc.cluster), gc.firstTask,
                                                      gc.grouped, &plasticSeconds[size_t(i)]);
              });
  // Batches of small clusters (rigid and linear bodies without plastic flow): eight clusters per
  // kernel call; a lane the kernel cannot certify goes through updateCluster.
  const std::vector<GlobalBatch>& batches = layout.batches;
  for (int o : order) {
    BodyState& s = slots[size_t(o)].state;
    const BodyModel& m = *slots[size_t(o)].model;
    if (!s.batchShapeStale || !usesBatches(m, slots[size_t(o)].params)) continue;
    for (size_t k = 0; k < m.batches.size(); ++k)
      for (int l = 0; l < kBatchLanes; ++l) {
        const size_t c = size_t(m.batches[k].cluster[l]);
        setBatchShapeLane(s.batchShape[k], l, s.plastic[c], s.shape[c], m.clusterRest[c].centre);
      }
    s.batchShapeStale = false;
  }
  batchBad.assign(batches.size(), 0);
  // Static split: a thread handles the same batches every sub-step, so the clusters' state and
  // goals stay in its cache (with a dynamic split they moved between cores every sub-step, which
  // cost more than the load balance gained).
  parallelFor(static_cast<int>(batches.size()), 64, [&](int i) {
    const GlobalBatch& gb = batches[size_t(i)];
    BodySlot& b = slots[size_t(gb.slot)];
    const BodyModel& m = *b.model;
    BodyState& s = b.state;
    const ClusterBatch& batch = m.batches[size_t(gb.batch)];
    ClusterBatchLanes& lanes = s.batchLanes[size_t(gb.batch)];
    const float* x[3] = {s.x.col(0).data(), s.x.col(1).data(), s.x.col(2).data()};
    const ClusterBatchGoals goals =
        matchClusterBatch(batch, s.batchShape[size_t(gb.batch)], x, b.params, lanes);
    for (int l = 0; l < batch.count; ++l) {
      const size_t c = size_t(batch.cluster[l]);
      if (goals.nonFinite >> l & 1u) {
        batchBad[size_t(i)] = 1;
      } else if (goals.fallback >> l & 1u) {
        // The general path, from and back to the lane's state.
        laneToCluster(lanes, l, s, c);
        double unusedPlasticTime = 0;  // batched bodies have no plastic flow
        if (updateCluster(gb.slot, c, gb.firstTask + m.taskStart[c], false, &unusedPlasticTime))
          batchBad[size_t(i)] = 1;
        clusterToLane(s, c, lanes, l);
      } else {
        // goalQuad stays zero (set when the body entered the batches).
        Eigen::Matrix<float, 12, 1>& rows = s.goalRows[c];
        for (int a = 0; a < 3; ++a) {
          for (int j = 0; j < 3; ++j) rows[4 * a + j] = goals.L[3 * a + j][l];
          rows[4 * a + 3] = goals.t[a][l];
        }
      }
    }
  });
  for (size_t i = 0; i < batches.size(); ++i)
    if (batchBad[i]) badBodies[size_t(batches[i].slot)] = 1;
  // The plastic path may have changed Sᵖ of clusters that a later switch puts into batches.
  for (int o : order)
    if (slots[size_t(o)].params.plasticity.enabled()) slots[size_t(o)].state.batchShapeStale = true;
  double plasticTotal = 0;
  for (size_t i = 0; i < clusters.size(); ++i) {
    plasticTotal += plasticSeconds[i];
    if (clusterBad[i]) badBodies[size_t(clusters[i].slot)] = 1;
  }
  // Plastic time is measured inside the cluster loop (summed over threads); report it apart.
  const double total = secondsSince(t0);
  prof.plasticity += std::min(plasticTotal, total);
  prof.goals += total - std::min(plasticTotal, total);
}

namespace {

// Müller's update of particle i toward goal g: v += α(g − x)/h + h·gravity, x += h·v, with
// pull = α/h and (gvx, gvy, gvz) = h·gravity. Returns 1 if a non-finite value appeared: x − x is
// 0 for finite x and NaN otherwise, and the test vectorises as an integer OR.
[[gnu::always_inline]] inline int mullerUpdate(float* __restrict px, float* __restrict py,
                                               float* __restrict pz, float* __restrict vx,
                                               float* __restrict vy, float* __restrict vz, int i,
                                               float g0, float g1, float g2, float hf, float pull,
                                               float gvx, float gvy, float gvz) {
  const float nvx = vx[i] + pull * (g0 - px[i]) + gvx;
  const float nvy = vy[i] + pull * (g1 - py[i]) + gvy;
  const float nvz = vz[i] + pull * (g2 - pz[i]) + gvz;
  const float nx = px[i] + hf * nvx, ny = py[i] + hf * nvy, nz = pz[i] + hf * nvz;
  vx[i] = nvx;
  vy[i] = nvy;
  vz[i] = nvz;
  px[i] = nx;
  py[i] = ny;
  pz[i] = nz;
  return ((nx - nx) + (ny - ny) + (nz - nz) + (nvx - nvx) + (nvy - nvy) + (nvz - nvz)) != 0.0f;
}

// v += α(g − x)/h + h·gravity ; x += h·v for particles [begin, end), with g from goal(i, g).
// Plain restrict pointers and a goal functor taken by value keep this loop vectorised.
// Returns non-zero if a non-finite value appeared.
template <typename Goal>
int integrateRange(float* __restrict px, float* __restrict py, float* __restrict pz,
                   float* __restrict vx, float* __restrict vy, float* __restrict vz, int begin,
                   int end, float hf, float pull, float gvx, float gvy, float gvz, Goal goal) {
  int bad = 0;
  for (int i = begin; i < end; ++i) {
    float g[3];
    goal(i, g);
    bad |= mullerUpdate(px, py, pz, vx, vy, vz, i, g[0], g[1], g[2], hf, pull, gvx, gvy, gvz);
  }
  return bad;
}

// The whole-body-cluster kernels: the goal is one transform, so the loop is pure streaming.
// Written as plain functions of restrict pointers: that is what GCC vectorises.
int integrateLinearRange(float* __restrict px, float* __restrict py, float* __restrict pz,
                         float* __restrict vx, float* __restrict vy, float* __restrict vz,
                         const float* __restrict rx, const float* __restrict ry,
                         const float* __restrict rz, int begin, int end, const GoalTransform& T,
                         float hf, float pull, float gvx, float gvy, float gvz) {
  const float L00 = T.L(0, 0), L01 = T.L(0, 1), L02 = T.L(0, 2);
  const float L10 = T.L(1, 0), L11 = T.L(1, 1), L12 = T.L(1, 2);
  const float L20 = T.L(2, 0), L21 = T.L(2, 1), L22 = T.L(2, 2);
  const float tx = T.t.x(), ty = T.t.y(), tz = T.t.z();
  int bad = 0;
  for (int i = begin; i < end; ++i) {
    const float x = rx[i], y = ry[i], z = rz[i];
    const float g0 = L00 * x + L01 * y + L02 * z + tx;
    const float g1 = L10 * x + L11 * y + L12 * z + ty;
    const float g2 = L20 * x + L21 * y + L22 * z + tz;
    bad |= mullerUpdate(px, py, pz, vx, vy, vz, i, g0, g1, g2, hf, pull, gvx, gvy, gvz);
  }
  return bad;
}

int integrateQuadraticRange(float* __restrict px, float* __restrict py, float* __restrict pz,
                            float* __restrict vx, float* __restrict vy, float* __restrict vz,
                            const float* __restrict rx, const float* __restrict ry,
                            const float* __restrict rz, int begin, int end, const GoalTransform& T,
                            float hf, float pull, float gvx, float gvy, float gvz) {
  float C[3][10];  // per row: L (3), Q (6), t
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) C[a][j] = T.L(a, j);
    for (int j = 0; j < 6; ++j) C[a][3 + j] = T.Q(a, j);
    C[a][9] = T.t[a];
  }
  int bad = 0;
  for (int i = begin; i < end; ++i) {
    const float x = rx[i], y = ry[i], z = rz[i];
    const float xx = x * x, yy = y * y, zz = z * z, xy = x * y, yz = y * z, zx = z * x;
    float g[3];
    for (int a = 0; a < 3; ++a)
      g[a] = C[a][0] * x + C[a][1] * y + C[a][2] * z + C[a][3] * xx + C[a][4] * yy + C[a][5] * zz +
             C[a][6] * xy + C[a][7] * yz + C[a][8] * zx + C[a][9];
    bad |= mullerUpdate(px, py, pz, vx, vy, vz, i, g[0], g[1], g[2], hf, pull, gvx, gvy, gvz);
  }
  return bad;
}

// g = (L·r + t + Q·mono(r))·invCount for summed goal rows [L | t] and quadratic parts Q.
[[gnu::always_inline]] inline void evaluateQuadraticGoal(const Eigen::Matrix<float, 12, 1>& sum,
                                                         const Eigen::Matrix<float, 3, 6>& Q,
                                                         float rx, float ry, float rz,
                                                         float invCount, float* g) {
  Eigen::Matrix3f L;
  Eigen::Vector3f t;
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) L(a, j) = sum[4 * a + j];
    t[a] = sum[4 * a + 3];
  }
  const Eigen::Vector3f r(rx, ry, rz);
  Eigen::Vector3f goal = L * r + t;
  goal += Q * monomials<float>(r);
  goal *= invCount;
  g[0] = goal.x();
  g[1] = goal.y();
  g[2] = goal.z();
}

// groupRows/groupQuad of groups [begin, end) of a body (the quadratic parts only if `quadratic`).
void sumGroupGoals(const BodyModel& m, BodyState& s, bool quadratic, int begin, int end) {
  for (int g = begin; g < end; ++g) {
    Eigen::Matrix<float, 12, 1> sum = Eigen::Matrix<float, 12, 1>::Zero();
    Eigen::Matrix<float, 3, 6> Q = Eigen::Matrix<float, 3, 6>::Zero();
    for (int k = m.groups.clusterStart[size_t(g)]; k < m.groups.clusterStart[size_t(g) + 1]; ++k) {
      const size_t c = size_t(m.groups.clusters[size_t(k)]);
      sum += s.goalRows[c];
      if (quadratic) Q += s.goalQuad[c];
    }
    s.groupRows[size_t(g)] = sum;
    if (quadratic) s.groupQuad[size_t(g)] = Q;
  }
}

// Integrates particles [begin, end) of one body; returns true if a non-finite value appeared.
bool integrateBlock(const BodyModel& m, BodyState& s, const BodyParams& params, const Vec3& gravity,
                    double h, int begin, int end) {
  float* px = s.x.col(0).data();
  float* py = s.x.col(1).data();
  float* pz = s.x.col(2).data();
  float* vx = s.v.col(0).data();
  float* vy = s.v.col(1).data();
  float* vz = s.v.col(2).data();
  const float* rx = m.rest.col(0).data();
  const float* ry = m.rest.col(1).data();
  const float* rz = m.rest.col(2).data();
  const float hf = float(h);
  const float pull = float(params.alpha / h);
  const float gvx = float(h * gravity.x()), gvy = float(h * gravity.y()),
              gvz = float(h * gravity.z());
  const bool quadratic = params.mode == Mode::Quadratic;
  auto run = [&](auto goal) {
    return integrateRange(px, py, pz, vx, vy, vz, begin, end, hf, pull, gvx, gvy, gvz, goal) != 0;
  };
  if (m.wholeBodyCluster) {
    auto kernel = quadratic ? integrateQuadraticRange : integrateLinearRange;
    return kernel(px, py, pz, vx, vy, vz, rx, ry, rz, begin, end, goalOf(s, 0), hf, pull, gvx, gvy,
                  gvz) != 0;
  }
  const int* start = m.particleStart.data();
  const int* clusterOf = m.particleClusters.data();
  const float* invCount = m.invCount.data();
  const Eigen::Matrix<float, 12, 1>* rows = s.goalRows.data();
  const Eigen::Matrix<float, 3, 6>* quads = s.goalQuad.data();
  if (!m.groups.empty()) {  // the sums are formed per group already
    const int* groupOf = m.groups.groupOf.data();
    const Eigen::Matrix<float, 12, 1>* groupRows = s.groupRows.data();
    const Eigen::Matrix<float, 3, 6>* groupQuad = s.groupQuad.data();
    if (!quadratic)
      return run([=](int i, float* g) {
        const Eigen::Matrix<float, 12, 1>& sum = groupRows[groupOf[i]];
        const float x = rx[i], y = ry[i], z = rz[i];
        for (int a = 0; a < 3; ++a)
          g[a] = (sum[4 * a] * x + sum[4 * a + 1] * y + sum[4 * a + 2] * z + sum[4 * a + 3]) *
                 invCount[i];
      });
    return run([=](int i, float* g) {
      evaluateQuadraticGoal(groupRows[groupOf[i]], groupQuad[groupOf[i]], rx[i], ry[i], rz[i],
                            invCount[i], g);
    });
  }
  if (!quadratic) {
    return run([=](int i, float* g) {
      // Average the goal transforms of the particle's clusters, then evaluate once.
      Eigen::Matrix<float, 12, 1> sum = Eigen::Matrix<float, 12, 1>::Zero();
      for (int k = start[i]; k < start[i + 1]; ++k) sum += rows[clusterOf[k]];
      const float x = rx[i], y = ry[i], z = rz[i];
      for (int a = 0; a < 3; ++a)
        g[a] = (sum[4 * a] * x + sum[4 * a + 1] * y + sum[4 * a + 2] * z + sum[4 * a + 3]) *
               invCount[i];
    });
  }
  return run([=](int i, float* g) {
    // Average the goal transforms of the particle's clusters, then evaluate once.
    Eigen::Matrix<float, 12, 1> sum = Eigen::Matrix<float, 12, 1>::Zero();
    Eigen::Matrix<float, 3, 6> Q = Eigen::Matrix<float, 3, 6>::Zero();
    for (int k = start[i]; k < start[i + 1]; ++k) {
      sum += rows[clusterOf[k]];
      Q += quads[clusterOf[k]];
    }
    evaluateQuadraticGoal(sum, Q, rx[i], ry[i], rz[i], invCount[i], g);
  });
}

}  // namespace

void World::Data::integrate(double h, std::vector<char>& badBodies) {
  const std::vector<ParticleBlock>& blocks = layout.blocks;
  blockBad.assign(blocks.size(), 0);
  const long long work = layout.particles + layout.members;
  // Goal sums per particle group, in the order each particle would form them (same bits).
  const std::vector<ParticleBlock>& groupBlocks = layout.groupBlocks;
  parallelFor(static_cast<int>(groupBlocks.size()), work >= kMinParallelIntegration ? 2 : INT32_MAX,
              [&](int i) {
                const ParticleBlock& blk = groupBlocks[size_t(i)];
                BodySlot& b = slots[size_t(blk.slot)];
                sumGroupGoals(*b.model, b.state, b.params.mode == Mode::Quadratic, blk.begin,
                              blk.end);
              });
  parallelFor(
      static_cast<int>(blocks.size()), work >= kMinParallelIntegration ? 2 : INT32_MAX, [&](int i) {
        const ParticleBlock& blk = blocks[size_t(i)];
        BodySlot& b = slots[size_t(blk.slot)];
        blockBad[size_t(i)] =
            integrateBlock(*b.model, b.state, b.params, settings.gravity, h, blk.begin, blk.end);
      });
  for (size_t i = 0; i < blocks.size(); ++i)
    if (blockBad[i]) badBodies[size_t(blocks[i].slot)] = 1;
  // Pinned particles stay where they started.
  for (int s : order) {
    BodySlot& b = slots[size_t(s)];
    for (int p : b.model->pinned) {
      b.state.x.row(p) = b.model->startPositions.row(p);
      b.state.v.row(p).setZero();
    }
  }
}

void World::Data::damp() {
  std::vector<int> damped;
  for (int s : order)
    if (slots[size_t(s)].params.damping > 0.0) damped.push_back(s);
  parallelFor(static_cast<int>(damped.size()),
              layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX, [&](int k) {
                BodySlot& b = slots[size_t(damped[size_t(k)])];
                const BodyModel& m = *b.model;
                MatX3f& x = b.state.x;
                MatX3f& v = b.state.v;
                const int n = m.particleCount();
                // Fit the rigid motion (linear and angular velocity) that has the body's momenta.
                const MassProperties mp = massProperties(x.col(0).data(), x.col(1).data(),
                                                         x.col(2).data(), m.mass.data(), n);
                const Vec3 xc = mp.centre;
                Vec3 vc = Vec3::Zero();
                for (int i = 0; i < n; ++i)
                  vc += double(m.mass[i]) * v.row(i).transpose().cast<double>();
                vc /= m.totalMass;
                Vec3 L = Vec3::Zero();
                for (int i = 0; i < n; ++i) {
                  const Vec3 r = x.row(i).transpose().cast<double>() - xc;
                  L += double(m.mass[i]) * r.cross(v.row(i).transpose().cast<double>());
                }
                const Vec3 omega = mp.inverseInertia * L;
                const double kd = b.params.damping;
                for (int i = 0; i < n; ++i) {
                  const Vec3 r = x.row(i).transpose().cast<double>() - xc;
                  const Vec3 vi = v.row(i).transpose().cast<double>();
                  const Vec3 rigid = vc + omega.cross(r);
                  v.row(i) = (vi + kd * (rigid - vi)).transpose().cast<float>();
                }
              });
}

void World::Data::prepareContactBody(int s) {
  BodySlot& b = slots[size_t(s)];
  const BodyModel& m = *b.model;
  ContactScratch& cs = contactScratch[size_t(s)];
  ContactBody& view = cs.view;
  for (int a = 0; a < 3; ++a) {
    view.x[a] = b.state.x.col(a).data();
    view.v[a] = b.state.v.col(a).data();
  }
  view.mass = m.mass.data();
  view.invMass = m.contactInvMass.data();
  view.count = m.particleCount();
  view.triangles = &m.surface;
  view.topology = &m.surfaceTopology;
  view.grid = &cs.grid;
  view.gap = kContactGap * m.spacing;
  view.meanVelocity = cs.meanVelocity;
  view.maxRelativeSpeed = cs.maxRelativeSpeed;
  // A stiff body answers a contact mostly as a whole (see sim/body_contact.h); one held by
  // pinned particles cannot move as a whole.
  prepareRigidResponse(view, m.pinned.empty() ? float(b.params.alpha) : 0.0f);
}

void World::Data::collideBodies(double h) {
  contactCount = 0;
  if (!settings.bodyContact || order.size() < 2) return;
  contactScratch.resize(slots.size());
  const int minParallel = layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX;
  // Bounds and speeds of every body (serial: a light pass, not worth a fork/join).
  for (int k = 0; k < static_cast<int>(order.size()); ++k) {
    const int s = order[size_t(k)];
    const BodyState& st = slots[size_t(s)].state;
    ContactScratch& cs = contactScratch[size_t(s)];
    const BodyModel& m = *slots[size_t(s)].model;
    cs.box.setEmpty();
    Eigen::Vector3f momentum = Eigen::Vector3f::Zero();
    for (int i = 0; i < st.x.rows(); ++i) {
      cs.box.extend(st.x.row(i).transpose());
      momentum += m.mass[i] * st.v.row(i).transpose();
    }
    cs.meanVelocity = momentum / float(m.totalMass);
    float speed2 = 0, relative2 = 0;
    for (int i = 0; i < st.x.rows(); ++i) {
      speed2 = std::max(speed2, st.v.row(i).squaredNorm());
      relative2 = std::max(relative2, (st.v.row(i).transpose() - cs.meanVelocity).squaredNorm());
    }
    cs.maxSpeed = std::sqrt(speed2);
    cs.maxRelativeSpeed = std::sqrt(relative2);
    cs.obstacle = false;
    cs.involved = false;
  }
  // A particle moves at most h·maxSpeed in this sub-step, and so does the surface it meets.
  // Boxes grow by the grid's base reach (a quarter spacing) plus twice that travel, so no pair
  // that can touch within the sub-step is missed; each particle then looks only as far as its
  // own speed needs (findContacts).
  float maxSpeed = 0;
  for (int s : order) maxSpeed = std::max(maxSpeed, contactScratch[size_t(s)].maxSpeed);
  const float travel = 2.0f * float(h) * maxSpeed;
  auto reachOf = [&](int s) {
    const BodyModel& m = *slots[size_t(s)].model;
    return m.surface.empty() ? 0.0f : 0.25f * m.spacing;
  };
  auto grown = [&](int s) {
    Eigen::AlignedBox3f box = contactScratch[size_t(s)].box;
    box.min().array() -= reachOf(s) + travel;
    box.max().array() += reachOf(s) + travel;
    return box;
  };

  // Broad phase: sweep over the grown boxes sorted along x; pairs come out in creation order.
  std::vector<int>& sweep = contactSweep;
  std::vector<Eigen::AlignedBox3f>& boxes = contactBoxes;
  std::vector<int>& rank = contactRank;
  sweep.assign(order.begin(), order.end());
  boxes.resize(slots.size());
  for (int s : order) boxes[size_t(s)] = grown(s);
  rank.resize(slots.size());
  for (size_t k = 0; k < order.size(); ++k) rank[size_t(order[k])] = int(k);
  std::sort(sweep.begin(), sweep.end(), [&](int a, int b) {
    const float ma = boxes[size_t(a)].min().x(), mb = boxes[size_t(b)].min().x();
    return ma != mb ? ma < mb : rank[size_t(a)] < rank[size_t(b)];
  });
  contactPairs.clear();
  for (size_t i = 0; i < sweep.size(); ++i) {
    const int a = sweep[i];
    for (size_t j = i + 1; j < sweep.size(); ++j) {
      const int b = sweep[j];
      if (boxes[size_t(b)].min().x() > boxes[size_t(a)].max().x()) break;
      if (!boxes[size_t(a)].intersects(boxes[size_t(b)])) continue;
      const int first = rank[size_t(a)] < rank[size_t(b)] ? a : b;
      const int second = first == a ? b : a;
      if (!slots[size_t(second)].model->surface.empty()) contactPairs.push_back({first, second});
      if (!slots[size_t(first)].model->surface.empty()) contactPairs.push_back({second, first});
    }
  }
  std::sort(contactPairs.begin(), contactPairs.end(),
            [&](const ContactPair& x, const ContactPair& y) {
              const int xa = std::min(rank[size_t(x.probe)], rank[size_t(x.obstacle)]);
              const int ya = std::min(rank[size_t(y.probe)], rank[size_t(y.obstacle)]);
              if (xa != ya) return xa < ya;
              const int xb = std::max(rank[size_t(x.probe)], rank[size_t(x.obstacle)]);
              const int yb = std::max(rank[size_t(y.probe)], rank[size_t(y.obstacle)]);
              if (xb != yb) return xb < yb;
              return rank[size_t(x.probe)] < rank[size_t(y.probe)];
            });
  if (contactPairs.empty()) return;

  // Each obstacle's grid covers only where its probes' particles are.
  std::vector<int>& obstacles = contactObstacles;
  std::vector<int>& involved = contactInvolved;
  obstacles.clear();
  involved.clear();
  for (const ContactPair& p : contactPairs) {
    ContactScratch& cs = contactScratch[size_t(p.obstacle)];
    if (!cs.obstacle) {
      obstacles.push_back(p.obstacle);
      cs.region.setEmpty();
    }
    cs.obstacle = true;
    Eigen::AlignedBox3f probeBox = contactScratch[size_t(p.probe)].box;
    probeBox.min().array() -= travel;
    probeBox.max().array() += travel;
    cs.region.extend(probeBox);
    for (int s : {p.probe, p.obstacle})
      if (!contactScratch[size_t(s)].involved) {
        contactScratch[size_t(s)].involved = true;
        involved.push_back(s);
      }
  }
  std::sort(involved.begin(), involved.end(),
            [&](int a, int b) { return rank[size_t(a)] < rank[size_t(b)]; });
  for (int s : involved) prepareContactBody(s);
  parallelFor(static_cast<int>(obstacles.size()), minParallel, [&](int k) {
    const int s = obstacles[size_t(k)];
    const BodyModel& m = *slots[size_t(s)].model;
    const MatX3f& x = slots[size_t(s)].state.x;
    ContactScratch& cs = contactScratch[size_t(s)];
    // The grid is kept while the surface has moved less than a quarter spacing since it was
    // built and the region still fits: lookups then widen by that drift (findContacts), so
    // resting and slowly moving bodies skip the rebuild.
    float drift = 0;
    const bool reusable = cs.gridModel == &m && cs.gridRegion.contains(cs.region);
    if (reusable) drift = std::sqrt((x - cs.gridPositions).rowwise().squaredNorm().maxCoeff());
    if (!reusable || !(drift <= kGridSlack * m.spacing)) {
      cs.gridRegion = cs.region;
      cs.gridRegion.min().array() -= kGridSlack * m.spacing;
      cs.gridRegion.max().array() += kGridSlack * m.spacing;
      // Cells of one spacing: a triangle grown by its reach (a quarter spacing) lands in at most
      // 3×3×3 cells, and a cell holds a dozen or two triangles (most rejected by their boxes).
      cs.grid.build(m.surface, x.col(0).data(), x.col(1).data(), x.col(2).data(), reachOf(s),
                    m.spacing, cs.gridRegion);
      cs.gridPositions = x;
      cs.gridModel = &m;
      drift = 0;
    }
    cs.view.gridDrift = drift;
  });

  // Narrow phase reads only, so pairs run in parallel; contacts then resolve one after another
  // in pair order (Gauss–Seidel), which makes the result independent of the thread count.
  pairContacts.resize(contactPairs.size());
  parallelFor(static_cast<int>(contactPairs.size()), minParallel, [&](int k) {
    const ContactPair& p = contactPairs[size_t(k)];
    pairContacts[size_t(k)].clear();
    findContacts(contactScratch[size_t(p.probe)].view, contactScratch[size_t(p.obstacle)].view,
                 float(h), pairContacts[size_t(k)]);
  });
  // Several sweeps: a body pressed by several others (a stack) needs the corrections to travel
  // through it, and each sweep sees the previous sweeps' results.
  const float friction = float(settings.contactFriction);
  for (int pass = 0; pass < kContactSweeps; ++pass)
    for (size_t k = 0; k < contactPairs.size(); ++k) {
      ContactBody& probe = contactScratch[size_t(contactPairs[k].probe)].view;
      ContactBody& obstacle = contactScratch[size_t(contactPairs[k].obstacle)].view;
      for (const Contact& c : pairContacts[k]) resolveContact(probe, obstacle, c, friction);
    }
  for (const auto& list : pairContacts) contactCount += static_cast<int>(list.size());
  for (int s : involved) applyRigidResponse(contactScratch[size_t(s)].view);
}

void World::Data::collide() {
  if (colliders.empty()) return;
  contactScratch.resize(slots.size());
  // Bodies are independent here: each runs its own sweeps, so any thread split gives the same
  // result. Like body–body contacts, a contact acts partly on the body's rigid motion (see
  // sim/body_contact.h): a stiff body lands and rests as a whole instead of bouncing off the
  // few particles that touch.
  parallelFor(static_cast<int>(order.size()),
              layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX, [&](int k) {
                const int s = order[size_t(k)];
                ContactScratch& cs = contactScratch[size_t(s)];
                const BodyState& st = slots[size_t(s)].state;
                cs.staticContacts.clear();
                for (int p = 0; p < st.x.rows(); ++p) {
                  const Vec3 x = st.x.row(p).transpose().cast<double>();
                  for (size_t c = 0; c < colliders.size(); ++c) {
                    Vec3 n;
                    if (colliderDistance(colliders[c], x, &n) < 0.0)
                      cs.staticContacts.push_back({p, int(c)});
                  }
                }
                if (cs.staticContacts.empty()) return;
                prepareContactBody(s);
                ContactBody& view = cs.view;
                for (int pass = 0; pass < kContactSweeps; ++pass)
                  for (const auto& [p, c] : cs.staticContacts) {
                    const Collider& collider = colliders[size_t(c)];
                    Vec3 n;
                    const double d =
                        colliderDistance(collider, correctedPosition(view, p).cast<double>(), &n);
                    resolveStaticContact(view, p, n.cast<float>(), float(std::min(d, 0.0)),
                                         float(collider.friction));
                  }
                applyRigidResponse(view);
              });
}

namespace {
// Pieces [0, count) of body `slot` in blocks of `size`.
void appendBlocks(std::vector<ParticleBlock>& blocks, int slot, int count, int size) {
  for (int b = 0; b < count; b += size) blocks.push_back({slot, b, std::min(count, b + size)});
}
}  // namespace

void World::Data::rebuildLayout() {
  layout = WorkLayout{};
  for (int s : order) {
    const BodyModel& m = *slots[size_t(s)].model;
    const int base = static_cast<int>(layout.tasks.size());
    for (int t = 0; t < static_cast<int>(m.tasks.size()); ++t) layout.tasks.push_back({s, t});
    std::vector<char> inBatch(size_t(m.clusterCount()), 0);
    BodyState& state = slots[size_t(s)].state;
    const bool batched = usesBatches(m, slots[size_t(s)].params);
    if (batched && !state.lanesHoldState) lanesFromClusters(m, state);
    if (!batched && state.lanesHoldState) clustersFromLanes(m, state);
    state.lanesHoldState = batched;
    if (batched) {
      // The batched kernel writes only [L | t]; rigid and linear goals have no quadratic part.
      for (auto& Q : state.goalQuad) Q.setZero();
      for (int k = 0; k < static_cast<int>(m.batches.size()); ++k) {
        layout.batches.push_back({s, k, base});
        for (int l = 0; l < m.batches[size_t(k)].count; ++l)
          inBatch[size_t(m.batches[size_t(k)].cluster[l])] = 1;
      }
    }
    const bool grouped = usesGroupedMoments(m, slots[size_t(s)].params);
    for (int c = 0; c < m.clusterCount(); ++c) {
      if (!inBatch[size_t(c)])
        layout.clusters.push_back({s, c, base + m.taskStart[size_t(c)], grouped});
      if (!grouped && m.taskStart[size_t(c) + 1] - m.taskStart[size_t(c)] > 1)
        for (int t = m.taskStart[size_t(c)]; t < m.taskStart[size_t(c) + 1]; ++t)
          layout.splitTasks.push_back(base + t);
    }
    const int n = m.particleCount();
    // Clustered bodies in smaller blocks: a particle there costs a sum over its clusters, and
    // blocks that follow the clusters' split over threads read goals their own thread wrote.
    const int block = m.wholeBodyCluster ? kParticlesPerBlock : kClusteredParticlesPerBlock;
    appendBlocks(layout.blocks, s, n, block);
    const int groups = m.groups.count();
    appendBlocks(layout.groupBlocks, s, groups, kClusteredParticlesPerBlock);
    state.groupRows.resize(size_t(groups));
    state.groupQuad.resize(size_t(groups));
    if (grouped) {
      appendBlocks(layout.momentGroupBlocks, s, groups, kClusteredParticlesPerBlock);
      state.groupMoments.resize(size_t(groups));
      state.groupRef.resize(size_t(groups));
    }
    layout.members += static_cast<long long>(m.members.size());
    layout.particles += n;
  }
  layoutDirty = false;
}

void World::Data::substep(double h, StepProfile& prof) {
  if (layoutDirty) rebuildLayout();
  auto t = Clock::now();
  applyExternal(h);
  prof.external += secondsSince(t);

  bad.assign(slots.size(), 0);
  computeGoals(h, bad, prof);

  t = Clock::now();
  integrate(h, bad);
  prof.integrate += secondsSince(t);

  t = Clock::now();
  damp();
  prof.damping += secondsSince(t);

  t = Clock::now();
  collideBodies(h);
  prof.contacts += secondsSince(t);

  t = Clock::now();
  collide();
  prof.collide += secondsSince(t);

  t = Clock::now();
  for (int s : order) {
    if (!bad[size_t(s)]) continue;
    BodySlot& b = slots[size_t(s)];
    resetBodyState(*b.model, b.state);
    events.push_back({handleOf(s), "body '" + b.model->name + "' produced NaN/Inf (time " +
                                       str(time) + " s); it was reset to its start state"});
  }
  prof.check += secondsSince(t);
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
  if (!s.gravity.allFinite() || s.gravity.norm() > 1e4)
    throw std::invalid_argument("gravity: must be finite and at most 1e4 m/s²");
  if (!(s.timeStep > 0.0 && s.timeStep <= 10.0))
    throw std::invalid_argument("timeStep: must be in (0, 10] seconds, got " + str(s.timeStep));
  if (s.substeps < 1 || s.substeps > 1000)
    throw std::invalid_argument("substeps: must be in [1, 1000], got " +
                                std::to_string(s.substeps));
  if (!(s.contactFriction >= 0.0 && s.contactFriction <= 1e3))
    throw std::invalid_argument("contactFriction: must be in [0, 1000], got " +
                                str(s.contactFriction));
  d_->settings = s;
}

void World::addCollider(const Collider& c) {
  auto finite = [](const Vec3& v) { return v.allFinite(); };
  if (!(c.friction >= 0.0 && c.friction <= 1e3))
    throw std::invalid_argument("friction: must be in [0, 1000], got " + str(c.friction));
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
}

void World::clearColliders() {
  d_->colliders.clear();
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
  if (!def.masses.empty()) {
    if (int(def.masses.size()) != n)
      throw std::invalid_argument("masses: " + std::to_string(def.masses.size()) + " values for " +
                                  std::to_string(n) + " particles");
    for (int i = 0; i < n; ++i)
      if (!(def.masses[size_t(i)] > 0.0) || !std::isfinite(def.masses[size_t(i)]))
        throw std::invalid_argument("masses[" + std::to_string(i) + "]: must be > 0");
  } else if (!(def.totalMass > 0.0) || !std::isfinite(def.totalMass)) {
    throw std::invalid_argument("mass: must be > 0 kg, got " + str(def.totalMass));
  }
  if (!def.velocity.allFinite()) throw std::invalid_argument("velocity: not finite");
  for (int p : def.pinned)
    if (p < 0 || p >= n)
      throw std::invalid_argument("pinned: particle index " + std::to_string(p) +
                                  " out of range [0, " + std::to_string(n) + ")");
  validateParams(def.params);
  if (!def.surface.empty()) {
    // Interior particles (not on the surface) are allowed: validate the surface's own points.
    std::vector<int> remap(size_t(n), -1);
    cage::TriangleMesh mesh;
    for (size_t t = 0; t < def.surface.size(); ++t)
      for (int i : def.surface[t]) {
        if (i < 0 || i >= n)
          throw std::invalid_argument("surface[" + std::to_string(t) + "]: particle index " +
                                      std::to_string(i) + " out of range [0, " + std::to_string(n) +
                                      ")");
        if (remap[size_t(i)] < 0) {
          remap[size_t(i)] = static_cast<int>(mesh.vertices.size());
          mesh.vertices.push_back(def.positions[size_t(i)]);
        }
      }
    for (const auto& t : def.surface)
      mesh.triangles.push_back({remap[size_t(t[0])], remap[size_t(t[1])], remap[size_t(t[2])]});
    try {
      cage::validateCage(mesh, def.name);
    } catch (const std::exception& e) {
      throw std::invalid_argument(std::string("surface: ") + e.what());
    }
  }

  BodySlot slot;
  slot.model = buildModel(def, def.clusters, nullptr);  // throws on bad clusters
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
  d_->layoutDirty = true;
  return d_->handleOf(static_cast<int>(index));
}

void World::removeBody(BodyHandle h) {
  BodySlot& s = d_->slot(h);
  s.alive = false;
  ++s.generation;
  s.model.reset();
  s.state = BodyState{};
  d_->order.erase(std::find(d_->order.begin(), d_->order.end(), int(h.index)));
  d_->layoutDirty = true;
  for (auto it = d_->drags.begin(); it != d_->drags.end();)
    it = it->second.body == h ? d_->drags.erase(it) : std::next(it);
  // Forces queued for the removed body die with it (step() must not meet a stale handle).
  auto& forces = d_->forces;
  forces.erase(
      std::remove_if(forces.begin(), forces.end(), [&](const Force& f) { return f.body == h; }),
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
  if (usesBatches(*s.model, p) != usesBatches(*s.model, s.params) ||
      usesGroupedMoments(*s.model, p) != usesGroupedMoments(*s.model, s.params))
    d_->layoutDirty = true;
  s.params = p;
}

const ClusterDef& World::clusterDef(BodyHandle h) const {
  return d_->slot(h).model->clusterDef;
}

void World::setClusters(BodyHandle h, const ClusterDef& clusters) {
  BodySlot& s = d_->slot(h);
  auto model = buildModel(BodyDef{}, clusters, s.model);  // throws; body unchanged then
  s.model = std::move(model);
  resetClusterState(*s.model, s.state);
  d_->layoutDirty = true;
}

int World::clusterCount(BodyHandle h) const {
  return d_->slot(h).model->clusterCount();
}

std::vector<std::vector<int>> World::clusterMembers(BodyHandle h) const {
  const BodyModel& m = *d_->slot(h).model;
  std::vector<std::vector<int>> out(size_t(m.clusterCount()));
  for (int c = 0; c < m.clusterCount(); ++c)
    out[size_t(c)].assign(m.members.begin() + m.memberStart[size_t(c)],
                          m.members.begin() + m.memberStart[size_t(c) + 1]);
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
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < s.model->particleCount(); ++i)
    c += double(s.model->mass[i]) * s.state.x.row(i).transpose().cast<double>();
  return c / s.model->totalMass;
}

Vec3 World::linearMomentum(BodyHandle h) const {
  const BodySlot& s = d_->slot(h);
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < s.model->particleCount(); ++i)
    p += double(s.model->mass[i]) * s.state.v.row(i).transpose().cast<double>();
  return p;
}

Vec3 World::angularMomentum(BodyHandle h, const Vec3& about) const {
  const BodySlot& s = d_->slot(h);
  Vec3 L = Vec3::Zero();
  for (int i = 0; i < s.model->particleCount(); ++i) {
    const Vec3 r = s.state.x.row(i).transpose().cast<double>() - about;
    L += double(s.model->mass[i]) * r.cross(s.state.v.row(i).transpose().cast<double>());
  }
  return L;
}

void World::setState(BodyHandle h, const Eigen::MatrixX3d& x, const Eigen::MatrixX3d& v) {
  BodySlot& s = d_->slot(h);
  const int n = s.model->particleCount();
  if (x.rows() != n || v.rows() != n)
    throw std::invalid_argument("setState: expected " + std::to_string(n) + " rows");
  if (!x.allFinite() || !v.allFinite()) throw std::invalid_argument("setState: not finite");
  s.state.x = x.cast<float>();
  s.state.v = v.cast<float>();
}

Eigen::MatrixX3d World::goals(BodyHandle h) const {
  const BodySlot& b = d_->slot(h);
  const BodyModel& m = *b.model;
  Eigen::MatrixX3d out(m.particleCount(), 3);
  for (int i = 0; i < m.particleCount(); ++i) {
    Vec3 g = Vec3::Zero();
    const Vec3 r = m.rest.row(i).transpose().cast<double>();
    for (int k = m.particleStart[size_t(i)]; k < m.particleStart[size_t(i) + 1]; ++k) {
      const GoalTransform T = goalOf(b.state, size_t(m.particleClusters[size_t(k)]));
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
  return b.state.plastic[size_t(cluster)];
}

void World::addForce(BodyHandle h, int particle, const Vec3& force) {
  const BodySlot& b = d_->slot(h);
  if (particle < 0 || particle >= b.model->particleCount())
    throw std::invalid_argument("addForce: particle index out of range");
  if (!force.allFinite()) throw std::invalid_argument("addForce: force not finite");
  d_->forces.push_back({h, particle, force});
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
  requireRange("drag stiffness", drag.stiffness, 0.0, 1.0);
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
  requireRange("drag stiffness", stiffness, 0.0, 1.0);
  it->second.stiffness = stiffness;
}

void World::removeDrag(int id) {
  d_->drags.erase(id);
}

void World::step() {
  step(d_->settings.timeStep);
}

void World::step(double dt) {
  if (!(dt > 0.0 && dt <= 10.0))
    throw std::invalid_argument("step: dt must be in (0, 10] seconds, got " + str(dt));
  const int n = d_->settings.substeps;
  StepProfile prof;
  for (int i = 0; i < n; ++i) d_->substep(dt / n, prof);
  d_->forces.clear();
  d_->profile = prof;
  d_->time += dt;
}

void World::reset() {
  for (int s : d_->order) {
    BodySlot& b = d_->slots[size_t(s)];
    resetBodyState(*b.model, b.state);
  }
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
    const BodyState& st = d_->slots[size_t(s)].state;
    mix(st.x.data(), sizeof(float) * size_t(st.x.size()));
    mix(st.v.data(), sizeof(float) * size_t(st.v.size()));
    for (const Mat3& p : st.plastic) mix(p.data(), sizeof(double) * 9);
  }
  return hash;
}

}  // namespace sb
