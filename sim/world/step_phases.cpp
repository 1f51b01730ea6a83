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
    case Phase::Contacts:
      return "contacts";
    case Phase::Solve:
      return "solve";
    case Phase::Damping:
      return "damping";
    case Phase::Check:
      return "check";
    case Phase::Sleep:
      return "sleep";
  }
  return "?";
}

}  // namespace sb
