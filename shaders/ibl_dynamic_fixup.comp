// ibl_dynamic_fixup.comp - tri-Ace 2010's "Edge overlapping" (1) on the GPU, the edge fixup of
// the dynamic box and Gaussian chains: every border texel becomes the mean of itself and the
// texels across its seams (two at an edge, three at a cube corner), and a 1x1 level the mean
// of its six faces ("the color becomes the average of all faces"). The C:
// src/bake/specular_dynamic/fixup_tables.c (its groups, found by the same unfolding as
// partner() there) and ibl_edge_fixup_apply; compared with ibl_specular_plan_run in
// tests/test_shaders.c. (overlap2's second row is not ported; the Phong presets' bent fixup
// lives in their directions and only averages a 1x1 level, which this shader also does.)
//
// Dispatch per level after its filter: image 0 the filtered level (read), image 1 the output
// level (write, a different image: a texel's partners must be read before they change),
// groups (ceil(n/8), ceil(n/8), 6). Faces in OpenGL's order and orientation.
#version 450
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0, rgba32f) uniform readonly imageCube u_src;
layout(binding = 1, rgba32f) uniform writeonly imageCube u_dst;
#ifdef VULKAN
layout(push_constant) uniform Params { int u_size; };
#else
uniform int u_size;
#endif

// include/ibl/cubemap.h's direction through (s, t) of a face, unnormalised
vec3 face_direction(int face, float s, float t)
{
    float sc = 2.0 * s - 1.0, tc = 2.0 * t - 1.0;
    if (face == 0) return vec3(1.0, -tc, -sc);
    if (face == 1) return vec3(-1.0, -tc, sc);
    if (face == 2) return vec3(sc, 1.0, tc);
    if (face == 3) return vec3(sc, -1.0, -tc);
    if (face == 4) return vec3(sc, -tc, 1.0);
    return vec3(-sc, -tc, -1.0);
}

// the face and (s, t) of a direction (OpenGL's table; ties to x, then y)
int face_st(vec3 d, out vec2 st)
{
    vec3 a = abs(d);
    int face;
    float ma, sc, tc;
    if (a.x >= a.y && a.x >= a.z) {
        face = d.x >= 0.0 ? 0 : 1;
        ma = a.x;
        sc = d.x >= 0.0 ? -d.z : d.z;
        tc = -d.y;
    } else if (a.y >= a.z) {
        face = d.y >= 0.0 ? 2 : 3;
        ma = a.y;
        sc = d.x;
        tc = d.y >= 0.0 ? d.z : -d.z;
    } else {
        face = d.z >= 0.0 ? 4 : 5;
        ma = a.z;
        sc = d.z >= 0.0 ? d.x : -d.x;
        tc = -d.y;
    }
    st = vec2(sc, tc) * (0.5 / ma) + 0.5;
    return face;
}

// the texel across edge e (0: x = 0, 1: x = n-1, 2: y = 0, 3: y = n-1) beside texel (x, y):
// the point half a texel inside the face along the major axis, on the seam, lands on the
// neighbour's texel centre (fixup_tables.c's partner at depth 0)
ivec3 partner(int face, int n, ivec2 xy, int e)
{
    vec3 m = face_direction(face, 0.5, 0.5);
    vec3 s = face_direction(face, 1.0, 0.5) - m, t = face_direction(face, 0.5, 1.0) - m;
    float sign_ = (e & 1) != 0 ? 1.0 : -1.0, major = 1.0 - 1.0 / float(n);
    float sc = e < 2 ? sign_ : (2.0 * float(xy.x) + 1.0) / float(n) - 1.0;
    float tc = e < 2 ? (2.0 * float(xy.y) + 1.0) / float(n) - 1.0 : sign_;
    vec2 st;
    int pf = face_st(major * m + sc * s + tc * t, st);
    ivec2 p = clamp(ivec2(floor(st * float(n))), ivec2(0), ivec2(n - 1));
    return ivec3(p, pf);
}

void main()
{
    ivec3 id = ivec3(gl_GlobalInvocationID); // x, y, face
    int n = u_size;
    if (id.x >= n || id.y >= n || id.z >= 6) return;
    vec4 acc = imageLoad(u_src, id);
    float count = 1.0;
    if (n == 1) {
        for (int f = 0; f < 6; f++)
            if (f != id.z) acc += imageLoad(u_src, ivec3(0, 0, f));
        count = 6.0;
    } else {
        int depth[4] = int[4](id.x, n - 1 - id.x, id.y, n - 1 - id.y);
        for (int e = 0; e < 4; e++) {
            if (depth[e] != 0) continue;
            acc += imageLoad(u_src, partner(id.z, n, id.xy, e));
            count += 1.0;
        }
    }
    imageStore(u_dst, id, acc / count);
}
