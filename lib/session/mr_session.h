#ifndef MR_SESSION_H
#define MR_SESSION_H
#include "mr_track.h"
#endif
