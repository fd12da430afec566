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
 * instead (eq_texel_near_pole). Around that region, on the faces centred on a pole, texels
 * spanning many source columns would need k^2 thin windows; they take one window per source
 * column crossing them instead (polar_columns), which tile the sphere exactly as well.
 * Measured accuracy of the energy of a 3x3-pixel sun, and of texels against a brute-force
 * footprint integral: tests/test_layout.c and docs/CONVENTIONS.md.
 *
 * Speed (docs/PERFORMANCE.md, "Equirect to cube"): the samples of a texel row are handled in
 * batches. Windows at most two pixels wide and tall, which is nearly all of them, take the
 * fast path (equirect_lanes.h): directions, longitudes, latitudes and the weights of fixed
 * 4 x 4 taps in float vectors without branches (4 lanes, or 8 with AVX2 where the CPU has it:
 * the same bits), then the taps, two columns to a vector. The rest (windows under 1/16 pixel,
 * or wider than two) are computed in double (slow_values; the widest by window_value). */
#include "layout_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

/* Samples per axis: this many per source row / column the texel spans (at least 1). */
static const double SAMPLES_PER_ROW = 0.6;
static const double SAMPLES_PER_COLUMN = 0.6;
/* The polar region handled by direct integration: at least 3 texels and this many rows. */
static const double POLE_ROWS = 4.0;
/* Cells per texel there (their solid angle is a texel's / POLE_CELLS). */
static const double POLE_CELLS = 4096.0;
/* Texels of the faces around the poles that take this many samples per axis or more take one
 * window per source column instead (polar_columns). The two methods blur a texel's edge
 * differently, so their border is not exactly energy-neutral: at this k the grid's windows
 * reach only 1/16 of the texel past it in latitude (and it lies inside the directly
 * integrated polar region for cubes about as fine as the picture). */
enum { POLAR_COLUMNS_K = 8 };
/* Texels whose sample counts are found in one pass. */
enum { TEXEL_RUN = 64 };

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

/* atan on [0, 1]: Abramowitz & Stegun 4.4.49 (|error| <= 2e-8 rad, far below any pixel). */
static inline double atan01(double x)
{
    double x2 = x * x;
    return x * (1.0 + x2 * (-0.3333314528 + x2 * (0.1999355085 + x2 * (-0.1420889944 +
           x2 * (0.1065626393 + x2 * (-0.0752896400 + x2 * (0.0429096138 +
           x2 * (-0.0161657367 + x2 * 0.0028662257))))))));
}

int ibl__equirect_dir(double u, double v, double d[3])
{
    double phi = 2.0 * IBL_PI * (u - 0.5), theta = IBL_PI * v;
    double st = sin(theta);
    d[0] = st * sin(phi);
    d[1] = cos(theta);
    d[2] = -st * cos(phi);
    return 1;
}

void ibl__equirect_uv(const double d[3], double *u, double *v)
{
    double rho = sqrt(d[0] * d[0] + d[2] * d[2]);
    *u = atan2(d[0], -d[2]) / (2.0 * IBL_PI) + 0.5;
    *v = atan2(rho, d[1]) / IBL_PI;
}

/* A face's axes and the picture's sizes, for the fast path (fast_windows) */
typedef struct eq_fast_face {
    float m[3], a[3], b[3];
    int W, H, R, narrow_ok, N;
    float pole_radius2;
} eq_fast_face;

