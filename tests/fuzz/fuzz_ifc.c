/* Fuzz target: the IFC front door: the content sniffing that sends a file
 * to the IFC loader, and the loader's C face over IFC++ (its STEP parser,
 * the geometry it converts, the units and storeys read). */
#include "../../lib/scene/ifc_internal.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
const char *__lsan_default_suppressions(void);

/* Debian's libcarve leaks its CSG collector (240 bytes) when IFC++ stops an
 * opening's subtraction on a damaged solid (carve::csg::makeCollector,
 * under RepresentationConverter::subtractOpenings): not ours to free, and
 * only on damaged input. LeakSanitizer reads this hook when it runs. */
const char *__lsan_default_suppressions(void) { return "leak:libcarve.so\n"; }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_error err = {0};
    bool ifc = mr_ifc_sniff(data, size);
    mr_scene_params p = MR_SCENE_DEFAULTS;
    p.no_cache = true;
    mr_scene *s = mr_ifc_load_memory(data, size, &p, &err);
    if (!s && (err.code == MR_OK || !err.msg[0])) __builtin_trap(); /* a failure must say why */
    if (s && !ifc) __builtin_trap();                                  /* only what the sniff lets in loads */
    if (s) {
        /* What loads is usable: finite bounds, an element per product node. */
        for (int i = 0; i < 3; i++)
            if (!(s->bounds_min[i] <= s->bounds_max[i])) __builtin_trap();
    }
    mr_scene_destroy(&s);
    return 0;
}
