/* Ambient occlusion passes: positions texture, corner mask (Park & Baek),
 * the SSAO methods (Scheer & Keutel and its baselines), bilateral blur and
 * joint bilateral upsampling (Doronin et al.). The shaders are
 * shaders/ao_*.glsl.
 *
 * A frame decides once (ao_plan) whether AO is off, reused (the camera,
 * the size, the scene and the settings are those of the last computed AO)
 * or computed; the k_passes rows ask that plan, so a frame that does not
 * need AO runs none of these passes and a frozen camera runs only shading. */
#include "render_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

_Static_assert(MR_AO_SCHEER == MR_AO_METHOD_ID_SCHEER && MR_AO_CRYTEK == MR_AO_METHOD_ID_CRYTEK &&
                   MR_AO_FILION == MR_AO_METHOD_ID_FILION && MR_AO_HBAO == MR_AO_METHOD_ID_HBAO &&
                   MR_AO_ALCHEMY == MR_AO_METHOD_ID_ALCHEMY && MR_AO_MAX_SAMPLES == MR_AO_KERNEL_SIZE &&
                   MR_AO_GTAO == MR_AO_METHOD_ID_GTAO && MR_AO_BITMASK == MR_AO_METHOD_ID_BITMASK &&
                   MR_AO_SCHEER_GT == MR_AO_METHOD_ID_SCHEER_GT && MR_AO_MAX_SLICES == MR_AO_SLICES_SIZE &&
                   MR_AO_SCHEER_BM == MR_AO_METHOD_ID_SCHEER_BM,
               "shaders/mr_bindings.h and mr_render.h disagree on AO method ids or the kernel size");

enum { AO_PLAN_OFF = 0, AO_PLAN_REUSE, AO_PLAN_RUN, AO_PLAN_EXTERNAL };

/* Everything that makes an AO buffer what it is; equal keys mean the last
 * buffer can be shown again. */
typedef struct ao_key {
    mr_dmat4 pose;
    mr_camera cam;
    int w, h;
    bool hide_hidden;
    uint64_t scene_gen;
    mr_ao_params p; /* resolved, with want_ao / want_mask / no_reuse cleared */
    mr_display_map display; /* zeros for the pinhole */
} ao_key;

struct mr_ao_state {
    bool broken;          /* a shader failed: AO stays off, the error is reported */
    mr_error error;
    GLuint prog_main, prog_blur, prog_up, prog_outline;
    int w, h, aw, ah, step; /* G-buffer size, AO size, G-buffer pixels per AO pixel */
    GLuint tex_ao[2], fbo_ao[2]; /* AO resolution, ping-pong */
    GLuint tex_full, fbo_full;   /* upsampled result */
    GLuint tex_mask, fbo_mask;   /* outline counts, depth-tested against the G-buffer */
    GLuint result;               /* texture with the finished AO (full resolution) */
    int cur;                     /* which tex_ao holds the latest AO */
    /* kernel */
    int k_n;
    mr_ao_kernel k_kind;
    float k_rmin, k_rmax;
    float kernel3[MR_AO_MAX_SAMPLES * 4], kernel2[MR_AO_MAX_SAMPLES * 4];
    float slices[MR_AO_MAX_SLICES * 4]; /* gtao / bitmask / scheer-gt: directions over half a turn */
    GLuint linear_sampler;              /* their bilinear depth reads (texelFetch ignores it) */
    /* The depth mip chain of their far samples */
    GLuint prog_mip, tex_mip, fbo_mip, mip_sampler;
    int mip_w, mip_h, mip_levels;
    /* Deinterleaved AO: the depth and AO atlases
     * (4x4 tiles of dq_w x dq_h) and the programs that fill and empty them */
    GLuint prog_split, prog_merge, tex_dz, fbo_dz, tex_dao, fbo_dao;
    int dq_w, dq_h;
    bool deint; /* this frame's AO goes through the atlas */
    /* Temporal accumulation, full resolution, ping-pong */
    GLuint prog_temporal;
    GLuint tex_hist[2], tex_hist_n[2], fbo_hist[2]; /* (AO, frames, view z), normal */
    int t_cur;                 /* which holds the latest history */
    bool t_valid;              /* a history to reproject */
    int t_w, t_h;
    int t_frame;               /* frames since the history started (the noise's frame index) */
    mr_dmat4 t_pose;           /* world_from_camera of the history */
    mr_camera t_cam;
    /* reuse */
    bool valid;
    ao_key last;
    uint64_t scene_gen;
    /* outline volumes, per scene mesh: miter-offset copies (mr_mesh_outline) */
    mr_geo_own outline;          /* positions + offset per unit radius as attribute MR_ATTR_OUTLINE_DIR */
    bool outline_built;
    uint64_t outline_gen;
    /* this frame */
    mr_ao_params p; /* resolved */
    float screen_k;
};

/* ------------------------------------------------------------ state */

static void free_targets(mr_ao_state *s) {
    glDeleteFramebuffers(2, s->fbo_ao);
    glDeleteTextures(2, s->tex_ao);
    glDeleteFramebuffers(1, &s->fbo_full);
    glDeleteTextures(1, &s->tex_full);
    glDeleteFramebuffers(1, &s->fbo_mask);
    glDeleteTextures(1, &s->tex_mask);
    s->fbo_ao[0] = s->fbo_ao[1] = s->tex_ao[0] = s->tex_ao[1] = 0;
    s->fbo_full = s->tex_full = s->fbo_mask = s->tex_mask = 0;
    s->w = s->h = s->aw = s->ah = 0;
    s->valid = false;
}

static void free_mips(mr_ao_state *s) {
    glDeleteFramebuffers(1, &s->fbo_mip);
    glDeleteTextures(1, &s->tex_mip);
    s->fbo_mip = s->tex_mip = 0;
    s->mip_w = s->mip_h = s->mip_levels = 0;
}

static void free_deint(mr_ao_state *s) {
    glDeleteFramebuffers(1, &s->fbo_dz);
    glDeleteTextures(1, &s->tex_dz);
    glDeleteFramebuffers(1, &s->fbo_dao);
    glDeleteTextures(1, &s->tex_dao);
    s->fbo_dz = s->tex_dz = s->fbo_dao = s->tex_dao = 0;
    s->dq_w = s->dq_h = 0;
}

static void free_history(mr_ao_state *s) {
    glDeleteFramebuffers(2, s->fbo_hist);
    glDeleteTextures(2, s->tex_hist);
    glDeleteTextures(2, s->tex_hist_n);
    memset(s->fbo_hist, 0, sizeof s->fbo_hist);
    memset(s->tex_hist, 0, sizeof s->tex_hist);
    memset(s->tex_hist_n, 0, sizeof s->tex_hist_n);
    s->t_w = s->t_h = 0;
    s->t_valid = false;
    s->t_frame = 0;
}

static void free_outlines(mr_ao_state *s) {
    mr_geometry_own_free(&s->outline);
    s->outline_built = false;
}

static void free_state(mr_ao_state *s);

void mr_pass_ao_free(mr_renderer *r) {
    free_state(r->ao);
    free_state(r->ao_hidden);
    r->ao = r->ao_hidden = NULL;
}

