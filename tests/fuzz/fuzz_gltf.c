/* Fuzz target: the glTF front door (GLB or JSON, by content). */
#include "mr_scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_error err = {0};
    mr_scene_params p = MR_SCENE_DEFAULTS;
    static const char *const globs[] = {"Pipe*", "[a-c]?x*"};
    p.hidden_globs = globs;
    p.hidden_glob_count = 2;
    /* NULL base_dir: external URIs are refused, so the fuzzer never reads
     * files outside its input. */
    mr_scene *s = mr_scene_load_gltf_memory(data, size, NULL, &p, &err);
    if (!s && (err.code == MR_OK || !err.msg[0])) __builtin_trap(); /* a failure must say why */
    mr_scene_destroy(&s);
    return 0;
}
