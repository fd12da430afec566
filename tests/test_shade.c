/* Runtime shading (shade.h) against independent references: a float64 quadrature of the GGX
 * directional albedo written here, hand-computed values of tri-Ace 2010's formulas, analytic
 * ray/box and ray/sphere hits, and exact round trips. */
#include "test_support.h"

#include "ibl/brdf.h"

#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* ---------------------------------------------------------------------------------------- */
/* Independent reference: GGX directional albedo (single scattering, height-correlated Smith,
 * Schlick) by a midpoint rule in the variables (xi, phi) that map the GGX NDF's projected
 * measure D(h) n.h dw_h to dxi dphi / 2pi, in double. Returns A and B with E = F0 A + B. */
static void reference_ab(double nv, double r, int steps, double *a_out, double *b_out)
{
    double alpha = r * r, a2 = alpha * alpha;
    double vx = sqrt(1.0 - nv * nv), vz = nv;
    double sa = 0.0, sb = 0.0;
    for (int i = 0; i < steps; i++) {
        double xi = (i + 0.5) / steps;
        double c2 = (1.0 - xi) / (1.0 + (a2 - 1.0) * xi);
        double ct = sqrt(c2), st = sqrt(1.0 - c2);
        for (int j = 0; j < steps; j++) {
            double phi = 2.0 * PI * (j + 0.5) / steps;
            double hx = st * cos(phi), hy = st * sin(phi), hz = ct;
            (void)hy;
            double vh = vx * hx + vz * hz;
            double nl = 2.0 * vh * hz - vz;
            if (nl <= 0.0 || vh <= 0.0) continue;
            double lv = nl * sqrt(nv * nv * (1.0 - a2) + a2),
                   ll = nv * sqrt(nl * nl * (1.0 - a2) + a2);
            double vis = 0.5 / (lv + ll);
            double w = vis * 4.0 * vh * nl / hz; /* D V F n.l 4 v.h / (D n.h) */
            double fc = pow(1.0 - vh, 5.0);
            sa += (1.0 - fc) * w;
            sb += fc * w;
        }
    }
    *a_out = sa / ((double)steps * steps);
    *b_out = sb / ((double)steps * steps);
}

/* The library's split-sum table (brdf.h), 32 texels, texel-centred on both axes. */
enum { TSIZE = 32 };
static ibl_image lut;

static ibl_splitsum_view make_table(ibl_context *ctx)
{
    if (!lut.pixels) {
        ibl_brdf_lut_desc d = {.size = TSIZE};
        assert_int_equal(ibl_brdf_lut(ctx, &d, &lut), IBL_OK);
    }
    ibl_table_axis axis = {TSIZE, 0.5f / TSIZE, 1.0f - 0.5f / TSIZE, 0};
    ibl_splitsum_view t = {lut.pixels, 4, axis, axis};
    return t;
}

/* A probe over a constant white environment: every level 1, irradiance SH of radiance 1. */
static void white_probe(ibl_context *ctx, ibl_probe *p, ibl_cubemap *cube, int levels)
{
    memset(p, 0, sizeof *p);
    assert_int_equal(ibl_cubemap_alloc(ctx, 8, levels, cube), IBL_OK);
    test_fill_cube(cube, 1, 1, 1);
    p->specular = *cube;
    p->mapping.levels = levels;
    for (int k = 0; k < levels; k++) p->mapping.roughness[k] = (float)k / (float)(levels - 1);
    p->sh_kind = IBL_SH_KIND_RADIANCE;
    /* projection of L = 1 on Y00: 0.282095 * 4 pi */
    for (int c = 0; c < 3; c++) p->sh[0][c] = (float)(0.28209479 * 4.0 * PI);
    p->splitsum = make_table(ctx);
    assert_int_equal(ibl_probe_validate(ctx, p), IBL_OK);
}

static ibl_surface surface_at(double nv)
{
    ibl_surface s;
    memset(&s, 0, sizeof s);
    s.n = (ibl_vec3){0, 0, 1};
    s.v = (ibl_vec3){(float)sqrt(1.0 - nv * nv), 0, (float)nv};
    return s;
}

static void furnace(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_probe p;
    ibl_cubemap cube;
    white_probe(ctx, &p, &cube, 4);
    /* the SH path reproduces the constant: IEM = E / pi = 1 (float rounding only) */
    float irr[3];
    ibl_probe_irradiance(&p, (ibl_vec3){0.3f, -0.8f, 0.52f}, irr);
    assert_near(irr[0], 1.0, 1e-5);
    static const float one[3] = {1, 1, 1};
    double worst_plain = 0;
    for (int ri = 0; ri <= 10; ri++) {
        for (int vi = 0; vi <= 9; vi++) {
            double r = ri / 10.0, nv = 0.07 + 0.093 * vi;
            ibl_material m = ibl_material_gltf(one, 1.0f, (float)r);
            ibl_surface s = surface_at(nv);
            ibl_shade_result res;
            /* with compensation F0 = 1 reflects everything: exactly 1 up to float rounding, since
             * both methods turn the table's E into 1 algebraically (docs/SHADING.md) */
            for (int e = IBL_ENERGY_FDEZ_AGUERA; e <= IBL_ENERGY_TURQUIN; e++) {
                ibl_shade_desc d = {.energy = (ibl_energy_compensation)e};
                ibl_shade(&p, &d, &m, &s, &res);
                for (int c = 0; c < 3; c++) assert_near(res.color[c], 1.0, 1e-5);
            }
            /* without: the directional albedo of the lobe, against the test's own quadrature
             * at off-grid points; the bound is the bilinear error of a 32x32 table and its
             * clamping to the outermost texel centres (n.v < 1/64, r > 63/64) (measured worst
             * below), so 0.03 */
            ibl_shade(&p, NULL, &m, &s, &res);
            double a, b;
            reference_ab(nv, r, 160, &a, &b);
            double err = fabs(res.color[0] - (a + b));
            if (err > worst_plain) worst_plain = err;
            assert_near(res.color[0], a + b, 0.03);
        }
    }
    print_message("furnace: worst |E_table - E_ref| = %.4f\n", worst_plain);
    ibl_image_free(ctx, &lut);
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
}

