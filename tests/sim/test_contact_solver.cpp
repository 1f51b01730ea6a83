// The contact solve on its own (sim/world/contact/contact_solver.h), on hand-made islands: what
// it may and may not do to the kinetic energy.
#include <gtest/gtest.h>

#include <array>
#include <random>

#include "sim/base/parallel.h"
#include "sim/world/contact/contact_solver.h"

namespace sb {
namespace {

// A body's arrays, owned here; the solve gets views.
struct Particles {
  std::vector<float> x[3], v[3], mass, invMass;
  std::vector<mesh::Triangle> triangles;

  void add(const Vec3f& p, const Vec3f& vel, float m) {
    for (int a = 0; a < 3; ++a) {
      x[a].push_back(p[a]);
      v[a].push_back(vel[a]);
    }
    mass.push_back(m);
    invMass.push_back(1.0f / m);
  }
  double kineticEnergy() const {
    double e = 0;
    for (size_t i = 0; i < mass.size(); ++i)
      e += 0.5 * mass[i] *
           (double(v[0][i]) * v[0][i] + double(v[1][i]) * v[1][i] + double(v[2][i]) * v[2][i]);
    return e;
  }
  SolverBody view(float rigidShare) {
    SolverBody b;
    for (int a = 0; a < 3; ++a) {
      b.x[a] = x[a].data();
      b.v[a] = v[a].data();
    }
    b.mass = mass.data();
    b.invMass = invMass.data();
    b.count = int(mass.size());
    b.triangles = &triangles;
    b.spacing = 0.1f;
    b.gap = 0.001f;
    b.rigidShare = rigidShare;
    for (float m : mass) b.totalMass += m;
    prepareSolverBody(b);
    return b;
  }
};

// The eight corners of a box of the given size with its lowest face at height y (and, with
// centreMass, a particle of that mass at its centre), each moving with a random velocity; its
// top face as two triangles.
Particles box(const Vec3f& size, float y, std::mt19937& rng, float speed, float centreMass = 0) {
  std::uniform_real_distribution<float> u(-speed, speed);
  Particles c;
  for (int k = 0; k < 8; ++k) {
    const Vec3f p(size.x() * float(k & 1), y + size.y() * float((k >> 1) & 1),
                  size.z() * float(k >> 2));
    const float vx = u(rng), vy = u(rng), vz = u(rng);
    c.add(p, Vec3f(vx, vy, vz), 0.125f);
  }
  c.triangles = {{2, 7, 3}, {2, 6, 7}};  // the corners with (k >> 1) & 1 set: the top face
  if (centreMass > 0) {                  // a ninth particle at the centre
    const float vx = u(rng), vy = u(rng), vz = u(rng);
    c.add(0.5f * size + Vec3f(0, y, 0), Vec3f(vx, vy, vz), centreMass);
  }
  return c;
}

Particles cube(float y, std::mt19937& rng, float speed) {
  return box(Vec3f::Constant(0.2f), y, rng, speed);
}

// The four bottom corners of `lower` on the floor and of `upper` on `lower`'s top face, each
// 1 cm in, with friction mu.
std::vector<ContactPoint> stackedContacts(float mu) {
  std::vector<ContactPoint> points;
  for (int body = 0; body < 2; ++body)
    for (int i : {0, 1, 4, 5}) {
      ContactPoint c;
      c.probe = body;
      c.particle = i;
      if (body == 0) {
        c.collider = 0;
      } else {
        c.obstacle = 0;
        c.triangle = i < 4 ? 0 : 1;
        c.weights = Vec3f::Constant(1.0f / 3);
      }
      c.normal = Vec3f::UnitY();
      c.distance0 = -0.01f;
      c.friction = mu;
      points.push_back(c);
    }
  return points;
}

// Solves the two-body island of stackedContacts on a floor at y = 0 for one sub-step of 1/240 s
// (an approach of 1 m/s closes 4 mm: every contact stays inside) and applies the rigid parts.
void solveStack(std::vector<SolverBody>& bodies, std::vector<ContactPoint>& points) {
  ContactSolverSettings settings;
  settings.h = 1.0f / 240;
  const std::vector<Collider> floor = {Collider::plane(Vec3::UnitY(), 0.0, 0.0)};
  solveIsland(bodies, points, {0, 1}, {0, 1, 2, 3, 4, 5, 6, 7}, floor, settings);
  for (SolverBody& b : bodies) finishSolverBody(b);
}

// Contacts whose particles touch or are inside, approaching no faster than the depth allows
// to close in one sub-step, have nothing to let through (target 0): every visit then moves
// the measured velocity toward zero, and a solve without a warm start, friction or
// restitution can only take kinetic energy away, whatever the bodies' rigid shares. (With the
// approach of a particle that already separates as its target, constraint A pushed a whole
// soft body to match it, and a pile of bodies on a very soft one gained energy each sub-step
// until it blew up: the soak found it.)
TEST(ContactSolver, TouchingContactsOnlyTakeEnergyAway) {
  std::mt19937 rng(7);
  const float shares[] = {0.0f, 0.005f, 0.3f, 0.7f, 1.0f};
  int pushed = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Particles lower = cube(-0.01f, rng, 1.0f), upper = cube(0.2f, rng, 1.0f);
    std::vector<SolverBody> bodies = {lower.view(shares[trial % 5]),
                                      upper.view(shares[(trial / 5) % 5])};
    std::vector<ContactPoint> points = stackedContacts(0.0f);
    const double before = lower.kineticEnergy() + upper.kineticEnergy();
    solveStack(bodies, points);
    const double after = lower.kineticEnergy() + upper.kineticEnergy();
    EXPECT_LE(after, before * (1 + 1e-5) + 1e-9) << "trial " << trial;
    for (const ContactPoint& c : points) pushed += c.lambda[0] + c.lambda[1] > 0.0f;
  }
  EXPECT_GT(pushed, 400);  // the contacts did work: the check is not vacuous
}

// Friction too, for the whole solve: each friction visit takes the lowest kinetic energy
// within the cone in the metric of the contact's effective inverse mass K (friction_cone.h;
// tests/sim/test_friction_cone.cpp checks the visit itself, including a case where the radial
// clamp used before adds energy). Here K is made anisotropic — long flat slabs with most of
// their mass at the centre, contacts at their far corners, so their rigid shares turn far more
// easily about some axes than others — and the friction is often at its limit.
TEST(ContactSolver, FrictionOnlyTakesEnergyAway) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> mu(0.1f, 1.5f);
  const float shares[] = {0.0f, 0.005f, 0.3f, 0.7f, 1.0f};
  int sliding = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Particles lower = box(Vec3f(1.6f, 0.02f, 0.1f), -0.01f, rng, 1.0f, 12.0f);
    Particles upper = box(Vec3f(0.1f, 0.1f, 1.2f), 0.02f, rng, 1.0f, 12.0f);
    std::vector<SolverBody> bodies = {lower.view(shares[trial % 5]),
                                      upper.view(shares[(trial / 5) % 5])};
    std::vector<ContactPoint> points = stackedContacts(mu(rng));
    const double before = lower.kineticEnergy() + upper.kineticEnergy();
    solveStack(bodies, points);
    const double after = lower.kineticEnergy() + upper.kineticEnergy();
    EXPECT_LE(after, before * (1 + 1e-5) + 1e-9) << "trial " << trial;
    for (const ContactPoint& c : points)
      for (int j = 0; j < 2; ++j) {
        EXPECT_LE(c.tangent[j].norm(), c.friction * c.lambda[j] * (1 + 1e-5f) + 1e-9f);
        sliding += c.lambda[j] > 0.0f &&
                   c.tangent[j].norm() > 0.999f * c.friction * c.lambda[j];  // on the cone
      }
  }
  EXPECT_GT(sliding, 200);  // friction reached its limit often: the cone was exercised
}

