// The viewer's scene (GLSL ES 3.00, after "#version 300 es" and the text of shaders/ibl.glsl,
// which does every piece of the shading): a full-screen pass that casts one ray per pixel
// from an orbit camera into either the sphere grid of `ibl render` (7 x 3 spheres of radius
// 0.48 spaced 1.1, src/render/render.c) or a shader ball (a signed distance field, sphere
// tracing), and shades the hit with ibl_shade. Misses show the chain at u_bg_lod. Then
// exposure and the display table (ibl_tonemap_apply and sRGB, computed by `ibl view`).
layout(std140) uniform ProbeBlock { ibl_probe probe; };
uniform samplerCube u_specular;
uniform samplerCube u_mirror;
uniform samplerCube u_irradiance;
uniform sampler2D u_splitsum;
uniform highp sampler3D u_ambient;
uniform highp sampler2D u_tonemap;  // R32F, N x 2: filmic row 0, clamp row 1 (sRGB-encoded)

uniform vec2 u_size;                // canvas in pixels
uniform vec3 u_eye, u_right, u_up, u_forward;
uniform vec2 u_tan_half;            // tangents of the half field of view (x, y)
uniform int u_scene;                // 0 sphere grid, 1 shader ball
uniform float u_bg_lod;             // background level of the chain; < 0: the mirror cube
uniform ivec4 u_desc0;              // energy, so, mix, horizon_occlusion
uniform ivec4 u_desc1;              // bp_diffuse, no_mirror, nearest_level, mirror_direction
uniform float u_horizon_k;
uniform float u_sphere_ao_min;      // > 0: render.c's synthetic AO on the spheres
uniform float u_ball_ao;            // 0..1: how much of the ball's own occlusion is applied
uniform vec4 u_params[21];          // sphere grid: model, metallic, roughness, shininess
uniform vec4 u_base[21];
uniform vec4 u_f0[21];
uniform vec4 u_mat_params;          // ball: model, metallic, roughness, shininess
uniform vec3 u_mat_base;
uniform vec3 u_mat_f0;
uniform float u_exposure;           // EV
uniform int u_tonemap_row;          // 0 filmic, 1 clamp
uniform int u_linear;               // 1: write linear radiance (float targets)
uniform int u_mask;                 // 1: write white where an object is hit (tests)

out vec4 o_color;

vec3 sphere_center(int i)
{
    return vec3((float(i % 7) - 3.0) * 1.1, (1.0 - float(i / 7)) * 1.1, 0.0);
}

int hit_spheres(vec3 o, vec3 d, out float best_t)
{
    int best = -1;
    best_t = 3.402823466e38;
    for (int i = 0; i < 21; i++) {
        vec3 oc = o - sphere_center(i);
        float b = dot(oc, d), q = dot(oc, oc) - 0.48 * 0.48, disc = b * b - q;
        if (disc < 0.0) continue;
        float t = -b - sqrt(disc);
        if (t > 1e-4 && t < best_t) {
            best_t = t;
            best = i;
        }
    }
    return best;
}

// ---- the shader ball: a sphere with a recessed band over a pedestal, as a distance field ----
float sd_cylinder(vec3 p, float r, float y0, float y1)
{
    vec2 d = vec2(length(p.xz) - r, max(y0 - p.y, p.y - y1));
    return min(max(d.x, d.y), 0.0) + length(max(d, 0.0));
}

float ball_sdf(vec3 p)
{
    vec3 q = p - vec3(0.0, 0.35, 0.0);
    float outer = length(q) - 1.0;
    float band = abs(q.y - 0.12) - 0.09;            // the groove
    float shell = max(outer, -band);
    float core = length(q) - 0.86;                   // seen through the groove
    float ball = min(shell, core);
    float neck = sd_cylinder(p, 0.32, -0.95, -0.4);
    float foot = sd_cylinder(p, 0.95, -1.12, -0.95) - 0.03;
    return min(ball, min(neck, foot));
}

vec3 ball_normal(vec3 p)
{
    const vec2 k = vec2(1.0, -1.0);
    const float h = 5e-4;
    return normalize(k.xyy * ball_sdf(p + k.xyy * h) + k.yyx * ball_sdf(p + k.yyx * h) +
                     k.yxy * ball_sdf(p + k.yxy * h) + k.xxx * ball_sdf(p + k.xxx * h));
}

