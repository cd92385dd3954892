/* The multi-view options shared by render and replay: mr_rig_opts does
 * --views, --view-cone, --view-fov and --focal-distance; --quilt is parsed
 * by mr_quilt_parse. What is left here is the check of options that
 * depend on each other; rendering a rig is lib/render's mr_render_rig_files. */
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
