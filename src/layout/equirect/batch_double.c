/* The windows of a batch that the float lanes (batch_lanes.h) leave, in double: windows under
 * 1/16 pixel (float rounding of their ends would eat their width), wider or taller than two
 * pixels, across the border of the polar bands, and those of pictures under 8 x 64.
 *
 * The same steps as the lanes, one sample at a time: the sample's direction on the face, its
 * weight dA / |d|^3, its window from the gradients of phi and theta along the face's axes
 * (times the cell size), then the window's mean: 4 x 4 taps for tent rows and polar bands (the
 * tent weights by the lanes' own four-lane function, redone in double for the narrowest
 * windows), ibl__eq_window_mean (area_windows.c) for the rest. */
#include "equirect_internal.h"

#include <math.h>

/* sqrt of n values: two at a time with SSE2 where there is SSE2 (the same IEEE results) */
#if defined(__SSE2__)
#include <emmintrin.h>
static inline void sqrt_run(const double *in, double *out, int n)
{
    int i = 0;
    for (; i + 2 <= n; i += 2) _mm_storeu_pd(out + i, _mm_sqrt_pd(_mm_loadu_pd(in + i)));
    for (; i < n; i++) out[i] = sqrt(in[i]);
}
#else
static inline void sqrt_run(const double *in, double *out, int n)
{
    for (int i = 0; i < n; i++) out[i] = sqrt(in[i]);
}
#endif

/* Each sample's weight and window: centre (px, py) and extent (wpx, hpx) in pixels, sin and
 * cos of its latitude; the windows given by the polar columns as they are. */
static void sample_windows(const eq_job *job, int face, eq_double_windows *dw)
{
    int W = job->im->width, H = job->im->height, n = dw->n;
    const double *m = job->basis[face][0], *a = job->basis[face][1], *b = job->basis[face][2];
    const double px_per_rad_u = W / IBL_TWO_PI, px_per_rad_v = H / IBL_PI;
    double *x = dw->t0, *y = dw->t1, *z = dw->t2, *rho = dw->t3, *len = dw->t4;
    for (int i = 0; i < n; i++) {
        double sc = dw->sc[i], tc = dw->tc[i];
        x[i] = m[0] + tc * b[0] + sc * a[0];
        y[i] = m[1] + tc * b[1] + sc * a[1];
        z[i] = m[2] + tc * b[2] + sc * a[2];
    }
    double *sq = dw->t5;
    for (int i = 0; i < n; i++) {
        sq[i] = x[i] * x[i] + z[i] * z[i];
        sq[EQ_BATCH + i] = sq[i] + y[i] * y[i];
    }
    sqrt_run(sq, rho, n);
    sqrt_run(sq + EQ_BATCH, len, n);
    for (int i = 0; i < n; i++) {
        double xi = x[i], yi = y[i], zi = z[i], sub = dw->sub[i];
        double rho2 = xi * xi + zi * zi;
        double inv_len = 1.0 / len[i], inv_len2 = inv_len * inv_len;
        double wt = inv_len2 * inv_len;
        double px = (eq_atan2_branchless(xi, -zi) * (0.5 / IBL_PI) + 0.5) * W;
        double py = eq_atan2_branchless(rho[i], yi) * (H / IBL_PI);
        /* extents of this sample's cell in longitude and latitude (pixels): the gradients of
         * phi and theta along both face axes, times the cell size */
        double g1 = fabs(yi * (xi * a[0] + zi * a[2]) - rho2 * a[1]);
        double g2 = fabs(yi * (xi * b[0] + zi * b[2]) - rho2 * b[1]);
        double ga = fabs(xi * a[2] - zi * a[0]), gb = fabs(xi * b[2] - zi * b[0]);
        double safe_rho2 = rho2 > 1e-300 ? rho2 : 1.0; /* on the axis: whole rows */
        double inv_rho2 = 1.0 / safe_rho2;
        double wpx = (ga + gb) * inv_rho2 * sub * px_per_rad_u;
        wpx = wpx < W ? wpx : (double)W;
        wpx = rho2 > 1e-300 ? wpx : (double)W;
        double hpx_axis = 2.0 * inv_len * sub * px_per_rad_v;
        double hpx = (g1 + g2) * rho[i] * inv_rho2 * inv_len2 * sub * px_per_rad_v;
        hpx = rho2 > 1e-300 ? hpx : hpx_axis;
        dw->wt[i] = wt;
        dw->px[i] = px;
        dw->py[i] = py;
        dw->wpx[i] = wpx;
        dw->hpx[i] = hpx;
        dw->st[i] = rho[i] * inv_len;
        dw->ct[i] = yi * inv_len;
    }
    for (int i = 0; i < n; i++)
        if (dw->preset[i]) {
            const double *g = dw->given[i];
            dw->wt[i] = g[0];
            dw->px[i] = g[1];
            dw->py[i] = g[2];
            dw->wpx[i] = g[3];
            dw->hpx[i] = g[4];
            dw->st[i] = g[5];
            dw->ct[i] = g[6];
        }
}

