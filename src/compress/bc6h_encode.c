/* BC6H encoding (layouts: Khronos Data Format Specification 1.3, section "BC6H").
 *
 * BC6H interpolates integers that the final unquantization turns into half-float bit
 * patterns, so the encoder works in that integer domain: a texel value x becomes the
 * continuous half bit pattern h(x) (exponent * 1024 + mantissa, a piecewise-linear log2),
 * plus 0.5 (the final step truncates), scaled by 64/31 (unsigned) or 32/31 (signed) to the
 * interpolation domain. Errors are squared distances there, summed over R, G and B.
 *
 * Per block:
 *  1. one region: a principal-axis line through the 16 texels gives two endpoints; each
 *     one-region mode (3, 7, 11, 15) quantizes them (nearest unquantized value), orders them
 *     so the anchor texel sits near E0, and, when its deltas do not fit, clamps them;
 *  2. two regions: every partition is scored by the residual of a principal-axis fit of
 *     each subset; the best few (1 fast, 2 default, 8 thorough) are tried in the two-region
 *     modes;
 *  3. each try assigns the nearest palette entry to every texel, makes the anchors' top
 *     index bit 0 (swapping a subset's endpoints when the deltas allow, else restricting the
 *     anchor's index), then refines: least-squares endpoints for the chosen indices,
 *     quantized again, kept while the error falls;
 *  4. thorough: a last search moves each quantized endpoint channel by +-1.
 * Modes are tried from the highest endpoint precision down; fast and default stop after the
 * first whose deltas fit unclamped (or the untransformed mode), thorough tries all 14 with
 * clamped deltas where they do not fit, and compares every palette entry for each texel
 * (fast and default: the entries next to the texel's projection on the endpoints' line).
 * Fast and default skip two regions when one region is already within 4 (fast) or 2
 * (default) interpolation-domain units RMS per channel. */
#include <math.h>
#include <string.h>

#include "ibl/compress.h"
#include "compress/bc6h_internal.h"
#include "core/context_internal.h"

typedef struct enc_block {
    float v[16][3]; /* targets in the interpolation domain */
    int is_signed;
    int exhaustive; /* indices: every palette entry (thorough), else the line projection +-1 */
} enc_block;

typedef struct cand {
    int mode, partition;
    int q[4][3]; /* quantized endpoints E0..E3 (E0, E1: subset 0; E2, E3: subset 1) */
    uint8_t index[16];
    float err;
} cand;

typedef struct effort {
    int partitions; /* two-region partitions tried                                      */
    int modes;      /* fitting modes tried per region count (14: all)                    */
    int refine;     /* least-squares passes                                              */
    int search;     /* +-1 endpoint search on the best candidate, exhaustive indices     */
    float enough;   /* one-region error per texel channel below which two regions are
                       not tried (squared interpolation-domain units; 0.5 unit = 1/4 of
                       a half-float step)                                                */
} effort;

static effort effort_of(ibl_quality q)
{
    switch (q) {
    case IBL_QUALITY_FAST: return (effort){1, 1, 1, 0, 16.0f};
    case IBL_QUALITY_THOROUGH: return (effort){8, BC6H_MODES, 4, 1, 0.0f};
    default: return (effort){2, 1, 2, 0, 4.0f};
    }
}

/* Modes by decreasing endpoint precision (indices into ibl__bc6h_modes). */
static const uint8_t TWO_REGION_ORDER[10] = {2, 3, 4, 0, 5, 6, 7, 8, 1, 9};
static const uint8_t ONE_REGION_ORDER[4] = {13, 12, 11, 10};

/* ---- the interpolation domain ---- */

