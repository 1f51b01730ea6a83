// A body inside the World: its model (what never changes while it runs), its parameters and its
// state (what every step changes). Internal to sim/world (the public API is world.h).
//
// Three lifetimes, three types (as Jolt's shared settings / motion properties / update context,
// MuJoCo's mjModel / mjData): BodyModel is built once by addBody (again by setClusters) and
// shared read-only; BodyParams change between steps; BodyState is written by the step's phases,
// each array documented with the phase that writes it (docs/design.md §3).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sim/base/csr.h"
#include "sim/base/types.h"
#include "sim/mesh/closed_surface.h"
#include "sim/world/body_def.h"
#include "sim/world/cluster_state.h"
#include "sim/world/mass_properties.h"
#include "sim/world/matching/cluster_batch.h"
#include "sim/world/matching/cluster_rest.h"
#include "sim/world/matching/particle_groups.h"

namespace sb {

using MatX3f = Eigen::Matrix<float, Eigen::Dynamic, 3>;

// Pinned particles weigh this many times their mass in every fit (clusters, the whole-body
// level, the rigid motion damping keeps): immovable, so a goal passes through its pins instead
// of the pins being pulled along by the rest of the body. Large enough that a rigid bar pinned
// at one face sags well under a millimetre, small enough to keep the fits well conditioned.
constexpr float kPinnedWeightFactor = 1e4f;

// A fixed range of one cluster's memberships whose moments are summed together (large clusters
// are split so their sums run in parallel).
struct MomentTask {
  int cluster;
  int begin, end;  // positions in clusterMembers.items (or particle indices: whole-body cluster)
};

// What never changes while a body runs (rebuilt only by setClusters).
struct BodyModel {
  std::string name;
  Vec3 origin = Vec3::Zero();  // world position of the body frame's origin: rest centre of mass
  MatX3f rest;                 // r: rest positions in the body frame (#P×3, m)
  Eigen::VectorXf mass;        // #P, kg
  double totalMass = 0;        // kg
  std::vector<int> pinned;     // particle indices held at their start positions
  MatX3f startPositions, startVelocities;  // #P×3, the state reset() returns to
  ClusterDef clusterDef;
  // Clusters in both directions: the members of cluster c (particle indices, ascending) and the
  // clusters of particle i (ascending).
  Csr clusterMembers, particleClusters;
  // Particles with the same clusters (sim/world/matching/particle_groups.h); empty when there is
  // little to share. Goal sums are formed per group; so are the moments of non-quadratic bodies.
  ParticleGroups groups;
  // wᵢ = mᵢ / (number of clusters of i), × kPinnedWeightFactor for pinned particles (#P, kg):
  // with these weights the clusters conserve momentum (bodies without pins).
  Eigen::VectorXf matchWeight;
  Eigen::VectorXf invCount;                   // 1 / (number of clusters of i), #P
  std::vector<ClusterRestModel> clusterRest;  // #C
  // Per membership (parallel to clusterMembers.items): q⁰ = r − rc (#M×3, m) and the member's
  // matching weight (#M, kg).
  MatX3f memberRest;
  Eigen::VectorXf memberWeight;
  std::vector<MomentTask> tasks;  // in cluster order
  std::vector<int> taskStart;     // tasks of cluster c: taskStart[c] .. taskStart[c+1]
  bool wholeBodyCluster = false;  // exactly one cluster holding every particle in order
  // Clusters of at most kBatchMaxMembers members, eight per batch (cluster_batch.h).
  std::vector<ClusterBatch> batches;
  // The whole-body level (bodies with several clusters, cluster_state.h): one cluster over
  // every particle, weights mᵢ (pinned: × kPinnedWeightFactor; also the weights of the rigid
  // motion of pinned bodies), its rest model and shape (linear and quadratic parts, Sᵖ = I).
  bool wholeBodyLevel = false;
  Eigen::VectorXf bodyWeight;  // #P, kg
  ClusterRestModel bodyRest;
  ClusterShape bodyShape;
  // Body–body contact: the closed surface (may be empty) and its adjacency, the surface's mean
  // edge length at rest (m) and the inverse masses contacts use (1/kg; 0 = pinned, #P).
  std::vector<mesh::Triangle> surface;
  mesh::SurfaceTopology surfaceTopology;
  float spacing = 0;
  Eigen::VectorXf contactInvMass;
  // Sleep: the body may sleep once no particle has moved farther than this speed carries it in
  // kTimeToSleep, for kTimeToSleep (m/s; scaled to its size, body_model.cpp).
  float sleepSpeed = 0;
  // Rest radius of gyration √(Σ mᵢ|rᵢ|² / M) about the rest centre of mass (m): the body's
  // size as it turns (the reach, rolling resistance's lever).
  float gyrationRadius = 0;
  // The reach: no particle ends a goal projection farther than this from its goal (m; the
  // rest radius of gyration, ×kReachOfGyration; docs/design.md §5.3).
  float reach = 0;

