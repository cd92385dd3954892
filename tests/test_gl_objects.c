/* No GL object outlives the renderer. A renderer renders frames at 100
 * different tiny sizes with every pass that allocates switched on (AO with
 * corner masking, half resolution and the positions path, ghosting with
 * its hidden-layer AO, the video overlay, timing queries, a textured mesh,
 * LOD re-uploads and a scene change), so every target is freed and made
 * again on each resize; then it is destroyed. In a GL context that outlives
 * the renderer, the names of every kind of GL object still valid are
 * counted (glIsTexture(i) etc. over 1..65536) before the renderer is created
 * and after it is destroyed: the counts must be equal. Skips (77) without
 * an EGL device. */
#include "mr_render.h"
#include "mr_test.h"
#include "mr_test_scene.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <stdlib.h>
#include <string.h>

/* Mesa hands out fresh names rather than reusing freed ones at once, so
 * 100 resizes reach names in the thousands; the test checks that the range
 * covers the newest name. */
#define NAME_RANGE 65536

typedef struct gl_kind {
    const char *name;
    GLboolean (*is)(GLuint);
} gl_kind;

/* A program or shader whose deletion was asked for stays a valid name while
 * something still uses it; Mesa (llvmpipe) keeps one compute program of the
 * ghosting alive that way after glUseProgram(0), for reasons of its own. Those
 * the renderer did delete do not count: a program it forgot to delete does. */
static GLboolean is_live_program(GLuint n) {
    if (!glIsProgram(n)) return GL_FALSE;
    GLint flagged = GL_FALSE;
    glGetProgramiv(n, GL_DELETE_STATUS, &flagged);
    return flagged ? GL_FALSE : GL_TRUE;
}
static GLboolean is_live_shader(GLuint n) {
    if (!glIsShader(n)) return GL_FALSE;
    GLint flagged = GL_FALSE;
    glGetShaderiv(n, GL_DELETE_STATUS, &flagged);
    return flagged ? GL_FALSE : GL_TRUE;
}

/* Programs and shaders share one name space, the rest have their own. */
static const gl_kind k_kinds[] = {
    {"texture", glIsTexture},           {"buffer", glIsBuffer},         {"framebuffer", glIsFramebuffer},
    {"renderbuffer", glIsRenderbuffer}, {"program", is_live_program},   {"shader", is_live_shader},
    {"vertex array", glIsVertexArray},  {"query", glIsQuery},           {"sampler", glIsSampler},
};
#define KIND_COUNT (int)(sizeof k_kinds / sizeof k_kinds[0])

static void count_objects(int out[KIND_COUNT]) {
    for (int k = 0; k < KIND_COUNT; k++) {
        out[k] = 0;
        for (GLuint i = 1; i <= NAME_RANGE; i++) out[k] += k_kinds[k].is(i) ? 1 : 0;
    }
}

static void build_scene(mr_scene *s) {
    mr_material wall = {"wall", {0.6f, 0.5f, 0.4f, 1}, -1, false};
    mr_material pipe = {"pipe", {0.2f, 0.4f, 0.8f, 1}, -1, false};
    int32_t mw = mr_scene_add_material(s, &wall), mp = mr_scene_add_material(s, &pipe);
    /* A 4x4 checker texture on a quad, so the textured draw group and the
     * scene's texture upload are exercised too. */
    mr_texture t;
    memset(&t, 0, sizeof t);
    mr_image_alloc(&t.image, 4, 4, 4, MR_PIX_U8, NULL);
    unsigned char *px = t.image.data;
    for (int i = 0; i < 16; i++) {
        unsigned char v = ((i + i / 4) & 1) ? 230 : 40;
        px[4 * i] = px[4 * i + 1] = px[4 * i + 2] = v;
        px[4 * i + 3] = 255;
    }
    int32_t ti = mr_scene_add_texture(s, &t);
    mr_material tex = {"plate", {1, 1, 1, 1}, ti, false};
    int32_t mt = mr_scene_add_material(s, &tex);
    /* Camera axes: z forward. A wall with a box on it (corners for the
     * mask), a hidden pipe behind the wall (ghosting), a textured plate. */
    mr_test_add_node(s, "Wall", mr_m4_translate(0, 0, 5), mr_test_add_box(s, 6, 6, 0.2, mw), MR_LAYER_VISIBLE);
    mr_test_add_node(s, "Box", mr_m4_translate(0.8, 0.5, 4.6), mr_test_add_box(s, 1, 1, 0.6, mw), MR_LAYER_VISIBLE);
    mr_test_add_node(s, "Pipe", mr_m4_translate(-0.5, 0, 6), mr_test_add_box(s, 0.4, 3, 0.4, mp), MR_LAYER_HIDDEN);
    mr_test_add_node(s, "Plate", mr_m4_translate(-1.2, -1.0, 4.7), mr_test_add_quad(s, 0.8, 0.8, mt, true),
                     MR_LAYER_VISIBLE);
    mr_scene_update_bounds(s);
}

/* Renders the frames; returns the number of frames that rendered and had
 * the passes this test relies on. */