static void free_state(mr_ao_state *s) {
    if (!s) return;
    free_targets(s);
    free_outlines(s);
    free_history(s);
    free_mips(s);
    free_deint(s);
    glDeleteProgram(s->prog_split);
    glDeleteProgram(s->prog_merge);
    glDeleteProgram(s->prog_mip);
    glDeleteSamplers(1, &s->mip_sampler);
    glDeleteProgram(s->prog_temporal);
    glDeleteProgram(s->prog_main);
    glDeleteProgram(s->prog_blur);
    glDeleteProgram(s->prog_up);
    glDeleteProgram(s->prog_outline);
    glDeleteSamplers(1, &s->linear_sampler);
    free(s);
}

static void mr_pass_ao_scene_changed(mr_renderer *r) {
    mr_ao_state *states[2] = {r->ao, r->ao_hidden};
    for (int i = 0; i < 2; i++) {
        if (!states[i]) continue;
        states[i]->scene_gen++;
        states[i]->valid = false;
        states[i]->t_valid = false; /* another scene's history */
        states[i]->t_frame = 0;
        free_outlines(states[i]);
    }
}

static GLuint fbo_for(GLuint tex) {
    GLuint fbo;
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, tex, 0);
    return fbo;
}

static bool ensure_programs(mr_ao_state *s) {
    if (s->prog_main) return true;
    static const char *const m[] = {"fullscreen.vert.glsl", "ao_main.frag.glsl", NULL};
    static const char *const b[] = {"fullscreen.vert.glsl", "ao_blur.frag.glsl", NULL};
    static const char *const u[] = {"fullscreen.vert.glsl", "ao_upsample.frag.glsl", NULL};
    static const char *const o[] = {"ao_outline.vert.glsl", "ao_outline.frag.glsl", NULL};
    if ((s->prog_main = mr_gl_program(m, &s->error)) && (s->prog_blur = mr_gl_program(b, &s->error)) &&
        (s->prog_up = mr_gl_program(u, &s->error)) &&
        (s->prog_outline = mr_gl_program(o, &s->error)))
        return true;
    s->broken = true;
    return false;
}

static void ensure_targets(mr_ao_state *s, int w, int h, int step) {
    int aw = (w + step - 1) / step, ah = (h + step - 1) / step;
    if (s->w == w && s->h == h && s->aw == aw && s->ah == ah) return;
    free_targets(s);
    for (int i = 0; i < 2; i++) {
        s->tex_ao[i] = mr_gl_make_tex(GL_R32F, aw, ah, GL_NEAREST);
        s->fbo_ao[i] = fbo_for(s->tex_ao[i]);
    }
    s->tex_full = mr_gl_make_tex(GL_R32F, w, h, GL_NEAREST);
    s->fbo_full = fbo_for(s->tex_full);
    s->tex_mask = mr_gl_make_tex(GL_R16F, w, h, GL_NEAREST);
    s->fbo_mask = fbo_for(s->tex_mask);
    s->w = w; s->h = h; s->aw = aw; s->ah = ah;
}

/* Defaults and ranges applied, so that the shaders never see a value that
 * can make them divide by zero or loop without end. */
double mr_ao_default_radius(const mr_scene *scene) {
    double diag = mr_scene_diagonal(scene);
    return diag > 0 ? MR_AO_DEFAULT_RADIUS_FRACTION * diag : 1.0;
}

mr_ao_params mr_ao_params_resolve(const mr_ao_params *in, const mr_scene *scene) {
    mr_ao_params p = *in;
    if (p.samples <= 0) p.samples = MR_AO_DEFAULT_SAMPLES;
    if (p.samples > MR_AO_MAX_SAMPLES) p.samples = MR_AO_MAX_SAMPLES;
    if (p.radii <= 0) p.radii = MR_AO_DEFAULT_RADII;
    if (p.radii > MR_AO_MAX_RADII) p.radii = MR_AO_MAX_RADII;
    if (!(p.screen_radius > 0) || !isfinite(p.screen_radius)) p.screen_radius = MR_AO_DEFAULT_SCREEN_RADIUS;
    if (!(p.radius > 0) || !isfinite(p.radius)) p.radius = mr_ao_default_radius(scene);
    /* Each estimator has its own scale (scheer's attenuated cosines average
     * well below the visibility they stand for), so each has its own
     * default strength: the value `bench ao` found best against the ray-
     * traced reference on a view it does not report. */
    static const float k_strength[MR_AO_METHOD_COUNT] = {1.0f, 3.0f, 1.0f, 1.0f, 1.5f, 2.0f,
                                                         /* gtao, bitmask, scheer-gt: visibility integrals, 1 */
                                                         1.0f, 1.0f, 1.0f,
                                                         /* scheer-bm: attenuated sector counts, 1 */
                                                         1.0f};
    if (!(p.strength > 0) || !isfinite(p.strength))
        p.strength = p.method > MR_AO_NONE && p.method < MR_AO_METHOD_COUNT ? k_strength[p.method] : 1.0f;
    if (!(p.c >= 0) || !isfinite(p.c)) p.c = MR_AO_DEFAULT_C;
    if (!(p.bias >= 0) || !(p.bias < 0.9f)) p.bias = MR_AO_DEFAULT_BIAS;
    if (!(p.r_max > 0 && p.r_max <= 1)) p.r_max = MR_AO_DEFAULT_R_MAX;
    if (!(p.r_min >= 0)) p.r_min = 0.0f;
    if (p.r_min > p.r_max) p.r_min = p.r_max;
    if (p.blur_radius < 0) p.blur_radius = 0;
    if (p.blur_radius > 32) p.blur_radius = 32;
    if ((int)p.kernel < 0 || p.kernel > MR_AO_KERNEL_POISSON) p.kernel = MR_AO_KERNEL_UNIFORM;
    if ((int)p.mask < 0 || p.mask > MR_AO_MASK_STANDALONE) p.mask = MR_AO_MASK_OFF;
    /* Clamped here, before the shader and the blur: the standalone mask is a
     * visibility in [0,1] whatever the method and its strength. */
    if (!(p.mask_strength > 0) || !isfinite(p.mask_strength)) p.mask_strength = MR_AO_DEFAULT_MASK_STRENGTH;
    if (p.mask_strength > 1) p.mask_strength = 1;
    if (!(p.thickness > 0) || !isfinite(p.thickness)) p.thickness = MR_AO_DEFAULT_THICKNESS;
    if (p.thickness > 100) p.thickness = 100;
    if ((int)p.radius_mode < 0 || p.radius_mode > MR_AO_RADIUS_VIEW) p.radius_mode = MR_AO_RADIUS_SCREEN;
    p.want_ao = false;
    p.want_mask = false;
    p.no_reuse = false;
    p.temporal_reset = false;
    p.external = NULL;
    return p;
}

/* The frame's AO plan from the state before the frame: pure, so every
 * needed() can ask it and get the same answer. */
static bool external_ok(const frame *f) {
    const mr_image *ext = f->p->ao.external;
    return ext && ext->data && ext->type == MR_PIX_F32 && ext->channels == 1 && ext->width == f->r->w &&
           ext->height == f->r->h;
}

