/* The base passes: G-buffer, Lambert + ambient shading, video overlay. */
#include "render_internal.h"

#include <math.h>
#include <string.h>

bool mr_pass_need_always(frame *f) { (void)f; return true; }
bool mr_pass_need_overlay(frame *f) { return f->p->video != NULL; }

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
    glClearNamedFramebufferfv(t->fbo, GL_COLOR, 0, zero4);
    glClearNamedFramebufferfv(t->fbo, GL_COLOR, 1, zero4);
    glClearNamedFramebufferuiv(t->fbo, GL_COLOR, 2, zero_u);
    glClearNamedFramebufferfv(t->fbo, GL_DEPTH, 0, &depth0);
}

void mr_pass_gbuffer(frame *f) {
    mr_renderer *r = f->r;
    static const float zero4[4] = {0, 0, 0, 0};
    mr_gbuffer_begin(f, &r->gbuf);
    /* View-space positions are rasterised (not un-projected from depth) so
     * that AO also works where the projection cannot be inverted; the
     * attachment costs bandwidth, so it is written only when this frame's AO
     * reads positions. */
    static const GLenum bufs[4] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                                   GL_COLOR_ATTACHMENT3};
    bool want_pos = mr_pass_need_ao_positions(f);
    glNamedFramebufferDrawBuffers(r->gbuf.fbo, want_pos ? 4 : 3, bufs);
    if (want_pos) glClearNamedFramebufferfv(r->gbuf.fbo, GL_COLOR, 3, zero4);
    uint32_t mask = 1u << MR_LAYER_VISIBLE;
    /* With ghosting, the hidden layer goes to its own target D (pass_ghost.c). */
    if (!f->p->hide_hidden_layer && !mr_ghost_active(f)) mask |= 1u << MR_LAYER_HIDDEN;
    mr_geometry_draw(f, mask);
    glDisable(GL_DEPTH_TEST);
}

void mr_pass_shade(frame *f) {
    mr_shade_draw(f, &f->r->gbuf, &f->r->shaded);
    f->final_tex = f->r->shaded.color[0];
}

void mr_shade_draw(frame *f, const target *src, const target *dst) {
    mr_renderer *r = f->r;
    glBindFramebuffer(GL_FRAMEBUFFER, dst->fbo);
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
    glUniform1f(20, f->p->specular > 0 ? f->p->specular : 0.0f);
    glUniform1f(21, f->p->shininess >= 1 ? f->p->shininess : MR_FRAME_DEFAULT_SHININESS);
    /* The main G-buffer's AO, or the hidden layer's own (pass_ghost.c). */
    GLuint ao = src == &r->gbuf ? mr_pass_ao_texture(f) : f->hidden_ao; /* 0 when there is no AO */
    glUniform1i(19, ao != 0);
    glBindTextureUnit(0, src->color[0]);
    glBindTextureUnit(1, src->color[1]);
    glBindTextureUnit(2, ao);
    glBindVertexArray(r->empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
}


void mr_pass_overlay(frame *f) {
    mr_renderer *r = f->r;
    const mr_image *v = f->p->video;
    GLenum fmt = v->channels == 1 ? GL_RED : v->channels == 2 ? GL_RG : v->channels == 3 ? GL_RGB : GL_RGBA;
    if (!r->video_tex || r->video_w != v->width || r->video_h != v->height) {
        glDeleteTextures(1, &r->video_tex);
        r->video_tex = mr_gl_make_tex(GL_SRGB8_ALPHA8, v->width, v->height, GL_LINEAR);
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

