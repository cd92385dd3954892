/* The base passes: G-buffer, Lambert + ambient shading, video overlay.
 *
 *   gbuffer  writes depth, albedo, normal, ids (+ positions when a pass
 *            this frame reads them); the hidden layer too unless the
 *            ghosting makes hidden.* this frame
 *   shade    reads albedo, normal (+ ao), writes shaded and image
 *   overlay  reads image and the video, writes image */
#include "render_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct mr_base_state {
    GLuint prog_gbuffer, prog_shade, prog_overlay;
    int w, h;              /* size of the targets below */
    target gbuf;           /* albedo (sRGB8), normal (RGBA16F), ids (RG32UI), positions (RGBA32F), depth (32F) */
    target shaded;         /* sRGB8: the virtual image */
    target composed;       /* sRGB8: virtual + video */
    target pick;           /* 1x1: albedo, normal, ids, depth (mr_gbuffer_pick_pixel) */
    GLuint video_tex;
    int video_w, video_h;
};

static void free_targets(struct mr_base_state *b) {
    mr_gl_target_free(&b->gbuf);
    mr_gl_target_free(&b->shaded);
    mr_gl_target_free(&b->composed);
    b->w = b->h = 0;
}

void mr_base_free(mr_renderer *r) {
    struct mr_base_state *b = r->base;
    if (!b) return;
    free_targets(b);
    mr_gl_target_free(&b->pick);
    glDeleteTextures(1, &b->video_tex);
    glDeleteProgram(b->prog_gbuffer);
    glDeleteProgram(b->prog_shade);
    glDeleteProgram(b->prog_overlay);
    free(b);
    r->base = NULL;
}

/* Programs are built once, targets whenever the output size changes; each
 * pass makes only what it writes. */
static struct mr_base_state *base(frame *f, mr_error *err) {
    mr_renderer *r = f->r;
    if (!r->base && !(r->base = calloc(1, sizeof *r->base))) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    struct mr_base_state *b = r->base;
    if (b->w != r->w || b->h != r->h) {
        free_targets(b);
        b->w = r->w;
        b->h = r->h;
    }
    return b;
}

static bool ensure_program(GLuint *prog, const char *vert, const char *frag, mr_error *err) {
    const char *const files[] = {vert, frag, NULL};
    return *prog || (*prog = mr_gl_program(files, err)) != 0;
}

static bool mr_pass_prepare_gbuffer(frame *f, mr_error *err) {
    struct mr_base_state *b = base(f, err);
    if (!b || !ensure_program(&b->prog_gbuffer, "gbuffer.vert.glsl", "gbuffer.frag.glsl", err)) return false;
    /* albedo, view normal, ids, view-space position (written only when a
     * frame's AO reads positions: see mr_pass_gbuffer) */
    static const GLenum gfmt[MR_OUT_GBUFFER_COUNT] = {
        [MR_OUT_GBUFFER_ALBEDO] = GL_SRGB8_ALPHA8, [MR_OUT_GBUFFER_NORMAL] = GL_RGBA16F,
        [MR_OUT_GBUFFER_IDS] = GL_RG32UI, [MR_OUT_GBUFFER_POSITIONS] = GL_RGBA32F};
    return b->gbuf.fbo || mr_gl_target_make(&b->gbuf, b->w, b->h, gfmt, MR_OUT_GBUFFER_COUNT, true, err);
}

static bool mr_pass_prepare_shade(frame *f, mr_error *err) {
    struct mr_base_state *b = base(f, err);
    if (!b || !ensure_program(&b->prog_shade, "fullscreen.vert.glsl", "shade.frag.glsl", err)) return false;
    static const GLenum cfmt[1] = {GL_SRGB8_ALPHA8};
    return b->shaded.fbo || mr_gl_target_make(&b->shaded, b->w, b->h, cfmt, 1, false, err);
}

static bool mr_pass_prepare_overlay(frame *f, mr_error *err) {
    struct mr_base_state *b = base(f, err);
    if (!b || !ensure_program(&b->prog_overlay, "fullscreen.vert.glsl", "overlay.frag.glsl", err)) return false;
    static const GLenum cfmt[1] = {GL_SRGB8_ALPHA8};
    if (!b->composed.fbo && !mr_gl_target_make(&b->composed, b->w, b->h, cfmt, 1, false, err)) return false;
    const mr_image *v = f->p->video;
    if (!b->video_tex || b->video_w != v->width || b->video_h != v->height) {
        glDeleteTextures(1, &b->video_tex);
        b->video_tex = mr_gl_make_tex(GL_SRGB8_ALPHA8, v->width, v->height, GL_LINEAR);
        b->video_w = v->width;
        b->video_h = v->height;
    }
    return true;
}

