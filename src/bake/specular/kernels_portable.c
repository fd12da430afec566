/* The four inner loops of the fast prefilter in portable C (see fast_kernels in
 * fast_internal.h): what runs on CPUs without AVX2, FMA and F16C, and with a context created
 * with IBL_KERNELS_PORTABLE. Their AVX2 twins are in kernels_avx2.c.
 *
 * The piece is read from its table (g and g'' in u, PIECE_TABLE_STEPS steps, linear
 * interpolation) instead of being evaluated in closed form, so the two paths differ by ~1e-4 of
 * a value. Phong texels whose spread reaches the horizon, where x^n has a kink, take the
 * closed-form mean of x^n over the spread, as the AVX2 path does. */
#include "bake/specular/fast_internal.h"
#include "core/numeric.h"
#include "core/pixel_format.h"

#include <math.h>

/* psi_out - psi_in of the piece at u (the partition of unity alone). */
static float piece_partition(const lobe_piece *pc, float u)
{
    float v[2];
    const psi_step *steps[2] = {&pc->outer, &pc->inner};
    for (int i = 0; i < 2; i++) {
        float s = ibl__saturate(u * steps[i]->scale - steps[i]->offset);
        v[i] = 1.0f - s * s * s * (10.0f + s * (-15.0f + 6.0f * s));
    }
    return v[0] - v[1];
}

/* g(u) + g''(u) q / 2 of the piece, q = R^T C R. */
static float piece_leaf(const lobe_piece *pc, float u, float q)
{
    if (!pc->is_ggx && q > 0) {
        /* Phong near the horizon: the closed-form mean over u +- a (see kernels_avx2.c) */
        float a = sqrtf(3.0f * q);
        if (u + 2.0f * a >= 1.0f && a > 1e-6f && a <= u) {
            float xl = 1.0f - u + a, xh = 1.0f - u - a, n1 = pc->phong_n + 1.0f;
            float pl = xl > 0 ? powf(xl, n1) : 0.0f, ph = xh > 0 ? powf(xh, n1) : 0.0f;
            return (pl - ph) / (2.0f * a * n1) * piece_partition(pc, u);
        }
    }
    float ti = ibl__clampf((u - pc->table_u0) * pc->table_scale, 0.0f, (float)(PIECE_TABLE_STEPS + 1));
    int i = (int)ti;
    i = i > PIECE_TABLE_STEPS ? PIECE_TABLE_STEPS : i;
    float fr = ti - (float)i;
    const float *tab = pc->table;
    float g = tab[2 * i] + fr * (tab[2 * i + 2] - tab[2 * i]);
    float g2 = tab[2 * i + 1] + fr * (tab[2 * i + 3] - tab[2 * i + 1]);
    return g + 0.5f * g2 * q;
}

static void leaves_at(const leaf_batch *batch, const float R[3], const float RR[6], double out[4])
{
    const int B = BLOCK_TEXELS;
    int moments = batch->mode == LEAF_COARSE || batch->mode == LEAF_DIFFERENCE ? FIELD_LUM_MEAN : FIELD_MEAN;
    int light = batch->mode == LEAF_COARSE || batch->mode == LEAF_DIFFERENCE
                    ? (batch->without_bright ? FIELD_POWER_NOT_BRIGHT : FIELD_POWER)
                    : FIELD_RADIANCE;
    int difference = batch->mode == LEAF_DIFFERENCE;
    float acc[4] = {0, 0, 0, 0};
    for (int ci = 0; ci < batch->count; ci++) {
        const float *rec = candidate_record(batch, ci, R);
        if (!rec) continue;
        const float *om = rec + FIELD_SOLID_ANGLE * B, *L = rec + light * B;
        for (int t = 0; t < B; t++) {
            float w = 0;
            /* the difference form: the moment leaf, then minus the leaf at the geometric moments */
            for (int pass = 0; pass <= difference; pass++) {
                const float *m = rec + (pass ? FIELD_MEAN : moments) * B, *e = m + 3 * B, *c = m + 4 * B;
                float dx = R[0] - m[t], dy = R[1] - m[B + t], dz = R[2] - m[2 * B + t];
                float u = 0.5f * (dx * dx + dy * dy + dz * dz) + e[t];
                float q = RR[0] * c[t] + RR[1] * c[B + t] + RR[2] * c[2 * B + t] +
                          RR[3] * c[3 * B + t] + RR[4] * c[4 * B + t] + RR[5] * c[5 * B + t];
                float v = piece_leaf(batch->piece, u, q);
                w = pass ? w - v : v;
            }
            if (batch->mode == LEAF_NORMALISER) {
                acc[3] += w * om[t];
                continue;
            }
            if (batch->mode == LEAF_LEVEL0) w *= om[t];
            acc[0] += w * L[t], acc[1] += w * L[B + t], acc[2] += w * L[2 * B + t];
        }
    }
    for (int k = 0; k < 4; k++) out[k] += acc[k];
}

