/* The renderer: scene upload, render targets and the frame's pass list.
 *
 * A frame is a list of passes, each with a predicate saying whether this
 * frame needs it; only the needed ones run and are reported (a scene without
 * video runs no overlay pass, and so on). Later passes (AO, ghosting) slot
 * into the table in mr_render_frame. */
#include "gpu_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct gl_mesh {
    GLuint vao, vbo[3], ibo; /* positions, normals, uvs */
    uint32_t index_count;
} gl_mesh;

typedef struct target {
    GLuint fbo, color[3], depth;
} target;

struct mr_renderer {
    mr_gpu *gpu;
    const mr_scene *scene;
    gl_mesh *meshes;
    int32_t mesh_count;
    GLuint *textures;
    int32_t texture_count;
    GLuint prog_gbuffer, prog_shade, prog_overlay;
    GLuint empty_vao;
    int w, h;              /* current target size */
    target gbuf;           /* albedo (sRGB8), normal (RGBA16F), ids (RG32UI), depth (32F) */
    target shaded;         /* sRGB8: the virtual image */
    target composed;       /* sRGB8: virtual + video */
    GLuint video_tex;
    int video_w, video_h;
    GLuint queries[MR_MAX_PASSES];
};

/* ------------------------------------------------------------- set-up */

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

static void target_free(target *t) {
    glDeleteFramebuffers(1, &t->fbo);
    glDeleteTextures(3, t->color);
    glDeleteTextures(1, &t->depth);
    memset(t, 0, sizeof *t);
}

static bool target_make(target *t, int w, int h, const GLenum *fmts, int n, bool depth, mr_error *err) {
    glCreateFramebuffers(1, &t->fbo);
    GLenum bufs[3];
    for (int i = 0; i < n; i++) {
        t->color[i] = make_tex(fmts[i], w, h, GL_NEAREST);
        glNamedFramebufferTexture(t->fbo, GL_COLOR_ATTACHMENT0 + i, t->color[i], 0);
        bufs[i] = GL_COLOR_ATTACHMENT0 + i;
    }
    glNamedFramebufferDrawBuffers(t->fbo, n, bufs);
    if (depth) {
        t->depth = make_tex(GL_DEPTH_COMPONENT32F, w, h, GL_NEAREST);
        glNamedFramebufferTexture(t->fbo, GL_DEPTH_ATTACHMENT, t->depth, 0);
    }
    GLenum st = glCheckNamedFramebufferStatus(t->fbo, GL_FRAMEBUFFER);
    if (st != GL_FRAMEBUFFER_COMPLETE) return mr_fail(err, MR_ERR_GL, "framebuffer incomplete (0x%x)", st);
    return true;
}

static bool ensure_targets(mr_renderer *r, int w, int h, mr_error *err) {
    if (r->w == w && r->h == h) return true;
    target_free(&r->gbuf);
    target_free(&r->shaded);
    target_free(&r->composed);
    r->w = r->h = 0;
    static const GLenum gfmt[3] = {GL_SRGB8_ALPHA8, GL_RGBA16F, GL_RG32UI};
    static const GLenum cfmt[1] = {GL_SRGB8_ALPHA8};
    if (!target_make(&r->gbuf, w, h, gfmt, 3, true, err) || !target_make(&r->shaded, w, h, cfmt, 1, false, err) ||
        !target_make(&r->composed, w, h, cfmt, 1, false, err))
        return false;
    r->w = w;
    r->h = h;
    return true;
}

mr_renderer *mr_renderer_create(mr_gpu *gpu, mr_error *err) {
    if (!gpu) {
        mr_fail(err, MR_ERR_INVALID, "renderer needs a GPU context");
        return NULL;
    }
    mr_renderer *r = calloc(1, sizeof *r);
    if (!r) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    r->gpu = gpu;
    static const char *const gb[] = {"gbuffer.vert.glsl", "gbuffer.frag.glsl", NULL};
    static const char *const sh[] = {"fullscreen.vert.glsl", "shade.frag.glsl", NULL};
    static const char *const ov[] = {"fullscreen.vert.glsl", "overlay.frag.glsl", NULL};
    if (!(r->prog_gbuffer = mr_gl_program(gb, err)) || !(r->prog_shade = mr_gl_program(sh, err)) ||
        !(r->prog_overlay = mr_gl_program(ov, err))) {
        mr_renderer_destroy(&r);
        return NULL;
    }
    glCreateVertexArrays(1, &r->empty_vao);
    glGenQueries(MR_MAX_PASSES, r->queries);
    /* Reversed-Z: depth = near / z, so 1 is the near plane and 0 infinity. */
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    return r;
}

