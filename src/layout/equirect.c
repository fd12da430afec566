/* Equirectangular (latitude-longitude) images.
 *
 * Mapping (docs/CONVENTIONS.md): u in [0, 1] left to right, v in [0, 1] top to bottom,
 *   phi = 2 pi (u - 1/2), theta = pi v (angle from +Y),
 *   d = (sin theta sin phi, cos theta, -sin theta cos phi):
 * the centre column looks toward -Z, u = 3/4 toward +X, u = 0 and 1 toward +Z, the top row is +Y.
 *
 * To a cube. The source is reconstructed by linear interpolation between pixel centres
 * (wrapping in longitude); near the poles the rows are constant bands instead (row_share
 * explains why). Each cube texel is the solid-angle-weighted mean of k x k sample cells on its
 * face-plane footprint (weights dA / |d|^3). k follows the texel's extent in source rows and
 * columns (SAMPLES_PER_ROW / _COLUMN per pixel crossed), and every pixel is reached anyway
 * because the samples' windows (below) cover the texel.
 * Each sample does not read a point but the mean of the reconstruction over its cell's
 * longitude/latitude extent, weighted by solid angle: where the cells line up with the
 * meridians these windows tile the sphere, so a small bright source keeps its energy exactly
 * wherever it falls, and a texel much larger than a pixel is a true area average (no
 * aliasing). Within a few texels of each pole, where texels turn against the meridians and
 * such windows would overlap, the texel integrates the constant source pixels directly
 * instead (eq_texel_near_pole). Measured accuracy of the energy of a 3x3-pixel sun: tests/test_layout.c
 * and docs/CONVENTIONS.md. */
#include "layout_internal.h"

#include <math.h>
#include <string.h>

/* Samples per axis: this many per source row / column the texel spans (at least 1). */
static const double SAMPLES_PER_ROW = 0.6;
static const double SAMPLES_PER_COLUMN = 0.6;
/* The polar region handled by direct integration: at least 3 texels and this many rows. */
static const double POLE_ROWS = 4.0;
/* Cells per texel there (their solid angle is a texel's / POLE_CELLS). */
static const double POLE_CELLS = 4096.0;
static const double PI = 3.14159265358979323846;

/* The batch loop below (batch_flush) vectorises once sqrt may skip errno (its arguments are
 * sums of squares) and selects may evaluate both sides (no floating-point traps are used). */
#if defined(__GNUC__) && !defined(__clang__)
#define NO_ERRNO __attribute__((optimize("no-math-errno", "no-trapping-math")))
#else
#define NO_ERRNO
#endif

/* atan on [0, 1]: Abramowitz & Stegun 4.4.49 (|error| <= 2e-8 rad, far below any pixel). */
NO_ERRNO static inline double atan01(double x)
{
    double x2 = x * x;
    return x * (1.0 + x2 * (-0.3333314528 + x2 * (0.1999355085 + x2 * (-0.1420889944 +
           x2 * (0.1065626393 + x2 * (-0.0752896400 + x2 * (0.0429096138 +
           x2 * (-0.0161657367 + x2 * 0.0028662257))))))));
}

int ibl__equirect_dir(double u, double v, double d[3])
{
    double phi = 2.0 * PI * (u - 0.5), theta = PI * v;
    double st = sin(theta);
    d[0] = st * sin(phi);
    d[1] = cos(theta);
    d[2] = -st * cos(phi);
    return 1;
}

void ibl__equirect_uv(const double d[3], double *u, double *v)
{
    double rho = sqrt(d[0] * d[0] + d[2] * d[2]);
    *u = atan2(d[0], -d[2]) / (2.0 * PI) + 0.5;
    *v = atan2(rho, d[1]) / PI;
}

typedef struct eq_job {
    const ibl_image *im;
    double basis[6][3][3]; /* per face: major, s axis, t axis, in the picture frame */
    double world[3][3];    /* world = world * picture */
    double pole_cell_area; /* solid angle of the cells near the poles (about 1/POLE_CELLS texel) */
    double pole_radius2;   /* sin^2 of the polar region's angular radius */
    const float *row_mean; /* height x 4 */
    ibl_cubemap *out;
    int fixed_k;
} eq_job;

