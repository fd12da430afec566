/*
 * ibl/shader.h - the numbers shaders/ibl.glsl and ibl.hlsl read, in their uniform-block
 * layout: a probe's level mapping, SH and table axes (ibl_shader_probe = the shaders'
 * `ibl_probe` struct, std140 / HLSL cbuffer packing) and a mip atlas layout
 * (ibl_shader_atlas = `ibl_atlas_layout`). Plain data; no graphics API here. docs/SHADERS.md
 * shows the upload (textures, bindings, samplers) and a complete fragment shader.
 *
 *   ibl_shader_probe block;
 *   ibl_shader_probe_fill(ctx, &probe, &block);      // probe from ibl_bake_probe
 *   glBufferData(GL_UNIFORM_BUFFER, sizeof block, &block, GL_STATIC_DRAW);
 */
#ifndef IBL_SHADER_H
#define IBL_SHADER_H

#include "core.h"
#include "shade.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One table axis (ibl_table_axis), 16 bytes. */
typedef struct ibl_shader_axis {
    int32_t count;
    float first, last;
    int32_t logarithmic;
} ibl_shader_axis;

/* The shaders' ibl_probe struct, byte for byte (std140 and HLSL packing agree: every member
 * is a 16-byte row). 384 bytes. */
typedef struct ibl_shader_probe {
    float roughness[IBL_MAX_LEVELS]; /* vec4[4]: mapping.roughness                       */
    float shininess[IBL_MAX_LEVELS]; /* vec4[4]: mapping.shininess                       */
    float sh[9][4];                  /* vec4[9]: rgb, w = 0                               */
    ibl_shader_axis splitsum_n_dot_v, splitsum_roughness;
    ibl_shader_axis ambient_n_dot_v, ambient_shininess, ambient_f0;
    int32_t levels, sh_kind;
    float intensity, mirror_shininess; /* resolved: 0 in the probe becomes 1 and 10000     */
    int32_t has_mirror, has_splitsum, has_ambient_brdf, reserved;
} ibl_shader_probe;

/* The shaders' ibl_atlas_layout struct (std140 / HLSL), 208 bytes. */
typedef struct ibl_shader_atlas {
    int32_t width, height, levels, gutter;
    int32_t face_size[IBL_MAX_LEVELS]; /* ivec4[4] */
    int32_t x[IBL_MAX_LEVELS];
    int32_t y[IBL_MAX_LEVELS];
} ibl_shader_atlas;

/* Fills the block from a validated probe (ibl_probe_validate or ibl_bake_probe). Fails when
 * the mapping uses lod functions (lod_from_roughness / lod_from_shininess): a shader has
 * only the per-level tables. */
ibl_status ibl_shader_probe_fill(ibl_context *ctx, const ibl_probe *probe, ibl_shader_probe *out);
void ibl_shader_atlas_fill(const ibl_atlas_layout *layout, ibl_shader_atlas *out);

#ifdef __cplusplus
}
#endif
#endif
