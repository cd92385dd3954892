/* mrcheck — mixed-reality discrepancy checks for factory planning. */
#include "app.h"
#include "app_track.h"
#include "mr_session.h"

#include <string.h>

static const struct {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *help;
} k_commands[] = {
    {"demo", cmd_demo, "build the demo hall (as planned / as built), render camera frames and overlays"},
    {"render", cmd_render, "render one headless frame of a scene from a view"},
    {"view", cmd_view, "the interactive check: overlay window with a touch UI, live or replayed"},
    {"bench", cmd_bench, "measure run time: bench frame, ao, ghost, tracking, scene"},
    {"synth", cmd_synth, "synthetic recording of the demo hall with ground truth (or a calibration set)"},
    {"track", cmd_track, "AprilTag detection and camera pose per frame (V4L2, video, images, recording)"},
    {"record", cmd_record, "track a camera or video and write a crash-safe recording as it goes"},
    {"calibrate", cmd_calibrate, "camera intrinsics from images of an AprilTag grid board (OpenCV)"},
    {"replay", cmd_replay, "render the overlay of a recording's frames headless (deterministic)"},
    {"factory", cmd_factory, "write a big synthetic factory (1M..20M triangles) as .glb"},
    {"study", cmd_study, "pairwise comparison studies: stimuli, plan, run (window), analyze"},
    {"map", cmd_map, "the marker map from photos: bundle adjustment, per-tag sigma, control points"},
    {"measure", cmd_measure, "triangulate a feature tapped in several recorded frames; distance to the plan with sigma"},
    /* Findings as BCF and a report */
    {"export", cmd_export, "a session's marks as BCF 2.1/3.0 topics or a self-contained HTML report"},
    {"bcf", cmd_bcf, "topics of a BCF made elsewhere: list them, answer one (comment, status, snapshot)"},
    {"tags", cmd_sheets, "printable AprilTag sheets (PDF, PNG at a stated dpi) and the marker-map template"},
    {"board", cmd_sheets, "a printable calibration board for calibrate (PDF, PNG) and its board.json"},
    {"hall", cmd_hall, "a hall folder: plan, camera, marker map, tolerances and sessions in one place"},
};

static void usage(FILE *f) {
    fprintf(f, "usage: mrcheck <command> [options]   (mrcheck <command> --help for details)\n\ncommands:\n");
    for (size_t i = 0; i < sizeof k_commands / sizeof k_commands[0]; i++)
        fprintf(f, "  %-10s %s\n", k_commands[i].name, k_commands[i].help);
}

int main(int argc, char **argv) {
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    if (strcmp(argv[1], "--help") == 0 || strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "help") == 0) {
        usage(stdout);
        return 0;
    }
    if (strcmp(argv[1], "--version") == 0) {
        printf("mrcheck 0.1.0\n");
        return 0;
    }
    for (size_t i = 0; i < sizeof k_commands / sizeof k_commands[0]; i++)
        if (strcmp(argv[1], k_commands[i].name) == 0) return mr_hall_run(k_commands[i].run, argc, argv); /* HALL stands for its files */
    fprintf(stderr, "mrcheck: unknown command '%s' (see mrcheck --help)\n", argv[1]);
    return 2;
}
