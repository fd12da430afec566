/* The page `ibl view` writes: one self-contained HTML file (viewer/viewer.html with its
 * style, script and scene shader inlined, shaders/ibl.glsl verbatim, and the probe's
 * textures and uniform block as base64 in a JSON block). The page's sources are compiled
 * into the CLI by viewer/viewer.cmake. docs/VIEWER.md describes the page. */
#ifndef IBL_CLI_VIEWER_HTML_H
#define IBL_CLI_VIEWER_HTML_H

#include "ibl/ibl.h"

#include <stddef.h>

typedef struct viewer_input {
    const ibl_probe *probe;       /* validated (ibl_bake_probe)                           */
    const ibl_shader_probe *block; /* ibl_shader_probe_fill of probe                      */
    int sh_bands;                 /* of the bake: > 0 lets the page switch to the SH       */
    const char *manifest_json;    /* the bake's manifest.json text (parsed by the page)    */
    const char *title;            /* the bake's name, shown in the page                    */
    float exposure;               /* the page's starting exposure (EV)                     */
} viewer_input;

/* Builds the page into a new buffer (free()); returns IBL_OK, or an error with the reason
 * in err. */
ibl_status viewer_html_build(const viewer_input *in, char **html, size_t *size, char *err,
                             size_t err_size);

#endif
