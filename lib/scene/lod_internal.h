/* lod_internal.h — lod.c's build kernel compiled a second time for
 * x86-64-v3 CPUs (lod_v3.c, -march=x86-64-v3: AVX2 and FMA), which lod.c
 * calls where the CPU has them (mr_lod_kernel says which). Internal to
 * lib/scene. */
#ifndef MR_LOD_INTERNAL_H
#define MR_LOD_INTERNAL_H

#include "mr_scene.h"

#ifdef MR_LOD_HAVE_V3
/* One mesh's levels (lod.c's build_mesh), p resolved. */
bool mr_lod_build_mesh_v3(const mr_mesh *m, const mr_lod_params *p, mr_mesh_lods *out);
#endif

#endif
