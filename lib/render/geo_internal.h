/* geo_internal.h — what the scene's geometry (geometry.c) and the LOD
 * hierarchy's proxies (hlod_draw.c) share: the instance record the
 * G-buffer's vertex shader reads, the indirect command, and the helpers
 * that fill and bind them. Internal to lib/render. */
#ifndef MR_GEO_INTERNAL_H
#define MR_GEO_INTERNAL_H

#include "render_internal.h"

/* One instance as the G-buffer vertex shader reads it (attributes 3..11). */
typedef struct gpu_instance {
    float modelview[16]; /* camera (OpenCV axes) from mesh, column-major */
    float normal[12];    /* inverse transpose of its 3x3: 3 columns padded to vec4 */
    float color[4];      /* linear RGBA base colour */
    uint32_t ids[4];     /* node index + 1, layer, has texture, unused */
} gpu_instance;

/* glMultiDrawElementsIndirect's command layout. */
typedef struct draw_cmd {
    uint32_t count, instance_count, first_index;
    int32_t base_vertex;
    uint32_t base_instance;
} draw_cmd;

/* The model-view (camera-relative, composed in double, then cast) and its
 * normal matrix; false where the 3x3 is degenerate (nothing to draw). */
bool mr_geo_instance_matrices(const mr_dmat4 *mv, gpu_instance *out);
/* Binds attributes 3..11 of vao to the instance records in binding 1
 * (divisor 1). */
void mr_geo_vao_instances(GLuint vao);

/* The LOD hierarchy (hlod_draw.c). */
bool mr_hlod_active(const mr_renderer *r);
/* Draws the proxies of vw's cut and writes the scene nodes left to the
 * part levels into nodes (room for the scene's node count); returns their
 * count. frustum NULL: no culling. */
int32_t mr_hlod_draw(mr_renderer *r, const mr_geo_view *vw, const mr_frustum *frustum, int32_t *nodes,
                     mr_frame_result *out);
void mr_hlod_gpu_free(mr_renderer *r);

#endif
