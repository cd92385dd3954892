/* The renderer: scene hand-over and the frame's pass list.
 *
 * A frame is the registry k_passes, one row per pass, in order. Before any
 * pass runs, every row's needed() is asked (a frame without video runs no
 * overlay pass, a frozen camera no AO, and so on); the needed rows' reads
 * and writes say which named resources this frame makes. Then each needed
 * row is prepared (targets, programs) and run; the listed ones are
 * reported. New passes go into k_passes. */
#include "render_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *const mr_resource_names[RES_COUNT] = {
    [RES_DEPTH] = "depth", [RES_ALBEDO] = "albedo", [RES_NORMAL] = "normal", [RES_IDS] = "ids",
    [RES_POSITIONS] = "positions", [RES_AO_MASK] = "ao.mask", [RES_AO] = "ao",
    [RES_HIDDEN_DEPTH] = "hidden.depth", [RES_HIDDEN_NORMAL] = "hidden.normal", [RES_HIDDEN_IDS] = "hidden.ids",
    [RES_HIDDEN_SHADED] = "hidden.shaded", [RES_SHADED] = "shaded", [RES_IMAGE] = "image",
    [RES_CURVATURE] = "curvature", [RES_GHOST_MASK] = "ghost.mask",
    [RES_SHADOW_MAP] = "shadow.map", [RES_SHADOW] = "shadow.visibility",
    [RES_SHADOW_PYRAMID] = "shadow.pyramid",
};

/* The registry: one row per pass, in the order they run; each row's
 * descriptor lives in its pass's file. */
static const pass_desc *const k_passes[] = {
    &mr_pass_desc_gbuffer,
    &mr_pass_desc_ao_mask,
    &mr_pass_desc_ao_deint_split,
    &mr_pass_desc_ao,
    &mr_pass_desc_ao_deint_merge,
    &mr_pass_desc_ao_blur,
    &mr_pass_desc_ao_upsample,
    &mr_pass_desc_ao_temporal,
    &mr_pass_desc_ao_reuse,
    &mr_pass_desc_ao_external,
    &mr_pass_desc_ghost_hidden,
    /* Shadows before the shading, which scales the casting light by them. */
    &mr_pass_desc_shadow_map,
    &mr_pass_desc_shadow_map_reuse,
    &mr_pass_desc_shadow_pyramid,
    &mr_pass_desc_shadow_pyramid_reuse,
    &mr_pass_desc_shadow,
    &mr_pass_desc_shade,
    &mr_pass_desc_overlay,
    /* Ghosting after the overlay: with video, the occluder O is what the
     * user sees in front of the hidden structure (the real wall). */
    &mr_pass_desc_ghost_curvature,
    &mr_pass_desc_ghost_importance,
    &mr_pass_desc_ghost_g0,
    &mr_pass_desc_ghost_analysis,
    &mr_pass_desc_ghost_emphasis,
};
#define PASS_COUNT (sizeof k_passes / sizeof k_passes[0])

mr_geo_view mr_frame_view(const frame *f, GLuint program, uint32_t layers) {
    mr_geo_view v;
    memset(&v, 0, sizeof v);
    v.cam = f->cam;
    v.cam_from_world = f->cam_from_world;
    v.world_from_camera = f->view->world_from_camera;
    v.near_plane = f->near_plane;
    v.program = program;
    v.layers = layers;
    /* A rig frame's pinhole views share one cull (the display
     * mapping's bands reach past the rig's union volume). */
    v.shared = f->r->share != NULL && !f->p->display;
    return v;
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
    /* Programs and targets are made by the passes' prepare, when a frame
     * first needs them. */
    glCreateVertexArrays(1, &r->empty_vao);
    glGenQueries(MR_MAX_PASSES, r->queries);
    /* Reversed-Z: depth = near / z, so 1 is the near plane and 0 infinity. */
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    return r;
}


void mr_renderer_destroy(mr_renderer **rp) {
    if (!rp || !*rp) return;
    mr_renderer *r = *rp;
    /* A deleted program that is still current lives on until another one
     * is made current: let go of it, so destroy really frees. */
    glUseProgram(0);
    glBindVertexArray(0);
    for (size_t i = 0; i < PASS_COUNT; i++)
        if (k_passes[i]->destroy) k_passes[i]->destroy(r);
    /* A rig frame left open (mr_render_rig_begin). */
    mr_geometry_share_end(r);
    free((void *)r->rig);
    mr_geometry_free(r);
    glDeleteVertexArrays(1, &r->empty_vao);
    glDeleteQueries(MR_MAX_PASSES, r->queries);
    free(r);
    *rp = NULL;
}