/* Keys are compared with memcmp, so the parameters are copied field by
 * field into zeroed storage: the padding of a struct copy is unspecified. */
static void copy_fields(mr_ao_params *d, const mr_ao_params *p) {
    memset(d, 0, sizeof *d);
    d->method = p->method;
    d->radius_mode = p->radius_mode;
    d->radius = p->radius;
    d->screen_radius = p->screen_radius;
    d->samples = p->samples;
    d->kernel = p->kernel;
    d->r_min = p->r_min;
    d->r_max = p->r_max;
    d->radii = p->radii;
    d->c = p->c;
    d->bias = p->bias;
    d->strength = p->strength;
    d->blur_radius = p->blur_radius;
    d->half_res = p->half_res;
    d->positions = p->positions;
    d->mask = p->mask;
    d->mask_strength = p->mask_strength;
    d->thickness = p->thickness;
    d->temporal = p->temporal;
    d->temporal_reset = p->temporal_reset;
    d->want_ao = p->want_ao;
    d->want_mask = p->want_mask;
    d->no_reuse = p->no_reuse;
    d->external = p->external;
    d->noise = p->noise;
    d->noise_cell = p->noise_cell;
    d->noise_anchor = p->noise_anchor;
    d->noise_anchor_set = p->noise_anchor_set;
    d->mips = p->mips;
    d->deinterleave = p->deinterleave;
}

static ao_key key_of(const frame *f, const mr_ao_params *resolved, uint64_t scene_gen) {
    ao_key key;
    memset(&key, 0, sizeof key); /* padding too: keys are compared with memcmp */
    key.pose = f->view->world_from_camera;
    key.cam = f->cam;
    key.w = f->r->w;
    key.h = f->r->h;
    key.hide_hidden = f->p->hide_hidden_layer;
    key.scene_gen = scene_gen;
    copy_fields(&key.p, resolved);
    if (f->p->display) {
        key.display.distance = f->p->display->distance;
        key.display.eye_half = f->p->display->eye_half;
        key.display.band = f->p->display->band;
    }
    return key;
}

static int plan_of(const frame *f, const mr_ao_state *s) {
    const mr_ao_params *in = &f->p->ao;
    if (external_ok(f)) return AO_PLAN_EXTERNAL; /* an AO image from outside: no AO pass runs */
    if (in->method <= MR_AO_NONE || in->method >= MR_AO_METHOD_COUNT) return AO_PLAN_OFF;
    if (s && s->broken) return AO_PLAN_OFF;
    /* Accumulation keeps refining a frozen camera's AO: computed every frame. */
    if (!s || !s->valid || in->no_reuse || in->temporal) return AO_PLAN_RUN;
    mr_ao_params p = mr_ao_params_resolve(in, f->r->scene);
    ao_key key = key_of(f, &p, s->scene_gen);
    return memcmp(&key, &s->last, sizeof key) == 0 ? AO_PLAN_REUSE : AO_PLAN_RUN;
}

static bool runs(const frame *f) { return plan_of(f, f->r->ao) == AO_PLAN_RUN; }
/* The standalone mask is a hard 0/1 stencil: it needs the blur to be AO. */
static bool blur_wanted(const mr_ao_params *p) { return p->blur_radius > 0 || p->mask == MR_AO_MASK_STANDALONE; }

static bool mr_pass_need_ao(const frame *f) { return runs(f); }
static bool mr_pass_need_ao_mask(const frame *f) { return runs(f) && mr_ao_params_resolve(&f->p->ao, f->r->scene).mask != MR_AO_MASK_OFF; }
static bool mr_pass_need_ao_blur(const frame *f) {
    if (!runs(f)) return false;
    mr_ao_params p = mr_ao_params_resolve(&f->p->ao, f->r->scene);
    return blur_wanted(&p);
}
/* The atlas path, for every method but not the
 * positions path (its texture is not split) or the standalone mask (it
 * samples nothing). */
static bool deint_wanted(const mr_ao_params *p) {
    return p->deinterleave && !p->positions && p->mask != MR_AO_MASK_STANDALONE;
}
static bool mr_pass_need_ao_deint(const frame *f) {
    if (!runs(f)) return false;
    mr_ao_params p = mr_ao_params_resolve(&f->p->ao, f->r->scene);
    return deint_wanted(&p);
}
static bool mr_pass_need_ao_upsample(const frame *f) { return runs(f) && f->p->ao.half_res; }
static bool mr_pass_need_ao_reuse(const frame *f) { return plan_of(f, f->r->ao) == AO_PLAN_REUSE; }
static bool mr_pass_need_ao_external(const frame *f) { return plan_of(f, f->r->ao) == AO_PLAN_EXTERNAL; }

static uint32_t mr_pass_ao_reads(const frame *f) {
    mr_ao_params p = mr_ao_params_resolve(&f->p->ao, f->r->scene);
    uint32_t r = RES(RES_DEPTH) | RES(RES_NORMAL);
    if (p.positions && p.mask != MR_AO_MASK_STANDALONE) r |= RES(RES_POSITIONS);
    if (p.mask != MR_AO_MASK_OFF) r |= RES(RES_AO_MASK);
    return r;
}

static mr_ao_state *state_of(mr_ao_state **sp, mr_error *err) {
    if (!*sp && !(*sp = calloc(1, sizeof **sp))) mr_fail(err, MR_ERR_NOMEM, "out of memory");
    return *sp;
}

/* Programs, targets and kernel for a computed AO; remembers the key, so the
 * next frame with the same one reuses the result. */
static bool prepare_state(frame *f, mr_ao_state *s, mr_error *err) {
    if (!ensure_programs(s)) {
        *err = s->error;
        mr_error_prefix(err, "ambient occlusion: ");
        return false;
    }
    mr_renderer *r = f->r;
    s->p = mr_ao_params_resolve(&f->p->ao, r->scene);
    s->step = s->p.half_res ? 2 : 1;
    ensure_targets(s, r->w, r->h, s->step);
    /* Scheer & Keutel's depth-scaled radius. Printed as r_S = r_B s_scene
     * d / Z_p (d: depth of the image plane), which shrinks as Z_p grows: the
     * opposite of their text ("the sampling radius [grows] linearly with
     * increasing depth values, keeping its projection constant in screen
     * space"). A radius whose projection r_S f / Z_p stays constant is
     * r_S = (r_B s_scene / d) Z_p: the d / Z_p is a misprint for Z_p / d.
     * Here the projection is a fraction F of the image height: r_S = k Z_p,
     * k = F height / f_y (the same r_S with r_B s_scene = F height, d = f_y). */
    s->screen_k = (float)(s->p.screen_radius * f->cam.height / f->cam.fy);
    if (s->k_n != s->p.samples || s->k_kind != s->p.kernel || s->k_rmin != s->p.r_min || s->k_rmax != s->p.r_max) {
        float k3[MR_AO_MAX_SAMPLES * 3], k2[MR_AO_MAX_SAMPLES * 2];
        mr_ao_kernel_generate(s->p.kernel, s->p.samples, s->p.r_min, s->p.r_max, 0x5eedu, k3, k2);
        memset(s->kernel3, 0, sizeof s->kernel3);
        memset(s->kernel2, 0, sizeof s->kernel2);
        for (int i = 0; i < s->p.samples; i++) {
            memcpy(s->kernel3 + 4 * i, k3 + 3 * i, 3 * sizeof(float));
            memcpy(s->kernel2 + 4 * i, k2 + 2 * i, 2 * sizeof(float));
        }
        s->k_n = s->p.samples;
        s->k_kind = s->p.kernel;
        s->k_rmin = s->p.r_min;
        s->k_rmax = s->p.r_max;
    }
    s->last = key_of(f, &s->p, s->scene_gen);
    s->valid = false; /* until the passes have run */
    s->deint = deint_wanted(&s->p);
    return true;
}