/* Antiderivative of the unit tent max(0, 1 - |t|). */
static inline double tent_cdf(double t)
{
    if (t <= -1.0) return 0.0;
    if (t <= 0.0) return 0.5 * (t + 1.0) * (t + 1.0);
    if (t < 1.0) return 1.0 - 0.5 * (1.0 - t) * (1.0 - t);
    return 1.0;
}

/* Mean over the column window [a, b] (pixel i covers [i, i+1)) of the linear interpolant of
 * row r through its pixel centres, wrapping in longitude. Windows that tile the row add up to
 * exactly the sum of its pixels, so energy is kept however the windows fall. */
static void row_window(const eq_job *job, int r, double a, double b, float out[4])
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
        double wt = tent_cdf(b - centre) - tent_cdf(a - centre);
        if (wt <= 0.0) continue;
        long j = i < 0 ? i + W : i >= W ? i - W : i; /* a in [0, W), the window < W */
        const float *p = row + j * 4;
        for (int c = 0; c < 4; c++) acc[c] += wt * p[c];
    }
    for (int c = 0; c < 4; c++) out[c] = (float)(acc[c] / w);
}

/* First moment of the unit tent: integral of s max(0, 1 - |s|) from -1 to t. */
static inline double tent_moment(double t)
{
    if (t <= -1.0 || t >= 1.0) return 0.0;
    if (t <= 0.0) return t * t * (0.5 + t / 3.0) - 1.0 / 6.0;
    return t * t * (0.5 - t / 3.0) - 1.0 / 6.0;
}

/* Rows this close to a pole are reconstructed as constant bands instead of being interpolated:
 * a tent folded at the pole gives its row about 1/24 of a row too much solid angle (the
 * kernel's first moment no longer matches the row's), and the error, a fixed amount, is only
 * negligible against rows far from the pole. Box rows are exact. */
enum { POLAR_BOX_ROWS = 12 };

/* Solid angle (in pixel-row units of the integral of sin(theta)) of band [a, b]. */
static inline double band(int H, double a, double b)
{
    return (H / PI) * (cos(PI * a / H) - cos(PI * b / H));
}

/* The share of window [py0, py1] given to row r: the integral over the window of the row's
 * reconstruction kernel times sin(theta). Away from the poles the kernel is the tent between
 * the row centres and sin(theta) is taken linear across the window (its curvature is
 * pi^2/H^2 per row), so the rows' shares add up to the window's solid angle and every row
 * hands out exactly its own. Near the poles the kernel is the row's own band; the first tent
 * row is flat on its half next to the bands, so the kernels still sum to one everywhere. */
static double row_share(int H, long r, double py0, double py1, double c, double s_c, double s_d)
{
    long R = POLAR_BOX_ROWS < H / 4 ? POLAR_BOX_ROWS : H / 4;
    if (r < R || r >= H - R) {
        double a = fmax(py0, (double)r), b = fmin(py1, (double)r + 1);
        return b > a ? band(H, a, b) : 0.0;
    }
    double lo = py0, hi = py1, flat = 0.0;
    if (r == R) {
        /* flat on [R, R + 1/2] */
        double a = fmax(py0, (double)R), b = fmin(py1, R + 0.5);
        if (b > a) flat = band(H, a, b);
        lo = fmax(lo, R + 0.5);
    } else if (r == H - R - 1) {
        double a = fmax(py0, H - R - 0.5), b = fmin(py1, (double)(H - R));
        if (b > a) flat = band(H, a, b);
        hi = fmin(hi, H - R - 0.5);
    }
    if (hi <= lo) return flat;
    double centre = r + 0.5;
    double t = tent_cdf(hi - centre) - tent_cdf(lo - centre);
    double mom = tent_moment(hi - centre) - tent_moment(lo - centre);
    return flat + t * (s_c + s_d * (centre - c)) + s_d * mom;
}

/* The unit tent's antiderivative and first moment (tent_cdf, tent_moment) without branches,
 * for arguments clamped to [-1, 1]: T(t) = 1/2 + t - t|t|/2, M(t) = t^2 (1/2 - |t|/3) - 1/6. */
NO_ERRNO static inline double clamp1(double t)
{
    t = t < -1.0 ? -1.0 : t;
    return t > 1.0 ? 1.0 : t;
}
NO_ERRNO static inline double tent_cdf_c(double t)
{
    t = clamp1(t);
    return 0.5 + t - 0.5 * t * fabs(t);
}
NO_ERRNO static inline double tent_moment_c(double t)
{
    t = clamp1(t);
    return t * t * (0.5 - fabs(t) * (1.0 / 3.0)) - 1.0 / 6.0;
}

