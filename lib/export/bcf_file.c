/* `mrcheck bcf list` and `bcf answer` as library calls: read a BCF made
 * elsewhere, print its topics or answer one and write the topics out
 * again. The command only parses options. */
#include "export_internal.h"

#include <stdlib.h>

static bool read_warned(const char *path, mr_bcf *b, FILE *warn, mr_error *err) {
    if (!mr_bcf_read(path, b, err)) return false;
    for (int i = 0; warn && i < b->warning_count; i++) fprintf(warn, "mrcheck bcf: warning: %s\n", b->warnings[i]);
    return true;
}

bool mr_bcf_list_file(const char *path, const char *scene_path, FILE *out, FILE *warn, mr_error *err) {
    mr_bcf b;
    if (!read_warned(path, &b, warn, err)) return false;
    mr_scene *scene = NULL;
    bool ok = !scene_path || (scene = mr_scene_load(scene_path, NULL, err)) != NULL;
    if (ok) mr_bcf_print_list(&b, scene, out);
    mr_scene_destroy(&scene);
    mr_bcf_free(&b);
    return ok;
}

bool mr_bcf_answer_file(const mr_bcf_answer_file_params *p, mr_error *err) {
    if (!p->out) return mr_fail(err, MR_ERR_INVALID, "answer needs --out OUT.bcf");
    mr_bcf b;
    if (!read_warned(p->in, &b, p->warn, err)) return false;
    mr_bcf_topic *t = mr_bcf_find_topic(&b, p->topic, err);
    mr_bcf_answer_params a = p->answer;
    char *png = NULL;
    if (t && p->snapshot_path && !(png = mr_file_read(p->snapshot_path, &a.snapshot_size, 0, err))) t = NULL;
    a.snapshot = (const unsigned char *)png;
    bool ok = t && mr_bcf_answer(t, &a, err) && mr_bcf_write(&b, p->version, p->out, err);
    free(png);
    mr_bcf_free(&b);
    return ok;
}
