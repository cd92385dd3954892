/* Adaptive ghosted views (Kalkofen et al., "Adaptive Ghosted Views for
 * Augmented Reality"), on the GPU.
 *
 * Passes (listed in k_passes in renderer.c, run only when a frame ghosts):
 *   ghost_hidden     the hidden layer into its own G-buffer and shaded: D
 *   ghost_curvature  per-pixel principal curvature of the occluding model
 *   ghost_importance IM (curvature and/or saliency of O), region, silhouette
 *   ghost_g0         alpha = t * IM, G0 = O*alpha + D*(1-alpha)
 *   ghost_analysis   S(G0), C = max(0, C_desired - S(G0))          (adaptive)
 *   ghost_emphasis   GK(C), GK(D), one L* sign per occluder object, G_A
 *
 * The stage functions work on the textures in mr_ghost_state, so the same
 * code serves the frame and the image-level API (mr_ghost_compose, used by
 * tests and benches). All full-screen work is compute shaders on rgba32f
 * images; the finished image is written sRGB-encoded into RGBA8 storage
 * that an sRGB texture view reinterprets, so read-back and later passes see
 * a normal sRGB8 texture. */
#include "render_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Eq. 9 with centres 0..2 reads levels 0..6 with surrounds n+2..n+4 (the
 * default) and levels 0..8 as printed (surrounds n+m, m = n+2..n+4); see
 * mr_saliency_levels for why the default is not the printed one. */
#define SAL_LEVELS 9
/* Sigmas of the two-Gaussian approximation, in level-0 pixels: a Gaussian
 * pyramid with a unit-sigma f_p gives level n the variance (4^n - 1) / 3;
 * the positive terms (levels 0,1,2) average a variance of 2, the negative
 * ones (2,3,3,4,4,4,5,5,6) about 261, as printed (2,3,4,4,5,6,6,7,8) about
 * 3397. The default's wide one is cut at 20 pixels each side, the paper's
 * "approximately 40 samples"; the printed one at 3 sigma. */
#define SAL_SIGMA_POS 1.41421356f
#define SAL_SIGMA_NEG 16.2f
#define SAL_RADIUS_NEG 20
#define SAL_SIGMA_NEG_PRINTED 58.28f
/* Pointer-jumping steps of the connected-region labelling of the video
 * occluder; each step at least halves the label path of a region. */
#define LABEL_STEPS 24

typedef struct mr_ghost_state {
    GLuint prog_lab, prog_blur, prog_sal, prog_imp, prog_g0, prog_ana, prog_label, prog_emph, prog_stats, prog_curv;
    int w, h;
    target hid;          /* D's G-buffer: albedo, normal, ids, depth */
    target hid_shaded;   /* D shaded (sRGB8) */
    target curv;         /* R32F curvature + depth */
    GLuint lab;          /* rgba32f with lab_levels (<= SAL_LEVELS) mips: L*a*b* pyramid */
    int lab_levels;
    GLuint tmp, gpos, gneg, sal_o, sal_g0, sal_final;
    GLuint mask, key, label[2];
    GLuint g0, c, gkc, dgk, oa, ga;
    GLuint in_o, in_d;   /* inputs of the image-level API (rgba32f) */
    GLuint out_store, out_view; /* RGBA8 storage and its sRGB view */
    GLuint ssbo_stats, ssbo_votes, ssbo_sums;
    size_t votes_cap;    /* ints */
    mr_geo_aux curv_aux; /* per-vertex curvature as attribute 3, once per scene (cache) */
    bool curv_built;
    /* per frame */
    GLuint o_tex;        /* the occluder image of this frame (linear when sampled) */
    bool layers_valid;   /* o_tex, hid_shaded and mask hold a frame's layers (mr_ghost_read_layers) */
} mr_ghost_state;

static void free_targets(mr_ghost_state *g) {
    mr_gl_target_free(&g->hid);
    mr_gl_target_free(&g->hid_shaded);
    mr_gl_target_free(&g->curv);
    GLuint t[] = {g->lab, g->tmp, g->gpos, g->gneg, g->sal_o, g->sal_g0, g->sal_final, g->mask, g->key,
                  g->label[0], g->label[1], g->g0, g->c, g->gkc, g->dgk, g->oa, g->ga, g->in_o, g->in_d,
                  g->out_view, g->out_store};
    glDeleteTextures((GLsizei)(sizeof t / sizeof t[0]), t);
    g->lab = g->tmp = g->gpos = g->gneg = g->sal_o = g->sal_g0 = g->sal_final = g->mask = g->key = 0;
    g->label[0] = g->label[1] = g->g0 = g->c = g->gkc = g->dgk = g->oa = g->ga = g->in_o = g->in_d = 0;
    g->out_view = g->out_store = 0;
    g->w = g->h = 0;
    g->layers_valid = false;
}

static void mr_ghost_scene_changed(mr_renderer *r) {
    mr_ghost_state *g = r ? r->ghost : NULL;
    if (!g) return;
    mr_geometry_aux_free(&g->curv_aux);
    g->curv_built = false;
}

static void mr_ghost_free(mr_renderer *r) {
    mr_ghost_state *g = r->ghost;
    if (!g) return;
    mr_ghost_scene_changed(r);
    free_targets(g);
    GLuint progs[] = {g->prog_lab, g->prog_blur, g->prog_sal, g->prog_imp, g->prog_g0,
                      g->prog_ana, g->prog_label, g->prog_emph, g->prog_stats, g->prog_curv};
    for (size_t i = 0; i < sizeof progs / sizeof progs[0]; i++) glDeleteProgram(progs[i]);
    GLuint bufs[] = {g->ssbo_stats, g->ssbo_votes, g->ssbo_sums};
    glDeleteBuffers(3, bufs);
    free(g);
    r->ghost = NULL;
}

/* Programs are built on first use, so renderers that never ghost pay
 * nothing. */
