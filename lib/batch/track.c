/* `mrcheck track` as a library call: the tracker over every frame of a
 * source, detection and pose lines out, poses.jsonl written at the end. */
#include "mr_batch.h"

#include <stdlib.h>
#include <unistd.h>

/* Prints o as one line on out (false: out of memory). */
static bool put_line(cJSON *o, FILE *out) {
    char *s = cJSON_PrintUnformatted(o);
    if (s) fprintf(out, "%s\n", s);
    free(s);
    return s != NULL;
}

/* One frame's lines: the detections (with the pose when there is one) on
 * out, the pose line on out or into poses. */
static bool frame_lines(const mr_batch_track_params *p, bool want_pose, const mr_frame *f, const mr_tracker_result *r,
                        mr_jsonl *poses) {
    bool ok = true;
    if (p->print_detections) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "frame", (double)f->index);
        cJSON_AddItemToObject(o, "detections", mr_detections_json(r->detections, r->detection_count, 1e-3));
        if (want_pose) cJSON_AddItemToObject(o, "pose", mr_pose_line_json(f->index, f->timestamp, r));
        put_line(o, p->lines);
        cJSON_Delete(o);
    }
    if (want_pose) {
        cJSON *o = mr_pose_line_json(f->index, f->timestamp, r);
        if (p->out) ok = mr_jsonl_add(poses, o);
        else if (!p->print_detections) ok = put_line(o, p->lines);
        cJSON_Delete(o);
    }
    fflush(p->lines);
    return ok;
}

bool mr_batch_track(const mr_batch_track_params *p, mr_batch_track_stats *st, mr_error *err) {
    *st = (mr_batch_track_stats){0};
    const bool want_pose = mr_tracker_camera(p->tracker) && mr_tracker_markers(p->tracker);
    if (p->out && !want_pose) return mr_fail(err, MR_ERR_INVALID, "--out needs --camera and --markers (or a recording as input)");
    mr_jsonl poses = {0};
    bool ok = true;
    /* The first bad frame's message is held back: if no frame at all can be
     * processed (a single tiny image, say) it becomes the one error line. */
    char held[600] = "";
    const bool tty = p->progress && isatty(2);
    double shown = mr_time_now();
    while (ok && !mr_stop_requested() && (p->max_frames < 0 || st->frames < p->max_frames)) {
        mr_frame f;
        mr_read_status rs = mr_source_read(p->source, &f, err);
        if (rs == MR_READ_END) break;
        if (rs == MR_READ_ERROR) {
            ok = false;
            break;
        }
        st->frames++;
        if (tty && mr_time_now() - shown > 0.25) {
            fprintf(stderr, "\rtrack: frame %lld, %ld with a pose", (long long)f.index, st->with_pose);
            shown = mr_time_now();
        }
        mr_tracker_result r;
        mr_error fe = {0};
        if (!mr_tracker_frame(p->tracker, &f.image, f.timestamp, &r, &fe)) {
            /* One bad frame (too small, broken) does not end the run. */
            if (st->failed == 0 && st->frames == 1) snprintf(held, sizeof held, "frame %lld: %s", (long long)f.index, fe.msg);
            else fprintf(stderr, "mrcheck: track: warning: frame %lld: %s\n", (long long)f.index, fe.msg);
            st->failed++;
            continue;
        }
        if (held[0]) {
            fprintf(stderr, "mrcheck: track: warning: %s\n", held);
            held[0] = 0;
        }
        st->with_tags += r.detection_count > 0;
        st->with_pose += r.pose.valid;
        if (!frame_lines(p, want_pose, &f, &r, &poses)) ok = mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    if (tty) fprintf(stderr, "\r\033[K");
    if (ok && st->frames == 0) ok = mr_fail(err, MR_ERR_INVALID, "%s: no frames", p->input ? p->input : "input");
    else if (ok && st->failed == st->frames)
        ok = mr_fail(err, MR_ERR_INVALID, "no frame could be processed (%ld failed; %s)", st->failed,
                     held[0] ? held : "see above");
    if (ok && p->out) ok = mr_jsonl_save(&poses, p->out, err);
    st->interrupted = mr_stop_requested();
    if (ok && p->summary) /* on stderr: stdout may be the poses */
        fprintf(stderr, "track: %s%ld frames, %ld with tags, %ld with a pose, %ld failed%s%s\n",
                st->interrupted ? "interrupted after " : "", st->frames, st->with_tags, st->with_pose, st->failed,
                p->out ? "; wrote " : "", p->out ? p->out : "");
    mr_jsonl_free(&poses);
    return ok;
}