// The velocity sweeps skip a contact that carries nothing while its bodies' velocities have
// moved less than its slack at its last visit (ContactPoint::idleSlack): that visit would do
// nothing. The skip must not change a bit. One box on the floor or two stacked, contacts from
// 1 cm inside to 4 mm apart, some warm started (they may let go), random velocities up to 2 m/s,
// rigid shares from 0 to 1, friction, resting contacts: solved with and without skipping,
// everything compared bit for bit.
TEST(ContactSolver, SkippingIdleContactsChangesNothing) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> depth(-0.01f, 0.004f), warm(0.0f, 0.01f);
  const float shares[] = {0.0f, 0.005f, 0.3f, 0.7f, 1.0f};
  int skipped = 0, visits = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const Particles lower0 = cube(-0.01f, rng, 2.0f), upper0 = cube(0.2f, rng, 2.0f);
    std::vector<ContactPoint> points0 = stackedContacts(0.5f);
    // Two boxes stacked, the lower one alone, or one of its corners alone.
    const int contacts = std::array<int, 3>{8, 4, 1}[size_t(trial % 3)];
    points0.resize(size_t(contacts));
    for (ContactPoint& c : points0) {
      c.distance0 = depth(rng);
      if (rng() % 2) c.lambda[rng() % 2] = warm(rng);  // a warm start, which may let go
    }
    Particles result[2][2];
    std::vector<ContactPoint> points[2];
    for (int skip = 0; skip < 2; ++skip) {
      Particles lower = lower0, upper = upper0;
      std::vector<SolverBody> bodies = {lower.view(shares[trial % 5]),
                                        upper.view(shares[(trial / 5) % 5])};
      points[skip] = points0;
      ContactSolverSettings settings;
      settings.h = 1.0f / 240;
      settings.restingSpeed = (trial / 25) % 2 ? 0.08f : -1e30f;  // as shipped, or none
      settings.skipIdle = skip == 1;
      const std::vector<Collider> floor = {Collider::plane(Vec3::UnitY(), 0.0, 0.0)};
      std::vector<int> bodyList = {0, 1}, pointList = {0, 1, 2, 3, 4, 5, 6, 7};
      bodyList.resize(contacts == 8 ? 2 : 1);
      pointList.resize(size_t(contacts));
      solveIsland(bodies, points[skip], bodyList, pointList, floor, settings);
      for (SolverBody& b : bodies) finishSolverBody(b);
      result[skip][0] = lower;
      result[skip][1] = upper;
    }
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(result[0][b].x[a], result[1][b].x[a]) << "trial " << trial;
        EXPECT_EQ(result[0][b].v[a], result[1][b].v[a]) << "trial " << trial;
      }
    for (size_t k = 0; k < points[0].size(); ++k) {
      const ContactPoint &a = points[0][k], &b = points[1][k];
      for (int j = 0; j < 2; ++j) {
        EXPECT_EQ(a.lambda[j], b.lambda[j]) << "trial " << trial << ", contact " << k;
        EXPECT_EQ(a.tangent[j], b.tangent[j]) << "trial " << trial << ", contact " << k;
      }
      EXPECT_EQ(a.skippedVisits, 0);
      skipped += b.skippedVisits;
      visits += 8;  // the velocity sweeps
    }
  }
  // Many visits were skipped, and many were not: both paths ran.
  EXPECT_GT(skipped, visits / 5);
  EXPECT_LT(skipped, visits * 4 / 5);
}