static mr_ghost_state *state(mr_renderer *r, mr_error *err) {
    if (r->ghost) return r->ghost;
    mr_ghost_state *g = calloc(1, sizeof *g);
    if (!g) {
        mr_fail(err, MR_ERR_NOMEM, "out of memory");
        return NULL;
    }
    r->ghost = g;
    static const char *const lab[] = {"ghost_lab.comp.glsl", NULL}, *const blur[] = {"ghost_blur.comp.glsl", NULL},
                             *const sal[] = {"ghost_saliency.comp.glsl", NULL},
                             *const imp[] = {"ghost_importance.comp.glsl", NULL},
                             *const g0[] = {"ghost_g0.comp.glsl", NULL},
                             *const ana[] = {"ghost_analysis.comp.glsl", NULL},
                             *const label[] = {"ghost_label.comp.glsl", NULL},
                             *const emph[] = {"ghost_emphasis.comp.glsl", NULL},
                             *const stats[] = {"ghost_stats.comp.glsl", NULL},
                             *const curv[] = {"ghost_curv.vert.glsl", "ghost_curv.frag.glsl", NULL};
    if (!(g->prog_lab = mr_gl_program(lab, err)) || !(g->prog_blur = mr_gl_program(blur, err)) ||
        !(g->prog_sal = mr_gl_program(sal, err)) || !(g->prog_imp = mr_gl_program(imp, err)) ||
        !(g->prog_g0 = mr_gl_program(g0, err)) || !(g->prog_ana = mr_gl_program(ana, err)) ||
        !(g->prog_label = mr_gl_program(label, err)) || !(g->prog_emph = mr_gl_program(emph, err)) ||
        !(g->prog_stats = mr_gl_program(stats, err)) || !(g->prog_curv = mr_gl_program(curv, err))) {
        mr_ghost_free(r);
        return NULL;
    }
    glCreateBuffers(1, &g->ssbo_stats);
    glNamedBufferStorage(g->ssbo_stats, 2 * sizeof(GLuint), NULL, GL_DYNAMIC_STORAGE_BIT);
    glCreateBuffers(1, &g->ssbo_sums);
    glNamedBufferStorage(g->ssbo_sums, 6 * sizeof(GLuint), NULL, GL_DYNAMIC_STORAGE_BIT);
    return g;
}

static GLuint tex(GLenum fmt, int w, int h) { return mr_gl_make_tex(fmt, w, h, GL_NEAREST); }

