/* The 2D layer of the window: the renderer's finished frame scaled into a
 * rectangle of the window, then the touch UI's draw list on top, both with
 * one small program. Vertices stream through one buffer that grows as
 * needed; the atlas is uploaded only when its version changes. */
#include "window_internal.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

/* UI vertices are drawn as they are. */
_Static_assert(sizeof(mr_ui_vertex) == sizeof(mr_draw2d_vertex), "vertex layouts differ");
_Static_assert(offsetof(mr_ui_vertex, u) == offsetof(mr_draw2d_vertex, u), "vertex layouts differ");
_Static_assert(offsetof(mr_ui_vertex, rgba) == offsetof(mr_draw2d_vertex, rgba), "vertex layouts differ");

struct mr_draw2d {
    mr_gpu *gpu;
    GLuint prog, vao, vbo, ibo, atlas;
    GLuint sampler;            /* linear filtering for the scaled frame */
    size_t vbo_bytes, ibo_bytes;
    uint32_t atlas_version;
    int atlas_w, atlas_h;
    int fb_w, fb_h;
};

static GLuint make_tex(GLenum fmt, int w, int h, GLenum filter) {
    GLuint t;
    glCreateTextures(GL_TEXTURE_2D, 1, &t);
    glTextureStorage2D(t, 1, fmt, w, h);
    glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, filter);
    glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, filter);
    glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return t;
}

