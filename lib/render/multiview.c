/* Multi-view rigs and quilts for 3D displays: the frusta, the views as
 * pinhole cameras, the quilt layout and its file name (pure functions), and
 * the loop that renders a rig's views with one renderer. */
#include "render_internal.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEG (3.14159265358979323846 / 180.0)

#define RIG(f) offsetof(mr_rig_params, f)
const mr_opt mr_rig_opts[] = {
    {"views", MR_OPT_INT, RIG(views), 1, MR_RIG_MAX_VIEWS, 0, NULL,
     "render N views for a 3D display (per-view PNGs and a quilt; --out is then a folder)", MR_OPT_ZERO_AUTO},
    /* 180 degrees would put the outer eyes at infinity. */
    {"view-cone", MR_OPT_DOUBLE, RIG(cone_deg), 0, 179, MR_RIG_DEFAULT_CONE, NULL,
     "multi-view: total view cone in degrees", 0},
    {"view-fov", MR_OPT_DOUBLE, RIG(fov_deg), 0.01, 179, MR_RIG_DEFAULT_FOV, NULL,
     "multi-view: vertical field of view at the focal plane in degrees", 0},
    {"focal-distance", MR_OPT_DOUBLE, RIG(focal_distance), 1e-30, 1e30, 0, NULL,
     "multi-view: distance of the focal (zero-parallax) plane in scene units (auto: the scene's centre)",
     MR_OPT_ZERO_AUTO},
    {"views-per-view-work", MR_OPT_BOOL, RIG(per_view_work), 0, 1, 0, NULL,
     "multi-view: cull and fit the shadow maps per view instead of once per frame (for comparison)", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef RIG

double mr_rig_distance_for_size(double fov_deg, double size) { return size / tan(0.5 * fov_deg * DEG); }

bool mr_rig_make(const mr_rig_params *p, double aspect, double distance, mr_rig *rig, mr_error *err) {
    memset(rig, 0, sizeof *rig);
    double fov = p->fov_deg > 0 ? p->fov_deg : MR_RIG_DEFAULT_FOV;
    if (p->views < 1 || p->views > MR_RIG_MAX_VIEWS)
        return mr_fail(err, MR_ERR_INVALID, "views must be in [1, %d], got %d", MR_RIG_MAX_VIEWS, p->views);
    if (!(p->cone_deg >= 0 && p->cone_deg < 180))
        return mr_fail(err, MR_ERR_INVALID, "view cone must be in [0, 180) degrees, got %g", p->cone_deg);
    if (!(fov > 0 && fov < 180))
        return mr_fail(err, MR_ERR_INVALID, "view field of view must be in (0, 180) degrees, got %g", fov);
    if (!(aspect > 0 && isfinite(aspect))) return mr_fail(err, MR_ERR_INVALID, "view aspect must be positive, got %g", aspect);
    if (!(distance > 0 && isfinite(distance)))
        return mr_fail(err, MR_ERR_INVALID, "focal distance must be positive and finite, got %g", distance);
    rig->views = p->views;
    rig->cone = p->cone_deg * DEG;
    rig->fov = fov * DEG;
    rig->distance = distance;
    rig->size = distance * tan(0.5 * rig->fov);
    rig->aspect = aspect;
    rig->per_view_work = p->per_view_work;
    return true;
}

double mr_rig_angle(const mr_rig *rig, int i) {
    if (rig->views < 2) return 0;
    return ((double)i / (rig->views - 1) - 0.5) * rig->cone;
}

double mr_rig_shift(const mr_rig *rig, int i) { return rig->distance * tan(mr_rig_angle(rig, i)); }

void mr_rig_frustum(const mr_rig *rig, int i, double n, double *l, double *r, double *b, double *t) {
    double s = mr_rig_shift(rig, i), k = n / rig->distance, hw = rig->aspect * rig->size;
    *l = (-hw - s) * k;
    *r = (hw - s) * k;
    *b = -rig->size * k;
    *t = rig->size * k;
}

void mr_rig_project(const mr_rig *rig, int i, mr_dvec3 p, double ndc[2]) {
    /* The point in view i's axes, on its near plane (n = 1), mapped
     * linearly from [l, r] x [b, t] to [-1, 1]^2. */
    double l, r, b, t;
    mr_rig_frustum(rig, i, 1.0, &l, &r, &b, &t);
    double x = (p.x - mr_rig_shift(rig, i)) / p.z, y = p.y / p.z;
    ndc[0] = (2 * x - (r + l)) / (r - l);
    ndc[1] = (2 * y - (t + b)) / (t - b);
}

mr_view mr_rig_view(const mr_rig *rig, const mr_view *centre, int i, int width, int height) {
    mr_view v;
    memset(&v, 0, sizeof v);
    double s = mr_rig_shift(rig, i), hw = rig->aspect * rig->size;
    mr_camera *c = &v.camera;
    c->width = width;
    c->height = height;
    c->fx = width * rig->distance / (2 * hw);
    c->fy = height * rig->distance / (2 * rig->size);
    /* mr_gl_projection puts NDC 0 at cx + 0.5 = W/2; the shear moves it by
     * s_i / half-width of NDC. */
    c->cx = 0.5 * width * (1 + s / hw) - 0.5;
    c->cy = 0.5 * height - 0.5;
    mr_dmat4 shift = mr_m4_translate(s, 0, 0);
    v.world_from_camera = mr_m4_mul(&centre->world_from_camera, &shift);
    return v;
}

double mr_rig_auto_focal_distance(const mr_scene *scene, const mr_view *view) {
    mr_dvec3 c = mr_v3(0.5 * (scene->bounds_min[0] + scene->bounds_max[0]), 0.5 * (scene->bounds_min[1] + scene->bounds_max[1]),
                       0.5 * (scene->bounds_min[2] + scene->bounds_max[2]));
    mr_dmat4 cw = mr_m4_invert_rigid(&view->world_from_camera);
    mr_dvec3 pc = mr_m4_point(&cw, c);
    return isfinite(pc.z) ? pc.z : 0;
}

static int cmp_float(const void *a, const void *b) {
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

double mr_rig_focal_from_depth(const mr_image *depth) {
    if (!depth->data || depth->type != MR_PIX_F32 || depth->channels != 1) return 0;
    int x0 = depth->width / 3, x1 = depth->width - x0, y0 = depth->height / 3, y1 = depth->height - y0;
    float *v = malloc((size_t)(x1 - x0) * (size_t)(y1 - y0) * sizeof *v + 1);
    if (!v) return 0;
    size_t n = 0;
    const float *d = depth->data;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            float z = d[(size_t)y * depth->width + x];
            if (z > 0 && isfinite(z)) v[n++] = z;
        }
    double m = 0;
    if (n) {
        qsort(v, n, sizeof *v, cmp_float);
        m = v[n / 2];
    }
    free(v);
    return m;
}

/* Looking Glass's published quilt defaults for its displays. */
static const struct {
    const char *name;
    int cols, rows, w, h;
    double aspect;
} k_presets[] = {
    {"portrait", 8, 6, 3360, 3360, 0.75},
    {"go", 11, 6, 4092, 4092, 0.5625},
    {"4k", 5, 9, 4096, 4096, 16.0 / 9.0},
    {"8k", 5, 9, 8192, 8192, 16.0 / 9.0},
};

bool mr_quilt_parse(const char *spec, mr_quilt *q, mr_error *err) {
    memset(q, 0, sizeof *q);
    for (size_t k = 0; k < sizeof k_presets / sizeof k_presets[0]; k++)
        if (strcmp(spec, k_presets[k].name) == 0) {
            q->cols = k_presets[k].cols;
            q->rows = k_presets[k].rows;
            q->width = k_presets[k].w;
            q->height = k_presets[k].h;
            q->aspect = k_presets[k].aspect;
            q->preset = k_presets[k].name;
            return true;
        }
    int c = 0, r = 0, w = 0, h = 0, used = 0;
    size_t len = strlen(spec);
    bool ok = (sscanf(spec, "%dx%d%n", &c, &r, &used) == 2 && (size_t)used == len) ||
              (sscanf(spec, "%dx%d@%dx%d%n", &c, &r, &w, &h, &used) == 4 && (size_t)used == len);
    if (!ok || c < 1 || r < 1 || c > 1024 || r > 1024 || w < 0 || h < 0 || w > 16384 || h > 16384 ||
        (used && strchr(spec, '@') && (w < 1 || h < 1)))
        return mr_fail(err, MR_ERR_INVALID,
                       "quilt must be portrait, go, 4k, 8k, CxR or CxR@WxH (1..1024 tiles, up to 16384 pixels), got '%s'",
                       spec);
    q->cols = c;
    q->rows = r;
    q->width = w;
    q->height = h;
    return true;
}

bool mr_quilt_layout_make(const mr_quilt *spec, int views, int view_w, int view_h, mr_quilt_layout *out,
                          mr_error *err) {
    memset(out, 0, sizeof *out);
    if (views < 1) return mr_fail(err, MR_ERR_INVALID, "a quilt needs at least one view, got %d", views);
    int cols, rows;
    if (spec) {
        cols = spec->cols;
        rows = spec->rows;
    } else {
        cols = (int)ceil(sqrt((double)views));
        rows = (views + cols - 1) / cols;
    }
    if ((long)cols * rows < views)
        return mr_fail(err, MR_ERR_INVALID, "quilt %dx%d has %ld tiles, too few for %d views", cols, rows,
                       (long)cols * rows, views);
    int tw = view_w, th = view_h, w = 0, h = 0;
    if (spec && spec->width > 0) {
        tw = spec->width / cols;
        th = spec->height / rows;
        w = spec->width;
        h = spec->height;
    }
    if (tw < 1 || th < 1)
        return mr_fail(err, MR_ERR_INVALID, "quilt %dx%d of %dx%d pixels leaves tiles under one pixel", cols, rows, w, h);
    if (!w) {
        w = cols * tw;
        h = rows * th;
    }
    if (w > 16384 || h > 16384) return mr_fail(err, MR_ERR_INVALID, "quilt of %dx%d pixels is too large", w, h);
    out->cols = cols;
    out->rows = rows;
    out->tile_w = tw;
    out->tile_h = th;
    out->width = w;
    out->height = h;
    out->aspect = spec && spec->aspect > 0 ? spec->aspect : (double)tw / th;
    return true;
}

void mr_quilt_tile_origin(const mr_quilt_layout *q, int i, int *x, int *y) {
    /* Tile rows count up from the bottom; image rows go down from the top. */
    *x = (i % q->cols) * q->tile_w;
    *y = q->height - (i / q->cols + 1) * q->tile_h;
}

bool mr_quilt_put(const mr_quilt_layout *q, mr_image *quilt, int i, const mr_image *view, mr_error *err) {
    if (i < 0 || i >= q->cols * q->rows) return mr_fail(err, MR_ERR_INVALID, "view %d is outside the quilt", i);
    if (view->width != q->tile_w || view->height != q->tile_h || view->channels != quilt->channels ||
        view->type != quilt->type || quilt->width != q->width || quilt->height != q->height)
        return mr_fail(err, MR_ERR_INVALID, "view %d (%dx%d) does not fit the quilt's %dx%d tiles", i, view->width,
                       view->height, q->tile_w, q->tile_h);
    int x0, y0;
    mr_quilt_tile_origin(q, i, &x0, &y0);
    size_t px = (size_t)quilt->channels * (quilt->type == MR_PIX_F32 ? 4 : 1);
    for (int y = 0; y < q->tile_h; y++)
        memcpy((unsigned char *)quilt->data + ((size_t)(y0 + y) * quilt->width + x0) * px,
               (const unsigned char *)view->data + (size_t)y * view->width * px, (size_t)view->width * px);
    return true;
}

void mr_quilt_file_name(const char *name, const mr_quilt_layout *q, char *out, size_t n) {
    snprintf(out, n, "%s_qs%dx%da%.4g.png", name, q->cols, q->rows, q->aspect);
}

/* The union volume in the centre camera's axes: a.xyz . p + a.w >= 0. */
static void rig_planes(const mr_rig *rig, const mr_view *centre, int w, int h, double near_plane, double margin_px,
                       double planes[5][4]) {
    double a0 = INFINITY, a1 = -INFINITY, e0 = INFINITY, e1 = -INFINITY, b0 = 0, b1 = 0;
    for (int i = 0; i < rig->views; i++) {
        mr_view v = mr_rig_view(rig, centre, i, w, h);
        const mr_camera *c = &v.camera;
        double s = mr_rig_shift(rig, i);
        /* As mr_frustum_from_camera: the image edges at -0.5 and w - 0.5. */
        a0 = fmin(a0, (-0.5 - margin_px - c->cx) / c->fx);
        a1 = fmax(a1, (c->width - 0.5 + margin_px - c->cx) / c->fx);
        b0 = (-0.5 - margin_px - c->cy) / c->fy;
        b1 = (c->height - 0.5 + margin_px - c->cy) / c->fy;
        e0 = fmin(e0, s);
        e1 = fmax(e1, s);
    }
    const double p[5][4] = {
        {1, 0, -a0, -e0}, /* x - e0 >= a0 z */
        {-1, 0, a1, e1},  /* x - e1 <= a1 z */
        {0, 1, -b0, 0},
        {0, -1, b1, 0},
        {0, 0, 1, -near_plane},
    };
    memcpy(planes, p, sizeof p);
}

mr_frustum mr_rig_cull_frustum(const mr_rig *rig, const mr_view *centre, int width, int height, double near_plane,
                               double margin_px) {
    double cp[5][4];
    rig_planes(rig, centre, width, height, near_plane, margin_px, cp);
    mr_frustum f;
    memset(&f, 0, sizeof f);
    const double *M = centre->world_from_camera.m;
    mr_dvec3 t = mr_v3(M[3], M[7], M[11]);
    for (int i = 0; i < 5; i++) {
        /* p_cam = R^T (P - t): n . p_cam + w = (R n) . P - (R n) . t + w. */
        double nw[3];
        for (int r = 0; r < 3; r++) nw[r] = M[r * 4 + 0] * cp[i][0] + M[r * 4 + 1] * cp[i][1] + M[r * 4 + 2] * cp[i][2];
        double len = sqrt(nw[0] * nw[0] + nw[1] * nw[1] + nw[2] * nw[2]);
        for (int k = 0; k < 3; k++) f.planes[i][k] = nw[k] / len;
        f.planes[i][3] = (cp[i][3] - (nw[0] * t.x + nw[1] * t.y + nw[2] * t.z)) / len;
    }
    f.plane_count = 5;
    return f;
}

void mr_render_rig_end(mr_renderer *r) {
    mr_geometry_share_end(r);
    free((void *)r->rig);
    r->rig = NULL;
}

bool mr_render_rig_begin(mr_renderer *r, const mr_rig *rig, const mr_view *centre, int width, int height,
                         mr_error *err) {
    mr_render_rig_end(r);
    if (rig->views < 2 || rig->per_view_work || !r->scene) return true;
    mr_rig_share *sh = calloc(1, sizeof *sh);
    if (!sh) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    /* The views' near planes (each eye's own, as mr_render_frame picks
     * it): the nearest bounds them all; the LOD factor: the largest. */
    double near_plane = INFINITY, fmax_t = 0;
    for (int i = 0; i < rig->views; i++) {
        mr_view v = mr_rig_view(rig, centre, i, width, height);
        near_plane = fmin(near_plane, mr_render_near_plane(r->scene, &v.world_from_camera));
        fmax_t = fmax(fmax_t, mr_geometry_lod_fmax(&v.camera));
        if (i == 0 || i == rig->views - 1) {
            int k = i == 0 ? 0 : 1;
            sh->cam[k] = v.camera;
            sh->world_from_camera[k] = v.world_from_camera;
        }
    }
    static unsigned serial;
    sh->serial = ++serial ? serial : ++serial; /* never 0 */
    sh->views = rig->views;
    sh->near_plane = near_plane;
    sh->centre_cam = sh->cam[0];
    sh->centre_cam.cx = 0.5 * width - 0.5; /* no shear */
    sh->world_from_centre = centre->world_from_camera;
    sh->centre_from_world = mr_m4_invert_rigid(&centre->world_from_camera);
    rig_planes(rig, centre, width, height, near_plane, 0.0, sh->planes);
    /* The same margin as each view's own culling (geometry.c). */
    mr_frustum fr = mr_rig_cull_frustum(rig, centre, width, height, near_plane, 1.0);
    if (!mr_geometry_share_begin(r, &fr, &sh->centre_from_world, near_plane, fmax_t, err)) {
        free(sh);
        return false;
    }
    r->rig = sh;
    return true;
}

bool mr_rig_geometry_time(mr_renderer *r, const mr_rig *rig, const mr_view *centre, int w, int h, bool layered,
                          int frames, double *ms, mr_image *depth, mr_error *err) {
    if (!r->scene) return mr_fail(err, MR_ERR_INVALID, "the layered experiment needs a scene");
    if (frames < 1 || frames > 64) return mr_fail(err, MR_ERR_INVALID, "frames must be in [1, 64]");
    GLint max_vp = 0;
    glGetIntegerv(GL_MAX_VIEWPORTS, &max_vp);
    int per_draw = max_vp < MR_RIG_LAYERED_MAX ? max_vp : MR_RIG_LAYERED_MAX;
    if (layered && per_draw < 2) return mr_fail(err, MR_ERR_GL, "the GPU has no viewport arrays");
    mr_quilt_layout l;
    if (!mr_quilt_layout_make(NULL, rig->views, w, h, &l, err)) return false;
    const char *const files[] = {"rig_layered.vert.glsl", "rig_layered.frag.glsl", NULL};
    GLuint prog = mr_gl_program(files, err);
    if (!prog) return false;
    GLuint tex = mr_gl_make_tex(GL_DEPTH_COMPONENT32F, l.width, l.height, GL_NEAREST), fbo;
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, tex, 0);
    glNamedFramebufferDrawBuffer(fbo, GL_NONE);
    bool ok = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    if (!ok) mr_fail(err, MR_ERR_GL, "layered experiment: framebuffer incomplete");
    /* Shared culling as in a rig frame (per_view_work left aside: both
     * ways draw the same list, only the submission differs). */
    mr_rig shared = *rig;
    shared.per_view_work = false;
    ok = ok && mr_render_rig_begin(r, &shared, centre, w, h, err);
    if (ok && !r->share) ok = mr_fail(err, MR_ERR_INVALID, "the layered experiment needs 2 or more views");
    mr_view *vs = ok ? malloc((size_t)rig->views * sizeof *vs) : NULL;
    if (ok && !vs) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    for (int i = 0; ok && i < rig->views; i++) vs[i] = mr_rig_view(rig, centre, i, w, h);
    double near_plane = ok ? r->rig->near_plane : 1;
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    glDisable(GL_BLEND);
    glUseProgram(prog);
    for (int f = 0; ok && f < frames; f++) {
        glFinish();
        double t0 = mr_time_now();
        static const float zero = 0;
        glClearNamedFramebufferfv(fbo, GL_DEPTH, 0, &zero);
        if (!layered) {
            /* The per-view loop: each view's own instance matrices. */
            glUniform1i(MR_LOC_RIG_VIEWS, 1);
            glUniform1f(MR_LOC_RIG_SHIFT, 0.0f);
            for (int i = 0; i < rig->views; i++) {
                int x0, y0;
                mr_quilt_tile_origin(&l, i, &x0, &y0);
                glViewportIndexedf(0, (float)x0, (float)(l.height - y0 - h), (float)w, (float)h);
                mr_geo_view gv;
                memset(&gv, 0, sizeof gv);
                gv.cam = vs[i].camera;
                gv.world_from_camera = vs[i].world_from_camera;
                gv.cam_from_world = mr_m4_invert_rigid(&vs[i].world_from_camera);
                gv.near_plane = near_plane;
                gv.program = prog;
                gv.layers = 1u << MR_LAYER_VISIBLE | 1u << MR_LAYER_HIDDEN;
                gv.shared = true;
                mr_geometry_draw(r, &gv, NULL);
            }
        } else {
            /* Layered: the centre camera's instances once per batch of
             * views, each copy moved to its eye and viewport. */
            mr_geo_view gv;
            memset(&gv, 0, sizeof gv);
            gv.cam = r->rig->centre_cam;
            gv.world_from_camera = centre->world_from_camera;
            gv.cam_from_world = r->rig->centre_from_world;
            gv.near_plane = near_plane;
            gv.program = prog;
            gv.layers = 1u << MR_LAYER_VISIBLE | 1u << MR_LAYER_HIDDEN;
            for (int i0 = 0; ok && i0 < rig->views; i0 += per_draw) {
                int n = rig->views - i0 < per_draw ? rig->views - i0 : per_draw;
                float proj[16 * MR_RIG_LAYERED_MAX], shift[MR_RIG_LAYERED_MAX];
                for (int k = 0; k < n; k++) {
                    int x0, y0;
                    mr_quilt_tile_origin(&l, i0 + k, &x0, &y0);
                    glViewportIndexedf((GLuint)k, (float)x0, (float)(l.height - y0 - h), (float)w, (float)h);
                    mr_gl_projection(&vs[i0 + k].camera, near_plane, proj + 16 * k);
                    shift[k] = (float)mr_rig_shift(rig, i0 + k);
                }
                glUniformMatrix4fv(MR_LOC_PROJECTION, n, GL_FALSE, proj);
                glUniform1fv(MR_LOC_RIG_SHIFT, n, shift);
                glUniform1i(MR_LOC_RIG_VIEWS, n);
                ok = mr_geometry_draw_replicated(r, &gv, n);
                if (!ok) mr_fail(err, MR_ERR_GL, "layered experiment: no shared list");
            }
        }
        glFinish();
        ms[f] = (mr_time_now() - t0) * 1e3;
    }
    glDisable(GL_DEPTH_TEST);
    glViewport(0, 0, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (ok && depth) {
        /* Framebuffer rows bottom-up: tile row 0 (views 0..) at the bottom. */
        ok = mr_image_alloc(depth, l.width, l.height, 1, MR_PIX_F32, err);
        if (ok) glGetTextureImage(tex, 0, GL_DEPTH_COMPONENT, GL_FLOAT, (GLsizei)mr_image_bytes(depth), depth->data);
    }
    mr_render_rig_end(r);
    free(vs);
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(1, &tex);
    glDeleteProgram(prog);
    GLenum e = glGetError();
    if (ok && e != GL_NO_ERROR) ok = mr_fail(err, MR_ERR_GL, "GL error 0x%x in the layered experiment", e);
    return ok;
}

bool mr_render_rig(mr_renderer *r, const mr_rig *rig, const mr_view *centre, const mr_frame_params *params,
                   const mr_quilt_layout *layout, const char *views_dir, mr_image *quilt, mr_rig_result *res,
                   mr_error *err) {
    mr_rig_result dummy;
    if (!res) res = &dummy;
    memset(res, 0, sizeof *res);
    if (quilt && !mr_image_alloc(quilt, layout->width, layout->height, 3, MR_PIX_U8, err)) return false;
    if (quilt) memset(quilt->data, 0, mr_image_bytes(quilt));
    if (views_dir && !mr_mkdirs(views_dir, err)) goto fail;
    mr_frame_params fp = *params;
    fp.video = NULL;
    fp.width = layout->tile_w;
    fp.height = layout->tile_h;
    /* The noise's frame: the centre camera, shared by all views. */
    fp.ao.noise_anchor = centre->world_from_camera;
    fp.ao.noise_anchor_set = true;
    double t0 = mr_time_now();
    if (!mr_render_rig_begin(r, rig, centre, layout->tile_w, layout->tile_h, err)) goto fail;
    for (int i = 0; i < rig->views; i++) {
        mr_view v = mr_rig_view(rig, centre, i, layout->tile_w, layout->tile_h);
        mr_frame_result fr;
        if (!mr_render_frame(r, &v, &fp, &fr, err)) goto fail;
        mr_draw_stats ds;
        mr_renderer_draw_stats(r, &ds);
        res->frustum_culls += (int)ds.frustum_culls;
        res->cull_ms += ds.cull_ms;
        for (int k = 0; k < fr.pass_count; k++) res->shadow_maps += strcmp(fr.passes[k], "shadow_map") == 0;
        bool ok = !quilt || mr_quilt_put(layout, quilt, i, &fr.color, err);
        if (ok && views_dir) {
            char name[32], path[4096];
            snprintf(name, sizeof name, "view_%03d.png", i);
            mr_path_join(views_dir, name, path, sizeof path);
            ok = mr_image_save_png(path, &fr.color, err);
        }
        mr_frame_result_free(&fr);
        if (!ok) goto fail;
    }
    mr_render_rig_end(r);
    res->ms_total = (mr_time_now() - t0) * 1e3;
    res->views = rig->views;
    return true;
fail:
    mr_render_rig_end(r);
    if (quilt) mr_image_free(quilt);
    return false;
}

bool mr_rig_focus(mr_renderer *r, const mr_scene *scene, const mr_rig_params *rp, const mr_view *centre,
                  const mr_frame_params *fp, double *focal, mr_error *err) {
    double d = rp->focal_distance > 0 ? rp->focal_distance : *focal;
    if (!(d > 0)) {
        /* Where the centre view looks: one frame of depth at the view size. */
        mr_frame_params dp = *fp;
        dp.video = NULL;
        dp.display = NULL;
        dp.want_depth = true;
        dp.ao.method = MR_AO_NONE;
        dp.ao.external = NULL;
        mr_frame_result fr;
        if (!mr_render_frame(r, centre, &dp, &fr, err)) return false;
        d = mr_rig_focal_from_depth(&fr.depth);
        mr_frame_result_free(&fr);
        if (!(d > 0)) d = mr_rig_auto_focal_distance(scene, centre);
    }
    if (!(d > 0)) return mr_fail(err, MR_ERR_INVALID, "nothing in front of the camera to focus on: give --focal-distance");
    *focal = d;
    return true;
}

bool mr_display_setup(mr_renderer *r, const mr_scene *scene, const mr_rig_params *rp, int band, mr_view *view,
                      const mr_frame_params *fp, mr_display_map *map, mr_error *err) {
    mr_frame_params sized = *fp;
    sized.width = fp->width > 0 ? fp->width : view->camera.width;
    sized.height = fp->height > 0 ? fp->height : view->camera.height;
    double d = 0;
    if (!mr_rig_focus(r, scene, rp, view, &sized, &d, err)) return false;
    mr_rig_params one = *rp;
    one.views = 1;
    mr_rig rig;
    if (!mr_rig_make(&one, (double)sized.width / sized.height, d, &rig, err)) return false;
    rig.cone = rp->cone_deg * DEG; /* the observer line's, not a single view's */
    *view = mr_rig_view(&rig, view, 0, sized.width, sized.height);
    *map = mr_display_from_rig(&rig, band);
    return true;
}

bool mr_render_rig_files(mr_renderer *r, const mr_scene *scene, mr_rig_files *job, const mr_view *centre,
                         const mr_frame_params *fp, mr_rig_result *res, mr_error *err) {
    mr_rig_params p = *job->rig;
    const mr_quilt *q = job->quilt;
    int w = fp->width > 0 ? fp->width : centre->camera.width, h = fp->height > 0 ? fp->height : centre->camera.height;
    if (p.views == 0) p.views = q->cols * q->rows; /* --quilt alone: a view per tile */
    if (!mr_quilt_layout_make(q->cols ? q : NULL, p.views, w, h, &job->layout, err)) return false;
    mr_frame_params tile = *fp;
    tile.width = job->layout.tile_w;
    tile.height = job->layout.tile_h;
    if (!mr_rig_focus(r, scene, &p, centre, &tile, &job->focal, err)) return false;
    mr_rig rig;
    if (!mr_rig_make(&p, job->layout.aspect, job->focal, &rig, err)) return false;
    mr_image img = {0};
    if (!mr_render_rig(r, &rig, centre, fp, &job->layout, job->views_dir, &img, res, err)) return false;
    char name[256], path[4096];
    mr_quilt_file_name(job->quilt_name, &job->layout, name, sizeof name);
    mr_path_join(job->quilt_dir, name, path, sizeof path);
    bool ok = mr_image_save_png(path, &img, err);
    mr_image_free(&img);
    return ok;
}
