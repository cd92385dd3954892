/* Fuzz target: the LOD cache reader (<scene>.mrlod, binary): whatever the
 * file holds, mr_lod_load_or_build either trusts it (then every level must
 * be in range for the scene) or rebuilds. The scene is fixed (a bumpy 7 x 7
 * grid, small so a rejected cache is rebuilt quickly), so the seeds, caches
 * written for it, pass the scene hash and the checksum and reach the level
 * records; most mutations stop at the checksum, as they should. */
#include "fuzz_file.h"
#include "mr_scene.h"

#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static mr_scene *grid_scene(void) {
    enum { N = 7 };
    mr_mesh m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "grid");
    m.vertex_count = N * N;
    m.index_count = (N - 1) * (N - 1) * 6;
    m.positions = malloc((size_t)m.vertex_count * 12);
    m.indices = malloc((size_t)m.index_count * 4);
    m.material = -1;
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            float *p = m.positions + 3 * (j * N + i);
            p[0] = (float)i;
            p[1] = (float)(0.3 * sin(0.7 * i) * cos(0.5 * j));
            p[2] = (float)j;
        }
    uint32_t k = 0;
    for (uint32_t j = 0; j + 1 < N; j++)
        for (uint32_t i = 0; i + 1 < N; i++) {
            uint32_t a = j * N + i, q[6] = {a, a + N, a + 1, a + 1, a + N, a + N + 1};
            for (int t = 0; t < 6; t++) m.indices[k++] = q[t];
        }
    mr_scene *s = mr_scene_create();
    if (s && mr_scene_add_mesh(s, &m, NULL) != 0) mr_scene_destroy(&s);
    return s;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static mr_scene *s;
    if (!s) {
        mr_log_set_level(MR_LOG_ERROR); /* a rejected cache is a warning, thousands of times */
        s = grid_scene();
        if (!s) __builtin_trap();
    }
    char path[600];
    if (!fuzz_put("scene.mrlod", data, size, path, sizeof path)) __builtin_trap();
    mr_lod_params lp = MR_LOD_DEFAULTS;
    lp.max_error = 0.2;
    lp.min_triangles = 16;
    mr_lod_info info;
    mr_error err = {0};
    mr_lod *l = mr_lod_load_or_build(s, path, &lp, &info, &err);
    if (!l) __builtin_trap(); /* a bad cache is rebuilt, never an error */
    if (l->mesh_count != s->mesh_count) __builtin_trap();
    for (int32_t i = 0; i < l->mesh_count; i++) {
        const mr_mesh_lods *ml = &l->meshes[i];
        double prev = 0;
        if (ml->level_count < 0 || ml->level_count > MR_LOD_MAX_LEVELS) __builtin_trap();
        for (int k = 0; k < ml->level_count; k++) {
            const mr_lod_level *lv = &ml->levels[k];
            if (lv->index_count == 0 || lv->index_count % 3 || lv->index_count > s->meshes[i].index_count ||
                !(lv->error >= prev) || !isfinite(lv->error))
                __builtin_trap();
            for (uint32_t j = 0; j < lv->index_count; j++)
                if (lv->indices[j] >= s->meshes[i].vertex_count) __builtin_trap();
            prev = lv->error;
        }
    }
    mr_lod_destroy(&l);
    return 0;
}
