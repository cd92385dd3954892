/* prepare_internal.h — the steps of mr_mesh_prepare one array at a time
 * (scene.c), for the glTF loader: it converts a compressed file's arrays
 * on both cores as their views decode, prepares each array there, and adds
 * the mesh prepared (mr_scene_add_prepared_mesh). Each step is all or
 * nothing: false + err changes nothing. name: the mesh's, for messages.
 * Internal to lib/scene. */
#ifndef MR_PREPARE_INTERNAL_H
#define MR_PREPARE_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mr_core.h"
#include "mr_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Every index below vertex_count. */
bool mr_mesh_check_indices(const uint32_t *idx, uint32_t count, uint32_t vertex_count, const char *name, mr_error *err);
/* lo/hi extended by n xyz positions (start them at +inf / -inf); false if
 * one is not finite. */
bool mr_mesh_bounds_add(const float *pos, size_t n, double lo[3], double hi[3]);
/* n xyz positions, all finite, whose bounds are lo/hi, recentred on the
 * bounds' centre (computed in double), the centre added to origin, their
 * float bounds in bmin/bmax. */
void mr_mesh_recentre_within(float *pos, uint32_t n, const double lo[3], const double hi[3], double origin[3], float bmin[3],
                             float bmax[3]);
/* Every one of n floats finite. */
bool mr_floats_finite(const float *v, size_t n);
/* n xyz normals, all finite, made unit length (degenerate ones get a
 * fallback); an already unit one stays bit for bit. */
void mr_mesh_unit_normals(float *nrm, uint32_t n);

/* Gives s the malloc'd buffer p of n bytes, whose parts are (or will be)
 * arrays of its meshes: freed when s is, those arrays never on their own.
 * false (p still the caller's) if out of memory. */
bool mr_scene_adopt_block(mr_scene *s, void *p, size_t n);
/* Whether p lies inside one of s's blocks (then it is not to be freed). */
bool mr_scene_block_holds(mr_scene *s, const void *p);
/* A mesh array let go: freed, unless it lies inside one of s's blocks
 * (s may be NULL: then always freed). */
void mr_scene_array_free(mr_scene *s, void *p);

#ifdef __cplusplus
}
#endif

#endif
