// Coulomb friction of one contact visit, as maximal dissipation (docs/design.md §5.5).
//
// Within one visit the kinetic energy, as a function of the contact's accumulated friction
// impulse f (a vector in the tangent plane, N·s), is the convex quadratic
//   E(f) = E(f₀) + s·(f − f₀) + ½ (f − f₀)ᵀ K (f − f₀),
// where s is the tangential slip velocity with f₀ applied (m/s) and K the tangent block of the
// contact's effective inverse mass C M⁻¹ Cᵀ (1/kg; symmetric positive definite). The new
// impulse is the lowest energy inside the cone |f| ≤ μλ: the unconstrained minimiser
// f* = f₀ − K⁻¹s if it lies inside (the contact sticks), else f*'s projection onto the disc in
// K's metric, where the slip that remains is −ν f (ν ≥ 0): friction at the limit, opposite to
// the slip, as Coulomb's law asks.
//
// Why not the radial clamp f*·μλ/|f*| that most impulse solvers use: it is the closest point of
// the disc in the plain metric, not in K's, and with anisotropic K — a body's rigid response
// turns far more easily about one axis than another — it can end at a higher energy than the
// visit started from (tests/sim/test_friction_cone.cpp shows a case).
#pragma once

#include <Eigen/Core>

namespace sb {

// The new accumulated friction impulse (N·s, tangent-plane coordinates) of a visit that starts
// from `before` with slip `slip` (m/s) and may use at most `limit` = μλ ≥ 0 (N·s). An old
// impulse beyond the limit (the normal impulse dropped in this visit) is first brought to the
// limit radially. K must be symmetric positive definite.
Eigen::Vector2f frictionImpulse(const Eigen::Matrix2f& K, const Eigen::Vector2f& slip,
                                const Eigen::Vector2f& before, float limit);

// The point of the disc |f| ≤ radius closest to `outside` (|outside| > radius) in the metric of
// the symmetric positive definite K.
Eigen::Vector2f projectOntoDisc(const Eigen::Matrix2f& K, const Eigen::Vector2f& outside,
                                float radius);

}  // namespace sb
