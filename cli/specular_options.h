/* The options that describe a prefiltered chain, shared by `ibl bake` and `ibl prefilter`:
 * one table, one help text, one way presets and explicit options combine. */
#ifndef IBL_CLI_SPECULAR_OPTIONS_H
#define IBL_CLI_SPECULAR_OPTIONS_H

#include "cli.h"
#include "input.h"

typedef struct cli_specular_options {
    const char *preset;     /* --preset (NULL: the command's default)              */
    ibl_specular_desc set;  /* the values given explicitly                          */
    unsigned given;         /* which of them (bits of cli_specular_options.c)        */
    float table[IBL_MAX_LEVELS];
    int last_level_size;    /* --target: the chain ends at this edge unless --levels says */
} cli_specular_options;

#define CLI_SPECULAR_HELP                                                                       \
    "  --preset P           gltf, filament, unreal, unity, or the tri-Ace 2010 configurations\n" \
    "                       dynamic-box16, dynamic-gauss32, dynamic-phong16, dynamic-phong32,\n" \
    "                       static-phong32, static-phong64 (explicit options override it)\n"    \
    "  --filter K           ggx, phong, blinn, box, gauss\n"                                     \
    "  --size N             chain face edge (default: the preset's, else the input's)\n"        \
    "  --levels L           number of levels (default: down to 1x1, or the mapping's last\n"    \
    "                       distinct level)\n"                                                  \
    "  --mapping M          level <-> roughness/shininess: triace (tri-Ace 2010, lod = a -\n"   \
    "                       0.5 log2 s), linear (glTF), filament, unreal, unity, babylon,\n"    \
    "                       table (default: linear for ggx, triace otherwise)\n"               \
    "  --table V,V,...      the values of --mapping table, one per level\n"                    \
    "  --shininess-min S, --shininess-max S   the triace mapping's range (default 1-1000)\n"  \
    "  --blinn-factor F     Blinn-to-Phong fit factor (default 4.2; cmft uses 4)\n"            \
    "  --edge-fixup E       none, overlap, overlap2, bent, warp\n"                              \
    "  --mirror             level 0 is the unfiltered source (mirror-like materials)\n"        \
    "  --method M           fast (default) or reference (exact double integral: slow)\n"       \
    "  --accuracy A         fast method's quadrature step scale (default 0.35; smaller: more\n" \
    "                       exact, slower)\n"                                                  \
    "  --babylon-lod-scale S  the babylon mapping's lodGenerationScale (default 0.8)\n"

#define CLI_TARGET_HELP                                                                         \
    "  --target ENGINE      three, babylon, gltf (filament, unity, unreal, godot: reserved):\n"  \
    "                       the engine's orientation, mapping, levels, container, format and\n" \
    "                       SH form (docs/ENGINES.md); options after it override it\n"

/* --target NAME: applies the row's chain to spec and its orientation to input (either may be
 * NULL) as if they had been given there, so later options override them. Returns the row, or
 * NULL when arg is not --target; an unknown or reserved target is a usage error. */
const ibl_target_profile *cli_target_option(cli_args *a, const char *arg, cli_specular_options *spec,
                                            cli_input_options *input);

/* Parses one of the options above into o; returns 1 if arg was one of them. */
int cli_specular_option(cli_args *a, const char *arg, cli_specular_options *o);
/* The preset (default_preset when none was given; NULL: none) with the explicit options over
 * it. Contradictions are usage errors (exit 2), found before any work. */
ibl_specular_desc cli_specular_resolve(const cli_args *a, const cli_specular_options *o,
                                       const char *default_preset);
/* Checks the chain desc describes for an input of that face edge (e.g. a table of the wrong
 * length): a usage error, before any work. */
void cli_specular_check(const cli_args *a, ibl_context *ctx, const ibl_specular_desc *d,
                        int source_size);

#endif