typedef struct eq_job {
    const ibl_image *im;
    double basis[6][3][3]; /* per face: major, s axis, t axis, in the picture frame */
    double world[3][3];    /* world = world * picture */
    double pole_cell_area; /* solid angle of the cells near the poles (about 1/POLE_CELLS texel) */
    double pole_radius2;   /* sin^2 of the polar region's angular radius */
    double *col_sin, *col_cos; /* sin and cos of each source column's centre longitude */
    const float *row_mean; /* height x 4 */
    ibl_cubemap *out;
    int fixed_k;
    eq_fast_face fast[6];
    int avx2; /* the fast path may use AVX2 */
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
    return (H / IBL_PI) * (cos(IBL_PI * a / H) - cos(IBL_PI * b / H));
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

/* Mean of the bilinear interpolant of the picture over the window [px0, px1] x [py0, py1]
 * (pixel units). Rows past a pole continue on the opposite meridian (row -1 is row 0 turned
 * by half a revolution). */
static void window_value(const eq_job *job, double px0, double px1, double py0, double py1,
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
    if (a > IBL_PI) a -= 2.0 * IBL_PI;
    else if (a < -IBL_PI) a += 2.0 * IBL_PI;
    return a;
}

/* Doubles two and four at a time (GCC / Clang vector extensions) */
typedef double v2d __attribute__((vector_size(16)));
typedef long long v2l __attribute__((vector_size(16)));
typedef double v4d __attribute__((vector_size(32)));

/* Where the picture-frame direction p lies against texel (tx, ty): bits 1 / 2 left / right of
 * it by more than margin (texels), 4 / 8 above / below; 0 if behind the face. *in: inside. */
static inline int texel_outcode(const double *m, const double *a, const double *b, double half,
                                int tx, int ty, double margin, double px, double py, double pz,
                                int *in)
{
    double pm = m[0] * px + m[1] * py + m[2] * pz;
    if (!(pm > 0.0)) {
        *in = 0;
        return 0;
    }
    double inv = half / pm;
    double fx = (a[0] * px + a[1] * py + a[2] * pz) * inv + half;
    double fy = (b[0] * px + b[1] * py + b[2] * pz) * inv + half;
    *in = fx >= tx && fx < tx + 1 && fy >= ty && fy < ty + 1;
    return (fx < tx - margin) | (fx >= tx + 1 + margin) << 1 | (fy < ty - margin) << 2 |
           (fy >= ty + 1 + margin) << 3;
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
        double rho = sqrt(x * x + z * z), py = atan2(rho, y) / IBL_PI * H;
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
    int full = any_pole || fabs(winding) > IBL_PI;
    /* a texel only a few pixels across can lie between pixel corners: then every pixel of its
     * range is cut into cells, not only those its edges visibly cross */
    int thin = yhi - ylo < 4.0 || (!full && (hi - lo) / (2.0 * IBL_PI) * W < 4.0);
    /* the closest approach to the pole can lie inside an edge: widen by a row */
    ylo = fmax(0.0, floor(ylo) - 1.0);
    yhi = fmin((double)H, ceil(yhi) + 1.0);
    if (full) {
        if (cy > 0) ylo = 0;
        else yhi = H;
    }
    long c0 = 0, c1 = W;
    if (!full) {
        c0 = (long)floor(((centre + lo) / (2.0 * IBL_PI) + 0.5) * W) - 1;
        c1 = (long)ceil(((centre + hi) / (2.0 * IBL_PI) + 0.5) * W) + 1;
        if (c1 - c0 > W) {
            c0 = 0;
            c1 = W;
        }
    }
    int r0 = (int)ylo, r1 = (int)yhi;
    double acc[4] = {0, 0, 0, 0}, wsum = 0;
    const double half = 0.5 * N;
    const double dphi = 2.0 * IBL_PI / W;
    const double cd = cos(dphi), sd = sin(dphi);
    /* a parallel strays from the chord between two pixel corners by under dphi^2 / 8 radians,
     * at most 3 times that on the face plane: in texels, under this */
    const double margin = N * dphi * dphi / 4.0 + 1e-9;
    const double phi_start = 2.0 * IBL_PI * ((double)c0 / W - 0.5);
    const double cos_start = cos(phi_start), sin_start = sin(phi_start);
    /* crossed pixels are cut into FINE rows of cells, each row into cells about as wide as
     * tall (a pixel near the pole is a thin wedge: sin(theta) dphi << dtheta) */
    enum { FINE = 16 };
    for (int r = r0; r < r1; r++) {
        const float *row = job->im->pixels + (size_t)r * W * 4;
        double th0 = IBL_PI * r / H, th1 = IBL_PI * (r + 1) / H;
        double st0 = sin(th0), ct0 = cos(th0), st1 = sin(th1), ct1 = cos(th1);
        double w_pixel = (ct0 - ct1) * dphi;
        double wedge = fmax(st0, st1) * dphi / (th1 - th0) * FINE;
        int nlon = wedge >= FINE ? FINE : (int)ceil(wedge);
        if (nlon < 1) nlon = 1;
        const double fine_d = dphi / nlon, fcd = cos(fine_d), fsd = sin(fine_d);
        const double hc = cos(0.5 * fine_d), hs = sin(0.5 * fine_d);
        /* the cells of a crossed pixel: their rows' sin, cos and solid angle */
        double sub_st[FINE], sub_ct[FINE], sub_w[FINE]; /* (FINE: even) */
        for (int j = 0; j < FINE; j++) {
            double ta = th0 + (th1 - th0) * j / FINE, tb = th0 + (th1 - th0) * (j + 1) / FINE;
            double tm = 0.5 * (ta + tb);
            sub_st[j] = sin(tm);
            sub_ct[j] = cos(tm);
            sub_w[j] = (cos(ta) - cos(tb)) * fine_d;
        }
        /* pixel corners along this row's top and bottom edges: inside the texel, and where
         * outside (a pixel whose four corners are all beyond one of the texel's edges, by more
         * than its parallels bulge past their chords, misses the texel: its other edges are
         * meridians, straight on the face plane) */
        double cp = cos_start, sp = sin_start;
        int top, bottom;
        int top_code = texel_outcode(m, a, b, half, tx, ty, margin, st0 * sp, ct0, -st0 * cp, &top);
        int bottom_code =
            texel_outcode(m, a, b, half, tx, ty, margin, st1 * sp, ct1, -st1 * cp, &bottom);
        long wc = c0 % W;
        if (wc < 0) wc += W;
        for (long col = c0; col < c1; col++) {
            double ncp = cp * cd - sp * sd, nsp = sp * cd + cp * sd;
            int top2, bottom2;
            int top2_code =
                texel_outcode(m, a, b, half, tx, ty, margin, st0 * nsp, ct0, -st0 * ncp, &top2);
            int bottom2_code =
                texel_outcode(m, a, b, half, tx, ty, margin, st1 * nsp, ct1, -st1 * ncp, &bottom2);
            int inside = top + bottom + top2 + bottom2;
            int missed = top_code & bottom_code & top2_code & bottom2_code;
            const float *p = row + wc * 4;
            if (inside == 4) {
                for (int c = 0; c < 4; c++) acc[c] += w_pixel * p[c];
                wsum += w_pixel;
            } else if (inside > 0 || (thin && !missed)) {
                /* the texel's edge crosses this pixel: count its cells by centre, a column of
                 * them at a time (two rows to a vector). Cell (st fs, ct, -st fc) is in the
                 * texel when its texel coordinates are, with m.p > 0: the same operations as
                 * texel_outcode, so that a cell on an edge goes to the same texel as there (a
                 * yaw of a round number of degrees puts whole columns of cells on a face's
                 * centre line, where the rounding of a.p decides). */
                v2d share2 = {0, 0};
                double fc = cp * hc - sp * hs, fs = sp * hc + cp * hs;
                for (int i = 0; i < nlon; i++) {
                    for (int j = 0; j < FINE; j += 2) {
                        v2d st, ct, wc;
                        memcpy(&st, sub_st + j, sizeof st);
                        memcpy(&ct, sub_ct + j, sizeof ct);
                        memcpy(&wc, sub_w + j, sizeof wc);
                        v2d px = st * fs, pz = -st * fc;
                        v2d pm = m[0] * px + m[1] * ct + m[2] * pz;
                        v2d inv = half / pm;
                        v2d fx = (a[0] * px + a[1] * ct + a[2] * pz) * inv + half;
                        v2d fy = (b[0] * px + b[1] * ct + b[2] * pz) * inv + half;
                        v2l in = (pm > 0.0) & (fx >= tx) & (fx < tx + 1) & (fy >= ty) &
                                 (fy < ty + 1);
                        share2 += (v2d)(in & (v2l)wc);
                    }
                    double t = fc * fcd - fs * fsd;
                    fs = fs * fcd + fc * fsd;
                    fc = t;
                }
                double share = share2[0] + share2[1];
                for (int c = 0; c < 4; c++) acc[c] += share * p[c];
                wsum += share;
            }
            cp = ncp;
            sp = nsp;
            top = top2;
            bottom = bottom2;
            top_code = top2_code;
            bottom_code = bottom2_code;
            if (++wc == W) wc = 0;
        }
    }
    if (wsum > 0.0) {
        for (int c = 0; c < 4; c++) out[c] = (float)(acc[c] / wsum);
    } else {
        /* a texel smaller than any cell: the picture at its centre */
        double py = atan2(sqrt(cx * cx + cz * cz), cy) / IBL_PI * H;
        double px = (centre / (2.0 * IBL_PI) + 0.5) * W;
        window_value(job, px, px, py, py, 0.0, 1.0, out);
    }
}

/* atan2 from atan01, without branches (the selects compile to masks, not jumps) */
static inline double atan2_nb(double y, double x)
{
    double ax = fabs(x), ay = fabs(y);
    double mn = ax < ay ? ax : ay, mx = ax < ay ? ay : ax;
    double r = atan01(mn / (mx > 0.0 ? mx : 1.0));
    double r_steep = 0.5 * IBL_PI - r;
    r = ay > ax ? r_steep : r;
    double r_back = IBL_PI - r;
    r = x < 0.0 ? r_back : r;
    double r_neg = -r;
    return y < 0.0 ? r_neg : r;
}

/* Four floats at a time (GCC / Clang vector extensions; plain SSE on x86-64). */
typedef float v4f __attribute__((vector_size(16)));
typedef int v4i __attribute__((vector_size(16)));
static inline v4f vsplat(float x) { return (v4f){x, x, x, x}; }
static inline v4f vload(const float *p)
{
    v4f v;
    memcpy(&v, p, sizeof v);
    return v;
}
static inline void vstore(float *p, v4f v) { memcpy(p, &v, sizeof v); }
/* Samples are gathered in batches over a texel row. Most take the fast path (fast_windows,
 * below: float vectors, 4 x 4 taps); the rest (windows under 1/16 pixel or over two pixels,
 * windows across the border of the polar bands, pictures under 8 x 64) go to a second batch
 * handled in double (slow_values). */
enum { BATCH = 128 };
typedef struct eq_slow {
    int n;
    double sc[BATCH], tc[BATCH], sub[BATCH];
    int preset[BATCH]; /* the window is given (polar_columns), not the face point */
    double given[BATCH][7]; /* its weight, px, py, wpx, hpx, sin and cos theta */
    double px[BATCH], py[BATCH], wpx[BATCH], hpx[BATCH], st[BATCH], ct[BATCH], wt[BATCH];
    double t0[BATCH], t1[BATCH], t2[BATCH], t3[BATCH], t4[BATCH], t5[2 * BATCH]; /* scratch */
    /* the windows: kind (0: general, window_value), first row, 4 x 4 taps */
    int kind[BATCH], row[BATCH], rows[BATCH], col[4][BATCH];
    float wx[4][BATCH], wyt[4][BATCH], wyp[3][BATCH];
    /* the tent windows' parameters (see slow_values) */
    float v_da[BATCH], v_e[BATCH], v_dy[BATCH], v_ey[BATCH], v_h[BATCH];
    float v_sc[BATCH], v_sd[BATCH];
    int fine[BATCH];       /* windows whose weights are redone in double */
    double fd[BATCH][6];   /* their da, w, dy, h, s_c, s_d */
    float val[BATCH][4];   /* the result: each window's value */
} eq_slow;

typedef struct eq_batch {
    int n;
    int texel[BATCH];
    /* a window given by polar_columns (as eq_slow's), where fsub is 0; in float below */
    double given[BATCH][7];
    /* the face point and cell size; the fast path's windows: weight, first row, rows, columns,
     * tap weights */
    float fsc[BATCH], ftc[BATCH], fsub[BATCH];
    float gwt[BATCH], gpx[BATCH], gpy[BATCH], gwpx[BATCH], ghpx[BATCH], gst[BATCH], gct[BATCH];
    int fast[BATCH], frow[BATCH], frows[BATCH], fcol[BATCH];
    float fwt[BATCH], fwx[4][BATCH], fwy[4][BATCH];
    eq_slow *slow;
    /* the running sum of the texel being summed (its samples can span two batches) */
    int cur;
    v4d acc;
    double wsum;
} eq_batch;

static void batch_emit(eq_batch *bt, float *out)
{
    if (bt->cur >= 0) {
        v4f mean = __builtin_convertvector(bt->acc * (1.0 / bt->wsum), v4f);
        memcpy(out + (size_t)bt->cur * 4, &mean, sizeof mean);
    }
    bt->cur = -1;
}

/* The value of each window of a batch, in double (the samples the fast path leaves). */
/* equirect_lanes.h's four-lane copy (included below) */
static void tent_weights_4(v4f da, v4f e, v4f dy, v4f ey, v4f h, v4f s_c, v4f s_d, v4f wy[4], v4f wx[4]);

static void slow_values(const eq_job *job, int face, eq_slow *bt)
{
    int W = job->im->width, H = job->im->height, n = bt->n;
    const double *m = job->basis[face][0], *a = job->basis[face][1], *b = job->basis[face][2];
    const double px_per_rad_u = W / (2.0 * IBL_PI), px_per_rad_v = H / IBL_PI;
    double *x = bt->t0, *y = bt->t1, *z = bt->t2, *rho = bt->t3, *len = bt->t4;
    for (int i = 0; i < n; i++) {
        double sc = bt->sc[i], tc = bt->tc[i];
        x[i] = m[0] + tc * b[0] + sc * a[0];
        y[i] = m[1] + tc * b[1] + sc * a[1];
        z[i] = m[2] + tc * b[2] + sc * a[2];
    }
    double *sq = bt->t5;
    for (int i = 0; i < n; i++) {
        sq[i] = x[i] * x[i] + z[i] * z[i];
        sq[BATCH + i] = sq[i] + y[i] * y[i];
    }
    sqrt_run(sq, rho, n);
    sqrt_run(sq + BATCH, len, n);
    for (int i = 0; i < n; i++) {
        double xi = x[i], yi = y[i], zi = z[i], sub = bt->sub[i];
        double rho2 = xi * xi + zi * zi;
        double inv_len = 1.0 / len[i], inv_len2 = inv_len * inv_len;
        double wt = inv_len2 * inv_len;
        double px = (atan2_nb(xi, -zi) * (0.5 / IBL_PI) + 0.5) * W;
        double py = atan2_nb(rho[i], yi) * (H / IBL_PI);
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
        bt->wt[i] = wt;
        bt->px[i] = px;
        bt->py[i] = py;
        bt->wpx[i] = wpx;
        bt->hpx[i] = hpx;
        bt->st[i] = rho[i] * inv_len;
        bt->ct[i] = yi * inv_len;
    }
    for (int i = 0; i < n; i++)
        if (bt->preset[i]) {
            const double *g = bt->given[i];
            bt->wt[i] = g[0];
            bt->px[i] = g[1];
            bt->py[i] = g[2];
            bt->wpx[i] = g[3];
            bt->hpx[i] = g[4];
            bt->st[i] = g[5];
            bt->ct[i] = g[6];
        }
    /* The windows (as window_value): the 4 x 4 tap weights of the narrow ones, tent rows
     * (as row_share) or polar bands (constant rows); kind 0 takes window_value. First the
     * positions and the polar bands in double, one sample at a time. */
    const long R = POLAR_BOX_ROWS < H / 4 ? POLAR_BOX_ROWS : H / 4;
    const double k_rad = IBL_PI / H;
    const int narrow_ok = W >= 8, polar_ok = W >= 8 && H >= 64;
    int n4 = (n + 3) & ~3;
    for (int i = 0; i < n4; i++) {
        if (i >= n) {
            /* lanes past the batch: any finite window */
            bt->v_da[i] = bt->v_e[i] = bt->v_dy[i] = bt->v_ey[i] = 0.0f;
            bt->v_sc[i] = bt->v_sd[i] = bt->v_h[i] = 0.0f;
            continue;
        }
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
        if (!(tent | polar)) {
            bt->v_da[i] = bt->v_e[i] = bt->v_dy[i] = bt->v_ey[i] = 0.0f;
            bt->v_sc[i] = bt->v_sd[i] = bt->v_h[i] = 0.0f;
            continue;
        }
        /* longitude: the first column whose tent reaches the window, then four */
        double wa = px0 < 0.0 ? px0 + W : px0 >= W ? px0 - W : px0;
        int i0 = (int)(wa + 0.5) - 1; /* floor(wa - 1/2) */
        double da = wa - (i0 + 0.5);  /* in [0, 1) */
        for (int k = 0; k < 4; k++) {
            int col = i0 + k;
            col = col < 0 ? col + W : col >= W ? col - W : col;
            bt->col[k][i] = col;
        }
        bt->v_da[i] = (float)da;
        bt->v_e[i] = (float)(da + w);
        /* a window much narrower than a pixel loses its width to float rounding of its ends
         * (6e-8 / w relative): its weights are redone in double below */
        bt->fine[i] = w < 1.0 / 16 || (tent && h < 1.0 / 16);
        bt->fd[i][0] = da;
        bt->fd[i][1] = w;
        if (tent) {
            /* row jt + k has centre py0 - dy + k */
            int jt = (int)(py0 + 0.5) - 1; /* floor(py0 - 1/2) */
            double dy = py0 - (jt + 0.5);
            bt->row[i] = jt;
            bt->rows[i] = dy + h > 2.0 ? 4 : dy + h > 1.0 ? 3 : 2;
            bt->v_dy[i] = (float)dy;
            bt->v_ey[i] = (float)(dy + h);
            bt->v_h[i] = (float)h;
            bt->v_sc[i] = (float)s_c;
            bt->v_sd[i] = (float)s_d;
            bt->fd[i][2] = dy;
            bt->fd[i][3] = h;
            bt->fd[i][4] = s_c;
            bt->fd[i][5] = s_d;
        } else {
            /* polar bands: row jp + k covers [jp + k, jp + k + 1]. The solid angle between
             * theta_i < theta_j is cos theta_i - cos theta_j = 2 sin(mean) sin(half the
             * difference), both from the window's centre theta_c (sin_t, cos_t) by the
             * angle-sum formula and Taylor series in offsets below pi / H (H >= 64: terms
             * past the seventh power are below 1e-15) */
            int jp = (int)py0;
            double cut[4] = {py0, py1 < jp + 1.0 ? py1 : jp + 1.0,
                             py1 < jp + 2.0 ? py1 : jp + 2.0, py1};
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
            for (int k = 0; k < 3; k++) bt->wyp[k][i] = (float)(share[k] * inv);
            bt->row[i] = jp;
            bt->rows[i] = cut[2] < py1 ? 3 : cut[1] < py1 ? 2 : 1;
            bt->v_dy[i] = bt->v_ey[i] = bt->v_h[i] = bt->v_sc[i] = bt->v_sd[i] = 0.0f;
        }
    }
    /* Then the tent weights of four samples at a time, in float (the taps are float), by the
     * fast path's own function (equirect_lanes.h, tent_weights) */
    for (int i = 0; i < n4; i += 4) {
        v4f da = vload(bt->v_da + i), e = vload(bt->v_e + i);
        v4f dy = vload(bt->v_dy + i), ey = vload(bt->v_ey + i), h = vload(bt->v_h + i);
        v4f sc = vload(bt->v_sc + i), sd = vload(bt->v_sd + i);
        v4f wy[4], wx[4];
        tent_weights_4(da, e, dy, ey, h, sc, sd, wy, wx);
        for (int k = 0; k < 4; k++) {
            vstore(bt->wyt[k] + i, wy[k]);
            vstore(bt->wx[k] + i, wx[k]);
        }
    }
    for (int i = 0; i < n; i++) {
        if (!bt->kind[i] || !bt->fine[i]) continue;
        const double *f = bt->fd[i];
        double wx[4], sum = 0.0;
        for (int k = 0; k < 4; k++) {
            wx[k] = tent_cdf(f[0] + f[1] - k) - tent_cdf(f[0] - k);
            sum += wx[k];
        }
        for (int k = 0; k < 4; k++) bt->wx[k][i] = (float)(wx[k] / sum);
        if (bt->kind[i] != 1) continue;
        double dy = f[2], h = f[3], share[4];
        sum = 0.0;
        for (int k = 0; k < 4; k++) {
            double t = tent_cdf(dy + h - k) - tent_cdf(dy - k);
            double mom = tent_moment(dy + h - k) - tent_moment(dy - k);
            share[k] = t * (f[4] + f[5] * (k - dy - 0.5 * h)) + f[5] * mom;
            sum += share[k];
        }
        for (int k = 0; k < 4; k++) bt->wyt[k][i] = (float)(share[k] / sum);
    }
    const float *pix = job->im->pixels;
    for (int i = 0; i < n; i++) {
        float *val = bt->val[i];
        val[0] = val[1] = val[2] = val[3] = 0.0f;
        if (bt->kind[i]) {
            for (int k = 0; k < bt->rows[i]; k++) {
                long r = bt->row[i] + k < H ? bt->row[i] + k : H - 1; /* past the window: 0 */
                const float *rowp = pix + (size_t)r * W * 4;
                float wy = bt->kind[i] == 1 ? bt->wyt[k][i] : bt->wyp[k][i], v[4] = {0, 0, 0, 0};
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
    }
}

/* The fast path: the windows of samples whose window is at most two pixels wide and tall,
 * which is nearly all of them, in float vectors (src/layout/equirect_lanes.h, compiled for
 * four lanes and, with AVX2 where the CPU has it, eight: the same bits either way). Float is
 * enough here: a window's ends move by under 3e-4 pixel (float spacing at 2048 pixels, and the
 * float polynomial atan2), against windows 1/16 pixel and wider (narrower ones, and the wide
 * ones of window_value, are left to slow_values). */
typedef float v8f __attribute__((vector_size(32)));
typedef int v8i __attribute__((vector_size(32)));
/* Lane helpers for the vector type VF (mask type VI) of the including width. Macros
 * (statement expressions): GCC notes an ABI change for every function taking a 32-byte
 * vector, even an always inlined one. */
#define LLOAD(p) ({ VF l_; memcpy(&l_, (p), sizeof l_); l_; })
#define LSTORE(p, v) do { __typeof__(v) s_ = (v); memcpy((p), &s_, sizeof s_); } while (0)
#define LSEL(m, a, b) ({ VI m_ = (m); (VF)((m_ & (VI)(a)) | (~m_ & (VI)(b))); })
#define LABS(x) ((VF)((VI)(x) & 0x7fffffff))
#define LCLAMP1(t) LMIN(LMAX((t), (VF){} - 1.0f), (VF){} + 1.0f)
/* tent_cdf and tent_moment without branches, for t clamped to [-1, 1]:
 * T(t) = 1/2 + t - t |t| / 2, M(t) = t^2 (1/2 - |t| / 3) - 1/6 */
#define LTENT(t) ({ VF u_ = LCLAMP1(t); 0.5f + u_ - 0.5f * u_ * LABS(u_); })
#define LMOMENT(t) ({ VF u_ = LCLAMP1(t); \
                      u_ * u_ * (0.5f - LABS(u_) * (1.0f / 3.0f)) - 1.0f / 6.0f; })
/* atan2 from atan01 (the same polynomial, in float), without branches */
#define LATAN2(y, x) ({ \
    VF y_ = (y), x_ = (x), ax_ = LABS(x_), ay_ = LABS(y_); \
    VI steep_ = ay_ > ax_; \
    VF mn_ = LMIN(ax_, ay_), mx_ = LMAX(ax_, ay_); \
    VF t_ = mn_ / LSEL(mx_ > 0.0f, mx_, (VF){} + 1.0f), t2_ = t_ * t_; \
    VF r_ = t_ * (1.0f + t2_ * (-0.3333314528f + t2_ * (0.1999355085f + \
            t2_ * (-0.1420889944f + t2_ * (0.1065626393f + t2_ * (-0.0752896400f + \
            t2_ * (0.0429096138f + t2_ * (-0.0161657367f + t2_ * 0.0028662257f)))))))); \
    r_ = LSEL(steep_, (float)(0.5 * IBL_PI) - r_, r_); \
    r_ = LSEL(x_ < 0.0f, (float)IBL_PI - r_, r_); \
    LSEL(y_ < 0.0f, -r_, r_); })