/* ---------------------------------------------------------------------------------------- */
/* tri-Ace 2010's SO conditions. theta is the elevation of E above the tangent plane (n.E =
 * sin theta); the talk's isotropic occlusion up to elevation alpha gives AO = cos^2 alpha, so
 * theta = acos(sqrt(AO)) is the occlusion boundary (docs/SHADING.md). Expected values are the
 * closed forms worked by hand in docs/SHADING.md. */
static void so_conditions(void **state)
{
    (void)state;
    for (int ai = 1; ai <= 9; ai++) {
        double ao = ai / 10.0;
        double mid = acos(sqrt(ao));
        float e0 = 0.0f, em = (float)sin(mid), e1 = 1.0f;
        /* (1): saturate(sin^2 + 2AO - 1) -> 2AO - 1, AO, 2AO */
        assert_near(ibl_specular_occlusion(IBL_SO_TRIACE, e0, (float)ao, 0, 0), fmax(0, 2 * ao - 1),
                    1e-6);
        assert_near(ibl_specular_occlusion(IBL_SO_TRIACE, em, (float)ao, 0, 0), ao, 1e-6);
        assert_near(ibl_specular_occlusion(IBL_SO_TRIACE, e1, (float)ao, 0, 0), fmin(1, 2 * ao),
                    1e-6);
        /* (3): saturate((sin + AO)^2 - 1 + AO) */
        double s0 = fmin(1, fmax(0, ao * ao + ao - 1));
        double sm = fmin(1, fmax(0, pow(sqrt(1 - ao) + ao, 2) - 1 + ao));
        double s1 = fmin(1, ao * ao + 3 * ao);
        assert_near(ibl_specular_occlusion(IBL_SO_TRIACE_FAST, e0, (float)ao, 0, 0), s0, 1e-6);
        assert_near(ibl_specular_occlusion(IBL_SO_TRIACE_FAST, em, (float)ao, 0, 0), sm, 1e-6);
        assert_near(ibl_specular_occlusion(IBL_SO_TRIACE_FAST, e1, (float)ao, 0, 0), s1, 1e-6);
        /* (2) at shininess 100 reduces to (1 + AO)^1 - 1 + AO forms: sin + 2AO - 1 */
        assert_near(ibl_specular_occlusion(IBL_SO_TRIACE_SHININESS, em, (float)ao, 0, 100),
                    fmin(1, fmax(0, sin(mid) + 2 * ao - 1)), 1e-5);
        /* Frostbite at r = 0: (n.v + AO)^(1/2) - 1 + AO */
        assert_near(ibl_specular_occlusion(IBL_SO_FROSTBITE, e1, (float)ao, 0, 0),
                    fmin(1, sqrt(1 + ao) - 1 + ao), 1e-5);
    }
    /* The talk's table of conditions at its design point AO = 1/2 (docs/SHADING.md):
     * (1) meets all three; (3) meets theta = 0 and pi/2 but gives 0.957 at the boundary. */
    float ao = 0.5f, em = (float)sin(acos(sqrt(0.5)));
    assert_near(ibl_specular_occlusion(IBL_SO_TRIACE, 0, ao, 0, 0), 0.0, 1e-6);
    assert_near(ibl_specular_occlusion(IBL_SO_TRIACE, em, ao, 0, 0), 0.5, 1e-6);
    assert_near(ibl_specular_occlusion(IBL_SO_TRIACE, 1, ao, 0, 0), 1.0, 1e-6);
    assert_near(ibl_specular_occlusion(IBL_SO_TRIACE_FAST, 0, ao, 0, 0), 0.0, 1e-6);
    assert_true(ibl_specular_occlusion(IBL_SO_TRIACE_FAST, em, ao, 0, 0) > 0.9f);
    assert_near(ibl_specular_occlusion(IBL_SO_TRIACE_FAST, 1, ao, 0, 0), 1.0, 1e-6);
    /* the cone formula meets all three conditions at any AO while the specular cone is
     * narrower than the visibility cone: at the boundary the lobe is centred on the cone's
     * edge, and Oat & Sander's smoothstep gives exactly one half there */
    for (int ai = 1; ai <= 3; ai++) {
        float a = ai * 0.25f, mid = (float)sin(acos(sqrt(a)));
        assert_near(ibl_specular_occlusion(IBL_SO_CONE, 0, a, 0.5f, 0), 0.0, 1e-6);
        assert_near(ibl_specular_occlusion(IBL_SO_CONE, mid, a, 0.5f, 0), 0.5, 1e-4);
        assert_near(ibl_specular_occlusion(IBL_SO_CONE, 1, a, 0.5f, 0), 1.0, 1e-6);
    }
    /* fully open (AO = 1) never occludes a view along n; no aperture occludes all */
    assert_near(ibl_specular_occlusion(IBL_SO_CONE, 1, 1.0f, 0.5f, 0), 1.0, 1e-5);
    assert_near(ibl_specular_occlusion(IBL_SO_CONE, 0.5f, 0.0f, 0.5f, 0), 0.0, 1e-6);
    assert_near(ibl_specular_occlusion(IBL_SO_NONE, 0.2f, 0.1f, 0, 0), 1.0, 0);
    assert_near(ibl_specular_occlusion(IBL_SO_AO, 0.2f, 0.3f, 0, 0), 0.3, 1e-7);
    /* names round-trip */
    for (int f = 0; f < IBL_SO_COUNT; f++) {
        ibl_so_formula back;
        assert_true(ibl_so_formula_from_name(ibl_so_formula_name((ibl_so_formula)f), &back));
        assert_int_equal(back, f);
    }
}

