// Wall-clock time spent in each phase of World::step, accumulated over its substeps.
#pragma once

namespace sb {

struct StepProfile {
  double external = 0;    // seconds: drags, forces
  double goals = 0;       // seconds: per cluster centre of mass, A_pq, rotation, goal transform
  double plasticity = 0;  // seconds: per cluster plastic update and rest-data rebuild
  double integrate = 0;   // seconds: goal blending, Müller integration
  double damping = 0;     // seconds: damping of non-rigid velocity
  double contacts = 0;    // seconds: body–body contact (bounds, grids, detection, response)
  double collide = 0;     // seconds: static colliders, friction
  double check = 0;       // seconds: NaN/Inf detection and recovery
  double total() const {
    return external + goals + plasticity + integrate + damping + contacts + collide + check;
  }
  StepProfile& operator+=(const StepProfile& o) {
    external += o.external;
    goals += o.goals;
    plasticity += o.plasticity;
    integrate += o.integrate;
    damping += o.damping;
    contacts += o.contacts;
    collide += o.collide;
    check += o.check;
    return *this;
  }
};

}  // namespace sb
