/* Private to lib/window: the GL entry points the 2D layer calls and the
 * binding numbers it shares with shaders/ui.*.glsl. */
#ifndef MR_WINDOW_INTERNAL_H
#define MR_WINDOW_INTERNAL_H

#include "mr_window.h"

/* glvnd's libOpenGL exports every core entry point up to 4.6, so prototypes
 * are enough and no loader is needed. */
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include "mr_bindings.h" /* uniform locations and texture units, shared with the GLSL */

#endif