static void compositions(void **state)
{
    (void)state;
    const float sd[3] = {0.5f, 0.5f, 0.5f}, da[3] = {2, 2, 2}, sa[3] = {10, 10, 10},
                alb[3] = {0.25f, 0.25f, 0.25f};
    float ao = 0.5f, so = 0.2f, out[3];
    /* hand values: lerp(x, y, t) = x + (y - x) t */
    const double expect[IBL_MIX_COUNT] = {
        0.5 + 10 * 0.2,                       /* multiply              */
        0.5 + (0.5 + (10 - 0.5) * 0.2),       /* (1) da*albedo = 0.5   */
        0.5 + (1.0 + (10 - 1.0) * 0.2),       /* (2) da*AO = 1         */
        0.5 + 0.5 * (1.0 + (10 - 1.0) * 0.2), /* (3)                  */
        0.5 + (0.5 + (10 - 0.5) * 0.2),       /* (4) da*AO^2 = 0.5     */
        0.5 * 0.2 + 0.5 * (1.0 + 9.0 * 0.2),  /* entire                */
    };
    for (int m = 0; m < IBL_MIX_COUNT; m++) {
        ibl_ambient_mix_apply((ibl_ambient_mix)m, sd, da, sa, alb, ao, so, out);
        assert_near(out[1], expect[m], 1e-5);
        ibl_ambient_mix back;
        assert_true(ibl_ambient_mix_from_name(ibl_ambient_mix_name((ibl_ambient_mix)m), &back));
        assert_int_equal(back, m);
    }
}

/* ---------------------------------------------------------------------------------------- */

static void shininess_hack_and_offset(void **state)
{
    (void)state;
    /* 60/30 * (1 - 0.8) = 0.4 -> 100 * 0.16 */
    assert_near(ibl_shininess_hack(100, 30, 0.8f), 16.0, 1e-4);
    /* 60/30 * 0.8 = 1.6 saturates -> unchanged */
    assert_near(ibl_shininess_hack(100, 30, 0.2f), 100.0, 1e-4);
    /* 60/120 * 0.5 = 0.25 -> 400 * 0.0625 */
    assert_near(ibl_shininess_hack(400, 120, 0.5f), 25.0, 1e-4);
    /* attenuation 1 (at the light's end): 0 */
    assert_near(ibl_shininess_hack(400, 120, 1.0f), 0.0, 1e-6);

    /* R' = normalize(c (P_obj - P_IBL) + R): (2 * (1, 0, 0) - 0 + (0, 0, 1)) / sqrt(5) */
    ibl_vec3 r =
        ibl_offset_reflection((ibl_vec3){0, 0, 1}, (ibl_vec3){3, 2, 0}, (ibl_vec3){2, 2, 0}, 2.0f);
    assert_near(r.x, 2.0 / sqrt(5.0), 1e-6);
    assert_near(r.y, 0.0, 1e-7);
    assert_near(r.z, 1.0 / sqrt(5.0), 1e-6);
    /* c = 0 leaves R as is */
    r = ibl_offset_reflection((ibl_vec3){0, 0.6f, 0.8f}, (ibl_vec3){3, 2, 0}, (ibl_vec3){0, 0, 0},
                              0.0f);
    assert_near(r.y, 0.6, 1e-6);

    /* environment switch: object centred on the border is half in, a whole extent away is out */
    assert_near(ibl_environment_switch(5, 5, 2), 0.5, 1e-7);
    assert_near(ibl_environment_switch(4, 5, 2), 0.0, 1e-7);
    assert_near(ibl_environment_switch(6, 5, 2), 1.0, 1e-7);
    assert_near(ibl_environment_switch(5.5f, 5, 2), 0.75, 1e-7);
}

static void parallax(void **state)
{
    (void)state;
    ibl_volume box = {IBL_VOLUME_BOX, {0, 0, 0}, {2, 1, 3}, 0, 0};
    ibl_vec3 c = {0, 0, 0};
    /* a ray from the capture point is unchanged, in any direction */
    for (int i = 0; i < 50; i++) {
        ibl_vec3 r = {sinf(i * 0.7f) * cosf(i * 1.3f), cosf(i * 0.7f),
                      sinf(i * 0.7f) * sinf(i * 1.3f)};
        ibl_vec3 o = ibl_parallax_correct(&box, c, c, r);
        assert_near(o.x, r.x, 1e-5);
        assert_near(o.y, r.y, 1e-5);
        assert_near(o.z, r.z, 1e-5);
    }
    /* from (1, 0, 0) straight up: the top at (1, 1, 0), seen from the centre (1, 1, 0)/sqrt2 */
    ibl_vec3 o = ibl_parallax_correct(&box, c, (ibl_vec3){1, 0, 0}, (ibl_vec3){0, 1, 0});
    assert_near(o.x, 1 / sqrt(2.0), 1e-6);
    assert_near(o.y, 1 / sqrt(2.0), 1e-6);
    assert_near(o.z, 0, 1e-6);
    /* capture point off-centre: from the origin along +Z the hit is (0, 0, 3), seen from
     * (0.5, 0, 0): (-0.5, 0, 3) normalised */
    o = ibl_parallax_correct(&box, (ibl_vec3){0.5f, 0, 0}, c, (ibl_vec3){0, 0, 1});
    assert_near(o.x, -0.5 / sqrt(9.25), 1e-6);
    assert_near(o.z, 3 / sqrt(9.25), 1e-6);
    /* sphere of radius 2: from (1, 0, 0) along +Y the hit is (1, sqrt 3, 0) */
    ibl_volume sph = {IBL_VOLUME_SPHERE, {0, 0, 0}, {0, 0, 0}, 2, 0};
    o = ibl_parallax_correct(&sph, c, (ibl_vec3){1, 0, 0}, (ibl_vec3){0, 1, 0});
    assert_near(o.x, 0.5, 1e-6);
    assert_near(o.y, sqrt(3.0) / 2, 1e-6);
    /* outside the proxy: unchanged */
    o = ibl_parallax_correct(&sph, c, (ibl_vec3){5, 0, 0}, (ibl_vec3){0, 1, 0});
    assert_near(o.y, 1.0, 0);
}

