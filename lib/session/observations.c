/* The taps of a measurement (`mrcheck measure --observations`), read
 * against the recording whose frames were tapped: each tap becomes the
 * frame's pose (and its covariance, where the recording carries one) and
 * the tapped pixel. */
#include "mr_session.h"

#include <string.h>

bool mr_observations_load(const char *path, const mr_recording *rec, mr_observations *o, mr_error *err) {
    memset(o, 0, sizeof *o);
    cJSON *obs = mr_json_load(path, err);
    if (!obs) return false;
    bool ok = false;
    const cJSON *arr = cJSON_GetObjectItemCaseSensitive(obs, "taps"), *t;
    o->has_planned = cJSON_GetObjectItemCaseSensitive(obs, "planned") != NULL;
    if (o->has_planned && !mr_json_numbers(obs, "planned", o->planned, 3, err)) {
        mr_error_prefix(err, "%s", path);
        goto done;
    }
    if (!cJSON_IsArray(arr)) {
        mr_fail(err, MR_ERR_PARSE, "%s: \"taps\" must be an array of {\"frame\", \"px\"}", path);
        goto done;
    }
    cJSON_ArrayForEach(t, arr) {
        double fr = -1, px[2];
        int n = o->count;
        if (n == MR_OBSERVATIONS_MAX) {
            mr_fail(err, MR_ERR_INVALID, "%s: more than %d taps", path, MR_OBSERVATIONS_MAX);
            goto done;
        }
        if (!cJSON_IsObject(t) || !mr_json_number(t, "frame", &fr, true, err) || !mr_json_numbers(t, "px", px, 2, err)) {
            if (!cJSON_IsObject(t)) mr_fail(err, MR_ERR_PARSE, "not an object");
            mr_error_prefix(err, "%s: tap %d", path, n + 1);
            goto done;
        }
        const mr_rec_frame *f = NULL;
        for (int i = 0; i < rec->frame_count; i++)
            if ((double)rec->frames[i].index == fr) f = &rec->frames[i];
        if (!f) {
            mr_fail(err, MR_ERR_INVALID, "%s: tap %d: frame %g is not in the recording%s", path, n + 1, fr,
                    rec->bad_lines ? " (its frames.jsonl has unreadable lines, skipped)" : "");
            goto done;
        }
        if (!f->pose.valid) {
            mr_fail(err, MR_ERR_INVALID, "%s: tap %d: frame %g has no tracked pose", path, n + 1, fr);
            goto done;
        }
        bool cov = f->pose.corner_sigma_px > 0;
        o->no_cov += !cov;
        o->taps[o->count++] = (mr_tap){f->pose.world_from_camera, cov ? f->pose.cov : NULL, {px[0], px[1]}, cov ? f->pose.cov_map : NULL};
    }
    ok = true;
done:
    cJSON_Delete(obs);
    return ok;
}
