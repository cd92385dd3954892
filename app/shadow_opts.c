/* The shadow options shared by the commands that render: mr_shadow_opts
 * does the names, ranges and defaults; what is left is the scene config's
 * default method. */
#include "app.h"

bool app_shadow_scene_default(const char *cmd, const mr_cli_table *t, const mr_scene *s, mr_shadow_params *p) {
    if (mr_cli_table_given(t, "") || !s || !s->shadow_method[0]) return true;
    if (!mr_shadow_method_parse(s->shadow_method, &p->method))
        return mr_cli_errorf(cmd, "%s: 'shadows' must be off, hard, pcf, pcss, bp or groundtruth, not '%s'",
                          s->source[0] ? s->source : "the scene config", s->shadow_method),
               false;
    return true;
}
