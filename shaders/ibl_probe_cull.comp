// ibl_probe_cull.comp - tiled culling of probe influence volumes against screen tiles with
// per-tile depth bounds ("Image Based Lighting", Just Another Game Engine blog, 2015, "Tiled
// Probe Culling"), the GPU twin of ibl_cull_probes (src/probes/probe_runtime.c; docs/PROBES.md
// "Run time"), tested list for list against it in tests/test_shaders_probes.c.
//
// One work group of 16x16 threads per 16x16-pixel tile: the tile's least and greatest valid
// depth (> 0 and finite; a tile of background gets an empty list) by shared atomics on the
// float bits (positive floats order as their bits do); the tile frustum's 6 planes, the side
// planes through the tile's pixel edges and near/far at the depth bounds (x (1 -+ 1e-5));
// each thread tests probes (a sphere's centre against its radius, a box's 8 corners) and
// appends survivors with atomicAdd, so they come in no set order; with u_exact, a probe stays
// only if some pixel's point of the tile lies inside its influence volume (the lists then
// equal a per-pixel brute force). Then the list is sorted into ascending record index (the
// records are stored in blend order) with one of the write-up's three sorts, u_sort:
//   0  odd-even transposition on one thread (its first)
//   1  rank sort in place: each entry counts the smaller ones, barrier, write (two barriers)
//   2  rank sort into a second array (one barrier)
//
// Bindings: buffer 0 the probe records (probes.bin, std430 ibl_local_probe, 240 bytes),
// buffer 1 the view depth (width x height floats, row 0 at the top; view depth along the
// camera's forward axis), buffer 2 the output: per tile u_capacity indices, buffer 3 the
// tile's list length, buffer 4 one uint: the comparisons the sorts made (atomicAdd; the
// bench's count). Dispatch (ceil(width / 16), ceil(height / 16), 1). At most
// IBL_CULL_MAX_PROBES probes per dispatch.
#version 450
layout(local_size_x = 16, local_size_y = 16, local_size_z = 1) in;
#define IBL_CULL_TILE 16
#define IBL_CULL_MAX_PROBES 256

struct ibl_local_probe {
    vec4 position_size;
    vec4 influence_center_radius;
    vec4 influence_half_extent_blend;
    vec4 proxy_center_radius;
    vec4 proxy_half_extent_coverage;
    ivec4 shapes_layer_priority;
    vec4 sh[9];
};
layout(std430, binding = 0) readonly buffer Probes { ibl_local_probe probes[]; };
layout(std430, binding = 1) readonly buffer Depth { float depth[]; };
layout(std430, binding = 2) writeonly buffer Lists { int lists[]; };
layout(std430, binding = 3) writeonly buffer Lengths { int lengths[]; };
layout(std430, binding = 4) buffer Stats { uint compares; };

#ifdef VULKAN
layout(push_constant) uniform Params {
    vec4 u_position, u_right, u_up, u_forward; // camera basis (unit), xyz
    vec2 u_tan;                                // tan(fov_y / 2) width / height, tan(fov_y / 2)
    ivec2 u_size;
    int u_count, u_sort, u_exact, u_capacity;
};
#else
uniform vec4 u_position, u_right, u_up, u_forward;
uniform vec2 u_tan;
uniform ivec2 u_size;
uniform int u_count, u_sort, u_exact, u_capacity;
#endif

shared uint s_dmin, s_dmax, s_n;
shared int s_list[IBL_CULL_MAX_PROBES], s_sorted[IBL_CULL_MAX_PROBES];
shared uint s_inside[IBL_CULL_MAX_PROBES / 32];

bool depth_valid(float d) { return d > 0.0 && d < 3.402823466e38; }

vec3 to_camera(vec3 p)
{
    vec3 q = p - u_position.xyz;
    return vec3(dot(q, u_right.xyz), dot(q, u_up.xyz), dot(q, u_forward.xyz));
}

vec4 make_plane(float a, float b, float c, float d)
{
    float len = sqrt(a * a + b * b + c * c);
    return vec4(a / len, b / len, c / len, d / len);
}

// every point of the volume (a sphere's centre with its radius, a box's 8 corners) outside?
bool outside(vec4 pl, ibl_local_probe r)
{
    vec3 c = r.influence_center_radius.xyz;
    if (r.shapes_layer_priority.x == 0) {
        vec3 p = to_camera(c);
        return !(dot(pl.xyz, p) + pl.w >= -r.influence_center_radius.w);
    }
    vec3 h = r.influence_half_extent_blend.xyz;
    for (int i = 0; i < 8; i++) {
        vec3 p = to_camera(c + vec3((i & 1) != 0 ? h.x : -h.x, (i & 2) != 0 ? h.y : -h.y,
                                    (i & 4) != 0 ? h.z : -h.z));
        if (dot(pl.xyz, p) + pl.w >= 0.0) return false;
    }
    return true;
}

// ibl_volume_weight(influence, p) > 0: inside, the surface included
bool inside(ibl_local_probe r, vec3 p)
{
    vec3 d = p - r.influence_center_radius.xyz;
    float dist;
    if (r.shapes_layer_priority.x == 1) {
        vec3 a = r.influence_half_extent_blend.xyz - abs(d);
        dist = min(min(a.x, a.y), a.z);
    } else {
        dist = r.influence_center_radius.w - length(d);
    }
    if (dist < 0.0) return false;
    return r.influence_half_extent_blend.w <= 0.0 || dist > 0.0;
}