static float to_domain(float x, int is_signed)
{
    if (!(x == x)) return 0.0f; /* NaN */
    float sign = 1.0f;
    if (x < 0.0f) {
        if (!is_signed) return 0.0f;
        sign = -1.0f;
        x = -x;
    }
    if (x > 65504.0f) x = 65504.0f;
    float h;
    if (x < 6.103515625e-05f) { /* a half denormal: x / 2^-24 */
        h = x * 16777216.0f;
    } else {
        int e;
        float f = frexpf(x, &e); /* x = f 2^e, f in [0.5, 1) */
        h = (float)(e + 14) * 1024.0f + (2.0f * f - 1.0f) * 1024.0f;
    }
    if (h <= 0.0f) return 0.0f;
    return sign * (h + 0.5f) * (is_signed ? 32.0f / 31.0f : 64.0f / 31.0f);
}

static float domain_min(int is_signed) { return is_signed ? -32767.0f : 0.0f; }
static float domain_max(int is_signed) { return is_signed ? 32767.0f : 65535.0f; }

/* The quantized endpoint of `prec` bits whose unquantized value is nearest v. */
static int quantize(float v, int prec, int is_signed)
{
    if (!is_signed) {
        if (prec >= 15) {
            long q = lrintf(v);
            return q < 0 ? 0 : q > 65535 ? 65535 : (int)q;
        }
        int max = (1 << prec) - 1;
        int q = (int)(v * (float)(1 << prec) * (1.0f / 65536.0f));
        /* inside the range, unquantize(q) is the middle of [q, q + 1) * 2^(16 - prec) */
        if (q >= 1 && q <= max - 2) return q;
        int best = 0;
        float best_d = 1e30f;
        for (int k = q - 1; k <= q + 1; k++) {
            if (k < 0 || k > max) continue;
            float d = fabsf((float)ibl__bc6h_unquantize(k, prec, 0) - v);
            if (d < best_d) best_d = d, best = k;
        }
        return best;
    }
    if (prec >= 16) {
        long q = lrintf(v);
        return q < -32767 ? -32767 : q > 32767 ? 32767 : (int)q;
    }
    float m = fabsf(v);
    int max = (1 << (prec - 1)) - 1;
    int q = (int)(m * (float)(1 << (prec - 1)) * (1.0f / 32768.0f));
    if (q >= 1 && q <= max - 2) return v < 0.0f ? -q : q;
    int best = 0;
    float best_d = 1e30f;
    for (int k = q - 1; k <= q + 1; k++) {
        if (k < 0 || k > max) continue;
        float d = fabsf((float)ibl__bc6h_unquantize(k, prec, 1) - m);
        if (d < best_d) best_d = d, best = k;
    }
    return v < 0.0f ? -best : best;
}

/* ---- endpoint deltas ---- */

/* The delta of endpoint k from E0 as stored (plain or wrapped modulo 2^prec, as the decoder
 * wraps); *fits is 0 when neither form fits the delta bits. */
static int delta_of(int q0, int qk, int prec, int bits, int *fits)
{
    int lo = -(1 << (bits - 1)), hi = (1 << (bits - 1)) - 1;
    int d = qk - q0;
    int alts[3] = {d, d - (1 << prec), d + (1 << prec)};
    for (int i = 0; i < 3; i++)
        if (alts[i] >= lo && alts[i] <= hi) {
            *fits = 1;
            return alts[i];
        }
    *fits = 0;
    return d < lo ? lo : hi;
}

/* Non-zero when every delta of a transformed mode fits; with clamp, moves the endpoints that
 * do not fit to the nearest that do. */
static int fit_deltas(const bc6h_mode *m, int q[4][3], int clamp)
{
    if (!m->transformed) return 1;
    int all = 1;
    for (int k = 1; k < 2 * m->regions; k++)
        for (int c = 0; c < 3; c++) {
            int fits;
            int d = delta_of(q[0][c], q[k][c], m->prec, m->delta[c], &fits);
            if (fits) continue;
            all = 0;
            if (clamp) q[k][c] = q[0][c] + d; /* between E0 and the wanted value: in range */
        }
    return all;
}

/* ---- index assignment ---- */