static void influence_blending(void **state)
{
    (void)state;
    ibl_volume v[3] = {
        {IBL_VOLUME_BOX, {0, 0, 0}, {10, 5, 10}, 0, 2},     /* big room        */
        {IBL_VOLUME_SPHERE, {2, 0, 0}, {0, 0, 0}, 3, 1},    /* medium, inside  */
        {IBL_VOLUME_SPHERE, {3, 0, 0}, {0, 0, 0}, 1, 0.5f}, /* small, inside  */
    };
    int order[3];
    ibl_volume_sort(v, 3, order);
    assert_int_equal(order[0], 2);
    assert_int_equal(order[1], 1);
    assert_int_equal(order[2], 0);
    float w[3];
    /* inside the small one's inner region: it takes everything */
    float rest = ibl_volume_blend(v, order, 3, (ibl_vec3){3.2f, 0, 0}, w);
    assert_near(w[2], 1.0, 0);
    assert_near(w[1], 0.0, 0);
    assert_near(w[0], 0.0, 0);
    assert_near(rest, 0.0, 0);
    /* in the small one's fade (distance 0.75 from centre: weight 0.5) and the medium's core */
    rest = ibl_volume_blend(v, order, 3, (ibl_vec3){3.75f, 0, 0}, w);
    assert_near(w[2], 0.5, 1e-6);
    assert_near(w[1], 0.5, 1e-6);
    assert_near(w[0], 0.0, 1e-6);
    /* outside everything: all to the global probe */
    rest = ibl_volume_blend(v, order, 3, (ibl_vec3){50, 0, 0}, w);
    assert_near(rest, 1.0, 0);
    /* anywhere: weights in [0, 1], sum <= 1, sum + rest = 1 */
    srand(3);
    for (int i = 0; i < 2000; i++) {
        ibl_vec3 p = {rand() / (float)RAND_MAX * 24 - 12, rand() / (float)RAND_MAX * 12 - 6,
                      rand() / (float)RAND_MAX * 24 - 12};
        rest = ibl_volume_blend(v, order, 3, p, w);
        float sum = w[0] + w[1] + w[2];
        for (int k = 0; k < 3; k++) assert_true(w[k] >= 0.0f && w[k] <= 1.0f);
        assert_true(sum <= 1.0f + 1e-6f);
        assert_near(sum + rest, 1.0, 1e-6);
    }
}

/* A volume's size and weight by hand: a box's is 8 hx hy hz and a sphere's 4/3 pi r^3; the
 * weight is 1 deeper than the blend distance, 0 outside, linear in between. */
static void volume_size_and_weight(void **state)
{
    (void)state;
    ibl_volume box = {IBL_VOLUME_BOX, {1, 2, 3}, {2, 1, 4}, 0, 0.5f};
    ibl_volume ball = {IBL_VOLUME_SPHERE, {0, 0, 0}, {0, 0, 0}, 2, 1};
    assert_near(ibl_volume_size(&box), 64.0, 1e-5);
    assert_near(ibl_volume_size(&ball), 4.0 / 3.0 * PI * 8.0, 1e-4);
    assert_near(ibl_volume_weight(&box, (ibl_vec3){1, 2, 3}), 1.0, 0);
    assert_near(ibl_volume_weight(&box, (ibl_vec3){2.75f, 2, 3}), 0.5, 1e-6); /* 0.25 inside */
    assert_near(ibl_volume_weight(&box, (ibl_vec3){3.5f, 2, 3}), 0.0, 0);
    assert_near(ibl_volume_weight(&ball, (ibl_vec3){0, 1.5f, 0}), 0.5, 1e-6);
    assert_near(ibl_volume_weight(&ball, (ibl_vec3){0, 0.5f, 0}), 1.0, 0);
    assert_near(ibl_volume_weight(&ball, (ibl_vec3){0, 2.5f, 0}), 0.0, 0);
}

/* The runtime's SH9 irradiance (float) against the float64 library: the radiance convolved
 * (ibl_sh_radiance_to_irradiance) and evaluated (ibl_sh_eval); 1e-5 relative is float
 * rounding of nine terms. An irradiance set is taken as it is. */
static void sh9_irradiance(void **state)
{
    (void)state;
    ibl_sh rad = {.bands = 3};
    float c[9][3];
    for (int i = 0; i < 9; i++)
        for (int k = 0; k < 3; k++) c[i][k] = (float)(rad.c[i][k] = (i == 0 ? 2.0 : 0.3) * (1 + k) * ((i % 3) - 0.7));
    ibl_sh irr;
    ibl_sh_radiance_to_irradiance(&rad, &irr);
    for (int t = 0; t < 200; t++) {
        double z = 1.0 - 2.0 * (t + 0.5) / 200, r = sqrt(1 - z * z), phi = t * 2.399963;
        double d[3] = {r * cos(phi), r * sin(phi), z};
        double want[3];
        ibl_sh_eval(&irr, d, want);
        float got[3];
        ibl_sh9_eval_irradiance(c, IBL_SH_KIND_RADIANCE, (ibl_vec3){(float)d[0], (float)d[1], (float)d[2]}, got);
        for (int k = 0; k < 3; k++) assert_near(got[k], want[k] > 0 ? want[k] : 0, 1e-5 * (1 + fabs(want[k])));
        float e[9][3];
        for (int i = 0; i < 9; i++)
            for (int k = 0; k < 3; k++) e[i][k] = (float)irr.c[i][k];
        ibl_sh9_eval_irradiance(e, IBL_SH_KIND_IRRADIANCE, (ibl_vec3){(float)d[0], (float)d[1], (float)d[2]}, got);
        for (int k = 0; k < 3; k++) assert_near(got[k], want[k] > 0 ? want[k] : 0, 1e-5 * (1 + fabs(want[k])));
    }
}