/* Mean of the bilinear interpolant of the picture over the window [px0, px1] x [py0, py1]
 * (pixel units). Rows past a pole continue on the opposite meridian (row -1 is row 0 turned
 * by half a revolution). */
static void window_value(const eq_job *job, double px0, double px1, double py0, double py1,
                         double sin_t, double cos_t, float out[4])
{
    int W = job->im->width, H = job->im->height;
    /* sin(theta) and its slope at the window's centre (given by the caller, who has them) */
    double k_rad = PI / H, c = 0.5 * (py0 + py1);
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
    /* (windows at most two pixels wide and tall take the 4 x 4 taps of batch_flush) */
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
            double wt = tent_cdf(b - centre) - tent_cdf(a - centre);
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
            row_window(job, (int)rr, px0 + shift, px1 + shift, v);
        }
        for (int c = 0; c < 4; c++) acc[c] += wt * v[c];
        wsum += wt;
    }
    double inv = 1.0 / wsum;
    for (int c = 0; c < 4; c++) out[c] = (float)(acc[c] * inv);
}

static double wrap_angle(double a)
{
    if (a > PI) a -= 2.0 * PI;
    else if (a < -PI) a += 2.0 * PI;
    return a;
}

/* Is the picture-frame direction p inside texel (tx, ty) of the face with axes m, a, b? */
static inline int in_texel(const double *m, const double *a, const double *b, double half,
                           int tx, int ty, double px, double py, double pz)
{
    double pm = m[0] * px + m[1] * py + m[2] * pz;
    if (!(pm > 0.0)) return 0;
    double inv = half / pm;
    double fx = (a[0] * px + a[1] * py + a[2] * pz) * inv + half;
    double fy = (b[0] * px + b[1] * py + b[2] * pz) * inv + half;
    return fx >= tx && fx < tx + 1 && fy >= ty && fy < ty + 1;
}

/* Texels within a few cells of a pole. There theta and phi are far from linear across a
 * texel and the sample cells, turned against the meridians, cannot be matched by
 * longitude/latitude windows. Instead the texel integrates the source pixels directly, each
 * with its exact solid angle: pixels whose four corners are in the texel count whole, pixels
 * the texel's edge crosses are cut into 16 x 16 cells counted by their centres, and the
 * texel's value is the solid-angle-weighted mean. */