/* The row weights of polar-band window i, [py0, py1] with centre c: row jp + k covers
 * [jp + k, jp + k + 1]. The solid angle between theta_i < theta_j is
 * cos theta_i - cos theta_j = 2 sin(mean) sin(half the difference), both from the window's
 * centre theta_c (sin_t, cos_t) by the angle-sum formula and Taylor series in offsets below
 * pi / H (H >= 64: terms past the seventh power are below 1e-15). */
static void polar_band_weights(eq_double_windows *dw, int i, double py0, double py1, double c,
                               double sin_t, double cos_t, double k_rad)
{
    int jp = (int)py0;
    double cut[4] = {py0, py1 < jp + 1.0 ? py1 : jp + 1.0, py1 < jp + 2.0 ? py1 : jp + 2.0, py1};
    double share[3], sum = 0.0;
    for (int k = 0; k < 3; k++) {
        double m = (0.5 * (cut[k] + cut[k + 1]) - c) * k_rad, m2 = m * m;
        double hd = 0.5 * (cut[k + 1] - cut[k]) * k_rad, hd2 = hd * hd;
        double cm = 1.0 - m2 * (0.5 - m2 * (1.0 / 24 - m2 * (1.0 / 720)));
        double sm = m * (1.0 - m2 * (1.0 / 6 - m2 * (1.0 / 120 - m2 * (1.0 / 5040))));
        double shd = hd * (1.0 - hd2 * (1.0 / 6 - hd2 * (1.0 / 120 - hd2 * (1.0 / 5040))));
        share[k] = 2.0 * (sin_t * cm + cos_t * sm) * shd;
        share[k] = share[k] > 0.0 ? share[k] : 0.0;
        sum += share[k];
    }
    double inv = 1.0 / sum;
    for (int k = 0; k < 3; k++) dw->wyp[k][i] = (float)(share[k] * inv);
    dw->row[i] = jp;
    dw->rows[i] = cut[2] < py1 ? 3 : cut[1] < py1 ? 2 : 1;
    dw->v_dy[i] = dw->v_ey[i] = dw->v_h[i] = dw->v_sc[i] = dw->v_sd[i] = 0.0f;
}

/* Sorts the windows (as ibl__eq_window_mean would treat them): tent rows and polar bands at
 * most two pixels wide and tall get their four columns, first row and row count, and the tent
 * weights' parameters; kind 0 is left to ibl__eq_window_mean. Lanes [n, n4): any finite
 * window. */
static void window_kinds(const eq_job *job, eq_double_windows *dw, int n4)
{
    int W = job->im->width, H = job->im->height, n = dw->n;
    const long R = eq_polar_box_rows(H);
    const double k_rad = IBL_PI / H;
    const int narrow_ok = W >= 8, polar_ok = W >= 8 && H >= 64;
    for (int i = 0; i < n4; i++) {
        if (i >= n) {
            dw->v_da[i] = dw->v_e[i] = dw->v_dy[i] = dw->v_ey[i] = 0.0f;
            dw->v_sc[i] = dw->v_sd[i] = dw->v_h[i] = 0.0f;
            continue;
        }
        double hw = 0.5 * dw->wpx[i], hh = 0.5 * dw->hpx[i];
        double px0 = dw->px[i] - hw, w = 2.0 * hw, c = dw->py[i];
        double py0 = c - hh, py1 = c + hh, h_orig = 2.0 * hh;
        double sin_t = dw->st[i], cos_t = dw->ct[i];
        py0 = py0 < 0.0 ? 0.0 : py0;
        py1 = py1 > H ? (double)H : py1;
        py1 = py1 < py0 ? py0 : py1;
        double h = py1 - py0, s_d = k_rad * cos_t;
        double s_c = sin_t + s_d * (0.5 * (py0 + py1) - c);
        int ok = (h >= 1e-6) & (h <= 2.0) & (w >= 1e-6) & (w <= 2.0);
        int tent = narrow_ok & ok & (py0 - 0.5 >= R + 1) & (py1 + 0.5 <= H - R - 1);
        int polar = polar_ok & ok & !tent & ((py1 <= R) | (py0 >= H - R)) & (h_orig <= 2.0);
        dw->kind[i] = tent ? 1 : polar ? 2 : 0;
        if (!(tent | polar)) {
            dw->v_da[i] = dw->v_e[i] = dw->v_dy[i] = dw->v_ey[i] = 0.0f;
            dw->v_sc[i] = dw->v_sd[i] = dw->v_h[i] = 0.0f;
            continue;
        }
        /* longitude: the first column whose tent reaches the window, then four */
        double wa = px0 < 0.0 ? px0 + W : px0 >= W ? px0 - W : px0;
        int i0 = (int)(wa + 0.5) - 1; /* floor(wa - 1/2) */
        double da = wa - (i0 + 0.5);  /* in [0, 1) */
        for (int k = 0; k < 4; k++) {
            int col = i0 + k;
            col = col < 0 ? col + W : col >= W ? col - W : col;
            dw->col[k][i] = col;
        }
        dw->v_da[i] = (float)da;
        dw->v_e[i] = (float)(da + w);
        /* a window much narrower than a pixel loses its width to float rounding of its ends
         * (6e-8 / w relative): its weights are redone in double (tent_weights) */
        dw->fine[i] = w < 1.0 / 16 || (tent && h < 1.0 / 16);
        dw->fd[i][0] = da;
        dw->fd[i][1] = w;
        if (!tent) {
            polar_band_weights(dw, i, py0, py1, c, sin_t, cos_t, k_rad);
            continue;
        }
        /* row jt + k has centre py0 - dy + k */
        int jt = (int)(py0 + 0.5) - 1; /* floor(py0 - 1/2) */
        double dy = py0 - (jt + 0.5);
        dw->row[i] = jt;
        dw->rows[i] = dy + h > 2.0 ? 4 : dy + h > 1.0 ? 3 : 2;
        dw->v_dy[i] = (float)dy;
        dw->v_ey[i] = (float)(dy + h);
        dw->v_h[i] = (float)h;
        dw->v_sc[i] = (float)s_c;
        dw->v_sd[i] = (float)s_d;
        dw->fd[i][2] = dy;
        dw->fd[i][3] = h;
        dw->fd[i][4] = s_c;
        dw->fd[i][5] = s_d;
    }
}