/* four lanes: the portable code */
#define LANES 4
#define EQ_FN(name) name##_4
#define EQ_TARGET
#if defined(__SSE__)
#include <xmmintrin.h>
/* the larger / smaller of finite a and b (as a select on a < b would give, in one instruction) */
#define LMAX(a, b) LSSE(_mm_max_ps, (a), (b))
#define LMIN(a, b) LSSE(_mm_min_ps, (a), (b))
#define LSSE(op, a, b) ({ __m128 p_, q_; VF a_ = (a), b_ = (b); memcpy(&p_, &a_, sizeof p_); \
                           memcpy(&q_, &b_, sizeof q_); p_ = op(p_, q_); \
                           memcpy(&a_, &p_, sizeof a_); a_; })
#define LSQRT(x) ({ __m128 q_; VF r_ = (x); memcpy(&q_, &r_, sizeof q_); q_ = _mm_sqrt_ps(q_); \
                    memcpy(&r_, &q_, sizeof r_); r_; })
#else
#define LSQRT(x) ({ VF r_ = (x); for (int l_ = 0; l_ < LANES; l_++) r_[l_] = sqrtf(r_[l_]); r_; })
#define LMAX(a, b) ({ VF a_ = (a), b_ = (b); LSEL(a_ < b_, b_, a_); })
#define LMIN(a, b) ({ VF a_ = (a), b_ = (b); LSEL(b_ < a_, b_, a_); })
#endif
#include "equirect_lanes.h" /* (it undefines LANES, EQ_FN, EQ_TARGET, LSQRT, LMAX, LMIN) */

