// The one place that includes OpenGL: core 3.3 prototypes straight from glvnd's libGL, no loader
// (toolchain.md). Every render file includes this instead of a GL header.
#pragma once

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/glcorearb.h>
