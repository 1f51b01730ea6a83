#include "sim/world/step_phases.h"

namespace sb {

const char* phaseName(Phase phase) {
  switch (phase) {
    case Phase::External:
      return "external";
    case Phase::Predict:
      return "predict";
    case Phase::Goals:
      return "goals";
    case Phase::Plasticity:
      return "plasticity";
    case Phase::Project:
      return "project";
    case Phase::WholeBody:
      return "wholebody";
    case Phase::Velocities:
      return "velocities";
    case Phase::Damping:
      return "damping";
    case Phase::Contacts:
      return "contacts";
    case Phase::Collide:
      return "collide";
    case Phase::Check:
      return "check";
  }
  return "?";
}

}  // namespace sb