/* eight lanes in AVX2 registers, where the compiler can target them (chosen at run time) */
#if (defined(__x86_64__) || defined(__i386__)) && \
    (defined(__clang__) || (defined(__GNUC__) && __GNUC__ >= 12))
#define EQ_HAVE_AVX2 1
#include <immintrin.h>
#define LANES 8
#define EQ_FN(name) name##_8
#define EQ_TARGET __attribute__((target("avx2")))
#define LMAX(a, b) LAVX(_mm256_max_ps, (a), (b))
#define LMIN(a, b) LAVX(_mm256_min_ps, (a), (b))
#define LAVX(op, a, b) ({ __m256 p_, q_; VF a_ = (a), b_ = (b); memcpy(&p_, &a_, sizeof p_); \
                          memcpy(&q_, &b_, sizeof q_); p_ = op(p_, q_); \
                          memcpy(&a_, &p_, sizeof a_); a_; })
#define LSQRT(x) ({ __m256 q_; VF r_ = (x); memcpy(&q_, &r_, sizeof q_); \
                    q_ = _mm256_sqrt_ps(q_); memcpy(&r_, &q_, sizeof r_); r_; })
/* two v4f side by side */
#define LJOIN(lo, hi) __builtin_shufflevector((lo), (hi), 0, 1, 2, 3, 4, 5, 6, 7)
#include "equirect_lanes.h" /* (it undefines LANES, EQ_FN, EQ_TARGET, LSQRT, LMAX, LMIN) */
#endif

