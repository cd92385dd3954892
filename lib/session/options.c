/* lib/session's option table: how a recorder stores its frames. */
#include "mr_session.h"

#include <stddef.h>

const mr_opt mr_recorder_opts[] = {
    /* 0 in the field is the recorder's default quality. */
    {"jpeg", MR_OPT_INT, offsetof(mr_recorder_params, jpeg_quality), 1, 100, MR_RECORDER_DEFAULT_JPEG_QUALITY, NULL,
     "JPEG quality of the stored frames", MR_OPT_ZERO_DEFAULT},
    {NULL, 0, 0, 0, 0, 0, NULL, NULL, 0},
};