bool mr_renderer_set_scene(mr_renderer *r, const mr_scene *s, mr_error *err) {
    return mr_renderer_set_scene_lod(r, s, NULL, err);
}

bool mr_renderer_set_scene_lod(mr_renderer *r, const mr_scene *s, const mr_lod *lod, mr_error *err) {
    for (size_t i = 0; i < PASS_COUNT; i++)
        if (k_passes[i]->scene_changed) k_passes[i]->scene_changed(r);
    mr_geometry_free(r);
    if (!s) return true;
    return mr_geometry_upload(r, s, lod, err);
}

/* Near plane: half the distance to the scene's bounding box, but never below
 * 1e-6 of the scene's size (so it scales with the scene's units). Reversed
 * float depth keeps precision at any distance, so only clipping matters. */
static double choose_near(const mr_scene *s, mr_dvec3 eye) {
    double d2 = 0;
    for (int i = 0; i < 3; i++) {
        const double *e = &eye.x;
        double lo = s->bounds_min[i], hi = s->bounds_max[i];
        double v = e[i] < lo ? lo - e[i] : e[i] > hi ? e[i] - hi : 0;
        d2 += v * v;
    }
    double diag = mr_scene_diagonal(s);
    if (!(diag > 0)) diag = 1;
    double n = 0.5 * sqrt(d2);
    return n > 1e-6 * diag ? n : 1e-6 * diag;
}


double mr_render_near_plane(const mr_scene *s, const mr_dmat4 *world_from_camera) {
    mr_dvec3 eye = mr_v3(world_from_camera->m[3], world_from_camera->m[7], world_from_camera->m[11]);
    return s ? choose_near(s, eye) : 1e-3;
}


static bool read_back(frame *f, mr_error *err) {
    mr_renderer *r = f->r;
    mr_frame_result *o = f->out;
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    if (!mr_image_alloc(&o->color, r->w, r->h, 3, MR_PIX_U8, err)) return false;
    /* Read the raw bytes of the sRGB texture: they are the encoded values. */
    glGetTextureImage(frame_get(f, RES_IMAGE), 0, GL_RGB, GL_UNSIGNED_BYTE, (GLsizei)mr_image_bytes(&o->color), o->color.data);
    if (f->p->want_depth) {
        if (!mr_image_alloc(&o->depth, r->w, r->h, 1, MR_PIX_F32, err)) return false;
        float *d = o->depth.data;
        glGetTextureImage(frame_get(f, RES_DEPTH), 0, GL_DEPTH_COMPONENT, GL_FLOAT, (GLsizei)mr_image_bytes(&o->depth), d);
        size_t n = (size_t)r->w * r->h;
        for (size_t i = 0; i < n; i++) d[i] = d[i] > 0 ? (float)(f->near_plane / d[i]) : 0.0f;
    }
    if (f->p->want_normals) {
        if (!mr_image_alloc(&o->normal, r->w, r->h, 3, MR_PIX_F32, err)) return false;
        glGetTextureImage(frame_get(f, RES_NORMAL), 0, GL_RGB, GL_FLOAT, (GLsizei)mr_image_bytes(&o->normal), o->normal.data);
    }
    for (size_t i = 0; i < PASS_COUNT; i++)
        if (k_passes[i]->read_back && !k_passes[i]->read_back(f, err)) return false;
    return true;
}


