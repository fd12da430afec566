/* The uniform block of shaders/ibl.glsl and ibl.hlsl from a probe or an atlas layout. The
 * struct mirrors the shaders' std140 layout; the static asserts pin the sizes. */
#include "ibl/shader.h"
#include "core/context_internal.h"

#include <string.h>

_Static_assert(sizeof(ibl_shader_axis) == 16, "ibl_table_axis is one 16-byte row");
_Static_assert(sizeof(ibl_shader_probe) == 384, "std140 size of the shaders' ibl_probe");
_Static_assert(sizeof(ibl_shader_atlas) == 208, "std140 size of the shaders' ibl_atlas_layout");
_Static_assert(sizeof(ibl_shader_light) == 64, "std140 size of the shaders' ibl_light");
_Static_assert(sizeof(ibl_shader_lights) == 528, "std140 size of the shaders' ibl_light_set");

static ibl_shader_axis axis(const ibl_table_axis *a)
{
    ibl_shader_axis s = {a->count, a->first, a->last, a->logarithmic ? 1 : 0};
    return s;
}

ibl_status ibl_shader_probe_fill(ibl_context *ctx, const ibl_probe *p, ibl_shader_probe *out)
{
    memset(out, 0, sizeof *out);
    if (!p || p->mapping.levels < 1 || p->mapping.levels > IBL_MAX_LEVELS)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "shader probe: no level mapping");
    if (p->mapping.lod_from_roughness || p->mapping.lod_from_shininess)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "shader probe: the mapping uses lod functions, which a shader cannot call; "
                         "give per-level roughness/shininess tables");
    for (int k = 0; k < IBL_MAX_LEVELS; k++) {
        /* past the last level, repeat it: the shader never reads there */
        int j = k < p->mapping.levels ? k : p->mapping.levels - 1;
        out->roughness[k] = p->mapping.roughness[j];
        out->shininess[k] = p->mapping.shininess[j];
    }
    for (int i = 0; i < 9; i++)
        for (int c = 0; c < 3; c++) out->sh[i][c] = p->sh[i][c];
    out->splitsum_n_dot_v = axis(&p->splitsum.n_dot_v);
    out->splitsum_roughness = axis(&p->splitsum.roughness);
    out->ambient_n_dot_v = axis(&p->ambient_brdf.n_dot_v);
    out->ambient_shininess = axis(&p->ambient_brdf.shininess);
    out->ambient_f0 = axis(&p->ambient_brdf.f0);
    out->levels = p->mapping.levels;
    out->sh_kind = (int32_t)p->sh_kind;
    out->intensity = p->intensity > 0.0f ? p->intensity : 1.0f;
    out->mirror_shininess = p->mirror_shininess > 0.0f ? p->mirror_shininess : 10000.0f;
    out->has_mirror = p->mirror.data != NULL;
    out->has_splitsum = p->splitsum.data != NULL;
    out->has_ambient_brdf = p->ambient_brdf.data != NULL;
    return IBL_OK;
}

void ibl_shader_atlas_fill(const ibl_atlas_layout *l, ibl_shader_atlas *out)
{
    memset(out, 0, sizeof *out);
    out->width = l->width;
    out->height = l->height;
    out->levels = l->levels;
    out->gutter = l->gutter;
    for (int k = 0; k < IBL_MAX_LEVELS; k++) {
        out->face_size[k] = l->face_size[k];
        out->x[k] = l->x[k];
        out->y[k] = l->y[k];
    }
}

void ibl_shader_light_fill(const ibl_light *l, ibl_shader_light *out)
{
    memset(out, 0, sizeof *out);
    memcpy(out->color, l->color, sizeof out->color);
    out->intensity = l->intensity;
    out->position[0] = l->position.x, out->position[1] = l->position.y;
    out->position[2] = l->position.z;
    out->range = l->range;
    out->direction[0] = l->direction.x, out->direction[1] = l->direction.y;
    out->direction[2] = l->direction.z;
    out->size = l->size;
    out->type = (int32_t)l->type;
    out->inner_cone = l->inner_cone;
    out->outer_cone = l->outer_cone;
}

ibl_status ibl_shader_lights_fill(ibl_context *ctx, const ibl_light *lights, int count,
                                  ibl_shader_lights *out)
{
    memset(out, 0, sizeof *out);
    if (count < 0 || count > IBL_SHADER_MAX_LIGHTS || (count > 0 && !lights))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "shader lights: %d lights, the block holds 0 to %d", count,
                         IBL_SHADER_MAX_LIGHTS);
    for (int i = 0; i < count; i++) {
        ibl_status st = ibl_light_validate(ctx, &lights[i], i);
        if (st != IBL_OK) {
            memset(out, 0, sizeof *out);
            return st;
        }
        ibl_shader_light_fill(&lights[i], &out->light[i]);
    }
    out->count = count;
    return IBL_OK;
}