static int fast_windows(const eq_job *job, int face, eq_batch *bt, int n, int n_real)
{
#ifdef EQ_HAVE_AVX2
    if (job->avx2) return fast_windows_8(&job->fast[face], bt, n, n_real);
#endif
    return fast_windows_4(&job->fast[face], bt, n, n_real);
}

static void batch_sum(const eq_job *job, eq_batch *bt, float *out)
{
#ifdef EQ_HAVE_AVX2
    if (job->avx2) {
        batch_sum_8(job, bt, out);
        return;
    }
#endif
    batch_sum_4(job, bt, out);
}

static void texel_ks(const eq_job *job, int face, int ty, int tx0, int n, int *ks)
{
    n = (n + 7) & ~7;
#ifdef EQ_HAVE_AVX2
    if (job->avx2) {
        texel_ks_8(&job->fast[face], ty, tx0, n, ks);
        return;
    }
#endif
    texel_ks_4(&job->fast[face], ty, tx0, n, ks);
}

/* The samples of a batch: the fast windows' values from their 4 x 4 taps, the others' from
 * slow_values, summed per texel in the samples' order. */
static void batch_flush(const eq_job *job, int face, eq_batch *bt, float *out)
{
    int n = bt->n, n8 = (n + 7) & ~7;
    for (int i = n; i < n8; i++) {
        /* lanes past the batch: the face's centre (unused) */
        bt->fsc[i] = bt->ftc[i] = 0.0f;
        bt->fsub[i] = 1.0f;
    }
    int all_fast = fast_windows(job, face, bt, n8, n) == n;
    eq_slow *sl = bt->slow;
    sl->n = 0;
    for (int i = 0; i < n && !all_fast; i++) {
        if (bt->fast[i]) continue;
        int j = sl->n++;
        sl->sc[j] = bt->fsc[i];
        sl->tc[j] = bt->ftc[i];
        sl->sub[j] = bt->fsub[i];
        sl->preset[j] = bt->fsub[i] == 0.0f;
        if (sl->preset[j]) memcpy(sl->given[j], bt->given[i], sizeof sl->given[j]);
    }
    if (sl->n) slow_values(job, face, sl);
    batch_sum(job, bt, out);
    bt->n = 0;
}