static void eq_texel_near_pole(const eq_job *job, int face, int tx, int ty, float *out)
{
    int N = job->out->size, W = job->im->width, H = job->im->height;
    const double *m = job->basis[face][0], *a = job->basis[face][1], *b = job->basis[face][2];
    const double cell = 2.0 / N;
    /* longitude / latitude range of the texel from its corners and edge midpoints */
    double sc0 = -1.0 + (tx + 0.5) * cell, tc0 = -1.0 + (ty + 0.5) * cell;
    double cx = m[0] + sc0 * a[0] + tc0 * b[0], cy = m[1] + sc0 * a[1] + tc0 * b[1],
           cz = m[2] + sc0 * a[2] + tc0 * b[2];
    double centre = atan2(cx, -cz), lo = 0, hi = 0, ylo = H, yhi = 0, winding = 0, prev = 0;
    int any_pole = 0;
    static const double ring[9][2] = {{0, 0}, {0.5, 0}, {1, 0}, {1, 0.5}, {1, 1},
                                      {0.5, 1}, {0, 1}, {0, 0.5}, {0, 0}};
    for (int c = 0; c < 9; c++) {
        double sc = -1.0 + (tx + ring[c][0]) * cell, tc = -1.0 + (ty + ring[c][1]) * cell;
        double x = m[0] + sc * a[0] + tc * b[0], y = m[1] + sc * a[1] + tc * b[1],
               z = m[2] + sc * a[2] + tc * b[2];
        double rho = sqrt(x * x + z * z), py = atan2(rho, y) / PI * H;
        ylo = fmin(ylo, py);
        yhi = fmax(yhi, py);
        if (rho <= 1e-12 * fabs(y)) {
            any_pole = 1;
            continue;
        }
        double phi = atan2(x, -z), rel = wrap_angle(phi - centre);
        lo = fmin(lo, rel);
        hi = fmax(hi, rel);
        if (c > 0) winding += wrap_angle(phi - prev);
        prev = phi;
    }
    int full = any_pole || fabs(winding) > PI;
    /* a texel only a few pixels across can lie between pixel corners: then every pixel of its
     * range is cut into cells, not only those its edges visibly cross */
    int thin = yhi - ylo < 4.0 || (!full && (hi - lo) / (2.0 * PI) * W < 4.0);
    /* the closest approach to the pole can lie inside an edge: widen by a row */
    ylo = fmax(0.0, floor(ylo) - 1.0);
    yhi = fmin((double)H, ceil(yhi) + 1.0);
    if (full) {
        if (cy > 0) ylo = 0;
        else yhi = H;
    }
    long c0 = 0, c1 = W;
    if (!full) {
        c0 = (long)floor(((centre + lo) / (2.0 * PI) + 0.5) * W) - 1;
        c1 = (long)ceil(((centre + hi) / (2.0 * PI) + 0.5) * W) + 1;
        if (c1 - c0 > W) {
            c0 = 0;
            c1 = W;
        }
    }
    int r0 = (int)ylo, r1 = (int)yhi;
    double acc[4] = {0, 0, 0, 0}, wsum = 0;
    const double half = 0.5 * N;
    const double dphi = 2.0 * PI / W;
    const double cd = cos(dphi), sd = sin(dphi);
    const double phi_start = 2.0 * PI * ((double)c0 / W - 0.5);
    const double cos_start = cos(phi_start), sin_start = sin(phi_start);
    /* crossed pixels are cut into FINE rows of cells, each row into cells about as wide as
     * tall (a pixel near the pole is a thin wedge: sin(theta) dphi << dtheta) */
    enum { FINE = 16 };
    for (int r = r0; r < r1; r++) {
        const float *row = job->im->pixels + (size_t)r * W * 4;
        double th0 = PI * r / H, th1 = PI * (r + 1) / H;
        double st0 = sin(th0), ct0 = cos(th0), st1 = sin(th1), ct1 = cos(th1);
        double w_pixel = (ct0 - ct1) * dphi;
        double wedge = fmax(st0, st1) * dphi / (th1 - th0) * FINE;
        int nlon = wedge >= FINE ? FINE : (int)ceil(wedge);
        if (nlon < 1) nlon = 1;
        const double fine_d = dphi / nlon, fcd = cos(fine_d), fsd = sin(fine_d);
        const double hc = cos(0.5 * fine_d), hs = sin(0.5 * fine_d);
        /* the cells of a crossed pixel: their rows' sin, cos and solid angle */
        double sub_st[FINE], sub_ct[FINE], sub_w[FINE];
        for (int j = 0; j < FINE; j++) {
            double ta = th0 + (th1 - th0) * j / FINE, tb = th0 + (th1 - th0) * (j + 1) / FINE;
            double tm = 0.5 * (ta + tb);
            sub_st[j] = sin(tm);
            sub_ct[j] = cos(tm);
            sub_w[j] = (cos(ta) - cos(tb)) * fine_d;
        }
        /* pixel corners along this row's top and bottom edges */
        double cp = cos_start, sp = sin_start;
        int top = in_texel(m, a, b, half, tx, ty, st0 * sp, ct0, -st0 * cp);
        int bottom = in_texel(m, a, b, half, tx, ty, st1 * sp, ct1, -st1 * cp);
        long wc = c0 % W;
        if (wc < 0) wc += W;
        for (long col = c0; col < c1; col++) {
            double ncp = cp * cd - sp * sd, nsp = sp * cd + cp * sd;
            int top2 = in_texel(m, a, b, half, tx, ty, st0 * nsp, ct0, -st0 * ncp);
            int bottom2 = in_texel(m, a, b, half, tx, ty, st1 * nsp, ct1, -st1 * ncp);
            int inside = top + bottom + top2 + bottom2;
            const float *p = row + wc * 4;
            if (inside == 4) {
                for (int c = 0; c < 4; c++) acc[c] += w_pixel * p[c];
                wsum += w_pixel;
            } else if (inside > 0 || thin) {
                /* the texel's edge crosses this pixel: count its cells by centre */
                double share = 0.0;
                for (int j = 0; j < FINE; j++) {
                    double st = sub_st[j], ct = sub_ct[j], wcell = sub_w[j];
                    double fc = cp * hc - sp * hs, fs = sp * hc + cp * hs;
                    for (int i = 0; i < nlon; i++) {
                        if (in_texel(m, a, b, half, tx, ty, st * fs, ct, -st * fc)) share += wcell;
                        double t = fc * fcd - fs * fsd;
                        fs = fs * fcd + fc * fsd;
                        fc = t;
                    }
                }
                for (int c = 0; c < 4; c++) acc[c] += share * p[c];
                wsum += share;
            }
            cp = ncp;
            sp = nsp;
            top = top2;
            bottom = bottom2;
            if (++wc == W) wc = 0;
        }
    }
    if (wsum > 0.0) {
        for (int c = 0; c < 4; c++) out[c] = (float)(acc[c] / wsum);
    } else {
        /* a texel smaller than any cell: the picture at its centre */
        double py = atan2(sqrt(cx * cx + cz * cz), cy) / PI * H;
        double px = (centre / (2.0 * PI) + 0.5) * W;
        window_value(job, px, px, py, py, 0.0, 1.0, out);
    }
}

