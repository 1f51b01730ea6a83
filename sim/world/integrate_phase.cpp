#include "sim/world/integrate_phase.h"

#include "sim/base/parallel_for.h"
#include "sim/world/mass_properties.h"

namespace sb {

namespace {

// Integration forks from this many particles plus cluster memberships: below, the goal sums of
// clustered bodies still gain from reading goals where the Goals phase wrote them.
constexpr long long kMinParallelIntegration = 8192;
// Damping forks only in worlds with at least this many particles.
constexpr long long kMinParallelBodyWork = 2048;

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
    return kernel(px, py, pz, vx, vy, vz, rx, ry, rz, begin, end, s.clusters.goal(0), hf, pull, gvx, gvy,
                  gvz) != 0;
  }
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

}  // namespace

void runIntegratePhase(const WorkLayout& layout, const Vec3& gravity, double h,
                       std::vector<BodySlot>& slots, const std::vector<int>& order,
                       std::vector<char>& blockBad, std::vector<char>& bad) {
  const std::vector<ParticleBlock>& blocks = layout.blocks;
  blockBad.assign(blocks.size(), 0);
  const long long work = layout.particles + layout.members;
  const int minParallel = work >= kMinParallelIntegration ? 2 : INT32_MAX;
  // Goal sums per particle group, in the order each particle would form them (same bits).
  const std::vector<ParticleBlock>& groupBlocks = layout.groupBlocks;
  parallelFor(static_cast<int>(groupBlocks.size()), minParallel, [&](int i) {
    const ParticleBlock& blk = groupBlocks[size_t(i)];
    BodySlot& b = slots[size_t(blk.slot)];
    b.state.clusters.sumGroupGoals(*b.model, b.params.mode == Mode::Quadratic, blk.begin, blk.end);
  });
  parallelFor(static_cast<int>(blocks.size()), minParallel, [&](int i) {
    const ParticleBlock& blk = blocks[size_t(i)];
    BodySlot& b = slots[size_t(blk.slot)];
    blockBad[size_t(i)] =
        integrateBlock(*b.model, b.state, b.params, gravity, h, blk.begin, blk.end);
  });
  for (size_t i = 0; i < blocks.size(); ++i)
    if (blockBad[i]) bad[size_t(blocks[i].slot)] = 1;
  // Pinned particles stay where they started.
  for (int s : order) {
    BodySlot& b = slots[size_t(s)];
    for (int p : b.model->pinned) {
      b.state.x.row(p) = b.model->startPositions.row(p);
      b.state.v.row(p).setZero();
    }
  }
}

void runDampingPhase(const WorkLayout& layout, std::vector<BodySlot>& slots,
                     const std::vector<int>& order) {
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
                const PointColumns xc{{x.col(0).data(), x.col(1).data(), x.col(2).data()}};
                const PointColumns vc{{v.col(0).data(), v.col(1).data(), v.col(2).data()}};
                const MassProperties mp = massProperties(xc, m.mass.data(), n);
                const Vec3 centre = mp.centre;
                const Vec3 velocity = linearMomentum(vc, m.mass.data(), n) / m.totalMass;
                const Vec3 omega =
                    mp.inverseInertia * angularMomentum(xc, vc, m.mass.data(), n, centre);
                const double kd = b.params.damping;
                for (int i = 0; i < n; ++i) {
                  const Vec3 r = x.row(i).transpose().cast<double>() - centre;
                  const Vec3 vi = v.row(i).transpose().cast<double>();
                  const Vec3 rigid = velocity + omega.cross(r);
                  v.row(i) = (vi + kd * (rigid - vi)).transpose().cast<float>();
                }
              });
}

}  // namespace sb
