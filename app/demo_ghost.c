/* The ghosted-view part of `mrcheck demo`: the partition with the pipes
 * behind it, in the no-conflict hall (coloured pipes) and the conflict hall
 * (pipes coloured like the partition), each as an alpha / g0 / adaptive
 * triptych (Kalkofen et al.'s comparison). */
#include "app.h"

#include <stdlib.h>
#include <string.h>

bool app_demo_ghost_hall(bool conflict, mr_demo_hall *hall, mr_error *err) {
    mr_demo_params dp = MR_DEMO_DEFAULTS;
    dp.pipes_like_partition = conflict;
    return mr_demo_build_tagged(&dp, 0, hall, err);
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

bool app_demo_ghost(const char *dir, mr_error *err) {
    static const char *const cases[2] = {"noconflict", "conflict"};
    static const mr_ghost_mode modes[3] = {MR_GHOST_ALPHA, MR_GHOST_G0, MR_GHOST_ADAPTIVE};
    static const char *const mode_names[3] = {"alpha", "g0", "adaptive"};
    char path[4096], sub[256];
    mr_path_join(dir, "ghost", path, sizeof path);
    if (!mr_mkdirs(path, err)) return false;
    app_gfx gfx;
    if (!app_gfx_open(&gfx, err)) return false;
    bool ok = true;
    mr_view view = mr_demo_view(0); /* the partition with the pipes behind it */
    for (int c = 0; ok && c < 2; c++) {
        mr_demo_hall hall;
        ok = app_demo_ghost_hall(c == 1, &hall, err) && mr_renderer_set_scene(gfx.renderer, hall.planned, err);
        mr_image shots[3];
        memset(shots, 0, sizeof shots);
        for (int m = 0; ok && m < 3; m++) {
            mr_frame_params fp = MR_FRAME_DEFAULTS;
            fp.ghost.mode = modes[m];
            fp.ghost.stats = true;
            mr_frame_result res;
            ok = mr_render_frame(gfx.renderer, &view, &fp, &res, err);
            if (!ok) break;
            snprintf(sub, sizeof sub, "ghost/%s_%s.png", cases[c], mode_names[m]);
            mr_path_join(dir, sub, path, sizeof path);
            ok = mr_image_save_png(path, &res.color, err);
            printf("  ghost %-10s %-8s target reached %.3f region %.3f meanIM %.3f C %.3f mean |dL*| %.2f\n", cases[c], mode_names[m], res.ghost.target_reached, res.ghost.region_fraction, res.ghost.mean_importance, res.ghost.mean_contrast_missing,
                   res.ghost.mean_abs_dL);
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
        mr_renderer_set_scene(gfx.renderer, NULL, NULL);
        mr_demo_free(&hall);
    }
    app_gfx_close(&gfx);
    if (ok) printf("  ghosted views (alpha | g0 | adaptive): %s/ghost/{noconflict,conflict}_triptych.png\n", dir);
    return ok;
}
