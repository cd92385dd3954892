/* mr_detect_each: a photo set through one full-resolution detector
 * (calibration and marker mapping). */
#include "mr_track.h"

bool mr_detect_each(const char *input, const char *family, const char *who, mr_detect_each_fn fn, void *user,
                    int *skipped, mr_error *err) {
    if (skipped) *skipped = 0;
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.gray = true;
    mr_source *src = mr_source_open(input, &sp, err);
    mr_detector_params dp = MR_DETECTOR_DEFAULTS;
    dp.family = family;
    dp.decimate = 1; /* full resolution: corner accuracy is what is measured */
    mr_detector *det = src ? mr_detector_create(&dp, err) : NULL;
    bool ok = det != NULL;
    int width = 0, height = 0, done = 0;
    while (ok) {
        if (mr_stop_requested()) {
            ok = mr_fail(err, MR_ERR_INTERRUPTED, "interrupted after %d image%s; nothing written", done, done == 1 ? "" : "s");
            break;
        }
        mr_frame f;
        mr_read_status st = mr_source_read(src, &f, err);
        if (st == MR_READ_END) break;
        if (st == MR_READ_ERROR) {
            ok = false;
            break;
        }
        if (width == 0) {
            width = f.image.width;
            height = f.image.height;
        } else if (f.image.width != width || f.image.height != height) {
            fprintf(stderr, "mrcheck: %s: warning: %s is %dx%d, not %dx%d; skipped\n", who, f.name, f.image.width,
                    f.image.height, width, height);
            if (skipped) ++*skipped;
            continue;
        }
        int n = 0;
        mr_error fe = {0};
        const mr_detection *d = mr_detector_detect(det, &f.image, &n, &fe);
        if (!d) {
            fprintf(stderr, "mrcheck: %s: warning: %s: %s\n", who, f.name, fe.msg);
            if (skipped) ++*skipped;
            continue;
        }
        ok = fn(user, &f, d, n, err);
        done++;
    }
    mr_detector_destroy(&det);
    mr_source_close(&src);
    return ok;
}