/* atan2 from atan01, without branches so that a loop of them vectorises */
NO_ERRNO static inline double atan2_nb(double y, double x)
{
    double ax = fabs(x), ay = fabs(y);
    double mn = ax < ay ? ax : ay, mx = ax < ay ? ay : ax;
    double r = atan01(mn / (mx > 0.0 ? mx : 1.0));
    r = ay > ax ? 0.5 * PI - r : r;
    r = x < 0.0 ? PI - r : r;
    return y < 0.0 ? -r : r;
}

/* Samples are gathered in batches over a texel row: first every sample's window in one loop
 * without branches (it vectorises), then the windows' values, summed per texel in order. */
enum { BATCH = 128 };
typedef struct eq_batch {
    int n;
    int texel[BATCH];
    double sc[BATCH], tc[BATCH], sub[BATCH];
    double px[BATCH], py[BATCH], wpx[BATCH], hpx[BATCH], st[BATCH], ct[BATCH], wt[BATCH];
    double t0[BATCH], t1[BATCH], t2[BATCH], t3[BATCH], t4[BATCH]; /* scratch */
    /* the windows: kind (0: general, window_value), first row, 4 x 4 taps */
    int kind[BATCH], row[BATCH], rows[BATCH], col[4][BATCH];
    float wx[4][BATCH], wy[4][BATCH];
    /* the running sum of the texel being summed (its samples can span two batches) */
    int cur;
    double acc[4], wsum;
} eq_batch;

static void batch_emit(eq_batch *bt, float *out)
{
    if (bt->cur >= 0)
        for (int c = 0; c < 4; c++) out[(size_t)bt->cur * 4 + c] = (float)(bt->acc[c] / bt->wsum);
    bt->cur = -1;
}

