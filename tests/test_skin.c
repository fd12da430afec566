/* Skin: the profile, the stretch map, the thickness map, the scattered normal map and the
 * run-time term, each against an independent reference (analytic or a float64 brute force),
 * and `ibl sss`'s handling of bad inputs. */
#include "test_support.h"
#include "skin_data.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/wait.h>

static const double PI = 3.14159265358979323846;

/* The profile integrates to 1 per channel: the integral over the plane of sum_i w_i G(v_i, r),
 * by the midpoint rule in r (2 pi r dr) in float64 out to 40 mm (> 14 standard deviations of
 * the widest Gaussian). Steps of 0.0005 mm, 1/160 of the narrowest standard deviation
 * (0.08 mm): the rule's error is below 1e-6; 1e-4 leaves room for the float evaluation. */
static void profile_integrates_to_one(void **state)
{
    (void)state;
    ibl_skin_profile p = ibl_skin_profile_deon();
    assert_int_equal(p.count, 6);
    for (int c = 0; c < 3; c++) {
        double sum = 0, dr = 0.0005;
        for (double r = dr / 2; r < 40.0; r += dr) sum += 2 * PI * r * ibl_skin_profile_eval(&p, c, (float)r) * dr;
        assert_near(sum, 1.0, 1e-4);
    }
    /* the run-time transmittance at zero thickness is the weights' sum (1) and falls off with
       red last (the profile's widest Gaussians are red) */
    float t0[3], t1[3];
    ibl_skin_transmittance(NULL, 0.0f, t0);
    ibl_skin_transmittance(NULL, 1.0f, t1);
    for (int c = 0; c < 3; c++) assert_near(t0[c], 1.0, 1e-6);
    /* T_red(1 mm) = 0.358 e^(-1/1.99) + 0.078 e^(-1/7.41) + ... by hand in float64 */
    double red = 0.233 * exp(-1 / 0.0064) + 0.1 * exp(-1 / 0.0484) + 0.118 * exp(-1 / 0.187) +
                 0.113 * exp(-1 / 0.567) + 0.358 * exp(-1 / 1.99) + 0.078 * exp(-1 / 7.41);
    assert_near(t1[0], red, 1e-6);
    assert_true(t1[0] > t1[1] && t1[1] > t1[2]);
}

/* A profile table read from JSON holds exactly the numbers written (here d'Eon's). */
static void profile_from_json(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const char *path = test_path("deon.json");
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    ibl_skin_profile p = ibl_skin_profile_deon(), q;
    fprintf(f, "{\"gaussians\": [");
    for (int i = 0; i < p.count; i++)
        fprintf(f, "%s{\"variance_mm2\": %.9g, \"weights\": [%.9g, %.9g, %.9g]}", i ? ", " : "",
                (double)p.variance_mm2[i], (double)p.weight[i][0], (double)p.weight[i][1],
                (double)p.weight[i][2]);
    fprintf(f, "]}\n");
    fclose(f);
    assert_int_equal(ibl_skin_profile_load(ctx, path, &q), IBL_OK);
    assert_int_equal(q.count, p.count);
    for (int i = 0; i < p.count; i++) {
        assert_true(q.variance_mm2[i] == p.variance_mm2[i]);
        for (int c = 0; c < 3; c++) assert_true(q.weight[i][c] == p.weight[i][c]);
    }
    ibl_context_destroy(ctx);
}

static ibl_scene *load_mesh(ibl_context *ctx, const char *path)
{
    ibl_scene *s = NULL;
    assert_int_equal(ibl_scene_load(ctx, path, &s), IBL_OK);
    return s;
}

/* The stretch map of a UV sphere against the analytic metric: |dP/du| = 2 pi R sin(theta),
 * |dP/dv| = pi R. Each triangle's Jacobian is exact for the flat triangle: its U edge lies on
 * row j or j + 1 of the grid, so |dP/du| is 2 pi R sin(theta) at one of the two rows (the chord
 * of the arc shortens it by (pi / seg_u)^2 / 6 = 0.02%): the tolerance is the change of
 * 2 pi R sin(theta) over one row of dt = pi / seg_v to second order, 2 pi R (|cos theta| dt +
 * dt^2 / 2), plus 0.1%. dP/dv is the chord
 * of a meridian arc: pi R within 0.1%. */
