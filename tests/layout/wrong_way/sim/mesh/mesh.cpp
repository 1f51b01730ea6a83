// Fixture for tests/layout: the mesh layer including the physics (wrong way).
#include "sim/world/world.h"