static void portable_sum_leaves(const leaf_batch *batch, int points, const float (*R)[3],
                                const float (*RR)[6], double (*out)[4])
{
    for (int i = 0; i < points; i++) leaves_at(batch, R[i], RR[i], out[i]);
}

static void portable_base_weights(const lobe_piece *pc, const float R[3], const float RR[6],
                                  const float *geometry, size_t plane, int padded_edge, int origin,
                                  const int32_t *rows, int row_count, float inv_scale, uint16_t *w,
                                  float lanes[8])
{
    for (int r = 0; r < row_count; r++) {
        const int32_t *row = rows + 3 * r;
        const float *g0 = geometry + (size_t)(row[0] + origin) * padded_edge + row[1] + origin;
        for (int i = 0; i < row[2]; i++) {
            const float *g = g0 + i;
            float dx = R[0] - g[0], dy = R[1] - g[plane], dz = R[2] - g[2 * plane];
            float u = 0.5f * (dx * dx + dy * dy + dz * dz) + g[FIELD_SPREAD * plane];
            float q = 0;
            for (int k = 0; k < 6; k++) q += RR[k] * g[(FIELD_COVARIANCE + k) * plane];
            float v = piece_leaf(pc, u, q) * g[FIELD_SOLID_ANGLE * plane] * inv_scale;
            w[i] = ibl_float_to_half(v);
            lanes[i % 8] += ibl_half_to_float(w[i]);
        }
        w += row[2];
    }
}

static void portable_row_extent(const float *g, size_t plane, int n, const float R[3],
                                float cos_reach, int *first, int *last)
{
    *first = *last = -1;
    for (int i = 0; i < n; i++) {
        float d = R[0] * g[i] + R[1] * g[plane + i] + R[2] * g[2 * plane + i];
        if (!(g[FIELD_SOLID_ANGLE * plane + i] > 0) || !(d >= cos_reach)) continue;
        if (*first < 0) *first = i;
        *last = i;
    }
}

static void portable_product(const precomputed_piece *c, size_t base, const uint16_t *w,
                             const uint16_t *cells, const float *planes, int flip_x, int flip_y,
                             double out[3])
{
    size_t plane = (size_t)c->padded_edge * c->padded_edge;
    (void)cells; /* (the rows say where the weights go) */
    const int32_t *rows = c->rows + 3 * (size_t)c->first_row[base];
    int row_count = (int)(c->first_row[base + 1] - c->first_row[base]), S = c->source_edge;
    float acc[3][8] = {{0}};
    for (int r = 0; r < row_count; r++) {
        const int32_t *row = rows + 3 * r;
        int Y = flip_y ? S - 1 - row[0] : row[0];
        const float *line = planes + (size_t)(Y + c->origin) * c->padded_edge + c->origin;
        for (int i = 0; i < row[2]; i += 8)
            for (int l = 0; l < 8; l++) {
                int X = flip_x ? S - 1 - (row[1] + i + l) : row[1] + i + l;
                float wl = ibl_half_to_float(w[i + l]);
                for (int ch = 0; ch < 3; ch++) acc[ch][l] += wl * line[ch * plane + X];
            }
        w += row[2];
    }
    for (int ch = 0; ch < 3; ch++) {
        double s = 0;
        for (int l = 0; l < 8; l++) s += acc[ch][l];
        out[ch] = s * c->weight_scale;
    }
}

const fast_kernels ibl__fast_kernels_portable = {portable_sum_leaves, portable_base_weights,
                                                  portable_row_extent, portable_product};
