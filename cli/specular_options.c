/* The options of a prefiltered chain (specular_options.h). */
#include "specular_options.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum {
    GIVEN_FILTER = 1u << 0,
    GIVEN_SIZE = 1u << 1,
    GIVEN_LEVELS = 1u << 2,
    GIVEN_MAPPING = 1u << 3,
    GIVEN_FIXUP = 1u << 4,
    GIVEN_MIRROR = 1u << 5,
    GIVEN_TABLE = 1u << 6,
    GIVEN_METHOD = 1u << 7
};

/* "v,v,..." of finite values >= 0; the count, or -1 */
static int parse_table(const char *v, float *table, int max)
{
    int count = 0;
    const char *p = v;
    while (*p) {
        char *end = NULL;
        double x = strtod(p, &end);
        if (end == p || count >= max || !isfinite(x) || x < 0) return -1;
        table[count++] = (float)x;
        p = end;
        if (*p == ',') p++;
        else if (*p) return -1;
    }
    return count;
}

int cli_specular_option(cli_args *a, const char *arg, cli_specular_options *o)
{
    ibl_specular_desc *s = &o->set;
    if (cli_is(a, arg, "--preset", NULL)) {
        o->preset = cli_value(a, arg);
        ibl_specular_desc probe;
        if (!ibl_specular_preset(o->preset, &probe)) cli_usage_error(a, "unknown preset '%s'", o->preset);
    } else if (cli_is(a, arg, "--filter", NULL)) {
        const char *v = cli_value(a, arg);
        if (!ibl_specular_filter_from_name(v, &s->filter))
            cli_usage_error(a, "--filter wants ggx, phong, blinn, box or gauss, not '%s'", v);
        o->given |= GIVEN_FILTER;
    } else if (cli_is(a, arg, "--size", NULL)) {
        s->size = cli_int(a, arg, 1, 16384);
        o->given |= GIVEN_SIZE;
    } else if (cli_is(a, arg, "--levels", NULL)) {
        s->levels = cli_int(a, arg, 1, IBL_MAX_LEVELS);
        o->given |= GIVEN_LEVELS;
    } else if (cli_is(a, arg, "--mapping", NULL)) {
        const char *v = cli_value(a, arg);
        if (!ibl_specular_mapping_from_name(v, &s->mapping) || s->mapping == IBL_MAPPING_DEFAULT)
            cli_usage_error(a, "--mapping wants triace, linear, filament, unreal, unity, babylon "
                               "or table, not '%s'", v);
        o->given |= GIVEN_MAPPING;
    } else if (cli_is(a, arg, "--table", NULL)) {
        const char *v = cli_value(a, arg);
        s->table_count = parse_table(v, o->table, IBL_MAX_LEVELS);
        if (s->table_count < 1)
            cli_usage_error(a, "--table wants up to %d comma-separated finite numbers >= 0, not '%s'",
                            IBL_MAX_LEVELS, v);
        s->table = o->table;
        o->given |= GIVEN_TABLE;
    } else if (cli_is(a, arg, "--shininess-min", NULL)) {
        s->shininess_min = (float)cli_double(a, arg, 1e-3, 1e7);
    } else if (cli_is(a, arg, "--shininess-max", NULL)) {
        s->shininess_max = (float)cli_double(a, arg, 1e-3, 1e7);
    } else if (cli_is(a, arg, "--blinn-factor", NULL)) {
        s->blinn_factor = (float)cli_double(a, arg, 0.1, 100);
    } else if (cli_is(a, arg, "--babylon-lod-scale", NULL)) {
        s->babylon_lod_scale = (float)cli_double(a, arg, 0.05, 10);
    } else if (cli_is(a, arg, "--accuracy", NULL)) {
        s->accuracy = (float)cli_double(a, arg, 0.01, 2);
    } else if (cli_is(a, arg, "--edge-fixup", NULL)) {
        const char *v = cli_value(a, arg);
        if (!ibl_edge_fixup_from_name(v, &s->edge_fixup))
            cli_usage_error(a, "--edge-fixup wants none, overlap, overlap2, bent or warp, not '%s'", v);
        o->given |= GIVEN_FIXUP;
    } else if (cli_is(a, arg, "--mirror", NULL)) {
        s->mirror = 1;
        o->given |= GIVEN_MIRROR;
    } else if (cli_is(a, arg, "--method", NULL)) {
        const char *v = cli_value(a, arg);
        if (strcmp(v, "fast") == 0) s->method = IBL_METHOD_FAST;
        else if (strcmp(v, "reference") == 0) s->method = IBL_METHOD_REFERENCE;
        else cli_usage_error(a, "--method wants fast or reference, not '%s'", v);
        o->given |= GIVEN_METHOD;
    } else {
        return 0;
    }
    return 1;
}

