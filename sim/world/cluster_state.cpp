#include "sim/world/cluster_state.h"

#include <chrono>

#include "sim/world/body.h"
#include "sim/world/matching/goal_projection.h"
#include "sim/world/matching/plasticity.h"

namespace sb {

namespace {

using Clock = std::chrono::steady_clock;

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

// Where the moment kernel reads a body's particles.
ParticleColumns columnsOf(const BodyModel& m, const MatX3f& x) {
  return ParticleColumns{{x.col(0).data(), x.col(1).data(), x.col(2).data()},
                         {m.rest.col(0).data(), m.rest.col(1).data(), m.rest.col(2).data()},
                         m.matchWeight.data()};
}

}  // namespace

void ClusterState::reset(const BodyModel& m, const MatX3f& x) {
  const size_t nc = size_t(m.clusterCount());
  plastic_.assign(nc, Mat3::Identity());
  shape_.resize(nc);
  rotation_.assign(nc, Eigen::Quaterniond::Identity());
  ref_.resize(nc);
  goalRows_.resize(nc);
  goalQuad_.resize(nc);
  for (size_t c = 0; c < nc; ++c) {
    shape_[c] = deriveClusterShape(m.clusterRest[c], Mat3::Identity(), false);
    Vec3 centre = Vec3::Zero();
    double mass = 0;
    for (const int* i = m.clusterMembers.begin(int(c)); i != m.clusterMembers.end(int(c)); ++i) {
      centre += double(m.matchWeight[*i]) * x.row(*i).transpose().cast<double>();
      mass += m.matchWeight[*i];
    }
    ref_[c] = (centre / mass).cast<float>();
    GoalTransform restGoal;
    restGoal.t = m.origin.cast<float>();
    storeGoal(restGoal, int(c));
  }
  const size_t groups = size_t(m.groups.count());
  groupRows_.resize(groups);
  groupQuad_.resize(groups);
  groupMoments_.resize(groups);
  groupRef_.resize(groups);
  batchShape_.resize(m.batches.size());
  lanesShapeStale_ = true;
  // Both representations current: the lanes get the same reference points and rotations.
  batchLanes_.resize(m.batches.size());
  for (size_t k = 0; k < m.batches.size(); ++k)
    for (int l = 0; l < kBatchLanes; ++l) clusterToLane(m.batches[k].cluster[l], batchLanes_[k], l);
  bodyRotation_ = Eigen::Quaterniond::Identity();
  if (m.wholeBodyLevel) {
    Vec3 centre = Vec3::Zero();
    double weight = 0;
    for (int i = 0; i < m.particleCount(); ++i) {
      centre += double(m.bodyWeight[i]) * x.row(i).transpose().cast<double>();
      weight += m.bodyWeight[i];
    }
    bodyRef_ = (centre / weight).cast<float>();
  }
  plasticRest_ = m.rest;
  plasticBodyRest_ = m.bodyRest;
  plasticBodyShape_ = m.bodyShape;
}

bool ClusterState::selectPath(const BodyModel& m, const BodyParams& params) {
  const Path want{usesBatches(m, params), usesGroupedMoments(m, params)};
  const bool changed = want != path_;
  if (want.batched && !path_.batched) {
    // Into the lanes (every lane, padding included).
    for (size_t k = 0; k < m.batches.size(); ++k)
      for (int l = 0; l < kBatchLanes; ++l)
        clusterToLane(m.batches[k].cluster[l], batchLanes_[k], l);
    // The batched kernel writes only [L | t]; rigid and linear goals have no quadratic part.
    for (GoalQuad& Q : goalQuad_) Q.setZero();
  } else if (!want.batched && path_.batched) {
    // Back from the lanes in use.
    for (size_t k = 0; k < m.batches.size(); ++k)
      for (int l = 0; l < m.batches[k].count; ++l)
        laneToCluster(batchLanes_[k], l, m.batches[k].cluster[l]);
  }
  path_ = want;
  if (!path_.batched) {
    lanesShapeStale_ = true;  // plastic flow on the general path may change Sᵖ
  } else if (lanesShapeStale_) {
    for (size_t k = 0; k < m.batches.size(); ++k)
      for (int l = 0; l < kBatchLanes; ++l) {
        const size_t c = size_t(m.batches[k].cluster[l]);
        setBatchShapeLane(batchShape_[k], l, plastic_[c], shape_[c], m.clusterRest[c].centre);
      }
    lanesShapeStale_ = false;
  }
  return changed;
}

ClusterMoments ClusterState::taskMoments(const BodyModel& m, bool quadratic, const MatX3f& x,
                                         int task) const {
  const MomentTask& t = m.tasks[size_t(task)];
  ParticleColumns cols = columnsOf(m, x);
  if (!m.wholeBodyCluster) {
    for (int a = 0; a < 3; ++a) cols.memberQ[a] = m.memberRest.col(a).data();
    cols.memberW = m.memberWeight.data();
  }
  return accumulateMoments(cols, m.wholeBodyCluster ? nullptr : m.clusterMembers.items.data(),
                           t.begin, t.end, ref_[size_t(t.cluster)],
                           m.clusterRest[size_t(t.cluster)].centre, quadratic);
}

void ClusterState::computeGroupMoments(const BodyModel& m, const MatX3f& x, int begin, int end) {
  const ParticleGroups& groups = m.groups;
  ParticleColumns cols = columnsOf(m, x);
  for (int a = 0; a < 3; ++a) cols.memberQ[a] = groups.memberRest.col(a).data();
  cols.memberW = groups.memberWeight.data();
  for (int g = begin; g < end; ++g) {
    const int first = groups.particles.start[size_t(g)];
    const int last = groups.particles.start[size_t(g) + 1];
    groupRef_[size_t(g)] = x.row(groups.particles.items[size_t(first)]).transpose();
    groupMoments_[size_t(g)] =
        accumulateMoments(cols, groups.particles.items.data(), first, last, groupRef_[size_t(g)],
                          groups.restCentre[size_t(g)], false);
  }
}

ClusterMoments ClusterState::momentsFromGroups(const BodyModel& m, int c) const {
  return clusterMomentsFromGroups(m.groups, c, groupMoments_.data(), groupRef_.data(),
                                  ref_[size_t(c)], m.clusterRest[size_t(c)].centre);
}

bool ClusterState::updateCluster(const BodyModel& m, const BodyParams& params, int c,
                                 const ClusterMoments& sum, double h, double* plasticSeconds) {
  const size_t i = size_t(c);
  const Eigen::Vector3f ref = ref_[i];
  const bool quadratic = params.mode == Mode::Quadratic;
  if (quadratic && !shape_[i].hasQuadratic)  // switched to quadratic since the last derive
    shape_[i] = deriveClusterShape(m.clusterRest[i], plastic_[i], true);
  ClusterFit fit = fitCluster(sum, ref, m.clusterRest[i], shape_[i], plastic_[i], rotation_[i]);
  if (!fit.finite) return true;
  if (params.plasticity.enabled()) {
    const auto t0 = Clock::now();
    const Mat3 R = fit.rotation.matrix();
    const Mat3 stretch = R.transpose() * fit.linear;
    if (updatePlasticDeformation(0.5 * (stretch + stretch.transpose()), h, params.plasticity,
                                 plastic_[i])) {
      shape_[i] = deriveClusterShape(m.clusterRest[i], plastic_[i], quadratic);
      fit = fitCluster(sum, ref, m.clusterRest[i], shape_[i], plastic_[i], fit.rotation);
    }
    *plasticSeconds += std::chrono::duration<double>(Clock::now() - t0).count();
  }
  rotation_[i] = fit.rotation;
  ref_[i] = fit.centre.cast<float>();
  const GoalTransform goal =
      goalTransform(fit, sum, m.clusterRest[i], shape_[i], plastic_[i], params);
  storeGoal(goal, c);
  return !goal.L.allFinite() || !goal.Q.allFinite() || !goal.t.allFinite();
}

bool ClusterState::updateBatch(const BodyModel& m, const BodyParams& params, int k, const MatX3f& x,
                               double h) {
  const ClusterBatch& batch = m.batches[size_t(k)];
  ClusterBatchLanes& lanes = batchLanes_[size_t(k)];
  const float* xs[3] = {x.col(0).data(), x.col(1).data(), x.col(2).data()};
  const ClusterBatchGoals goals =
      matchClusterBatch(batch, batchShape_[size_t(k)], xs, params, lanes);
  bool bad = false;
  for (int l = 0; l < batch.count; ++l) {
    const int c = batch.cluster[l];
    if (goals.nonFinite >> l & 1u) {
      bad = true;
    } else if (goals.fallback >> l & 1u) {
      // The general path, from and back to the lane's state. A batched cluster is one task.
      laneToCluster(lanes, l, c);
      const ClusterMoments sum = taskMoments(m, false, x, m.taskStart[size_t(c)]);
      double unusedPlasticSeconds = 0;  // batched bodies have no plastic flow
      bad |= updateCluster(m, params, c, sum, h, &unusedPlasticSeconds);
      clusterToLane(c, lanes, l);
    } else {
      // goalQuad_ stays zero (set when the body entered the batches).
      GoalRows& rows = goalRows_[size_t(c)];
      for (int a = 0; a < 3; ++a) {
        for (int j = 0; j < 3; ++j) rows[4 * a + j] = goals.L[3 * a + j][l];
        rows[4 * a + 3] = goals.t[a][l];
      }
    }
  }
  return bad;
}

bool ClusterState::projectWholeBody(const BodyModel& m, const BodyParams& params, MatX3f& x) {
  const int n = m.particleCount();
  const bool quadratic = params.mode == Mode::Quadratic;
  const bool plastic = params.plasticity.enabled();
  if (plastic) {
    // The rest positions rᵢ' whose clusters each hold their plastic shape: cluster c's members
    // sit at c' + Sᵖ(rᵢ − rc) about the centre c' of their rᵢ'; one Jacobi step per sub-step,
    // warm-started from the last (the clusters' strains integrated into one displacement field,
    // so the level keeps a dent instead of pulling it out).
    MatX3f next = MatX3f::Zero(n, 3);
    for (int c = 0; c < m.clusterCount(); ++c) {
      const Eigen::Matrix3f S = plastic_[size_t(c)].cast<float>();
      const Eigen::Vector3f rc = m.clusterRest[size_t(c)].centre;
      Eigen::Vector3f centre = Eigen::Vector3f::Zero();
      float weight = 0;
      for (const int* i = m.clusterMembers.begin(c); i != m.clusterMembers.end(c); ++i) {
        centre += m.matchWeight[*i] * plasticRest_.row(*i).transpose();
        weight += m.matchWeight[*i];
      }
      centre /= weight;
      for (const int* i = m.clusterMembers.begin(c); i != m.clusterMembers.end(c); ++i)
        next.row(*i) +=
            (centre + S * (m.rest.row(*i).transpose() - rc)).transpose() * m.invCount[*i];
    }
    plasticRest_ = next;
    std::vector<int> all(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) all[size_t(i)] = i;
    plasticBodyRest_ =
        buildClusterRest(all.data(), n, plasticRest_.col(0).data(), plasticRest_.col(1).data(),
                         plasticRest_.col(2).data(), m.bodyWeight.data());
    plasticBodyShape_ = deriveClusterShape(plasticBodyRest_, Mat3::Identity(), quadratic);
  }
  const MatX3f& rest = plastic ? plasticRest_ : m.rest;
  const ClusterRestModel& bodyRest = plastic ? plasticBodyRest_ : m.bodyRest;
  const ClusterShape& bodyShape = plastic ? plasticBodyShape_ : m.bodyShape;
  const ParticleColumns cols{{x.col(0).data(), x.col(1).data(), x.col(2).data()},
                             {rest.col(0).data(), rest.col(1).data(), rest.col(2).data()},
                             m.bodyWeight.data()};
  const ClusterMoments sum =
      accumulateMoments(cols, nullptr, 0, n, bodyRef_, bodyRest.centre, quadratic);
  const ClusterFit fit =
      fitCluster(sum, bodyRef_, bodyRest, bodyShape, Mat3::Identity(), bodyRotation_);
  if (!fit.finite) return true;
  bodyRotation_ = fit.rotation;
  bodyRef_ = fit.centre.cast<float>();
  const GoalTransform goal = goalTransform(fit, sum, bodyRest, bodyShape, Mat3::Identity(), params);
  const PositionColumns p{x.col(0).data(), x.col(1).data(), x.col(2).data()};
  const RestColumns r{rest.col(0).data(), rest.col(1).data(), rest.col(2).data()};
  return projectOntoTransform(p, r, 0, n, goal, quadratic, float(params.alpha), m.reach) != 0;
}

GoalTransform ClusterState::goal(int c) const {
  GoalTransform T;
  const GoalRows& rows = goalRows_[size_t(c)];
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) T.L(a, j) = rows[4 * a + j];
    T.t[a] = rows[4 * a + 3];
  }
  T.Q = goalQuad_[size_t(c)];
  return T;
}