static void stretch_of_uv_sphere(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    const char *path = test_path("sphere.obj");
    const int seg_u = 96, seg_v = 48;
    const double radius = 0.1;
    assert_int_equal(skin_write_sphere_obj(path, radius, seg_u, seg_v, 0.0), 0);
    ibl_scene *mesh = load_mesh(ctx, path);
    ibl_image st;
    assert_int_equal(ibl_skin_stretch_map(ctx, mesh, &(ibl_skin_map_desc){256, 128, 0}, &st), IBL_OK);
    int checked = 0;
    for (int y = 0; y < st.height; y++)
        for (int x = 0; x < st.width; x++) {
            const float *p = ibl_image_texel(&st, x, y);
            assert_true(p[3] == 1.0f); /* the sphere covers the whole texture */
            double theta = PI * (y + 0.5) / st.height;
            double su = 2 * PI * radius * sin(theta), sv = PI * radius;
            double dt = PI / seg_v, tol = 2 * PI * radius * (fabs(cos(theta)) * dt + dt * dt / 2 + 1e-3);
            assert_near(p[0], su, tol);
            assert_near(p[1], sv, 1e-3 * sv);
            checked++;
        }
    assert_int_equal(checked, 256 * 128);
    ibl_image_free(ctx, &st);
    ibl_scene_destroy(mesh);
    ibl_context_destroy(ctx);
}

/* Dilation: a slab's top face covers the texture, so shrink it: a box whose top face maps to
 * the texture's middle only is not needed; instead the sphere map with its poles cut out by
 * UV-less triangles is covered by the slab test below. Here: texels beyond the chart of a
 * half-covered map take their neighbours' values (never 0) and keep alpha 0. */
