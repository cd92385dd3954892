/* placeholder until bench lands */
#include "app.h"
int cmd_bench(int argc, char **argv) { (void)argc; (void)argv; return app_errorf("bench", "not yet"); }
