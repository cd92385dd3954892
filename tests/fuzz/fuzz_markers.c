/* libFuzzer target: the marker map reader. Build with -DMR_FUZZ=ON (clang). */
#include "mr_track.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_marker_map map;
    mr_error err = {0};
    if (mr_marker_map_parse((const char *)data, size, &map, &err)) {
        /* what the reader accepts must be usable */
        for (int i = 0; i < map.count; i++) {
            mr_dvec3 c[4];
            mr_marker_corners_world(&map, &map.tags[i], c);
            if (!(map.tag_size > 0) || !mr_m4_is_rigid(&map.tags[i].world_from_tag, 1e-3)) __builtin_trap();
        }
        mr_marker_map_free(&map);
    }
    return 0;
}
