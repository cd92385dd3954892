/* GL helpers the passes share: textures, framebuffers with colour and
 * depth targets, and the reversed-Z projection. No pass and no renderer
 * state here, so every file of lib/render may call them. */
#include "render_internal.h"

#include <string.h>

GLuint mr_gl_make_tex(GLenum fmt, int w, int h, GLenum filter) {
    GLuint t;
    glCreateTextures(GL_TEXTURE_2D, 1, &t);
    glTextureStorage2D(t, 1, fmt, w, h);
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, filter);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, filter);
    glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}


void mr_gl_target_free(target *t) {
    glDeleteFramebuffers(1, &t->fbo);
    glDeleteTextures((GLsizei)(sizeof t->color / sizeof t->color[0]), t->color);
    glDeleteTextures(1, &t->depth);
    memset(t, 0, sizeof *t);
}


bool mr_gl_target_make(target *t, int w, int h, const GLenum *fmts, int n, bool depth, mr_error *err) {
    glCreateFramebuffers(1, &t->fbo);
    GLenum bufs[4];
    for (int i = 0; i < n; i++) {
        t->color[i] = mr_gl_make_tex(fmts[i], w, h, GL_NEAREST);
        glNamedFramebufferTexture(t->fbo, GL_COLOR_ATTACHMENT0 + i, t->color[i], 0);
        bufs[i] = GL_COLOR_ATTACHMENT0 + i;
    }
    glNamedFramebufferDrawBuffers(t->fbo, n, bufs);
    if (depth) {
        t->depth = mr_gl_make_tex(GL_DEPTH_COMPONENT32F, w, h, GL_NEAREST);
        glNamedFramebufferTexture(t->fbo, GL_DEPTH_ATTACHMENT, t->depth, 0);
    }
    GLenum st = glCheckNamedFramebufferStatus(t->fbo, GL_FRAMEBUFFER);
    if (st != GL_FRAMEBUFFER_COMPLETE) return mr_fail(err, MR_ERR_GL, "framebuffer incomplete (0x%x)", st);
    return true;
}

/* OpenCV intrinsics to a GL projection. Rows of the image are stored top
 * first, so image row v lands in framebuffer row v. Infinite far plane,
 * reversed Z: z_clip = near, w_clip = z, depth = near / z. */
void mr_gl_projection(const mr_camera *c, double near_plane, float out[16]) {
    mr_dmat4 p;
    memset(&p, 0, sizeof p);
    p.m[0] = 2 * c->fx / c->width;
    p.m[2] = 2 * (c->cx + 0.5) / c->width - 1;
    p.m[5] = 2 * c->fy / c->height;
    p.m[6] = 2 * (c->cy + 0.5) / c->height - 1;
    p.m[11] = near_plane;
    p.m[14] = 1;
    mr_m4_to_gl(&p, out);
}
