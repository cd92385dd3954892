/* Bench load: how fast gltfpack's files load against
 * the file they were made from. The instanced factory (mr_synth_build) and
 * the unique CAD-like one (mr_synth_cad_build) are written as .glb and
 * packed with gltfpack: default (KHR_mesh_quantization), -c and -cc
 * (EXT_meshopt_compression). Each load runs in a fresh child process, as a
 * user's first load does (fresh pages, nothing cached in the heap): CPU
 * seconds (user + system, from wait4), wall seconds of mr_scene_load alone,
 * MB/s of the file and the child's peak RSS. Files are loaded in turn,
 * round after round, and each column is the median of the rounds, so a
 * busy machine slows all files alike. Each round loads every file twice:
 * from the page cache (warm, what a second open of a file sees), then
 * after dropping it from there (cold_wall_s: written to disk and evicted
 * with posix_fadvise, so the load reads the disk as the first open after a
 * reboot, or from a share, does; where the file system keeps no such
 * cache, e.g. tmpfs, the two are alike). Draco files are not made:
 * gltfpack cannot write them. */
#include "bench_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

enum { k_scenes = 2, k_variants = 4, k_files = k_scenes * k_variants, k_max_runs = 99 };
static const char *const k_scene_name[k_scenes] = {"instanced", "unique"};
static const char *const k_variant_name[k_variants] = {"unpacked", "gltfpack", "gltfpack -c", "gltfpack -cc"};
static const char *const k_variant_flags[k_variants] = {NULL, "", "-c", "-cc"};

/* What a child reports through its pipe. */
typedef struct child_result {
    double wall_s, base_rss_mb;
    uint64_t triangles;
    int32_t nodes;
    bool ok;
    char msg[sizeof(((mr_error *)0)->msg)];
} child_result;

static double rss_now_mb(void) {
    FILE *f = fopen("/proc/self/statm", "r");
    long pages = 0, resident = 0;
    if (f) {
        if (fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
        fclose(f);
    }
    return resident * (double)sysconf(_SC_PAGESIZE) / 1048576.0;
}

/* One load in a child: *r from the child, CPU and peak RSS from wait4. */
static bool timed_load(const char *path, child_result *r, double *cpu_s, double *peak_mb, mr_error *err) {
    int fd[2];
    if (pipe(fd) != 0) return mr_fail(err, MR_ERR_IO, "bench load: pipe failed");
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]);
        close(fd[1]);
        return mr_fail(err, MR_ERR_IO, "bench load: fork failed");
    }
    if (pid == 0) {
        close(fd[0]);
        child_result c;
        memset(&c, 0, sizeof c);
        c.base_rss_mb = rss_now_mb();
        mr_error e = {0};
        double t0 = mr_time_now();
        mr_scene *s = mr_scene_load(path, NULL, &e);
        c.wall_s = mr_time_now() - t0;
        c.ok = s != NULL;
        if (s) {
            c.triangles = mr_scene_triangle_count(s);
            c.nodes = s->node_count;
        } else {
            snprintf(c.msg, sizeof c.msg, "%s", e.msg);
        }
        ssize_t w = write(fd[1], &c, sizeof c);
        _exit(w == (ssize_t)sizeof c ? 0 : 1); /* no atexit handlers, no scene teardown timed */
    }
    close(fd[1]);
    memset(r, 0, sizeof *r);
    ssize_t got = read(fd[0], r, sizeof *r);
    close(fd[0]);
    int status = 0;
    struct rusage ru;
    memset(&ru, 0, sizeof ru);
    if (wait4(pid, &status, 0, &ru) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0 || got != (ssize_t)sizeof *r)
        return mr_fail(err, MR_ERR_IO, "bench load: the child loading %s died", path);
    if (!r->ok) return mr_fail(err, MR_ERR_PARSE, "bench load: %s", r->msg);
    *cpu_s = (double)ru.ru_utime.tv_sec + ru.ru_utime.tv_usec * 1e-6 + (double)ru.ru_stime.tv_sec + ru.ru_stime.tv_usec * 1e-6;
    *peak_mb = ru.ru_maxrss / 1024.0; /* KiB on Linux */
    return true;
}

/* Drops path's pages from the page cache (written back first: dirty pages
 * stay). A hint: where it does nothing, the cold load is a warm one. */
static void evict(const char *path) {
    int fd = open(path, O_RDONLY);
    if (fd < 0) return;
    (void)fdatasync(fd);
    (void)posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    close(fd);
}

