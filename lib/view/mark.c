/* The view's marking and render decisions as plain data (no GL, no
 * window): where a tap lands in the picture and the camera image, where a
 * finished measurement's mark goes, which shadow method a frame uses and
 * the frame parameters the settings give. run.c carries them out. */
#include "view_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

bool mr_view_window_to_image(mr_ui_rect image_rect, int rw, int rh, double x, double y, double *u, double *v) {
    mr_ui_rect r = image_rect;
    if (!mr_ui_rect_contains(r, (float)x, (float)y)) return false;
    *u = (x - r.x) * rw / r.w - 0.5;
    *v = (y - r.y) * rh / r.h - 0.5;
    return true;
}

void mr_view_draw_pin(mr_image *img, double u, double v) {
    if (!img || !img->data || img->channels != 3 || img->type != MR_PIX_U8) return;
    const double r_in = MR_VIEW_PIN_R, r_out = 7.0;
    int x0 = (int)floor(u - r_out - 1), x1 = (int)ceil(u + r_out + 1), y0 = (int)floor(v - r_out - 1),
        y1 = (int)ceil(v + r_out + 1);
    for (int y = y0 < 0 ? 0 : y0; y <= y1 && y < img->height; y++)
        for (int x = x0 < 0 ? 0 : x0; x <= x1 && x < img->width; x++) {
            double d = hypot(x - u, y - v);
            if (d > r_out) continue;
            uint8_t *p = (uint8_t *)img->data + ((size_t)y * (size_t)img->width + (size_t)x) * 3;
            bool in = d <= r_in;
            p[0] = 255, p[1] = in ? 0 : 255, p[2] = 255;
        }
}

void mr_view_image_to_camera(const mr_camera *cam, int rw, int rh, double u, double v, double *px, double *py) {
    *px = (u + 0.5) * cam->width / rw - 0.5;
    *py = (v + 0.5) * cam->height / rh - 0.5;
}

void mr_view_measure_mark(const mr_camera *cam, int image_w, int image_h, const mr_dmat4 *world_from_camera,
                          mr_dvec3 measured, const mr_view_planned *planned, mr_view_mark_at *out) {
    /* The picture is shown undistorted: project with the pinhole. */
    mr_camera pin = mr_camera_resized(cam, image_w, image_h);
    memset(pin.dist, 0, sizeof pin.dist);
    double u = pin.cx, v = pin.cy;
    if (!mr_project_point(&pin, world_from_camera, measured, &u, &v)) u = pin.cx, v = pin.cy;
    memset(&out->pick, 0, sizeof out->pick);
    out->pick.node = -1;
    if (planned && planned->found) {
        /* The mark's point: where the model is nearest to what was built. */
        mr_dmat4 cfw = mr_m4_invert_rigid(world_from_camera);
        out->pick = (mr_pick){true, planned->point, mr_m4_point(&cfw, planned->point).z, planned->node, planned->layer};
    }
    out->px = u;
    out->py = v;
    out->note_u = (float)((u + 0.5) / pin.width);
    out->note_v = (float)((v + 0.5) / pin.height);
}

mr_shadow_method mr_view_shadow_choose(mr_view_shadow_choice *c, mr_shadow_method setting, const char *scene_method) {
    mr_shadow_method m = setting;
    if (m != c->start) c->keyed = true;
    if (c->keyed) return m;
    if (c->given) return c->flag;
    if (scene_method && scene_method[0] && !mr_shadow_method_parse(scene_method, &m)) m = MR_SHADOW_OFF;
    return m;
}

void mr_view_frame_params(const mr_view_settings *s, mr_shadow_method shadows, mr_frame_params *fp) {
    fp->hide_hidden_layer = s->hide_hidden;
    fp->ao.method = mr_view_ao(s);
    fp->ghost.mode = mr_view_ghost(s);
    fp->shadow.method = shadows;
}

void mr_view_state_add_window(cJSON *j, const mr_view_window_state *w) {
    cJSON_AddNumberToObject(j, "marks", w->marks);
    cJSON_AddNumberToObject(j, "snapshots", w->snapshots);
    cJSON_AddStringToObject(j, "source_state", w->source_state ? w->source_state : "");
    cJSON_AddStringToObject(j, "source_message", w->source_message ? w->source_message : "");
    cJSON_AddStringToObject(j, "scene_message", w->scene_message ? w->scene_message : "");
    if (w->screen && w->screen->data) {
        double mean, std;
        mr_image_u8_stats(w->screen, &mean, &std);
        cJSON_AddNumberToObject(j, "screen_mean", mean);
        cJSON_AddNumberToObject(j, "screen_std", std);
    }
    if (w->have_render) {
        cJSON_AddNumberToObject(j, "render_width", w->render_w);
        cJSON_AddNumberToObject(j, "render_height", w->render_h);
        cJSON_AddNumberToObject(j, "diff_to_model", w->diff_to_model);
        cJSON_AddNumberToObject(j, "diff_to_video", w->diff_to_video);
    }
}

