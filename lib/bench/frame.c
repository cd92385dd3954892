/* mrcheck bench frame: median GPU and CPU ms per pass of one frame. */
#include "bench_internal.h"

#include <stdlib.h>
#include <string.h>

/* A horizontal bar chart of median GPU and CPU ms per pass. */
static bool write_svg(const char *path, const char *title, int n, const char *const *names, const double *gpu,
                      const double *cpu, mr_error *err) {
    const mr_plot_bar_set sets[2] = {{"GPU ms (median)", gpu, "#3b6fb6"}, {"CPU ms", cpu, "#e08a2c"}};
    return mr_plot_bars(path, title, names, n, sets, 2, err);
}

static void csv_row(mr_csv *csv, const char *pass, double gpu_ms, double cpu_ms, long frames, int w, int h,
                    uint64_t tris, uint32_t draws) {
    mr_csv_text(csv, pass);
    mr_csv_num(csv, "%.4f", gpu_ms);
    mr_csv_num(csv, "%.4f", cpu_ms);
    mr_csv_int(csv, frames);
    mr_csv_int(csv, w);
    mr_csv_int(csv, h);
    mr_csv_int(csv, (long long)tris);
    mr_csv_int(csv, draws);
    mr_csv_end_row(csv);
}

bool mr_bench_frame(const mr_bench_frame_params *params, mr_error *err) {
    mr_bench_frame_params p = {MR_BENCH_FRAME_DEFAULTS};
    if (params) p = *params;
    const mr_bench_frame_params dflt = {MR_BENCH_FRAME_DEFAULTS};
    if (!p.out_dir) p.out_dir = dflt.out_dir;
    if (p.width <= 0 || p.height <= 0) p.width = dflt.width, p.height = dflt.height;
    if (p.frames <= 0) p.frames = dflt.frames;
    const int w = p.width, h = p.height;
    const long frames = p.frames;
    const char *out_dir = p.out_dir;
    FILE *out = p.out;
    if (!bench_gpu_check(&p.gfx, "bench frame", err)) return false;
    mr_view view = p.view ? *p.view : mr_demo_view(0);
    mr_scene *scene = NULL;
    mr_demo_hall hall;
    memset(&hall, 0, sizeof hall);
    double t0 = mr_time_now();
    if (p.scene) {
        scene = mr_scene_load(p.scene, NULL, err);
        if (!scene) return false;
    } else {
        if (!mr_demo_build_tagged(NULL, 0, &hall, err)) return false;
        scene = hall.planned;
    }
    double load_ms = (mr_time_now() - t0) * 1e3;
    mr_image video = {0};
    bool ok = true;
    if (!p.video && !p.no_video) {
        ok = mr_image_alloc(&video, view.camera.width, view.camera.height, 3, MR_PIX_U8, err);
        mr_rng rng;
        mr_rng_seed(&rng, 7);
        for (size_t i = 0; ok && i < mr_image_bytes(&video); i++) ((unsigned char *)video.data)[i] = (unsigned char)(mr_rng_u64(&rng) >> 56);
    }
    const mr_bench_gpu gfx = p.gfx;
    ok = ok && mr_mkdirs(out_dir, err) && mr_renderer_set_scene(gfx.renderer, scene, err);
    int npass = 0;
    const char *names[MR_MAX_PASSES + 1];
    double *gpu = NULL, *cpu = NULL, *total = NULL;
    if (ok) {
        gpu = calloc((size_t)frames * (MR_MAX_PASSES + 1), sizeof *gpu);
        cpu = calloc((size_t)frames * (MR_MAX_PASSES + 1), sizeof *cpu);
        total = calloc((size_t)frames, sizeof *total);
        ok = gpu && cpu && total;
        if (!ok) mr_fail(err, MR_ERR_NOMEM, "out of memory");
    }
    mr_frame_params fp = MR_FRAME_DEFAULTS;
    fp.width = w;
    fp.height = h;
    fp.timing = true;
    fp.video = p.video ? p.video : video.data ? &video : NULL;
    uint64_t tris = 0;
    uint32_t draws = 0;
    for (long f = -3; ok && f < frames; f++) {
        mr_frame_result res;
        double ft = mr_time_now();
        ok = mr_render_frame(gfx.renderer, &view, &fp, &res, err);
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
    if (ok) {
        double mg[MR_MAX_PASSES + 1], mc[MR_MAX_PASSES + 1], gsum = 0;
        mr_csv *csv = mr_csv_create(err);
        mr_csv_header(csv, "pass,gpu_ms_median,cpu_ms_median,frames,width,height,triangles,draw_calls");
        BENCH_PRINT(out, "bench frame: %s, %dx%d, %ld frames (median), %llu triangles, %u draw calls, scene load %.0f ms\n",
               mr_gpu_description(gfx.gpu), w, h, frames, (unsigned long long)tris, draws, load_ms);
        BENCH_PRINT(out, "  %-10s %10s %10s\n", "pass", "GPU ms", "CPU ms");
        for (int k = 0; k < npass; k++) {
            mg[k] = mr_median(&gpu[(size_t)k * frames], (int)frames);
            mc[k] = mr_median(&cpu[(size_t)k * frames], (int)frames);
            gsum += mg[k];
            BENCH_PRINT(out, "  %-10s %10.2f %10.2f\n", names[k], mg[k], mc[k]);
            csv_row(csv, names[k], mg[k], mc[k], frames, w, h, tris, draws);
        }
        double mt = mr_median(total, (int)frames);
        BENCH_PRINT(out, "  %-10s %10.2f %10.2f   (frame incl. readback, wall clock)\n", "total", gsum, mt);
        csv_row(csv, "frame_wall", gsum, mt, frames, w, h, tris, draws);
        names[npass] = "frame";
        mg[npass] = gsum;
        mc[npass] = mt;
        char path[4096], title[256];
        mr_path_join(out_dir, "bench_frame.csv", path, sizeof path);
        ok = csv && mr_csv_save(csv, path, err);
        mr_csv_destroy(&csv);
        snprintf(title, sizeof title, "mrcheck bench frame: %dx%d, %llu triangles, median of %ld", w, h,
                 (unsigned long long)tris, frames);
        mr_path_join(out_dir, "bench_frame.svg", path, sizeof path);
        ok = ok && write_svg(path, title, npass + 1, names, mg, mc, err);
        if (ok) BENCH_PRINT(out, "wrote %s/bench_frame.csv and bench_frame.svg\n", out_dir);
    }
    free(gpu);
    free(cpu);
    free(total);
    mr_renderer_set_scene(gfx.renderer, NULL, NULL); /* the scene goes now */
    mr_image_free(&video);
    if (hall.planned) mr_demo_free(&hall);
    else mr_scene_destroy(&scene);
    return ok;
}

