// ibl_box_mip.comp - one level of the area-correct box chain on the GPU: every texel of level
// L is the solid-angle-weighted mean of its 2x2 children in level L-1, so a constant cube
// stays constant and each level keeps the radiant energy of level 0. This is the "box
// filter" dynamic profile of tri-Ace 2010 ("Generate PMREM (1)") and the C of
// ibl_cubemap_build_mips (src/core/cubemap.c), tested against it in tests/test_shaders.c.
// The exact texel solid angles (Driscoll 2012) come from the CPU, once per size:
// ibl_cube_solid_angle_table(child_size) (float64 there; float differences of the corner
// function would cancel). GLSL 4.50 core or Vulkan GLSL (detected by VULKAN).
//
// Dispatch per level L = 1 .. levels-1: groups (ceil(n/8), ceil(n/8), 6), n = max(1, child/2);
// image 0 = level L-1 (read), image 1 = level L (write), both layered cube images;
// then glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT) before the next level.
#version 450
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0, rgba32f) uniform readonly imageCube u_child;
layout(binding = 1, rgba32f) uniform writeonly imageCube u_parent;
layout(std430, binding = 0) readonly buffer ChildSolidAngles { float solid_angle[]; };
#ifdef VULKAN
layout(push_constant) uniform Params { int u_child_size; };
#else
uniform int u_child_size;
#endif

void main()
{
    ivec3 id = ivec3(gl_GlobalInvocationID); // x, y, face
    int cn = u_child_size, n = max(cn / 2, 1);
    if (id.x >= n || id.y >= n || id.z >= 6) return;
    vec4 acc = vec4(0.0);
    float wsum = 0.0;
    for (int dy = 0; dy < 2; dy++)
        for (int dx = 0; dx < 2; dx++) {
            ivec2 c = 2 * id.xy + ivec2(dx, dy);
            if (c.x >= cn || c.y >= cn) continue;
            float w = solid_angle[c.y * cn + c.x];
            acc += w * imageLoad(u_child, ivec3(c, id.z));
            wsum += w;
        }
    imageStore(u_parent, id, acc / wsum);
}
