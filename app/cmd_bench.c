/* mrcheck bench: measurements (CSV + SVG plot), never pass/fail. */
#include "app.h"
#include "app_track.h"

#include <stdlib.h>
#include <string.h>

/* A horizontal bar chart of median GPU and CPU ms per pass. */
static bool write_svg(const char *path, const char *title, int n, const char *const *names, const double *gpu,
                      const double *cpu, mr_error *err) {
    double maxv = 1e-9;
    for (int i = 0; i < n; i++) {
        if (gpu[i] > maxv) maxv = gpu[i];
        if (cpu[i] > maxv) maxv = cpu[i];
    }
    int W = 720, row = 44, top = 50, H = top + row * n + 40;
    size_t cap = 8192 + (size_t)n * 1024;
    char *s = malloc(cap);
    if (!s) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
    int len = snprintf(s, cap,
                       "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-family=\"sans-serif\" "
                       "font-size=\"13\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n"
                       "<text x=\"10\" y=\"22\" font-size=\"15\">%s</text>\n"
                       "<rect x=\"470\" y=\"32\" width=\"12\" height=\"10\" fill=\"#3b6fb6\"/><text x=\"486\" y=\"42\">GPU ms (median)</text>\n"
                       "<rect x=\"600\" y=\"32\" width=\"12\" height=\"10\" fill=\"#e08a2c\"/><text x=\"616\" y=\"42\">CPU ms</text>\n",
                       W, H, title);
    for (int i = 0; i < n; i++) {
        int y = top + i * row;
        double wg = 480.0 * gpu[i] / maxv, wc = 480.0 * cpu[i] / maxv;
        len += snprintf(s + len, cap - (size_t)len,
                        "<text x=\"10\" y=\"%d\">%s</text>\n"
                        "<rect x=\"130\" y=\"%d\" width=\"%.1f\" height=\"14\" fill=\"#3b6fb6\"/>"
                        "<text x=\"%.1f\" y=\"%d\">%.2f</text>\n"
                        "<rect x=\"130\" y=\"%d\" width=\"%.1f\" height=\"14\" fill=\"#e08a2c\"/>"
                        "<text x=\"%.1f\" y=\"%d\">%.2f</text>\n",
                        y + 18, names[i], y, wg, 136 + wg, y + 12, gpu[i], y + 16, wc, 136 + wc, y + 28, cpu[i]);
    }
    len += snprintf(s + len, cap - (size_t)len, "</svg>\n");
    bool ok = mr_file_write_atomic(path, s, (size_t)len, err);
    free(s);
    return ok;
}