// A large island's shock-propagation pass runs in waves of bodies that touch none of each other,
// a wave on all threads (contact_solver.cpp): the results must be those of one thread, which
// goes bottom-up, bit for bit. 128 columns of four boxes on the floor, each box's bottom corners
// 1 cm into what is below it, moving at random: 2,048 contacts (so the sweeps run on both
// threads too), four waves of 512.
TEST(ContactSolver, LargeIslandOnTwoThreadsEqualsOneBitForBit) {
  constexpr int kColumns = 128, kHigh = 4;
  static_assert(kColumns * kHigh * 4 >= kMinParallelSweep);
  static_assert(kColumns * 4 >= 2 * kMinParallelShockWave);
  struct Result {
    std::vector<Particles> boxes;
    std::vector<ContactPoint> points;
  };
  auto run = [&](int threads) {
    setThreadCount(threads);
    std::mt19937 rng(11);
    Result r;
    r.boxes.reserve(kColumns * kHigh);
    for (int c = 0; c < kColumns; ++c)
      for (int l = 0; l < kHigh; ++l) {
        r.boxes.push_back(cube(0.19f * float(l) - 0.01f, rng, 0.5f));
        for (float& x : r.boxes.back().x[0]) x += 0.3f * float(c);
      }
    std::vector<SolverBody> bodies;
    for (Particles& b : r.boxes) bodies.push_back(b.view(0.5f));
    for (int b = 0; b < kColumns * kHigh; ++b)
      for (int i : {0, 1, 4, 5}) {
        ContactPoint c;
        c.probe = b;
        c.particle = i;
        if (b % kHigh == 0) {
          c.collider = 0;
        } else {
          c.obstacle = b - 1;
          c.triangle = i < 4 ? 0 : 1;
          c.weights = Vec3f::Constant(1.0f / 3);
        }
        c.normal = Vec3f::UnitY();
        c.distance0 = -0.01f;
        c.friction = 0.5f;
        r.points.push_back(c);
      }
    std::vector<int> bodyList(bodies.size()), pointList(r.points.size());
    for (size_t b = 0; b < bodyList.size(); ++b) bodyList[b] = int(b);
    for (size_t k = 0; k < pointList.size(); ++k) pointList[k] = int(k);
    ContactSolverSettings settings;
    settings.h = 1.0f / 240;
    settings.restingSpeed = 0.08f;
    settings.up = Vec3f::UnitY();  // grounded under gravity: the shock-propagation pass runs
    const std::vector<Collider> floor = {Collider::plane(Vec3::UnitY(), 0.0, 0.0)};
    solveIsland(bodies, r.points, bodyList, pointList, floor, settings);
    for (SolverBody& b : bodies) finishSolverBody(b);
    setThreadCount(0);
    return r;
  };
  const Result one = run(1), two = run(2);
  std::mt19937 rng(11);
  int moved = 0;
  for (size_t b = 0; b < one.boxes.size(); ++b) {
    const Particles start = cube(0.0f, rng, 0.5f);  // the same draws: the starting velocities
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(one.boxes[b].x[a], two.boxes[b].x[a]) << "box " << b;
      EXPECT_EQ(one.boxes[b].v[a], two.boxes[b].v[a]) << "box " << b;
      moved += one.boxes[b].v[a] != start.v[a];
    }
  }
  for (size_t k = 0; k < one.points.size(); ++k)
    for (int j = 0; j < 2; ++j) {
      EXPECT_EQ(one.points[k].lambda[j], two.points[k].lambda[j]) << "contact " << k;
      EXPECT_EQ(one.points[k].tangent[j], two.points[k].tangent[j]) << "contact " << k;
    }
  // The solve did act on (nearly) every box.
  EXPECT_GT(moved, int(one.boxes.size()) * 3 * 9 / 10);
}

