// The one owner of a body's per-cluster runtime state: reference points, rotations, plastic
// deformation, goal transforms and the SIMD lanes of batched clusters.
//
// A cluster's state can live in two representations: double precision per cluster (the general
// path: shape_matching.h + rotation.h) or float lanes of eight clusters (the batched path for
// small clusters of rigid and linear bodies without plastic flow: cluster_batch.h). Which one is
// current, and whether the lanes' copy of the plastic shape lags behind, is this class's private
// business: selectPath() is the only way to change path, and goals are read through goal(),
// goalRows() and the group sums. Written by the Goals and WholeBody phases; read by Project.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sim/base/types.h"
#include "sim/world/body_def.h"
#include "sim/world/matching/cluster_batch.h"
#include "sim/world/matching/cluster_rest.h"
#include "sim/world/matching/shape_matching.h"

namespace sb {

struct BodyModel;

// A cluster's goal transform as rows [L | t] (12 floats, SIMD-aligned: summing a particle's
// clusters is three vector adds) and its quadratic part Q (zero outside quadratic mode); kept
// apart so the common linear case reads and writes one cache line per cluster.
using GoalRows = Eigen::Matrix<float, 12, 1>;
using GoalQuad = Eigen::Matrix<float, 3, 6>;
using GoalRowsList = std::vector<GoalRows, Eigen::aligned_allocator<GoalRows>>;

class ClusterState {
 public:
  // How the Goals phase treats a body's clusters (chosen by selectPath from the model and the
  // parameters).
  struct Path {
    bool batched = false;  // small clusters eight at a time in lanes
    bool grouped = false;  // moments added up from the particle groups' moments
    bool operator==(const Path& o) const { return batched == o.batched && grouped == o.grouped; }
    bool operator!=(const Path& o) const { return !(*this == o); }
  };

  // Identity plastic state, identity rotations, reference points at the clusters' centres of
  // `x` (#P×3 positions), goals = the rest shape at the body's rest place. Sizes everything for
  // `model`; both representations are current afterwards, so any path may follow.
  void reset(const BodyModel& model, const Eigen::Matrix<float, Eigen::Dynamic, 3>& x);

  // Puts the state on the path `params` call for, handing the reference points and rotations
  // over between lanes and per-cluster state when that changes, and refreshing the lanes' copy
  // of the plastic shape when it may lag. Returns true when the path changed (the World's work
  // lists must then be rebuilt). Call serially, before each Goals phase.
  bool selectPath(const BodyModel& model, const BodyParams& params);
  const Path& path() const { return path_; }

  // ---- Goals phase (parallel over clusters / batches / groups of one or many bodies) ----
  // Moments of the model's moment task `task` (a range of one cluster's members) about the
  // cluster's reference point. x: #P×3 positions.
  ClusterMoments taskMoments(const BodyModel& model, bool quadratic,
                             const Eigen::Matrix<float, Eigen::Dynamic, 3>& x, int task) const;
  // Moments of cluster c from the particle groups' moments (path().grouped).
  ClusterMoments momentsFromGroups(const BodyModel& model, int c) const;
  // Moments of groups [begin, end), each about its first particle (path().grouped). x: #P×3.
  void computeGroupMoments(const BodyModel& model, const Eigen::Matrix<float, Eigen::Dynamic, 3>& x,
                           int begin, int end);
  // The general path for cluster c with moments `sum` taken about its reference point (as
  // taskMoments and momentsFromGroups give them): fit, plastic
  // flow over h seconds, goal. Adds the seconds spent in plastic flow to *plasticSeconds.
  // Returns true when the cluster produced NaN/Inf.
  bool updateCluster(const BodyModel& model, const BodyParams& params, int c,
                     const ClusterMoments& sum, double h, double* plasticSeconds);
  // Batch k of the model (path().batched); lanes the kernel cannot certify take the general path.
  // Returns true when a cluster of the batch produced NaN/Inf.
  bool updateBatch(const BodyModel& model, const BodyParams& params, int k,
                   const Eigen::Matrix<float, Eigen::Dynamic, 3>& x, double h);

  // ---- reading goals (Project, World::goals) ----
  GoalTransform goal(int c) const;
  const GoalRows* goalRows() const { return goalRows_.data(); }
  const GoalQuad* goalQuads() const { return goalQuad_.data(); }
  // Per particle group: the sums of its clusters' goal rows (and quadratic parts when
  // `quadratic`), for groups [begin, end). Then read by groupRows()/groupQuads().
  void sumGroupGoals(const BodyModel& model, bool quadratic, int begin, int end);
  const GoalRows* groupRows() const { return groupRows_.data(); }
  const GoalQuad* groupQuads() const { return groupQuad_.data(); }

  // Permanent deformation Sᵖ of cluster c (identity without plasticity).
  const Mat3& plastic(int c) const { return plastic_[size_t(c)]; }

  // ---- the whole-body level (BodyModel::wholeBodyLevel) ----
  // One cluster over every particle, fitted to x (#P×3, after the clusters' projection) and
  // projected α of the way to its goal with the body's mode and β: it carries the body's
  // large-scale stiffness, so a body's material does not depend on how many clusters it has
  // (the clusters add local detail). Plastic bodies match the rest shape their clusters' plastic
  // deformations add up to (a dent stays). Returns true when NaN/Inf appeared.
  bool projectWholeBody(const BodyModel& model, const BodyParams& params,
                        Eigen::Matrix<float, Eigen::Dynamic, 3>& x);

 private:
  void storeGoal(const GoalTransform& goal, int c);
  void clusterToLane(int c, ClusterBatchLanes& lanes, int lane) const;
  void laneToCluster(const ClusterBatchLanes& lanes, int lane, int c);

  Path path_;
  std::vector<Mat3> plastic_;                 // Sᵖ per cluster
  std::vector<ClusterShape> shape_;           // derived from Sᵖ
  std::vector<Eigen::Quaterniond> rotation_;  // warm start of the rotation extraction
  std::vector<Eigen::Vector3f> ref_;          // last centre of mass: reference for float sums
  GoalRowsList goalRows_;
  std::vector<GoalQuad> goalQuad_;
  // Per particle group (BodyModel::groups): sums of its clusters' goals, and for grouped moments
  // each group's moments about its reference point groupRef_ (its first particle this sub-step).
  GoalRowsList groupRows_;
  std::vector<GoalQuad> groupQuad_;
  std::vector<ClusterMoments> groupMoments_;
  std::vector<Eigen::Vector3f> groupRef_;
  // Per batch of the model: Sᵖ-dependent data in lanes (may lag behind Sᵖ while the body is on
  // the general path: lanesShapeStale_), and the clusters' reference points and rotations in
  // lanes (the current ones while path_.batched; ref_/rotation_ of batched clusters lag then).
  std::vector<ClusterBatchShape> batchShape_;
  std::vector<ClusterBatchLanes> batchLanes_;
  bool lanesShapeStale_ = true;
  // The whole-body level: warm-start rotation and reference point of its fit; for plastic
  // bodies the plastic rest positions (#P×3, body frame) and their rest model and shape.
  Eigen::Quaterniond bodyRotation_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3f bodyRef_ = Eigen::Vector3f::Zero();
  Eigen::Matrix<float, Eigen::Dynamic, 3> plasticRest_;
  ClusterRestModel plasticBodyRest_;
  ClusterShape plasticBodyShape_;
};

}  // namespace sb
