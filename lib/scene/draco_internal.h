/* draco_internal.h — the KHR_draco_mesh_compression decoder (draco_io.cc,
 * the only file that sees Debian's libdraco) behind a plain C face, so
 * gltf_io.cc stays free of draco's types. Internal to lib/scene. */
#ifndef MR_DRACO_INTERNAL_H
#define MR_DRACO_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mr_draco mr_draco;

/* Decodes a draco mesh from untrusted bytes; NULL + a one-line reason in
 * why on failure (never throws, never aborts). */
mr_draco *mr_draco_decode(const void *data, size_t size, char *why, size_t why_size);
uint32_t mr_draco_points(const mr_draco *d);
uint32_t mr_draco_faces(const mr_draco *d);
/* 3 * faces point indices (all < points). */
void mr_draco_indices(const mr_draco *d, uint32_t *out);
/* The attribute with draco's unique id as ncomp floats per point (integer
 * attributes as plain values, normalised ones in [0,1] / [-1,1]); false +
 * why if it does not exist or has fewer components. */
bool mr_draco_attribute(const mr_draco *d, int unique_id, int ncomp, float *out, char *why, size_t why_size);
void mr_draco_free(mr_draco *d);

#ifdef __cplusplus
}
#endif
#endif
