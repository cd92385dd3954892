/* The multi-view options shared by render and replay: mr_rig_opts does
 * --views, --view-cone, --view-fov and --focal-distance; --quilt is parsed
 * by mr_quilt_parse. What is left here is wiring: the rig and the quilt
 * layout for a view, and writing one rig frame into a folder. */
#include "app.h"

#include <stdio.h>

bool app_rig_check(const char *cmd, const mr_cli_table *t, const mr_cli_opt *opts, mr_quilt *quilt, bool *have_quilt) {
    const mr_rig_params *rp = t->params;
    *have_quilt = false;
    const char *q = mr_cli_get(opts, "quilt");
    if (q) {
        mr_error err = {0};
        if (!mr_quilt_parse(q, quilt, &err)) return mr_cli_errorf(cmd, "--quilt: %s", err.msg), false;
        *have_quilt = true;
    }
    bool rig_opt = mr_cli_table_given(t, "view-cone") || mr_cli_table_given(t, "view-fov") || mr_cli_table_given(t, "focal-distance");
    bool lf = mr_cli_get(opts, "lightfield") != NULL;
    if (rp->views == 0 && !*have_quilt && !lf && rig_opt)
        return mr_cli_errorf(cmd, "--view-cone, --view-fov and --focal-distance need --views, --quilt or --lightfield"), false;
    if (rp->views == 0 && !*have_quilt && mr_cli_table_given(t, "views-per-view-work"))
        return mr_cli_errorf(cmd, "--views-per-view-work needs --views or --quilt"), false;
    if (lf && (rp->views > 0 || *have_quilt))
        return mr_cli_errorf(cmd, "--lightfield is one display image: not with --views or --quilt"), false;
    return true;
}

bool app_rig_focal(mr_renderer *r, const mr_scene *scene, const mr_rig_params *rp, const mr_view *centre,
                   const mr_frame_params *fp, int w, int h, double *focal, mr_error *err) {
    double d = rp->focal_distance > 0 ? rp->focal_distance : *focal;
    if (!(d > 0)) {
        /* Where the centre view looks: one frame of depth at the view size. */
        mr_frame_params dp = *fp;
        dp.video = NULL;
        dp.display = NULL;
        dp.want_depth = true;
        dp.ao.method = MR_AO_NONE;
        dp.ao.external = NULL;
        dp.width = w;
        dp.height = h;
        mr_frame_result fr;
        if (!mr_render_frame(r, centre, &dp, &fr, err)) return false;
        d = mr_rig_focal_from_depth(&fr.depth);
        mr_frame_result_free(&fr);
        if (!(d > 0)) d = mr_rig_auto_focal_distance(scene, centre);
    }
    if (!(d > 0)) return mr_fail(err, MR_ERR_INVALID, "nothing in front of the camera to focus on: give --focal-distance");
    *focal = d;
    return true;
}

bool app_lightfield_view(mr_renderer *r, const mr_scene *scene, const mr_rig_params *rp, int band, const mr_view *view,
                         const mr_frame_params *fp, mr_view *centre, mr_display_map *map, mr_error *err) {
    int w = fp->width > 0 ? fp->width : view->camera.width, h = fp->height > 0 ? fp->height : view->camera.height;
    double d = 0;
    if (!app_rig_focal(r, scene, rp, view, fp, w, h, &d, err)) return false;
    mr_rig_params one = *rp;
    one.views = 1;
    mr_rig rig;
    if (!mr_rig_make(&one, (double)w / h, d, &rig, err)) return false;
    rig.cone = rp->cone_deg * 3.14159265358979323846 / 180; /* the observer line's, not a single view's */
    *centre = mr_rig_view(&rig, view, 0, w, h);
    *map = mr_display_from_rig(&rig, band);
    return true;
}

bool app_rig_render(mr_renderer *r, const mr_scene *scene, const mr_rig_params *rp, const mr_quilt *quilt,
                    const mr_view *centre, const mr_frame_params *fp, const char *views_dir, const char *quilt_dir,
                    const char *quilt_name, double *focal, mr_quilt_layout *layout, mr_rig_result *res, mr_error *err) {
    mr_rig_params p = *rp;
    int w = fp->width > 0 ? fp->width : centre->camera.width, h = fp->height > 0 ? fp->height : centre->camera.height;
    if (p.views == 0) p.views = quilt->cols * quilt->rows; /* --quilt alone: a view per tile */
    if (!mr_quilt_layout_make(quilt->cols ? quilt : NULL, p.views, w, h, layout, err)) return false;
    if (!app_rig_focal(r, scene, &p, centre, fp, layout->tile_w, layout->tile_h, focal, err)) return false;
    double d = *focal;
    mr_rig rig;
    if (!mr_rig_make(&p, layout->aspect, d, &rig, err)) return false;
    mr_image img = {0};
    if (!mr_render_rig(r, &rig, centre, fp, layout, views_dir, &img, res, err)) return false;
    char name[256], path[4096];
    mr_quilt_file_name(quilt_name, layout, name, sizeof name);
    mr_path_join(quilt_dir, name, path, sizeof path);
    bool ok = mr_image_save_png(path, &img, err);
    mr_image_free(&img);
    return ok;
}
