#include "export_internal.h"
bool mr_export_report(const char *session_dir, const char *out_dir, const mr_export_params *p, mr_error *err) {
    return mr_fail(err, MR_ERR_UNSUPPORTED, "not yet");
}
