// Rolling resistance: the couple a contact pair exchanges against their relative spin
// (docs/design.md §5.5, "Rolling resistance").
//
// Contacts through single particles exert no couple, so a body rolling or rocking on a
// rounded part (a bunny on its back, a ball) kept its rigid motion's energy between pivot
// changes and rocked on for ten seconds after it landed. Real contacts are patches: the load
// shifts to the leading side of the patch and resists the spin with a couple up to b·N, N
// the normal force and b a length (rolling resistance's lever). Here b = c·ρ, c the world's
// dimensionless coefficient and ρ the smaller rest radius of gyration of the pair, so the
// same c means the same resistance for a pebble and a boulder (a ball of radius R rests on a
// slope below tan θ ≈ c).
#pragma once

#include "sim/base/types.h"

namespace sb {

// The angular impulse (N·m·s, world axes) on side a of a pair (−it on side b) against their
// relative spin w = ωa − ωb (rad/s), with the sides' inverse inertias about their centres
// (1/(kg·m²), world axes, zero for a side that does not move), bounded by maxCouple (N·m·s,
// ≥ 0: lever × the pair's normal impulse in the sub-step). It is the impulse that stops the
// relative spin (−K⁺w, K = Ia⁻¹ + Ib⁻¹), scaled down to the bound: the kinetic energy is a
// convex quadratic along that line with its minimum at the full impulse, so any share of it
// takes energy away and never reverses the spin; angular momentum is exchanged, not made.
Vec3 rollingCouple(const Mat3& invInertiaA, const Mat3& invInertiaB, const Vec3& relativeSpin,
                   double maxCouple);

}  // namespace sb