/* Writes the two factories, in a child so that their memory never counts
 * in the loads' children (which start as copies of this process). */
static bool make_factories(const mr_bench_load_params *p, char paths[k_scenes][4096], mr_error *err) {
    pid_t pid = fork();
    if (pid < 0) return mr_fail(err, MR_ERR_IO, "bench load: fork failed");
    if (pid == 0) {
        mr_error e = {0};
        mr_synth_params sp = MR_SYNTH_DEFAULTS;
        sp.halls = mr_synth_halls_for((uint64_t)p->triangles);
        mr_scene *s = mr_synth_build(&sp, &e);
        bool ok = s && mr_scene_save_glb(s, paths[0], &e);
        mr_scene_destroy(&s);
        mr_synth_cad_params cp = MR_SYNTH_CAD_DEFAULTS;
        cp.parts = mr_synth_cad_parts_for(&cp, p->unique_triangles);
        s = ok ? mr_synth_cad_build(&cp, &e) : NULL;
        ok = s && mr_scene_save_glb(s, paths[1], &e);
        mr_scene_destroy(&s);
        if (!ok) fprintf(stderr, "bench load: %s\n", e.msg);
        _exit(ok ? 0 : 1);
    }
    int status = 0;
    if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return mr_fail(err, MR_ERR_IO, "bench load: cannot write the factories into %s", p->out_dir);
    return true;
}