/* A texel of a face around a pole (the pole at the face's centre, its axes level) spanning
 * many source columns: there a k x k grid of samples wastes most of them, as each sample's
 * window is a pixel wide in longitude but much less tall. Instead the texel takes one window
 * per source column j whose centre meridian phi_j crosses it: that column's longitude range by
 * the latitude range where the meridian crosses the texel (the ray from the face's centre
 * meets the texel's square in one segment, as the square does not hold the centre), weighted
 * by its solid angle (2 pi / W) (cos theta_in - cos theta_out). The meridians are shared by
 * all texels and a ray's segments in neighbouring texels share their ends, so these windows
 * tile the sphere exactly as the columns do: energy is kept wherever a sun falls.
 * Returns 0 when the texel is not such a texel. */
static int polar_columns(const eq_job *job, int face, int tx, int ty, eq_batch *bt, float *out)
{
    int N = job->out->size, W = job->im->width, H = job->im->height;
    const double *m = job->basis[face][0], *a = job->basis[face][1], *b = job->basis[face][2];
    if (!(fabs(m[1]) > 1.0 - 1e-9 && fabs(a[1]) < 1e-9 && fabs(b[1]) < 1e-9)) return 0;
    const double cell = 2.0 / N;
    /* the same expressions for a texel's edges as for its neighbours' */
    double s0 = -1.0 + tx * cell, s1 = -1.0 + (tx + 1) * cell;
    double t0 = -1.0 + ty * cell, t1 = -1.0 + (ty + 1) * cell;
    /* longitude range from the corners, about the centre's */
    double sm = 0.5 * (s0 + s1), tm = 0.5 * (t0 + t1);
    double centre = atan2(sm * a[0] + tm * b[0], -(sm * a[2] + tm * b[2])), lo = 0, hi = 0;
    for (int c = 0; c < 4; c++) {
        double sc = c & 1 ? s1 : s0, tc = c & 2 ? t1 : t0;
        double rel = wrap_angle(atan2(sc * a[0] + tc * b[0], -(sc * a[2] + tc * b[2])) - centre);
        lo = rel < lo ? rel : lo;
        hi = rel > hi ? rel : hi;
    }
    if (!(hi - lo < 0.5 * IBL_PI)) return 0; /* not clear of the pole */
    /* the columns whose centres phi_j = 2 pi ((j + 1/2) / W - 1/2) lie in the range */
    double u_lo = ((centre + lo) / (2.0 * IBL_PI) + 0.5) * W - 0.5;
    double u_hi = ((centre + hi) / (2.0 * IBL_PI) + 0.5) * W - 0.5;
    long j_lo = (long)ceil(u_lo), j_hi = (long)floor(u_hi);
    if (j_hi < j_lo) return 0;
    const double my = m[1], dphi = 2.0 * IBL_PI / W;
    for (long j = j_lo; j <= j_hi; j++) {
        long jj = j % W;
        jj = jj < 0 ? jj + W : jj;
        double hx = job->col_sin[jj], hz = -job->col_cos[jj]; /* level direction of phi_j */
        double ua = hx * a[0] + hz * a[2], ub = hx * b[0] + hz * b[2];
        double rin = 0.0, rout = 1e300;
        double u[2] = {ua, ub}, l[2] = {s0, t0}, h[2] = {s1, t1};
        for (int ax = 0; ax < 2; ax++) {
            if (fabs(u[ax]) < 1e-300) {
                if (l[ax] > 0.0 || h[ax] <= 0.0) rout = -1.0;
                continue;
            }
            double r1 = l[ax] / u[ax], r2 = h[ax] / u[ax];
            double near = r1 < r2 ? r1 : r2, far = r1 < r2 ? r2 : r1;
            rin = near > rin ? near : rin;
            rout = far < rout ? far : rout;
        }
        if (!(rout > rin)) continue;
        /* theta = atan2(r, my) at both ends; cos theta = my / sqrt(r^2 + 1) */
        double li = 1.0 / sqrt(rin * rin + 1.0), lo_ = 1.0 / sqrt(rout * rout + 1.0);
        double wt = fabs(my * li - my * lo_) * dphi;
        if (!(wt > 0.0)) continue;
        double py_in = atan2_nb(rin, my) * (H / IBL_PI), py_out = atan2_nb(rout, my) * (H / IBL_PI);
        /* sin and cos of the middle latitude: the bisector of the two ends' directions */
        double vx = rin * li + rout * lo_, vy = my * (li + lo_), vl = 1.0 / sqrt(vx * vx + vy * vy);
        if (bt->n == BATCH) batch_flush(job, face, bt, out);
        int n = bt->n++;
        bt->texel[n] = tx;
        bt->fsc[n] = bt->ftc[n] = bt->fsub[n] = 0.0f;
        double *g = bt->given[n];
        g[0] = wt;
        g[1] = jj + 0.5;
        g[2] = 0.5 * (py_in + py_out);
        g[3] = 1.0;
        g[4] = fabs(py_out - py_in);
        g[5] = vx * vl;
        g[6] = vy * vl;
        bt->gwt[n] = (float)g[0];
        bt->gpx[n] = (float)g[1];
        bt->gpy[n] = (float)g[2];
        bt->gwpx[n] = (float)g[3];
        bt->ghpx[n] = (float)g[4];
        bt->gst[n] = (float)g[5];
        bt->gct[n] = (float)g[6];
    }
    return 1;
}