/* ibl_shade_dir with the reflection vector is ibl_shade along R; an axis' index inverts its
 * value. */
static void shade_dir_and_axes(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_probe p;
    ibl_cubemap cube;
    white_probe(ctx, &p, &cube, 4);
    test_fill_smooth(&cube);
    static const float base[3] = {0.9f, 0.6f, 0.3f};
    ibl_material m = ibl_material_gltf(base, 1.0f, 0.4f);
    ibl_surface s = {.n = {0, 1, 0}, .v = {0.6f, 0.8f, 0}};
    ibl_shade_desc d = {.mirror_direction = 1};
    ibl_shade_result a, b;
    ibl_shade(&p, &d, &m, &s, &a);
    ibl_shade_dir(&p, &d, &m, &s, (ibl_vec3){-0.6f, 0.8f, 0}, &b);
    for (int c = 0; c < 3; c++) assert_near(a.color[c], b.color[c], 1e-6);
    ibl_cubemap_free(ctx, &cube);
    ibl_table_axis lin = {17, 0.25f, 4.25f, 0}, lg = {9, 1.0f, 256.0f, 1};
    for (int i = 0; i < 17; i++) assert_near(ibl_table_axis_index(&lin, ibl_table_axis_value(&lin, i)), i, 1e-5);
    for (int i = 0; i < 9; i++) assert_near(ibl_table_axis_index(&lg, ibl_table_axis_value(&lg, i)), i, 1e-5);
    assert_near(ibl_table_axis_index(&lg, 0.5f), 0, 0); /* clamped */
    assert_near(ibl_table_axis_index(&lg, 16.0f), 4, 1e-5);
    ibl_context_destroy(ctx);
}

static void tiled_culling(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    /* three rectangles on a 64x32 screen with 16-pixel tiles (4 x 2 tiles) */
    ibl_screen_rect rects[3] = {{0, 0, 64, 32}, {10, 5, 20, 12}, {40, 20, 41, 21}};
    ibl_volume v[3] = {{IBL_VOLUME_SPHERE, {0, 0, 0}, {0, 0, 0}, 10, 0},
                       {IBL_VOLUME_SPHERE, {0, 0, 0}, {0, 0, 0}, 1, 0},
                       {IBL_VOLUME_SPHERE, {0, 0, 0}, {0, 0, 0}, 2, 0}};
    int order[3];
    ibl_volume_sort(v, 3, order); /* 1, 2, 0 */
    ibl_tile_lists l;
    assert_int_equal(ibl_tile_probes(ctx, rects, order, 3, 64, 32, 16, &l), IBL_OK);
    assert_int_equal(l.tiles_x, 4);
    assert_int_equal(l.tiles_y, 2);
    /* expected by hand: rect 1 covers x tiles 0..1, y tile 0; rect 2 covers tile (2, 1) */
    for (int ty = 0; ty < 2; ty++)
        for (int tx = 0; tx < 4; tx++) {
            int t = ty * 4 + tx, n = l.offsets[t + 1] - l.offsets[t];
            const int *list = l.indices + l.offsets[t];
            if (ty == 0 && tx <= 1) {
                assert_int_equal(n, 2);
                assert_int_equal(list[0], 1);
                assert_int_equal(list[1], 0);
            } else if (ty == 1 && tx == 2) {
                assert_int_equal(n, 2);
                assert_int_equal(list[0], 2);
                assert_int_equal(list[1], 0);
            } else {
                assert_int_equal(n, 1);
                assert_int_equal(list[0], 0);
            }
        }
    ibl_tile_lists_free(ctx, &l);
    /* screen rectangle through a plain perspective (eye at origin looking down -Z, 90 degrees):
     * a unit box centred at (0, 0, -5) spans x, y in [-0.5/4.5, 0.5/4.5] in NDC */
    float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, -1, 0, 0, -0.2f, 0};
    ibl_volume box = {IBL_VOLUME_BOX, {0, 0, -5}, {0.5f, 0.5f, 0.5f}, 0, 0};
    ibl_screen_rect r = ibl_volume_screen_rect(&box, m, 1000, 1000);
    double ndc = 0.5 / 4.5;
    assert_int_equal(r.x0, (int)floor((0.5 - ndc / 2) * 1000));
    assert_int_equal(r.x1, (int)ceil((0.5 + ndc / 2) * 1000));
    /* behind the eye: conservative full screen */
    box.center.z = 0.2f;
    r = ibl_volume_screen_rect(&box, m, 900, 900);
    assert_int_equal(r.x1 - r.x0, 900);
    ibl_context_destroy(ctx);
}

/* ---------------------------------------------------------------------------------------- */

static float level_lod_fn(void *user, float r)
{
    (void)user;
    return r * 3.0f;
}