static void free_scene_gpu(mr_renderer *r) {
    for (int32_t i = 0; i < r->mesh_count; i++) {
        glDeleteVertexArrays(1, &r->meshes[i].vao);
        glDeleteBuffers(3, r->meshes[i].vbo);
        glDeleteBuffers(1, &r->meshes[i].ibo);
    }
    free(r->meshes);
    r->meshes = NULL;
    r->mesh_count = 0;
    if (r->textures) glDeleteTextures(r->texture_count, r->textures);
    free(r->textures);
    r->textures = NULL;
    r->texture_count = 0;
    r->scene = NULL;
}

void mr_renderer_destroy(mr_renderer **rp) {
    if (!rp || !*rp) return;
    mr_renderer *r = *rp;
    free_scene_gpu(r);
    target_free(&r->gbuf);
    target_free(&r->shaded);
    target_free(&r->composed);
    glDeleteTextures(1, &r->video_tex);
    glDeleteProgram(r->prog_gbuffer);
    glDeleteProgram(r->prog_shade);
    glDeleteProgram(r->prog_overlay);
    glDeleteVertexArrays(1, &r->empty_vao);
    glDeleteQueries(MR_MAX_PASSES, r->queries);
    free(r);
    *rp = NULL;
}

static GLuint upload_buffer(const void *data, size_t bytes) {
    GLuint b;
    glCreateBuffers(1, &b);
    glNamedBufferStorage(b, (GLsizeiptr)bytes, data, 0);
    return b;
}

bool mr_renderer_set_scene(mr_renderer *r, const mr_scene *s, mr_error *err) {
    free_scene_gpu(r);
    if (!s) return true;
    r->meshes = calloc((size_t)s->mesh_count + 1, sizeof *r->meshes);
    r->textures = calloc((size_t)s->texture_count + 1, sizeof *r->textures);
    if (!r->meshes || !r->textures) {
        free_scene_gpu(r);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory uploading the scene");
    }
    /* UVs are uploaded only for meshes whose material samples a texture. */
    for (int32_t i = 0; i < s->mesh_count; i++) {
        const mr_mesh *m = &s->meshes[i];
        gl_mesh *g = &r->meshes[i];
        bool textured = m->uvs && m->material >= 0 && m->material < s->material_count &&
                        s->materials[m->material].base_color_texture >= 0;
        glCreateVertexArrays(1, &g->vao);
        g->vbo[0] = upload_buffer(m->positions, (size_t)m->vertex_count * 12);
        g->vbo[1] = upload_buffer(m->normals, (size_t)m->vertex_count * 12);
        glVertexArrayVertexBuffer(g->vao, 0, g->vbo[0], 0, 12);
        glVertexArrayVertexBuffer(g->vao, 1, g->vbo[1], 0, 12);
        for (GLuint a = 0; a < 2; a++) {
            glEnableVertexArrayAttrib(g->vao, a);
            glVertexArrayAttribFormat(g->vao, a, 3, GL_FLOAT, GL_FALSE, 0);
            glVertexArrayAttribBinding(g->vao, a, a);
        }
        if (textured) {
            g->vbo[2] = upload_buffer(m->uvs, (size_t)m->vertex_count * 8);
            glVertexArrayVertexBuffer(g->vao, 2, g->vbo[2], 0, 8);
            glEnableVertexArrayAttrib(g->vao, 2);
            glVertexArrayAttribFormat(g->vao, 2, 2, GL_FLOAT, GL_FALSE, 0);
            glVertexArrayAttribBinding(g->vao, 2, 2);
        }
        g->ibo = upload_buffer(m->indices, (size_t)m->index_count * 4);
        glVertexArrayElementBuffer(g->vao, g->ibo);
        g->index_count = m->index_count;
    }
    r->mesh_count = s->mesh_count;
    for (int32_t i = 0; i < s->texture_count; i++) {
        const mr_texture *t = &s->textures[i];
        if (!t->image.data || t->image.channels != 4 || t->image.type != MR_PIX_U8) {
            free_scene_gpu(r);
            return mr_fail(err, MR_ERR_INVALID, "texture %d is not RGBA8", (int)i);
        }
        int w = t->image.width, h = t->image.height, levels = 1;
        while ((w >> levels) > 0 || (h >> levels) > 0) levels++;
        GLuint tex;
        glCreateTextures(GL_TEXTURE_2D, 1, &tex);
        glTextureStorage2D(tex, levels, GL_SRGB8_ALPHA8, w, h);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTextureSubImage2D(tex, 0, 0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, t->image.data);
        glGenerateTextureMipmap(tex);
        glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
        glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, t->nearest ? GL_NEAREST : GL_LINEAR);
        r->textures[i] = tex;
    }
    r->texture_count = s->texture_count;
    r->scene = s;
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) {
        free_scene_gpu(r);
        return mr_fail(err, MR_ERR_GL, "GL error 0x%x while uploading the scene", e);
    }
    return true;
}

