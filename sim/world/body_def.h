// Definitions from which bodies are created, and the parameters that can be changed while a
// body runs. Every field has a default that gives a sensible body; units are SI.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "sim/base/types.h"

namespace sb {

// How a cluster's goal positions follow its particles (docs/design.md §5.1).
enum class Mode {
  Rigid,  // goal = R·q + c: the cluster keeps its rest shape exactly
  Linear,  // goal = (β·A + (1−β)·R)·q + c, A the best affine fit (optionally volume-normalised)
  Quadratic,  // goal = (β·Ã + (1−β)·[R 0 0])·q̃ + c, allows bending and twisting
};

const char* modeName(Mode mode);
// Parses "rigid", "linear" or "quadratic"; returns false for anything else.
bool parseMode(const std::string& text, Mode* mode);

// How a body's particles are grouped into shape-matching clusters.
struct ClusterDef {
  enum class Kind {
    Single,    // one cluster holding every particle: stiffest
    Grid,      // a regular grid of cubic cells over the rest shape, each cell plus a margin
    Explicit,  // user-given particle index lists
  };
  Kind kind = Kind::Single;
  // Grid: edge length of a cell in metres (> 0). Smaller cells = more clusters = finer local
  // deformation; the body's large-scale stiffness is α's and β's (the whole-body level).
  double cellSize = 0.5;
  // Grid: each cell also takes particles within this distance of it, in metres (≥ 0). Overlap
  // couples neighbouring clusters; 0 leaves cells disjoint (the body falls apart into pieces).
  double overlap = 0.25;
  // Explicit: each inner vector is one cluster's particle indices (0-based, within the body).
  std::vector<std::vector<int>> clusters;
};

const char* clusterKindName(ClusterDef::Kind kind);

// Plastic deformation per cluster (docs/design.md §5.2). Off while yield is infinite or creep is 0.
struct PlasticityParams {
  double yield = 0.0;  // c_yield: stretch ‖S − I‖₂ above which the rest shape creeps, ≥ 0
  double creep = 0.0;  // c_creep in 1/s: rate at which the excess stretch is absorbed, ≥ 0
  double max = 0.5;    // c_max: bound on the permanent deformation ‖Sᵖ − I‖₂, ≥ 0
  bool enabled() const { return creep > 0.0; }
};

// Parameters that may change at any time while the body runs (no rebuild needed).
struct BodyParams {
  Mode mode = Mode::Linear;
  // α in [0, 1]: the fraction of the way from the predicted positions x̂ = x + h·v + h²·g to the
  // goals per reference sub-step h_ref = 1/240 s; 1 = onto the goal (rigid mode: rigid at any
  // time step). As a stiffness per unit mass, k = α / ((1 − α)·h_ref²) (1/s²), kept at every
  // other sub-step (substep_material.h), so the material does not depend on the time step or
  // the sub-step count. The same α drives the whole-body level of clustered bodies, so the
  // stiffness does not depend on the clusters either.
  double alpha = 0.5;
  // β in [0, 1]: blend of the goal from the best rotation (0) toward the linear/quadratic fit,
  // applied as 0.9·β (shape_matching.h): even β = 1 keeps a restoring force on every shape.
  // Stated at h_ref; converted for other sub-steps so that what the fit follows keeps its
  // stiffness too (substep_material.h).
  double beta = 0.5;
  // Linear mode: divide A by ∛det(A) so the goal keeps the rest volume.
  bool preserveVolume = true;
  // Damping in [0, 1] per reference sub-step (1/240 s; the same decay per second at any
  // sub-step, substep_material.h) of the velocity relative to the body's rigid motion (linear
  // and angular velocity with the body's momenta, pinned particles immovable: a pinned body's
  // rigid motion is only what its pins allow, so its swing is damped); free rigid motion is
  // never damped.
  double damping = 0.0;
  // Restitution e in [0, 1]: the normal speed a contact gives back, relative to the approach,
  // for impacts faster than WorldSettings::restitutionThreshold. A contact uses the larger of
  // its two sides' (the other body's or the collider's), as Box2D. 0: impacts are inelastic.
  // Bodies rebound e² of their fall height: rigid ones (α = 1) contact by contact (± 0.03), soft
  // ones (α < 1) as a whole, the pair's centres parting with e times their approach speed and
  // the deformation stored on impact held back from springing off faster (α 0.3–0.9: e² ± 0.05;
  // softer bodies start their rebound lower, from their compression depth; soft_impact.h).
  double restitution = 0.0;
  PlasticityParams plasticity;
};

// Everything needed to create a body. Positions are given in world space.
struct BodyDef {
  std::string name = "body";
  // Particle rest positions in metres (#P, P ≥ 1); the particles start here.
  std::vector<Vec3> positions;
  // Per-particle masses in kg (> 0), or empty to split totalMass evenly.
  std::vector<double> masses;
  double totalMass = 1.0;        // kg, > 0; used when masses is empty
  Vec3 velocity = Vec3::Zero();  // initial velocity of every particle, m/s
  // Particles held in place (indices within the body). They keep their start position and weigh
  // as immovable (10⁴ × their mass, body.h) in every fit: a cluster's goal passes through its
  // pins, so a rigid body pinned at one face does not sag.
  std::vector<int> pinned;
  // The body's closed surface for body–body contact: triangles of particle indices,
  // counter-clockwise seen from outside (normally the cage's faces). It must be a closed,
  // 2-manifold, outward-oriented surface (checked). Empty: other bodies pass through this one,
  // while its own particles are still kept out of the other bodies' surfaces.
  std::vector<std::array<int, 3>> surface;
  ClusterDef clusters;
  BodyParams params;
};

}  // namespace sb
