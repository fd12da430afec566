/* The energy-preserving windows of the equirect -> cube conversion, in double.
 *
 * The source is reconstructed by linear interpolation between pixel centres (wrapping in
 * longitude), which is the convolution of the pixels with the unit tent max(0, 1 - |t|);
 * near the poles the rows are constant bands instead (row_share says why). A cube sample does
 * not read that reconstruction at a point but averages it over its cell's longitude/latitude
 * extent (a window), weighted by solid angle, sin(theta) dtheta dphi. Where the cells line up
 * with the meridians these windows tile the sphere, and because the tents of a row sum to one
 * (and each pixel's tent integrates to one pixel), windows that tile a row add up to exactly
 * the sum of its pixels: a small bright source keeps its energy wherever it falls, and a
 * window much larger than a pixel is a true area average (no aliasing).
 *
 * The integrals are closed forms of the tent (eq_tent_cdf, eq_tent_moment in
 * equirect_internal.h) and of sin(theta) over a band (band_solid_angle). These are the
 * reference windows; the batch engine's float lanes (batch_lanes.h) compute the same windows
 * for the common narrow ones. */
#include "equirect_internal.h"

#include <math.h>

/* Mean over the column window [a, b] (pixel i covers [i, i+1)) of the linear interpolant of
 * row r through its pixel centres, wrapping in longitude. Windows that tile the row add up to
 * exactly the sum of its pixels, so energy is kept however the windows fall. */
static void row_window_mean(const eq_job *job, int r, double a, double b, float out[4])
{
    const ibl_image *im = job->im;
    int W = im->width;
    const float *row = im->pixels + (size_t)r * W * 4;
    double w = b - a;
    if (w >= W) {
        memcpy(out, job->row_mean + (size_t)r * 4, 4 * sizeof(float));
        return;
    }
    double shift = floor(a / W) * W;
    a -= shift;
    b -= shift;
    if (w < 1e-6) {
        /* a point: plain linear interpolation */
        double x = 0.5 * (a + b) - 0.5, fl = floor(x);
        float f = (float)(x - fl);
        long i0 = (long)fl, i1 = i0 + 1;
        i0 = i0 < 0 ? i0 + W : i0 >= W ? i0 - W : i0;
        i1 = i1 >= W ? i1 - W : i1;
        const float *p = row + i0 * 4, *q = row + i1 * 4;
        for (int c = 0; c < 4; c++) out[c] = p[c] + (q[c] - p[c]) * f;
        return;
    }
    /* pixel i (centre i + 1/2) contributes T(b - c) - T(a - c); those entirely inside the
     * window contribute 1 */
    long lo = (long)floor(a - 0.5), hi = (long)floor(b + 0.5);
    long full_lo = (long)ceil(a + 0.5), full_hi = (long)floor(b - 1.5);
    if (full_lo > full_hi) {
        full_lo = hi + 1;
        full_hi = hi;
    }
    double acc[4] = {0, 0, 0, 0};
    for (long i = lo; i <= hi; i++) {
        if (i == full_lo) {
            float sum[4] = {0, 0, 0, 0};
            long j = full_lo >= W ? full_lo - W : full_lo;
            for (long n = full_lo; n <= full_hi; n++) {
                const float *p = row + j * 4;
                for (int c = 0; c < 4; c++) sum[c] += p[c];
                if (++j == W) j = 0;
            }
            for (int c = 0; c < 4; c++) acc[c] += sum[c];
            i = full_hi;
            continue;
        }
        double centre = i + 0.5;
        double wt = eq_tent_cdf(b - centre) - eq_tent_cdf(a - centre);
        if (wt <= 0.0) continue;
        long j = i < 0 ? i + W : i >= W ? i - W : i; /* a in [0, W), the window < W */
        const float *p = row + j * 4;
        for (int c = 0; c < 4; c++) acc[c] += wt * p[c];
    }
    for (int c = 0; c < 4; c++) out[c] = (float)(acc[c] / w);
}

/* Solid angle (in pixel-row units of the integral of sin(theta)) of the band [a, b] of rows:
 * the integral of sin(theta) over theta = pi a / H .. pi b / H, times H / pi. */
static inline double band_solid_angle(int H, double a, double b)
{
    return (H / IBL_PI) * (cos(IBL_PI * a / H) - cos(IBL_PI * b / H));
}

/* The share of window [py0, py1] given to row r: the integral over the window of the row's
 * reconstruction kernel times sin(theta). Away from the poles the kernel is the tent between
 * the row centres and sin(theta) is taken linear across the window (its curvature is
 * pi^2/H^2 per row), so the rows' shares add up to the window's solid angle and every row
 * hands out exactly its own. Near the poles (EQ_POLAR_BOX_ROWS) the kernel is the row's own
 * band instead: a tent folded at the pole gives its row about 1/24 of a row too much solid
 * angle (the kernel's first moment no longer matches the row's), a fixed error that is only
 * negligible against rows far from the pole; box rows are exact. The first tent row is flat
 * on its half next to the bands, so the kernels still sum to one everywhere. */
