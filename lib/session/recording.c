#include "mr_session.h"
