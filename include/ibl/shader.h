/*
 * ibl/shader.h - the numbers shaders/ibl.glsl and ibl.hlsl read, in their uniform-block
 * layout: a probe's level mapping, SH and table axes (ibl_shader_probe = the shaders'
 * `ibl_probe` struct, std140 / HLSL cbuffer packing) and a mip atlas layout
 * (ibl_shader_atlas = `ibl_atlas_layout`), and punctual lights (ibl_shader_lights = the
 * shaders' `ibl_light_set`, light.h's ibl_light). Plain data; no graphics API here. docs/SHADERS.md
 * shows the upload (textures, bindings, samplers) and a complete fragment shader.
 *
 *   ibl_shader_probe block;
 *   ibl_shader_probe_fill(ctx, &probe, &block);      // probe from ibl_bake_probe
 *   glBufferData(GL_UNIFORM_BUFFER, sizeof block, &block, GL_STATIC_DRAW);
 */
#ifndef IBL_SHADER_H
#define IBL_SHADER_H

#include "core.h"
#include "light.h"
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

/* The shaders' ibl_light struct (std140 / HLSL), 64 bytes: light.h's ibl_light as it is
 * (zeros keep their meaning: white, intensity 1, no range, outer cone pi/4). */
typedef struct ibl_shader_light {
    float color[3], intensity;
    float position[3], range;
    float direction[3], size;
    int32_t type;
    float inner_cone, outer_cone;
    int32_t reserved;
} ibl_shader_light;

enum { IBL_SHADER_MAX_LIGHTS = 8 }; /* the shaders' IBL_MAX_LIGHTS default */

/* The shaders' ibl_light_set struct (std140 / HLSL), 528 bytes: a count row, then the
 * lights. */
typedef struct ibl_shader_lights {
    int32_t count, reserved[3];
    ibl_shader_light light[IBL_SHADER_MAX_LIGHTS];
} ibl_shader_lights;

/* Fills the block from a validated probe (ibl_probe_validate or ibl_bake_probe). Fails when
 * the mapping uses lod functions (lod_from_roughness / lod_from_shininess): a shader has
 * only the per-level tables. */
ibl_status ibl_shader_probe_fill(ibl_context *ctx, const ibl_probe *probe, ibl_shader_probe *out);
void ibl_shader_atlas_fill(const ibl_atlas_layout *layout, ibl_shader_atlas *out);
/* Fills the block from count lights (0 <= count <= IBL_SHADER_MAX_LIGHTS), each checked by
 * ibl_light_validate; unused slots are zero. */
ibl_status ibl_shader_lights_fill(ibl_context *ctx, const ibl_light *lights, int count,
                                  ibl_shader_lights *out);
void ibl_shader_light_fill(const ibl_light *light, ibl_shader_light *out);

#ifdef __cplusplus
}
#endif
#endif
