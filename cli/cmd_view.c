/* woven view: placeholder */
#include "cli.h"
int cmd_view(int argc, char **argv) { (void)argc, (void)argv; return EXIT_USAGE; }
