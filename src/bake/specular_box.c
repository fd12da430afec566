/* tri-Ace's fastest dynamic profile: a plain box-filtered mip chain (tri-Ace 2010
 * "Generate PMREM (1)"), with the level <-> shininess table the talk fits for it ("Mipmap
 * LOD": lod = a - 0.5 log2(shininess), "fitted for both Box Filter Kernel and Phong").
 *
 * The fit (docs/EDGE_FIXUP.md, "Box chain shininess"): a texel of level l is the exact
 * area mean of the radiance over its footprint (the block mean or ibl_cubemap_resample, and
 * ibl_cubemap_build_mips are area-correct), and a renderer reads it back with seamless
 * bilinear filtering. The response at direction d to a unit delta at w0 is therefore
 * tent_T(d) / Omega_T, T the texel holding w0 and tent_T its bilinear weight. Averaged over
 * w0 in T (shift average), the least-squares distance to a normalised Phong lobe
 * P_s(mu) = (s+1)/(2 pi) max(mu, 0)^s, mu = d.w0, splits into a part independent of s and
 * the distance between P_s and the response's mean over rings of constant mu; so the ring
 * means are tabulated once and s is found by a 1D search. The result depends on the level's
 * edge n only (the chain below is an exact area mean); it is ~0.94 n^2 for n >= 16 (docs give
 * the table). */
#include "bake/specular_kernels.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>


ibl_status ibl__specular_box(ibl_context *ctx, const ibl_cubemap *src, ibl_cubemap *dst)
{
    if (!src || !dst || !src->data || !dst->data || dst->levels < 1 || dst->size < 1 || src->size < 1)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "box prefilter: missing cubemap");
    ibl_status st = ibl_cubemap_resample(ctx, src, dst);
    if (st != IBL_OK) return st;
    return ibl_cubemap_build_mips(ctx, dst);
}

/* ---- the fit ---- */

enum { FIT_BINS = 384, FIT_SUB = 4, FIT_GRID = 48, FIT_GRID_SMALL = 40 };

typedef struct ring_table {
    double mass[FIT_BINS]; /* sum of response * solid angle per ring, shift-averaged */
    double root_qmax;      /* rings are uniform in sqrt(1 - mu) over [0, root_qmax] */
    double log_mu[FIT_BINS + 1]; /* log of mu at the ring borders (-inf where mu <= 0) */
    double area[FIT_BINS];       /* solid angle of each ring */
} ring_table;

/* Bilinear weight of texel (x0, y0) of face 4 when sampling at face-plane (u, v) of face 4
 * (the window path: the whole support lies inside the face for n >= 4). */
static double tent_in_face(int n, int x0, int y0, double u, double v)
{
    double px = (u + 1.0) * 0.5 * n - 0.5, py = (v + 1.0) * 0.5 * n - 0.5;
    double wx = 1.0 - fabs(px - x0), wy = 1.0 - fabs(py - y0);
    return wx > 0 && wy > 0 ? wx * wy : 0.0;
}

typedef struct fit_setup {
    int n, x0, y0;
    double omega0;
    /* shift-average samples of the delta within the texel */
    double w0[FIT_SUB * FIT_SUB][3], w0_weight[FIT_SUB * FIT_SUB];
    /* small cubes (n < 4): the response is read through the library's seamless sampler */
    ibl_cubemap cube;
    float memory[6 * 2 * 2 * 4];
} fit_setup;

static void setup(fit_setup *f, int n)
{
    memset(f, 0, sizeof *f);
    f->n = n;
    f->x0 = f->y0 = n / 2;
    f->omega0 = ibl_cube_texel_solid_angle(n, f->x0, f->y0);
    double h = 2.0 / n, u0 = f->x0 * h - 1.0, v0 = f->y0 * h - 1.0, sub = h / FIT_SUB;
    for (int j = 0; j < FIT_SUB; j++) {
        for (int i = 0; i < FIT_SUB; i++) {
            int k = j * FIT_SUB + i;
            double ua = u0 + i * sub, va = v0 + j * sub;
            f->w0_weight[k] = ibl_cube_rect_solid_angle(ua, va, ua + sub, va + sub) / f->omega0;
            double d[3];
            ibl_cube_direction_d(IBL_FACE_POS_Z, (ua + 0.5 * sub + 1.0) * 0.5,
                                 (va + 0.5 * sub + 1.0) * 0.5, d);
            double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int c = 0; c < 3; c++) f->w0[k][c] = d[c] / l;
        }
    }
    if (n < 4) {
        ibl_cubemap_wrap(n, 1, f->memory, &f->cube);
        ibl_cubemap_face(&f->cube, 0, IBL_FACE_POS_Z)[((size_t)f->y0 * n + f->x0) * 4] = 1.0f;
    }
}

/* Visits every integration cell of the response's support: its direction, solid angle and
 * response value (bilinear weight / Omega_T). pass 0 finds the largest 1 - mu, pass 1 bins. */
