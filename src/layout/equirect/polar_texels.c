/* Cube texels at and around the poles of an equirect picture, where longitude/latitude
 * windows (area_windows.c) stop tiling the sphere.
 *
 * At a pole. Within a few texels of each pole theta and phi are far from linear across a
 * texel, and sample cells turned against the meridians cannot be matched by longitude/latitude
 * windows: their windows would overlap and count energy twice. Such a texel integrates the
 * source pixels directly instead, each with its exact solid angle
 * (ibl__equirect_row_solid_angle): pixels whose four corners are in the texel count whole,
 * pixels the texel's edge crosses are cut into 16 x 16 cells counted by their centres, and the
 * texel's value is the solid-angle-weighted mean (ibl__eq_polar_texel).
 *
 * Around a pole. On the faces centred on a pole, texels crossed by many source columns would
 * need k x k samples whose windows are a pixel wide but much less tall. Instead such a texel
 * takes one window per source column whose centre meridian crosses it, the column's longitude
 * range by the latitude range where the meridian crosses the texel, weighted by its solid
 * angle (2 pi / W)(cos theta_in - cos theta_out) (ibl__eq_polar_columns). Meridians are
 * straight lines through the face's centre on a polar face (a gnomonic projection maps great
 * circles to lines), so neighbouring texels share each segment's ends and these windows tile
 * the sphere exactly as the columns do. */
#include "equirect_internal.h"

#include <math.h>

typedef double v2d __attribute__((vector_size(16)));
typedef long long v2l __attribute__((vector_size(16)));

static double wrap_angle(double a)
{
    if (a > IBL_PI) a -= IBL_TWO_PI;
    else if (a < -IBL_PI) a += IBL_TWO_PI;
    return a;
}

/* A texel seen from the picture's frame: its face's centre m and axes a, b, the face's half
 * size in texels, and the texel. */
typedef struct texel_frame {
    const double *m, *a, *b;
    double half;
    int tx, ty;
} texel_frame;

/* Where the picture-frame direction p lies against the texel: bits 1 / 2 left / right of it by
 * more than margin (texels), 4 / 8 above / below; 0 if behind the face. *in: inside. */