/* -------------------------------------------------------------- frame */

typedef struct frame {
    mr_renderer *r;
    const mr_view *view;
    const mr_frame_params *p;
    mr_camera cam;          /* the view's camera at the output size */
    mr_dmat4 cam_from_world;
    double near_plane;
    mr_frame_result *out;
    GLuint final_tex;       /* the texture holding the finished image */
} frame;

/* Near plane: half the distance to the scene's bounding box, but never below
 * 1e-6 of the scene's size (so it scales with the scene's units). Reversed
 * float depth keeps precision at any distance, so only clipping matters. */
static double choose_near(const mr_scene *s, mr_dvec3 eye) {
    double d2 = 0, diag2 = 0;
    for (int i = 0; i < 3; i++) {
        const double *e = &eye.x;
        double lo = s->bounds_min[i], hi = s->bounds_max[i];
        double v = e[i] < lo ? lo - e[i] : e[i] > hi ? e[i] - hi : 0;
        d2 += v * v;
        diag2 += (hi - lo) * (hi - lo);
    }
    double diag = sqrt(diag2);
    if (!(diag > 0) || !isfinite(diag)) diag = 1;
    double n = 0.5 * sqrt(d2);
    return n > 1e-6 * diag ? n : 1e-6 * diag;
}

/* OpenCV intrinsics to a GL projection. Rows of the image are stored top
 * first, so image row v lands in framebuffer row v. Infinite far plane,
 * reversed Z: z_clip = near, w_clip = z, depth = near / z. */
