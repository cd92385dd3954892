/* Fuzz target: the scene config (configs/scenes/NAME.json: the glTF path,
 * hidden-layer globs, lights, ambient), read from a file next to a small
 * valid glTF so an accepted config loads a real scene. */
#include "fuzz_file.h"
#include "mr_scene.h"

#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const char k_tri[] =
    "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0,\"name\":\"Pipe_1\"}],"
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],\"buffers\":[{\"byteLength\":36,\"uri\":"
    "\"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36}],\"accessors\":[{\"bufferView\":0,"
    "\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]}]}";

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static bool have_gltf;
    char path[600], gpath[600];
    if (!have_gltf) have_gltf = fuzz_put("tri.gltf", k_tri, sizeof k_tri - 1, gpath, sizeof gpath);
    if (!have_gltf || !fuzz_put("scene.json", data, size, path, sizeof path)) __builtin_trap();
    mr_error err = {0};
    mr_scene *s = mr_scene_load(path, NULL, &err);
    if (!s) {
        /* A failure says why, on one line, naming the file. */
        if (err.code == MR_OK || !strstr(err.msg, "scene.json") || strchr(err.msg, '\n')) __builtin_trap();
        return 0;
    }
    /* What the reader accepts is usable: unit light directions, colours
     * and ambient in range. */
    if (s->light_count < 0 || s->light_count > MR_SCENE_MAX_LIGHTS || !(s->ambient >= 0 && s->ambient <= 1)) __builtin_trap();
    for (int i = 0; i < s->light_count; i++) {
        const mr_light *l = &s->lights[i];
        double len = sqrt((double)l->direction[0] * l->direction[0] + (double)l->direction[1] * l->direction[1] +
                          (double)l->direction[2] * l->direction[2]);
        if (!(fabs(len - 1) < 1e-5)) __builtin_trap();
        for (int k = 0; k < 3; k++)
            if (!(l->color[k] >= 0) || !isfinite(l->color[k])) __builtin_trap();
    }
    mr_scene_destroy(&s);
    return 0;
}
