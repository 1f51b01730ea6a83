// Body–body contact: particles of one body against the closed surface (cage) of another.
// Stateless kernels; the World decides which bodies meet and in what order contacts resolve.
//
// A particle p touches the obstacle's surface when its signed distance to it is below the gap:
// the closest surface point c is found among the triangles near p in the obstacle's grid, and p
// is inside when (p − c) · pseudo-normal < 0. Particles deeper than they can have moved in one
// sub-step (plus the grid's reach) are not seen, so a particle is seen while it enters.
#pragma once

#include <vector>

#include "sim/mesh/closed_surface.h"
#include "sim/world/contact/surface_grid.h"

namespace sb {

// One body as the contact kernels see it: views into the World's particle arrays, plus what
// its response to contacts as a whole needs.
//
// Why a body answers contacts partly as a whole: shape matching couples a particle to the rest
// of its body only through the goals, by a fraction α per step. A contact that pushes and stops
// just the touching particles is therefore diluted over the whole body: a stiff body (α near 1)
// keeps most of its momentum and its goals drag the touched particles back in, so it sinks into
// or tunnels through the other body. So each contact's correction and impulse go a fraction
// `rigidShare` (the World uses α) to the body's rigid motion — as if it were a rigid body with
// its mass and inertia — and the rest to the touched particles. Both parts conserve linear
// momentum exactly, and angular momentum up to the small gap between the two touching points.
struct ContactBody {
  float* x[3] = {nullptr, nullptr, nullptr};  // position columns (#P each), metres
  float* v[3] = {nullptr, nullptr, nullptr};  // velocity columns (#P each), m/s
  const float* mass = nullptr;                // kg per particle
  const float* invMass = nullptr;  // 1/kg per particle; 0 for pinned particles (immovable)
  int count = 0;                   // #P
  // The body's closed, outward-oriented surface; only needed when it is the obstacle.
  const std::vector<mesh::Triangle>* triangles = nullptr;
  const mesh::SurfaceTopology* topology = nullptr;  // adjacency of *triangles
  // The surface grid, built from earlier positions of the surface that every point has left by
  // at most gridDrift metres (0: built from the current positions).
  const SurfaceGrid* grid = nullptr;
  float gridDrift = 0;
  float gap = 0;  // metres ≥ 0: separation contacts restore (keeps particles off the surface)
  Vec3f meanVelocity = Vec3f::Zero();  // m/s: velocity of the centre of mass this sub-step
  float maxRelativeSpeed = 0;          // m/s: fastest particle relative to meanVelocity

  // Response as a whole (set by prepareRigidResponse): share in [0, 1] (0 for bodies with
  // pinned particles), centre of mass (m), 1/total mass (1/kg), inverse inertia about the centre
  // (world frame, 1/(kg·m²); pseudo-inverse for flat bodies).
  float rigidShare = 0;
  Vec3f centre = Vec3f::Zero();
  float invTotalMass = 0;
  Eigen::Matrix3f invInertia = Eigen::Matrix3f::Zero();
  // Rigid corrections gathered over this sub-step's contacts, applied by applyRigidResponse:
  // translation (m) and small rotation (rad) of the positions, velocity change (m/s) and angular
  // velocity change (rad/s).
  Vec3f shift = Vec3f::Zero(), turn = Vec3f::Zero();
  Vec3f deltaV = Vec3f::Zero(), deltaW = Vec3f::Zero();

  Vec3f position(int i) const { return Vec3f(x[0][i], x[1][i], x[2][i]); }
  Vec3f velocity(int i) const { return Vec3f(v[0][i], v[1][i], v[2][i]); }
};

// Computes the centre, mass and inertia of the body's current positions, sets its rigid share
// and clears the gathered rigid corrections.
void prepareRigidResponse(ContactBody& body, float rigidShare);

// Moves and accelerates every particle by the gathered rigid corrections (x += shift + turn × r,
// v += deltaV + deltaW × r, r = x − centre) and clears them.
void applyRigidResponse(ContactBody& body);

// A particle of the probe body touching a triangle of the obstacle body.
struct Contact {
  int particle = 0;               // index within the probe body
  int triangle = 0;               // index into the obstacle's triangles
  Vec3f weights = Vec3f::Zero();  // barycentric weights of the touched point on the triangle
  Vec3f normal = Vec3f::Zero();   // unit, pointing out of the obstacle
};

// Appends a contact for every particle of `probe` whose signed distance to the obstacle's
// surface is below obstacle.gap, in particle order. Each particle looks as far as the grid's
// reach plus how far it can have moved relative to the surface in this sub-step of h seconds,
// h·(|v − obstacle.meanVelocity| + obstacle.maxRelativeSpeed), so one that entered during the
// sub-step is seen. Reads only.
void findContacts(const ContactBody& probe, const ContactBody& obstacle, float h,
                  std::vector<Contact>& out);

// Resolves one contact with the current positions (including the rigid corrections gathered so
// far): moves the particle and the touched point apart along the normal until they are
// obstacle.gap apart, then removes their approaching normal velocity and, Coulomb-style, up to
// friction × that impulse of their sliding velocity. Corrections and impulses are equal and
// opposite and split between particles and rigid motion by effective inverse mass, so linear
// momentum is conserved exactly in exact arithmetic. friction ≥ 0.
void resolveContact(ContactBody& probe, ContactBody& obstacle, const Contact& contact,
                    float friction);

// Resolves a particle of `body` against an immovable surface (a static collider): `distance` is
// the particle's signed distance to it at its current position including the gathered rigid
// corrections (negative inside), `normal` the unit normal out of the collider there. The same
// split between the particle and the body's rigid motion, the same normal and friction
// impulses as resolveContact, with the other side immovable. friction ≥ 0.
void resolveStaticContact(ContactBody& body, int particle, const Vec3f& normal, float distance,
                          float friction);

// The particle's position including the gathered rigid corrections (metres).
inline Vec3f correctedPosition(const ContactBody& body, int particle) {
  const Vec3f x = body.position(particle);
  return x + body.shift + body.turn.cross(x - body.centre);
}

}  // namespace sb
