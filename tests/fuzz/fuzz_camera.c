/* libFuzzer target: the camera JSON reader, then the camera model on the
 * accepted camera (undistort must terminate and stay finite or fail). */
#include "mr_track.h"

#include <math.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    mr_camera cam;
    mr_error err = {0};
    if (!mr_camera_parse((const char *)data, size, &cam, &err)) return 0;
    if (!(cam.fx > 0) || !(cam.fy > 0)) __builtin_trap();
    double x, y;
    if (mr_camera_undistort(&cam, (0 - cam.cx) / cam.fx, (0 - cam.cy) / cam.fy, &x, &y) && (!isfinite(x) || !isfinite(y)))
        __builtin_trap();
    return 0;
}