static inline int texel_outcode(const texel_frame *t, double margin, double px, double py,
                                double pz, int *in)
{
    const double *m = t->m, *a = t->a, *b = t->b;
    double half = t->half;
    int tx = t->tx, ty = t->ty;
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

/* The pixels a polar texel can touch: rows [r0, r1), columns [c0, c1) (running past the seam
 * where needed). */
typedef struct polar_extent {
    int r0, r1;
    long c0, c1;
    int thin;          /* cut every pixel of the range into cells, not only crossed ones */
    double centre;     /* longitude of the texel's centre                                */
    double cx, cy, cz; /* the direction of the texel's centre (not normalised)           */
} polar_extent;

/* The texel's longitude / latitude range, from its corners and edge midpoints. */
static void polar_texel_extent(const eq_job *job, int face, int tx, int ty, polar_extent *e)
{
    int N = job->out->size, W = job->im->width, H = job->im->height;
    const double *m = job->basis[face][0], *a = job->basis[face][1], *b = job->basis[face][2];
    const double cell = 2.0 / N;
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
    e->thin = yhi - ylo < 4.0 || (!full && (hi - lo) / IBL_TWO_PI * W < 4.0);
    /* the closest approach to the pole can lie inside an edge: widen by a row */
    ylo = fmax(0.0, floor(ylo) - 1.0);
    yhi = fmin((double)H, ceil(yhi) + 1.0);
    if (full) {
        if (cy > 0) ylo = 0;
        else yhi = H;
    }
    long c0 = 0, c1 = W;
    if (!full) {
        c0 = (long)floor(((centre + lo) / IBL_TWO_PI + 0.5) * W) - 1;
        c1 = (long)ceil(((centre + hi) / IBL_TWO_PI + 0.5) * W) + 1;
        if (c1 - c0 > W) {
            c0 = 0;
            c1 = W;
        }
    }
    e->r0 = (int)ylo;
    e->r1 = (int)yhi;
    e->c0 = c0;
    e->c1 = c1;
    e->centre = centre;
    e->cx = cx;
    e->cy = cy;
    e->cz = cz;
}

/* Crossed pixels are cut into FINE rows of cells, each row into cells about as wide as tall
 * (a pixel near the pole is a thin wedge: sin(theta) dphi << dtheta). */
enum { FINE = 16 }; /* (even: two rows of cells to a vector) */

/* The cells of a crossed pixel of one source row. */
typedef struct pixel_cells {
    int nlon;                                  /* cells per row of cells                  */
    double sub_st[FINE], sub_ct[FINE], sub_w[FINE]; /* per row of cells: sin, cos, solid angle */
    double fcd, fsd, hc, hs; /* cos, sin of a cell's longitude step and of half of it       */
} pixel_cells;

/* The solid angle of the cells of the pixel starting at longitude (cos cp, sin sp) whose
 * centres are in the texel, a column of cells at a time (two rows to a vector). Cell
 * (st fs, ct, -st fc) is in the texel when its texel coordinates are, with m.p > 0: the same
 * operations as texel_outcode, so that a cell on an edge goes to the same texel as there (a
 * yaw of a round number of degrees puts whole columns of cells on a face's centre line, where
 * the rounding of a.p decides). */
static double crossed_pixel_share(const texel_frame *t, const pixel_cells *cells, double cp,
                                  double sp)
{
    const double *m = t->m, *a = t->a, *b = t->b;
    const double half = t->half;
    const int tx = t->tx, ty = t->ty;
    v2d share2 = {0, 0};
    double fc = cp * cells->hc - sp * cells->hs, fs = sp * cells->hc + cp * cells->hs;
    for (int i = 0; i < cells->nlon; i++) {
        for (int j = 0; j < FINE; j += 2) {
            v2d st, ct, wc;
            memcpy(&st, cells->sub_st + j, sizeof st);
            memcpy(&ct, cells->sub_ct + j, sizeof ct);
            memcpy(&wc, cells->sub_w + j, sizeof wc);
            v2d px = st * fs, pz = -st * fc;
            v2d pm = m[0] * px + m[1] * ct + m[2] * pz;
            v2d inv = half / pm;
            v2d fx = (a[0] * px + a[1] * ct + a[2] * pz) * inv + half;
            v2d fy = (b[0] * px + b[1] * ct + b[2] * pz) * inv + half;
            v2l in = (pm > 0.0) & (fx >= tx) & (fx < tx + 1) & (fy >= ty) & (fy < ty + 1);
            share2 += (v2d)(in & (v2l)wc);
        }
        double nc = fc * cells->fcd - fs * cells->fsd;
        fs = fs * cells->fcd + fc * cells->fsd;
        fc = nc;
    }
    return share2[0] + share2[1];
}

/* The walk along the columns of the texel's range: the longitude step and where it starts. */
typedef struct column_walk {
    double dphi, cd, sd;          /* step, its cos and sin                                */
    double margin;                /* how far a parallel strays from a chord, in texels     */
    double cos_start, sin_start;  /* cos and sin of the first column's left edge           */
} column_walk;

/* Adds the texel's part of source row r to acc and wsum. */
static void polar_texel_row(const eq_job *job, const texel_frame *t, const polar_extent *e,
                            const column_walk *walk, int r, double acc[4], double *wsum)
{
    int W = job->im->width, H = job->im->height;
    const float *row = job->im->pixels + (size_t)r * W * 4;
    const double dphi = walk->dphi, cd = walk->cd, sd = walk->sd, margin = walk->margin;
    double th0 = IBL_PI * r / H, th1 = IBL_PI * (r + 1) / H;
    double st0 = sin(th0), ct0 = cos(th0), st1 = sin(th1), ct1 = cos(th1);
    double w_pixel = ibl__equirect_row_solid_angle(W, H, r);
    pixel_cells cells;
    double wedge = fmax(st0, st1) * dphi / (th1 - th0) * FINE;
    cells.nlon = wedge >= FINE ? FINE : (int)ceil(wedge);
    if (cells.nlon < 1) cells.nlon = 1;
    const double fine_d = dphi / cells.nlon;
    cells.fcd = cos(fine_d);
    cells.fsd = sin(fine_d);
    cells.hc = cos(0.5 * fine_d);
    cells.hs = sin(0.5 * fine_d);
    for (int j = 0; j < FINE; j++) {
        double ta = th0 + (th1 - th0) * j / FINE, tb = th0 + (th1 - th0) * (j + 1) / FINE;
        double tm = 0.5 * (ta + tb);
        cells.sub_st[j] = sin(tm);
        cells.sub_ct[j] = cos(tm);
        cells.sub_w[j] = (cos(ta) - cos(tb)) * fine_d;
    }
    /* pixel corners along this row's top and bottom edges: inside the texel, and where
     * outside (a pixel whose four corners are all beyond one of the texel's edges, by more
     * than its parallels bulge past their chords, misses the texel: its other edges are
     * meridians, straight on the face plane) */
    double cp = walk->cos_start, sp = walk->sin_start;
    int top, bottom;
    int top_code = texel_outcode(t, margin, st0 * sp, ct0, -st0 * cp, &top);
    int bottom_code = texel_outcode(t, margin, st1 * sp, ct1, -st1 * cp, &bottom);
    long wc = e->c0 % W;
    if (wc < 0) wc += W;
    for (long col = e->c0; col < e->c1; col++) {
        double ncp = cp * cd - sp * sd, nsp = sp * cd + cp * sd;
        int top2, bottom2;
        int top2_code = texel_outcode(t, margin, st0 * nsp, ct0, -st0 * ncp, &top2);
        int bottom2_code = texel_outcode(t, margin, st1 * nsp, ct1, -st1 * ncp, &bottom2);
        int inside = top + bottom + top2 + bottom2;
        int missed = top_code & bottom_code & top2_code & bottom2_code;
        const float *p = row + wc * 4;
        if (inside == 4) {
            for (int c = 0; c < 4; c++) acc[c] += w_pixel * p[c];
            *wsum += w_pixel;
        } else if (inside > 0 || (e->thin && !missed)) {
            double share = crossed_pixel_share(t, &cells, cp, sp);
            for (int c = 0; c < 4; c++) acc[c] += share * p[c];
            *wsum += share;
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

void ibl__eq_polar_texel(const eq_job *job, int face, int tx, int ty, float out[4])
{
    int N = job->out->size, W = job->im->width, H = job->im->height;
    polar_extent e;
    polar_texel_extent(job, face, tx, ty, &e);
    texel_frame t = {job->basis[face][0], job->basis[face][1], job->basis[face][2], 0.5 * N,
                     tx, ty};
    column_walk walk;
    walk.dphi = IBL_TWO_PI / W;
    walk.cd = cos(walk.dphi);
    walk.sd = sin(walk.dphi);
    /* a parallel strays from the chord between two pixel corners by under dphi^2 / 8 radians,
     * at most 3 times that on the face plane: in texels, under this */
    walk.margin = N * walk.dphi * walk.dphi / 4.0 + 1e-9;
    const double phi_start = IBL_TWO_PI * ((double)e.c0 / W - 0.5);
    walk.cos_start = cos(phi_start);
    walk.sin_start = sin(phi_start);
    double acc[4] = {0, 0, 0, 0}, wsum = 0;
    for (int r = e.r0; r < e.r1; r++) polar_texel_row(job, &t, &e, &walk, r, acc, &wsum);
    if (wsum > 0.0) {
        for (int c = 0; c < 4; c++) out[c] = (float)(acc[c] / wsum);
    } else {
        /* a texel smaller than any cell: the picture at its centre */
        double py = atan2(sqrt(e.cx * e.cx + e.cz * e.cz), e.cy) / IBL_PI * H;
        double px = (e.centre / IBL_TWO_PI + 0.5) * W;
        ibl__eq_window_mean(job, px, px, py, py, 0.0, 1.0, out);
    }
}

int ibl__eq_polar_columns(const eq_job *job, int face, int tx, int ty, eq_batch *bt, float *out)
{
    int N = job->out->size, W = job->im->width, H = job->im->height;
    const double *m = job->basis[face][0], *a = job->basis[face][1], *b = job->basis[face][2];
    /* a face around a pole: its centre on the axis, its axes level */
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
    if (!(hi - lo < IBL_HALF_PI)) return 0; /* not clear of the pole */
    /* the columns whose centres phi_j = 2 pi ((j + 1/2) / W - 1/2) lie in the range */
    double u_lo = ((centre + lo) / IBL_TWO_PI + 0.5) * W - 0.5;
    double u_hi = ((centre + hi) / IBL_TWO_PI + 0.5) * W - 0.5;
    long j_lo = (long)ceil(u_lo), j_hi = (long)floor(u_hi);
    if (j_hi < j_lo) return 0;
    const double my = m[1], dphi = IBL_TWO_PI / W;
    for (long j = j_lo; j <= j_hi; j++) {
        long jj = j % W;
        jj = jj < 0 ? jj + W : jj;
        double hx = job->col_sin[jj], hz = -job->col_cos[jj]; /* level direction of phi_j */
        /* where the ray r (hx, hz) from the face's centre is in the texel: r in (rin, rout) */
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
        double py_in = eq_atan2_branchless(rin, my) * (H / IBL_PI);
        double py_out = eq_atan2_branchless(rout, my) * (H / IBL_PI);
        /* sin and cos of the middle latitude: the bisector of the two ends' directions */
        double vx = rin * li + rout * lo_, vy = my * (li + lo_), vl = 1.0 / sqrt(vx * vx + vy * vy);
        if (bt->n == EQ_BATCH) ibl__eq_batch_flush(job, face, bt, out);
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