NO_ERRNO static void batch_flush(const eq_job *job, int face, eq_batch *bt, float *out)
{
    int W = job->im->width, H = job->im->height, n = bt->n;
    const double *m = job->basis[face][0], *a = job->basis[face][1], *b = job->basis[face][2];
    const double px_per_rad_u = W / (2.0 * PI), px_per_rad_v = H / PI;
    double *x = bt->t0, *y = bt->t1, *z = bt->t2, *rho = bt->t3, *len = bt->t4;
    for (int i = 0; i < n; i++) {
        double sc = bt->sc[i], tc = bt->tc[i];
        x[i] = m[0] + tc * b[0] + sc * a[0];
        y[i] = m[1] + tc * b[1] + sc * a[1];
        z[i] = m[2] + tc * b[2] + sc * a[2];
    }
    /* (sqrt keeps this loop scalar: it may set errno) */
    for (int i = 0; i < n; i++) {
        double rho2 = x[i] * x[i] + z[i] * z[i];
        rho[i] = sqrt(rho2);
        len[i] = sqrt(rho2 + y[i] * y[i]);
    }
    for (int i = 0; i < n; i++) {
        double xi = x[i], yi = y[i], zi = z[i], sub = bt->sub[i];
        double rho2 = xi * xi + zi * zi;
        double inv_len = 1.0 / len[i], inv_len2 = inv_len * inv_len;
        bt->wt[i] = inv_len2 * inv_len;
        bt->px[i] = (atan2_nb(xi, -zi) * (0.5 / PI) + 0.5) * W;
        bt->py[i] = atan2_nb(rho[i], yi) * (H / PI);
        /* extents of this sample's cell in longitude and latitude (pixels): the gradients of
         * phi and theta along both face axes, times the cell size */
        double g1 = fabs(yi * (xi * a[0] + zi * a[2]) - rho2 * a[1]);
        double g2 = fabs(yi * (xi * b[0] + zi * b[2]) - rho2 * b[1]);
        double ga = fabs(xi * a[2] - zi * a[0]), gb = fabs(xi * b[2] - zi * b[0]);
        double safe_rho2 = rho2 > 1e-300 ? rho2 : 1.0; /* on the axis: whole rows */
        double inv_rho2 = 1.0 / safe_rho2;
        double wpx = (ga + gb) * inv_rho2 * sub * px_per_rad_u;
        wpx = wpx < W ? wpx : (double)W;
        bt->wpx[i] = rho2 > 1e-300 ? wpx : (double)W;
        double hpx_axis = 2.0 * inv_len * sub * px_per_rad_v;
        double hpx = (g1 + g2) * rho[i] * inv_rho2 * inv_len2 * sub * px_per_rad_v;
        bt->hpx[i] = rho2 > 1e-300 ? hpx : hpx_axis;
        bt->st[i] = rho[i] * inv_len;
        bt->ct[i] = yi * inv_len;
    }
    /* The windows (as window_value): the 4 x 4 tap weights of the narrow ones, tent rows
     * (narrow_window) or polar bands (polar_narrow_window); kind 0 takes window_value. */
    const long R = POLAR_BOX_ROWS < H / 4 ? POLAR_BOX_ROWS : H / 4;
    const double k_rad = PI / H;
    const int narrow_ok = W >= 8, polar_ok = W >= 8 && H >= 64;
    for (int i = 0; i < n; i++) {
        double hw = 0.5 * bt->wpx[i], hh = 0.5 * bt->hpx[i];
        double px0 = bt->px[i] - hw, w = 2.0 * hw, c = bt->py[i];
        double py0 = c - hh, py1 = c + hh, h_orig = 2.0 * hh;
        double sin_t = bt->st[i], cos_t = bt->ct[i];
        py0 = py0 < 0.0 ? 0.0 : py0;
        py1 = py1 > H ? (double)H : py1;
        py1 = py1 < py0 ? py0 : py1;
        double h = py1 - py0, s_d = k_rad * cos_t;
        double s_c = sin_t + s_d * (0.5 * (py0 + py1) - c);
        int ok = (h >= 1e-6) & (h <= 2.0) & (w >= 1e-6) & (w <= 2.0);
        int tent = narrow_ok & ok & (py0 - 0.5 >= R + 1) & (py1 + 0.5 <= H - R - 1);
        int polar = polar_ok & ok & !tent & ((py1 <= R) | (py0 >= H - R)) & (h_orig <= 2.0);
        bt->kind[i] = tent ? 1 : polar ? 2 : 0;
        /* longitude: the first column whose tent reaches the window, then four */
        double wa = px0 < 0.0 ? px0 + W : px0 >= W ? px0 - W : px0;
        wa = wa < 0.0 ? 0.0 : wa > W ? (double)W : wa; /* only windows of kind 0 move */
        int i0 = (int)(wa + 0.5) - 1;                   /* floor(wa - 1/2) */
        /* da in [0, 1): T(da - k) is T(da), da^2 / 2, 0, 0 */
        double da = wa - (i0 + 0.5), e = da + w, inv_w = 1.0 / (ok ? w : 1.0);
        double lower[4] = {0.5 + da - 0.5 * da * da, 0.5 * da * da, 0.0, 0.0};
        for (int k = 0; k < 4; k++) {
            bt->wx[k][i] = (float)((tent_cdf_c(e - k) - lower[k]) * inv_w);
            int col = i0 + k;
            col = col < 0 ? col + W : col >= W ? col - W : col;
            bt->col[k][i] = col;
        }
        double share[4], sum = 0.0;
        if (tent) {
            /* tent rows: row j0 + k has centre py0 - dy + k, dy in [0, 1) */
            int jt = (int)(py0 + 0.5) - 1; /* floor(py0 - 1/2) */
            double dy = py0 - (jt + 0.5), ey = dy + h, dm = dy - 1.0;
            double t_lo[2] = {0.5 + dy - 0.5 * dy * dy, 0.5 * dy * dy};
            double m_lo[2] = {dy * dy * (0.5 - dy * (1.0 / 3.0)) - 1.0 / 6.0,
                              dm * dm * (0.5 + dm * (1.0 / 3.0)) - 1.0 / 6.0};
            for (int k = 0; k < 4; k++) {
                double t = tent_cdf_c(ey - k) - (k < 2 ? t_lo[k] : 0.0);
                double mom = tent_moment_c(ey - k) - (k < 2 ? m_lo[k] : 0.0);
                share[k] = t * (s_c + s_d * (k - dy - 0.5 * h)) + s_d * mom;
            }
            bt->row[i] = jt;
            bt->rows[i] = ey > 2.0 ? 4 : ey > 1.0 ? 3 : 2;
        } else {
            /* polar bands: row jp + k covers [jp + k, jp + k + 1]; cos(theta) at the cuts
             * from its value at the centre (polar_narrow_window) */
            int jp = (int)py0;
            double cth[4], at[4] = {py0, jp + 1.0, jp + 2.0, py1};
            for (int k = 0; k < 4; k++) {
                double d = (at[k] - c) * k_rad, d2 = d * d;
                double cd = 1.0 - d2 * (0.5 - d2 * (1.0 / 24 - d2 * (1.0 / 720)));
                double sd = d * (1.0 - d2 * (1.0 / 6 - d2 * (1.0 / 120 - d2 * (1.0 / 5040))));
                cth[k] = cos_t * cd - sin_t * sd;
            }
            share[0] = cth[0] - (py1 < jp + 1.0 ? cth[3] : cth[1]);
            share[1] = py1 > jp + 1.0 ? cth[1] - (py1 < jp + 2.0 ? cth[3] : cth[2]) : 0.0;
            share[2] = py1 > jp + 2.0 ? cth[2] - cth[3] : 0.0;
            share[3] = 0.0;
            /* cos falls with the row: a share is positive, but for rounding */
            for (int k = 0; k < 3; k++) share[k] = share[k] > 0.0 ? share[k] : 0.0;
            bt->row[i] = jp;
            bt->rows[i] = 3;
        }
        for (int k = 0; k < 4; k++) sum += share[k];
        double inv = 1.0 / (sum > 0.0 ? sum : 1.0);
        for (int k = 0; k < 4; k++) bt->wy[k][i] = (float)(share[k] * inv);
    }
    const float *pix = job->im->pixels;
    for (int i = 0; i < n; i++) {
        if (bt->texel[i] != bt->cur) {
            batch_emit(bt, out);
            bt->cur = bt->texel[i];
            bt->acc[0] = bt->acc[1] = bt->acc[2] = bt->acc[3] = bt->wsum = 0.0;
        }
        float val[4] = {0, 0, 0, 0};
        if (bt->kind[i]) {
            for (int k = 0; k < bt->rows[i]; k++) {
                long r = bt->row[i] + k < H ? bt->row[i] + k : H - 1; /* past the window: 0 */
                const float *rowp = pix + (size_t)r * W * 4;
                float wy = bt->wy[k][i], v[4] = {0, 0, 0, 0};
                for (int t = 0; t < 4; t++) {
                    const float *p = rowp + (size_t)bt->col[t][i] * 4;
                    float wx = bt->wx[t][i];
                    for (int ch = 0; ch < 4; ch++) v[ch] += wx * p[ch];
                }
                for (int ch = 0; ch < 4; ch++) val[ch] += wy * v[ch];
            }
        } else {
            double px = bt->px[i], py = bt->py[i], hw = 0.5 * bt->wpx[i], hh = 0.5 * bt->hpx[i];
            window_value(job, px - hw, px + hw, py - hh, py + hh, bt->st[i], bt->ct[i], val);
        }
        double wt = bt->wt[i];
        for (int c = 0; c < 4; c++) bt->acc[c] += wt * val[c];
        bt->wsum += wt;
    }
    bt->n = 0;
}