static bool ensure_size(mr_ghost_state *g, int w, int h, mr_error *err) {
    if (g->w == w && g->h == h) return true;
    free_targets(g);
    static const GLenum gfmt[3] = {GL_SRGB8_ALPHA8, GL_RGBA16F, GL_RG32UI};
    static const GLenum cfmt[1] = {GL_SRGB8_ALPHA8};
    static const GLenum kfmt[1] = {GL_R32F};
    if (!mr_gl_target_make(&g->hid, w, h, gfmt, 3, true, err) || !mr_gl_target_make(&g->hid_shaded, w, h, cfmt, 1, false, err) ||
        !mr_gl_target_make(&g->curv, w, h, kfmt, 1, true, err))
        return false;
    /* Small images have fewer levels; the shader clamps to the last one. */
    g->lab_levels = 1;
    while (g->lab_levels < SAL_LEVELS && ((w >> g->lab_levels) > 0 || (h >> g->lab_levels) > 0)) g->lab_levels++;
    glCreateTextures(GL_TEXTURE_2D, 1, &g->lab);
    glTextureStorage2D(g->lab, g->lab_levels, GL_RGBA32F, w, h);
    /* Level n is sampled bilinearly inside the level (eq. 10's pyramid). */
    glTextureParameteri(g->lab, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
    glTextureParameteri(g->lab, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(g->lab, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(g->lab, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    g->tmp = tex(GL_RGBA32F, w, h);
    g->gpos = tex(GL_RGBA32F, w, h);
    g->gneg = tex(GL_RGBA32F, w, h);
    g->sal_o = tex(GL_R32F, w, h);
    g->sal_g0 = tex(GL_R32F, w, h);
    g->sal_final = tex(GL_R32F, w, h);
    g->mask = tex(GL_RGBA32F, w, h);
    g->key = tex(GL_R32UI, w, h);
    g->label[0] = tex(GL_R32UI, w, h);
    g->label[1] = tex(GL_R32UI, w, h);
    g->g0 = tex(GL_RGBA32F, w, h);
    g->c = tex(GL_RGBA32F, w, h);
    g->gkc = tex(GL_RGBA32F, w, h);
    g->dgk = tex(GL_RGBA32F, w, h);
    g->oa = tex(GL_RGBA32F, w, h);
    g->ga = tex(GL_RGBA32F, w, h);
    g->in_o = tex(GL_RGBA32F, w, h);
    g->in_d = tex(GL_RGBA32F, w, h);
    g->out_store = tex(GL_RGBA8, w, h);
    glGenTextures(1, &g->out_view);
    glTextureView(g->out_view, GL_TEXTURE_2D, g->out_store, GL_SRGB8_ALPHA8, 0, 1, 0, 1);
    glTextureParameteri(g->out_view, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(g->out_view, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    g->w = w;
    g->h = h;
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) return mr_fail(err, MR_ERR_GL, "GL error 0x%x allocating the ghosting targets", e);
    return true;
}

static bool ensure_votes(mr_ghost_state *g, size_t n) {
    if (g->votes_cap >= n) return true;
    glDeleteBuffers(1, &g->ssbo_votes);
    glCreateBuffers(1, &g->ssbo_votes);
    glNamedBufferStorage(g->ssbo_votes, (GLsizeiptr)(n * sizeof(GLint)), NULL, GL_DYNAMIC_STORAGE_BIT);
    g->votes_cap = n;
    return true;
}

static void dispatch(int w, int h) {
    glDispatchCompute((GLuint)(w + 7) / 8, (GLuint)(h + 7) / 8, 1);
    /* Every stage reads what the previous one wrote, through samplers,
     * images or buffers. */
    glMemoryBarrier(GL_ALL_BARRIER_BITS);
}

/* --------------------------------------------------------------- stages */

/* src (linear RGB, sampled) -> dst (rgba32f), forward or inverse. */
static void lab_convert(mr_ghost_state *g, GLuint src, GLuint dst, bool inverse) {
    glUseProgram(g->prog_lab);
    glUniform1i(MR_LOC_LAB_INVERSE, inverse ? 1 : 0);
    glBindTextureUnit(MR_TEX_LAB_SRC, src);
    glBindImageTexture(MR_IMG_LAB_DST, dst, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    dispatch(g->w, g->h);
}

static void blur_pass(mr_ghost_state *g, GLuint src, GLuint dst, int dx, int dy, float sigma, int radius) {
    glUseProgram(g->prog_blur);
    glUniform2i(MR_LOC_GBLUR_DIR, dx, dy);
    glUniform1f(MR_LOC_GBLUR_SIGMA, sigma);
    glUniform1i(MR_LOC_GBLUR_RADIUS, radius);
    glBindTextureUnit(MR_TEX_GBLUR_SRC, src);
    glBindImageTexture(MR_IMG_GBLUR_DST, dst, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    dispatch(g->w, g->h);
}

/* Separable Gaussian src -> dst through g->tmp (src may not be g->tmp). */
static void blur(mr_ghost_state *g, GLuint src, GLuint dst, float sigma, int radius) {
    if (radius < 1) radius = 1;
    blur_pass(g, src, g->tmp, 1, 0, sigma, radius);
    blur_pass(g, g->tmp, dst, 0, 1, sigma, radius);
}

static int radius_of(float sigma) { return (int)ceilf(3.0f * sigma); }

/* Saliency of a linear RGB texture into an R32F texture. */
static void saliency(mr_ghost_state *g, GLuint src, GLuint dst, mr_saliency_impl impl, mr_saliency_levels levels,
                     float gain) {
    bool printed = levels == MR_SAL_LEVELS_PRINTED;
    lab_convert(g, src, g->lab, false);
    glUseProgram(g->prog_sal);
    if (impl == MR_SALIENCY_GAUSS) {
        blur(g, g->lab, g->gpos, SAL_SIGMA_POS, radius_of(SAL_SIGMA_POS));
        if (printed) blur(g, g->lab, g->gneg, SAL_SIGMA_NEG_PRINTED, radius_of(SAL_SIGMA_NEG_PRINTED));
        else blur(g, g->lab, g->gneg, SAL_SIGMA_NEG, SAL_RADIUS_NEG);
        glUseProgram(g->prog_sal);
        glUniform1i(MR_LOC_SAL_IMPL, 1);
        glBindTextureUnit(MR_TEX_SAL_PYR, g->gpos);
        glBindTextureUnit(MR_TEX_SAL_SURROUND, g->gneg);
    } else {
        /* The built-in (box) mip-map generation is the pyramid of eq. 10. */
        glGenerateTextureMipmap(g->lab);
        glUseProgram(g->prog_sal);
        glUniform1i(MR_LOC_SAL_IMPL, 0);
        glBindTextureUnit(MR_TEX_SAL_PYR, g->lab);
        glBindTextureUnit(MR_TEX_SAL_SURROUND, g->lab);
    }
    glUniform1f(MR_LOC_SAL_GAIN, gain);
    glUniform1i(MR_LOC_SAL_MAX_LEVEL, g->lab_levels - 1);
    glUniform1i(MR_LOC_SAL_PRINTED, printed ? 1 : 0);
    glBindImageTexture(MR_IMG_SAL_DST, dst, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    dispatch(g->w, g->h);
}

/* G0 from o/d textures (linear when sampled) and g->mask; writes g->g0 and
 * the finished image. Reads mean(IM) from ssbo_stats (mode alpha). */
static void stage_g0(mr_ghost_state *g, GLuint o, GLuint d, const mr_ghost_params *gp) {
    glUseProgram(g->prog_g0);
    glUniform1i(MR_LOC_G0_MODE, (int)gp->mode);
    glUniform1f(MR_LOC_G0_T, gp->opacity);
    glBindTextureUnit(MR_TEX_G0_O, o);
    glBindTextureUnit(MR_TEX_G0_D, d);
    glBindTextureUnit(MR_TEX_G0_MASK, g->mask);
    glBindImageTexture(MR_IMG_G0_G0, g->g0, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(MR_IMG_G0_OUT, g->out_store, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA8);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, MR_SSBO_G0_STATS, g->ssbo_stats);
    dispatch(g->w, g->h);
}

static void stage_analysis(mr_ghost_state *g, const mr_ghost_params *gp) {
    saliency(g, g->g0, g->sal_g0, gp->saliency, gp->saliency_levels, gp->saliency_gain);
    glUseProgram(g->prog_ana);
    glUniform1f(MR_LOC_ANA_TC_MIN, gp->tc_minimal);
    glUniform1f(MR_LOC_ANA_GAMMA, gp->gamma);
    glUniform1f(MR_LOC_ANA_TC_SIL, gp->tc_silhouette);
    glBindTextureUnit(MR_TEX_ANA_MASK, g->mask);
    glBindTextureUnit(MR_TEX_ANA_SAL, g->sal_g0);
    glBindTextureUnit(MR_TEX_ANA_G0, g->g0);
    glBindImageTexture(MR_IMG_ANA_C, g->c, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    dispatch(g->w, g->h);
}

/* key_base: the first vote slot of the video's connected regions (object
 * ids of the model lie below it). */
static void stage_emphasis(mr_ghost_state *g, GLuint o, GLuint d, const mr_ghost_params *gp, uint32_t key_base,
                           bool regions) {
    blur(g, g->c, g->gkc, gp->sigma_c, radius_of(gp->sigma_c));
    blur(g, d, g->dgk, gp->sigma_d, radius_of(gp->sigma_d));
    /* Connected regions of the video occluder: only where some occluder
     * has no object id (video without a model in front); otherwise the
     * single init step writes zeros. */
    glUseProgram(g->prog_label);
    glBindTextureUnit(MR_TEX_LABEL_MASK, g->mask);
    glBindTextureUnit(MR_TEX_LABEL_KEY, g->key);
    int cur = 0;
    glUniform1i(MR_LOC_LABEL_INIT, 1);
    glBindTextureUnit(MR_TEX_LABEL_SRC, g->label[1]);
    glBindImageTexture(MR_IMG_LABEL_DST, g->label[0], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
    dispatch(g->w, g->h);
    glUniform1i(MR_LOC_LABEL_INIT, 0);
    for (int i = 0; regions && i < LABEL_STEPS; i++) {
        glBindTextureUnit(MR_TEX_LABEL_SRC, g->label[cur]);
        glBindImageTexture(MR_IMG_LABEL_DST, g->label[1 - cur], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
        dispatch(g->w, g->h);
        cur = 1 - cur;
    }
    size_t nvotes = (size_t)key_base + (size_t)g->w * g->h + 2;
    ensure_votes(g, nvotes);
    static const GLint zero = 0;
    glClearNamedBufferSubData(g->ssbo_votes, GL_R32I, 0, (GLsizeiptr)(nvotes * sizeof(GLint)), GL_RED_INTEGER, GL_INT, &zero);
    glUseProgram(g->prog_emph);
    glUniform1ui(MR_LOC_EMPH_KEY_BASE, key_base);
    glUniform1f(MR_LOC_EMPH_GAIN, gp->emphasis_gain);
    glBindTextureUnit(MR_TEX_EMPH_O, o);
    glBindTextureUnit(MR_TEX_EMPH_D, d);
    glBindTextureUnit(MR_TEX_EMPH_DGK, g->dgk);
    glBindTextureUnit(MR_TEX_EMPH_GKC, g->gkc);
    glBindTextureUnit(MR_TEX_EMPH_MASK, g->mask);
    glBindTextureUnit(MR_TEX_EMPH_G0, g->g0);
    glBindTextureUnit(MR_TEX_EMPH_KEY, g->key);
    glBindTextureUnit(MR_TEX_EMPH_LABEL, g->label[cur]);
    glBindImageTexture(MR_IMG_EMPH_OUT, g->out_store, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA8);
    glBindImageTexture(MR_IMG_EMPH_OA, g->oa, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(MR_IMG_EMPH_GA, g->ga, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, MR_SSBO_EMPH_VOTES, g->ssbo_votes);
    glUniform1i(MR_LOC_EMPH_STAGE, 0);
    dispatch(g->w, g->h);
    glUniform1i(MR_LOC_EMPH_STAGE, 1);
    dispatch(g->w, g->h);
}

/* How far the adaptive stage reached its own target, and the lightness
 * change of the finished ghosted view (legibility proper is measured by
 * mr_eval_ghost_legibility from D alone). */
static void stage_stats(mr_ghost_state *g, GLuint o, bool adaptive, const mr_ghost_params *gp, mr_ghost_stats *st) {
    /* One yardstick for every configuration: the measure always uses the
     * two-Gaussian saliency, whichever pyramid the analysis used. */
    saliency(g, adaptive ? g->ga : g->g0, g->sal_final, MR_SALIENCY_GAUSS, gp->saliency_levels, gp->saliency_gain);
    static const GLuint zero = 0;
    glClearNamedBufferData(g->ssbo_sums, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    glUseProgram(g->prog_stats);
    glUniform1f(MR_LOC_STATS_TC_MIN, gp->tc_minimal);
    glUniform1f(MR_LOC_STATS_GAMMA, gp->gamma);
    glUniform1f(MR_LOC_STATS_TC_SIL, gp->tc_silhouette);
    glBindTextureUnit(MR_TEX_STATS_MASK, g->mask);
    glBindTextureUnit(MR_TEX_STATS_SAL, g->sal_final);
    glBindTextureUnit(MR_TEX_STATS_O, o);
    glBindTextureUnit(MR_TEX_STATS_OA, adaptive ? g->oa : o);
    glBindTextureUnit(MR_TEX_STATS_C, g->c);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, MR_SSBO_STATS_SUMS, g->ssbo_sums);
    dispatch(g->w, g->h);
    GLuint s[6];
    glGetNamedBufferSubData(g->ssbo_sums, 0, sizeof s, s);
    double npx = (double)g->w * g->h, reg = s[0] > 0 ? (double)s[0] : 1.0;
    st->valid = true;
    st->region_fraction = s[0] / npx;
    st->mean_importance = s[3] / 256.0 / reg;
    st->target_reached = s[1] > 0 ? (double)s[2] / s[1] : NAN; /* no important pixel: undefined */
    st->mean_abs_dL = s[4] / 16.0 / reg;
    st->mean_contrast_missing = adaptive ? s[5] / 256.0 / reg : 0.0;
}

/* --------------------------------------------------------------- frame */

/* Is any hidden-layer mesh's box (conservatively) inside the view? */
static bool hidden_in_view(const frame *f) {
    const mr_scene *s = f->r->scene;
    if (!s) return false;
    const mr_camera *c = &f->cam;
    for (int32_t ni = 0; ni < s->node_count; ni++) {
        const mr_node *n = &s->nodes[ni];
        if (n->layer != MR_LAYER_HIDDEN || n->mesh_first < 0) continue;
        mr_dmat4 cam_from_node = mr_m4_mul(&f->cam_from_world, &n->world);
        for (int32_t k = 0; k < n->mesh_count && n->mesh_first + k < s->mesh_count; k++) {
            const mr_mesh *m = &s->meshes[n->mesh_first + k];
            double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
            int in_front = 0, behind = 0;
            for (int corner = 0; corner < 8; corner++) {
                mr_dvec3 p = mr_v3(m->origin[0] + (corner & 1 ? m->bounds_max[0] : m->bounds_min[0]),
                                   m->origin[1] + (corner & 2 ? m->bounds_max[1] : m->bounds_min[1]),
                                   m->origin[2] + (corner & 4 ? m->bounds_max[2] : m->bounds_min[2]));
                mr_dvec3 q = mr_m4_point(&cam_from_node, p);
                if (q.z <= f->near_plane) { behind++; continue; }
                in_front++;
                double u = c->fx * q.x / q.z + c->cx, v = c->fy * q.y / q.z + c->cy;
                umin = fmin(umin, u); umax = fmax(umax, u); vmin = fmin(vmin, v); vmax = fmax(vmax, v);
            }
            if (!in_front) continue;
            /* A box crossing the near plane may cover the whole view. */
            if (behind) return true;
            if (umax >= -0.5 && umin <= c->width - 0.5 && vmax >= -0.5 && vmin <= c->height - 0.5) return true;
        }
    }
    return false;
}

static bool finite_in(float v, float lo, float hi) { return v >= lo && v <= hi; }

static bool ghost_check(const mr_frame_params *p, mr_error *err) {
    const mr_ghost_params *gp = &p->ghost;
    if (gp->mode == MR_GHOST_OFF) return true;
    if ((unsigned)gp->mode > MR_GHOST_ADAPTIVE || (unsigned)gp->importance > MR_GHOST_IMP_SALIENCY ||
        (unsigned)gp->saliency > MR_SALIENCY_GAUSS || (unsigned)gp->saliency_levels > MR_SAL_LEVELS_PRINTED)
        return mr_fail(err, MR_ERR_INVALID, "ghost: unknown mode, importance source or saliency implementation");
    if (!finite_in(gp->opacity, 0, 1)) return mr_fail(err, MR_ERR_INVALID, "ghost: opacity must be in [0,1]");
    if (!finite_in(gp->curv_scale, 0, 1e6f) || !finite_in(gp->curv_bias, -1e6f, 1e6f) ||
        !finite_in(gp->saliency_gain, 0, 1e6f) || !finite_in(gp->tc_minimal, 0, 1e6f) || !finite_in(gp->gamma, 0, 1e6f) ||
        !finite_in(gp->tc_silhouette, 0, 1e6f) || !finite_in(gp->emphasis_gain, 0, 1e6f))
        return mr_fail(err, MR_ERR_INVALID, "ghost: parameters must be finite and not negative");
    if (!finite_in(gp->sigma_c, 0.1f, 64) || !finite_in(gp->sigma_d, 0.1f, 64))
        return mr_fail(err, MR_ERR_INVALID, "ghost: sigma_c and sigma_d must be in [0.1, 64] pixels");
    return true;
}

/* This frame ghosts: a mode other than off, the hidden layer drawn, and
 * hidden structure in view. */
static bool ghosting(const frame *f) {
    const mr_frame_params *p = f->p;
    return p->ghost.mode != MR_GHOST_OFF && !p->hide_hidden_layer && hidden_in_view(f);
}

static bool mr_pass_need_ghost(const frame *f) { return ghosting(f); }
static bool mr_pass_need_ghost_curvature(const frame *f) {
    return ghosting(f) && f->p->ghost.importance != MR_GHOST_IMP_SALIENCY;
}
static bool mr_pass_need_ghost_adaptive(const frame *f) { return ghosting(f) && f->p->ghost.mode == MR_GHOST_ADAPTIVE; }

/* Programs (first use), targets (size changes) and D's AO state. */
static bool mr_pass_prepare_ghost(frame *f, mr_error *err) {
    mr_ghost_state *g = state(f->r, err);
    return g && ensure_size(g, f->r->w, f->r->h, err) && mr_ao_hidden_prepare(f, err);
}

static void mr_pass_ghost_hidden(frame *f) {
    mr_renderer *r = f->r;
    mr_ghost_state *g = r->ghost;
    mr_gbuffer_begin(f, &g->hid);
    mr_geo_view v = mr_frame_view(f, mr_gbuffer_program(f), 1u << MR_LAYER_HIDDEN);
    mr_geometry_draw(r, &v, f->out);
    glDisable(GL_DEPTH_TEST);
    frame_put(f, RES_HIDDEN_DEPTH, g->hid.depth);
    frame_put(f, RES_HIDDEN_NORMAL, g->hid.color[MR_OUT_GBUFFER_NORMAL]);
    frame_put(f, RES_HIDDEN_IDS, g->hid.color[MR_OUT_GBUFFER_IDS]);
    /* D is shaded like the model, with its own AO when AO is on. */
    GLuint ao = mr_ao_hidden_run(f, g->hid.depth, g->hid.color[MR_OUT_GBUFFER_NORMAL]);
    mr_shade_draw(f, g->hid.color[MR_OUT_GBUFFER_ALBEDO], g->hid.color[MR_OUT_GBUFFER_NORMAL], ao, &g->hid_shaded);
    frame_put(f, RES_HIDDEN_SHADED, g->hid_shaded.color[0]);
}

/* Per-vertex curvature as attribute 3 of the curvature program, laid out
 * like the shared geometry; computed once per scene. */
static void ensure_curvature(mr_renderer *r, mr_ghost_state *g) {
    const mr_scene *s = r->scene;
    if (!s || g->curv_built) return;
    g->curv_built = true;
    float **k = calloc((size_t)s->mesh_count + 1, sizeof *k);
    if (!k) return;
    for (int32_t i = 0; i < s->mesh_count; i++) {
        const mr_mesh *m = &s->meshes[i];
        k[i] = malloc((size_t)(m->vertex_count ? m->vertex_count : 1) * sizeof **k);
        if (k[i]) mr_mesh_curvature(m, k[i]);
    }
    mr_geometry_aux_create(r, k, 1, MR_ATTR_CURVATURE, &g->curv_aux);
    for (int32_t i = 0; i < s->mesh_count; i++) free(k[i]);
    free(k);
}

static void mr_pass_ghost_curvature(frame *f) {
    mr_renderer *r = f->r;
    mr_ghost_state *g = r->ghost;
    ensure_curvature(r, g);
    glBindFramebuffer(GL_FRAMEBUFFER, g->curv.fbo);
    glViewport(0, 0, r->w, r->h);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDepthMask(GL_TRUE);
    static const float zero4[4] = {0, 0, 0, 0};
    static const float depth0 = 0.0f;
    glClearNamedFramebufferfv(g->curv.fbo, GL_COLOR, 0, zero4);
    glClearNamedFramebufferfv(g->curv.fbo, GL_DEPTH, 0, &depth0);
    mr_geo_view v = mr_frame_view(f, g->prog_curv, 1u << MR_LAYER_VISIBLE);
    mr_geometry_aux_draw(r, &v, &g->curv_aux);
    glDisable(GL_DEPTH_TEST);
    frame_put(f, RES_CURVATURE, g->curv.color[0]);
}

static bool needs_saliency_of_o(const frame *f) {
    mr_ghost_importance im = f->p->ghost.importance;
    return im == MR_GHOST_IMP_SALIENCY || (im == MR_GHOST_IMP_AUTO && f->p->video != NULL);
}

static void mr_pass_ghost_importance(frame *f) {
    mr_renderer *r = f->r;
    mr_ghost_state *g = r->ghost;
    const mr_ghost_params *gp = &f->p->ghost;
    g->o_tex = frame_get(f, RES_IMAGE);
    bool sal = needs_saliency_of_o(f);
    if (sal) saliency(g, g->o_tex, g->sal_o, gp->saliency, gp->saliency_levels, gp->saliency_gain);
    static const GLuint zero = 0;
    glClearNamedBufferData(g->ssbo_stats, GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    glUseProgram(g->prog_imp);
    glUniform1i(MR_LOC_IMP_VIDEO, f->p->video != NULL);
    glUniform1i(MR_LOC_IMP_IMPORTANCE, (int)gp->importance);
    glUniform1f(MR_LOC_IMP_SCALE, gp->curv_scale);
    glUniform1f(MR_LOC_IMP_BIAS, gp->curv_bias);
    glUniform1f(MR_LOC_IMP_NEAR, (float)f->near_plane);
    glUniform1f(MR_LOC_IMP_FX, (float)f->cam.fx);
    glUniform1i(MR_LOC_IMP_HAVE_SALIENCY, sal);
    glBindTextureUnit(MR_TEX_IMP_DEPTH, frame_get(f, RES_DEPTH));
    glBindTextureUnit(MR_TEX_IMP_NORMAL, frame_get(f, RES_NORMAL));
    glBindTextureUnit(MR_TEX_IMP_IDS, frame_get(f, RES_IDS));
    glBindTextureUnit(MR_TEX_IMP_HIDDEN_DEPTH, frame_get(f, RES_HIDDEN_DEPTH));
    glBindTextureUnit(MR_TEX_IMP_HIDDEN_IDS, frame_get(f, RES_HIDDEN_IDS));
    glBindTextureUnit(MR_TEX_IMP_CURVATURE, frame_get(f, RES_CURVATURE));
    glBindTextureUnit(MR_TEX_IMP_SAL, g->sal_o);
    glBindImageTexture(MR_IMG_IMP_MASK, g->mask, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(MR_IMG_IMP_KEY, g->key, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, MR_SSBO_IMP_STATS, g->ssbo_stats);
    dispatch(g->w, g->h);
}

static void mr_pass_ghost_g0(frame *f) {
    mr_ghost_state *g = f->r->ghost;
    stage_g0(g, g->o_tex, frame_get(f, RES_HIDDEN_SHADED), &f->p->ghost);
    g->layers_valid = true;
    frame_put(f, RES_IMAGE, g->out_view);
    if (f->p->ghost.stats && f->p->ghost.mode != MR_GHOST_ADAPTIVE) {
        /* C is not computed outside adaptive mode: report zero missing. */
        static const float zero4[4] = {0, 0, 0, 0};
        glClearTexImage(g->c, 0, GL_RGBA, GL_FLOAT, zero4);
        stage_stats(g, g->o_tex, false, &f->p->ghost, &f->out->ghost);
    }
}

static void mr_pass_ghost_analysis(frame *f) { stage_analysis(f->r->ghost, &f->p->ghost); }

static void mr_pass_ghost_emphasis(frame *f) {
    mr_ghost_state *g = f->r->ghost;
    uint32_t key_base = (uint32_t)(f->r->scene ? f->r->scene->node_count : 0) + 1;
    stage_emphasis(g, g->o_tex, frame_get(f, RES_HIDDEN_SHADED), &f->p->ghost, key_base, f->p->video != NULL);
    frame_put(f, RES_IMAGE, g->out_view);
    if (f->p->ghost.stats) stage_stats(g, g->o_tex, true, &f->p->ghost, &f->out->ghost);
}

/* ---------------------------------------------------------- image level */

static bool check_img(const mr_image *im, int w, int h, int ch, const char *what, mr_error *err) {
    if (!im || !im->data || im->type != MR_PIX_F32 || im->channels != ch || im->width != w || im->height != h)
        return mr_fail(err, MR_ERR_INVALID, "ghost: %s must be a %dx%d F32 image with %d channel(s)", what, w, h, ch);
    return true;
}

static bool begin_images(mr_renderer *r, int w, int h, mr_ghost_state **gs, mr_error *err) {
    if (w < 1 || h < 1 || w > 16384 || h > 16384) return mr_fail(err, MR_ERR_INVALID, "ghost: bad image size %dx%d", w, h);
    mr_ghost_state *g = state(r, err);
    if (!g || !ensure_size(g, w, h, err)) return false;
    *gs = g;
    return true;
}

/* Uploads a 1- or 3-channel F32 image into an rgba32f texture. */
static void upload_rgba(GLuint t, const mr_image *im) {
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(t, 0, 0, 0, im->width, im->height, im->channels == 1 ? GL_RED : GL_RGB, GL_FLOAT, im->data);
}

static bool read_tex(GLuint t, int w, int h, int ch, mr_image *out, mr_error *err) {
    if (!mr_image_alloc(out, w, h, ch, MR_PIX_F32, err)) return false;
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTextureImage(t, 0, ch == 1 ? GL_RED : GL_RGB, GL_FLOAT, (GLsizei)mr_image_bytes(out), out->data);
    return true;
}

static bool finish(mr_error *err) {
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) return mr_fail(err, MR_ERR_GL, "GL error 0x%x in the ghosting stages", e);
    return true;
}

bool mr_ghost_lab(mr_renderer *r, const mr_image *in, bool inverse, mr_image *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    mr_ghost_state *g;
    if (!in) return mr_fail(err, MR_ERR_INVALID, "ghost: no image");
    if (!begin_images(r, in->width, in->height, &g, err)) return false;
    if (!check_img(in, g->w, g->h, 3, "the input", err)) return false;
    upload_rgba(g->in_o, in);
    lab_convert(g, g->in_o, g->g0, inverse);
    if (!read_tex(g->g0, g->w, g->h, 3, out, err)) return false;
    if (!finish(err)) {
        mr_image_free(out);
        return false;
    }
    return true;
}

bool mr_ghost_saliency(mr_renderer *r, const mr_image *rgb, mr_saliency_impl impl, mr_saliency_levels levels,
                       float gain, mr_image *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    mr_ghost_state *g;
    if (!rgb) return mr_fail(err, MR_ERR_INVALID, "ghost: no image");
    if (!begin_images(r, rgb->width, rgb->height, &g, err)) return false;
    if (!check_img(rgb, g->w, g->h, 3, "the input", err)) return false;
    upload_rgba(g->in_o, rgb);
    if ((unsigned)levels > MR_SAL_LEVELS_PRINTED) return mr_fail(err, MR_ERR_INVALID, "ghost: unknown saliency levels");
    saliency(g, g->in_o, g->sal_o, impl, levels, gain);
    if (!read_tex(g->sal_o, g->w, g->h, 1, out, err)) return false;
    if (!finish(err)) {
        mr_image_free(out);
        return false;
    }
    return true;
}

void mr_ghost_output_free(mr_ghost_output *o) {
    if (!o) return;
    mr_image_free(&o->g0);
    mr_image_free(&o->ga);
    mr_image_free(&o->occluder_a);
    mr_image_free(&o->contrast);
    mr_image_free(&o->alpha);
}

bool mr_ghost_compose(mr_renderer *r, const mr_ghost_images *in, const mr_ghost_params *params, mr_ghost_output *out,
                      mr_error *err) {
    memset(out, 0, sizeof *out);
    if (!in || !in->occluder) return mr_fail(err, MR_ERR_INVALID, "ghost: no occluder image");
    int w = in->occluder->width, h = in->occluder->height;
    mr_ghost_state *g;
    if (!begin_images(r, w, h, &g, err)) return false;
    if (!check_img(in->occluder, w, h, 3, "O", err) || !check_img(in->occludee, w, h, 3, "D", err) ||
        !check_img(in->importance, w, h, 1, "IM", err) || !check_img(in->region, w, h, 1, "the region", err) ||
        (in->silhouette && !check_img(in->silhouette, w, h, 1, "the silhouette", err)) ||
        (in->objects && !check_img(in->objects, w, h, 1, "the object ids", err)))
        return false;
    mr_ghost_params gp = MR_GHOST_DEFAULTS;
    if (params) gp = *params;
    if (gp.mode == MR_GHOST_OFF) gp.mode = MR_GHOST_ADAPTIVE;
    size_t n = (size_t)w * h;
    float *mask = malloc(n * 4 * sizeof *mask);
    GLuint *keys = malloc(n * sizeof *keys);
    if (!mask || !keys) {
        free(mask);
        free(keys);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    const float *im = in->importance->data, *reg = in->region->data;
    const float *sil = in->silhouette ? in->silhouette->data : NULL, *obj = in->objects ? in->objects->data : NULL;
    uint32_t key_base = 1;
    GLuint stats[2] = {0, 0};
    for (size_t i = 0; i < n; i++) {
        float v = im[i] > 0 ? (im[i] < 1 ? im[i] : 1) : 0;
        bool rg = reg[i] > 0.5f;
        mask[i * 4 + 0] = v;
        mask[i * 4 + 1] = rg ? 1.0f : 0.0f;
        mask[i * 4 + 2] = rg && sil && sil[i] > 0.5f ? 1.0f : 0.0f;
        mask[i * 4 + 3] = rg ? 1.0f : 0.0f;
        keys[i] = obj && obj[i] >= 1 && obj[i] < 1e9f ? (GLuint)obj[i] : 0;
        if (keys[i] + 1 > key_base) key_base = keys[i] + 1;
        if (rg) {
            stats[0] += (GLuint)(v * 256.0f + 0.5f);
            stats[1]++;
        }
    }
    glTextureSubImage2D(g->mask, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, mask);
    glTextureSubImage2D(g->key, 0, 0, 0, w, h, GL_RED_INTEGER, GL_UNSIGNED_INT, keys);
    free(mask);
    free(keys);
    glNamedBufferSubData(g->ssbo_stats, 0, sizeof stats, stats);
    g->layers_valid = false; /* the mask is the caller's now */
    upload_rgba(g->in_o, in->occluder);
    upload_rgba(g->in_d, in->occludee);
    stage_g0(g, g->in_o, g->in_d, &gp);
    stage_analysis(g, &gp);
    stage_emphasis(g, g->in_o, g->in_d, &gp, key_base, in->objects == NULL);
    mr_image rgba = {0};
    bool ok = read_tex(g->g0, w, h, 3, &out->g0, err) && read_tex(g->ga, w, h, 3, &out->ga, err) &&
              read_tex(g->oa, w, h, 3, &out->occluder_a, err) && read_tex(g->c, w, h, 1, &out->contrast, err) &&
              mr_image_alloc(&rgba, w, h, 4, MR_PIX_F32, err) && mr_image_alloc(&out->alpha, w, h, 1, MR_PIX_F32, err);
    if (ok) {
        glGetTextureImage(g->g0, 0, GL_RGBA, GL_FLOAT, (GLsizei)mr_image_bytes(&rgba), rgba.data);
        const float *src = rgba.data;
        float *a = out->alpha.data;
        for (size_t i = 0; i < n; i++) a[i] = src[i * 4 + 3];
    }
    mr_image_free(&rgba);
    ok = ok && finish(err);
    if (!ok) mr_ghost_output_free(out);
    return ok;
}

bool mr_ghost_read_layers(mr_renderer *r, mr_image *occluder, mr_image *hidden, mr_image *region, mr_error *err) {
    memset(occluder, 0, sizeof *occluder);
    memset(hidden, 0, sizeof *hidden);
    memset(region, 0, sizeof *region);
    mr_ghost_state *g = r ? r->ghost : NULL;
    if (!g || !g->layers_valid || !g->o_tex) return mr_fail(err, MR_ERR_INVALID, "ghost: no ghosted frame to read");
    int w = g->w, h = g->h;
    mr_image mask = {0};
    bool ok = mr_image_alloc(occluder, w, h, 3, MR_PIX_U8, err) && mr_image_alloc(hidden, w, h, 3, MR_PIX_U8, err) &&
              mr_image_alloc(region, w, h, 1, MR_PIX_F32, err) && mr_image_alloc(&mask, w, h, 4, MR_PIX_F32, err);
    if (ok) {
        /* The sRGB textures' bytes as stored: sRGB-encoded, like the frame's
         * colour; rows already top first (the projection flips y, OpenCV's
         * camera frame). */
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glGetTextureImage(g->o_tex, 0, GL_RGB, GL_UNSIGNED_BYTE, (GLsizei)mr_image_bytes(occluder), occluder->data);
        glGetTextureImage(g->hid_shaded.color[0], 0, GL_RGB, GL_UNSIGNED_BYTE, (GLsizei)mr_image_bytes(hidden), hidden->data);
        glGetTextureImage(g->mask, 0, GL_RGBA, GL_FLOAT, (GLsizei)mr_image_bytes(&mask), mask.data);
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        const float *m = mask.data;
        float *rg = region->data;
        for (size_t i = 0; i < (size_t)w * h; i++) rg[i] = m[i * 4 + 1] > 0.5f ? 1.0f : 0.0f;
        ok = finish(err);
    }
    mr_image_free(&mask);
    if (!ok) {
        mr_image_free(occluder);
        mr_image_free(hidden);
        mr_image_free(region);
    }
    return ok;
}

/* The rows of the registry (k_passes in renderer.c). Programs and targets
 * are made by ghost_hidden's prepare for all of them. */
#define GHOST_DESTROY .scene_changed = mr_ghost_scene_changed, .destroy = mr_ghost_free
const pass_desc mr_pass_desc_ghost_hidden = {
    .name = "ghost_hidden", .needed = mr_pass_need_ghost, .prepare = mr_pass_prepare_ghost,
    .run = mr_pass_ghost_hidden, GHOST_DESTROY, .check = ghost_check,
    .writes = RES(RES_HIDDEN_DEPTH) | RES(RES_HIDDEN_NORMAL) | RES(RES_HIDDEN_IDS) | RES(RES_HIDDEN_SHADED)};
const pass_desc mr_pass_desc_ghost_curvature = {
    .name = "ghost_curvature", .needed = mr_pass_need_ghost_curvature, .run = mr_pass_ghost_curvature, GHOST_DESTROY,
    .writes = RES(RES_CURVATURE)};
const pass_desc mr_pass_desc_ghost_importance = {
    .name = "ghost_importance", .needed = mr_pass_need_ghost, .run = mr_pass_ghost_importance, GHOST_DESTROY,
    .reads = RES(RES_IMAGE) | RES(RES_DEPTH) | RES(RES_NORMAL) | RES(RES_IDS) | RES(RES_HIDDEN_DEPTH) |
             RES(RES_HIDDEN_IDS),
    .uses = RES(RES_CURVATURE), .writes = RES(RES_GHOST_MASK)};
const pass_desc mr_pass_desc_ghost_g0 = {
    .name = "ghost_g0", .needed = mr_pass_need_ghost, .run = mr_pass_ghost_g0, GHOST_DESTROY,
    .reads = RES(RES_IMAGE) | RES(RES_HIDDEN_SHADED) | RES(RES_GHOST_MASK), .writes = RES(RES_IMAGE)};
const pass_desc mr_pass_desc_ghost_analysis = {
    .name = "ghost_analysis", .needed = mr_pass_need_ghost_adaptive, .run = mr_pass_ghost_analysis, GHOST_DESTROY,
    .reads = RES(RES_GHOST_MASK)};
const pass_desc mr_pass_desc_ghost_emphasis = {
    .name = "ghost_emphasis", .needed = mr_pass_need_ghost_adaptive, .run = mr_pass_ghost_emphasis, GHOST_DESTROY,
    .reads = RES(RES_HIDDEN_SHADED) | RES(RES_GHOST_MASK), .writes = RES(RES_IMAGE)};