void ClusterState::sumGroupGoals(const BodyModel& m, bool quadratic, int begin, int end) {
  for (int g = begin; g < end; ++g) {
    GoalRows sum = GoalRows::Zero();
    GoalQuad Q = GoalQuad::Zero();
    for (const int* c = m.groups.clusters.begin(g); c != m.groups.clusters.end(g); ++c) {
      sum += goalRows_[size_t(*c)];
      if (quadratic) Q += goalQuad_[size_t(*c)];
    }
    groupRows_[size_t(g)] = sum;
    if (quadratic) groupQuad_[size_t(g)] = Q;
  }
}

void ClusterState::storeGoal(const GoalTransform& T, int c) {
  GoalRows& rows = goalRows_[size_t(c)];
  for (int a = 0; a < 3; ++a) {
    for (int j = 0; j < 3; ++j) rows[4 * a + j] = T.L(a, j);
    rows[4 * a + 3] = T.t[a];
  }
  goalQuad_[size_t(c)] = T.Q;
}

void ClusterState::clusterToLane(int c, ClusterBatchLanes& lanes, int l) const {
  for (int a = 0; a < 3; ++a) lanes.ref[a][l] = ref_[size_t(c)][a];
  const Eigen::Quaterniond& q = rotation_[size_t(c)];
  lanes.rotation[0][l] = float(q.w());
  lanes.rotation[1][l] = float(q.x());
  lanes.rotation[2][l] = float(q.y());
  lanes.rotation[3][l] = float(q.z());
}

void ClusterState::laneToCluster(const ClusterBatchLanes& lanes, int l, int c) {
  for (int a = 0; a < 3; ++a) ref_[size_t(c)][a] = lanes.ref[a][l];
  rotation_[size_t(c)] = Eigen::Quaterniond(lanes.rotation[0][l], lanes.rotation[1][l],
                                            lanes.rotation[2][l], lanes.rotation[3][l])
                             .normalized();
}

}  // namespace sb