static void projection(const mr_camera *c, double near_plane, float out[16]) {
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

static bool need_always(frame *f) { (void)f; return true; }
static bool need_overlay(frame *f) { return f->p->video != NULL; }

static void run_gbuffer(frame *f) {
    mr_renderer *r = f->r;
    const mr_scene *s = r->scene;
    glBindFramebuffer(GL_FRAMEBUFFER, r->gbuf.fbo);
    glViewport(0, 0, r->w, r->h);
    glEnable(GL_FRAMEBUFFER_SRGB);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    static const float zero4[4] = {0, 0, 0, 0};
    static const GLuint zero_u[4] = {0, 0, 0, 0};
    static const float depth0 = 0.0f; /* reversed Z: clear to infinity */
    glClearNamedFramebufferfv(r->gbuf.fbo, GL_COLOR, 0, zero4);
    glClearNamedFramebufferfv(r->gbuf.fbo, GL_COLOR, 1, zero4);
    glClearNamedFramebufferuiv(r->gbuf.fbo, GL_COLOR, 2, zero_u);
    glClearNamedFramebufferfv(r->gbuf.fbo, GL_DEPTH, 0, &depth0);
    if (!s) return;
    glUseProgram(r->prog_gbuffer);
    float proj[16];
    projection(&f->cam, f->near_plane, proj);
    glUniformMatrix4fv(2, 1, GL_FALSE, proj);
    for (int32_t ni = 0; ni < s->node_count; ni++) {
        const mr_node *n = &s->nodes[ni];
        if (n->mesh_first < 0 || n->mesh_count <= 0) continue;
        if (f->p->hide_hidden_layer && n->layer == MR_LAYER_HIDDEN) continue;
        mr_dmat4 cam_from_node = mr_m4_mul(&f->cam_from_world, &n->world);
        glUniform2ui(5, (GLuint)ni + 1, n->layer);
        for (int32_t k = 0; k < n->mesh_count; k++) {
            int32_t mi = n->mesh_first + k;
            if (mi >= r->mesh_count) break;
            const mr_mesh *m = &s->meshes[mi];
            /* Camera-relative in double, then float: this is what keeps a
             * scene 1e7 units from the origin as sharp as one at it. */
            mr_dmat4 T = mr_m4_translate(m->origin[0], m->origin[1], m->origin[2]);
            mr_dmat4 mv = mr_m4_mul(&cam_from_node, &T);
            mr_dmat4 inv;
            float mvf[16], nm[9];
            mr_m4_to_gl(&mv, mvf);
            if (!mr_m4_invert(&mv, &inv)) continue; /* degenerate (zero scale): nothing to draw */
            for (int rr = 0; rr < 3; rr++)
                for (int cc = 0; cc < 3; cc++) nm[cc * 3 + rr] = (float)inv.m[cc * 4 + rr]; /* transpose */
            glUniformMatrix4fv(0, 1, GL_FALSE, mvf);
            glUniformMatrix3fv(1, 1, GL_FALSE, nm);
            float color[4] = {0.7f, 0.7f, 0.7f, 1.0f};
            int has_tex = 0;
            if (m->material >= 0 && m->material < s->material_count) {
                const mr_material *mat = &s->materials[m->material];
                memcpy(color, mat->base_color, sizeof color);
                if (mat->base_color_texture >= 0 && mat->base_color_texture < r->texture_count && m->uvs) {
                    glBindTextureUnit(0, r->textures[mat->base_color_texture]);
                    has_tex = 1;
                }
            }
            glUniform4fv(3, 1, color);
            glUniform1i(4, has_tex);
            glBindVertexArray(r->meshes[mi].vao);
            glDrawElements(GL_TRIANGLES, (GLsizei)r->meshes[mi].index_count, GL_UNSIGNED_INT, NULL);
            f->out->triangles += r->meshes[mi].index_count / 3;
            f->out->draw_calls++;
        }
    }
    glBindVertexArray(0);
    glDisable(GL_DEPTH_TEST);
}

static void run_shade(frame *f) {
    mr_renderer *r = f->r;
    glBindFramebuffer(GL_FRAMEBUFFER, r->shaded.fbo);
    glViewport(0, 0, r->w, r->h);
    glEnable(GL_FRAMEBUFFER_SRGB);
    glUseProgram(r->prog_shade);
    const mr_scene *s = r->scene;
    float dirs[8][3], cols[8][3];
    int nl = 0;
    static const mr_light default_lights[2] = {
        {{0.4, 1.0, 0.25}, {0.55f, 0.55f, 0.52f}}, /* sun */
        {{-0.5, 0.3, -0.7}, {0.18f, 0.19f, 0.22f}}, /* sky fill */
    };
    const mr_light *lights = s && s->light_count > 0 ? s->lights : default_lights;
    int count = s && s->light_count > 0 ? s->light_count : 2;
    for (int i = 0; i < count && i < 8; i++) {
        /* World direction to camera axes with the pose's rotation only. */
        mr_dvec3 d = mr_v3_normalize(mr_m4_dir(&f->cam_from_world, mr_v3(lights[i].direction[0], lights[i].direction[1],
                                                                        lights[i].direction[2])));
        dirs[nl][0] = (float)d.x; dirs[nl][1] = (float)d.y; dirs[nl][2] = (float)d.z;
        memcpy(cols[nl], lights[i].color, sizeof cols[nl]);
        nl++;
    }
    glUniform1i(0, nl);
    if (nl) {
        glUniform3fv(1, nl, &dirs[0][0]);
        glUniform3fv(9, nl, &cols[0][0]);
    }
    glUniform1f(17, s ? s->ambient : 0.35f);
    float bg[3];
    for (int i = 0; i < 3; i++) {
        float c = f->p->background[i];
        bg[i] = c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
    }
    glUniform3fv(18, 1, bg);
    glBindTextureUnit(0, r->gbuf.color[0]);
    glBindTextureUnit(1, r->gbuf.color[1]);
    glBindVertexArray(r->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    f->final_tex = r->shaded.color[0];
}

static void run_overlay(frame *f) {
    mr_renderer *r = f->r;
    const mr_image *v = f->p->video;
    GLenum fmt = v->channels == 1 ? GL_RED : v->channels == 2 ? GL_RG : v->channels == 3 ? GL_RGB : GL_RGBA;
    if (!r->video_tex || r->video_w != v->width || r->video_h != v->height) {
        glDeleteTextures(1, &r->video_tex);
        r->video_tex = make_tex(GL_SRGB8_ALPHA8, v->width, v->height, GL_LINEAR);
        r->video_w = v->width;
        r->video_h = v->height;
    }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage2D(r->video_tex, 0, 0, 0, v->width, v->height, fmt, GL_UNSIGNED_BYTE, v->data);
    /* Grey frames: replicate red into green and blue. */
    GLint swz[4] = {GL_RED, v->channels < 3 ? GL_RED : GL_GREEN, v->channels < 3 ? GL_RED : GL_BLUE, GL_ONE};
    glTextureParameteriv(r->video_tex, GL_TEXTURE_SWIZZLE_RGBA, swz);
    glBindFramebuffer(GL_FRAMEBUFFER, r->composed.fbo);
    glViewport(0, 0, r->w, r->h);
    glEnable(GL_FRAMEBUFFER_SRGB);
    glUseProgram(r->prog_overlay);
    /* The view's camera describes the raw video frame at its own size. */
    mr_camera vc = mr_camera_resized(&f->view->camera, v->width, v->height);
    glUniform4f(0, (float)f->cam.fx, (float)f->cam.fy, (float)f->cam.cx, (float)f->cam.cy);
    glUniform4f(1, (float)vc.fx, (float)vc.fy, (float)vc.cx, (float)vc.cy);
    glUniform2f(2, (float)v->width, (float)v->height);
    float dist[5];
    for (int i = 0; i < 5; i++) dist[i] = (float)vc.dist[i];
    glUniform1fv(3, 5, dist);
    float a = f->p->alpha;
    glUniform1f(8, a < 0 ? 0.0f : a > 1 ? 1.0f : a);
    glBindTextureUnit(0, f->final_tex);
    glBindTextureUnit(1, r->video_tex);
    glBindVertexArray(r->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    f->final_tex = r->composed.color[0];
}

typedef struct pass_desc {
    const char *name;
    bool (*needed)(frame *f);
    void (*run)(frame *f);
} pass_desc;

static const pass_desc k_passes[] = {
    {"gbuffer", need_always, run_gbuffer},
    {"shade", need_always, run_shade},
    {"overlay", need_overlay, run_overlay},
};

static bool read_back(frame *f, mr_error *err) {
    mr_renderer *r = f->r;
    mr_frame_result *o = f->out;
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    if (!mr_image_alloc(&o->color, r->w, r->h, 3, MR_PIX_U8, err)) return false;
    /* Read the raw bytes of the sRGB texture: they are the encoded values. */
    glGetTextureImage(f->final_tex, 0, GL_RGB, GL_UNSIGNED_BYTE, (GLsizei)mr_image_bytes(&o->color), o->color.data);
    if (f->p->want_depth) {
        if (!mr_image_alloc(&o->depth, r->w, r->h, 1, MR_PIX_F32, err)) return false;
        float *d = o->depth.data;
        glGetTextureImage(r->gbuf.depth, 0, GL_DEPTH_COMPONENT, GL_FLOAT, (GLsizei)mr_image_bytes(&o->depth), d);
        size_t n = (size_t)r->w * r->h;
        for (size_t i = 0; i < n; i++) d[i] = d[i] > 0 ? (float)(f->near_plane / d[i]) : 0.0f;
    }
    if (f->p->want_normals) {
        if (!mr_image_alloc(&o->normal, r->w, r->h, 3, MR_PIX_F32, err)) return false;
        glGetTextureImage(r->gbuf.color[1], 0, GL_RGB, GL_FLOAT, (GLsizei)mr_image_bytes(&o->normal), o->normal.data);
    }
    return true;
}

bool mr_render_frame(mr_renderer *r, const mr_view *view, const mr_frame_params *params, mr_frame_result *out,
                     mr_error *err) {
    memset(out, 0, sizeof *out);
    mr_frame_params defaults = MR_FRAME_DEFAULTS;
    const mr_frame_params *p = params ? params : &defaults;
    if (!mr_camera_validate(&view->camera, err)) return false;
    if (!mr_m4_is_rigid(&view->world_from_camera, 1e-5))
        return mr_fail(err, MR_ERR_INVALID, "world_from_camera is not a rigid transform");
    if (p->video && (!p->video->data || p->video->type != MR_PIX_U8 || p->video->channels < 1 ||
                     p->video->channels > 4))
        return mr_fail(err, MR_ERR_INVALID, "video frame must be an 8-bit image with 1-4 channels");
    if (!(p->alpha >= 0 && p->alpha <= 1)) return mr_fail(err, MR_ERR_INVALID, "alpha must be in [0,1]");
    int w = p->width > 0 ? p->width : view->camera.width;
    int h = p->height > 0 ? p->height : view->camera.height;
    if (w > 16384 || h > 16384) return mr_fail(err, MR_ERR_INVALID, "output size %dx%d too large", w, h);
    if (!ensure_targets(r, w, h, err)) return false;

    frame f = {0};
    f.r = r;
    f.view = view;
    f.p = p;
    f.out = out;
    f.cam = mr_camera_resized(&view->camera, w, h);
    f.cam_from_world = mr_m4_invert_rigid(&view->world_from_camera);
    mr_dvec3 eye = mr_v3(view->world_from_camera.m[3], view->world_from_camera.m[7], view->world_from_camera.m[11]);
    f.near_plane = r->scene ? choose_near(r->scene, eye) : 1e-3;
    out->near_plane = f.near_plane;

    for (size_t i = 0; i < sizeof k_passes / sizeof k_passes[0]; i++) {
        if (!k_passes[i].needed(&f)) continue;
        int k = out->pass_count;
        double t0 = mr_time_now();
        if (p->timing) glBeginQuery(GL_TIME_ELAPSED, r->queries[k]);
        k_passes[i].run(&f);
        if (p->timing) glEndQuery(GL_TIME_ELAPSED);
        out->cpu_ms[k] = (mr_time_now() - t0) * 1e3;
        out->passes[k] = k_passes[i].name;
        out->pass_count++;
    }
    if (p->timing)
        for (int k = 0; k < out->pass_count; k++) {
            GLuint64 ns = 0;
            glGetQueryObjectui64v(r->queries[k], GL_QUERY_RESULT, &ns);
            out->gpu_ms[k] = (double)ns * 1e-6;
        }
    bool ok = read_back(&f, err);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    GLenum e = glGetError();
    if (ok && e != GL_NO_ERROR) ok = mr_fail(err, MR_ERR_GL, "GL error 0x%x during the frame", e);
    if (!ok) mr_frame_result_free(out);
    return ok;
}

void mr_frame_result_free(mr_frame_result *res) {
    if (!res) return;
    mr_image_free(&res->color);
    mr_image_free(&res->depth);
    mr_image_free(&res->normal);
}

void mr_frame_result_passes(const mr_frame_result *res, char *buf, size_t n) {
    size_t len = 0;
    buf[0] = 0;
    for (int i = 0; i < res->pass_count && len < n; i++)
        len += (size_t)snprintf(buf + len, n - len, "%s%s", i ? " " : "", res->passes[i]);
}