/* Programs and atlases for deinterleaved AO; the
 * atlas is 4x4 tiles of ceil(AO size / 4), so a layer's padding texel (an
 * AO size not divisible by 4) stays inside its own tile. */
static bool ensure_deint(mr_ao_state *s, mr_error *err) {
    if (!s->prog_split) {
        static const char *const a[] = {"fullscreen.vert.glsl", "ao_deint_split.frag.glsl", NULL};
        static const char *const b[] = {"fullscreen.vert.glsl", "ao_deint_merge.frag.glsl", NULL};
        if (!(s->prog_split = mr_gl_program(a, err)) || !(s->prog_merge = mr_gl_program(b, err))) {
            mr_error_prefix(err, "ambient occlusion (deinterleave): ");
            return false;
        }
    }
    int qw = (s->aw + 3) / 4, qh = (s->ah + 3) / 4;
    if (s->dq_w != qw || s->dq_h != qh) {
        free_deint(s);
        s->tex_dz = mr_gl_make_tex(GL_R32F, 4 * qw, 4 * qh, GL_NEAREST);
        s->fbo_dz = fbo_for(s->tex_dz);
        s->tex_dao = mr_gl_make_tex(GL_R32F, 4 * qw, 4 * qh, GL_NEAREST);
        s->fbo_dao = fbo_for(s->tex_dao);
        s->dq_w = qw;
        s->dq_h = qh;
    }
    return true;
}

static bool mr_pass_prepare_ao_deint(frame *f, mr_error *err) {
    mr_ao_state *s = state_of(&f->r->ao, err);
    return s && prepare_state(f, s, err) && ensure_deint(s, err);
}

/* Called for ao_mask and ao: the second call finds everything in place. */
static bool mr_pass_prepare_ao(frame *f, mr_error *err) {
    mr_ao_state *s = state_of(&f->r->ao, err);
    return s && prepare_state(f, s, err);
}

static bool mr_pass_prepare_ao_external(frame *f, mr_error *err) {
    mr_ao_state *s = state_of(&f->r->ao, err);
    if (!s) return false;
    ensure_targets(s, f->r->w, f->r->h, s->step > 0 ? s->step : 1);
    return true;
}

static void mr_pass_ao_external(frame *f) {
    mr_renderer *r = f->r;
    mr_ao_state *s = r->ao;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(s->tex_full, 0, 0, 0, r->w, r->h, GL_RED, GL_FLOAT, f->p->ao.external->data);
    s->result = s->tex_full;
    s->valid = false; /* the next computed AO must not mistake this for its own */
    s->p.mask = MR_AO_MASK_OFF;
    frame_put(f, RES_AO, s->result);
}

static void mr_pass_ao_reuse(frame *f) {
    mr_ao_state *s = f->r->ao;
    frame_put(f, RES_AO, s->result);
    if (s->p.mask != MR_AO_MASK_OFF) frame_put(f, RES_AO_MASK, s->tex_mask);
    f->ao_reused = true;
}

/* What the full-screen AO shaders read: a G-buffer's depth and normal, the
 * positions (0 unless that path is on) and the outline counts. */
typedef struct ao_inputs {
    GLuint depth, normal, positions, mask;
} ao_inputs;

static ao_inputs main_inputs(const frame *f) {
    ao_inputs in = {frame_get(f, RES_DEPTH), frame_get(f, RES_NORMAL), frame_get(f, RES_POSITIONS),
                    frame_get(f, RES_AO_MASK)};
    return in;
}

/* The uniforms the full-screen AO shaders share. */
static void common_uniforms(frame *f, const mr_ao_state *s, const ao_inputs *in) {
    glUniform4f(MR_LOC_AO_INTR, (float)f->cam.fx, (float)f->cam.fy, (float)f->cam.cx, (float)f->cam.cy);
    glUniform2i(MR_LOC_AO_FULL, f->r->w, f->r->h);
    glUniform1i(MR_LOC_AO_STEP, s->step);
    glUniform1f(MR_LOC_AO_NEAR, (float)f->near_plane);
    glBindTextureUnit(MR_TEX_AO_DEPTH, in->depth);
    glBindTextureUnit(MR_TEX_AO_NORMAL, in->normal);
    glBindTextureUnit(MR_TEX_AO_POSITIONS, in->positions);
    glBindTextureUnit(MR_TEX_AO_MASK, in->mask);
}

static void fullscreen(frame *f, GLuint fbo, int w, int h) {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, w, h);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glBindVertexArray(f->r->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
}

static bool ensure_outlines(mr_renderer *r, mr_ao_state *s) {
    const mr_scene *sc = r->scene;
    if (!sc) return false;
    if (s->outline_built && s->outline_gen == s->scene_gen) return s->outline.valid;
    free_outlines(s);
    s->outline_built = true;
    s->outline_gen = s->scene_gen;
    mr_outline *ol = calloc((size_t)sc->mesh_count + 1, sizeof *ol);
    mr_geo_own_mesh *gm = calloc((size_t)sc->mesh_count + 1, sizeof *gm);
    bool ok = ol && gm;
    for (int32_t i = 0; ok && i < sc->mesh_count; i++) {
        mr_error err = {0};
        if (!mr_mesh_outline(&sc->meshes[i], &ol[i], &err)) continue; /* no outline: the mesh never masks */
        gm[i] = (mr_geo_own_mesh){ol[i].positions, ol[i].dirs, ol[i].indices, ol[i].vertex_count, ol[i].index_count};
    }
    ok = ok && mr_geometry_own_create(gm, sc->mesh_count, MR_ATTR_OUTLINE_DIR, &s->outline);
    for (int32_t i = 0; ol && i < sc->mesh_count; i++) mr_outline_free(&ol[i]);
    free(ol);
    free(gm);
    return ok;
}

/* Park & Baek: draw every outline volume with additive blending into a
 * float target; a count >= 2 marks a pixel where two volumes overlap at the
 * visible surface: a corner. The paper counts the faces in front of the
 * surface (+1 entering, -1 leaving), which is wrong by one for every volume
 * the camera stands in (the entering face is behind the eye). Counted here
 * behind the surface instead (depth-tested farther than the G-buffer: +1
 * leaving, -1 entering), which gives the number of volumes holding the
 * surface point wherever the camera is: every volume is closed and the far
 * plane is at infinity, so no face behind the surface is clipped. */
