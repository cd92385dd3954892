/* ifc_internal.h — IFC2x3 / IFC4 import through Debian's IFC++ (ifc_io.cc,
 * the only file that sees IFC++ and carve) behind a plain C face. Internal
 * to lib/scene; mr_scene_load reaches it for files recognised by content. */
#ifndef MR_IFC_INTERNAL_H
#define MR_IFC_INTERNAL_H

#include "mr_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* True if data starts (after a BOM and white space) with "ISO-10303-21;"
 * and its header names an IFC schema in FILE_SCHEMA. */
bool mr_ifc_sniff(const void *data, size_t size);

/* Converts an IFC file's bytes into a scene: one node per IfcProduct with
 * geometry (openings cut by IFC++), named by its Name (or GlobalId), with
 * its element (GlobalId, class, storey, property sets). Metres whatever the
 * file's length unit; IFC's Z up turned into the scene's Y up by
 * (x, y, z) -> (x, z, -y), with no recentring: placements and site offsets
 * stay in double precision. Progress stages "parse" and "convert". Fails
 * with one line for a file that is not IFC, is truncated (no
 * END-ISO-10303-21;) or has no product with geometry. */
mr_scene *mr_ifc_load_memory(const void *data, size_t size, const mr_scene_params *params, mr_error *err);

#ifdef __cplusplus
}
#endif
#endif