  int clusterCount() const { return static_cast<int>(clusterRest.size()); }
  int particleCount() const { return static_cast<int>(rest.rows()); }
};

// Builds the model of a new body from its (validated) definition, with the surface topology
// built by the validation.
std::shared_ptr<BodyModel> buildBodyModel(const BodyDef& def,
                                          mesh::SurfaceTopology surfaceTopology);
// The same body with other clusters (everything but the clusters is shared with `base`).
// Throws std::invalid_argument on a bad cluster definition.
std::shared_ptr<BodyModel> withClusters(const BodyModel& base, const ClusterDef& clusters);

// What changes every step.
struct BodyState {
  // Positions (m), #P×3: written by Predict, Project, WholeBody, Contacts, Collide.
  MatX3f x;
  // Velocities (m/s), #P×3: written by External, Velocities, Damping, Contacts, Collide.
  MatX3f v;
  // Per-cluster runtime state: written by Goals and WholeBody (see cluster_state.h).
  ClusterState clusters;
  // Written by Predict, read by Velocities: the predicted positions x̂ and the velocities carried
  // with them (#P×3), and the body's angular momentum about its centre before the sub-step
  // (kg·m²/s; zero for pinned bodies). xPred and vPred are empty for a body with one cluster: its
  // Project phase forms the velocities, reading x̂ from x and forming v̂ = v + turn·(v −
  // turnCentre) from v with the prediction's turn (T = R − I, m/s; integrate_phase.cpp).
  MatX3f xPred, vPred;
  Vec3 spin = Vec3::Zero();
  Eigen::Matrix3f turn = Eigen::Matrix3f::Zero();
  Eigen::Vector3f turnCentre = Eigen::Vector3f::Zero();
  // Written by Project for a body with one cluster and no pins, read by Velocities: the rigid
  // motion of the projected positions and velocities, summed block by block as they are formed.
  RigidMotionSums motion;
};

// Start positions and velocities, identity plastic state, goals = the rest shape.
void resetBodyState(const BodyModel& model, BodyState& state);

// Whether a body sleeps (WorldSettings::sleep): written by the Sleep phase, which puts islands
// of bodies at rest to sleep, and by everything that wakes them (contact with an awake body,
// drags, forces, parameter, collider and setting changes). A sleeping body skips every phase;
// it stays an obstacle for awake bodies.
struct SleepState {
  bool asleep = false;
  // Seconds every particle has stayed within model.sleepSpeed × kTimeToSleep of where it was
  // when the count started (`anchor`, #P×3, m; empty: start counting at the next sub-step).
  double still = 0;
  MatX3f anchor;
  int island = -1;  // bodies that fell asleep together (one island) wake together
};

// One entry of the World's body table; handles refer to it by index and generation.
struct BodySlot {
  std::uint32_t generation = 0;
  bool alive = false;
  std::shared_ptr<const BodyModel> model;
  BodyParams params;  // as set (World::params)
  // What the phases apply: params with α, β and damping converted to the sub-step the step runs
  // (substep_material.h). Set by World::step before its sub-steps.
  BodyParams stepParams;
  BodyState state;
  SleepState sleep;
};

}  // namespace sb