// What is still inside after the velocity sweeps is pushed out without velocity; the push moves
// the body as a whole, so a soft body's shape is not changed by it (a local push stored
// deformation without velocity, which shape matching turned into speed: elastic energy from
// nowhere, which blew up the soak's pile). A resting soft cube 1 cm into the floor, at rest:
// the velocity sweeps have nothing to do, the pushes lift it rigidly by at most their rate.
TEST(ContactSolver, PushesOutAsAWholeWithoutDeforming) {
  for (float share : {0.0f, 0.005f, 0.5f}) {
    std::mt19937 rng(3);
    Particles soft = cube(-0.01f, rng, 0.0f);
    std::vector<SolverBody> bodies = {soft.view(share)};
    std::vector<ContactPoint> points = stackedContacts(0.6f);
    points.resize(4);  // the floor contacts only
    ContactSolverSettings settings;
    settings.h = 1.0f / 240;
    const std::vector<Collider> floor = {Collider::plane(Vec3::UnitY(), 0.0, 0.0)};
    const Particles before = soft;
    solveIsland(bodies, points, {0}, {0, 1, 2, 3}, floor, settings);
    finishSolverBody(bodies[0]);
    auto at = [](const Particles& p, int i) { return Vec3f(p.x[0][i], p.x[1][i], p.x[2][i]); };
    for (int i = 0; i < 8; ++i) {
      for (int j = i + 1; j < 8; ++j)
        EXPECT_NEAR((at(soft, i) - at(soft, j)).norm(), (at(before, i) - at(before, j)).norm(),
                    1e-6f)
            << "share " << share << ", particles " << i << " and " << j;
      EXPECT_EQ(soft.v[1][size_t(i)], 0.0f) << "share " << share;  // no velocity from the push
    }
    // Lifted, by at most 2 sweeps × 4 contacts × 2 % of a spacing (0.1 m) and not past the floor.
    const float lift = at(soft, 0).y() - at(before, 0).y();
    EXPECT_GT(lift, 0.001f) << "share " << share;
    EXPECT_LE(lift, 0.01f + 1e-6f) << "share " << share;
  }
}

