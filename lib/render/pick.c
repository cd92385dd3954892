/* Picking: what lies under one pixel of the last frame, read back from the
 * G-buffer (reversed-Z depth and node ids), so a tap on the screen names the
 * part and the world point without a CPU ray cast. */
#include "render_internal.h"

#include <math.h>
#include <string.h>

bool mr_renderer_pick(mr_renderer *r, double x, double y, mr_pick *out, mr_error *err) {
    memset(out, 0, sizeof *out);
    out->node = -1;
    if (!r || !r->last.valid || !r->last.depth || !r->last.ids) return mr_fail(err, MR_ERR_INVALID, "no frame has been rendered to pick from");
    int px = (int)floor(x + 0.5), py = (int)floor(y + 0.5);
    if (!(isfinite(x) && isfinite(y)) || px < 0 || py < 0 || px >= r->w || py >= r->h)
        return mr_fail(err, MR_ERR_INVALID, "pick position (%g, %g) is outside the %dx%d frame", x, y, r->w, r->h);
    float d = 0;
    GLuint ids[2] = {0, 0};
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    /* Targets are stored top row first, so image row py is texture row py. */
    glGetTextureSubImage(r->last.depth, 0, px, py, 0, 1, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, sizeof d, &d);
    glGetTextureSubImage(r->last.ids, 0, px, py, 0, 1, 1, 1, GL_RG_INTEGER, GL_UNSIGNED_INT, sizeof ids, ids);
    GLenum e = glGetError();
    if (e != GL_NO_ERROR) return mr_fail(err, MR_ERR_GL, "GL error 0x%x reading the pick pixel", e);
    /* Proxies of the LOD hierarchy move edges and surfaces by up to their
     * error: where the frame drew some, the pixel is drawn again at the
     * part levels, so a tap names the part and the point that a frame
     * without the hierarchy shows there. */
    if (r->last.hier && !mr_gbuffer_pick_pixel(r, px, py, &d, ids, err)) return false;
    if (!(d > 0)) return true; /* reversed Z: 0 is infinity, nothing there */
    /* depth = near / z (see mr_gl_projection); the ray through (x, y)
     * itself, not the pixel centre, of the ideal pinhole camera the frame
     * was rendered with, so a tap lands where it was made. */
    const mr_camera *c = &r->last.cam;
    double z = r->last.near_plane / d;
    mr_dvec3 pc = mr_v3((x - c->cx) / c->fx * z, (y - c->cy) / c->fy * z, z);
    out->hit = true;
    out->depth = z;
    out->world = mr_m4_point(&r->last.world_from_camera, pc);
    out->node = ids[0] > 0 && r->scene && (int32_t)ids[0] <= r->scene->node_count ? (int32_t)ids[0] - 1 : -1;
    out->layer = (int)ids[1];
    return true;
}

uint32_t mr_renderer_frame_texture(const mr_renderer *r) { return r && r->last.valid ? r->last.tex : 0; }
