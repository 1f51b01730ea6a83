// Every accepted range of a parameter, in one place: the World checks its inputs against these,
// the scene parser checks scene fields against them and the command line checks its options, so
// the three can never disagree. Units as in body_def.h / world.h.
#pragma once

#include <string>

namespace sb {

// The closed interval [lo, hi], or (lo, hi] when loOpen.
struct ParamRange {
  double lo, hi;
  bool loOpen = false;
  bool contains(double v) const { return (loOpen ? v > lo : v >= lo) && v <= hi; }
};

// "must be in [lo, hi], got V" when v is outside (NaN included), else "".
std::string rangeViolation(const ParamRange& range, double v);
// The range as text: "[0, 1]" or "(0, 10]".
std::string describe(const ParamRange& range);
// A number as the messages print it (%g).
std::string formatNumber(double v);

namespace limits {
// World settings.
inline constexpr ParamRange timeStep{1e-7, 10.0};  // s, per step() (and per dt of step(dt))
inline constexpr ParamRange substeps{1, 1000};     // sub-steps per step()
// s, longest sub-step before splitting. At most 1 s: longer sub-steps let a pile pass through
// itself in one sub-step (gravity predicts g·h² = 98 m at 10 s) and blow up (world.h).
inline constexpr ParamRange maxSubstep{1e-4, 1.0};
inline constexpr ParamRange gravityNorm{0.0, 1e4};  // m/s², length of the gravity vector
inline constexpr ParamRange friction{0.0, 1000.0};  // μ, colliders and body–body contact
inline constexpr ParamRange restitution{0.0, 1.0};  // e, colliders and bodies
inline constexpr ParamRange restitutionThreshold{0.0, 1e4};  // m/s
inline constexpr ParamRange rollingResistance{0.0, 1.0};     // dimensionless (lever / ρ)
// Body parameters.
inline constexpr ParamRange alpha{0.0, 1.0};
inline constexpr ParamRange beta{0.0, 1.0};
inline constexpr ParamRange damping{0.0, 1.0};
inline constexpr ParamRange plasticYield{0.0, 1e6};
inline constexpr ParamRange plasticCreep{0.0, 1e6};  // 1/s
// ‖Sᵖ − I‖₂ ≤ 2 (a stretch up to ×3 along an axis, as the fits' own bound): beyond, Sᵖ (det 1)
// is so anisotropic that A_qq⁻¹ of the rest shape amplifies round-off into far-away goals.
inline constexpr ParamRange plasticMax{0.0, 2.0};
inline constexpr ParamRange bodyMass{1e-9, 1e9};       // kg, a body's total mass
inline constexpr ParamRange particleMass{1e-12, 1e9};  // kg, one particle's mass
inline constexpr ParamRange cellSize{1e-6, 1e6};       // m, grid clusters
inline constexpr ParamRange overlap{0.0, 1e6};         // m, grid clusters
inline constexpr ParamRange dragStiffness{0.0, 1.0};   // fraction of the gap per step
// Placement (scene files): coordinates, speeds, angles, scale, collider sizes.
inline constexpr double coordinateLimit = 1e6;  // m, |component| of positions and offsets
inline constexpr double speedLimit = 1e4;       // m/s, |component| of initial velocities
inline constexpr double angleLimit = 1e4;       // degrees, |component| of Euler angles
inline constexpr ParamRange scale{1e-9, 1e9};   // uniform scale of a body's mesh
inline constexpr ParamRange radius{1e-9, 1e6};  // m, sphere and capsule colliders
// What the float32 particle state can carry (float resolves about 6e-8 of a coordinate): a
// body of two or more particles must be at least minBodyExtent across (diagonal of its
// bounding box) and at least minExtentToDistance times the distance of its farthest particle
// from the origin; smaller, its shape drowns in round-off (a body at scale 1e-6 spreads to
// metres). So a 1 mm body may sit up to 10 m from the origin, a 1 m body up to 10 km.
inline constexpr double minBodyExtent = 1e-4;        // m
inline constexpr double minExtentToDistance = 1e-4;  // extent / distance from the origin
}  // namespace limits

}  // namespace sb
