// ibl_dynamic_phong.comp - the spherical Phong kernel of tri-Ace 2010's dynamic configurations
// "Phong 16x16x6" and "Phong 32x32x6" (presets dynamic-phong16, dynamic-phong32; any dynamic
// plan of the phong, blinn or ggx filter) on the GPU: every output texel is a fixed row of
// weights over the texels of one box mip of the freshly rendered source (ibl_box_mip.comp),
// the lobe integrated over each texel and the row normalised to sum 1 when the plan was made.
// The rows come from the C plan, expanded to all six faces, in CSR form:
// ibl_specular_plan_rows_info / ibl_specular_plan_rows_fill (include/ibl/specular.h). So the
// result is the C's (src/bake/specular_dynamic/lobe_rows.c, run by dynamic.c) up to the order
// of the float additions; compared with ibl_specular_plan_run in tests/test_shaders.c.
//
// Dispatch per level: image 0 the source's box mip source_mip (read), image 1 the output level
// (write), SSBO 0 the row offsets (6 n^2 + 1), SSBO 1 the columns ((face M + y) M + x in the
// mip), SSBO 2 the weights; groups (ceil(n/8), ceil(n/8), 6). Then, when the plan's level
// reports a fixup (rows.fixup != NONE: for dynamic-phong only the 1x1 level, the mean of its
// six faces), ibl_dynamic_fixup.comp from this level into the final one. GLSL 4.50 or Vulkan.
#version 450
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0, rgba32f) uniform readonly imageCube u_mip;
layout(binding = 1, rgba32f) uniform writeonly imageCube u_dst;
layout(std430, binding = 0) readonly buffer RowOffsets { uint row_offset[]; };
layout(std430, binding = 1) readonly buffer Columns { uint column[]; };
layout(std430, binding = 2) readonly buffer Weights { float weight[]; };
#ifdef VULKAN
layout(push_constant) uniform Params { int u_size; int u_mip_size; };
#else
uniform int u_size;     // n, the output level's edge
uniform int u_mip_size; // M, the edge of the box mip the rows read
#endif

void main()
{
    ivec3 id = ivec3(gl_GlobalInvocationID); // x, y, face
    int n = u_size, M = u_mip_size;
    if (id.x >= n || id.y >= n || id.z >= 6) return;
    uint r = uint((id.z * n + id.y) * n + id.x);
    uint mm = uint(M * M);
    vec3 acc = vec3(0.0);
    for (uint k = row_offset[r]; k < row_offset[r + 1u]; k++) {
        uint c = column[k], face = c / mm, t = c - face * mm;
        ivec3 p = ivec3(int(t % uint(M)), int(t / uint(M)), int(face));
        acc += weight[k] * imageLoad(u_mip, p).rgb;
    }
    imageStore(u_dst, id, vec4(acc, 1.0));
}