static int anchor_of(const cand *c, int subset)
{
    return subset ? ibl__bc6h_anchor2[c->partition] : 0;
}

static uint16_t shape_of(const bc6h_mode *m, int partition)
{
    return m->regions == 2 ? ibl__bc6h_partitions[partition] : 0;
}

/* The palettes of both subsets (interpolated integers, before the final step). */
static int palettes(const bc6h_mode *m, const int q[4][3], int is_signed, float pal[2][16][3])
{
    int n = m->regions == 2 ? 8 : 16;
    const uint8_t *w = n == 8 ? ibl__bc6h_weights3 : ibl__bc6h_weights4;
    for (int s = 0; s < m->regions; s++)
        for (int c = 0; c < 3; c++) {
            int a = ibl__bc6h_unquantize(q[2 * s][c], m->prec, is_signed);
            int b = ibl__bc6h_unquantize(q[2 * s + 1][c], m->prec, is_signed);
            for (int i = 0; i < n; i++) pal[s][i][c] = (float)ibl__bc6h_interpolate(a, b, w[i]);
        }
    return n;
}

static float texel_error(const float *v, const float *p)
{
    float dr = v[0] - p[0], dg = v[1] - p[1], db = v[2] - p[2];
    return dr * dr + dg * dg + db * db;
}

/* Nearest palette entry among the first `limit`; returns its error. */
static float nearest(const float *v, float pal[16][3], int limit, uint8_t *index)
{
    float best = 1e38f;
    for (int i = 0; i < limit; i++) {
        float e = texel_error(v, pal[i]);
        if (e < best) best = e, *index = (uint8_t)i;
    }
    return best;
}

/* The palette entry nearest v by projection onto the endpoints' line: the weight nearest
 * the projection and its two neighbours are compared (the entries lie on the line up to
 * the interpolation's rounding). */
static float nearest_on_line(const float *v, float pal[16][3], int n, uint8_t *index)
{
    const float *a = pal[0], *z = pal[n - 1];
    float d[3] = {z[0] - a[0], z[1] - a[1], z[2] - a[2]};
    float len = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    int guess = 0;
    if (len > 0.0f) {
        /* the weights are within one of index * 64 / (n - 1): start there */
        float t = ((v[0] - a[0]) * d[0] + (v[1] - a[1]) * d[1] + (v[2] - a[2]) * d[2]) / len;
        guess = (int)(t * (float)(n - 1) + 0.5f);
        guess = guess < 0 ? 0 : guess > n - 1 ? n - 1 : guess;
    }
    int lo = guess > 0 ? guess - 1 : 0, hi = guess < n - 1 ? guess + 1 : n - 1;
    float best = 1e38f;
    for (int i = lo; i <= hi; i++) {
        float e = texel_error(v, pal[i]);
        if (e < best) best = e, *index = (uint8_t)i;
    }
    return best;
}

/* Assigns indices for c's endpoints and makes each anchor's top index bit 0. Returns the
 * error (also stored in c->err). */
static float evaluate(const enc_block *b, cand *c)
{
    const bc6h_mode *m = &ibl__bc6h_modes[c->mode];
    float pal[2][16][3];
    int n = palettes(m, c->q, b->is_signed, pal);
    uint16_t shape = shape_of(m, c->partition);
    float err = 0.0f;
    for (int t = 0; t < 16; t++)
        err += b->exhaustive ? nearest(b->v[t], pal[(shape >> t) & 1], n, &c->index[t])
                             : nearest_on_line(b->v[t], pal[(shape >> t) & 1], n, &c->index[t]);
    for (int s = 0; s < m->regions; s++) {
        int anchor = anchor_of(c, s);
        if (c->index[anchor] < n / 2) continue;
        int swapped[4][3];
        memcpy(swapped, c->q, sizeof swapped);
        for (int ch = 0; ch < 3; ch++) {
            swapped[2 * s][ch] = c->q[2 * s + 1][ch];
            swapped[2 * s + 1][ch] = c->q[2 * s][ch];
        }
        if (fit_deltas(m, swapped, 0)) { /* the same palette reversed: the same error */
            memcpy(c->q, swapped, sizeof swapped);
            for (int t = 0; t < 16; t++)
                if (((shape >> t) & 1) == s) c->index[t] = (uint8_t)(n - 1 - c->index[t]);
        } else {
            err -= texel_error(b->v[anchor], pal[s][c->index[anchor]]);
            err += nearest(b->v[anchor], pal[s], n / 2, &c->index[anchor]);
        }
    }
    c->err = err;
    return err;
}

