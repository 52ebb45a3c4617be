// The OpenGL headers with prototypes of GL 2.0+ entry points (libglvnd's libOpenGL/libGL export them all on Linux).
#pragma once

#ifndef GL_GLEXT_PROTOTYPES
#define GL_GLEXT_PROTOTYPES 1
#endif
#include <GL/gl.h>
#include <GL/glext.h>
