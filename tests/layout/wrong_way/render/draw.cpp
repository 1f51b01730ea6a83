// Fixture for tests/layout: render including the simulation (wrong).
#include "sim/base/types.h"