static void eq_row_task(void *arg, int index)
{
    const eq_job *job = arg;
    int N = job->out->size, face = index / N, ty = index % N;
    float *out = ibl_cubemap_face(job->out, 0, face) + (size_t)ty * N * 4;
    const double cell = 2.0 / N; /* texel edge on the face plane */
    eq_batch bt;
    eq_slow slow;
    bt.n = 0;
    bt.cur = -1;
    bt.slow = &slow;
    /* (the given windows' lanes are read for every sample, and selected only where given) */
    memset(bt.gwt, 0, sizeof bt.gwt);
    memset(bt.gpx, 0, sizeof bt.gpx);
    memset(bt.gpy, 0, sizeof bt.gpy);
    memset(bt.gwpx, 0, sizeof bt.gwpx);
    memset(bt.ghpx, 0, sizeof bt.ghpx);
    memset(bt.gst, 0, sizeof bt.gst);
    memset(bt.gct, 0, sizeof bt.gct);
    int ks[TEXEL_RUN];
    const float fcell = (float)cell, ftc_mid = (float)(-1.0 + (ty + 0.5) * cell);
    for (int tx0 = 0; tx0 < N; tx0 += TEXEL_RUN) {
        int run = N - tx0 < TEXEL_RUN ? N - tx0 : TEXEL_RUN;
        if (job->fixed_k == 0) texel_ks(job, face, ty, tx0, run, ks);
        int all_one = job->fixed_k == 1;
        if (job->fixed_k == 0) {
            all_one = 1;
            for (int r = 0; r < run; r++) all_one &= ks[r] == 1;
        }
        if (all_one) {
            /* one sample at each texel's centre (most runs of the faces around the equator) */
            for (int r = 0; r < run;) {
                if (bt.n == BATCH) batch_flush(job, face, &bt, out);
                int n0 = bt.n, m = run - r < BATCH - n0 ? run - r : BATCH - n0;
                for (int q = 0; q < m; q++) {
                    bt.texel[n0 + q] = tx0 + r + q;
                    bt.fsc[n0 + q] = (float)(-1.0 + (tx0 + r + q + 0.5) * cell);
                    bt.ftc[n0 + q] = ftc_mid;
                    bt.fsub[n0 + q] = fcell;
                }
                bt.n += m;
                r += m;
            }
            continue;
        }
        for (int r = 0; r < run; r++) {
            int tx = tx0 + r, k = job->fixed_k ? job->fixed_k : ks[r];
            if (k == 0) {
                eq_texel_near_pole(job, face, tx, ty, out + (size_t)tx * 4);
                continue;
            }
            if (k >= POLAR_COLUMNS_K && job->fixed_k == 0 &&
                polar_columns(job, face, tx, ty, &bt, out))
                continue;
            if (k == 1) {
                if (bt.n == BATCH) batch_flush(job, face, &bt, out);
                bt.texel[bt.n] = tx;
                bt.fsc[bt.n] = (float)(-1.0 + (tx + 0.5) * cell);
                bt.ftc[bt.n] = ftc_mid;
                bt.fsub[bt.n] = fcell;
                bt.n++;
                continue;
            }
            /* k x k samples, a row of them at a time (k <= 64 < BATCH) */
            const double sub = cell / k;
            const float fsub = (float)sub;
            float sci[64];
            for (int i = 0; i < k; i++) sci[i] = (float)(-1.0 + tx * cell + (i + 0.5) * sub);
            for (int j = 0; j < k; j++) {
                if (bt.n + k > BATCH) batch_flush(job, face, &bt, out);
                float tcj = (float)(-1.0 + ty * cell + (j + 0.5) * sub);
                int *texel = bt.texel + bt.n;
                float *fsc = bt.fsc + bt.n, *ftc = bt.ftc + bt.n, *fs = bt.fsub + bt.n;
                for (int i = 0; i < k; i++) {
                    texel[i] = tx;
                    fsc[i] = sci[i];
                    ftc[i] = tcj;
                    fs[i] = fsub;
                }
                bt.n += k;
            }
        }
    }
    if (bt.n) batch_flush(job, face, &bt, out);
    batch_emit(&bt, out);
}

