/* One mesh into an Embree geometry: shared by the ground truths
 * (groundtruth.c) and the nearest-point queries (nearest.c). */
#include "eval_internal.h"

#include <math.h>

RTCGeometry mr_eval_embree_mesh(RTCDevice dev, const mr_mesh *m, const mr_dmat4 *M, double *extent) {
    RTCGeometry geom = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!geom) return NULL;
    float *v = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                       m->vertex_count);
    unsigned *idx = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                            m->index_count / 3);
    if (!v || !idx) {
        rtcReleaseGeometry(geom);
        return NULL;
    }
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        mr_dvec3 p = mr_m4_point(M, mr_v3(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]));
        v[3 * i] = (float)p.x;
        v[3 * i + 1] = (float)p.y;
        v[3 * i + 2] = (float)p.z;
        if (extent) {
            double e = fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z)));
            if (isfinite(e) && e > *extent) *extent = e;
        }
    }
    for (uint32_t i = 0; i < m->index_count / 3 * 3; i++) idx[i] = m->indices[i] < m->vertex_count ? m->indices[i] : 0;
    rtcCommitGeometry(geom);
    return geom;
}
