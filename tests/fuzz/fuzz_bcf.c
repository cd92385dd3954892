/* Fuzz target: the BCF reader (a zip archive's bytes) and, on the same
 * input, its XML reader, which meets every markup and viewpoint. */
#include "../../lib/export/export_internal.h"

#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_error err = {0};
    mr_bcf b;
    bool ok = mr_bcf_read_memory(data, size, &b, &err);
    if (!ok && (err.code == MR_OK || !err.msg[0])) __builtin_trap(); /* a failure must say why */
    if (ok) {
        /* What was read can be written again (GUIDs were checked or made). */
        void *out = NULL;
        size_t n = 0;
        if (!mr_bcf_write_memory(&b, MR_BCF_3_0, &out, &n, &err) && err.code != MR_ERR_NOMEM) __builtin_trap();
        free(out);
        mr_bcf_free(&b);
    }
    mr_xml_node *x = mr_xml_parse((const char *)data, size, &err);
    mr_xml_node_free(x);
    return 0;
}