/* The tent weights: four windows at a time in float (the taps are float), by the lanes' own
 * function, then the narrowest windows' again in double. */
static void tent_weights(eq_double_windows *dw, int n4)
{
    for (int i = 0; i < n4; i += 4) {
        v4f da = vload(dw->v_da + i), e = vload(dw->v_e + i);
        v4f dy = vload(dw->v_dy + i), ey = vload(dw->v_ey + i), h = vload(dw->v_h + i);
        v4f sc = vload(dw->v_sc + i), sd = vload(dw->v_sd + i);
        v4f wy[4], wx[4];
        ibl__eq_tent_weights_4(da, e, dy, ey, h, sc, sd, wy, wx);
        for (int k = 0; k < 4; k++) {
            vstore(dw->wyt[k] + i, wy[k]);
            vstore(dw->wx[k] + i, wx[k]);
        }
    }
    for (int i = 0; i < dw->n; i++) {
        if (!dw->kind[i] || !dw->fine[i]) continue;
        const double *f = dw->fd[i];
        double wx[4], sum = 0.0;
        for (int k = 0; k < 4; k++) {
            wx[k] = eq_tent_cdf(f[0] + f[1] - k) - eq_tent_cdf(f[0] - k);
            sum += wx[k];
        }
        for (int k = 0; k < 4; k++) dw->wx[k][i] = (float)(wx[k] / sum);
        if (dw->kind[i] != 1) continue;
        double dy = f[2], h = f[3], share[4];
        sum = 0.0;
        for (int k = 0; k < 4; k++) {
            double t = eq_tent_cdf(dy + h - k) - eq_tent_cdf(dy - k);
            double mom = eq_tent_moment(dy + h - k) - eq_tent_moment(dy - k);
            share[k] = t * (f[4] + f[5] * (k - dy - 0.5 * h)) + f[5] * mom;
            sum += share[k];
        }
        for (int k = 0; k < 4; k++) dw->wyt[k][i] = (float)(share[k] / sum);
    }
}

/* Each window's mean: from its taps, or by ibl__eq_window_mean. */
static void window_means(const eq_job *job, eq_double_windows *dw)
{
    int W = job->im->width, H = job->im->height;
    const float *pix = job->im->pixels;
    for (int i = 0; i < dw->n; i++) {
        float *val = dw->val[i];
        val[0] = val[1] = val[2] = val[3] = 0.0f;
        if (dw->kind[i]) {
            for (int k = 0; k < dw->rows[i]; k++) {
                long r = dw->row[i] + k < H ? dw->row[i] + k : H - 1; /* past the window: 0 */
                const float *rowp = pix + (size_t)r * W * 4;
                float wy = dw->kind[i] == 1 ? dw->wyt[k][i] : dw->wyp[k][i], v[4] = {0, 0, 0, 0};
                for (int t = 0; t < 4; t++) {
                    const float *p = rowp + (size_t)dw->col[t][i] * 4;
                    float wx = dw->wx[t][i];
                    for (int ch = 0; ch < 4; ch++) v[ch] += wx * p[ch];
                }
                for (int ch = 0; ch < 4; ch++) val[ch] += wy * v[ch];
            }
        } else {
            double px = dw->px[i], py = dw->py[i], hw = 0.5 * dw->wpx[i], hh = 0.5 * dw->hpx[i];
            ibl__eq_window_mean(job, px - hw, px + hw, py - hh, py + hh, dw->st[i], dw->ct[i],
                                val);
        }
    }
}

void ibl__eq_double_windows(const eq_job *job, int face, eq_double_windows *dw)
{
    int n4 = (dw->n + 3) & ~3;
    sample_windows(job, face, dw);
    window_kinds(job, dw, n4);
    tent_weights(dw, n4);
    window_means(job, dw);
}
