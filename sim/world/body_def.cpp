#include "sim/world/body_def.h"

namespace sb {

const char* modeName(Mode mode) {
  switch (mode) {
    case Mode::Rigid:
      return "rigid";
    case Mode::Linear:
      return "linear";
    case Mode::Quadratic:
      return "quadratic";
  }
  return "?";
}

bool parseMode(const std::string& text, Mode* mode) {
  for (Mode m : {Mode::Rigid, Mode::Linear, Mode::Quadratic}) {
    if (text == modeName(m)) {
      *mode = m;
      return true;
    }
  }
  return false;
}

const char* clusterKindName(ClusterDef::Kind kind) {
  switch (kind) {
    case ClusterDef::Kind::Single:
      return "single";
    case ClusterDef::Kind::Grid:
      return "grid";
    case ClusterDef::Kind::Explicit:
      return "explicit";
  }
  return "?";
}

}  // namespace sb
