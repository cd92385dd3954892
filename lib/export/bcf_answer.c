/* Topics made elsewhere, on site: a summary line per topic (with how many
 * of its components the scene has), and the planner's answer (a comment,
 * a status, a new snapshot) added to a topic, its GUIDs kept. */
#include "export_internal.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Distinct components of a topic's viewpoints (by IfcGuid, else by
 * AuthoringToolId); *resolved of them name an element or node of scene. */
static int topic_components(const mr_bcf_topic *t, const mr_scene *scene, int *resolved) {
    int n = 0;
    *resolved = 0;
    const mr_bcf_component **seen = NULL;
    int cap = 0;
    for (int v = 0; v < t->viewpoint_count; v++) {
        const mr_bcf_viewpoint *vp = &t->viewpoints[v];
        for (int list = 0; list < 3 + vp->coloring_count; list++) {
            const mr_bcf_component *c = list == 0 ? vp->selection : list == 1 ? vp->exceptions : list == 2 ? NULL
                                        : vp->colorings[list - 3].items;
            int cn = list == 0 ? vp->selection_count : list == 1 ? vp->exception_count : list == 2 ? 0
                     : vp->colorings[list - 3].count;
            for (int i = 0; i < cn; i++) {
                bool dup = false;
                for (int k = 0; k < n && !dup; k++)
                    dup = c[i].ifc_guid[0] ? strcmp(seen[k]->ifc_guid, c[i].ifc_guid) == 0
                                           : !seen[k]->ifc_guid[0] && strcmp(seen[k]->authoring_id, c[i].authoring_id) == 0;
                if (dup) continue;
                if (n == cap) {
                    int nc = cap ? cap * 2 : 16;
                    const mr_bcf_component **g = realloc(seen, (size_t)nc * sizeof *g);
                    if (!g) break;
                    seen = g;
                    cap = nc;
                }
                seen[n++] = &c[i];
                if (!scene) continue;
                bool found = c[i].ifc_guid[0] && mr_scene_node_of_guid(scene, c[i].ifc_guid) >= 0;
                for (int32_t k = 0; !found && !c[i].ifc_guid[0] && c[i].authoring_id[0] && k < scene->node_count; k++)
                    found = strcmp(scene->nodes[k].name, c[i].authoring_id) == 0;
                *resolved += found;
            }
        }
    }
    free(seen);
    return n;
}

void mr_bcf_print_list(const mr_bcf *b, const mr_scene *scene, FILE *out) {
    for (int i = 0; i < b->topic_count; i++) {
        const mr_bcf_topic *t = &b->topics[i];
        int resolved = 0, n = topic_components(t, scene, &resolved);
        int cams = 0;
        for (int v = 0; v < t->viewpoint_count; v++) cams += t->viewpoints[v].camera_kind != MR_BCF_CAMERA_NONE;
        fprintf(out, "%d\t%s\t%s\t%s\tviewpoints %d (%d with a camera)\tcomments %d\tcomponents %d", i + 1, t->guid,
                t->status[0] ? t->status : "-", t->title[0] ? t->title : "(untitled)", t->viewpoint_count, cams,
                t->comment_count, n);
        if (scene) fprintf(out, "\tin the scene %d of %d", resolved, n);
        fputc('\n', out);
    }
}

static void now_date(char *out, size_t n) {
    time_t t = time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(out, n, "%Y-%m-%dT%H:%M:%SZ", &tm);
}

bool mr_bcf_answer(mr_bcf_topic *t, const mr_bcf_answer_params *a, mr_error *err) {
    const char *author = a->author && a->author[0] ? a->author : "mrcheck";
    char date[32];
    now_date(date, sizeof date);
    char key[512];
    snprintf(key, sizeof key, "%s|%s|%d|%d", t->guid, date, t->comment_count, t->viewpoint_count);
    mr_bcf_viewpoint *nv = NULL;
    if (a->snapshot && a->snapshot_size > 0) {
        /* The new snapshot as a viewpoint of its own: the camera and
         * components of the topic's first viewpoint (where the planner
         * was sent), the picture from site. */
        nv = mr_bcf_add_viewpoint(t);
        if (!nv) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        if (t->viewpoint_count > 1) {
            const mr_bcf_viewpoint *f = &t->viewpoints[0];
            nv->camera_kind = f->camera_kind;
            nv->camera = f->camera;
            nv->view_to_world_scale = f->view_to_world_scale;
            nv->has_components = f->has_components;
            nv->default_visibility = f->default_visibility;
            for (int i = 0; i < f->selection_count; i++)
                if (!mr_bcf_add_component(&nv->selection, &nv->selection_count, &f->selection[i]))
                    return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        }
        nv->snapshot = malloc(a->snapshot_size);
        if (!nv->snapshot) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        memcpy(nv->snapshot, a->snapshot, a->snapshot_size);
        nv->snapshot_size = a->snapshot_size;
        mr_bcf_guid(key, strlen(key), 6, nv->guid);
    }
    if ((a->comment && a->comment[0]) || nv) {
        mr_bcf_comment *c = mr_bcf_add_comment(t);
        if (!c) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        mr_bcf_guid(key, strlen(key), 7, c->guid);
        snprintf(c->date, sizeof c->date, "%s", date);
        snprintf(c->author, sizeof c->author, "%s", author);
        const char *text = a->comment && a->comment[0] ? a->comment : "New snapshot from site.";
        free(c->text);
        c->text = malloc(strlen(text) + 1);
        if (!c->text) return mr_fail(err, MR_ERR_NOMEM, "out of memory");
        strcpy(c->text, text);
        if (nv) snprintf(c->viewpoint_guid, sizeof c->viewpoint_guid, "%s", nv->guid);
    }
    if (a->status && a->status[0]) snprintf(t->status, sizeof t->status, "%s", a->status);
    snprintf(t->modified_date, sizeof t->modified_date, "%s", date);
    snprintf(t->modified_author, sizeof t->modified_author, "%s", author);
    return true;
}
