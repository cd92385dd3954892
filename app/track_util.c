/* Shared wiring of the tracking commands: input, tracker, line formats. */
#include "app_track.h"

#include <string.h>

mr_source *app_open_input(const char *uri, bool gray, mr_recording **rec_info, mr_error *err) {
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.gray = gray;
    return mr_input_open(uri, &sp, rec_info, err);
}

bool app_open_input_opts(const char *cmd, const mr_cli_opt *opts, bool gray, mr_recording **rec_info, mr_source **src,
                         mr_error *err) {
    (void)cmd;
    *src = NULL;
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    sp.gray = gray;
    if (mr_cli_get(opts, "size") && !mr_cli_size("size", mr_cli_get(opts, "size"), &sp.width, &sp.height)) return false;
    if (mr_cli_get(opts, "fps") && !mr_cli_double("fps", mr_cli_get(opts, "fps"), 0.1, 1000, &sp.fps)) return false;
    sp.pixel_format = mr_cli_get(opts, "pixel-format");
    *src = mr_input_open(mr_cli_get(opts, "input"), &sp, rec_info, err);
    return true;
}

bool app_tracker_init(app_tracker *t, const char *cmd, const mr_cli_opt *opts, const mr_detector_params *dp,
                      const mr_recording *rec) {
    memset(t, 0, sizeof *t);
    mr_error err = {0};
    mr_tracker_params tp = MR_TRACKER_DEFAULTS;
    tp.detector = *dp;
    tp.detector.family = mr_cli_get(opts, "family");
    tp.no_filter = mr_cli_flag(opts, "no-filter");
    tp.freeze_first = mr_cli_flag(opts, "freeze");
    t->tracker = mr_input_tracker_create(mr_cli_get(opts, "camera"), mr_cli_get(opts, "markers"), rec, &tp, &err);
    if (!t->tracker) return mr_cli_error(cmd, &err), false;
    t->camera = mr_tracker_camera(t->tracker);
    t->markers = mr_tracker_markers(t->tracker);
    t->has_camera = t->camera != NULL;
    t->has_markers = t->markers != NULL;
    return true;
}
void app_tracker_free(app_tracker *t) {
    mr_tracker_destroy(&t->tracker);
    memset(t, 0, sizeof *t);
}