/* Level k filled with the constant k + 1, so the value read names the level. */
static void level_mapping_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    enum { L = 5 };
    ibl_cubemap cube, mirror;
    assert_int_equal(ibl_cubemap_alloc(ctx, 16, L, &cube), IBL_OK);
    for (int k = 0; k < L; k++) {
        int n = ibl_level_size(16, k);
        float *f = ibl_cubemap_face(&cube, k, 0);
        for (size_t i = 0; i < (size_t)6 * n * n; i++)
            for (int c = 0; c < 4; c++) f[i * 4 + c] = (float)(k + 1);
    }
    assert_int_equal(ibl_cubemap_alloc(ctx, 32, 1, &mirror), IBL_OK);
    test_fill_cube(&mirror, 100, 100, 100);
    ibl_probe p;
    memset(&p, 0, sizeof p);
    p.specular = cube;
    p.mirror = mirror;
    p.mapping.levels = L;
    const float rough[L] = {0.0f, 0.13f, 0.4f, 0.77f, 1.0f}; /* uneven on purpose */
    memcpy(p.mapping.roughness, rough, sizeof rough);
    p.sh_kind = IBL_SH_KIND_IRRADIANCE;
    assert_int_equal(ibl_probe_validate(ctx, &p), IBL_OK);
    static const float one[3] = {1, 1, 1};
    ibl_surface s = surface_at(0.8);
    for (int k = 0; k < L; k++) {
        ibl_material m = ibl_material_gltf(one, 1.0f, rough[k]);
        ibl_shade_result res;
        ibl_shade(&p, NULL, &m, &s, &res);
        assert_true(res.lod == (float)k);
        /* no table: A = 1, B = 0; F0 = 1 -> the level's value exactly */
        assert_true(res.specular[0] == (float)(k + 1));
        /* Blinn-Phong at the level's shininess: the same level (the mirror only beyond level 0) */
        ibl_material bp = ibl_material_blinn_phong(one, one, p.mapping.shininess[k]);
        ibl_shade(&p, NULL, &bp, &s, &res);
        assert_true(res.lod == (float)k);
    }
    /* half way in roughness between levels 1 and 2 reads the average of their values */
    ibl_material m = ibl_material_gltf(one, 1.0f, 0.5f * (rough[1] + rough[2]));
    ibl_shade_result res;
    ibl_shade(&p, NULL, &m, &s, &res);
    assert_near(res.lod, 1.5, 1e-5);
    assert_near(res.specular[0], 2.5, 1e-5);
    /* beyond level 0's shininess (1e6 for r = 0) with a mirror threshold below it: level 0 */
    ibl_material bp = ibl_material_blinn_phong(one, one, 2e6f);
    ibl_shade(&p, NULL, &bp, &s, &res);
    assert_near(res.lod, 0.0, 1e-6);
    /* a Phong bake whose level 0 is shininess 2000: beyond it the mirror takes over (tri-Ace 2010's
     * mirror option) */
    p.mapping.shininess[0] = 2000;
    for (int k = 1; k < L; k++) p.mapping.shininess[k] = 2000.0f / powf(8.0f, (float)k);
    bp = ibl_material_blinn_phong(one, one, 1e5f);
    ibl_shade(&p, NULL, &bp, &s, &res);
    assert_near(res.lod, -1.0, 1e-6);
    assert_near(res.specular[0], 100.0, 1e-4);
    /* shininess between levels: linear in log2 (tri-Ace 2010's lod = a - 0.5 log2 n form) */
    bp = ibl_material_blinn_phong(one, one, 2000.0f / powf(8.0f, 1.5f));
    ibl_shade(&p, NULL, &bp, &s, &res);
    assert_near(res.lod, 1.5, 1e-5);
    /* a mapping function overrides the table */
    p.mapping.lod_from_roughness = level_lod_fn;
    m = ibl_material_gltf(one, 1.0f, 0.5f);
    ibl_shade(&p, NULL, &m, &s, &res);
    assert_near(res.lod, 1.5, 1e-6);
    /* bad mappings are refused */
    p.mapping.roughness[2] = 0.1f;
    assert_int_equal(ibl_probe_validate(ctx, &p), IBL_ERR_INVALID_ARGUMENT);
    ibl_cubemap_free(ctx, &cube);
    ibl_cubemap_free(ctx, &mirror);
    ibl_context_destroy(ctx);
}

/* ---------------------------------------------------------------------------------------- */

static void fill_smooth_chain(ibl_cubemap *c)
{
    for (int k = 0; k < c->levels; k++) {
        int n = ibl_level_size(c->size, k);
        for (int f = 0; f < 6; f++) {
            float *t = ibl_cubemap_face(c, k, f);
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    ibl_vec3 d = ibl_cube_texel_direction(f, n, x, y);
                    float *p = t + ((size_t)y * n + x) * 4;
                    p[0] = 1.0f + 0.5f * d.x + (float)k;
                    p[1] = 1.0f + 0.3f * d.y * d.z;
                    p[2] = 2.0f + d.z;
                    p[3] = 1.0f;
                }
        }
    }
}