static void stretch_dilates_past_charts(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    const char *path = test_path("half.obj");
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    /* one quad of 2 x 1 units over the left half of the texture (u in [0, 0.5]) */
    fprintf(f, "v 0 0 0\nv 2 0 0\nv 2 0 -1\nv 0 0 -1\nvt 0 0\nvt 0.5 0\nvt 0.5 1\nvt 0 1\n"
               "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
    fclose(f);
    ibl_scene *mesh = load_mesh(ctx, path);
    ibl_image st;
    assert_int_equal(ibl_skin_stretch_map(ctx, mesh, &(ibl_skin_map_desc){64, 32, 4}, &st), IBL_OK);
    for (int y = 0; y < 32; y++) {
        /* |dP/du| = 2 / 0.5 = 4 units per texture, |dP/dv| = 1 */
        assert_near(ibl_image_texel(&st, 10, y)[0], 4.0, 1e-5);
        assert_near(ibl_image_texel(&st, 10, y)[1], 1.0, 1e-5);
        assert_true(ibl_image_texel(&st, 10, y)[3] == 1.0f);
        for (int x = 32; x < 36; x++) { /* the 4 dilated rings */
            assert_near(ibl_image_texel(&st, x, y)[0], 4.0, 1e-5);
            assert_true(ibl_image_texel(&st, x, y)[3] == 0.0f);
        }
        assert_true(ibl_image_texel(&st, 36, y)[0] == 0.0f); /* past the dilation */
    }
    ibl_image_free(ctx, &st);
    ibl_scene_destroy(mesh);
    ibl_context_destroy(ctx);
}

/* Thickness of a sphere against the chord: along the inward normal it is 2R (the surface
 * point lies on a flat triangle, at most R (1 - cos(pi / seg_v)) = 0.2% inside the sphere,
 * and the interpolated normal leans by less than a triangle's angle: 1% covers both). Over a
 * cone the rays' chords are 2R cos(theta_k) with cos(theta_k) spread evenly over
 * [cos(alpha), 1], whose mean is exactly R (1 + cos(alpha)). */
static void thickness_of_sphere(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    const char *path = test_path("ball.obj");
    const double radius = 0.05;
    assert_int_equal(skin_write_sphere_obj(path, radius, 96, 48, 0.0), 0);
    ibl_scene *mesh = load_mesh(ctx, path);
    ibl_image one, cone;
    ibl_skin_thickness_desc d = {{64, 32, 0}, 1, 0, 0};
    assert_int_equal(ibl_skin_thickness_map(ctx, mesh, &d, &one), IBL_OK);
    d.rays = 64;
    d.cone_degrees = 40;
    assert_int_equal(ibl_skin_thickness_map(ctx, mesh, &d, &cone), IBL_OK);
    ibl_context *one_thread = test_context(1);
    ibl_image again;
    assert_int_equal(ibl_skin_thickness_map(one_thread, mesh, &d, &again), IBL_OK);
    assert_memory_equal(again.pixels, cone.pixels, sizeof(float) * 4 * 64 * 32);
    ibl_image_free(one_thread, &again);
    ibl_context_destroy(one_thread);
    double cone_mean = radius * (1 + cos(40 * PI / 180));
    for (int y = 2; y < 30; y++) /* away from the poles' fans */
        for (int x = 0; x < 64; x++) {
            assert_near(ibl_image_texel(&one, x, y)[0], 2 * radius, 0.01 * 2 * radius);
            assert_near(ibl_image_texel(&cone, x, y)[0], cone_mean, 0.01 * 2 * radius);
        }
    ibl_image_free(ctx, &one);
    ibl_image_free(ctx, &cone);
    ibl_scene_destroy(mesh);
    ibl_context_destroy(ctx);
}

/* Thickness of a slab of depth d: each ray at angle theta crosses d / cos(theta); over the cone
 * the mean of 1 / cos(theta) for cos(theta) uniform on [cos(alpha), 1] is
 * ln(1 / cos(alpha)) / (1 - cos(alpha)) (the integral), which the 64 evenly spread rays meet
 * within 0.1% (the midpoint rule on a smooth integrand); 0.5% allowed. Texels far enough from
 * the slab's sides that no ray leaves through them. */
static void thickness_of_slab(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    const char *path = test_path("slab.obj");
    const double depth = 0.01, alpha = 30 * PI / 180;
    assert_int_equal(skin_write_slab_obj(path, 0.1, 0.1, depth), 0);
    ibl_scene *mesh = load_mesh(ctx, path);
    ibl_image one, cone;
    ibl_skin_thickness_desc d = {{32, 32, 0}, 1, 0, 0};
    assert_int_equal(ibl_skin_thickness_map(ctx, mesh, &d, &one), IBL_OK);
    d.rays = 64;
    assert_int_equal(ibl_skin_thickness_map(ctx, mesh, &d, &cone), IBL_OK);
    double mean = depth * log(1 / cos(alpha)) / (1 - cos(alpha));
    for (int y = 8; y < 24; y++)
        for (int x = 8; x < 24; x++) {
            assert_near(ibl_image_texel(&one, x, y)[0], depth, 1e-5 * depth);
            assert_near(ibl_image_texel(&cone, x, y)[0], mean, 0.005 * mean);
        }
    /* and the transmittance map: t = 1 - d mm_per_unit / range = 1 - 10 / 20 */
    ibl_skin_transmittance_from_thickness(&one, 1000.0f, 20.0f);
    assert_near(ibl_image_texel(&one, 16, 16)[0], 0.5, 1e-5);
    ibl_image_free(ctx, &one);
    ibl_image_free(ctx, &cone);
    ibl_scene_destroy(mesh);
    ibl_context_destroy(ctx);
}

/* ---- scattering on a flat plane --------------------------------------------------------- */

enum { PW = 512, PH = 64 };
static const double PERIOD = 64.0, AMP = 0.6, TEXEL_MM = 0.08;

/* The continuous Gaussian blur (standard deviation s texels) of the normal map's z component
 * sqrt(1 - a^2 sin^2(k x)) at x, by the midpoint rule over +-8 s in steps of s / 200 (float64). */
static double blurred_z(double x, double s)
{
    double k = 2 * PI / PERIOD, sum = 0, wsum = 0, h = s / 200;
    for (double t = -8 * s + h / 2; t < 8 * s; t += h) {
        double g = exp(-0.5 * t * t / (s * s)), sn = sin(k * (x - t));
        sum += g * sqrt(1 - AMP * AMP * sn * sn);
        wsum += g;
    }
    return sum / wsum;
}

/* A plane with uniform stretch (every texel 0.08 mm: the narrowest Gaussian is one texel wide,
 * the widest 34) and a normal map n = (a sin(k x), 0, sqrt(1 - a^2 sin^2(k x))), constant along
 * V. The reference, per channel, is sum_i w_i of the continuous blur: the x component
 * a sin(k x) exp(-k^2 s_i^2 / 2) exactly, the z component by quadrature, then normalised.
 * Tolerance 0.005 on each component of the unit normal: the sampled, 3-sigma-truncated kernels
 * and the 2x2 pyramid with bilinear upsampling (the widest three Gaussians) match the
 * Gaussians' variance, not their higher moments (measured: 0.0014 at this frequency). Only
 * columns 160 wide away from the map's clamped edges are compared. */
static void scatter_flat_plane_matches_gaussian_blur(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    ibl_image normal, stretch, out[3];
    assert_int_equal(ibl_image_alloc(ctx, PW, PH, &normal), IBL_OK);
    assert_int_equal(ibl_image_alloc(ctx, PW, PH, &stretch), IBL_OK);
    double k = 2 * PI / PERIOD;
    for (int y = 0; y < PH; y++)
        for (int x = 0; x < PW; x++) {
            double sn = AMP * sin(k * (x + 0.5));
            float *n = ibl_image_texel(&normal, x, y), *s = ibl_image_texel(&stretch, x, y);
            n[0] = (float)(0.5 * sn + 0.5);
            n[1] = 0.5f;
            n[2] = (float)(0.5 * sqrt(1 - sn * sn) + 0.5);
            n[3] = 1.0f;
            /* mesh units = mm here; |dP/du| = texels x mm per texel */
            s[0] = (float)(PW * TEXEL_MM);
            s[1] = (float)(PH * TEXEL_MM);
            s[2] = 0.0f;
            s[3] = 1.0f;
        }
    ibl_skin_scatter_desc d = {NULL, 1.0f, 0};
    assert_int_equal(ibl_skin_scatter_normals(ctx, &normal, &stretch, &d, out), IBL_OK);
    ibl_skin_profile p = ibl_skin_profile_deon();
    double worst = 0;
    for (int x = PW / 2 - 80; x < PW / 2 + 80; x++) {
        double xc = x + 0.5;
        for (int c = 0; c < 3; c++) {
            double m[3] = {0, 0, 0};
            for (int i = 0; i < p.count; i++) {
                double s = sqrt(p.variance_mm2[i]) / TEXEL_MM;
                m[0] += p.weight[i][c] * AMP * sin(k * xc) * exp(-0.5 * k * k * s * s);
                m[2] += p.weight[i][c] * blurred_z(xc, s);
            }
            double len = sqrt(m[0] * m[0] + m[2] * m[2]);
            for (int y = 0; y < PH; y += 9) {
                const float *o = ibl_image_texel(&out[c], x, y);
                double got[3] = {2.0 * o[0] - 1, 2.0 * o[1] - 1, 2.0 * o[2] - 1};
                double e = fmax(fabs(got[0] - m[0] / len), fmax(fabs(got[1]), fabs(got[2] - m[2] / len)));
                if (e > worst) worst = e;
            }
        }
    }
    printf("flat plane: worst component error %.5f\n", worst);
    assert_true(worst < 0.005);
    /* red scatters furthest: its normals are the flattest */
    const float *r = ibl_image_texel(&out[0], PW / 2 + 16, 0), *b = ibl_image_texel(&out[2], PW / 2 + 16, 0);
    assert_true(fabs(r[0] - 0.5) < fabs(b[0] - 0.5));
    /* bit-identical on one thread */
    ibl_context *one = test_context(1);
    ibl_image again[3];
    assert_int_equal(ibl_skin_scatter_normals(one, &normal, &stretch, &d, again), IBL_OK);
    for (int c = 0; c < 3; c++) {
        assert_memory_equal(again[c].pixels, out[c].pixels, sizeof(float) * 4 * PW * PH);
        ibl_image_free(one, &again[c]);
        ibl_image_free(ctx, &out[c]);
    }
    ibl_context_destroy(one);
    ibl_image_free(ctx, &normal);
    ibl_image_free(ctx, &stretch);
    ibl_context_destroy(ctx);
}

/* ---- the run time ------------------------------------------------------------------------ */

/* With a constant SH irradiance the three normals do not matter, the diffuse term is albedo E/pi;
 * the translucent term is albedo T(d) E/pi, with T from the profile by hand. */
static void shade_constant_light(void **state)
{
    (void)state;
    ibl_probe probe;
    memset(&probe, 0, sizeof probe);
    probe.sh_kind = IBL_SH_KIND_IRRADIANCE;
    for (int c = 0; c < 3; c++) probe.sh[0][c] = (float)(PI / 0.282095); /* E = pi everywhere */
    ibl_skin_surface s;
    memset(&s, 0, sizeof s);
    s.n[0] = (ibl_vec3){0, 1, 0};
    s.n[1] = (ibl_vec3){1, 0, 0};
    s.n[2] = (ibl_vec3){0, 0, -1};
    s.geometric_normal = (ibl_vec3){0, 1, 0};
    s.albedo[0] = 0.8f, s.albedo[1] = 0.5f, s.albedo[2] = 0.4f;
    s.transmittance = 0.75f; /* d = 0.25 x 8 mm = 2 mm */
    ibl_skin_result r;
    ibl_skin_shade(&probe, NULL, &s, &r);
    ibl_skin_profile p = ibl_skin_profile_deon();
    for (int c = 0; c < 3; c++) {
        double t = 0;
        for (int i = 0; i < 6; i++) t += p.weight[i][c] * exp(-4.0 / p.variance_mm2[i]);
        assert_near(r.diffuse[c], s.albedo[c], 1e-5);
        assert_near(r.translucent[c], s.albedo[c] * t, 1e-5);
        assert_near(r.color[c], r.diffuse[c] + r.translucent[c], 1e-6);
    }
}

/* A linear SH (E(n) = pi (1 + 0.5 n_y)): each channel reads its own normal. */
static void shade_reads_each_channel_along_its_normal(void **state)
{
    (void)state;
    ibl_probe probe;
    memset(&probe, 0, sizeof probe);
    probe.sh_kind = IBL_SH_KIND_IRRADIANCE;
    for (int c = 0; c < 3; c++) {
        probe.sh[0][c] = (float)(PI / 0.282095);
        probe.sh[1][c] = (float)(0.5 * PI / 0.488603); /* Y_1,-1 = 0.488603 y */
    }
    ibl_skin_surface s;
    memset(&s, 0, sizeof s);
    s.n[0] = (ibl_vec3){0, 1, 0};
    s.n[1] = (ibl_vec3){1, 0, 0};
    s.n[2] = (ibl_vec3){0, -1, 0};
    s.geometric_normal = (ibl_vec3){0, 1, 0};
    s.albedo[0] = s.albedo[1] = s.albedo[2] = 1.0f;
    ibl_skin_result r;
    ibl_skin_shade(&probe, NULL, &s, &r);
    assert_near(r.diffuse[0], 1.5, 1e-5);
    assert_near(r.diffuse[1], 1.0, 1e-5);
    assert_near(r.diffuse[2], 0.5, 1e-5);
    for (int c = 0; c < 3; c++) assert_true(r.translucent[c] == 0.0f);
}

/* ---- the preview renderer ----------------------------------------------------------------- */

/* Skin in ibl_render: with scattered maps equal to the normal map and no transmittance, skin on
 * and skin off are the same image bit for bit (the wiring reads the maps it is given); flat
 * scattered maps change it; the reference refuses skin. */
static void render_skin_wiring(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(2);
    const char *path = test_path("render_ball.obj");
    assert_int_equal(skin_write_sphere_obj(path, 0.1, 48, 24, 0.0), 0);
    ibl_scene *mesh = load_mesh(ctx, path);
    ibl_cubemap env;
    assert_int_equal(ibl_cubemap_alloc(ctx, 16, 1, &env), IBL_OK);
    test_fill_smooth(&env);
    ibl_bake_desc bd;
    ibl_render_bake_desc(&env, 16, &bd);
    ibl_bake_data bake;
    ibl_probe probe;
    assert_int_equal(ibl_bake_compute(ctx, &env, &bd, &bake), IBL_OK);
    assert_int_equal(ibl_bake_probe(ctx, &bake, &probe), IBL_OK);
    ibl_image normal, flat;
    assert_int_equal(ibl_image_alloc(ctx, 64, 32, &normal), IBL_OK);
    assert_int_equal(ibl_image_alloc(ctx, 64, 32, &flat), IBL_OK);
    skin_pores_normal_map(&normal, 8, 1.0);
    for (int i = 0; i < 64 * 32; i++) {
        flat.pixels[4 * i] = flat.pixels[4 * i + 1] = 0.5f;
        flat.pixels[4 * i + 2] = flat.pixels[4 * i + 3] = 1.0f;
    }
    ibl_render_skin skin = {mesh, &normal, {&normal, &normal, &normal}, NULL, {0, 0, 0}, 0, 0};
    ibl_render_desc d;
    memset(&d, 0, sizeof d);
    d.width = 96;
    d.height = 48;
    d.skin = &skin;
    ibl_image on, off, smooth;
    assert_int_equal(ibl_render(ctx, &probe, &d, &on, NULL), IBL_OK);
    d.skin_off = 1;
    assert_int_equal(ibl_render(ctx, &probe, &d, &off, NULL), IBL_OK);
    assert_memory_equal(on.pixels, off.pixels, sizeof(float) * 4 * 96 * 48);
    d.skin_off = 0;
    for (int c = 0; c < 3; c++) skin.scattered[c] = &flat;
    assert_int_equal(ibl_render(ctx, &probe, &d, &smooth, NULL), IBL_OK);
    assert_memory_not_equal(on.pixels, smooth.pixels, sizeof(float) * 4 * 96 * 48);
    /* the centre pixel hits the ball: its colour is finite and positive */
    const float *centre = ibl_image_texel(&smooth, 48, 24);
    assert_true(centre[0] > 0.0f && centre[0] < 1e6f);
    d.reference = 1;
    ibl_image ref;
    assert_int_equal(ibl_render(ctx, &probe, &d, &ref, NULL), IBL_ERR_UNSUPPORTED);
    ibl_image_free(ctx, &on);
    ibl_image_free(ctx, &off);
    ibl_image_free(ctx, &smooth);
    ibl_image_free(ctx, &normal);
    ibl_image_free(ctx, &flat);
    ibl_bake_free(ctx, &bake);
    ibl_cubemap_free(ctx, &env);
    ibl_scene_destroy(mesh);
    ibl_context_destroy(ctx);
}

/* ---- the command line ----------------------------------------------------------------------- */

static int count_lines(const char *s)
{
    int n = 0;
    for (; *s; s++) n += *s == '\n';
    return n;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void cli_writes_maps_and_refuses_bad_inputs(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    char mesh[512], normal[512];
    snprintf(mesh, sizeof mesh, "%s", test_path("cli_ball.obj"));
    snprintf(normal, sizeof normal, "%s", test_path("pores.png"));
    assert_int_equal(skin_write_sphere_obj(mesh, 0.1, 32, 16, 0.0), 0);
    ibl_image n;
    assert_int_equal(ibl_image_alloc(ctx, 64, 32, &n), IBL_OK);
    skin_pores_normal_map(&n, 8, 1.0);
    ibl_write_desc wd = {.format = IBL_FORMAT_RGBA16_UNORM};
    assert_int_equal(ibl_write_image(ctx, normal, &n, &wd), IBL_OK);
    const char *out;
    char base[512];
    snprintf(base, sizeof base, "%s", test_path("scattered.png"));
    assert_int_equal(test_run_cli(&out, "sss -q --mesh %s --normal %s -o %s --transmittance %s",
                                  mesh, normal, base, test_path("trans.png")), 0);
    assert_true(test_file_exists(test_path("scattered_r.png")));
    assert_true(test_file_exists(test_path("scattered_g.png")));
    assert_true(test_file_exists(test_path("scattered_b.png")));
    assert_true(test_file_exists(test_path("trans.png")));
    /* the maps read back as data: unit normals, red flatter than blue on average */
    ibl_image r, b;
    assert_int_equal(ibl_read_image(ctx, test_path("scattered_r.png"), &(ibl_read_desc){.as_data = 1}, &r, NULL), IBL_OK);
    assert_int_equal(ibl_read_image(ctx, test_path("scattered_b.png"), &(ibl_read_desc){.as_data = 1}, &b, NULL), IBL_OK);
    double tilt_r = 0, tilt_b = 0;
    for (int i = 0; i < 64 * 32; i++) {
        double v[3], len = 0;
        for (int c = 0; c < 3; c++) {
            v[c] = 2.0 * r.pixels[4 * i + c] - 1;
            len += v[c] * v[c];
        }
        assert_near(len, 1.0, 1e-3); /* 16-bit quantisation */
        tilt_r += 1 - v[2];
        tilt_b += 1 - (2.0 * b.pixels[4 * i + 2] - 1);
    }
    assert_true(tilt_r < tilt_b);
    ibl_image_free(ctx, &r);
    ibl_image_free(ctx, &b);

    /* bad inputs: one line naming the file, exit 1, nothing written */
    const char *flat = test_path("flat.obj"), *bad_profile = test_path("bad.json");
    write_text(flat, "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
    write_text(bad_profile, "{\"gaussians\": [{\"variance_mm2\": -1, \"weights\": [1, 1, 1]}]}");
    write_text(test_path("junk.gltf"), "{\"asset\": {\"version\": \"2.0\"}, \"meshes\": [{\"primitives\": 7}]}");
    const char *cases[][2] = {
        {"--mesh %s/none.obj --normal %s -o %s", "none.obj"},
        {"--mesh %s/flat.obj --normal %s -o %s", "flat.obj"},
        {"--mesh %s/cli_ball.obj --normal %s.missing -o %s", "pores.png.missing"},
        {"--mesh %s/cli_ball.obj --normal %s -o %s --profile bad.json", "bad.json"},
        {"--mesh %s/junk.gltf --normal %s -o %s", "junk.gltf"},
    };
    for (int i = 0; i < 5; i++) {
        char fmt[256], outp[512];
        snprintf(outp, sizeof outp, "%s", test_path("bad_out.png"));
        snprintf(fmt, sizeof fmt, "cd %s && %s sss -q %s", test_tmpdir(), IBL_CLI_PATH, cases[i][0]);
        char cmd[2048];
        snprintf(cmd, sizeof cmd, fmt, test_tmpdir(), normal, outp);
        char full[2100];
        snprintf(full, sizeof full, "%s 2>&1", cmd);
        FILE *pipe = popen(full, "r");
        assert_non_null(pipe);
        char text[1024] = {0};
        size_t got = fread(text, 1, sizeof text - 1, pipe);
        text[got] = 0;
        int rc = pclose(pipe);
        printf("%s", text);
        assert_int_equal(WEXITSTATUS(rc), 1);
        assert_int_equal(count_lines(text), 1);
        assert_non_null(strstr(text, cases[i][1]));
        assert_false(test_file_exists(test_path("bad_out_r.png")));
    }
    /* ibl render with a missing scattered map: one line naming it, no image */
    assert_int_equal(test_run_cli(&out, "render -q sky --specular-size 16 --scene %s --scattered %s/none.png --normal %s "
                                  "--width 32 -o %s", mesh, test_tmpdir(), normal,
                                  test_path("render_out.png")), 1);
    assert_int_equal(count_lines(out), 1);
    assert_non_null(strstr(out, "none_r.png"));
    assert_false(test_file_exists(test_path("render_out.png")));
    /* and with the maps it draws skin on and off side by side */
    assert_int_equal(test_run_cli(&out, "render -q sky --specular-size 16 --scene %s --scattered %s --normal %s "
                                  "--transmittance %s --width 64 --compare skin=off skin=on -o %s",
                                  mesh, base, normal, test_path("trans.png"),
                                  test_path("render_out.png")), 0);
    assert_true(test_file_exists(test_path("render_out.png")));
    ibl_image_free(ctx, &n);
    ibl_context_destroy(ctx);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(profile_integrates_to_one),
        cmocka_unit_test(profile_from_json),
        cmocka_unit_test(stretch_of_uv_sphere),
        cmocka_unit_test(stretch_dilates_past_charts),
        cmocka_unit_test(thickness_of_sphere),
        cmocka_unit_test(thickness_of_slab),
        cmocka_unit_test(scatter_flat_plane_matches_gaussian_blur),
        cmocka_unit_test(shade_constant_light),
        cmocka_unit_test(shade_reads_each_channel_along_its_normal),
        cmocka_unit_test(render_skin_wiring),
        cmocka_unit_test(cli_writes_maps_and_refuses_bad_inputs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
