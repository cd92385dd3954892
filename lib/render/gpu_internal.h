/* Private to lib/render: GL headers and the shader library. */
#ifndef MR_GPU_INTERNAL_H
#define MR_GPU_INTERNAL_H

#include "mr_render.h"

/* glvnd's libOpenGL exports every core entry point up to 4.6, so prototypes
 * are enough and no loader is needed. */
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

/* Builds a program from embedded shaders/<name> files (NULL-terminated list
 * of stage file names: *.vert.glsl, *.frag.glsl, *.comp.glsl). Lines of the
 * form `#include "x.glsl"` are replaced by that file. Returns 0 + err. */
GLuint mr_gl_program(const char *const *files, mr_error *err);
/* The embedded source of shaders/<name>, or NULL. */
const char *mr_shader_source(const char *name);

#endif