static void sweep(const fit_setup *f, ring_table *t, int pass)
{
    int n = f->n;
    int faces = n < 4 ? 6 : 1, grid = n < 4 ? FIT_GRID_SMALL : FIT_GRID;
    /* window path: the support of the tent, centres of texels x0-1 .. x0+1 */
    double ua = -1.0, ub = 1.0, va = -1.0, vb = 1.0;
    if (n >= 4) {
        ua = (2.0 * (f->x0 - 1) + 1.0) / n - 1.0;
        ub = (2.0 * (f->x0 + 1) + 1.0) / n - 1.0;
        va = (2.0 * (f->y0 - 1) + 1.0) / n - 1.0;
        vb = (2.0 * (f->y0 + 1) + 1.0) / n - 1.0;
    }
    double du = (ub - ua) / grid, dv = (vb - va) / grid;
    for (int fi = 0; fi < faces; fi++) {
        int face = n < 4 ? fi : IBL_FACE_POS_Z;
        for (int j = 0; j < grid; j++) {
            for (int i = 0; i < grid; i++) {
                double u = ua + (i + 0.5) * du, v = va + (j + 0.5) * dv;
                double d[3];
                ibl_cube_direction_d(face, (u + 1.0) * 0.5, (v + 1.0) * 0.5, d);
                double weight;
                if (n >= 4) {
                    weight = tent_in_face(n, f->x0, f->y0, u, v);
                } else {
                    float out[4];
                    ibl_vec3 dir = {(float)d[0], (float)d[1], (float)d[2]};
                    ibl_cubemap_sample_bilinear(&f->cube, 0, dir, out);
                    weight = out[0];
                }
                if (weight <= 0) continue;
                double area = ibl_cube_rect_solid_angle(u - 0.5 * du, v - 0.5 * dv, u + 0.5 * du,
                                                        v + 0.5 * dv);
                double response = weight / f->omega0 * area;
                double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                for (int k = 0; k < FIT_SUB * FIT_SUB; k++) {
                    double mu = (d[0] * f->w0[k][0] + d[1] * f->w0[k][1] + d[2] * f->w0[k][2]) / l;
                    double q = 1.0 - mu;
                    if (q < 0) q = 0;
                    if (pass == 0) {
                        if (q > t->root_qmax) t->root_qmax = q;
                    } else {
                        int b = (int)(sqrt(q) / t->root_qmax * FIT_BINS);
                        if (b >= FIT_BINS) b = FIT_BINS - 1;
                        t->mass[b] += f->w0_weight[k] * response;
                    }
                }
            }
        }
    }
}

/* Least-squares distance to the normalised Phong lobe, up to a constant:
 * -2 int K P_s + int P_s^2, with int P_s^2 = (s+1)^2 / (2 pi (2s+1)) and, per ring of
 * mu in [m0, m1], int_ring P_s = m1^(s+1) - m0^(s+1) spread over the ring's 2 pi (m1 - m0). */
static double lobe_distance(const ring_table *t, double s)
{
    double cross = 0;
    for (int b = 0; b < FIT_BINS; b++) {
        if (t->mass[b] == 0) continue;
        double hi = exp((s + 1.0) * t->log_mu[b]), lo = exp((s + 1.0) * t->log_mu[b + 1]);
        cross += t->mass[b] * (hi - lo) / t->area[b];
    }
    return -2.0 * cross + (s + 1.0) * (s + 1.0) / (2.0 * IBL_PI * (2.0 * s + 1.0));
}

static double fit_shininess(int n)
{
    fit_setup f;
    ring_table t;
    memset(&t, 0, sizeof t);
    setup(&f, n);
    sweep(&f, &t, 0);
    t.root_qmax = sqrt(t.root_qmax) * 1.000001;
    sweep(&f, &t, 1);
    for (int b = 0; b <= FIT_BINS; b++) {
        double r = t.root_qmax * b / FIT_BINS, q = r * r; /* mu = 1 - q */
        t.log_mu[b] = q < 1 ? log1p(-q) : -INFINITY;
        if (b < FIT_BINS) {
            double r1 = t.root_qmax * (b + 1) / FIT_BINS;
            t.area[b] = 2.0 * IBL_PI * (r1 * r1 - q);
        }
    }
    /* coarse scan in log s, then golden-section refinement around the best point */
    double best = 0, best_e = INFINITY, step = 0.25;
    for (double x = log(0.05); x <= log(1e8); x += step) {
        double e = lobe_distance(&t, exp(x));
        if (e < best_e) best_e = e, best = x;
    }
    double a = best - step, b = best + step, g = 0.5 * (sqrt(5.0) - 1.0);
    double c = b - g * (b - a), d = a + g * (b - a);
    double ec = lobe_distance(&t, exp(c)), ed = lobe_distance(&t, exp(d));
    for (int it = 0; it < 40; it++) {
        if (ec < ed) {
            b = d, d = c, ed = ec;
            c = b - g * (b - a);
            ec = lobe_distance(&t, exp(c));
        } else {
            a = c, c = d, ec = ed;
            d = a + g * (b - a);
            ed = lobe_distance(&t, exp(d));
        }
    }
    return exp(0.5 * (a + b));
}

/* fit_shininess(n) for the power-of-two level edges 1, 2, 4 ... 4096, as it computes them
 * (each fit costs ~2 ms, and every chain description asks for them): tests/test_triace_kernels.c
 * recomputes the table with ibl__box_fit_shininess and requires the same floats. */
static const float box_fit_table[13] = {0.819779515f, 5.985116f,   17.5821171f, 62.8321457f,
                                        243.242935f,  964.609741f, 3849.05322f, 15386.7031f,
                                        61540.6719f,  246153.922f, 984606.938f, 3938418.25f,
                                        15753666.0f};

float ibl__box_fit_shininess(int n) { return (float)fit_shininess(n); }

float ibl__box_level_shininess(int size, int level)
{
    if (size < 1 || level < 0) return 0.0f;
    int n = ibl_level_size(size, level);
    for (int k = 0; k < 13; k++)
        if (n == 1 << k) return box_fit_table[k];
    return ibl__box_fit_shininess(n);
}