static bool mr_pass_need_overlay(const frame *f) { return f->p->video != NULL; }

GLuint mr_gbuffer_program(const frame *f) { return f->r->base ? f->r->base->prog_gbuffer : 0; }

void mr_gbuffer_begin(frame *f, const target *t) {
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glViewport(0, 0, f->r->w, f->r->h);
    glEnable(GL_FRAMEBUFFER_SRGB);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    static const float zero4[4] = {0, 0, 0, 0};
    static const GLuint zero_u[4] = {0, 0, 0, 0};
    static const float depth0 = 0.0f; /* reversed Z: clear to infinity */
    glClearNamedFramebufferfv(t->fbo, GL_COLOR, MR_OUT_GBUFFER_ALBEDO, zero4);
    glClearNamedFramebufferfv(t->fbo, GL_COLOR, MR_OUT_GBUFFER_NORMAL, zero4);
    glClearNamedFramebufferuiv(t->fbo, GL_COLOR, MR_OUT_GBUFFER_IDS, zero_u);
    glClearNamedFramebufferfv(t->fbo, GL_DEPTH, 0, &depth0);
}

/* The light-field display mapping: narrow perspective slices, each band of
 * columns a pinhole view from its own eye on the observer line, scissored
 * into the one G-buffer. Positions are written in the frame camera's axes
 * (the band's eye offset added), so AO reads them across band borders. */
static void gbuffer_display(frame *f, const mr_geo_view *centre) {
    const mr_display_map *m = f->p->display;
    GLuint prog = centre->program;
    int n = mr_display_band_count(m, f->r->w);
    glEnable(GL_SCISSOR_TEST);
    for (int b = 0; b < n; b++) {
        int x0, x1;
        double e;
        mr_geo_view v = *centre;
        v.cam = mr_display_band_camera(m, &centre->cam, b, &x0, &x1, &e);
        mr_dmat4 shift = mr_m4_translate(e, 0, 0);
        v.world_from_camera = mr_m4_mul(&centre->world_from_camera, &shift);
        v.cam_from_world = mr_m4_invert_rigid(&v.world_from_camera);
        glScissor(x0, 0, x1 - x0, f->r->h);
        glProgramUniform3f(prog, MR_LOC_GBUFFER_POS_OFFSET, (float)e, 0, 0);
        mr_geometry_draw(f->r, &v, f->out);
    }
    glDisable(GL_SCISSOR_TEST);
    glProgramUniform3f(prog, MR_LOC_GBUFFER_POS_OFFSET, 0, 0, 0);
}

static void mr_pass_gbuffer(frame *f) {
    struct mr_base_state *b = f->r->base;
    static const float zero4[4] = {0, 0, 0, 0};
    mr_gbuffer_begin(f, &b->gbuf);
    /* View-space positions are rasterised (not un-projected from depth) so
     * that AO also works where the projection cannot be inverted; the
     * attachment costs bandwidth, so it is written only when this frame's AO
     * reads positions. */
    static const GLenum bufs[MR_OUT_GBUFFER_COUNT] = {
        GL_COLOR_ATTACHMENT0 + MR_OUT_GBUFFER_ALBEDO, GL_COLOR_ATTACHMENT0 + MR_OUT_GBUFFER_NORMAL,
        GL_COLOR_ATTACHMENT0 + MR_OUT_GBUFFER_IDS, GL_COLOR_ATTACHMENT0 + MR_OUT_GBUFFER_POSITIONS};
    bool want_pos = (f->reading & RES(RES_POSITIONS)) != 0;
    glNamedFramebufferDrawBuffers(b->gbuf.fbo, want_pos ? MR_OUT_GBUFFER_COUNT : MR_OUT_GBUFFER_POSITIONS, bufs);
    if (want_pos) glClearNamedFramebufferfv(b->gbuf.fbo, GL_COLOR, MR_OUT_GBUFFER_POSITIONS, zero4);
    uint32_t mask = 1u << MR_LAYER_VISIBLE;
    /* With ghosting, the hidden layer goes to its own target D (pass_ghost.c). */
    if (!f->p->hide_hidden_layer && !(f->writing & RES(RES_HIDDEN_DEPTH))) mask |= 1u << MR_LAYER_HIDDEN;
    mr_geo_view v = mr_frame_view(f, b->prog_gbuffer, mask);
    v.cull_back = true; /* single-sided materials as glTF draws them */
    glProgramUniform3f(b->prog_gbuffer, MR_LOC_GBUFFER_POS_OFFSET, 0, 0, 0);
    if (f->p->display) {
        gbuffer_display(f, &v);
    } else {
        uint32_t proxies = f->r->stats.hlod_proxies;
        mr_geometry_draw(f->r, &v, f->out);
        f->r->last.hier = f->r->stats.hlod_proxies > proxies;
        f->r->last.layers = mask;
    }
    glDisable(GL_DEPTH_TEST);
    frame_put(f, RES_DEPTH, b->gbuf.depth);
    frame_put(f, RES_ALBEDO, b->gbuf.color[MR_OUT_GBUFFER_ALBEDO]);
    frame_put(f, RES_NORMAL, b->gbuf.color[MR_OUT_GBUFFER_NORMAL]);
    frame_put(f, RES_IDS, b->gbuf.color[MR_OUT_GBUFFER_IDS]);
    if (want_pos) frame_put(f, RES_POSITIONS, b->gbuf.color[MR_OUT_GBUFFER_POSITIONS]);
}