static void atlas_round_trip(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_cubemap chain;
    assert_int_equal(ibl_cubemap_alloc(ctx, 32, 6, &chain), IBL_OK);
    fill_smooth_chain(&chain);
    /* nearest enlargement: every level comes back bit for bit */
    ibl_atlas_desc nd = {.filter = IBL_ATLAS_NEAREST};
    ibl_image atlas;
    ibl_atlas_layout lay;
    assert_int_equal(ibl_atlas_pack(ctx, &chain, &nd, &atlas, &lay), IBL_OK);
    /* levels >= 2 are stored at level 2's size */
    for (int k = 2; k < 6; k++) assert_int_equal(lay.face_size[k], 8);
    assert_int_equal(atlas.width, 3 * (32 + 2));
    ibl_cubemap back;
    assert_int_equal(ibl_atlas_unpack(ctx, &atlas, &lay, 32, &back), IBL_OK);
    assert_memory_equal(back.data, chain.data, ibl_cubemap_floats(32, 6) * sizeof(float));
    ibl_cubemap_free(ctx, &back);
    ibl_image_free(ctx, &atlas);
    /* bilinear enlargement: levels 0-2 exact; a smaller level is enlarged by sampling between
     * its texels, so the box average pulls a texel toward its neighbours, by at most half the
     * largest difference between neighbouring texels of that level (1.0 for these functions:
     * blue = 2 + z between the 1x1 +Z face and its neighbours) -> 0.5 */
    ibl_atlas_desc bd = {0};
    assert_int_equal(ibl_atlas_pack(ctx, &chain, &bd, &atlas, &lay), IBL_OK);
    assert_int_equal(ibl_atlas_unpack(ctx, &atlas, &lay, 32, &back), IBL_OK);
    for (int k = 0; k < 6; k++) {
        int n = ibl_level_size(32, k);
        const float *a = ibl_cubemap_face(&chain, k, 0), *b = ibl_cubemap_face(&back, k, 0);
        for (size_t i = 0; i < (size_t)6 * n * n * 4; i++) {
            if (k <= 2)
                assert_true(a[i] == b[i]);
            else
                assert_near(b[i], a[i], 0.5);
        }
    }
    /* shader emulation: away from face edges the atlas's 2D bilinear equals the cube's seamless
     * bilinear (same four texels, float rounding); near edges it reads the gutter, within a
     * texel's change of the signal */
    srand(11);
    for (int i = 0; i < 3000; i++) {
        ibl_vec3 d = {rand() / (float)RAND_MAX * 2 - 1, rand() / (float)RAND_MAX * 2 - 1,
                      rand() / (float)RAND_MAX * 2 - 1};
        float lod = (float)(i % 3), s, t, a[4], b[4];
        ibl_cube_face_st(d, &s, &t);
        int n = ibl_level_size(32, (int)lod);
        int interior = s > 1.0f / n && s < 1 - 1.0f / n && t > 1.0f / n && t < 1 - 1.0f / n;
        ibl_atlas_sample(&atlas, &lay, lod, d, a);
        ibl_cubemap_sample_bilinear(&chain, (int)lod, d, b);
        for (int c = 0; c < 3; c++) assert_near(a[c], b[c], interior ? 1e-4 : 0.1);
        float u, v;
        ibl_atlas_uv(&lay, (int)lod, d, &u, &v);
        assert_true(u >= 0 && u <= 1 && v >= 0 && v <= 1);
    }
    ibl_cubemap_free(ctx, &back);
    ibl_image_free(ctx, &atlas);
    ibl_cubemap_free(ctx, &chain);
    ibl_context_destroy(ctx);
}

static void channel_packing(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_image in[4], packed, out[4];
    for (int i = 0; i < 4; i++) {
        assert_int_equal(ibl_image_alloc(ctx, 5, 3, &in[i]), IBL_OK);
        for (int p = 0; p < 15; p++) in[i].pixels[p * 4] = (float)(i * 100 + p);
    }
    assert_int_equal(ibl_pack_material_channels(ctx, &in[0], &in[1], &in[2], &in[3], &packed),
                     IBL_OK);
    assert_near(packed.pixels[7 * 4 + 2], 207, 0); /* AO of pixel 7 in blue */
    assert_int_equal(ibl_unpack_material_channels(ctx, &packed, out), IBL_OK);
    for (int i = 0; i < 4; i++) {
        for (int p = 0; p < 15; p++) assert_true(out[i].pixels[p * 4] == in[i].pixels[p * 4]);
        ibl_image_free(ctx, &out[i]);
    }
    ibl_image_free(ctx, &packed);
    /* defaults for missing inputs: metal 0, roughness 1, AO 1, transmittance 0 */
    assert_int_equal(ibl_pack_material_channels(ctx, NULL, &in[1], NULL, NULL, &packed), IBL_OK);
    assert_near(packed.pixels[0], 0, 0);
    assert_near(packed.pixels[2], 1, 0);
    assert_near(packed.pixels[3], 0, 0);
    ibl_image_free(ctx, &packed);
    for (int i = 0; i < 4; i++) ibl_image_free(ctx, &in[i]);
    ibl_context_destroy(ctx);
}

/* Blinn-Phong with the AmbientBRDF volume: the table value is used for the specular and the
 * talk's diffuse is Rd (1 - value) (hand-built table, linear in every axis, so the trilinear
 * lookup is exact). */
static void ambient_brdf_usage(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_probe p;
    ibl_cubemap cube;
    white_probe(ctx, &p, &cube, 4);
    static float vol[2 * 2 * 2];
    /* value = 0.1 + 0.2 nv + 0.3 f0 (independent of shininess) */
    for (int k = 0; k < 2; k++)
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 2; i++) vol[(k * 2 + j) * 2 + i] = 0.1f + 0.2f * i + 0.3f * k;
    p.ambient_brdf = (ibl_ambient_brdf_view){vol, 1, {2, 0, 1, 0}, {2, 1, 10000, 1}, {2, 0, 1, 0}};
    const float rd[3] = {0.5f, 0.5f, 0.5f}, f0[3] = {0.5f, 0.5f, 0.5f};
    ibl_material m = ibl_material_blinn_phong(rd, f0, 300);
    ibl_surface s = surface_at(0.6);
    ibl_shade_result r;
    ibl_shade(&p, NULL, &m, &s, &r);
    double ab = 0.1 + 0.2 * 0.6 + 0.3 * 0.5;
    assert_near(r.specular[0], ab, 1e-5);
    assert_near(r.diffuse[0], 0.5 * (1 - ab), 1e-5);
    ibl_shade_desc d = {.bp_diffuse = IBL_BP_DIFFUSE_F0};
    ibl_shade(&p, &d, &m, &s, &r);
    assert_near(r.diffuse[0], 0.5 * 0.5, 1e-5);
    ibl_image_free(ctx, &lut);
    ibl_cubemap_free(ctx, &cube);
    ibl_context_destroy(ctx);
}