static double row_share(int H, long r, double py0, double py1, double c, double s_c, double s_d)
{
    long R = eq_polar_box_rows(H);
    if (r < R || r >= H - R) {
        double a = fmax(py0, (double)r), b = fmin(py1, (double)r + 1);
        return b > a ? band_solid_angle(H, a, b) : 0.0;
    }
    double lo = py0, hi = py1, flat = 0.0;
    if (r == R) {
        /* flat on [R, R + 1/2] */
        double a = fmax(py0, (double)R), b = fmin(py1, R + 0.5);
        if (b > a) flat = band_solid_angle(H, a, b);
        lo = fmax(lo, R + 0.5);
    } else if (r == H - R - 1) {
        double a = fmax(py0, H - R - 0.5), b = fmin(py1, (double)(H - R));
        if (b > a) flat = band_solid_angle(H, a, b);
        hi = fmin(hi, H - R - 0.5);
    }
    if (hi <= lo) return flat;
    double centre = r + 0.5;
    double t = eq_tent_cdf(hi - centre) - eq_tent_cdf(lo - centre);
    double mom = eq_tent_moment(hi - centre) - eq_tent_moment(lo - centre);
    return flat + t * (s_c + s_d * (centre - c)) + s_d * mom;
}

/* Mean of the reconstruction over the window [px0, px1] x [py0, py1] (pixel units). Rows past
 * a pole continue on the opposite meridian (row -1 is row 0 turned by half a revolution). */
void ibl__eq_window_mean(const eq_job *job, double px0, double px1, double py0, double py1,
                         double sin_t, double cos_t, float out[4])
{
    int W = job->im->width, H = job->im->height;
    /* sin(theta) and its slope at the window's centre (given by the caller, who has them) */
    double k_rad = IBL_PI / H, c = 0.5 * (py0 + py1);
    double s_c = sin_t, s_d = k_rad * cos_t;
    /* a window reaching past a pole is cut there: the far side is already covered by the
     * neighbouring cells across the pole, and counting it twice would add energy */
    if (py0 < 0.0) py0 = 0.0;
    if (py1 > H) py1 = H;
    if (py1 < py0) py1 = py0;
    double h = py1 - py0;
    double acc[4] = {0, 0, 0, 0}, wsum = 0;
    double c_cut = 0.5 * (py0 + py1);
    s_c += s_d * (c_cut - c); /* the cut moved the centre */
    c = c_cut;
    long lo = (long)floor(py0 - 0.5), hi = (long)floor(py1 + 0.5);
    if (h < 1e-6) {
        /* a point in latitude: the two rows around it */
        double y = 0.5 * (py0 + py1) - 0.5;
        lo = (long)floor(y);
        hi = lo + 1;
    }
    /* narrow windows (the common case): the longitude weights once for all rows */
    enum { MAX_TAPS = 12 };
    long taps_at[MAX_TAPS];
    float taps_w[MAX_TAPS];
    int taps = -1;
    if (h >= 1e-6 && px1 - px0 >= 1e-6 && px1 - px0 < MAX_TAPS - 3) {
        double a = px0 - floor(px0 / W) * W, b = a + (px1 - px0), inv_w = 1.0 / (px1 - px0);
        long first = (long)floor(a - 0.5), last = (long)floor(b + 0.5);
        taps = 0;
        for (long i = first; i <= last; i++) {
            double centre = i + 0.5;
            double wt = eq_tent_cdf(b - centre) - eq_tent_cdf(a - centre);
            if (wt <= 0.0) continue;
            taps_at[taps] = (i < 0 ? i + W : i >= W ? i - W : i) * 4;
            taps_w[taps++] = (float)(wt * inv_w);
        }
    }
    for (long r = lo; r <= hi; r++) {
        double wt;
        if (h < 1e-6) {
            double y = 0.5 * (py0 + py1) - 0.5;
            wt = r == lo ? 1.0 - (y - lo) : y - lo;
        } else {
            if (r < 0 || r >= H) continue;
            wt = row_share(H, r, py0, py1, c, s_c, s_d);
        }
        if (wt <= 0.0) continue;
        long rr = r;
        double shift = 0.0;
        if (rr < 0) {
            rr = -1 - rr;
            shift = 0.5 * W;
        } else if (rr >= H) {
            rr = 2L * H - 1 - rr;
            shift = 0.5 * W;
        }
        if (rr < 0) rr = 0; /* only for images a pixel or two high */
        if (rr >= H) rr = H - 1;
        float v[4];
        if (taps >= 0 && shift == 0.0) {
            const float *row = job->im->pixels + (size_t)rr * W * 4;
            v[0] = v[1] = v[2] = v[3] = 0.0f;
            for (int t = 0; t < taps; t++) {
                const float *p = row + taps_at[t];
                float tw = taps_w[t];
                v[0] += tw * p[0];
                v[1] += tw * p[1];
                v[2] += tw * p[2];
                v[3] += tw * p[3];
            }
        } else {
            row_window_mean(job, (int)rr, px0 + shift, px1 + shift, v);
        }
        for (int c = 0; c < 4; c++) acc[c] += wt * v[c];
        wsum += wt;
    }
    double inv = 1.0 / wsum;
    for (int c = 0; c < 4; c++) out[c] = (float)(acc[c] * inv);
}