mr_draw2d *mr_draw2d_create(mr_gpu *gpu, mr_error *err) {
    if (!gpu) {
        mr_fail(err, MR_ERR_INVALID, "2D layer needs a GPU context");
        return NULL;
    }
    mr_draw2d *d = calloc(1, sizeof *d);
    if (!d) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    d->gpu = gpu;
    static const char *const files[] = {"ui.vert.glsl", "ui.frag.glsl", NULL};
    if (!(d->prog = mr_gpu_program(files, err))) {
        free(d);
        return NULL;
    }
    glCreateVertexArrays(1, &d->vao);
    static const GLuint attrs[3] = {MR_ATTR_UI_POS, MR_ATTR_UI_UV, MR_ATTR_UI_COLOR};
    for (int a = 0; a < 3; a++) {
        glEnableVertexArrayAttrib(d->vao, attrs[a]);
        glVertexArrayAttribBinding(d->vao, attrs[a], 0);
    }
    glVertexArrayAttribFormat(d->vao, MR_ATTR_UI_POS, 2, GL_FLOAT, GL_FALSE, (GLuint)offsetof(mr_draw2d_vertex, x));
    glVertexArrayAttribFormat(d->vao, MR_ATTR_UI_UV, 2, GL_FLOAT, GL_FALSE, (GLuint)offsetof(mr_draw2d_vertex, u));
    glVertexArrayAttribFormat(d->vao, MR_ATTR_UI_COLOR, 4, GL_UNSIGNED_BYTE, GL_TRUE, (GLuint)offsetof(mr_draw2d_vertex, rgba));
    /* A sampler object, so the renderer's textures keep their own (nearest)
     * filtering for its passes. */
    glCreateSamplers(1, &d->sampler);
    glSamplerParameteri(d->sampler, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glSamplerParameteri(d->sampler, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glSamplerParameteri(d->sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glSamplerParameteri(d->sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return d;
}

void mr_draw2d_destroy(mr_draw2d **dp) {
    if (!dp || !*dp) return;
    mr_draw2d *d = *dp;
    glDeleteProgram(d->prog);
    glDeleteVertexArrays(1, &d->vao);
    glDeleteBuffers(1, &d->vbo);
    glDeleteBuffers(1, &d->ibo);
    glDeleteTextures(1, &d->atlas);
    glDeleteSamplers(1, &d->sampler);
    free(d);
    *dp = NULL;
}

void mr_draw2d_begin(mr_draw2d *d, int fb_w, int fb_h, const float clear_srgb[3]) {
    d->fb_w = fb_w > 0 ? fb_w : 1;
    d->fb_h = fb_h > 0 ? fb_h : 1;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, d->fb_w, d->fb_h);
    /* We write encoded sRGB values ourselves. */
    glDisable(GL_FRAMEBUFFER_SRGB);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glClearColor(clear_srgb[0], clear_srgb[1], clear_srgb[2], 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
}

/* Streams vertices and indices into buffers that only ever grow (buffer
 * storage is immutable, so a bigger one replaces the old). */
static bool upload(GLuint *buf, size_t *have, const void *data, size_t bytes) {
    if (bytes > *have) {
        glDeleteBuffers(1, buf);
        size_t cap = *have ? *have : 64 * 1024;
        while (cap < bytes) cap *= 2;
        glCreateBuffers(1, buf);
        glNamedBufferStorage(*buf, (GLsizeiptr)cap, NULL, GL_DYNAMIC_STORAGE_BIT);
        *have = cap;
    }
    if (bytes) glNamedBufferSubData(*buf, 0, (GLsizeiptr)bytes, data);
    return true;
}

static void draw(mr_draw2d *d, int mode, GLuint tex, int index_count) {
    glUseProgram(d->prog);
    glUniform2f(MR_LOC_UI_FB_SIZE, (float)d->fb_w, (float)d->fb_h);
    glUniform1i(MR_LOC_UI_MODE, mode);
    glBindTextureUnit(MR_TEX_UI_TEX, tex);
    glVertexArrayVertexBuffer(d->vao, 0, d->vbo, 0, sizeof(mr_draw2d_vertex));
    glVertexArrayElementBuffer(d->vao, d->ibo);
    glBindVertexArray(d->vao);
    glDrawElements(GL_TRIANGLES, index_count, GL_UNSIGNED_INT, NULL);
    glBindVertexArray(0);
}

/* One texture, top row first, over the rectangle (x, y, w, h), unblended. */
static bool textured_quad(mr_draw2d *d, GLuint tex, float x, float y, float w, float h, const char *what,
                          mr_error *err) {
    /* Textures hold the top image row first, so v runs with y. */
    const mr_draw2d_vertex v[4] = {
        {x, y, 0, 0, 0xffffffffu}, {x + w, y, 1, 0, 0xffffffffu},
        {x + w, y + h, 1, 1, 0xffffffffu}, {x, y + h, 0, 1, 0xffffffffu},
    };
    static const uint32_t ix[6] = {0, 1, 2, 0, 2, 3};
    upload(&d->vbo, &d->vbo_bytes, v, sizeof v);
    upload(&d->ibo, &d->ibo_bytes, ix, sizeof ix);
    glDisable(GL_BLEND);
    glBindSampler(MR_TEX_UI_TEX, d->sampler);
    draw(d, 1, tex, 6);
    glBindSampler(MR_TEX_UI_TEX, 0);
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) return mr_fail(err, MR_ERR_GL, "GL error 0x%x drawing %s", e, what);
    return true;
}

bool mr_draw2d_frame(mr_draw2d *d, mr_renderer *r, float x, float y, float w, float h, mr_error *err) {
    GLuint tex = mr_renderer_frame_texture(r);
    if (!tex) return mr_fail(err, MR_ERR_INVALID, "no rendered frame to show");
    return textured_quad(d, tex, x, y, w, h, "the frame", err);
}

struct mr_draw2d_image {
    GLuint tex;
};

mr_draw2d_image *mr_draw2d_image_create(mr_draw2d *d, const mr_image *img, mr_error *err) {
    if (!d || !img || !img->data || img->type != MR_PIX_U8 || img->width <= 0 || img->height <= 0 ||
        !(img->channels == 1 || img->channels == 3 || img->channels == 4)) {
        mr_fail(err, MR_ERR_INVALID, "2D image: needs an 8-bit image with 1, 3 or 4 channels");
        return NULL;
    }
    mr_draw2d_image *im = calloc(1, sizeof *im);
    if (!im) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    /* sRGB storage: the 2D program decodes on sampling and re-encodes, so
     * the pixels reach the window as they are in the file. */
    im->tex = make_tex(GL_SRGB8_ALPHA8, img->width, img->height, GL_LINEAR);
    static const GLenum fmts[5] = {0, GL_RED, 0, GL_RGB, GL_RGBA};
    if (img->channels == 1) {
        const GLint swz[4] = {GL_RED, GL_RED, GL_RED, GL_ONE};
        glTextureParameteriv(im->tex, GL_TEXTURE_SWIZZLE_RGBA, swz);
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    /* Images are top row first and so is the 2D layer's v. */
    glTextureSubImage2D(im->tex, 0, 0, 0, img->width, img->height, fmts[img->channels], GL_UNSIGNED_BYTE, img->data);
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) {
        mr_draw2d_image_destroy(&im);
        mr_fail(err, MR_ERR_GL, "GL error 0x%x uploading a 2D image", e);
        return NULL;
    }
    return im;
}

void mr_draw2d_image_destroy(mr_draw2d_image **im) {
    if (!im || !*im) return;
    glDeleteTextures(1, &(*im)->tex);
    free(*im);
    *im = NULL;
}

bool mr_draw2d_image_draw(mr_draw2d *d, const mr_draw2d_image *im, float x, float y, float w, float h, mr_error *err) {
    if (!im) return mr_fail(err, MR_ERR_INVALID, "no 2D image to draw");
    return textured_quad(d, im->tex, x, y, w, h, "a 2D image", err);
}

bool mr_draw2d_list_draw(mr_draw2d *d, const mr_draw2d_list *l, mr_error *err) {
    if (!l || l->index_count <= 0) return true;
    if (!l->atlas || l->atlas_w <= 0 || l->atlas_h <= 0) return mr_fail(err, MR_ERR_INVALID, "2D list without an atlas");
    if (!d->atlas || d->atlas_version != l->atlas_version || d->atlas_w != l->atlas_w || d->atlas_h != l->atlas_h) {
        glDeleteTextures(1, &d->atlas);
        d->atlas = make_tex(GL_R8, l->atlas_w, l->atlas_h, GL_LINEAR);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTextureSubImage2D(d->atlas, 0, 0, 0, l->atlas_w, l->atlas_h, GL_RED, GL_UNSIGNED_BYTE, l->atlas);
        d->atlas_version = l->atlas_version;
        d->atlas_w = l->atlas_w;
        d->atlas_h = l->atlas_h;
    }
    upload(&d->vbo, &d->vbo_bytes, l->vertices, (size_t)l->vertex_count * sizeof *l->vertices);
    upload(&d->ibo, &d->ibo_bytes, l->indices, (size_t)l->index_count * sizeof *l->indices);
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
    draw(d, 0, d->atlas, l->index_count);
    glDisable(GL_BLEND);
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) return mr_fail(err, MR_ERR_GL, "GL error 0x%x drawing the UI", e);
    return true;
}

bool mr_draw2d_read(mr_draw2d *d, mr_image *out, mr_error *err) {
    if (!mr_image_alloc(out, d->fb_w, d->fb_h, 3, MR_PIX_U8, err)) return false;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, d->fb_w, d->fb_h, GL_RGB, GL_UNSIGNED_BYTE, out->data);
    /* GL's rows run bottom-up; images here are top row first. */
    size_t row = (size_t)d->fb_w * 3;
    uint8_t *p = out->data, *tmp = malloc(row);
    if (!tmp) {
        mr_image_free(out);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    for (int y = 0; y < d->fb_h / 2; y++) {
        uint8_t *a = p + (size_t)y * row, *b = p + (size_t)(d->fb_h - 1 - y) * row;
        memcpy(tmp, a, row);
        memcpy(a, b, row);
        memcpy(b, tmp, row);
    }
    free(tmp);
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) {
        mr_image_free(out);
        return mr_fail(err, MR_ERR_GL, "GL error 0x%x reading the window", e);
    }
    return true;
}

void mr_draw2d_ui(mr_draw2d *d, const mr_ui_draw_list *dl, const char *cmd) {
    mr_draw2d_list l = {(const mr_draw2d_vertex *)dl->vertices, dl->vertex_count, dl->indices, dl->index_count,
                        dl->atlas, dl->atlas_w, dl->atlas_h, dl->atlas_version};
    mr_error err = {0};
    if (!mr_draw2d_list_draw(d, &l, &err)) mr_log(MR_LOG_ERROR, "%s: %s", cmd, err.msg);
}
