/* `mrcheck demo`, the built-in job: the procedural hall as planned and as
 * built (demo_files.c), a synthetic recording and calibration set, camera
 * frames of the hall as built with the planned model over them at alpha 0.5
 * (mr_demo_render_frames), marks at the known discrepancies as BCF and a
 * report (demo_marks.c), and the ghosted views of the partition with the
 * pipes behind it as alpha / g0 / adaptive triptychs (Kalkofen et al.'s
 * comparison), in the no-conflict hall (coloured pipes) and the conflict
 * hall (pipes coloured like the partition). */
#include "mr_bench.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The calibration set and the recording; the recording first, as the marks
 * at the end are placed on its tracked frames. */
static bool demo_track(const char *dir, mr_error *err) {
    char path[4096], fl[4096];
    mr_path_join(dir, "calib", path, sizeof path);
    if (!mr_synth_calibration(path, 12, err)) return false;
    mr_path_join(dir, "recording", path, sizeof path);
    mr_path_join(path, "frames.jsonl", fl, sizeof fl);
    if (mr_file_exists(fl)) {
        /* A recording is never overwritten: say where the old one is. */
        printf("  recording exists, kept:        %s/\n", path);
        return true;
    }
    mr_synth_recording_params sp = {MR_SYNTH_RECORDING_DEFAULTS};
    sp.frames = 40; /* the path subsampled: the demo stays quick */
    sp.motion_blur = 1;
    sp.progress = isatty(2) && mr_log_get_level() < MR_LOG_INFO;
    mr_gfx g;
    bool ok = mr_gfx_open(&g, err) && mr_synth_recording(path, &sp, &g, err);
    mr_gfx_close(&g);
    if (!ok) return false;
    printf("  synthetic recording (tracked, with ground truth): %s/\n", path);
    printf("  calibration board and images:  %s/calib/\n", dir);
    return true;
}

/* Pastes n RGB8 images of one size side by side with a 4-pixel white gap. */
static bool side_by_side(const mr_image *imgs, int n, mr_image *out, mr_error *err) {
    const int gap = 4, w = imgs[0].width, h = imgs[0].height;
    if (!mr_image_alloc(out, n * w + (n - 1) * gap, h, 3, MR_PIX_U8, err)) return false;
    memset(out->data, 255, mr_image_bytes(out));
    for (int i = 0; i < n; i++)
        for (int y = 0; y < h; y++)
            memcpy((unsigned char *)out->data + ((size_t)y * out->width + (size_t)i * (w + gap)) * 3,
                   (const unsigned char *)imgs[i].data + (size_t)y * w * 3, (size_t)w * 3);
    return true;
}

/* One hall's three ghosting modes and their triptych. */
static bool ghost_case(const char *dir, mr_renderer *r, int c, mr_error *err) {
    static const char *const cases[2] = {"noconflict", "conflict"};
    static const mr_ghost_mode modes[3] = {MR_GHOST_ALPHA, MR_GHOST_G0, MR_GHOST_ADAPTIVE};
    static const char *const mode_names[3] = {"alpha", "g0", "adaptive"};
    char path[4096], sub[256];
    const mr_view view = mr_demo_view(0); /* the partition with the pipes behind it */
    mr_demo_params dp = MR_DEMO_DEFAULTS;
    dp.pipes_like_partition = c == 1;
    mr_demo_hall hall;
    bool ok = mr_demo_build_tagged(&dp, 0, &hall, err) && mr_renderer_set_scene(r, hall.planned, err);
    mr_image shots[3];
    memset(shots, 0, sizeof shots);
    for (int m = 0; ok && m < 3; m++) {
        mr_frame_params fp = MR_FRAME_DEFAULTS;
        fp.ghost.mode = modes[m];
        fp.ghost.stats = true;
        mr_frame_result res;
        ok = mr_render_frame(r, &view, &fp, &res, err);
        if (!ok) break;
        snprintf(sub, sizeof sub, "ghost/%s_%s.png", cases[c], mode_names[m]);
        mr_path_join(dir, sub, path, sizeof path);
        ok = mr_image_save_png(path, &res.color, err);
        printf("  ghost %-10s %-8s target reached %.3f region %.3f meanIM %.3f C %.3f mean |dL*| %.2f\n", cases[c],
               mode_names[m], res.ghost.target_reached, res.ghost.region_fraction, res.ghost.mean_importance,
               res.ghost.mean_contrast_missing, res.ghost.mean_abs_dL);
        shots[m] = res.color; /* keeps the pixels; res.depth/normal are empty */
    }
    if (ok) {
        mr_image tri;
        ok = side_by_side(shots, 3, &tri, err);
        snprintf(sub, sizeof sub, "ghost/%s_triptych.png", cases[c]);
        mr_path_join(dir, sub, path, sizeof path);
        ok = ok && mr_image_save_png(path, &tri, err);
        mr_image_free(&tri);
    }
    for (int m = 0; m < 3; m++) mr_image_free(&shots[m]);
    mr_renderer_set_scene(r, NULL, NULL);
    mr_demo_free(&hall);
    return ok;
}

