/* Fuzz target: the view's settings file (~/.config/mrcheck/view.json),
 * read tolerantly: whatever the file holds, the settings that come back are
 * usable (alpha in [0, 1], modes and rate valid) and a warning, if any, is
 * one line. */
#include "fuzz_file.h"
#include "mr_view.h"

#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char path[600], warn[512];
    if (!fuzz_put("view.json", data, size, path, sizeof path)) __builtin_trap();
    mr_view_settings s = MR_VIEW_SETTINGS_DEFAULTS;
    warn[0] = 0;
    mr_view_settings_load(path, &s, warn, sizeof warn);
    if (!(s.alpha >= 0 && s.alpha <= 1) || s.rate_i < 0 || s.rate_i >= MR_VIEW_RATE_COUNT || strchr(warn, '\n')) __builtin_trap();
    if (!mr_ao_method_name(s.ao) || !mr_view_ghost_name(s.ghost)) __builtin_trap();
    return 0;
}