// Two bodies hooked into each other: a particle of the upper body 5 % of a spacing inside the
// lower one's top face, pushed up by its contact, and another one 5 % inside its bottom face,
// pushed down (a thin part of one body gone through a thin part of the other during a landing).
// The whole-body pushes cancel, so nothing frees them; when both bodies are at rest the soft
// sides are pushed out locally instead, at the pushes' rate, and a rigid side keeps its shape.
// A moving body is not pushed locally (local pushes store deformation: ungated, they spread a
// very soft body of the soak through the pile), nor is a pair whose contacts do not oppose
// (there the whole-body pushes free it).
TEST(ContactSolver, HookedBodiesAtRestArePushedApartLocally) {
  constexpr float kDepth = 0.005f;  // 5 % of the 0.1 m spacing
  struct Run {
    float lowerShare;     // rigid share of the lower body (1: rigid)
    Vec3f upperVelocity;  // of every particle of the upper body (tangential: no approach)
    bool opposed;         // the second contact pushes the other way
    bool expectLocalPush;
  };
  for (const Run& run :
       {Run{0.3f, Vec3f::Zero(), true, true}, Run{1.0f, Vec3f::Zero(), true, true},
        Run{0.3f, Vec3f(0.5f, 0, 0), true, false}, Run{0.3f, Vec3f::Zero(), false, false}}) {
    std::mt19937 rng(1);
    Particles lower = cube(0.0f, rng, 0.0f);   // 0.2 m, y in [0, 0.2]
    lower.triangles = {{2, 7, 3}, {0, 1, 5}};  // top (y = 0.2) and bottom (y = 0)
    Particles upper;
    // Particle 0 just under the lower body's top face, particle 1 just above its bottom face
    // (or, not opposed, also under its top face), two more to give the body extent; its centre
    // at (0.1, ·, 0.1), so the pushes at particles 0 and 1 turn nothing.
    upper.add(Vec3f(0.1f, 0.2f - kDepth, 0.1f), run.upperVelocity, 0.25f);
    upper.add(Vec3f(0.1f, run.opposed ? kDepth : 0.2f - kDepth, 0.1f), run.upperVelocity, 0.25f);
    upper.add(Vec3f(0.0f, 0.1f, 0.0f), run.upperVelocity, 0.25f);
    upper.add(Vec3f(0.2f, 0.1f, 0.2f), run.upperVelocity, 0.25f);
    std::vector<SolverBody> bodies = {lower.view(run.lowerShare), upper.view(0.3f)};
    std::vector<ContactPoint> points(2);
    for (int k = 0; k < 2; ++k) {
      ContactPoint& c = points[size_t(k)];
      c.probe = 1;
      c.obstacle = 0;
      c.particle = k;
      const bool top = k == 0 || !run.opposed;
      c.triangle = top ? 0 : 1;
      c.weights = Vec3f::Constant(1.0f / 3);
      c.normal = top ? Vec3f::UnitY() : Vec3f(-Vec3f::UnitY());
      c.distance0 = -kDepth - 0.001f;  // minus the lower body's gap
    }
    ContactSolverSettings settings;
    settings.h = 1.0f / 240;
    settings.restingSpeed = 0.08f;  // 2|g|h
    settings.up = Vec3f::Zero();
    const Particles lowerBefore = lower, upperBefore = upper;
    solveIsland(bodies, points, {0, 1}, {0, 1}, {}, settings);
    for (SolverBody& b : bodies) finishSolverBody(b);

    auto at = [](const Particles& p, int i) { return Vec3f(p.x[0][i], p.x[1][i], p.x[2][i]); };
    // How far the upper body's two contact particles moved apart, along y: 0 for a body moved as
    // a whole, > 0 where both were pushed out locally (particle 0 up, particle 1 down).
    const float spread =
        (at(upper, 0).y() - at(upper, 1).y()) - (at(upperBefore, 0).y() - at(upperBefore, 1).y());
    // The lower body's shape: its largest change of a pairwise distance.
    float bent = 0;
    for (int i = 0; i < 8; ++i)
      for (int j = i + 1; j < 8; ++j)
        bent = std::max(bent, std::abs((at(lower, i) - at(lower, j)).norm() -
                                       (at(lowerBefore, i) - at(lowerBefore, j)).norm()));
    const std::string what = "lower share " + std::to_string(run.lowerShare) +
                             (run.upperVelocity.isZero() ? ", at rest" : ", moving") +
                             (run.opposed ? ", opposed" : ", not opposed");
    if (run.expectLocalPush) {
      // Each particle out by up to 2 % of a spacing (the rate), shared with the lower body's
      // soft side (none when rigid).
      EXPECT_GT(spread, 0.25f * 0.002f) << what;
      EXPECT_LE(spread, 2 * 0.002f + 1e-5f) << what;
      if (run.lowerShare >= 1.0f) {
        EXPECT_LT(bent, 1e-6f) << what;
      } else {
        EXPECT_GT(bent, 1e-5f) << what;
      }
    } else {
      EXPECT_NEAR(spread, 0.0f, 1e-6f) << what;
      EXPECT_LT(bent, 1e-6f) << what;
    }
    // Position pushes only: no velocity from them (the velocity sweeps had nothing to stop).
    for (int i = 0; i < 4; ++i)
      EXPECT_EQ(Vec3f(upper.v[0][size_t(i)], upper.v[1][size_t(i)], upper.v[2][size_t(i)]),
                run.upperVelocity)
          << what << ", particle " << i;
  }
}

}  // namespace
}  // namespace sb
