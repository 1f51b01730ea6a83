// The contact solve on its own (sim/world/contact/contact_solver.h), on hand-made islands: what
// it may and may not do to the kinetic energy.
#include <gtest/gtest.h>

#include <random>

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

// The eight corners of a cube of side 0.2 m with its lowest face at height y, each moving with
// a random velocity; its top face (y + 0.2) as two triangles.
Particles cube(float y, std::mt19937& rng, float speed) {
  std::uniform_real_distribution<float> u(-speed, speed);
  Particles c;
  for (int k = 0; k < 8; ++k) {
    const Vec3f p(0.2f * float(k & 1), y + 0.2f * float((k >> 1) & 1), 0.2f * float(k >> 2));
    const float vx = u(rng), vy = u(rng), vz = u(rng);
    c.add(p, Vec3f(vx, vy, vz), 0.125f);
  }
  c.triangles = {{2, 7, 3}, {2, 6, 7}};  // the corners with (k >> 1) & 1 set: the top face
  return c;
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
    std::vector<ContactPoint> points;
    for (int i : {0, 1, 4, 5}) {  // the lower cube's bottom corners on the floor, 1 cm in
      ContactPoint c;
      c.probe = 0;
      c.particle = i;
      c.collider = 0;
      c.normal = Vec3f::UnitY();
      c.distance0 = -0.01f;
      points.push_back(c);
    }
    for (int i : {0, 1, 4, 5}) {  // the upper cube's bottom corners on the lower one's top
      ContactPoint c;
      c.probe = 1;
      c.obstacle = 0;
      c.particle = i;
      c.triangle = i < 4 ? 0 : 1;
      c.weights = Vec3f::Constant(1.0f / 3);
      c.normal = Vec3f::UnitY();
      c.distance0 = -0.01f;
      points.push_back(c);
    }
    ContactSolverSettings settings;
    settings.h = 1.0f / 240;  // an approach of 1 m/s closes 4 mm: every contact stays inside
    const std::vector<Collider> floor = {Collider::plane(Vec3::UnitY(), 0.0, 0.0)};
    const double before = lower.kineticEnergy() + upper.kineticEnergy();
    solveIsland(bodies, points, {0, 1}, {0, 1, 2, 3, 4, 5, 6, 7}, floor, settings);
    for (SolverBody& b : bodies) finishSolverBody(b);
    const double after = lower.kineticEnergy() + upper.kineticEnergy();
    EXPECT_LE(after, before * (1 + 1e-5) + 1e-9) << "trial " << trial;
    for (const ContactPoint& c : points) pushed += c.lambda[0] + c.lambda[1] > 0.0f;
  }
  EXPECT_GT(pushed, 400);  // the contacts did work: the check is not vacuous
}

}  // namespace
}  // namespace sb