static void eq_row_task(void *arg, int index)
{
    const eq_job *job = arg;
    int N = job->out->size, face = index / N, ty = index % N;
    int W = job->im->width, H = job->im->height;
    const double *m = job->basis[face][0], *a = job->basis[face][1], *b = job->basis[face][2];
    float *out = ibl_cubemap_face(job->out, 0, face) + (size_t)ty * N * 4;
    const double cell = 2.0 / N;            /* texel edge on the face plane */
    const double px_per_rad_u = W / (2.0 * PI), px_per_rad_v = H / PI;
    eq_batch bt;
    bt.n = 0;
    bt.cur = -1;

    for (int tx = 0; tx < N; tx++) {
        int k = job->fixed_k;
        double sc = -1.0 + (tx + 0.5) * cell, tc = -1.0 + (ty + 0.5) * cell;
        double d[3] = {m[0] + sc * a[0] + tc * b[0], m[1] + sc * a[1] + tc * b[1],
                       m[2] + sc * a[2] + tc * b[2]};
        double rho2 = d[0] * d[0] + d[2] * d[2], r2 = rho2 + d[1] * d[1];
        if (k == 0 && rho2 < job->pole_radius2 * r2) {
            eq_texel_near_pole(job, face, tx, ty, out + (size_t)tx * 4);
            continue;
        }
        if (k == 0) {
            /* latitude extent of the texel in source rows, from the gradient of theta */
            double rho = sqrt(rho2), len = sqrt(r2), ext;
            if (rho < 2.0 * cell * len) {
                /* at a pole theta is a cone: bound its change by the full gradient 1/|d| */
                ext = 2.0 / len;
            } else {
                double g[3] = {d[1] * d[0] / rho / r2, -rho / r2, d[1] * d[2] / rho / r2};
                ext = fabs(g[0] * a[0] + g[1] * a[1] + g[2] * a[2]) +
                      fabs(g[0] * b[0] + g[1] * b[1] + g[2] * b[2]);
            }
            double rows = ext * cell * px_per_rad_v;
            /* and its longitude extent in source columns */
            double cols = (fabs(d[0] * a[2] - d[2] * a[0]) + fabs(d[0] * b[2] - d[2] * b[0])) /
                          rho2 * cell * px_per_rad_u;
            k = (int)ceil(fmax(SAMPLES_PER_ROW * rows, SAMPLES_PER_COLUMN * cols));
            if (k < 1) k = 1;
            if (k > 64) k = 64;
        }
        const double sub = cell / k;
        for (int j = 0; j < k; j++) {
            double tcj = -1.0 + ty * cell + (j + 0.5) * sub;
            for (int i = 0; i < k; i++) {
                if (bt.n == BATCH) batch_flush(job, face, &bt, out);
                bt.texel[bt.n] = tx;
                bt.sc[bt.n] = -1.0 + tx * cell + (i + 0.5) * sub;
                bt.tc[bt.n] = tcj;
                bt.sub[bt.n] = sub;
                bt.n++;
            }
        }
    }
    if (bt.n) batch_flush(job, face, &bt, out);
    batch_emit(&bt, out);
}

