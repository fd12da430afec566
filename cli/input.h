/* Reading any supported input as a cubemap, shared by the commands that take an environment. */
#ifndef IBL_CLI_INPUT_H
#define IBL_CLI_INPUT_H

#include "cli.h"

typedef struct cli_input_options {
    ibl_layout layout;           /* --layout (0: detect)              */
    ibl_orientation orientation; /* --yaw --mirror-input --z-up       */
    int size;                    /* the cube's edge (0: the input's)  */
    int detail;                  /* set by cli_read_cubemap: the face edge the input's
                                    pixels carry (an equirect W wide: W/4 at the horizon) */
    /* Set chain (the resolved desc of the chain the cube is read for) and a flat input also
     * gives its sources (ibl_specular_sources_create, made while the image is still in
     * memory): the caller applies them to the chain and destroys them. */
    const ibl_specular_desc *chain;
    ibl_specular_sources *sources;
} cli_input_options;

/* The one table of options that say how an environment is read; every command that reads one
 * takes them (and prints this in its --help). */
#define CLI_INPUT_HELP                                                                          \
    "  --layout L           layout of a flat input: auto (default: from the aspect ratio),\n"   \
    "                       equirect, hcross, vcross, hstrip, vstrip, angular, octahedral\n"    \
    "  --yaw DEG            rotate the environment about the up axis\n"                         \
    "  --mirror-input       flip the input left-right\n"                                         \
    "  --z-up               the input was made with +Z up\n"

/* Parses --layout, --yaw, --mirror-input, --z-up into o; returns 1 if arg was one of them. */
int cli_input_option(cli_args *a, const char *arg, cli_input_options *o);

/* Reads path (flat image in any layout, or a cube texture) into a one-level cubemap (level 0
 * of a cube texture; other levels are dropped). Prints the error and returns the exit code
 * (0 on success). If layout_out is not NULL it receives the layout used. */
int cli_read_cubemap(ibl_context *ctx, const cli_common *c, const char *path,
                     cli_input_options *o, ibl_cubemap *out, ibl_layout *layout_out);
/* The edge of the cube cli_read_cubemap makes with o from a file that holds what info says
 * (ibl_read_info: known from the header alone); 0 when it cannot tell (or the read fails). */
int cli_input_cube_size(const cli_input_options *o, const ibl_file_info *info);
/* The two halves of cli_read_cubemap: the file as a texture (pixels reported), then the
 * texture (freed here, whatever happens) as a cube of the options' size and orientation;
 * each prints its error and returns an exit code. */
int cli_read_input_texture(ibl_context *ctx, const cli_common *c, const char *path, ibl_texture *tex);
int cli_texture_to_cubemap(ibl_context *ctx, const char *path, cli_input_options *o,
                           ibl_texture *tex, ibl_cubemap *out, ibl_layout *layout_out);

/* The built-in clear sky (desc may be NULL: the defaults) as a one-level cube of edge
 * o->size (0: 256), oriented by o. Prints the error and returns the exit code. */
int cli_read_sky(ibl_context *ctx, const ibl_sky_desc *desc, const cli_input_options *o,
                 ibl_cubemap *out);

/* Reads six face images (+X -X +Y -Y +Z -Z, square, one size) into a one-level cubemap.
 * Prints the error (naming the offending file) and returns the exit code. */
int cli_read_cubemap_faces(ibl_context *ctx, const cli_common *c, const char *const paths[6],
                           const cli_input_options *o, ibl_cubemap *out);

/* Refuses (usage error, exit 2) an output path that names the same file as the input. */
void cli_check_distinct(const cli_args *a, const char *input, const char *output);
/* Refuses (usage error) an input that lies in the folder an output replaces whole. */
void cli_check_not_inside(const cli_args *a, const char *input, const char *folder);
/* The container of an output path, checked before any work: an unknown extension or an output
 * that is one of the command's input files is a usage error. */
ibl_file_type cli_check_output(const cli_args *a, const char *output);

/* Warns (stderr, unless -q) when an output cube of edge out_size is larger than the input's
 * detail (o->detail, from cli_read_cubemap): its extra texels are interpolated, not new. */
void cli_warn_upsampling(const cli_common *c, const char *path, const cli_input_options *o,
                         int out_size);

/* Refuses (usage error, before any work) an output of prefilter, irradiance or convert in a
 * bake folder (one whose manifest.json says "ibl-bake"): the bake owns that folder, a file
 * written there would replace one of its files behind its manifest's back or be a stranger
 * that makes the next `ibl bake` of the folder refuse it. docs/FORMATS.md "Bake folder". */
void cli_check_not_in_bake(const cli_args *a, const char *output);
/* Refuses (usage error) to replace the file `path` unless it is absent or a manifest of the
 * kind `format` ("ibl-chain"): a manifest another command wrote is not overwritten. */
void cli_check_manifest_replaceable(const cli_args *a, const char *path, const char *format);

#endif