bool mr_gbuffer_pick_pixel(mr_renderer *r, int px, int py, float *depth, GLuint ids[2], mr_error *err) {
    struct mr_base_state *b = r->base;
    if (!b || !b->prog_gbuffer) return mr_fail(err, MR_ERR_INVALID, "no G-buffer to pick from");
    static const GLenum gfmt[MR_OUT_GBUFFER_POSITIONS] = {GL_SRGB8_ALPHA8, GL_RGBA16F, GL_RG32UI};
    if (!b->pick.fbo && !mr_gl_target_make(&b->pick, 1, 1, gfmt, MR_OUT_GBUFFER_POSITIONS, true, err)) return false;
    /* The frame's camera shifted so that pixel (px, py) is the target's
     * only one; its levels chosen with the whole image's pixel factor. */
    mr_geo_view v;
    memset(&v, 0, sizeof v);
    v.cam = r->last.cam;
    v.lod_fmax = mr_geometry_lod_fmax(&r->last.cam);
    v.cam.width = v.cam.height = 1;
    v.cam.cx -= px;
    v.cam.cy -= py;
    v.world_from_camera = r->last.world_from_camera;
    v.cam_from_world = mr_m4_invert_rigid(&v.world_from_camera);
    v.near_plane = r->last.near_plane;
    v.program = b->prog_gbuffer;
    v.layers = r->last.layers;
    v.cull_back = true;
    GLint fbo = 0, vp[4];
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &fbo);
    glGetIntegerv(GL_VIEWPORT, vp);
    GLboolean depth_test = glIsEnabled(GL_DEPTH_TEST), scissor = glIsEnabled(GL_SCISSOR_TEST);
    glDisable(GL_SCISSOR_TEST); /* a caller's 2D layer may have left one */
    glBindFramebuffer(GL_FRAMEBUFFER, b->pick.fbo);
    glViewport(0, 0, 1, 1);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    static const GLenum bufs[MR_OUT_GBUFFER_POSITIONS] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glNamedFramebufferDrawBuffers(b->pick.fbo, MR_OUT_GBUFFER_POSITIONS, bufs);
    static const GLuint zero_u[4] = {0, 0, 0, 0};
    static const float depth0 = 0.0f;
    glClearNamedFramebufferuiv(b->pick.fbo, GL_COLOR, MR_OUT_GBUFFER_IDS, zero_u);
    glClearNamedFramebufferfv(b->pick.fbo, GL_DEPTH, 0, &depth0);
    glProgramUniform3f(b->prog_gbuffer, MR_LOC_GBUFFER_POS_OFFSET, 0, 0, 0);
    /* No hierarchy, no occlusion (nothing learnt from this draw), and the
     * frame's statistics kept. */
    const mr_draw_params saved = r->draw;
    const mr_draw_stats st = r->stats;
    r->draw.no_hlod = true;
    r->draw.occlusion = false;
    r->draw.occlusion_auto = false;
    mr_geometry_draw(r, &v, NULL);
    r->draw = saved;
    r->stats = st;
    if (!depth_test) glDisable(GL_DEPTH_TEST);
    if (scissor) glEnable(GL_SCISSOR_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, (GLuint)fbo);
    glViewport(vp[0], vp[1], vp[2], vp[3]);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTextureSubImage(b->pick.depth, 0, 0, 0, 0, 1, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, sizeof *depth, depth);
    glGetTextureSubImage(b->pick.color[MR_OUT_GBUFFER_IDS], 0, 0, 0, 0, 1, 1, 1, GL_RG_INTEGER, GL_UNSIGNED_INT,
                         2 * sizeof *ids, ids);
    GLenum e = glGetError();
    return e == GL_NO_ERROR || mr_fail(err, MR_ERR_GL, "GL error 0x%x redrawing the pick pixel", e);
}

