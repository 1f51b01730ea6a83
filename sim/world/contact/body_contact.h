// Body–body contact detection: particles of one body against the closed surface (cage) of
// another. Stateless kernels that only read; the Contacts phase decides which bodies meet, the
// contact solver (contact_solver.h) what a contact does.
//
// A particle p touches the obstacle's surface when its signed distance to it is below the gap
// plus the margin: the closest surface point c is found among the triangles near p in the
// obstacle's grid, and p is inside when (p − c) · pseudo-normal < 0 (docs/design.md §5.5).
// Particles deeper than they can have moved in one sub-step (plus the grid's reach) have no
// triangle in reach; a whole-surface search finds those on request (deep penetration).
#pragma once

#include <vector>

#include "sim/mesh/closed_surface.h"
#include "sim/world/contact/surface_grid.h"

namespace sb {

// One body as the detection sees it: views into the World's particle arrays and, when it is the
// obstacle, its surface.
struct ContactGeometry {
  const float* x[3] = {nullptr, nullptr, nullptr};  // position columns (#P each), metres
  const float* v[3] = {nullptr, nullptr, nullptr};  // velocity columns (#P each), m/s
  int count = 0;                                    // #P
  // The body's closed, outward-oriented surface; only needed when it is the obstacle.
  const std::vector<mesh::Triangle>* triangles = nullptr;
  const mesh::SurfaceTopology* topology = nullptr;  // adjacency of *triangles
  // The surface grid, built from earlier positions of the surface that every point has left by
  // at most gridDrift metres (0: built from the current positions).
  const SurfaceGrid* grid = nullptr;
  float gridDrift = 0;
  Eigen::AlignedBox3f box;  // bounding box of the current positions (metres)
  float gap = 0;  // metres ≥ 0: separation the solver keeps (particles stay off the surface)
  // Contacts are also made for particles up to this far beyond the gap (metres, ≤ the grid's
  // reach): the solver lets them approach only until they touch (speculative contact), so a
  // resting particle keeps its contact and a fast one is stopped at the surface.
  float margin = 0;
  // Metres ≥ 0: penetration the solver's position recovery leaves alone, when this body probes.
  float slop = 0;
  Vec3f meanVelocity = Vec3f::Zero();  // m/s: velocity of the centre of mass this sub-step
  float maxRelativeSpeed = 0;          // m/s: fastest particle relative to meanVelocity

  Vec3f position(int i) const { return Vec3f(x[0][i], x[1][i], x[2][i]); }
  Vec3f velocity(int i) const { return Vec3f(v[0][i], v[1][i], v[2][i]); }
};

// A particle of the probe body near a triangle of the obstacle body.
struct Contact {
  int particle = 0;               // index within the probe body
  int triangle = 0;               // index into the obstacle's triangles
  Vec3f weights = Vec3f::Zero();  // barycentric weights of the touched point on the triangle
  Vec3f normal = Vec3f::Zero();   // unit, pointing out of the obstacle
  // Signed distance of the particle to the surface along `normal` (metres, negative inside):
  // the distance the solver restores to the gap.
  float distance = 0;
};

// What earlier look-ups of one probe body in one obstacle's grid learned, kept between sub-steps
// (one build of the grid: the caller clears it when the grid is rebuilt). Per probe particle:
// where it was, a lower bound on its distance then to the surface as the grid holds it, and
// whether a deep search found it outside. The distance to a surface changes by at most how far
// the point and the surface move (the grid's drift bounds the surface's), so while the bound,
// less the particle's motion and the drift, still exceeds the particle's reach, the look-up
// would find no triangle in reach and is skipped; and while it stays positive, a particle found
// outside is still outside, and the deep search is skipped. Most look-ups in a pile are of
// particles near an obstacle's box but not its surface: 81 % find nothing in the seed-scale scene,
// and in the large scene the deep searches that find nothing took a third of the detection.
struct ProbeClearance {
  struct Known {
    Vec3f at = Vec3f::Zero();  // the particle's position then (metres)
    float clearance = 0;       // lower bound on its distance then to the grid's surface (metres)
    bool outside = false;      // a deep search found it outside the surface then
  };
  std::vector<Known> particles;  // #P, or empty: nothing known
};

// Appends a contact for every particle of `probe` whose signed distance to the obstacle's
// surface is below obstacle.gap + obstacle.margin, in particle order. Each particle looks as
// far as the grid's reach plus how far it can have moved relative to the surface in this
// sub-step of h seconds, h·(|v − obstacle.meanVelocity| + obstacle.maxRelativeSpeed), so one
// that entered during the sub-step is seen.
//
// The normal: inside, the face the particle came in through among the closest triangle and its
// neighbours (a box's corner pressed into another box's top face near its edge is pushed back
// up, not sideways out of the side face a hair away); outside, the adjacent face that separates
// most (near an edge the direction to the closest point turns sideways within a gap's width,
// and a resting corner would push its body over the edge); inside, closest to an edge or a
// corner (a concave crease), if `creases`: the face there it is deepest behind. Elsewhere the
// direction between the particle and its closest point.
//
// creases: hold crease particles by a face (above); the World sets it at the sub-steps where
// contacts can rest (ContactSolverSettings::restingSpeed).
//
// deep: also search the whole surface for particles inside the obstacle's box that have no
// triangle in reach (overlapping starts, fast drags); returns whether it found any inside.
// triangleTests, when given, grows by the number of point–triangle tests made: at most two per
// particle and triangle (the grid's look-up visits a triangle once, the deep search once).
// clearance, when given, is used and updated as ProbeClearance says: the contacts found are the
// same, only fewer look-ups are made (for closed surfaces that do not cross themselves, where
// the pseudo-normal tells inside from outside).
//
// apart: unit direction in which the probe leaves the obstacle when the two overlap by more than
// half (each body's box centre inside the other's box and the probe's inside the obstacle): then
// every inside particle is held along it instead of its closest face (which may be on the far
// side, pulling the bodies together), the deepest one along it with its depth to the obstacle's
// far extent. Checked on deep searches only; a pair found overlapping returns true, so it is
// searched every sub-step until it no longer is.
bool findContacts(const ContactGeometry& probe, const ContactGeometry& obstacle, float h, bool deep,
                  bool creases, const Vec3f& apart, std::vector<Contact>& out,
                  long* triangleTests = nullptr, ProbeClearance* clearance = nullptr);

}  // namespace sb