bool mr_render_frame(mr_renderer *r, const mr_view *view, const mr_frame_params *params, mr_frame_result *out,
                     mr_error *err) {
    memset(out, 0, sizeof *out);
    r->last.valid = false; /* targets may be reallocated below */
    r->last.hier = false;
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
    for (size_t i = 0; i < PASS_COUNT; i++)
        if (k_passes[i]->check && !k_passes[i]->check(p, err)) return false;
    /* The display mapping cannot be un-projected: AO reads positions. */
    mr_frame_params with_pos;
    if (p->display) {
        const mr_display_map *m = p->display;
        if (!(m->distance > 0 && isfinite(m->distance)) || !(m->eye_half >= 0 && isfinite(m->eye_half)) || m->band < 1)
            return mr_fail(err, MR_ERR_INVALID, "display mapping needs D > 0, E >= 0 and a band of >= 1 columns");
        /* The outline volumes and the hidden layer are drawn through the
         * frame's pinhole camera, so they would not line up. */
        if (p->ghost.mode != MR_GHOST_OFF || p->video || p->ao.mask != MR_AO_MASK_OFF)
            return mr_fail(err, MR_ERR_INVALID, "the display mapping draws no ghosting, corner mask or video overlay");
        with_pos = *p;
        with_pos.ao.positions = true;
        p = &with_pos;
    }
    r->w = w;
    r->h = h;

    frame f;
    memset(&f, 0, sizeof f);
    mr_geometry_begin_frame(r);
    f.r = r;
    f.view = view;
    f.p = p;
    f.out = out;
    f.cam = mr_camera_resized(&view->camera, w, h);
    f.cam_from_world = mr_m4_invert_rigid(&view->world_from_camera);
    mr_dvec3 eye = mr_v3(view->world_from_camera.m[3], view->world_from_camera.m[7], view->world_from_camera.m[11]);
    f.near_plane = r->scene ? choose_near(r->scene, eye) : 1e-3;
    out->near_plane = f.near_plane;

    /* Which passes run is decided before any of them does, so needed()
     * sees the state the frame started with. */
    bool need[PASS_COUNT];
    for (size_t i = 0; i < PASS_COUNT; i++) {
        const pass_desc *d = k_passes[i];
        need[i] = !d->needed || d->needed(&f);
        if (!need[i]) continue;
        uint32_t reads = d->reads_now ? d->reads_now(&f) & d->reads : d->reads;
        /* A row that needs what no earlier row of this frame makes is a
         * mistake in the registry (order or declarations), not in the input. */
        uint32_t missing = reads & ~f.writing;
        if (missing) {
            int k = 0;
            while (!(missing & RES(k))) k++;
            return mr_fail(err, MR_ERR_GL, "pass %s reads \"%s\", which no earlier pass of this frame writes",
                           d->name ? d->name : "(unlisted)", mr_resource_names[k]);
        }
        f.reading |= reads;
        f.writing |= d->writes;
    }
    for (size_t i = 0; i < PASS_COUNT; i++)
        if (need[i] && k_passes[i]->prepare && !k_passes[i]->prepare(&f, err)) return false;
    for (size_t i = 0; i < PASS_COUNT; i++) {
        if (!need[i]) continue;
        const pass_desc *d = k_passes[i];
        if (!d->name) {
            d->run(&f);
            continue;
        }
        int k = out->pass_count;
        /* Synchronous timing; the pass's wall time between two glFinish. */
        bool sync = p->timing && p->timing_sync;
        if (sync) glFinish();
        double t0 = mr_time_now();
        if (p->timing) glBeginQuery(GL_TIME_ELAPSED, r->queries[k]);
        d->run(&f);
        if (p->timing) glEndQuery(GL_TIME_ELAPSED);
        if (sync) glFinish();
        out->cpu_ms[k] = (mr_time_now() - t0) * 1e3;
        out->passes[k] = d->name;
        out->pass_count++;
    }
    if (p->timing)
        for (int k = 0; k < out->pass_count; k++) {
            GLuint64 ns = 0;
            glGetQueryObjectui64v(r->queries[k], GL_QUERY_RESULT, &ns);
            out->gpu_ms[k] = (double)ns * 1e-6;
        }
    bool ok = read_back(&f, err);
    r->last.valid = ok;
    r->last.tex = frame_get(&f, RES_IMAGE);
    r->last.depth = frame_get(&f, RES_DEPTH);
    r->last.ids = frame_get(&f, RES_IDS);
    r->last.cam = f.cam;
    r->last.world_from_camera = view->world_from_camera;
    r->last.near_plane = f.near_plane;
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
    mr_image_free(&res->ao);
    mr_image_free(&res->ao_mask);
    mr_image_free(&res->shadow);
}


void mr_frame_result_passes(const mr_frame_result *res, char *buf, size_t n) {
    size_t len = 0;
    buf[0] = 0;
    for (int i = 0; i < res->pass_count && len < n; i++)
        len += (size_t)snprintf(buf + len, n - len, "%s%s", i ? " " : "", res->passes[i]);
}


void mr_render_alpha_distances(mr_renderer *r, const mr_view *view, const mr_frame_params *params, const mr_image *shown,
                               double d[2]) {
    for (int k = 0; k < 2; k++) {
        mr_frame_params fp = *params;
        fp.alpha = (float)k;
        mr_frame_result res;
        mr_error err = {0};
        d[k] = -1;
        if (mr_render_frame(r, view, &fp, &res, &err)) {
            d[k] = mr_image_u8_mean_abs_diff(shown, &res.color);
            mr_frame_result_free(&res);
        }
    }
}