void main()
{
    uint t = gl_LocalInvocationIndex;
    ivec2 tile = ivec2(gl_WorkGroupID.xy);
    int tile_index = tile.y * int(gl_NumWorkGroups.x) + tile.x;
    ivec2 px = tile * IBL_CULL_TILE + ivec2(gl_LocalInvocationID.xy);
    int W = u_size.x, H = u_size.y;
    if (t == 0u) {
        s_dmin = 0x7f7fffffu; // FLT_MAX's bits
        s_dmax = 0u;
        s_n = 0u;
    }
    if (t < uint(IBL_CULL_MAX_PROBES / 32)) s_inside[t] = 0u;
    barrier();
    float d = 0.0;
    bool mine = px.x < W && px.y < H;
    if (mine) {
        d = depth[px.y * W + px.x];
        if (depth_valid(d)) {
            atomicMin(s_dmin, floatBitsToUint(d));
            atomicMax(s_dmax, floatBitsToUint(d));
        } else {
            mine = false;
        }
    }
    barrier();
    float dmin = uintBitsToFloat(s_dmin), dmax = uintBitsToFloat(s_dmax);
    if (s_dmax == 0u) { // background only: every thread leaves together
        if (t == 0u) lengths[tile_index] = 0;
        return;
    }
    int x0 = tile.x * IBL_CULL_TILE, y0 = tile.y * IBL_CULL_TILE;
    int x1 = min(x0 + IBL_CULL_TILE, W), y1 = min(y0 + IBL_CULL_TILE, H);
    float sx0 = (2.0 * float(x0) / float(W) - 1.0) * u_tan.x, sx1 = (2.0 * float(x1) / float(W) - 1.0) * u_tan.x;
    float syt = (1.0 - 2.0 * float(y0) / float(H)) * u_tan.y, syb = (1.0 - 2.0 * float(y1) / float(H)) * u_tan.y;
    vec4 planes[6] = vec4[6](make_plane(1.0, 0.0, -sx0, 0.0), make_plane(-1.0, 0.0, sx1, 0.0),
                             make_plane(0.0, 1.0, -syb, 0.0), make_plane(0.0, -1.0, syt, 0.0),
                             make_plane(0.0, 0.0, 1.0, -dmin * (1.0 - 1e-5)),
                             make_plane(0.0, 0.0, -1.0, dmax * (1.0 + 1e-5)));
    for (uint i = t; i < uint(u_count); i += uint(IBL_CULL_TILE * IBL_CULL_TILE)) {
        ibl_local_probe r = probes[i];
        bool culled = false;
        for (int k = 0; k < 6 && !culled; k++) culled = outside(planes[k], r);
        if (!culled) s_list[atomicAdd(s_n, 1u)] = int(i);
    }
    barrier();
    uint n = s_n;
    if (u_exact != 0) {
        if (mine) { // this pixel's point: the camera ray through its centre at its depth
            float sx = (2.0 * (float(px.x) + 0.5) / float(W) - 1.0) * u_tan.x;
            float sy = (1.0 - 2.0 * (float(px.y) + 0.5) / float(H)) * u_tan.y;
            vec3 ray = u_forward.xyz + (sx * u_right.xyz + sy * u_up.xyz); // ibl_camera_ray's order
            vec3 p = u_position.xyz + d * ray;
            for (uint j = 0u; j < n; j++)
                if (inside(probes[s_list[j]], p)) atomicOr(s_inside[j / 32u], 1u << (j % 32u));
        }
        barrier();
        if (t == 0u) { // keep the listed probes some pixel lies in, in list order
            uint kept = 0u;
            for (uint j = 0u; j < n; j++)
                if ((s_inside[j / 32u] & (1u << (j % 32u))) != 0u) s_list[kept++] = s_list[j];
            s_n = kept;
        }
        barrier();
        n = s_n;
    }
    if (u_sort == 0) { // odd-even transposition, one thread
        if (t == 0u && n > 1u) {
            uint c = 0u;
            for (uint pass = 0u; pass < n; pass++)
                for (uint i = 1u + (pass & 1u); i < n; i += 2u) {
                    c++;
                    if (s_list[i] < s_list[i - 1u]) {
                        int tmp = s_list[i];
                        s_list[i] = s_list[i - 1u];
                        s_list[i - 1u] = tmp;
                    }
                }
            atomicAdd(compares, c);
        }
        barrier();
    } else {
        int v = 0, rank = 0;
        if (t < n) {
            v = s_list[t];
            for (uint j = 0u; j < n; j++) rank += s_list[j] < v ? 1 : 0;
            if (n > 1u) atomicAdd(compares, n);
        }
        if (u_sort == 1) { // in place: everyone has read before anyone writes
            barrier();
            if (t < n) s_list[rank] = v;
        } else { // into the second array: no barrier before the write
            if (t < n) s_sorted[rank] = v;
        }
        barrier();
    }
    if (t < n && int(t) < u_capacity)
        lists[tile_index * u_capacity + int(t)] = u_sort == 2 ? s_sorted[t] : s_list[t];
    if (t == 0u) lengths[tile_index] = int(min(n, uint(u_capacity)));
}