/* The mean of each source row (the value of windows a whole turn wide), MEAN_ROWS rows per
 * task: each row is summed alone, in order, whichever thread takes it. */
enum { MEAN_ROWS = 16 };
typedef struct row_mean_job {
    const ibl_image *image;
    float *mean;
} row_mean_job;

static void row_mean_task(void *arg, int index)
{
    const row_mean_job *j = arg;
    int W = j->image->width, H = j->image->height;
    for (int r = index * MEAN_ROWS; r < H && r < (index + 1) * MEAN_ROWS; r++) {
        double s[4] = {0, 0, 0, 0};
        const float *p = j->image->pixels + (size_t)r * W * 4;
        for (int x = 0; x < W; x++)
            for (int c = 0; c < 4; c++) s[c] += p[(size_t)x * 4 + c];
        for (int c = 0; c < 4; c++) j->mean[(size_t)r * 4 + c] = (float)(s[c] / W);
    }
}

static ibl_status equirect_to_cube(ibl_context *ctx, const ibl_image *image,
                                   const ibl__frame *frame, int samples_per_axis, int simd,
                                   ibl_cubemap *out)
{
    int W = image->width, H = image->height;
    float *mean = ibl_alloc(ctx, (size_t)H * 4 * sizeof(float));
    if (!mean) return ibl_context_status(ctx);
    row_mean_job rm = {image, mean};
    ibl_parallel_for(ctx, (H + MEAN_ROWS - 1) / MEAN_ROWS, row_mean_task, &rm);
    double *cs = ibl_alloc(ctx, (size_t)W * 2 * sizeof(double));
    if (!cs) {
        ibl_free(ctx, mean);
        return ibl_context_status(ctx);
    }
    for (int j = 0; j < W; j++) {
        double phi = 2.0 * IBL_PI * ((j + 0.5) / W - 0.5);
        cs[j] = sin(phi);
        cs[W + j] = cos(phi);
    }
    eq_job job;
    memset(&job, 0, sizeof job);
    job.col_sin = cs;
    job.col_cos = cs + W;
    job.im = image;
    job.row_mean = mean;
    job.out = out;
    job.fixed_k = samples_per_axis;
    memcpy(job.world, frame->m, sizeof job.world);
    {
        /* The polar region: 3 texels, and at least POLE_ROWS source rows. */
        int N = out->size;
        double cell = 2.0 / N;
        double radius = fmin(fmax(atan(3.0 * cell), POLE_ROWS * IBL_PI / H), 0.5 * IBL_PI);
        job.pole_radius2 = sin(radius) * sin(radius);
        /* How finely the pixels are cut there: cells of about 1/POLE_CELLS of a texel. */
        job.pole_cell_area = cell * cell / POLE_CELLS;
    }
    ibl__picture_basis(frame, job.basis);
    {
        int R = POLAR_BOX_ROWS < H / 4 ? POLAR_BOX_ROWS : H / 4;
        for (int f = 0; f < 6; f++) {
            eq_fast_face *ff = &job.fast[f];
            for (int i = 0; i < 3; i++) {
                ff->m[i] = (float)job.basis[f][0][i];
                ff->a[i] = (float)job.basis[f][1][i];
                ff->b[i] = (float)job.basis[f][2][i];
            }
            ff->W = W;
            ff->H = H;
            ff->R = R;
            ff->narrow_ok = W >= 8;
            ff->N = out->size;
            ff->pole_radius2 = (float)job.pole_radius2;
        }
        (void)simd;
#ifdef EQ_HAVE_AVX2
        job.avx2 = simd && __builtin_cpu_supports("avx2");
#endif
    }
    ibl_parallel_for(ctx, 6 * out->size, eq_row_task, &job);
    ibl_free(ctx, cs);
    ibl_free(ctx, mean);
    return IBL_OK;
}

ibl_status ibl__equirect_to_cube(ibl_context *ctx, const ibl_image *image, const ibl__frame *frame,
                                 int samples_per_axis, ibl_cubemap *out)
{
    return equirect_to_cube(ctx, image, frame, samples_per_axis, 1, out);
}

ibl_status ibl__equirect_to_cube_portable(ibl_context *ctx, const ibl_image *image,
                                          const ibl__frame *frame, int samples_per_axis,
                                          ibl_cubemap *out)
{
    return equirect_to_cube(ctx, image, frame, samples_per_axis, 0, out);
}

int ibl__equirect_has_avx2(void)
{
#ifdef EQ_HAVE_AVX2
    return __builtin_cpu_supports("avx2") != 0;
#else
    return 0;
#endif
}