static int render_frames(mr_renderer *r, mr_scene *s, mr_image *video) {
    int good = 0;
    mr_error err = {0};
    mr_lod *lod = mr_lod_build(s, NULL, &err);
    CHECK_MSG(lod != NULL, "LOD levels: %s", err.msg);
    for (int i = 0; i < 100; i++) {
        /* 100 distinct sizes between 8 and 40 pixels (w, h) in some order. */
        int w = 8 + (i * 7) % 33, h = 8 + (i * 13 + i / 33) % 33;
        if (i % 25 == 10) {
            /* A scene change drops what was derived from the scene (outline
             * and curvature streams, LOD levels) and builds it again. */
            CHECK_MSG(mr_renderer_set_scene(r, s, &err), "set scene again: %s", err.msg);
            if (lod) CHECK_MSG(mr_renderer_set_lod(r, lod, &err), "set LOD: %s", err.msg);
        }
        mr_view v = {{w, h, 0.9 * w, 0.9 * w, 0.5 * w - 0.5, 0.5 * h - 0.5, {0}}, mr_m4_identity()};
        mr_frame_params p = MR_FRAME_DEFAULTS;
        p.ao.method = i % 3 == 0 ? MR_AO_HBAO : MR_AO_SCHEER;
        p.ao.mask = i % 4 == 3 ? MR_AO_MASK_STANDALONE : MR_AO_MASK_ON;
        p.ao.half_res = i % 2 == 0;
        p.ao.positions = true;
        p.ao.want_ao = true;
        p.ao.want_mask = true;
        p.ghost.mode = MR_GHOST_ADAPTIVE;
        p.ghost.stats = true;
        /* shadows: every method now and then (the ground truth with few samples) */
        p.shadow.method = (mr_shadow_method)(1 + i % (MR_SHADOW_METHOD_COUNT - 1));
        p.shadow.gt_samples = 4;
        p.shadow.map_size = 64 + 32 * (i % 3);
        p.shadow.want_shadow = i % 2 == 0;
        p.video = i % 5 != 4 ? video : NULL;
        p.want_depth = p.want_normals = true;
        p.timing = i % 10 == 0;
        mr_frame_result res;
        if (!mr_render_frame(r, &v, &p, &res, &err)) {
            CHECK_MSG(false, "frame %d at %dx%d: %s", i, w, h, err.msg);
            continue;
        }
        char passes[512];
        mr_frame_result_passes(&res, passes, sizeof passes);
        bool all = strstr(passes, "ao_mask") && strstr(passes, "ghost_hidden") && strstr(passes, "ghost_emphasis") &&
                   (!p.ao.half_res || strstr(passes, "ao_upsample")) && (!p.video || strstr(passes, "overlay")) &&
                   strstr(passes, "shadow");
        CHECK_MSG(all, "frame %d at %dx%d ran only \"%s\": the test does not reach every pass", i, w, h, passes);
        good += all;
        mr_frame_result_free(&res);
        if (i % 20 == 7) {
            mr_pick pk;
            CHECK_MSG(mr_renderer_pick(r, w / 2.0, h / 2.0, &pk, &err), "pick: %s", err.msg);
        }
    }
    if (lod) {
        CHECK_MSG(mr_renderer_set_lod(r, NULL, &err), "drop LOD: %s", err.msg);
        mr_lod_destroy(&lod);
    }
    return good;
}

int main(void) {
    mr_error err = {0};
    mr_gpu *gpu = mr_gpu_create_headless(NULL, &err);
    if (!gpu) return mr_test_no_gpu("test_gl_objects", &err);
    int before[KIND_COUNT], after[KIND_COUNT];
    count_objects(before);
    mr_scene *s = mr_scene_create();
    build_scene(s);
    mr_image video;
    CHECK(mr_image_alloc(&video, 24, 18, 3, MR_PIX_U8, &err));
    memset(video.data, 90, mr_image_bytes(&video));
    mr_renderer *r = mr_renderer_create(gpu, &err);
    CHECK_MSG(r != NULL, "renderer: %s", err.msg);
    int frames = 0;
    if (r && mr_renderer_set_scene(r, s, &err)) frames = render_frames(r, s, &video);
    else CHECK_MSG(false, "set scene: %s", err.msg);
    /* The renderer really made objects (else the comparison proves nothing):
     * counted while it is alive. */
    int during[KIND_COUNT];
    count_objects(during);
    GLuint probe[2] = {0, 0};
    glCreateTextures(GL_TEXTURE_2D, 1, &probe[0]);
    glCreateBuffers(1, &probe[1]);
    CHECK_MSG(probe[0] < NAME_RANGE / 2 && probe[1] < NAME_RANGE / 2,
              "the newest names (texture %u, buffer %u) are near the end of the counted range 1..%d", probe[0],
              probe[1], NAME_RANGE);
    glDeleteTextures(1, &probe[0]);
    glDeleteBuffers(1, &probe[1]);
    int made = 0;
    for (int k = 0; k < KIND_COUNT; k++) made += during[k] - before[k];
    CHECK_MSG(made > 50, "only %d GL objects alive while the renderer is: the count sees nothing", made);
    mr_renderer_destroy(&r);
    CHECK_MSG(r == NULL, "mr_renderer_destroy does not NULL the handle");
    count_objects(after);
    printf("  %d of 100 frames ran every pass; GL objects alive with the renderer: %d more than before\n", frames,
           made);
    CHECK_MSG(frames == 100, "%d of 100 frames ran every pass", frames);
    for (int k = 0; k < KIND_COUNT; k++) {
        printf("  %-13s before %4d, with renderer %4d, after destroy %4d\n", k_kinds[k].name, before[k], during[k],
               after[k]);
        CHECK_MSG(after[k] == before[k], "%d %s name(s) left after mr_renderer_destroy (before %d, after %d)",
                  after[k] - before[k], k_kinds[k].name, before[k], after[k]);
    }
    CHECK_MSG(glGetError() == GL_NO_ERROR, "GL error after destroying the renderer");
    mr_image_free(&video);
    mr_scene_destroy(&s);
    mr_gpu_destroy(&gpu);
    return mr_test_finish("test_gl_objects");
}