bool hit_ball(vec3 o, vec3 d, out float t)
{
    // bounding sphere first
    vec3 c = vec3(0.0, -0.1, 0.0);
    float b = dot(o - c, d), q = dot(o - c, o - c) - 1.8 * 1.8, disc = b * b - q;
    if (disc < 0.0) return false;
    t = max(-b - sqrt(disc), 0.0);
    float t_end = -b + sqrt(disc);
    for (int i = 0; i < 160; i++) {
        float s = ball_sdf(o + t * d);
        if (s < 2e-4 * t) return true;
        t += s;
        if (t > t_end) return false;
    }
    return false;
}

// Ambient occlusion of the ball from its distance field (samples along the normal).
float ball_occlusion(vec3 p, vec3 n)
{
    float occ = 0.0, w = 1.0;
    for (int i = 1; i <= 5; i++) {
        float h = 0.04 * float(i * i);
        occ += w * max(h - ball_sdf(p + n * h), 0.0) / h;
        w *= 0.6;
    }
    return clamp(1.0 - 0.55 * occ, 0.0, 1.0);
}

vec3 background(vec3 d)
{
    vec3 bg = u_bg_lod < 0.0 && probe.has_mirror != 0 ? textureLod(u_mirror, d, 0.0).rgb
                                                       : textureLod(u_specular, d, max(u_bg_lod, 0.0)).rgb;
    return probe.intensity * bg;
}

vec3 shade(ibl_material m, vec3 n, vec3 v)
{
    ibl_surface s = ibl_surface(n, v, vec3(0.0), vec3(0.0));
    /* light_size 0: the page has no punctual lights */
    ibl_shade_desc desc = ibl_shade_desc(u_desc0.x, u_desc0.y, u_desc0.z, u_desc0.w, u_horizon_k,
                                         u_desc1.x, u_desc1.y, u_desc1.z, u_desc1.w, 0);
    return ibl_shade(probe, u_specular, u_mirror, u_irradiance, u_splitsum, u_ambient, desc, m, s).color;
}

// The display value of a linear channel: the table at sqrt(x / 8), linearly interpolated.
float display(float x)
{
    float u = clamp(sqrt(max(x, 0.0) / 8.0), 0.0, 1.0) * float(textureSize(u_tonemap, 0).x - 1);
    int i = int(floor(u));
    int j = min(i + 1, textureSize(u_tonemap, 0).x - 1);
    float a = texelFetch(u_tonemap, ivec2(i, u_tonemap_row), 0).r;
    float b = texelFetch(u_tonemap, ivec2(j, u_tonemap_row), 0).r;
    return mix(a, b, u - float(i));
}

void main()
{
    // pixel (x, y) with y = 0 the top row, as ibl_render's image
    vec2 p = vec2(gl_FragCoord.x, u_size.y - gl_FragCoord.y);
    vec2 ndc = vec2(p.x / u_size.x * 2.0 - 1.0, 1.0 - p.y / u_size.y * 2.0);
    vec3 d = normalize(u_forward + ndc.x * u_tan_half.x * u_right + ndc.y * u_tan_half.y * u_up);
    vec3 color;
    float t;
    bool hit = true;
    if (u_scene == 0) {
        int i = hit_spheres(u_eye, d, t);
        if (i < 0) {
            hit = false;
            color = background(d);
        } else {
            vec3 n = normalize(u_eye + t * d - sphere_center(i));
            vec4 q = u_params[i];
            float ao = u_sphere_ao_min > 0.0 ? u_sphere_ao_min + (1.0 - u_sphere_ao_min) * 0.5 * (n.y + 1.0) : 1.0;
            ibl_material m = ibl_material(int(q.x), u_base[i].rgb, q.y, q.z, u_f0[i].rgb, q.w, ao);
            color = shade(m, n, -d);
        }
    } else if (hit_ball(u_eye, d, t)) {
        vec3 x = u_eye + t * d;
        vec3 n = ball_normal(x);
        float ao = mix(1.0, ball_occlusion(x, n), u_ball_ao);
        ibl_material m = ibl_material(int(u_mat_params.x), u_mat_base, u_mat_params.y,
                                      u_mat_params.z, u_mat_f0, u_mat_params.w, ao);
        color = shade(m, n, -d);
    } else {
        hit = false;
        color = background(d);
    }
    if (u_mask != 0) {
        o_color = vec4(hit ? 1.0 : 0.0);
        return;
    }
    if (u_linear != 0) {
        o_color = vec4(color, 1.0);
        return;
    }
    vec3 c = color * exp2(u_exposure);
    o_color = vec4(display(c.r), display(c.g), display(c.b), 1.0);
}