/* Two constant probes blended by weight: the sum of their results by weight, by hand. */
static void probe_blending(void **state)
{
    (void)state;
    ibl_context *ctx = test_context(1);
    ibl_probe p[2];
    ibl_cubemap cube[2];
    for (int i = 0; i < 2; i++) {
        memset(&p[i], 0, sizeof p[i]);
        assert_int_equal(ibl_cubemap_alloc(ctx, 4, 2, &cube[i]), IBL_OK);
        test_fill_cube(&cube[i], 2.0f + 4.0f * i, 2.0f + 4.0f * i, 2.0f + 4.0f * i);
        p[i].specular = cube[i];
        p[i].mapping.levels = 2;
        p[i].mapping.roughness[1] = 1.0f;
        p[i].sh_kind = IBL_SH_KIND_IRRADIANCE;
        assert_int_equal(ibl_probe_validate(ctx, &p[i]), IBL_OK);
    }
    const ibl_probe *list[2] = {&p[0], &p[1]};
    const float w[2] = {0.25f, 0.75f}, one[3] = {1, 1, 1};
    ibl_material m = ibl_material_gltf(one, 1.0f, 0.3f);
    ibl_surface s = surface_at(0.5);
    ibl_shade_result r;
    ibl_shade_blend(list, w, 2, NULL, NULL, &m, &s, &r);
    /* no table: A = 1, B = 0, F0 = 1: specular = the probe's value; 0.25 * 2 + 0.75 * 6 */
    assert_near(r.specular[0], 5.0, 1e-5);
    assert_near(r.color[0], 5.0, 1e-5);
    ibl_vec3 dirs[2] = {{0, 1, 0}, {1, 0, 0}};
    ibl_shade_blend(list, w, 2, dirs, NULL, &m, &s, &r);
    assert_near(r.r.x, 1.0, 0); /* the heaviest probe's direction */
    for (int i = 0; i < 2; i++) ibl_cubemap_free(ctx, &cube[i]);
    ibl_context_destroy(ctx);
}

/* The centroid of tri-Ace's normalised Blinn-Phong lobe, (n.h)^s n.l / max(n.l, n.v), as the
 * factor t of lerp(N, R, t) that points at it: float64, integrated over the half vector
 * (dl = 4 (v.h) dh) on a polar grid that covers the lobe. */
static double centroid_lean(double s, double view_angle)
{
    const double v[3] = {sin(view_angle), 0.0, cos(view_angle)};
    const double theta_max = fmin(PI / 2, 10.0 / sqrt(s + 1.0));
    enum { NT = 400, NP = 180 };
    double cx = 0, cz = 0;
    for (int i = 0; i < NT; i++) {
        double th = (i + 0.5) * theta_max / NT;
        for (int j = 0; j < NP; j++) {
            double ph = (j + 0.5) * 2 * PI / NP;
            double h[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)};
            double vh = v[0] * h[0] + v[2] * h[2];
            if (vh <= 0) continue;
            double lx = 2 * vh * h[0] - v[0], lz = 2 * vh * h[2] - v[2];
            if (lz <= 0) continue;
            double w = pow(h[2], s) * lz / fmax(lz, v[2]) * 4 * vh * sin(th);
            cx += w * lx, cz += w * lz;
        }
    }
    double tan_c = -cx / cz; /* R lies at -view_angle */
    return tan_c / (sin(view_angle) + tan_c * (1 - cos(view_angle)));
}

/* ibl_dominant_direction_lean for Blinn-Phong against the centroid, averaged over n.v with a
 * sphere's projected-area weight (sin cos), as the fit was made. The fit's rms is 0.0005 over
 * s = 0.5..5000; 0.003 covers it and this coarser grid. GGX keeps Lagarde's closed form. */
static void blinn_phong_lean_is_the_lobe_centroid(void **state)
{
    (void)state;
    const double shininess[5] = {1, 5, 30, 200, 2000};
    for (int i = 0; i < 5; i++) {
        double sum = 0, wsum = 0;
        for (int k = 0; k < 10; k++) {
            double a = (k + 0.5) * (PI / 2) / 10, w = sin(a) * cos(a);
            sum += w * centroid_lean(shininess[i], a), wsum += w;
        }
        float rd[3] = {0, 0, 0}, f0[3] = {0.5f, 0.5f, 0.5f};
        ibl_material m = ibl_material_blinn_phong(rd, f0, (float)shininess[i]);
        assert_near(ibl_dominant_direction_lean(&m), sum / wsum, 0.003);
    }
    ibl_material g = ibl_material_gltf((const float[3]){1, 1, 1}, 1.0f, 0.36f);
    assert_near(ibl_dominant_direction_lean(&g), 0.64 * (0.8 + 0.36), 1e-6);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(furnace),
        cmocka_unit_test(blinn_phong_lean_is_the_lobe_centroid),
        cmocka_unit_test(so_conditions),
        cmocka_unit_test(compositions),
        cmocka_unit_test(shininess_hack_and_offset),
        cmocka_unit_test(parallax),
        cmocka_unit_test(influence_blending),
        cmocka_unit_test(volume_size_and_weight),
        cmocka_unit_test(sh9_irradiance),
        cmocka_unit_test(shade_dir_and_axes),
        cmocka_unit_test(tiled_culling),
        cmocka_unit_test(level_mapping_round_trip),
        cmocka_unit_test(atlas_round_trip),
        cmocka_unit_test(channel_packing),
        cmocka_unit_test(ambient_brdf_usage),
        cmocka_unit_test(probe_blending),
    };
    return cmocka_run_group_tests_name("shade", tests, NULL, NULL);
}