/* ---- endpoint fitting ---- */

/* The principal-axis line through the texels of `mask`: endpoints at the extreme
 * projections. Returns the residual (sum of squared distances to the line). */
static float fit_line(const enc_block *b, uint16_t mask, float lo[3], float hi[3])
{
    float mean[3] = {0, 0, 0}, cov[6] = {0, 0, 0, 0, 0, 0};
    int count = 0;
    for (int t = 0; t < 16; t++)
        if ((mask >> t) & 1) {
            for (int c = 0; c < 3; c++) mean[c] += b->v[t][c];
            count++;
        }
    if (count == 0) {
        memset(lo, 0, 3 * sizeof *lo);
        memset(hi, 0, 3 * sizeof *hi);
        return 0.0f;
    }
    for (int c = 0; c < 3; c++) mean[c] /= (float)count;
    for (int t = 0; t < 16; t++)
        if ((mask >> t) & 1) {
            float d[3] = {b->v[t][0] - mean[0], b->v[t][1] - mean[1], b->v[t][2] - mean[2]};
            cov[0] += d[0] * d[0], cov[1] += d[0] * d[1], cov[2] += d[0] * d[2];
            cov[3] += d[1] * d[1], cov[4] += d[1] * d[2], cov[5] += d[2] * d[2];
        }
    /* power iteration from the row of the largest variance */
    float axis[3];
    int r = cov[0] >= cov[3] && cov[0] >= cov[5] ? 0 : cov[3] >= cov[5] ? 1 : 2;
    const float rows[3][3] = {{cov[0], cov[1], cov[2]}, {cov[1], cov[3], cov[4]},
                              {cov[2], cov[4], cov[5]}};
    memcpy(axis, rows[r], sizeof axis);
    float len = 0.0f;
    for (int it = 0; it < 4; it++) {
        float x[3];
        for (int c = 0; c < 3; c++)
            x[c] = rows[c][0] * axis[0] + rows[c][1] * axis[1] + rows[c][2] * axis[2];
        len = sqrtf(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        if (!(len > 1e-12f)) break;
        for (int c = 0; c < 3; c++) axis[c] = x[c] / len;
    }
    float trace = cov[0] + cov[3] + cov[5];
    if (!(len > 1e-12f)) { /* all texels equal */
        memcpy(lo, mean, sizeof mean);
        memcpy(hi, mean, sizeof mean);
        return trace;
    }
    float tmin = 1e30f, tmax = -1e30f, along = 0.0f;
    for (int t = 0; t < 16; t++)
        if ((mask >> t) & 1) {
            float p = 0.0f;
            for (int c = 0; c < 3; c++) p += (b->v[t][c] - mean[c]) * axis[c];
            tmin = p < tmin ? p : tmin;
            tmax = p > tmax ? p : tmax;
            along += p * p;
        }
    for (int c = 0; c < 3; c++) {
        lo[c] = mean[c] + axis[c] * tmin;
        hi[c] = mean[c] + axis[c] * tmax;
    }
    float residual = trace - along;
    return residual > 0.0f ? residual : 0.0f;
}

/* Least-squares endpoints of subset s for c's indices; 0 if the system is singular. */
static int least_squares(const enc_block *b, const cand *c, int s, float lo[3], float hi[3])
{
    const bc6h_mode *m = &ibl__bc6h_modes[c->mode];
    const uint8_t *w = m->regions == 2 ? ibl__bc6h_weights3 : ibl__bc6h_weights4;
    uint16_t shape = shape_of(m, c->partition);
    float a11 = 0, a12 = 0, a22 = 0, b1[3] = {0, 0, 0}, b2[3] = {0, 0, 0};
    for (int t = 0; t < 16; t++) {
        if (((shape >> t) & 1) != s) continue;
        float wt = (float)w[c->index[t]] * (1.0f / 64.0f), iw = 1.0f - wt;
        a11 += iw * iw, a12 += iw * wt, a22 += wt * wt;
        for (int ch = 0; ch < 3; ch++) b1[ch] += iw * b->v[t][ch], b2[ch] += wt * b->v[t][ch];
    }
    float det = a11 * a22 - a12 * a12;
    if (!(fabsf(det) > 1e-6f)) return 0;
    float lo_d = domain_min(b->is_signed), hi_d = domain_max(b->is_signed);
    for (int ch = 0; ch < 3; ch++) {
        float x = (a22 * b1[ch] - a12 * b2[ch]) / det, y = (a11 * b2[ch] - a12 * b1[ch]) / det;
        lo[ch] = x < lo_d ? lo_d : x > hi_d ? hi_d : x;
        hi[ch] = y < lo_d ? lo_d : y > hi_d ? hi_d : y;
    }
    return 1;
}

/* ---- trying a mode ---- */

/* Quantizes float endpoints into c (E0..E3 from ep, subset by subset) for c->mode; orders
 * each subset so its anchor texel projects nearer the first endpoint. Returns 0 if the
 * deltas do not fit and clamp is 0. */
static int set_endpoints(const enc_block *b, cand *c, float ep[4][3], int clamp)
{
    const bc6h_mode *m = &ibl__bc6h_modes[c->mode];
    for (int s = 0; s < m->regions; s++) {
        const float *v = b->v[anchor_of(c, s)], *e0 = ep[2 * s], *e1 = ep[2 * s + 1];
        float along = 0.0f, len = 0.0f;
        for (int ch = 0; ch < 3; ch++) {
            along += (v[ch] - e0[ch]) * (e1[ch] - e0[ch]);
            len += (e1[ch] - e0[ch]) * (e1[ch] - e0[ch]);
        }
        int swap = along > 0.5f * len;
        for (int ch = 0; ch < 3; ch++) {
            c->q[2 * s][ch] = quantize(swap ? e1[ch] : e0[ch], m->prec, b->is_signed);
            c->q[2 * s + 1][ch] = quantize(swap ? e0[ch] : e1[ch], m->prec, b->is_signed);
        }
    }
    return fit_deltas(m, c->q, clamp) || clamp;
}

/* Least-squares refinement passes, kept while the error falls. */
static void refine(const enc_block *b, cand *c, int passes)
{
    const bc6h_mode *m = &ibl__bc6h_modes[c->mode];
    for (int p = 0; p < passes; p++) {
        cand next = *c;
        float ep[4][3];
        int ok = 1;
        for (int s = 0; s < m->regions && ok; s++) ok = least_squares(b, c, s, ep[2 * s], ep[2 * s + 1]);
        if (!ok) {
            /* a subset whose texels all share one index: keep its endpoints */
            for (int s = 0; s < m->regions; s++)
                if (!least_squares(b, c, s, ep[2 * s], ep[2 * s + 1]))
                    for (int k = 0; k < 2; k++)
                        for (int ch = 0; ch < 3; ch++)
                            ep[2 * s + k][ch] = (float)ibl__bc6h_unquantize(c->q[2 * s + k][ch], m->prec, b->is_signed);
        }
        set_endpoints(b, &next, ep, 1);
        if (evaluate(b, &next) < c->err) *c = next;
        else break;
    }
}

/* The +-1 search over every quantized endpoint channel (thorough). */
static void endpoint_search(const enc_block *b, cand *c)
{
    const bc6h_mode *m = &ibl__bc6h_modes[c->mode];
    int lo = b->is_signed ? -((1 << (m->prec - 1)) - 1) : 0;
    int hi = b->is_signed ? (1 << (m->prec - 1)) - 1 : (1 << m->prec) - 1;
    if (m->prec >= 16) lo = b->is_signed ? -32767 : 0, hi = b->is_signed ? 32767 : 65535;
    for (int k = 0; k < 2 * m->regions; k++)
        for (int ch = 0; ch < 3; ch++)
            for (int step = -1; step <= 1; step += 2) {
                cand next = *c;
                int v = next.q[k][ch] + step;
                if (v < lo || v > hi) continue;
                next.q[k][ch] = v;
                if (!fit_deltas(m, next.q, 0)) continue;
                if (evaluate(b, &next) < c->err) *c = next;
            }
}

/* Tries the modes of one region count on float endpoints ep (partition p for two). */
static void try_modes(const enc_block *b, const effort *ef, int regions, int partition,
                      float ep[4][3], cand *best)
{
    const uint8_t *order = regions == 2 ? TWO_REGION_ORDER : ONE_REGION_ORDER;
    int count = regions == 2 ? 10 : 4, tried = 0;
    for (int i = 0; i < count && tried < ef->modes; i++) {
        cand c;
        memset(&c, 0, sizeof c);
        c.mode = order[i];
        c.partition = partition;
        int last = i == count - 1; /* the untransformed mode always fits */
        if (!set_endpoints(b, &c, ep, ef->modes >= BC6H_MODES || last)) continue;
        tried++;
        evaluate(b, &c);
        refine(b, &c, ef->refine);
        if (c.err < best->err) *best = c;
    }
}

/* ---- partitions ---- */

/* Sums of x and of x x^T (six products) per texel, for scoring partitions. */
typedef struct texel_sums {
    float x[16][3], xx[16][6], total_x[3], total_xx[6];
} texel_sums;

/* The residual of the principal-axis line through n texels with sums sx, sxx: the trace of
 * their scatter matrix minus its largest eigenvalue (power iteration). */
static float line_residual_of_sums(const float sx[3], const float sxx[6], int n)
{
    if (n < 2) return 0.0f;
    float inv = 1.0f / (float)n;
    float c00 = sxx[0] - sx[0] * sx[0] * inv, c01 = sxx[1] - sx[0] * sx[1] * inv;
    float c02 = sxx[2] - sx[0] * sx[2] * inv, c11 = sxx[3] - sx[1] * sx[1] * inv;
    float c12 = sxx[4] - sx[1] * sx[2] * inv, c22 = sxx[5] - sx[2] * sx[2] * inv;
    float trace = c00 + c11 + c22;
    float a[3] = {c00 >= c11 && c00 >= c22 ? 1.0f : 0.0f, c11 > c00 && c11 >= c22 ? 1.0f : 0.0f,
                  c22 > c00 && c22 > c11 ? 1.0f : 0.0f};
    float lambda = 0.0f;
    for (int it = 0; it < 3; it++) {
        float y[3] = {c00 * a[0] + c01 * a[1] + c02 * a[2], c01 * a[0] + c11 * a[1] + c12 * a[2],
                      c02 * a[0] + c12 * a[1] + c22 * a[2]};
        float len = sqrtf(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
        if (!(len > 1e-20f)) return trace > 0.0f ? trace : 0.0f;
        for (int c = 0; c < 3; c++) a[c] = y[c] / len;
        lambda = len;
    }
    float r = trace - lambda;
    return r > 0.0f ? r : 0.0f;
}

/* The two subsets' residuals: subset 1 summed from its mask, subset 0 the rest. */
static float partition_residual(const texel_sums *ts, uint16_t shape)
{
    float sx[3] = {0, 0, 0}, sxx[6] = {0, 0, 0, 0, 0, 0}, rx[3], rxx[6];
    int n = 0;
    for (int t = 0; t < 16; t++) {
        if (!((shape >> t) & 1)) continue;
        n++;
        for (int c = 0; c < 3; c++) sx[c] += ts->x[t][c];
        for (int k = 0; k < 6; k++) sxx[k] += ts->xx[t][k];
    }
    for (int c = 0; c < 3; c++) rx[c] = ts->total_x[c] - sx[c];
    for (int k = 0; k < 6; k++) rxx[k] = ts->total_xx[k] - sxx[k];
    return line_residual_of_sums(sx, sxx, n) + line_residual_of_sums(rx, rxx, 16 - n);
}

static void best_partitions(const enc_block *b, int want, int *out)
{
    /* centred on the block's mean: the scatter matrices do not change, and the sums stay
     * small enough for float (a sun's values are near 65535) */
    texel_sums ts;
    float mean[3] = {0, 0, 0};
    for (int t = 0; t < 16; t++)
        for (int c = 0; c < 3; c++) mean[c] += b->v[t][c] * (1.0f / 16.0f);
    for (int t = 0; t < 16; t++) {
        float v[3] = {b->v[t][0] - mean[0], b->v[t][1] - mean[1], b->v[t][2] - mean[2]};
        memcpy(ts.x[t], v, sizeof ts.x[t]);
        ts.xx[t][0] = v[0] * v[0], ts.xx[t][1] = v[0] * v[1], ts.xx[t][2] = v[0] * v[2];
        ts.xx[t][3] = v[1] * v[1], ts.xx[t][4] = v[1] * v[2], ts.xx[t][5] = v[2] * v[2];
    }
    memset(ts.total_x, 0, sizeof ts.total_x);
    memset(ts.total_xx, 0, sizeof ts.total_xx);
    for (int t = 0; t < 16; t++) {
        for (int c = 0; c < 3; c++) ts.total_x[c] += ts.x[t][c];
        for (int k = 0; k < 6; k++) ts.total_xx[k] += ts.xx[t][k];
    }
    float score[BC6H_PARTITIONS];
    for (int p = 0; p < BC6H_PARTITIONS; p++) score[p] = partition_residual(&ts, ibl__bc6h_partitions[p]);
    for (int k = 0; k < want; k++) { /* selection in a fixed order: ties keep the lower p */
        int pick = -1;
        for (int p = 0; p < BC6H_PARTITIONS; p++) {
            int used = 0;
            for (int j = 0; j < k; j++) used |= out[j] == p;
            if (!used && (pick < 0 || score[p] < score[pick])) pick = p;
        }
        out[k] = pick;
    }
}

/* ---- packing ---- */

static void pack(const cand *c, int is_signed, uint8_t block[16])
{
    const bc6h_mode *m = &ibl__bc6h_modes[c->mode];
    int field[14];
    int mask = (1 << m->prec) - 1;
    (void)is_signed;
    for (int k = 0; k < 2 * m->regions; k++)
        for (int ch = 0; ch < 3; ch++) {
            int v = c->q[k][ch];
            if (k > 0 && m->transformed) {
                int fits;
                v = delta_of(c->q[0][ch], v, m->prec, m->delta[ch], &fits);
                v &= (1 << m->delta[ch]) - 1;
            } else {
                v &= mask;
            }
            field[3 * k + ch] = v;
        }
    for (int i = 6 * m->regions; i < 12; i++) field[i] = 0;
    field[BC6H_FIELD_M] = m->number;
    field[BC6H_FIELD_PB] = c->partition;
    memset(block, 0, 16);
    int pos = 0;
    for (int s = 0; s < m->seg_count; s++) {
        const bc6h_seg *g = &m->segs[s];
        int n = g->a >= g->b ? g->a - g->b + 1 : g->b - g->a + 1;
        unsigned bits = 0;
        for (int i = 0; i < n; i++) {
            int src = g->a >= g->b ? g->b + i : g->b - i;
            bits |= (unsigned)((field[g->field] >> src) & 1) << i;
        }
        ibl__bc6h_put_bits(block, pos, n, bits);
        pos += n;
    }
    int two = m->regions == 2, ibits = two ? 3 : 4;
    int anchor = two ? ibl__bc6h_anchor2[c->partition] : 0;
    for (int t = 0; t < 16; t++) {
        int n = (t == 0 || (two && t == anchor)) ? ibits - 1 : ibits;
        ibl__bc6h_put_bits(block, pos, n, c->index[t]);
        pos += n;
    }
}

/* ---- blocks and images ---- */

void ibl_bc6h_encode_block(const ibl_bc6h_desc *desc, const float rgba[64], uint8_t block[16])
{
    ibl_bc6h_desc d = desc ? *desc : (ibl_bc6h_desc){0};
    effort ef = effort_of(d.quality);
    enc_block b;
    b.is_signed = d.is_signed != 0;
    b.exhaustive = ef.search;
    for (int t = 0; t < 16; t++)
        for (int c = 0; c < 3; c++) b.v[t][c] = to_domain(rgba[4 * t + c], b.is_signed);

    cand best;
    memset(&best, 0, sizeof best);
    best.err = 1e38f;
    float ep[4][3];
    fit_line(&b, 0xFFFF, ep[0], ep[1]);
    try_modes(&b, &ef, 1, 0, ep, &best);
    /* a block one region already encodes closely enough (effort.enough) needs no more */
    if (best.err > ef.enough * 48.0f || ef.modes >= BC6H_MODES) {
        int parts[BC6H_PARTITIONS];
        best_partitions(&b, ef.partitions, parts);
        for (int k = 0; k < ef.partitions; k++) {
            uint16_t shape = ibl__bc6h_partitions[parts[k]];
            fit_line(&b, (uint16_t)~shape, ep[0], ep[1]);
            fit_line(&b, shape, ep[2], ep[3]);
            try_modes(&b, &ef, 2, parts[k], ep, &best);
        }
    }
    if (ef.search) endpoint_search(&b, &best);
    pack(&best, b.is_signed, block);
}

typedef struct encode_job {
    ibl_bc6h_desc desc;
    int width, height, blocks_x;
    const float *rgba;
    uint8_t *blocks;
} encode_job;

static void encode_row(void *arg, int by)
{
    const encode_job *j = arg;
    float texels[64];
    for (int bx = 0; bx < j->blocks_x; bx++) {
        for (int y = 0; y < 4; y++) {
            int sy = by * 4 + y < j->height ? by * 4 + y : j->height - 1; /* padding: repeat */
            for (int x = 0; x < 4; x++) {
                int sx = bx * 4 + x < j->width ? bx * 4 + x : j->width - 1;
                memcpy(texels + 4 * (4 * y + x),
                       j->rgba + ((size_t)sy * (size_t)j->width + (size_t)sx) * 4, 4 * sizeof(float));
            }
        }
        ibl_bc6h_encode_block(&j->desc, texels,
                              j->blocks + ((size_t)by * (size_t)j->blocks_x + (size_t)bx) * 16);
    }
}

ibl_status ibl_bc6h_encode(ibl_context *ctx, const ibl_bc6h_desc *desc, const float *rgba,
                           int width, int height, void *blocks)
{
    if (!rgba || !blocks || width <= 0 || height <= 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "BC6H encode: invalid arguments");
    encode_job j = {desc ? *desc : (ibl_bc6h_desc){0}, width, height, (width + 3) / 4, rgba, blocks};
    ibl_parallel_for(ctx, (height + 3) / 4, encode_row, &j);
    return IBL_OK;
}
