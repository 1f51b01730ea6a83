#include "sim/world/integrate_phase.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <vector>

#include "sim/base/parallel_for.h"
#include "sim/world/mass_properties.h"
#include "sim/world/matching/goal_projection.h"

namespace sb {

namespace {

// Per-particle passes fork from this many particles plus cluster memberships: below, the goal
// sums of clustered bodies still gain from reading goals where the Goals phase wrote them.
constexpr long long kMinParallelIntegration = 8192;
// Per-body passes (predict, whole-body level, velocities, damping) fork only in worlds with at
// least this many particles.
constexpr long long kMinParallelBodyWork = 2048;
// A body's turn per sub-step below which the prediction moves along the tangent (the rotation's
// second-order term, (hω)²/2 of the radius, is below float resolution of the positions there).
constexpr double kMinTurn = 1e-3;

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

// A body with one cluster has its velocities formed by the Project phase, in the sweep that moves
// its particles (x̂ is the position that sweep reads: Predict wrote it to x, and nothing moves the
// body in between; v̂ it forms from v, which nothing changes in between either); the Velocities
// phase adds only the spin correction. Saves one sweep over x, x̂, v̂ and v per sub-step, and the
// prediction's stores of x̂ and v̂ (issue 17).
bool velocitiesFromProjection(const BodyModel& m) {
  return m.wholeBodyCluster;
}

// Such a body, if it keeps its spin (no pins, runVelocitiesPhase), also has the rigid motion of
// its new positions and velocities, which the spin correction needs, summed by the Project phase:
// each block (work_layout.cpp, 4,096 particles) as soon as it is projected, its x and v still in
// the second-level cache. Saves one sweep over x, v and masses from memory per sub-step (issue 17;
// summing pieces of 512 from the first-level cache measured the same).
bool motionFromProjection(const BodyModel& m) {
  return velocitiesFromProjection(m) && m.pinned.empty();
}

// What the Project phase forms the velocities of a body with one cluster from
// (velocitiesFromProjection): its v, the prediction's turn, 1/h and h·gravity.
ProjectedVelocities projectedVelocities(BodyState& s, float invH,
                                        const Eigen::Vector3f& fallSpeed) {
  ProjectedVelocities p{};
  for (int a = 0; a < 3; ++a) {
    p.v[a] = s.v.col(a).data();
    for (int b = 0; b < 3; ++b) p.turn[a][b] = s.turn(a, b);
    p.turnCentre[a] = s.turnCentre[a];
    p.fallSpeed[a] = fallSpeed[a];
  }
  p.invH = invH;
  return p;
}

// Moves particles [begin, end) of one body α of the way to the blend of their clusters' goals;
// returns true if a non-finite value appeared. `velocities`: see velocitiesFromProjection.
bool projectBlock(const BodyModel& m, BodyState& s, const BodyParams& params, int begin, int end,
                  const ProjectedVelocities& velocities) {
  const PositionColumns p{s.x.col(0).data(), s.x.col(1).data(), s.x.col(2).data()};
  const float* rx = m.rest.col(0).data();
  const float* ry = m.rest.col(1).data();
  const float* rz = m.rest.col(2).data();
  const float alpha = float(params.alpha);
  const bool quadratic = params.mode == Mode::Quadratic;
  auto run = [&](auto goal) { return projectRange(p, begin, end, alpha, goal) != 0; };
  if (m.wholeBodyCluster)
    return projectOntoTransform(p, RestColumns{rx, ry, rz}, begin, end, s.clusters.goal(0),
                                quadratic, alpha, m.reach, &velocities) != 0;
  const int* start = m.particleClusters.start.data();
  const int* clusterOf = m.particleClusters.items.data();
  const float* invCount = m.invCount.data();
  const GoalRows* rows = s.clusters.goalRows();
  const GoalQuad* quads = s.clusters.goalQuads();
  if (!m.groups.empty()) {  // the sums are formed per group already
    const int* groupOf = m.groups.groupOf.data();
    const GoalRows* groupRows = s.clusters.groupRows();
    const GoalQuad* groupQuad = s.clusters.groupQuads();
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

PointColumns columnsOf(const MatX3f& m) {
  return PointColumns{{m.col(0).data(), m.col(1).data(), m.col(2).data()}};
}

// Where projectBlock will put particle 0 of a body with one cluster: the projection of a copy.
std::array<float, 3> projectedFirst(const BodyModel& m, const BodyState& s,
                                    const BodyParams& params) {
  std::array<float, 3> p = {s.x(0, 0), s.x(0, 1), s.x(0, 2)};
  const RestColumns rest{m.rest.col(0).data(), m.rest.col(1).data(), m.rest.col(2).data()};
  projectOntoTransform(PositionColumns{&p[0], &p[1], &p[2]}, rest, 0, 1, s.clusters.goal(0),
                       params.mode == Mode::Quadratic, float(params.alpha), m.reach);
  return p;
}

// Writable column pointers of a #P×3 array (x, y, z), for the per-particle loops (no Eigen row
// access, which strides by #P through the column-major array).
std::array<float*, 3> writableColumns(MatX3f& m) {
  return {m.col(0).data(), m.col(1).data(), m.col(2).data()};
}

Eigen::Matrix3f skew(const Eigen::Vector3f& w) {
  Eigen::Matrix3f K;
  K << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return K;
}

// Calls body(begin, end) over pieces of [0, count) of one body's per-particle arrays: on the
// pool's threads for a large body (when called from a loop over bodies that already runs in
// parallel, on the calling thread). Every particle is computed alone, so the bits do not depend
// on the split.
template <typename Body>
void forParticleRanges(int count, const Body& body) {
  parallelRanges(count, kMinParallelParticles, 1 << 30, body);
}

// The prediction of particles [begin, end) of one body: x̂ = x + h·v + D·(x − xc) + fall and
// v̂ = v + T·(v − vc), with D = R − I − h·[ω]× and T = R − I; x takes x̂, and xPred a copy and
// vPred v̂ unless the body's velocities come from its projection (velocitiesFromProjection:
// Project forms v̂ itself where it reads v, and not writing them halves the sweep's stores).
struct PredictStep {
  Eigen::Matrix3f D, T;
  Eigen::Vector3f xc, vc, fall;
  float h;
};

// One vectorised loop (`omp simd`: GCC 12 does not take the local restricts as proof that the
// twelve columns do not overlap and gave up), every 3×3 product spelled out the way Eigen sums a
// fixed-size one, m₀d₀ + (m₁d₁ + m₂d₂): the bits are those of the per-particle Eigen::Vector3f
// expressions this replaced, which ran scalar (issue 17).
template <bool kKeepPredicted>
void predictRange(const PredictStep& c, const std::array<float*, 3>& x,
                  const std::array<float*, 3>& xPred, const std::array<float*, 3>& v,
                  const std::array<float*, 3>& vPred, int begin, int end) {
  float* __restrict x0 = x[0];
  float* __restrict x1 = x[1];
  float* __restrict x2 = x[2];
  float* __restrict xp0 = xPred[0];
  float* __restrict xp1 = xPred[1];
  float* __restrict xp2 = xPred[2];
  const float* __restrict v0 = v[0];
  const float* __restrict v1 = v[1];
  const float* __restrict v2 = v[2];
  float* __restrict vp0 = vPred[0];
  float* __restrict vp1 = vPred[1];
  float* __restrict vp2 = vPred[2];
  const float D00 = c.D(0, 0), D01 = c.D(0, 1), D02 = c.D(0, 2);
  const float D10 = c.D(1, 0), D11 = c.D(1, 1), D12 = c.D(1, 2);
  const float D20 = c.D(2, 0), D21 = c.D(2, 1), D22 = c.D(2, 2);
  const float T00 = c.T(0, 0), T01 = c.T(0, 1), T02 = c.T(0, 2);
  const float T10 = c.T(1, 0), T11 = c.T(1, 1), T12 = c.T(1, 2);
  const float T20 = c.T(2, 0), T21 = c.T(2, 1), T22 = c.T(2, 2);
  const float cx = c.xc.x(), cy = c.xc.y(), cz = c.xc.z();
  const float ux = c.vc.x(), uy = c.vc.y(), uz = c.vc.z();
  const float fx = c.fall.x(), fy = c.fall.y(), fz = c.fall.z();
  const float h = c.h;
#pragma omp simd
  for (int i = begin; i < end; ++i) {
    const float px = x0[i], py = x1[i], pz = x2[i];
    const float qx = v0[i], qy = v1[i], qz = v2[i];
    const float dx = px - cx, dy = py - cy, dz = pz - cz;
    const float ex = qx - ux, ey = qy - uy, ez = qz - uz;
    const float mx = ((px + h * qx) + (D00 * dx + (D01 * dy + D02 * dz))) + fx;
    const float my = ((py + h * qy) + (D10 * dx + (D11 * dy + D12 * dz))) + fy;
    const float mz = ((pz + h * qz) + (D20 * dx + (D21 * dy + D22 * dz))) + fz;
    x0[i] = mx;
    x1[i] = my;
    x2[i] = mz;
    if constexpr (kKeepPredicted) {
      xp0[i] = mx;
      xp1[i] = my;
      xp2[i] = mz;
      vp0[i] = qx + (T00 * ex + (T01 * ey + T02 * ez));
      vp1[i] = qy + (T10 * ex + (T11 * ey + T12 * ez));
      vp2[i] = qz + (T20 * ex + (T21 * ey + T22 * ez));
    }
  }
}

// v += K·(x − xc) − shift for particles [begin, end): one vectorised loop, the product summed in
// Eigen's order as in predictRange (same bits as the Eigen::Vector3f form it replaced).
void addTurn(const Eigen::Matrix3f& K, const Eigen::Vector3f& xc, const Eigen::Vector3f& shift,
             const std::array<float*, 3>& x, const std::array<float*, 3>& v, int begin, int end) {
  const float* __restrict x0 = x[0];
  const float* __restrict x1 = x[1];
  const float* __restrict x2 = x[2];
  float* __restrict v0 = v[0];
  float* __restrict v1 = v[1];
  float* __restrict v2 = v[2];
  const float K00 = K(0, 0), K01 = K(0, 1), K02 = K(0, 2);
  const float K10 = K(1, 0), K11 = K(1, 1), K12 = K(1, 2);
  const float K20 = K(2, 0), K21 = K(2, 1), K22 = K(2, 2);
  const float cx = xc.x(), cy = xc.y(), cz = xc.z();
  const float sx = shift.x(), sy = shift.y(), sz = shift.z();
#pragma omp simd
  for (int i = begin; i < end; ++i) {
    const float dx = x0[i] - cx, dy = x1[i] - cy, dz = x2[i] - cz;
    v0[i] += (K00 * dx + (K01 * dy + K02 * dz)) - sx;
    v1[i] += (K10 * dx + (K11 * dy + K12 * dz)) - sy;
    v2[i] += (K20 * dx + (K21 * dy + K22 * dz)) - sz;
  }
}

// The weights a body's rigid motion is fitted with: masses, pinned particles immovable.
const float* rigidWeights(const BodyModel& m) {
  return m.pinned.empty() ? m.mass.data() : m.bodyWeight.data();
}

}  // namespace

void runPredictPhase(const WorkLayout& layout, const Vec3& gravity, double h,
                     std::vector<BodySlot>& slots, const std::vector<int>& order) {
  const float hf = float(h);
  const Eigen::Vector3f fall = (h * h * gravity).cast<float>();
  parallelFor(
      static_cast<int>(order.size()), layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX,
      [&](int k) {
        BodySlot& b = slots[size_t(order[size_t(k)])];
        const BodyModel& m = *b.model;
        BodyState& s = b.state;
        const int n = m.particleCount();
        // A pinned body has no free turn to advance and no spin to keep.
        RigidMotion rm;
        if (m.pinned.empty())
          rm = rigidMotionOnThreads(columnsOf(s.x), columnsOf(s.v), m.mass.data(), n);
        s.spin = rm.angularMomentum;
        const double turn = h * rm.omega.norm();
        // x̂ = x + h·v + h²·g, with the tangential h·ω × r of the body's turn replaced by
        // the rotation (R − I)·r, r = x − xc; v̂ = v + (R − I)(v − vc): the velocities turn
        // with the body.
        Eigen::Matrix3f toRotation = Eigen::Matrix3f::Zero();    // R − I − h·[ω]×
        Eigen::Matrix3f turnVelocity = Eigen::Matrix3f::Zero();  // R − I
        if (turn > kMinTurn) {
          const Mat3 RmI = Eigen::AngleAxisd(turn, rm.omega / rm.omega.norm()).toRotationMatrix() -
                           Mat3::Identity();
          turnVelocity = RmI.cast<float>();
          toRotation = turnVelocity - hf * skew(rm.omega.cast<float>());
        }
        const PredictStep step{
            toRotation, turnVelocity, rm.centre.cast<float>(), rm.velocity.cast<float>(), fall, hf};
        const bool keepPredicted = !velocitiesFromProjection(m);
        s.xPred.resize(keepPredicted ? n : 0, 3);
        s.vPred.resize(keepPredicted ? n : 0, 3);
        s.turn = turnVelocity;
        s.turnCentre = step.vc;
        const std::array<float*, 3> x = writableColumns(s.x), xp = writableColumns(s.xPred),
                                    v = writableColumns(s.v), vp = writableColumns(s.vPred);
        forParticleRanges(n, [&](int begin, int end) {
          if (keepPredicted)
            predictRange<true>(step, x, xp, v, vp, begin, end);
          else
            predictRange<false>(step, x, xp, v, vp, begin, end);
        });
        for (int p : m.pinned) {
          s.x.row(p) = m.startPositions.row(p);
          if (keepPredicted) s.xPred.row(p) = m.startPositions.row(p);
        }
      });
}

void runProjectPhase(const WorkLayout& layout, const Vec3& gravity, double h,
                     std::vector<BodySlot>& slots, const std::vector<int>& order,
                     std::vector<char>& blockBad, std::vector<char>& bad) {
  const float invH = float(1.0 / h);
  const Eigen::Vector3f fallSpeed = (h * gravity).cast<float>();
  const std::vector<ParticleBlock>& blocks = layout.blocks;
  blockBad.assign(blocks.size(), 0);
  const long long work = layout.particles + layout.members;
  const int minParallel = work >= kMinParallelIntegration ? 2 : INT32_MAX;
  // Goal sums per particle group, in the order each particle would form them (same bits).
  const std::vector<ParticleBlock>& groupBlocks = layout.groupBlocks;
  parallelFor(static_cast<int>(groupBlocks.size()), minParallel, [&](int i) {
    const ParticleBlock& blk = groupBlocks[size_t(i)];
    BodySlot& b = slots[size_t(blk.slot)];
    b.state.clusters.sumGroupGoals(*b.model, b.stepParams.mode == Mode::Quadratic, blk.begin,
                                   blk.end);
  });
  // The sums are taken about the first particle, as rigidMotion takes them: where this sweep will
  // put it, projected ahead on a copy (the same kernel, the same bits).
  for (int s : order) {
    BodySlot& b = slots[size_t(s)];
    if (motionFromProjection(*b.model))
      startRigidMotionSums(b.state.motion, projectedFirst(*b.model, b.state, b.stepParams).data(),
                           b.model->particleCount());
  }
  parallelFor(static_cast<int>(blocks.size()), minParallel, [&](int i) {
    const ParticleBlock& blk = blocks[size_t(i)];
    BodySlot& b = slots[size_t(blk.slot)];
    const BodyModel& m = *b.model;
    BodyState& st = b.state;
    const ProjectedVelocities velocities = projectedVelocities(st, invH, fallSpeed);
    blockBad[size_t(i)] = projectBlock(m, st, b.stepParams, blk.begin, blk.end, velocities);
    if (motionFromProjection(m))
      sumRigidMotionBlocks(columnsOf(st.x), columnsOf(st.v), m.mass.data(), blk.begin, blk.end,
                           st.motion);
  });
  for (size_t i = 0; i < blocks.size(); ++i)
    if (blockBad[i]) bad[size_t(blocks[i].slot)] = 1;
  for (int s : order) {
    BodySlot& b = slots[size_t(s)];
    for (int p : b.model->pinned) b.state.x.row(p) = b.model->startPositions.row(p);
  }
}

void runWholeBodyPhase(const WorkLayout& layout, std::vector<BodySlot>& slots,
                       const std::vector<int>& order, std::vector<char>& bad) {
  parallelFor(static_cast<int>(order.size()),
              layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX, [&](int k) {
                const int s = order[size_t(k)];
                BodySlot& b = slots[size_t(s)];
                if (!b.model->wholeBodyLevel) return;
                if (b.state.clusters.projectWholeBody(*b.model, b.stepParams, b.state.x))
                  bad[size_t(s)] = 1;
                for (int p : b.model->pinned) b.state.x.row(p) = b.model->startPositions.row(p);
              });
}

void runVelocitiesPhase(const WorkLayout& layout, const Vec3& gravity, double h,
                        std::vector<BodySlot>& slots, const std::vector<int>& order) {
  const float invH = float(1.0 / h);
  const Eigen::RowVector3f fallSpeed = (h * gravity).transpose().cast<float>();
  parallelFor(static_cast<int>(order.size()),
              layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX, [&](int k) {
                BodySlot& b = slots[size_t(order[size_t(k)])];
                const BodyModel& m = *b.model;
                BodyState& s = b.state;
                const int n = m.particleCount();
                // v = v̂ + (x − x̂)/h + h·g: what the projections moved, on top of the velocity
                // carried with the prediction (which lacks the h·g the prediction fell).
                const std::array<float*, 3> x = writableColumns(s.x), xp = writableColumns(s.xPred),
                                            v = writableColumns(s.v), vp = writableColumns(s.vPred);
                if (!velocitiesFromProjection(m))
                  forParticleRanges(n, [&](int begin, int end) {
                    for (int a = 0; a < 3; ++a)
                      for (int i = begin; i < end; ++i)
                        v[a][i] = (vp[a][i] + (x[a][i] - xp[a][i]) * invH) + fallSpeed[a];
                  });
                for (int p : m.pinned) s.v.row(p).setZero();
                if (!m.pinned.empty()) return;
                // The projections are torque-free about the predicted positions, not about the
                // positions the momentum is measured at, and the chord Δx/h of a turning body
                // is shorter than its tangent (by sin(hω)/(hω)): put the body's spin back to what
                // it was before the sub-step.
                const RigidMotion rm =
                    motionFromProjection(m)
                        ? rigidMotionOf(s.motion)
                        : rigidMotionOnThreads(columnsOf(s.x), columnsOf(s.v), m.mass.data(), n);
                const Eigen::Vector3f dw =
                    (rm.inverseInertia * (s.spin - rm.angularMomentum)).cast<float>();
                if (dw == Eigen::Vector3f::Zero()) return;
                // v += dw × (x − xc) − shift: no linear momentum in exact arithmetic; the shift,
                // its mass-weighted mean as evaluated in float, keeps rounding from adding any.
                // The mean is summed in blocks of kRigidMotionBlock particles, blocks in order.
                const Eigen::Vector3f xc = rm.centre.cast<float>();
                const int blocks = (n + kRigidMotionBlock - 1) / kRigidMotionBlock;
                std::vector<Vec3> blockSums(static_cast<size_t>(blocks));
                parallelRanges(blocks, n >= kMinParallelParticles ? 2 : INT32_MAX, 1 << 30,
                               [&](int b0, int b1) {
                                 for (int blk = b0; blk < b1; ++blk) {
                                   double sum[3] = {0, 0, 0};
                                   const int end = std::min(n, (blk + 1) * kRigidMotionBlock);
                                   for (int i = blk * kRigidMotionBlock; i < end; ++i)
                                     for (int a = 0; a < 3; ++a)
                                       sum[a] += double(m.mass[i]) * double(s.x(i, a) - xc[a]);
                                   blockSums[size_t(blk)] = Vec3(sum[0], sum[1], sum[2]);
                                 }
                               });
                Vec3 sum = Vec3::Zero();
                for (const Vec3& blockSum : blockSums) sum += blockSum;
                const Eigen::Vector3f shift = dw.cross((sum / m.totalMass).cast<float>());
                forParticleRanges(
                    n, [&](int begin, int end) { addTurn(skew(dw), xc, shift, x, v, begin, end); });
              });
}

void runDampingPhase(const WorkLayout& layout, std::vector<BodySlot>& slots,
                     const std::vector<int>& order) {
  parallelFor(static_cast<int>(order.size()),
              layout.particles >= kMinParallelBodyWork ? 2 : INT32_MAX, [&](int k) {
                BodySlot& b = slots[size_t(order[size_t(k)])];
                const double kd = b.stepParams.damping;
                if (!(kd > 0.0)) return;
                const BodyModel& m = *b.model;
                MatX3f& x = b.state.x;
                MatX3f& v = b.state.v;
                const int n = m.particleCount();
                // The rigid motion with the body's momenta, pinned particles immovable: a pinned
                // body keeps only the motion its pins allow (none for three pins or more), so its
                // swing is damped like any other deformation.
                const RigidMotion rm =
                    rigidMotionOnThreads(columnsOf(x), columnsOf(v), rigidWeights(m), n);
                forParticleRanges(n, [&](int begin, int end) {
                  for (int i = begin; i < end; ++i) {
                    const Vec3 r = x.row(i).transpose().cast<double>() - rm.centre;
                    const Vec3 vi = v.row(i).transpose().cast<double>();
                    const Vec3 rigid = rm.velocity + rm.omega.cross(r);
                    v.row(i) = (vi + kd * (rigid - vi)).transpose().cast<float>();
                  }
                });
              });
}

}  // namespace sb