static void mr_pass_ao_mask(frame *f) {
    mr_renderer *r = f->r;
    mr_ao_state *s = r->ao;
    static const float zero[4] = {0, 0, 0, 0};
    glNamedFramebufferTexture(s->fbo_mask, GL_DEPTH_ATTACHMENT, frame_get(f, RES_DEPTH), 0);
    glClearNamedFramebufferfv(s->fbo_mask, GL_COLOR, 0, zero);
    frame_put(f, RES_AO_MASK, s->tex_mask);
    if (!ensure_outlines(r, s)) return;
    glBindFramebuffer(GL_FRAMEBUFFER, s->fbo_mask);
    glViewport(0, 0, s->w, s->h);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS); /* reversed Z: behind the visible surface */
    glDepthMask(GL_FALSE);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_ONE, GL_ONE);
    glUseProgram(s->prog_outline);
    glUniform1i(MR_LOC_OUTLINE_RADIUS_MODE, s->p.radius_mode == MR_AO_RADIUS_SCREEN ? 0 : 1);
    glUniform1f(MR_LOC_OUTLINE_RADIUS, (float)s->p.radius);
    glUniform1f(MR_LOC_OUTLINE_SCREEN_K, s->screen_k);
    uint32_t mask = 1u << MR_LAYER_VISIBLE;
    if (!f->p->hide_hidden_layer) mask |= 1u << MR_LAYER_HIDDEN;
    mr_geo_view v = mr_frame_view(f, s->prog_outline, mask);
    mr_geometry_own_draw(r, &v, &s->outline);
    glDepthFunc(GL_GREATER);
    glDisable(GL_BLEND);
    glDisable(GL_DEPTH_TEST);
    glDepthMask(GL_TRUE);
}

/* The slice integrators' split of the sample budget: floor(sqrt(samples /
 * 4)) slices (at least 1) and the rest as steps per side (8: 1 x 4,
 * 16: 2 x 4, 32: 2 x 8, 64: 4 x 8). Too few steps under-reads every
 * horizon (a bias the blur cannot remove), too few slices is noise across
 * pixels (the per-pixel rotation), so steps grow first. */
void mr_ao_slice_split(int samples, int *slices, int *steps) {
    if (samples < 1) samples = 1;
    int sl = (int)floor(sqrt(samples / 4.0));
    if (sl < 1) sl = 1;
    if (sl > MR_AO_MAX_SLICES) sl = MR_AO_MAX_SLICES;
    int st = samples / (2 * sl);
    *slices = sl;
    *steps = st > 0 ? st : 1;
}

static bool slice_method(mr_ao_method m) {
    return m == MR_AO_GTAO || m == MR_AO_BITMASK || m == MR_AO_SCHEER_GT || m == MR_AO_SCHEER_BM;
}

/* The depth mip chain, only for a slice method with mips on and
 * the positions path off (that path reads the nearest pixel's position).
 * Level 0 is a copy of the G-buffer's reversed-Z depth (ao_depth_mip), the
 * levels above it glGenerateTextureMipmap's box filter. Returns the levels
 * above 0 that the shader may read, 0 when there is no chain. */