static void mr_pass_shade(frame *f) {
    struct mr_base_state *b = f->r->base;
    mr_shade_draw(f, frame_get(f, RES_ALBEDO), frame_get(f, RES_NORMAL), frame_get(f, RES_AO), &b->shaded);
    frame_put(f, RES_SHADED, b->shaded.color[0]);
    frame_put(f, RES_IMAGE, b->shaded.color[0]);
}

/* The lights of a scene without lights; the sun casts shadows (of the
 * default angle) when a shadow method is on. */
const mr_light mr_default_lights[2] = {
    {.direction = {0.4, 1.0, 0.25}, .color = {0.55f, 0.55f, 0.52f}, .kind = MR_LIGHT_SUN, .casts = true,
     .angle = MR_LIGHT_DEFAULT_SUN_ANGLE},                                        /* sun */
    {.direction = {-0.5, 0.3, -0.7}, .color = {0.18f, 0.19f, 0.22f}, .kind = MR_LIGHT_SUN}, /* sky fill */
};

void mr_shade_draw(frame *f, GLuint albedo, GLuint normal, GLuint ao, const target *dst) {
    mr_renderer *r = f->r;
    glBindFramebuffer(GL_FRAMEBUFFER, dst->fbo);
    glViewport(0, 0, r->w, r->h);
    glEnable(GL_FRAMEBUFFER_SRGB);
    glUseProgram(r->base->prog_shade);
    const mr_scene *s = r->scene;
    float dirs[MR_SHADE_MAX_LIGHTS][3], cols[MR_SHADE_MAX_LIGHTS][3];
    int nl = 0;
    const mr_light *lights = s && s->light_count > 0 ? s->lights : mr_default_lights;
    int count = s && s->light_count > 0 ? s->light_count : 2;
    for (int i = 0; i < count && i < MR_SHADE_MAX_LIGHTS; i++) {
        /* World direction to camera axes with the pose's rotation only. */
        mr_dvec3 d = mr_v3_normalize(mr_m4_dir(&f->cam_from_world, mr_v3(lights[i].direction[0], lights[i].direction[1],
                                                                        lights[i].direction[2])));
        dirs[nl][0] = (float)d.x; dirs[nl][1] = (float)d.y; dirs[nl][2] = (float)d.z;
        memcpy(cols[nl], lights[i].color, sizeof cols[nl]);
        nl++;
    }
    glUniform1i(MR_LOC_SHADE_LIGHT_COUNT, nl);
    if (nl) {
        glUniform3fv(MR_LOC_SHADE_LIGHT_DIR, nl, &dirs[0][0]);
        glUniform3fv(MR_LOC_SHADE_LIGHT_COLOR, nl, &cols[0][0]);
    }
    glUniform1f(MR_LOC_SHADE_AMBIENT, s ? s->ambient : 0.35f);
    float bg[3];
    for (int i = 0; i < 3; i++) {
        float c = f->p->background[i];
        bg[i] = c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
    }
    glUniform3fv(MR_LOC_SHADE_BACKGROUND, 1, bg);
    glUniform1f(MR_LOC_SHADE_SPECULAR, f->p->specular > 0 ? f->p->specular : 0.0f);
    glUniform1f(MR_LOC_SHADE_SHININESS, f->p->shininess >= 1 ? f->p->shininess : MR_FRAME_DEFAULT_SHININESS);
    glUniform1i(MR_LOC_SHADE_HAVE_AO, ao != 0);
    /* The casting light's visibility shades the main image only (the
     * hidden layer D, shaded here too, lies behind what the map saw). */
    GLuint shadow = albedo == frame_get(f, RES_ALBEDO) ? frame_get(f, RES_SHADOW) : 0;
    int si = shadow ? mr_shadow_light_index(s) : -1;
    glUniform1i(MR_LOC_SHADE_SHADOW_LIGHT, si < nl ? si : -1);
    glBindTextureUnit(MR_TEX_SHADE_SHADOW, shadow);
    glBindTextureUnit(MR_TEX_SHADE_ALBEDO, albedo);
    glBindTextureUnit(MR_TEX_SHADE_NORMAL, normal);
    glBindTextureUnit(MR_TEX_SHADE_AO, ao);
    glBindVertexArray(r->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
}


static void mr_pass_overlay(frame *f) {
    mr_renderer *r = f->r;
    struct mr_base_state *b = r->base;
    const mr_image *v = f->p->video;
    GLenum fmt = v->channels == 1 ? GL_RED : v->channels == 2 ? GL_RG : v->channels == 3 ? GL_RGB : GL_RGBA;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage2D(b->video_tex, 0, 0, 0, v->width, v->height, fmt, GL_UNSIGNED_BYTE, v->data);
    /* Grey frames: replicate red into green and blue. */
    GLint swz[4] = {GL_RED, v->channels < 3 ? GL_RED : GL_GREEN, v->channels < 3 ? GL_RED : GL_BLUE, GL_ONE};
    glTextureParameteriv(b->video_tex, GL_TEXTURE_SWIZZLE_RGBA, swz);
    glBindFramebuffer(GL_FRAMEBUFFER, b->composed.fbo);
    glViewport(0, 0, r->w, r->h);
    glEnable(GL_FRAMEBUFFER_SRGB);
    glUseProgram(b->prog_overlay);
    /* The view's camera describes the raw video frame at its own size. */
    mr_camera vc = mr_camera_resized(&f->view->camera, v->width, v->height);
    glUniform4f(MR_LOC_OVERLAY_OUT_K, (float)f->cam.fx, (float)f->cam.fy, (float)f->cam.cx, (float)f->cam.cy);
    glUniform4f(MR_LOC_OVERLAY_VIDEO_K, (float)vc.fx, (float)vc.fy, (float)vc.cx, (float)vc.cy);
    glUniform2f(MR_LOC_OVERLAY_VIDEO_SIZE, (float)v->width, (float)v->height);
    float dist[5];
    for (int i = 0; i < 5; i++) dist[i] = (float)vc.dist[i];
    glUniform1fv(MR_LOC_OVERLAY_DIST, 5, dist);
    float a = f->p->alpha;
    glUniform1f(MR_LOC_OVERLAY_ALPHA, a < 0 ? 0.0f : a > 1 ? 1.0f : a);
    /* Receivers of the scene config show the video, darkened by the plan's
     * shadow (pass_shadow.c); off (and the image as before) without them. */
    mr_shadow_catcher_setup(f, b->prog_overlay, NULL);
    glBindTextureUnit(MR_TEX_OVERLAY_VIRTUAL, frame_get(f, RES_IMAGE));
    glBindTextureUnit(MR_TEX_OVERLAY_VIDEO, b->video_tex);
    glBindVertexArray(r->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    frame_put(f, RES_IMAGE, b->composed.color[0]);
}


/* The rows of the registry (k_passes in renderer.c). */
const pass_desc mr_pass_desc_gbuffer = {
    .name = "gbuffer", .prepare = mr_pass_prepare_gbuffer, .run = mr_pass_gbuffer, .destroy = mr_base_free,
    .writes = RES(RES_DEPTH) | RES(RES_ALBEDO) | RES(RES_NORMAL) | RES(RES_IDS) | RES(RES_POSITIONS)};
const pass_desc mr_pass_desc_shade = {
    .name = "shade", .prepare = mr_pass_prepare_shade, .run = mr_pass_shade, .destroy = mr_base_free,
    .reads = RES(RES_ALBEDO) | RES(RES_NORMAL), .uses = RES(RES_AO) | RES(RES_SHADOW),
    .writes = RES(RES_SHADED) | RES(RES_IMAGE)};
const pass_desc mr_pass_desc_overlay = {
    .name = "overlay", .needed = mr_pass_need_overlay, .prepare = mr_pass_prepare_overlay, .run = mr_pass_overlay,
    .destroy = mr_base_free, .reads = RES(RES_IMAGE), .uses = RES(RES_IDS) | RES(RES_NORMAL) | RES(RES_SHADOW),
    .writes = RES(RES_IMAGE)};
