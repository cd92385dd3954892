/* Fuzz target: the image readers (PFM, ours; PNG and the rest through
 * stb_image), from a file as the renderer's tests and --aux users read them. */
#include "fuzz_file.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char path[600];
    if (!fuzz_put("image", data, size, path, sizeof path)) __builtin_trap();
    mr_image img;
    mr_error err = {0};
    if (mr_image_load_pfm(path, &img, &err)) {
        if (img.width < 1 || img.height < 1 || (img.channels != 1 && img.channels != 3) || img.type != MR_PIX_F32 ||
            !img.data || (size_t)img.width * (size_t)img.height * (size_t)img.channels * 4 > size)
            __builtin_trap(); /* never more pixels than the file holds bytes for */
        mr_image_free(&img);
    } else if (err.code == MR_OK || !strstr(err.msg, path)) {
        __builtin_trap();
    }
    err = (mr_error){0};
    if (mr_image_load(path, 3, &img, &err)) {
        if (img.width < 1 || img.height < 1 || img.channels != 3 || !img.data) __builtin_trap();
        mr_image_free(&img);
    } else if (err.code == MR_OK || !strstr(err.msg, path)) {
        __builtin_trap();
    }
    return 0;
}