static int build_depth_mips(frame *f, mr_ao_state *s, const ao_inputs *in) {
    const mr_ao_params *p = &s->p;
    if (!p->mips || !slice_method(p->method) || p->positions || p->mask == MR_AO_MASK_STANDALONE) return 0;
    int w = f->r->w, h = f->r->h;
    if (!s->prog_mip) {
        static const char *const m[] = {"fullscreen.vert.glsl", "ao_depth_mip.frag.glsl", NULL};
        mr_error e = {0};
        if (!(s->prog_mip = mr_gl_program(m, &e))) return 0; /* no chain: level 0 only, as without mips */
    }
    if (s->mip_w != w || s->mip_h != h) {
        free_mips(s);
        int levels = 0;
        while (levels < MR_AO_MIP_LEVELS && (w >> (levels + 1)) >= 1 && (h >> (levels + 1)) >= 1) levels++;
        glCreateTextures(GL_TEXTURE_2D, 1, &s->tex_mip);
        glTextureStorage2D(s->tex_mip, levels + 1, GL_R32F, w, h);
        glCreateFramebuffers(1, &s->fbo_mip);
        glNamedFramebufferTexture(s->fbo_mip, GL_COLOR_ATTACHMENT0, s->tex_mip, 0);
        s->mip_w = w;
        s->mip_h = h;
        s->mip_levels = levels;
    }
    if (!s->mip_sampler) {
        glCreateSamplers(1, &s->mip_sampler);
        glSamplerParameteri(s->mip_sampler, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
        glSamplerParameteri(s->mip_sampler, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glSamplerParameteri(s->mip_sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glSamplerParameteri(s->mip_sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    glUseProgram(s->prog_mip);
    glBindTextureUnit(MR_TEX_AO_MIP_SRC, in->depth);
    fullscreen(f, s->fbo_mip, w, h);
    glGenerateTextureMipmap(s->tex_mip);
    return s->mip_levels;
}

/* World noise: the camera-space position goes to the anchor's frame
 * (composed in double, so only the small anchor-relative part is float)
 * and is hashed on a grid of noise_cell. Views that share the anchor give
 * the same surface point the same rotation. */
static void noise_uniforms(const frame *f, const mr_ao_params *p) {
    if (p->noise != MR_AO_NOISE_WORLD) {
        glUniform1i(MR_LOC_AO_NOISE, 0);
        return;
    }
    bool grid = p->noise_cell > 0 && isfinite(p->noise_cell);
    glUniform1i(MR_LOC_AO_NOISE, grid ? 1 : 2);
    /* Without an anchor the frame's own camera is it. */
    mr_dmat4 a = mr_m4_identity();
    if (p->noise_anchor_set) {
        mr_dmat4 anchor_from_world;
        if (mr_m4_invert(&p->noise_anchor, &anchor_from_world)) a = mr_m4_mul(&anchor_from_world, &f->view->world_from_camera);
    }
    float m[16];
    mr_m4_to_gl(&a, m);
    glUniformMatrix4fv(MR_LOC_AO_NOISE_FRAME, 1, GL_FALSE, m);
    glUniform1f(MR_LOC_AO_NOISE_CELL, grid ? (float)p->noise_cell : (float)MR_AO_NOISE_CELL_PX);
}

/* The G-buffer's depth into the 16 layers. */
static void stage_split(frame *f, mr_ao_state *s, const ao_inputs *in) {
    glUseProgram(s->prog_split);
    glUniform2i(MR_LOC_AO_DEINT_SPLIT_Q, s->dq_w, s->dq_h);
    glUniform1i(MR_LOC_AO_DEINT_SPLIT_STEP, s->step);
    glUniform2i(MR_LOC_AO_DEINT_SPLIT_FULL, f->r->w, f->r->h);
    glBindTextureUnit(MR_TEX_AO_DEINT_SRC, in->depth);
    fullscreen(f, s->fbo_dz, 4 * s->dq_w, 4 * s->dq_h);
}

/* ... and the AO atlas back into the interleaved AO image. */
static void stage_merge(frame *f, mr_ao_state *s) {
    glUseProgram(s->prog_merge);
    glUniform2i(MR_LOC_AO_DEINT_SPLIT_Q, s->dq_w, s->dq_h);
    glBindTextureUnit(MR_TEX_AO_DEINT_SRC, s->tex_dao);
    fullscreen(f, s->fbo_ao[0], s->aw, s->ah);
    glBindTextureUnit(MR_TEX_AO_DEINT_SRC, 0);
    s->cur = 0;
    s->result = s->tex_ao[0];
}

static void stage_main(frame *f, mr_ao_state *s, const ao_inputs *in) {
    const mr_ao_params *p = &s->p;
    int mips = build_depth_mips(f, s, in);
    glUseProgram(s->prog_main);
    glUniform1i(MR_LOC_AO_MIPS, mips);
    glUniform1f(MR_LOC_AO_MIP_NEAR, (float)MR_AO_MIP_NEAR_PX);
    if (mips > 0) {
        glBindTextureUnit(MR_TEX_AO_DEPTH_MIP, s->tex_mip);
        glBindSampler(MR_TEX_AO_DEPTH_MIP, s->mip_sampler);
    }
    common_uniforms(f, s, in);
    glUniform1i(MR_LOC_AO_METHOD, p->mask == MR_AO_MASK_STANDALONE ? MR_AO_METHOD_MASK_STANDALONE : (int)p->method);
    glUniform1i(MR_LOC_AO_SAMPLES, p->samples);
    glUniform1i(MR_LOC_AO_RADIUS_MODE, p->radius_mode == MR_AO_RADIUS_SCREEN ? 0 : 1);
    glUniform1f(MR_LOC_AO_RADIUS, (float)p->radius);
    glUniform1f(MR_LOC_AO_SCREEN_K, s->screen_k);
    glUniform1f(MR_LOC_AO_C, p->c);
    glUniform1f(MR_LOC_AO_BIAS, p->bias);
    glUniform1f(MR_LOC_AO_STRENGTH, p->strength);
    glUniform1i(MR_LOC_AO_RADII, p->radii);
    /* The standalone mask samples no AO, so the G-buffer writes no
     * positions for it: depth is un-projected instead. */
    glUniform1i(MR_LOC_AO_USE_POS, p->positions && p->mask != MR_AO_MASK_STANDALONE ? 1 : 0);
    glUniform1i(MR_LOC_AO_USE_MASK, p->mask == MR_AO_MASK_ON ? 1 : 0);
    glUniform1f(MR_LOC_AO_MASK_STRENGTH, p->mask_strength);
    glUniform4fv(MR_LOC_AO_KERNEL, MR_AO_MAX_SAMPLES, s->kernel3);
    glUniform4fv(MR_LOC_AO_KERNEL2, MR_AO_MAX_SAMPLES, s->kernel2);
    glUniform1i(MR_LOC_AO_FRAME, p->temporal ? s->t_frame : 0);
    if (slice_method(p->method)) {
        int sl, st;
        mr_ao_slice_split(p->samples, &sl, &st);
        /* Directions pi i / slices; the shader turns the set by a per-pixel
         * angle in [0, pi / slices), so no pixel computes more than one
         * sine and cosine for its directions. */
        memset(s->slices, 0, sizeof s->slices);
        for (int i = 0; i < sl; i++) {
            double a = 3.14159265358979323846 * i / sl;
            s->slices[4 * i] = (float)cos(a);
            s->slices[4 * i + 1] = (float)sin(a);
        }
        glUniform4fv(MR_LOC_AO_SLICES, MR_AO_MAX_SLICES, s->slices);
        glUniform1i(MR_LOC_AO_SLICE_COUNT, sl);
        glUniform1i(MR_LOC_AO_STEPS, st);
        glUniform1f(MR_LOC_AO_THICKNESS, p->thickness);
        if (!s->linear_sampler) {
            glCreateSamplers(1, &s->linear_sampler);
            glSamplerParameteri(s->linear_sampler, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
            glSamplerParameteri(s->linear_sampler, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
            glSamplerParameteri(s->linear_sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
            glSamplerParameteri(s->linear_sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
            glSamplerParameteri(s->linear_sampler, GL_TEXTURE_COMPARE_MODE, GL_NONE);
        }
        glBindSampler(MR_TEX_AO_DEPTH, s->linear_sampler);
    }
    noise_uniforms(f, p);
    /* The display mapping: D, E and the width for project()'s exact
     * per-column formula; D = 0 is the pinhole. */
    const mr_display_map *dm = f->p->display;
    glUniform3f(MR_LOC_AO_DISPLAY, dm ? (float)dm->distance : 0.0f, dm ? (float)dm->eye_half : 0.0f, (float)f->r->w);
    /* One draw over the atlas, every tile a layer */
    bool deint = s->deint && s->tex_dz;
    glUniform1i(MR_LOC_AO_DEINT, deint ? 1 : 0);
    glUniform2i(MR_LOC_AO_DEINT_Q, s->dq_w > 0 ? s->dq_w : 1, s->dq_h > 0 ? s->dq_h : 1);
    glUniform1f(MR_LOC_AO_DEINT_NEAR, (float)(MR_AO_DEINT_NEAR * 4 * s->step));
    if (deint) {
        glBindTextureUnit(MR_TEX_AO_DEINT_DEPTH, s->tex_dz);
        if (slice_method(p->method)) glBindSampler(MR_TEX_AO_DEINT_DEPTH, s->linear_sampler);
        fullscreen(f, s->fbo_dao, 4 * s->dq_w, 4 * s->dq_h);
        glBindSampler(MR_TEX_AO_DEINT_DEPTH, 0);
        glBindTextureUnit(MR_TEX_AO_DEINT_DEPTH, 0);
    } else {
        fullscreen(f, s->fbo_ao[0], s->aw, s->ah);
    }
    glBindSampler(MR_TEX_AO_DEPTH, 0);
    if (mips > 0) {
        glBindSampler(MR_TEX_AO_DEPTH_MIP, 0);
        glBindTextureUnit(MR_TEX_AO_DEPTH_MIP, 0);
    }
    s->cur = 0;
    s->result = s->tex_ao[0];
    s->valid = true;
}

static void stage_blur(frame *f, mr_ao_state *s, const ao_inputs *in) {
    int radius = s->p.blur_radius > 0 ? s->p.blur_radius : MR_AO_DEFAULT_BLUR_RADIUS;
    glUseProgram(s->prog_blur);
    common_uniforms(f, s, in);
    glUniform1i(MR_LOC_AO_BLUR_RADIUS, radius);
    glUniform2i(MR_LOC_AO_SIZE, s->aw, s->ah);
    for (int pass = 0; pass < 2; pass++) {
        glUniform2i(MR_LOC_AO_BLUR_DIR, pass == 0, pass == 1);
        glBindTextureUnit(MR_TEX_AO_INPUT, s->tex_ao[s->cur]);
        fullscreen(f, s->fbo_ao[1 - s->cur], s->aw, s->ah);
        s->cur = 1 - s->cur;
    }
    glBindTextureUnit(MR_TEX_AO_INPUT, 0);
    s->result = s->tex_ao[s->cur];
}

static void stage_upsample(frame *f, mr_ao_state *s, const ao_inputs *in) {
    glUseProgram(s->prog_up);
    common_uniforms(f, s, in);
    glUniform2i(MR_LOC_AO_SIZE, s->aw, s->ah);
    glBindTextureUnit(MR_TEX_AO_INPUT, s->tex_ao[s->cur]);
    fullscreen(f, s->fbo_full, s->w, s->h);
    glBindTextureUnit(MR_TEX_AO_INPUT, 0);
    s->result = s->tex_full;
}

static void mr_pass_ao(frame *f) {
    ao_inputs in = main_inputs(f);
    stage_main(f, f->r->ao, &in);
    frame_put(f, RES_AO, f->r->ao->result);
}

static void mr_pass_ao_deint_split(frame *f) {
    ao_inputs in = main_inputs(f);
    stage_split(f, f->r->ao, &in);
}

static void mr_pass_ao_deint_merge(frame *f) {
    stage_merge(f, f->r->ao);
    frame_put(f, RES_AO, f->r->ao->result);
}

static void mr_pass_ao_blur(frame *f) {
    ao_inputs in = main_inputs(f);
    stage_blur(f, f->r->ao, &in);
    frame_put(f, RES_AO, f->r->ao->result);
}

static void mr_pass_ao_upsample(frame *f) {
    ao_inputs in = main_inputs(f);
    stage_upsample(f, f->r->ao, &in);
    frame_put(f, RES_AO, f->r->ao->result);
}

/* ------------------------------------------------------------ temporal */

static bool mr_pass_need_ao_temporal(const frame *f) { return runs(f) && f->p->ao.temporal; }

/* Program and history targets; a new size, a reset or an explicit
 * temporal_reset start the history again (and the noise at frame 0, so
 * the first frame of a history is the single-frame AO). */
static bool mr_pass_prepare_ao_temporal(frame *f, mr_error *err) {
    mr_ao_state *s = f->r->ao;
    if (!s->prog_temporal) {
        static const char *const t[] = {"fullscreen.vert.glsl", "ao_temporal.frag.glsl", NULL};
        if (!(s->prog_temporal = mr_gl_program(t, err))) {
            mr_error_prefix(err, "ambient occlusion (temporal): ");
            return false;
        }
    }
    int w = f->r->w, h = f->r->h;
    if (s->t_w != w || s->t_h != h) {
        free_history(s);
        for (int i = 0; i < 2; i++) {
            s->tex_hist[i] = mr_gl_make_tex(GL_RGBA32F, w, h, GL_NEAREST);
            s->tex_hist_n[i] = mr_gl_make_tex(GL_RGBA16F, w, h, GL_NEAREST);
            glCreateFramebuffers(1, &s->fbo_hist[i]);
            glNamedFramebufferTexture(s->fbo_hist[i], GL_COLOR_ATTACHMENT0, s->tex_hist[i], 0);
            glNamedFramebufferTexture(s->fbo_hist[i], GL_COLOR_ATTACHMENT1, s->tex_hist_n[i], 0);
            static const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
            glNamedFramebufferDrawBuffers(s->fbo_hist[i], 2, bufs);
        }
        s->t_w = w;
        s->t_h = h;
    }
    if (f->p->ao.temporal_reset) {
        s->t_valid = false;
        s->t_frame = 0;
    }
    return true;
}

static void mr_pass_ao_temporal(frame *f) {
    mr_ao_state *s = f->r->ao;
    mr_renderer *r = f->r;
    /* current view -> previous view, in double, then float (camera-relative:
     * the translation is the camera's motion, not a world position) */
    mr_dmat4 prev_from_world = mr_m4_invert_rigid(&s->t_pose);
    mr_dmat4 m = mr_m4_mul(&prev_from_world, &f->view->world_from_camera);
    float mf[16];
    for (int i = 0; i < 16; i++) mf[i] = (float)m.m[i];
    int src = s->t_cur, dst = 1 - s->t_cur;
    glUseProgram(s->prog_temporal);
    glUniform4f(MR_LOC_AO_INTR, (float)f->cam.fx, (float)f->cam.fy, (float)f->cam.cx, (float)f->cam.cy);
    glUniform2i(MR_LOC_AO_FULL, r->w, r->h);
    glUniform1f(MR_LOC_AO_NEAR, (float)f->near_plane);
    glUniformMatrix4fv(MR_LOC_TAA_PREV_FROM_CUR, 1, GL_TRUE, mf); /* mr_dmat4 is row-major */
    glUniform4f(MR_LOC_TAA_PREV_INTR, (float)s->t_cam.fx, (float)s->t_cam.fy, (float)s->t_cam.cx, (float)s->t_cam.cy);
    glUniform1i(MR_LOC_TAA_HAVE_HISTORY, s->t_valid ? 1 : 0);
    glUniform1f(MR_LOC_TAA_MAX_COUNT, (float)MR_AO_TEMPORAL_FRAMES);
    glUniform1f(MR_LOC_TAA_DEPTH_TOL, (float)MR_AO_TEMPORAL_DEPTH_TOL);
    glUniform1f(MR_LOC_TAA_NORMAL_COS, (float)MR_AO_TEMPORAL_NORMAL_COS);
    glBindTextureUnit(MR_TEX_AO_DEPTH, frame_get(f, RES_DEPTH));
    glBindTextureUnit(MR_TEX_AO_NORMAL, frame_get(f, RES_NORMAL));
    glBindTextureUnit(MR_TEX_AO_INPUT, frame_get(f, RES_AO));
    glBindTextureUnit(MR_TEX_TAA_HISTORY, s->tex_hist[src]);
    glBindTextureUnit(MR_TEX_TAA_HISTORY_N, s->tex_hist_n[src]);
    fullscreen(f, s->fbo_hist[dst], r->w, r->h);
    glBindTextureUnit(MR_TEX_AO_INPUT, 0);
    glBindTextureUnit(MR_TEX_TAA_HISTORY, 0);
    glBindTextureUnit(MR_TEX_TAA_HISTORY_N, 0);
    s->t_cur = dst;
    s->t_valid = true;
    s->t_pose = f->view->world_from_camera;
    s->t_cam = f->cam;
    s->t_frame++;
    s->result = s->tex_hist[dst]; /* its .r is the accumulated AO */
    frame_put(f, RES_AO, s->result);
}

/* Fills out->ao (if asked) and the mask statistics. */
static bool ao_read_back(frame *f, mr_error *err) {
    mr_renderer *r = f->r;
    mr_frame_result *o = f->out;
    o->ao_masked_fraction = -1;
    o->ao_reused = f->ao_reused;
    if (f->p->ao.external && !external_ok(f))
        return mr_fail(err, MR_ERR_INVALID, "the external AO image must be F32x1 at the output size %dx%d", r->w, r->h);
    if (r->ao && r->ao->broken && f->p->ao.method != MR_AO_NONE) {
        *err = r->ao->error;
        mr_error_prefix(err, "ambient occlusion: ");
        return false;
    }
    GLuint ao = frame_get(f, RES_AO), mask = frame_get(f, RES_AO_MASK);
    if (f->p->ao.want_ao) {
        if (!mr_image_alloc(&o->ao, r->w, r->h, 1, MR_PIX_F32, err)) return false;
        float *a = o->ao.data;
        size_t n = (size_t)r->w * r->h;
        if (ao) {
            glPixelStorei(GL_PACK_ALIGNMENT, 4);
            glGetTextureImage(ao, 0, GL_RED, GL_FLOAT, (GLsizei)(n * sizeof *a), a);
        } else {
            for (size_t i = 0; i < n; i++) a[i] = 1.0f;
        }
    }
    if (mask) {
        size_t n = (size_t)r->w * r->h;
        float *cnt = malloc(n * sizeof *cnt), *dep = malloc(n * sizeof *dep);
        if (!cnt || !dep) {
            free(cnt); free(dep);
            return mr_fail(err, MR_ERR_NOMEM, "out of memory reading the AO mask");
        }
        glGetTextureImage(mask, 0, GL_RED, GL_FLOAT, (GLsizei)(n * sizeof *cnt), cnt);
        glGetTextureImage(frame_get(f, RES_DEPTH), 0, GL_DEPTH_COMPONENT, GL_FLOAT, (GLsizei)(n * sizeof *dep), dep);
        size_t geo = 0, in = 0;
        for (size_t i = 0; i < n; i++)
            if (dep[i] > 0) {
                geo++;
                in += cnt[i] > 1.5f;
            }
        o->ao_masked_fraction = geo ? (double)in / (double)geo : 0.0;
        free(dep);
        /* The counts themselves, for tests and debugging. */
        bool ok = !f->p->ao.want_mask || mr_image_alloc(&o->ao_mask, r->w, r->h, 1, MR_PIX_F32, err);
        if (ok && o->ao_mask.data) memcpy(o->ao_mask.data, cnt, n * sizeof *cnt);
        free(cnt);
        if (!ok) return false;
    }
    return true;
}

/* The hidden layer D gets AO when the main image has computed (or reused)
 * AO, in a state of its own; decided in ghost_hidden's prepare. */
bool mr_ao_hidden_prepare(frame *f, mr_error *err) {
    mr_renderer *r = f->r;
    int main_plan = plan_of(f, r->ao);
    f->ao_hidden_plan = AO_PLAN_OFF;
    if (main_plan != AO_PLAN_RUN && main_plan != AO_PLAN_REUSE) return true; /* no AO, or an external image */
    mr_ao_state *s = state_of(&r->ao_hidden, err);
    if (!s) return false;
    int pl = plan_of(f, s);
    if (pl == AO_PLAN_RUN) {
        if (!prepare_state(f, s, err)) return false;
        s->p.mask = MR_AO_MASK_OFF; /* outlines of D are not drawn */
        s->p.positions = false;     /* D has no positions attachment */
        s->deint = deint_wanted(&s->p);
    }
    f->ao_hidden_plan = pl;
    return true;
}

GLuint mr_ao_hidden_run(frame *f, GLuint depth, GLuint normal) {
    mr_ao_state *s = f->r->ao_hidden;
    if (f->ao_hidden_plan == AO_PLAN_RUN) {
        ao_inputs in = {depth, normal, 0, s->tex_mask};
        /* D's own atlases */
        mr_error e = {0};
        if (s->deint && !ensure_deint(s, &e)) s->deint = false;
        if (s->deint) stage_split(f, s, &in);
        stage_main(f, s, &in);
        if (s->deint) stage_merge(f, s);
        if (blur_wanted(&s->p)) stage_blur(f, s, &in);
        if (s->step > 1) stage_upsample(f, s, &in);
    }
    return f->ao_hidden_plan == AO_PLAN_RUN || f->ao_hidden_plan == AO_PLAN_REUSE ? s->result : 0;
}

/* The rows of the registry (k_passes in renderer.c). */
#define AO_DESTROY .scene_changed = mr_pass_ao_scene_changed, .destroy = mr_pass_ao_free
const pass_desc mr_pass_desc_ao_mask = {
    .name = "ao_mask", .needed = mr_pass_need_ao_mask, .prepare = mr_pass_prepare_ao, .run = mr_pass_ao_mask,
    AO_DESTROY, .reads = RES(RES_DEPTH), .writes = RES(RES_AO_MASK)};
const pass_desc mr_pass_desc_ao = {
    .name = "ao", .needed = mr_pass_need_ao, .prepare = mr_pass_prepare_ao, .run = mr_pass_ao, AO_DESTROY,
    .reads = RES(RES_DEPTH) | RES(RES_NORMAL) | RES(RES_POSITIONS) | RES(RES_AO_MASK), .writes = RES(RES_AO),
    .reads_now = mr_pass_ao_reads, .read_back = ao_read_back};
/* Around the AO pass, only with deinterleave on. */
const pass_desc mr_pass_desc_ao_deint_split = {
    .name = "ao_deint_split", .needed = mr_pass_need_ao_deint, .prepare = mr_pass_prepare_ao_deint,
    .run = mr_pass_ao_deint_split, AO_DESTROY, .reads = RES(RES_DEPTH)};
const pass_desc mr_pass_desc_ao_deint_merge = {
    .name = "ao_deint_merge", .needed = mr_pass_need_ao_deint, .run = mr_pass_ao_deint_merge, AO_DESTROY,
    .reads = RES(RES_AO), .writes = RES(RES_AO)};
const pass_desc mr_pass_desc_ao_blur = {
    .name = "ao_blur", .needed = mr_pass_need_ao_blur, .run = mr_pass_ao_blur, AO_DESTROY,
    .reads = RES(RES_DEPTH) | RES(RES_NORMAL) | RES(RES_AO), .writes = RES(RES_AO)};
const pass_desc mr_pass_desc_ao_upsample = {
    .name = "ao_upsample", .needed = mr_pass_need_ao_upsample, .run = mr_pass_ao_upsample, AO_DESTROY,
    .reads = RES(RES_DEPTH) | RES(RES_NORMAL) | RES(RES_AO), .writes = RES(RES_AO)};
/* Not listed (no GPU work of their own): the AO of an earlier frame with the
 * same camera, size, scene and settings, or an AO image given from outside
 * (ground truth), stands in for the AO passes. */
/* After the AO (and its blur / upsample), before shading. */
const pass_desc mr_pass_desc_ao_temporal = {
    .name = "ao_temporal", .needed = mr_pass_need_ao_temporal, .prepare = mr_pass_prepare_ao_temporal,
    .run = mr_pass_ao_temporal, AO_DESTROY, .reads = RES(RES_DEPTH) | RES(RES_NORMAL) | RES(RES_AO), .writes = RES(RES_AO)};
const pass_desc mr_pass_desc_ao_reuse = {
    .needed = mr_pass_need_ao_reuse, .run = mr_pass_ao_reuse, AO_DESTROY,
    .writes = RES(RES_AO) | RES(RES_AO_MASK)};
const pass_desc mr_pass_desc_ao_external = {
    .needed = mr_pass_need_ao_external, .prepare = mr_pass_prepare_ao_external, .run = mr_pass_ao_external,
    AO_DESTROY, .writes = RES(RES_AO)};
