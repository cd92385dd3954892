/* The export's option table (mr_export_opts): one row per tunable of
 * mr_export_params, for the command line and --help. */
#include "mr_export.h"

#include <stddef.h>

static const char *const k_versions[] = {"2.1", "3.0", NULL};

#define EX(f) offsetof(mr_export_params, f)
const mr_opt mr_export_opts[] = {
    {"version", MR_OPT_ENUM, EX(bcf_version), 0, 1, MR_BCF_2_1, k_versions, "BCF version of the archive", 0},
    {"snapshot-max", MR_OPT_INT, EX(max_side), 64, 8192, MR_EXPORT_DEFAULT_MAX_SIDE, NULL,
     "long side of a snapshot at most, px", 0},
    {"unit-m", MR_OPT_DOUBLE, EX(unit_m), 1e-9, 1e9, 1.0, NULL, "metres per scene unit", 0},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
#undef EX