static int bench_frame(int argc, char **argv) {
    static const char *cmd = "bench frame";
    app_opt opts[] = {
        {"scene", "FILE", "glTF/GLB or scene config (default: the demo hall as planned)", NULL},
        {"view", "VIEW.json", "view (default: the demo's first viewpoint)", NULL},
        {"size", "WxH", "output size (default 1024x768)", NULL},
        {"frames", "N", "frames to time after 3 warm-up frames (default 30)", NULL},
        {"video", "IMG", "camera frame to overlay (default: a synthetic frame, so the overlay pass runs)", NULL},
        {"no-video", NULL, "no overlay pass", NULL},
        {"out", "DIR", "write bench_frame.csv and bench_frame.svg there (default bench-out)", NULL},
        {"verbose", NULL, "more output", NULL},
        {"quiet", NULL, "errors only", NULL},
        {NULL, NULL, NULL, NULL},
    };
    bool help;
    if (!app_parse(argc, argv, 3, opts, NULL, 0, NULL, "usage: mrcheck bench frame [--scene S] [--view V] [--size WxH] [--frames N] [--out DIR]", &help))
        return 2;
    if (help) return 0;
    app_log_level(opts);
    int w = 1024, h = 768;
    long frames = 30;
    if (app_get(opts, "size") && !app_size("size", app_get(opts, "size"), &w, &h)) return 2;
    if (app_get(opts, "frames") && !app_int("frames", app_get(opts, "frames"), 1, 100000, &frames)) return 2;
    const char *out_dir = app_get(opts, "out") ? app_get(opts, "out") : "bench-out";

    mr_error err = {0};
    mr_view view = mr_demo_view(0);
    if (app_get(opts, "view") && !mr_view_load(app_get(opts, "view"), &view, &err)) return app_error(cmd, &err);
    mr_scene *scene = NULL;
    mr_demo_hall hall;
    memset(&hall, 0, sizeof hall);
    double t0 = mr_time_now();
    if (app_get(opts, "scene")) {
        scene = mr_scene_load(app_get(opts, "scene"), NULL, &err);
        if (!scene) return app_error(cmd, &err);
    } else {
        if (!mr_demo_build_tagged(NULL, 0, &hall, &err)) return app_error(cmd, &err);
        scene = hall.planned;
    }
    double load_ms = (mr_time_now() - t0) * 1e3;
    mr_image video = {0};
    bool ok = true;
    if (app_get(opts, "video")) {
        ok = mr_image_load(app_get(opts, "video"), 3, &video, &err);
    } else if (!app_flag(opts, "no-video")) {
        ok = mr_image_alloc(&video, view.camera.width, view.camera.height, 3, MR_PIX_U8, &err);
        mr_rng rng;
        mr_rng_seed(&rng, 7);
        for (size_t i = 0; ok && i < mr_image_bytes(&video); i++) ((unsigned char *)video.data)[i] = (unsigned char)(mr_rng_u64(&rng) >> 56);
    }
    app_gfx gfx = {0};
    ok = ok && mr_mkdirs(out_dir, &err) && app_gfx_open(&gfx, &err) && mr_renderer_set_scene(gfx.renderer, scene, &err);
    int npass = 0;
    const char *names[MR_MAX_PASSES + 1];
    double *gpu = NULL, *cpu = NULL, *total = NULL;
    if (ok) {
        gpu = calloc((size_t)frames * (MR_MAX_PASSES + 1), sizeof *gpu);
        cpu = calloc((size_t)frames * (MR_MAX_PASSES + 1), sizeof *cpu);
        total = calloc((size_t)frames, sizeof *total);
        ok = gpu && cpu && total;
        if (!ok) mr_fail(&err, MR_ERR_NOMEM, "out of memory");
    }
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = w;
    fp.height = h;
    fp.timing = true;
    fp.video = video.data ? &video : NULL;
    uint64_t tris = 0;
    uint32_t draws = 0;
    for (long f = -3; ok && f < frames; f++) {
        mr_frame_result res;
        double ft = mr_time_now();
        ok = mr_render_frame(gfx.renderer, &view, &fp, &res, &err);
        if (!ok) break;
        if (f < 0) { mr_frame_result_free(&res); continue; } /* warm-up: shader compiles, first uploads */
        total[f] = (mr_time_now() - ft) * 1e3;
        npass = res.pass_count;
        for (int k = 0; k < res.pass_count; k++) {
            names[k] = res.passes[k];
            gpu[(size_t)k * frames + f] = res.gpu_ms[k];
            cpu[(size_t)k * frames + f] = res.cpu_ms[k];
        }
        tris = res.triangles;
        draws = res.draw_calls;
        mr_frame_result_free(&res);
    }
    int rc = 0;
    if (ok) {
        double mg[MR_MAX_PASSES + 1], mc[MR_MAX_PASSES + 1], gsum = 0;
        char csv[8192];
        int len = snprintf(csv, sizeof csv, "pass,gpu_ms_median,cpu_ms_median,frames,width,height,triangles,draw_calls\n");
        printf("bench frame: %s, %dx%d, %ld frames (median), %llu triangles, %u draw calls, scene load %.0f ms\n",
               mr_gpu_description(gfx.gpu), w, h, frames, (unsigned long long)tris, draws, load_ms);
        printf("  %-10s %10s %10s\n", "pass", "GPU ms", "CPU ms");
        for (int k = 0; k < npass; k++) {
            mg[k] = mr_median(&gpu[(size_t)k * frames], (int)frames);
            mc[k] = mr_median(&cpu[(size_t)k * frames], (int)frames);
            gsum += mg[k];
            printf("  %-10s %10.2f %10.2f\n", names[k], mg[k], mc[k]);
            len += snprintf(csv + len, sizeof csv - (size_t)len, "%s,%.4f,%.4f,%ld,%d,%d,%llu,%u\n", names[k], mg[k], mc[k],
                            frames, w, h, (unsigned long long)tris, draws);
        }
        double mt = mr_median(total, (int)frames);
        printf("  %-10s %10.2f %10.2f   (frame incl. readback, wall clock)\n", "total", gsum, mt);
        len += snprintf(csv + len, sizeof csv - (size_t)len, "frame_wall,%.4f,%.4f,%ld,%d,%d,%llu,%u\n", gsum, mt, frames,
                        w, h, (unsigned long long)tris, draws);
        names[npass] = "frame";
        mg[npass] = gsum;
        mc[npass] = mt;
        char path[4096], title[256];
        mr_path_join(out_dir, "bench_frame.csv", path, sizeof path);
        ok = mr_file_write_atomic(path, csv, (size_t)len, &err);
        snprintf(title, sizeof title, "mrcheck bench frame: %dx%d, %llu triangles, median of %ld", w, h,
                 (unsigned long long)tris, frames);
        mr_path_join(out_dir, "bench_frame.svg", path, sizeof path);
        ok = ok && write_svg(path, title, npass + 1, names, mg, mc, &err);
        if (ok) printf("wrote %s/bench_frame.csv and bench_frame.svg\n", out_dir);
    }
    if (!ok) rc = app_error(cmd, &err);
    free(gpu);
    free(cpu);
    free(total);
    app_gfx_close(&gfx);
    mr_image_free(&video);
    if (hall.planned) mr_demo_free(&hall);
    else mr_scene_destroy(&scene);
    return rc;
}

int cmd_bench(int argc, char **argv) {
    if (argc >= 3 && strcmp(argv[2], "frame") == 0) return bench_frame(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "scene") == 0) return bench_scene(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "ao") == 0) return bench_ao(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "ghost") == 0) return app_bench_ghost(argc, argv);
    if (argc >= 3 && strcmp(argv[2], "tracking") == 0) return bench_tracking(argc, argv);
    if (argc >= 3 && (strcmp(argv[2], "--help") == 0 || strcmp(argv[2], "-h") == 0)) {
        printf("usage: mrcheck bench {frame,ao,ghost,tracking,scene} [options]   (mrcheck bench NAME --help)\n");
        return 0;
    }
    fprintf(stderr, "mrcheck: bench: unknown or missing benchmark%s%s (available: frame, ao, ghost, tracking, scene)\n", argc >= 3 ? " " : "",
            argc >= 3 ? argv[2] : "");
    return 2;
}
