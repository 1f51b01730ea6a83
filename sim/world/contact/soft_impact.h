// Restitution of impacts that involve a soft body (α < 1): an event of the pair of bodies, not
// of their particles (docs/design.md §5.5, restitution).
//
// Why: a rigid body meets the ground with all its touching particles in one sub-step, so each
// contact can aim at separating with e times its approach speed. A soft body's particles are
// stopped one after another over several sub-steps, and a bounce given to a particle is pulled
// back by shape matching; what came back was the deformation the impact stored, whatever e was
// (a linear α 0.3 body rebounded 0.14 of its fall for e = 0 and 0.11 for e = 0.9).
// So for such a pair the contacts are inelastic and the pair's centres of mass follow Newton's
// law of restitution as a whole: an impact starts when the pair comes within contact reach
// while its centres approach faster than the threshold along the pair's normal n (u₀: the
// fastest approach, before the solve, until the surfaces meet; the speculative contacts may
// slow the pair before that);
// once the surfaces meet it compresses while the centres still approach; when they stop approaching
// the relative normal velocity is set to e·u₀, and for as many sub-steps as the compression took (a
// spring's two half-periods are equal), and at least until the softer body has relaxed what it
// stored (relaxSubsteps), it is held at most e·u₀, so the stored deformation that springs back does
// not throw the body off faster than e says (e = 0: it lands dead). The hold is bounded in time
// so that a body resting after an impact can still be lifted off by a drag; it takes back at
// most what the pair's own contacts gave (`pushed`), and the phase applies it only to a pair
// whose bodies touch nothing else (contact_phase.cpp: in piles the holds fought each other). Each
// correction is one impulse along n on the two centres of mass (every particle of a body changes
// its velocity by the same amount), equal and opposite: momentum is exact, and the kinetic energy
// of the relative motion of the centres never exceeds ½μ(e·u₀)² ≤ the impact's (μ the reduced
// mass).
#pragma once

#include <array>

#include "sim/base/types.h"

namespace sb {

// One impact in progress.
struct SoftImpact {
  // The pair: (slot a, slot b) with a < b for two bodies, (slot, −1 − collider) for a collider.
  std::array<int, 2> key = {0, 0};
  Vec3f normal = Vec3f::UnitY();  // unit, from b toward a (out of the collider)
  float approach = 0;             // u₀ > 0: the centres' fastest approach until they met, m/s
  float restitution = 0;          // e in [0, 1]
  bool met = false;               // the surfaces have met (before: contacts within reach only)
  int compressing = 0;            // sub-steps the centres approached
  int released = -1;              // sub-steps since they stopped approaching; −1: not yet
  int relaxing = 0;               // sub-steps the softer body needs to relax (relaxSubsteps)
};

// Sub-steps after which a free body with stiffness α per sub-step keeps at most 1 % of the
// energy a deformation stored: shape matching's position-based update keeps 1 − α of it per
// sub-step (docs/design.md §5.3), so n = ⌈ln 0.01 / ln(1 − α)⌉ (α 0.1: 44, α 0.3: 13, α 0.9:
// 2; 1 for α = 1), at most kMaxRelaxSubsteps. A body held against its obstacle relaxes more
// slowly (it cannot expand without its centre moving away); what it still stores when the hold
// ends springs back: measured at most 2 % of the impact's energy for e = 0 (docs/design.md §5.5).
int relaxSubsteps(double alpha);
// Bodies softer than α ≈ 0.045 store too little stiffness to spring back much, and are not held
// longer (α 0.01 would be held 459 sub-steps, α 0 for ever). The cap was set when holds still
// acted in piles: holding longer kept a body without stiffness (α 0) pressed under heavy bodies
// and spread it to 2.9× its size instead of 1.8× (Contact.BodyWithoutStiffnessUnderAPile-
// StaysWithinItsReach); a body under a pile touches more than its pair and is now never held.
inline constexpr int kMaxRelaxSubsteps = 100;

// Advances an impact by one sub-step, given the relative normal velocity of the centres after
// the contact solve (m/s, (v_a − v_b)·n; < 0: approaching) and whether the surfaces meet (some
// particle inside after the integration). Returns the change of that velocity to apply this
// sub-step (m/s; 0 for none). Returns false in `alive` once the impact is over, or was a near
// miss (the centres stopped approaching before the surfaces met).
// `pushed`: how much the pair's own contacts raised that relative velocity in this sub-step
// (m/s); holding the pair back takes at most that, so the hold never fights what else moves
// the bodies (other bodies, drags, gravity).
float advanceSoftImpact(SoftImpact& impact, float relativeNormalVelocity, bool meets, float pushed,
                        bool& alive);

}  // namespace sb
