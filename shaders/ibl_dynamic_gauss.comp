// ibl_dynamic_gauss.comp - the per-face Gaussian of tri-Ace 2010's dynamic configuration
// "Gaussian 32x32x6" ("Generate PMREM (2)"): each level of the box chain (ibl_box_mip.comp)
// blurred within each face by a separable Gaussian, the kernel cut at the face border and
// renormalised there (nothing is read across an edge; a constant stays constant). The C:
// src/bake/specular_dynamic/box_chain.c (blur_line), the same as specular_gauss.c; compared
// with ibl_specular_plan_run (preset dynamic-gauss32) in tests/test_shaders.c.
//
// The kernel of a level of edge n with the Phong exponent e of the level
// (ibl_specular_level_phong_exponent) is exp(-k^2 / (2 sigma^2)), k = -radius .. radius, with
//     sigma^2 = (n / 2)^2 / (e + 3) - 1 / 12     (specular_gauss.c's ibl__gauss_sigma)
//     radius  = min(n - 1, ceil(4 sigma));  no blur (radius 0: a copy) when sigma < 1e-3
// The weights are computed here in float; the C's are double (relative 1e-7 apart).
//
// Dispatch per level, two passes: u_pass 0 reads the chain's level (image 0) and writes a
// scratch cube level (image 1) along rows; u_pass 1 reads the scratch and writes the output
// level along columns. Groups (ceil(n/8), ceil(n/8), 6) each, a memory barrier between
// (glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT)). GLSL 4.50 core or Vulkan GLSL.
#version 450
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0, rgba32f) uniform readonly imageCube u_src;
layout(binding = 1, rgba32f) uniform writeonly imageCube u_dst;
#ifdef VULKAN
layout(push_constant) uniform Params { int u_size; int u_radius; float u_sigma; int u_pass; };
#else
uniform int u_size;    // n, the level's edge
uniform int u_radius;  // 0: copy
uniform float u_sigma;
uniform int u_pass;    // 0: rows, 1: columns
#endif

void main()
{
    ivec3 id = ivec3(gl_GlobalInvocationID); // x, y, face
    int n = u_size;
    if (id.x >= n || id.y >= n || id.z >= 6) return;
    int i = u_pass == 0 ? id.x : id.y; // the position along the line
    int a = max(i - u_radius, 0), b = min(i + u_radius, n - 1);
    float inv = u_radius > 0 ? 0.5 / (u_sigma * u_sigma) : 0.0;
    vec4 acc = vec4(0.0);
    float wsum = 0.0;
    for (int k = a; k <= b; k++) {
        float d = float(k - i);
        float w = exp(-d * d * inv);
        ivec3 p = u_pass == 0 ? ivec3(k, id.y, id.z) : ivec3(id.x, k, id.z);
        acc += w * imageLoad(u_src, p);
        wsum += w;
    }
    imageStore(u_dst, id, acc / wsum);
}