const ibl_target_profile *cli_target_option(cli_args *a, const char *arg, cli_specular_options *spec,
                                            cli_input_options *input)
{
    if (!cli_is(a, arg, "--target", NULL)) return NULL;
    const char *v = cli_value(a, arg);
    ibl_target t;
    if (!ibl_target_from_name(v, &t))
        cli_usage_error(a, "--target wants three, babylon, filament, unity, unreal, godot or gltf, "
                           "not '%s'", v);
    const ibl_target_profile *p = ibl_target_profile_of(t);
    if (p->not_ready) cli_usage_error(a, "--target %s: %s", v, p->not_ready);
    if (input) input->orientation = p->orientation;
    if (spec) {
        ibl_specular_desc *s = &spec->set;
        s->filter = p->filter;
        s->mapping = p->mapping;
        s->size = p->size;
        s->babylon_lod_scale = p->babylon_lod_scale;
        spec->given |= GIVEN_FILTER | GIVEN_MAPPING | GIVEN_SIZE;
        spec->given &= ~(unsigned)GIVEN_LEVELS;
        spec->last_level_size = p->last_level_size;
    }
    return p;
}

ibl_specular_desc cli_specular_resolve(const cli_args *a, const cli_specular_options *o,
                                       const char *default_preset)
{
    ibl_specular_desc d;
    memset(&d, 0, sizeof d);
    const char *preset = o->preset ? o->preset : default_preset;
    if (preset && !ibl_specular_preset(preset, &d)) cli_usage_error(a, "unknown preset '%s'", preset);
    const ibl_specular_desc *s = &o->set;
    if (o->given & GIVEN_FILTER) d.filter = s->filter;
    if (o->given & GIVEN_SIZE) d.size = s->size;
    if (o->given & GIVEN_LEVELS) d.levels = s->levels;
    if (o->given & GIVEN_MAPPING) d.mapping = s->mapping;
    if (o->given & GIVEN_FIXUP) d.edge_fixup = s->edge_fixup;
    if (o->given & GIVEN_MIRROR) d.mirror = 1;
    if (o->given & GIVEN_METHOD) d.method = s->method;
    if (o->given & GIVEN_TABLE) d.table = s->table, d.table_count = s->table_count;
    /* a filter given without a mapping or preset takes its own default mapping (linear for
     * ggx, triace for the Phong family), not the command's default preset's */
    if ((o->given & GIVEN_FILTER) && !(o->given & GIVEN_MAPPING) && !o->preset)
        d.mapping = IBL_MAPPING_DEFAULT;
    if (s->shininess_min > 0) d.shininess_min = s->shininess_min;
    if (s->shininess_max > 0) d.shininess_max = s->shininess_max;
    if (s->blinn_factor > 0) d.blinn_factor = s->blinn_factor;
    if (s->accuracy > 0) d.accuracy = s->accuracy;
    if (s->babylon_lod_scale > 0) d.babylon_lod_scale = s->babylon_lod_scale;
    if (o->last_level_size > 0 && !(o->given & GIVEN_LEVELS))
        d.levels = ibl_target_levels(d.size > 0 ? d.size : 256, o->last_level_size);
    if (d.mapping == IBL_MAPPING_TABLE && !d.table)
        cli_usage_error(a, "--mapping table needs --table V,V,... (one value per level)");
    if (d.table && d.mapping != IBL_MAPPING_TABLE)
        cli_usage_error(a, "--table needs --mapping table");
    float smin = d.shininess_min > 0 ? d.shininess_min : 1.0f;
    float smax = d.shininess_max > 0 ? d.shininess_max : 1000.0f;
    if (smin > smax)
        cli_usage_error(a, "the shininess range %g-%g is empty (--shininess-min above "
                           "--shininess-max)", (double)smin, (double)smax);
    return d;
}

void cli_specular_check(const cli_args *a, ibl_context *ctx, const ibl_specular_desc *d,
                        int source_size)
{
    ibl_specular_info info;
    if (ibl_specular_levels(ctx, d, source_size, &info) != IBL_OK)
        cli_usage_error(a, "%s", ibl_context_message(ctx));
}
