/* The input and tracker of a tracking command (track, record): which
 * source a path names, and where the camera and marker map come from. */
#include "mr_session.h"

#include <string.h>

mr_source *mr_input_open(const char *uri, const mr_source_params *params, mr_recording **rec_info, mr_error *err) {
    mr_source_params sp = MR_SOURCE_DEFAULTS;
    if (params) sp = *params;
    if (rec_info) *rec_info = NULL;
    if (uri && mr_is_recording(uri)) {
        mr_recording *rec = mr_recording_open(uri, err);
        if (!rec) return NULL;
        if (rec_info) {
            /* A second, read-only copy for the caller's defaults: the
             * source owns the first. */
            *rec_info = mr_recording_open(uri, err);
            if (!*rec_info) {
                mr_recording_close(&rec);
                return NULL;
            }
        }
        return mr_recording_source(rec, sp.gray, err);
    }
    return mr_source_open(uri, &sp, err);
}

mr_tracker *mr_input_tracker_create(const char *camera_path, const char *markers_path, const mr_recording *rec,
                                    const mr_tracker_params *params, mr_error *err) {
    mr_tracker_params tp = MR_TRACKER_DEFAULTS;
    if (params) tp = *params;
    tp.camera = NULL;
    tp.markers = NULL;
    mr_camera cam;
    mr_marker_map loaded = {0};
    if (camera_path) {
        if (!mr_camera_load(camera_path, &cam, err)) return NULL;
        tp.camera = &cam;
    } else if (rec) {
        tp.camera = &rec->camera;
    }
    if (markers_path) {
        if (!mr_marker_map_load(markers_path, &loaded, err)) return NULL;
        tp.markers = &loaded;
    } else if (rec && rec->has_markers) {
        tp.markers = &rec->markers;
    }
    mr_tracker *t = mr_tracker_create(&tp, err);
    mr_marker_map_free(&loaded); /* the tracker keeps its own copy */
    const mr_marker_map *m = t ? mr_tracker_markers(t) : NULL;
    const char *family = tp.detector.family;
    if (m && family && strcmp(family, m->family) != 0)
        mr_log(MR_LOG_WARN, "--family %s differs from the marker map's %s", family, m->family);
    return t;
}
