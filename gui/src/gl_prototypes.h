// Force-included into Dear ImGui's OpenGL 3 backend (gui/CMakeLists.txt):
// the GL 3 entry points as plain prototypes, resolved at link time against
// libOSMesa (off-screen shell) or libGL (window), with no loader.
#pragma once
#include <GL/gl.h>
#include <GL/glext.h>
