// Fixture for tests/layout: the physics including the scene layer and JSON (both wrong).
#include <nlohmann/json.hpp>
#include "sim/scene/scene.h"