static bool demo_ghost(const char *dir, mr_error *err) {
    char path[4096];
    mr_path_join(dir, "ghost", path, sizeof path);
    if (!mr_mkdirs(path, err)) return false;
    mr_gfx g;
    bool ok = mr_gfx_open(&g, err);
    for (int c = 0; ok && c < 2; c++) ok = ghost_case(dir, g.renderer, c, err);
    mr_gfx_close(&g);
    if (ok) printf("  ghosted views (alpha | g0 | adaptive): %s/ghost/{noconflict,conflict}_triptych.png\n", dir);
    return ok;
}

bool mr_demo_run(const char *dir, mr_error *err) {
    char path[4096];
    double t0 = mr_time_now();
    mr_view views[MR_DEMO_VIEWS];
    int discrepancy_count = 0;
    if (!mr_demo_write_files(dir, views, &discrepancy_count, err)) return false;
    double t_build = mr_time_now() - t0;
    if (!demo_track(dir, err)) return false;
    /* Render from the files just written, as a user's run would. */
    mr_scene *built = NULL, *planned = NULL;
    mr_path_join(dir, "scene_built.json", path, sizeof path);
    built = mr_scene_load(path, NULL, err);
    mr_path_join(dir, "scene_planned.json", path, sizeof path);
    planned = built ? mr_scene_load(path, NULL, err) : NULL;
    mr_gfx g = {0};
    bool ok = planned && mr_gfx_open(&g, err);
    ok = ok && mr_demo_render_frames(dir, &g, built, planned, views, err);
    ok = ok && mr_demo_marks(dir, &g, built, planned, err);
    mr_gfx_close(&g);
    uint64_t tri = planned ? mr_scene_triangle_count(planned) : 0;
    mr_scene_destroy(&built);
    mr_scene_destroy(&planned);
    if (!ok || !demo_ghost(dir, err)) return false;
    printf("demo hall: %llu triangles as planned, %d known discrepancies (%.1f s to build)\n", (unsigned long long)tri,
           discrepancy_count, t_build);
    printf("wrote %s/: hall_planned.glb hall_built.glb scene_*.json markers.json discrepancies.json camera.json\n", dir);
    printf("  camera frames (as built):     %s/frames/frame_000..%03d.png\n", dir, mr_demo_view_count() - 1);
    printf("  overlays (planned, alpha 0.5): %s/overlay/overlay_000..%03d.png\n", dir, mr_demo_view_count() - 1);
    printf("  virtual only (planned):        %s/virtual/virtual_000..%03d.png\n", dir, mr_demo_view_count() - 1);
    printf("done in %.1f s\n", mr_time_now() - t0);
    return true;
}