void mr_view_render_setup(const mr_view_settings *s, const mr_camera *cam, const mr_capture_frame *f, bool frozen,
                          mr_shadow_method shadows, bool ao_temporal, bool had_pose, int rw, int rh, mr_view *view,
                          mr_frame_params *fp, mr_view_render_choice *c) {
    view->camera = mr_camera_resized(cam, f->image.width, f->image.height);
    view->world_from_camera = f->pose;
    *fp = (mr_frame_params)MR_FRAME_DEFAULTS;
    fp->width = rw;
    fp->height = rh;
    fp->video = s->show_video ? &f->image : NULL;
    mr_view_frame_params(s, shadows, fp);
    fp->ao.temporal = ao_temporal;
    fp->ao.temporal_reset = !had_pose; /* tracking (re)acquired: no history across the gap */
    *c = mr_view_render_policy(s, f->have_pose, f->pose_valid, frozen);
    fp->alpha = c->alpha;
    if (!c->use_pose) view->world_from_camera = mr_m4_look_at_cv(mr_v3(0, 0, 0), mr_v3(0, 0, 1), mr_v3(0, -1, 0));
}

cJSON *mr_view_mark_line(const mr_capture_frame *f, const mr_view_mark_words *w, double px, double py,
                         const mr_pick *pick, const mr_scene *scene, const mr_measurement *measured,
                         const mr_verdict *verdict) {
    mr_annotation m;
    bool cat = w->category >= 0 && w->category < MR_MARK_CATEGORY_COUNT;
    mr_annotation_from_frame(&m, f, cat ? mr_mark_categories[w->category] : "", (double)time(NULL));
    snprintf(m.id, sizeof m.id, "%s", w->id ? w->id : "");
    mr_mark_set_note(&m, w->typed);
    m.has_pixel = true;
    m.pixel[0] = px;
    m.pixel[1] = py;
    m.hit = pick->hit;
    m.world[0] = pick->world.x;
    m.world[1] = pick->world.y;
    m.world[2] = pick->world.z;
    m.depth = pick->depth;
    if (pick->node >= 0 && scene && pick->node < scene->node_count) {
        m.node_index = pick->node;
        snprintf(m.node, sizeof m.node, "%s", scene->nodes[pick->node].name);
        snprintf(m.layer, sizeof m.layer, "%s", pick->layer == MR_LAYER_HIDDEN ? "hidden" : "visible");
    }
    /* The element the mark is about: the picked one, else the planned
     * part a measurement was measured to. */
    int32_t en = m.node_index;
    if (en < 0 && measured && measured->planned_node[0] && scene)
        for (int32_t i = 0; i < scene->node_count && en < 0; i++)
            if (strcmp(scene->nodes[i].name, measured->planned_node) == 0) en = i;
    mr_element_words ew = mr_scene_element_words(scene, en);
    snprintf(m.element_guid, sizeof m.element_guid, "%s", ew.guid);
    snprintf(m.element_class, sizeof m.element_class, "%s", ew.ifc_class);
    snprintf(m.element_name, sizeof m.element_name, "%s", ew.name);
    /* The registration's sigma at the marked point (absent when
     * the pose has no covariance, e.g. an older recording, or nothing was
     * hit) */
    mr_viewer_frame sf = {.have_pose = f->have_pose, .world_from_camera = f->pose, .pose_cov = f->cov,
                          .corner_sigma_px = f->corner_sigma_px, .have_point = pick->hit, .point = pick->world};
    m.has_uncertainty = mr_view_sigma_here(&sf, &m.uncertainty_m);
    m.has_measurement = measured != NULL; /* a mark made by Measure */
    if (measured) m.measurement = *measured;
    m.has_verdict = measured && verdict && verdict->kind != MR_VERDICT_NONE;
    if (m.has_verdict) m.verdict = *verdict;
    mr_mark_title(&m, m.title, sizeof m.title);
    return mr_annotation_to_json(&m);
}

void mr_view_frame_from_capture(mr_viewer_frame *vf, const mr_capture_frame *f, bool have_frame, const mr_camera *cam,
                                mr_camera *picture_cam) {
    vf->have_frame = have_frame;
    vf->have_pose = f->have_pose;
    vf->pose_valid = f->pose_valid;
    vf->index = f->index;
    vf->count = f->count;
    vf->tags_seen = f->tags_seen;
    vf->rms_px = f->rms_px;
    /* The pose's covariance */
    vf->world_from_camera = f->pose;
    vf->pose_cov = f->cov;
    vf->corner_sigma_px = f->corner_sigma_px;
    /* Measure: taps are made on the undistorted picture */
    if (have_frame && f->image.width > 0) {
        *picture_cam = mr_camera_resized(cam, f->image.width, f->image.height);
        vf->camera = picture_cam;
    }
}
