#include "sim/world/external_phase.h"

namespace sb {

void runExternalPhase(const std::vector<QueuedForce>& forces, const std::map<int, DragDef>& drags,
                      double h, std::vector<BodySlot>& slots) {
  for (const QueuedForce& f : forces) {
    BodySlot& b = slots[f.body.index];
    const float dv = float(h / b.model->mass[f.particle]);
    for (int a = 0; a < 3; ++a) b.state.v(f.particle, a) += dv * float(f.force[a]);
  }
  for (const auto& [id, drag] : drags) {
    BodySlot& b = slots[drag.body.index];
    Vec3 point = Vec3::Zero(), pointVelocity = Vec3::Zero();
    double sumW2 = 0;
    for (size_t k = 0; k < drag.particles.size(); ++k) {
      point += drag.weights[k] * b.state.x.row(drag.particles[k]).transpose().cast<double>();
      pointVelocity +=
          drag.weights[k] * b.state.v.row(drag.particles[k]).transpose().cast<double>();
      sumW2 += drag.weights[k] * drag.weights[k];
    }
    // Give the dragged point the velocity that closes `stiffness` of the gap over this sub-step,
    // by the minimum-norm change of the particles' velocities (docs/design.md §5.4). Replacing the
    // point's velocity, rather than adding to it, keeps the pull from oscillating.
    const Vec3 wanted = (drag.stiffness / h) * (drag.target - point);
    const Vec3 change = (wanted - pointVelocity) / sumW2;
    for (size_t k = 0; k < drag.particles.size(); ++k)
      b.state.v.row(drag.particles[k]) += (drag.weights[k] * change).transpose().cast<float>();
  }
}

}  // namespace sb
