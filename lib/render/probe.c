/* The fetch floor of a full-screen AO pass (shaders/ao_probe.
 * frag.glsl): what `fetches` R32F texel fetches per pixel cost on this
 * machine with nothing else to do, so that `bench ao` can state every AO
 * pass's cost as a multiple of it. Timed on the CPU between two glFinish:
 * llvmpipe defers rasterisation, so a timer query around a lone draw can
 * read a fraction of the work. */
#include "render_internal.h"

#include <stdlib.h>
#include <string.h>

bool mr_render_fetch_probe(mr_renderer *r, int w, int h, int fetches, double radius_px, int frames, double *ms,
                           mr_error *err) {
    if (!r || w <= 0 || h <= 0 || frames <= 0 || !ms)
        return mr_fail(err, MR_ERR_INVALID, "fetch probe: a renderer, a size and at least one frame are needed");
    if (fetches < 1) fetches = 1;
    if (fetches > MR_AO_MAX_SAMPLES) fetches = MR_AO_MAX_SAMPLES;
    static const char *const files[] = {"fullscreen.vert.glsl", "ao_probe.frag.glsl", NULL};
    GLuint prog = mr_gl_program(files, err);
    if (!prog) return false;
    /* Source content does not matter to the cost; a ramp keeps it finite. */
    float *ramp = malloc((size_t)w * h * sizeof *ramp);
    if (!ramp) {
        glDeleteProgram(prog);
        return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    for (size_t i = 0; i < (size_t)w * h; i++) ramp[i] = (float)(i % 977) * 1e-3f;
    GLuint src = mr_gl_make_tex(GL_R32F, w, h, GL_NEAREST), dst = mr_gl_make_tex(GL_R32F, w, h, GL_NEAREST), fbo;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(src, 0, 0, 0, w, h, GL_RED, GL_FLOAT, ramp);
    free(ramp);
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, dst, 0);
    /* The AO disk kernel, scaled to the projected radius in pixels. */
    float k2[MR_AO_MAX_SAMPLES * 2], off[MR_AO_MAX_SAMPLES * 4];
    memset(off, 0, sizeof off);
    mr_ao_kernel_generate(MR_AO_KERNEL_UNIFORM, fetches, 0, 1, 0x5eedu, NULL, k2);
    for (int i = 0; i < fetches; i++) {
        off[4 * i] = (float)(k2[2 * i] * radius_px);
        off[4 * i + 1] = (float)(k2[2 * i + 1] * radius_px);
    }
    glUseProgram(prog);
    glUniform1i(MR_LOC_PROBE_FETCHES, fetches);
    glUniform4fv(MR_LOC_PROBE_OFFSETS, MR_AO_MAX_SAMPLES, off);
    glBindTextureUnit(MR_TEX_PROBE_SRC, src);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, w, h);
    glDisable(GL_FRAMEBUFFER_SRGB);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glBindVertexArray(r->empty_vao);
    for (int f = -1; f < frames; f++) {
        glFinish();
        double t0 = mr_time_now();
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glFinish();
        if (f >= 0) ms[f] = (mr_time_now() - t0) * 1e3;
    }
    glBindTextureUnit(MR_TEX_PROBE_SRC, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glUseProgram(0);
    glDeleteFramebuffers(1, &fbo);
    glDeleteTextures(1, &src);
    glDeleteTextures(1, &dst);
    glDeleteProgram(prog);
    return true;
}
