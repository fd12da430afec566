// The sphere grid of `ibl render` (src/render/render.c) as one fragment shader over a
// full-screen triangle: a pinhole camera at (0, 0, 12) looking down -Z, 7 x 3 spheres of
// radius 0.48 spaced 1.1, each shaded by ibl_shade from shaders/ibl.glsl; the background is
// the probe's mirror cube (the unfiltered environment) or, without one, the chain's level 0. The program prepends
// "#version 450 core" and ibl.glsl. Materials come from ibl_render_scene_objects. Punctual
// lights (the block ibl_shader_lights_fill makes; count 0 for none) are shaded as render.c's
// runtime does: their specular is the compositions' direct specular, their diffuse is added.
layout(std140, binding = 0) uniform ProbeBlock { ibl_probe probe; };
layout(binding = 0) uniform samplerCube u_specular;
layout(binding = 1) uniform samplerCube u_mirror;
layout(binding = 2) uniform samplerCube u_irradiance;
layout(binding = 3) uniform sampler2D u_splitsum;
layout(binding = 4) uniform sampler3D u_ambient;
layout(std140, binding = 2) uniform LightBlock { ibl_light_set lights; };

uniform vec2 u_size;        // image width, height in pixels
uniform vec2 u_half;        // half extent of the view at z = 0 (render.c's framing)
uniform vec4 u_params[21];  // per sphere: model, metallic, roughness, shininess
uniform vec4 u_base[21];    // base colour (GGX) or Rd (Blinn-Phong)
uniform vec4 u_f0[21];      // F0 (Blinn-Phong; GGX: zero = 0.04)

layout(location = 0) out vec4 o_color;

void main()
{
    // pixel (x, y) with y = 0 the top row, as the C image
    vec2 p = vec2(gl_FragCoord.x, u_size.y - gl_FragCoord.y);
    vec2 ndc = vec2(p.x / u_size.x * 2.0 - 1.0, 1.0 - p.y / u_size.y * 2.0);
    vec3 eye = vec3(0.0, 0.0, 12.0);
    vec3 d = normalize(vec3(ndc * u_half, -12.0));
    int best = -1;
    float best_t = 3.402823466e38;
    for (int i = 0; i < 21; i++) {
        vec3 c = vec3((float(i % 7) - 3.0) * 1.1, (1.0 - float(i / 7)) * 1.1, 0.0);
        vec3 oc = eye - c;
        float b = dot(oc, d), q = dot(oc, oc) - 0.48 * 0.48, disc = b * b - q;
        if (disc < 0.0) continue;
        float t = -b - sqrt(disc);
        if (t > 1e-4 && t < best_t) {
            best_t = t;
            best = i;
        }
    }
    if (best < 0) {
        // as render.c: the mirror cube when the probe has one, else the chain's level 0
        vec3 bg = probe.has_mirror != 0 ? textureLod(u_mirror, d, 0.0).rgb
                                        : textureLod(u_specular, d, 0.0).rgb;
        o_color = vec4(probe.intensity * bg, 0.0);
        return;
    }
    vec3 c = vec3((float(best % 7) - 3.0) * 1.1, (1.0 - float(best / 7)) * 1.1, 0.0);
    vec4 q = u_params[best];
    ibl_material m = ibl_material(int(q.x), u_base[best].rgb, q.y, q.z, u_f0[best].rgb, q.w, 1.0);
    vec3 hit = eye + best_t * d;
    ibl_surface s = ibl_surface(normalize(hit - c), -d, vec3(0.0), vec3(0.0));
    ibl_shade_desc desc = ibl_shade_desc(0, 0, 0, 0, 0.0, 0, 0, 0, 0, 0); // the defaults
    ibl_light_result direct = ibl_lights_shade(lights.light, lights.count, desc, m, s, hit);
    s.direct_specular = direct.specular;
    ibl_shade_result r = ibl_shade(probe, u_specular, u_mirror, u_irradiance, u_splitsum,
                                   u_ambient, desc, m, s);
    o_color = vec4(r.color + direct.diffuse, 1.0);
}