bool mr_bench_load(const mr_bench_load_params *params, mr_error *err) {
    mr_bench_load_params p = {MR_BENCH_LOAD_DEFAULTS};
    if (params) p = *params;
    if (!p.out_dir) p.out_dir = "bench-out";
    if (p.runs < 1 || p.runs > k_max_runs) return mr_fail(err, MR_ERR_INVALID, "bench load: runs must be in [1, %d]", k_max_runs);
    FILE *out = p.out;
    if (!mr_mkdirs(p.out_dir, err)) return false;
    if (system("command -v gltfpack >/dev/null 2>&1") != 0)
        return mr_fail(err, MR_ERR_UNSUPPORTED, "bench load: gltfpack is not installed (scripts/deps.sh installs it)");
    char path[k_files][4096], src[k_scenes][4096];
    for (int si = 0; si < k_scenes; si++) {
        char name[64];
        snprintf(name, sizeof name, "load_%s.glb", k_scene_name[si]);
        mr_path_join(p.out_dir, name, src[si], sizeof src[si]);
    }
    BENCH_PRINT(out, "bench load: writing the factories (%.3g M instanced, %.3g M unique triangles) ...\n",
                p.triangles / 1e6, p.unique_triangles / 1e6);
    if (!make_factories(&p, src, err)) return false;
    for (int si = 0; si < k_scenes; si++)
        for (int vi = 0; vi < k_variants; vi++) {
            char *dst = path[si * k_variants + vi];
            if (vi == 0) {
                snprintf(dst, sizeof path[0], "%s", src[si]);
                continue;
            }
            char name[64];
            snprintf(name, sizeof name, "load_%s_pack%d.glb", k_scene_name[si], vi);
            mr_path_join(p.out_dir, name, dst, sizeof path[0]);
            if (strchr(dst, '\'') || strchr(src[si], '\''))
                return mr_fail(err, MR_ERR_INVALID, "bench load: the output folder's name has a quote");
            char cmd[9000];
            snprintf(cmd, sizeof cmd, "gltfpack %s -i '%s' -o '%s' >/dev/null 2>&1", k_variant_flags[vi], src[si], dst);
            if (system(cmd) != 0) return mr_fail(err, MR_ERR_IO, "bench load: gltfpack %s failed on %s", k_variant_flags[vi], src[si]);
        }
    static double cpu[k_files][k_max_runs], wall[k_files][k_max_runs], peak[k_files][k_max_runs], base[k_files][k_max_runs],
        cold[k_files][k_max_runs];
    child_result last[k_files];
    BENCH_PRINT(out, "bench load: %d rounds over %d files, one fresh process per load, all from the page cache, then all "
                     "from disk\n", p.runs, k_files);
    /* All warm loads first, then all cold ones (each after dropping its
     * file from the page cache), the files in a new order each round (a
     * fixed seed: the same run is the same order). Measured: in a fixed
     * order, or with a warm load right after another file's cold one, a
     * file's warm median moved by 5-10 %. */
    uint32_t seed = 0x9E3779B9u;
    for (int phase = 0; phase < 2; phase++)
        for (int r = 0; r < p.runs; r++) {
            int order[k_files];
            for (int f = 0; f < k_files; f++) order[f] = f;
            for (int i = k_files - 1; i > 0; i--) {
                seed = seed * 1664525u + 1013904223u;
                int k = (int)((seed >> 8) % (uint32_t)(i + 1)), t = order[i];
                order[i] = order[k];
                order[k] = t;
            }
            for (int oi = 0; oi < k_files; oi++) {
                const int f = order[oi];
                if (phase == 0) {
                    if (!timed_load(path[f], &last[f], &cpu[f][r], &peak[f][r], err)) return false;
                    wall[f][r] = last[f].wall_s;
                    base[f][r] = last[f].base_rss_mb;
                } else {
                    child_result c;
                    double c_cpu, c_peak;
                    evict(path[f]);
                    if (!timed_load(path[f], &c, &c_cpu, &c_peak, err)) return false;
                    cold[f][r] = c.wall_s;
                }
            }
        }
    mr_csv *csv = mr_csv_create(err);
    if (!csv) return false;
    mr_csv_comment(csv, "bench load: each load in a fresh process; medians over the rounds");
    mr_csv_header(csv, "scene,variant,file_mb,runs,cpu_s,wall_s,mb_s,peak_rss_mb,base_rss_mb,triangles,nodes,cold_wall_s");
    BENCH_PRINT(out, "%-10s %-13s %9s %8s %8s %8s %10s %10s %10s %7s %8s\n", "scene", "file", "MB", "CPU s", "wall s", "MB/s",
                "peak RSS", "(base MB)", "triangles", "nodes", "cold s");
    double cpu_m[k_files], wall_m[k_files], cold_m[k_files];
    for (int f = 0; f < k_files; f++) {
        struct stat st;
        double mb = stat(path[f], &st) == 0 ? st.st_size / 1e6 : 0;
        double c = mr_median(cpu[f], p.runs), w = mr_median(wall[f], p.runs);
        double pk = mr_median(peak[f], p.runs), b = mr_median(base[f], p.runs);
        cpu_m[f] = c;
        wall_m[f] = w;
        cold_m[f] = mr_median(cold[f], p.runs);
        const char *scene = k_scene_name[f / k_variants], *variant = k_variant_name[f % k_variants];
        mr_csv_text(csv, scene);
        mr_csv_quoted(csv, variant);
        mr_csv_num(csv, "%.3f", mb);
        mr_csv_int(csv, p.runs);
        mr_csv_num(csv, "%.4f", c);
        mr_csv_num(csv, "%.4f", w);
        mr_csv_num(csv, "%.1f", w > 0 ? mb / w : 0);
        mr_csv_num(csv, "%.1f", pk);
        mr_csv_num(csv, "%.1f", b);
        mr_csv_int(csv, (long long)last[f].triangles);
        mr_csv_int(csv, last[f].nodes);
        mr_csv_num(csv, "%.4f", cold_m[f]);
        mr_csv_end_row(csv);
        BENCH_PRINT(out, "%-10s %-13s %9.1f %8.3f %8.3f %8.0f %10.1f %10.1f %10llu %7d %8.3f\n", scene, variant, mb, c, w,
                    w > 0 ? mb / w : 0, pk, b, (unsigned long long)last[f].triangles, (int)last[f].nodes, cold_m[f]);
    }
    char csv_path[4096], svg_path[4096];
    mr_path_join(p.out_dir, "bench_load.csv", csv_path, sizeof csv_path);
    mr_path_join(p.out_dir, "bench_load.svg", svg_path, sizeof svg_path);
    bool ok = mr_csv_save(csv, csv_path, err);
    mr_csv_destroy(&csv);
    char labels[k_files][64];
    const char *cats[k_files];
    for (int f = 0; f < k_files; f++) {
        snprintf(labels[f], sizeof labels[f], "%s, %s", k_scene_name[f / k_variants], k_variant_name[f % k_variants]);
        cats[f] = labels[f];
    }
    mr_plot_bar_set sets[3] = {{"CPU s (median)", cpu_m, NULL},
                               {"wall s (median)", wall_m, NULL},
                               {"wall s, read from disk (median)", cold_m, NULL}};
    ok = ok && mr_plot_bars(svg_path, "first load of a .glb and its gltfpack files (one process per load)", cats, k_files, sets, 3,
                            err);
    if (ok) BENCH_PRINT(out, "wrote %s and %s\n", csv_path, svg_path);
    return ok;
}
