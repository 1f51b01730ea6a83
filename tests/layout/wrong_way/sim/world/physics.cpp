// Fixture for tests/layout: the physics including the scene layer and JSON (both wrong).
#include "sim/scene/scene.h"
#include <nlohmann/json.hpp>
