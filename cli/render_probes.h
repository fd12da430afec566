/* ibl render SCENE --probes DIR (cli/render_probes.c): cli_cmd_render hands the command line
 * over when it names a probe bake. */
#ifndef IBL_CLI_RENDER_PROBES_H
#define IBL_CLI_RENDER_PROBES_H

#include "cli.h"

int cli_render_probes(int argc, char **argv);

#endif
