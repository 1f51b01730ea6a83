#include "sim/world/param_ranges.h"

#include <cstdio>

namespace sb {

std::string formatNumber(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

std::string describe(const ParamRange& range) {
  return std::string(range.loOpen ? "(" : "[") + formatNumber(range.lo) + ", " +
         formatNumber(range.hi) + "]";
}

std::string rangeViolation(const ParamRange& range, double v) {
  if (range.contains(v)) return "";
  return "must be in " + describe(range) + ", got " + formatNumber(v);
}

}  // namespace sb
