/* Fuzz target: the view's --script files (timed input). A bad file fails
 * with one line (naming the line it stopped at), never a crash. */
#include "fuzz_file.h"
#include "mr_view.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    char path[600];
    if (!fuzz_put("input.script", data, size, path, sizeof path)) __builtin_trap();
    mr_error err = {0};
    mr_view_script *s = mr_view_script_load(path, &err);
    if (!s && (err.code == MR_OK || !err.msg[0] || strchr(err.msg, '\n'))) __builtin_trap();
    mr_view_script_destroy(&s);
    if (s) __builtin_trap();
    return 0;
}