ibl_status ibl__equirect_to_cube(ibl_context *ctx, const ibl_image *image, const ibl__frame *frame,
                                 int samples_per_axis, ibl_cubemap *out)
{
    int W = image->width, H = image->height;
    float *mean = ibl_alloc(ctx, (size_t)H * 4 * sizeof(float));
    if (!mean) return ibl_context_status(ctx);
    for (int r = 0; r < H; r++) {
        double s[4] = {0, 0, 0, 0};
        const float *p = image->pixels + (size_t)r * W * 4;
        for (int x = 0; x < W; x++)
            for (int c = 0; c < 4; c++) s[c] += p[(size_t)x * 4 + c];
        for (int c = 0; c < 4; c++) mean[(size_t)r * 4 + c] = (float)(s[c] / W);
    }
    eq_job job;
    memset(&job, 0, sizeof job);
    job.im = image;
    job.row_mean = mean;
    job.out = out;
    job.fixed_k = samples_per_axis;
    memcpy(job.world, frame->m, sizeof job.world);
    {
        /* The polar region: 3 texels, and at least POLE_ROWS source rows. */
        int N = out->size;
        double cell = 2.0 / N;
        double radius = fmin(fmax(atan(3.0 * cell), POLE_ROWS * PI / H), 0.5 * PI);
        job.pole_radius2 = sin(radius) * sin(radius);
        /* How finely the pixels are cut there: cells of about 1/POLE_CELLS of a texel. */
        job.pole_cell_area = cell * cell / POLE_CELLS;
    }
    ibl__picture_basis(frame, job.basis);
    ibl_parallel_for(ctx, 6 * out->size, eq_row_task, &job);
    ibl_free(ctx, mean);
    return IBL_OK;
}
