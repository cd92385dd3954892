/* lib/eval's private helpers (not part of mr_eval.h). */
#ifndef MR_EVAL_INTERNAL_H
#define MR_EVAL_INTERNAL_H

#include "mr_scene.h"

#include <embree3/rtcore.h>

/* A committed Embree triangle geometry of mesh m, its stored positions
 * mapped by M (world, or a shifted world, from the mesh's positions, its
 * origin included) in double and then stored as float. Indices out of range
 * are clamped to vertex 0 (a degenerate triangle, harmless) so Embree never
 * reads past the vertex buffer. *extent (if given) grows to the largest
 * finite |coordinate| written. NULL: Embree is out of memory. */
RTCGeometry mr_eval_embree_mesh(RTCDevice dev, const mr_mesh *m, const mr_dmat4 *M, double *extent);

#endif
