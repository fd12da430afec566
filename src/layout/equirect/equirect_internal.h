/* Internal to src/layout/equirect/: what the files of the equirect -> cube conversion share.
 *
 * One mechanism per file:
 *   mapping.c               direction <-> picture coordinates, the exact solid angle of a
 *                           row, the exact solid-angle-weighted mean of a picture
 *   area_windows.c          the energy-preserving windows: the mean of the reconstructed
 *                           picture over a longitude/latitude window, in double
 *   polar_texels.c          texels at and around the poles: direct integration of the source
 *                           pixels, and one window per source column on the polar faces
 *   to_cube.c               the conversion: each texel row's samples, gathered in batches,
 *                           summed into texel means; the kernel choice
 *   batch_double.c          the windows of a batch the float lanes leave, in double
 *   batch_lanes.h           the float-lane kernels of a batch, written once for any width,
 *   batch_lanes_portable.c  ... compiled four lanes wide (plain C / SSE)
 *   batch_lanes_avx2.c      ... and eight lanes wide for AVX2 (the same bits)
 *
 * The vector types are GCC / Clang vector extensions, as everywhere in the library. */
#ifndef IBL_LAYOUT_EQUIRECT_INTERNAL_H
#define IBL_LAYOUT_EQUIRECT_INTERNAL_H

#include "layout/layout_internal.h"
#include "core/cpu.h"
#include "core/numeric.h"

#include <string.h>

/* The eight-lane kernels need AVX2 code generation and __builtin_shufflevector (GCC 12,
 * any Clang). */
#if IBL_HAVE_X86_KERNELS && (defined(__clang__) || __GNUC__ >= 12)
#define EQ_HAVE_LANES_8 1
#else
#define EQ_HAVE_LANES_8 0
#endif

/* Samples per batch (a batch is filled along one texel row of a face, then evaluated). */
enum { EQ_BATCH = 128 };
/* Texels whose sample counts are found in one pass. */
enum { EQ_TEXEL_RUN = 64 };
/* Rows this close to a pole are reconstructed as constant bands instead of being interpolated
 * (area_windows.c, row_share, says why); at most a quarter of the rows. */
enum { EQ_POLAR_BOX_ROWS = 12 };
static inline int eq_polar_box_rows(int height)
{
    return EQ_POLAR_BOX_ROWS < height / 4 ? EQ_POLAR_BOX_ROWS : height / 4;
}

typedef double v4d __attribute__((vector_size(32)));
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

/* A face's axes (in the picture's frame) and the picture's sizes, in float, for the lanes. */
typedef struct eq_lane_face {
    float m[3], a[3], b[3]; /* the face's centre, s axis, t axis                          */
    int W, H;               /* the picture's size                                         */
    int R;                  /* eq_polar_box_rows(H)                                       */
    int narrow_ok;          /* W >= 8: windows may take the lanes' 4 x 4 taps              */
    int N;                  /* the cube's size                                            */
    float pole_radius2;     /* sin^2 of the directly integrated polar region's radius     */
} eq_lane_face;

struct eq_lane_kernels;

/* The conversion's read-only state, shared by every texel row. */
typedef struct eq_job {
    const ibl_image *im;
    double basis[6][3][3];     /* per face: centre, s axis, t axis, in the picture frame */
    double *col_sin, *col_cos; /* sin and cos of each source column's centre longitude   */
    const float *row_mean;     /* height x 4: each source row's mean                    */
    ibl_cubemap *out;
    int fixed_k;               /* samples per texel axis; 0: chosen per texel             */
    eq_lane_face lanes[6];
    const struct eq_lane_kernels *kernels;
} eq_job;

/* The samples of a batch that the float lanes leave (windows under 1/16 pixel or over two
 * pixels, across the border of the polar bands, pictures under 8 x 64), in double. */
typedef struct eq_double_windows {
    int n;
    double sc[EQ_BATCH], tc[EQ_BATCH], sub[EQ_BATCH]; /* face point and cell size          */
    int preset[EQ_BATCH];           /* the window is given (polar columns), not the point   */
    double given[EQ_BATCH][7];      /* its weight, px, py, wpx, hpx, sin and cos theta      */
    double px[EQ_BATCH], py[EQ_BATCH], wpx[EQ_BATCH], hpx[EQ_BATCH], st[EQ_BATCH],
        ct[EQ_BATCH], wt[EQ_BATCH]; /* each window: centre, extent, latitude, weight        */
    double t0[EQ_BATCH], t1[EQ_BATCH], t2[EQ_BATCH], t3[EQ_BATCH], t4[EQ_BATCH],
        t5[2 * EQ_BATCH];           /* scratch                                              */
    /* kind (0: general, ibl__eq_window_mean; 1: tent rows; 2: polar bands), first row,
     * rows, four columns and the 4 x 4 tap weights */
    int kind[EQ_BATCH], row[EQ_BATCH], rows[EQ_BATCH], col[4][EQ_BATCH];
    float wx[4][EQ_BATCH], wyt[4][EQ_BATCH], wyp[3][EQ_BATCH];
    /* the tent windows' parameters, in float for the lanes' tent weights */
    float v_da[EQ_BATCH], v_e[EQ_BATCH], v_dy[EQ_BATCH], v_ey[EQ_BATCH], v_h[EQ_BATCH];
    float v_sc[EQ_BATCH], v_sd[EQ_BATCH];
    int fine[EQ_BATCH];         /* windows whose weights are redone in double        */
    double fd[EQ_BATCH][6];     /* their da, w, dy, h, s_c, s_d                       */
    float val[EQ_BATCH][4];     /* the result: each window's mean                     */
} eq_double_windows;

/* A batch of samples, all of one face. */
typedef struct eq_batch {
    int n;
    int texel[EQ_BATCH];
    double given[EQ_BATCH][7]; /* a window given by the polar columns (where fsub is 0)    */
    /* each sample's face point and cell size; the given windows in float */
    float fsc[EQ_BATCH], ftc[EQ_BATCH], fsub[EQ_BATCH];
    float gwt[EQ_BATCH], gpx[EQ_BATCH], gpy[EQ_BATCH], gwpx[EQ_BATCH], ghpx[EQ_BATCH],
        gst[EQ_BATCH], gct[EQ_BATCH];
    /* the lanes' windows: taken, first row, rows, first column, weight, tap weights */
    int fast[EQ_BATCH], frow[EQ_BATCH], frows[EQ_BATCH], fcol[EQ_BATCH];
    float fwt[EQ_BATCH], fwx[4][EQ_BATCH], fwy[4][EQ_BATCH];
    eq_double_windows *slow;
    /* the running sum of the texel being summed (its samples can span two batches) */
    int cur;
    v4d acc;
    double wsum;
} eq_batch;

/* The float-lane kernels of one width (batch_lanes.h). */
typedef struct eq_lane_kernels {
    /* Each sample's window; the tent and polar-band windows at most two pixels wide and tall
     * get their first row and column and 4 x 4 tap weights (fast[i]). n: a multiple of 8.
     * Returns how many of the first n_real samples took them. */
    int (*windows)(const eq_lane_face *face, eq_batch *bt, int n, int n_real);
    /* The windows' means summed per texel in the samples' order; a texel's mean is written
     * to out when the next texel starts. */
    void (*accumulate)(const eq_job *job, eq_batch *bt, float *out);
    /* Samples per axis for texels [tx0, tx0 + n) of row ty (0: near a pole). */
    void (*sample_counts)(const eq_lane_face *face, int ty, int tx0, int n, int *counts);
} eq_lane_kernels;

extern const eq_lane_kernels ibl__eq_lanes_4;
#if EQ_HAVE_LANES_8
extern const eq_lane_kernels ibl__eq_lanes_8;
#endif
/* The four-lane tent weights (batch_lanes.h), for the double path's tent windows. */
void ibl__eq_tent_weights_4(v4f da, v4f e, v4f dy, v4f ey, v4f h, v4f s_c, v4f s_d, v4f wy[4],
                            v4f wx[4]);

/* ---- shared arithmetic ---- */

/* Antiderivative of the unit tent max(0, 1 - |t|). */
static inline double eq_tent_cdf(double t)
{
    if (t <= -1.0) return 0.0;
    if (t <= 0.0) return 0.5 * (t + 1.0) * (t + 1.0);
    if (t < 1.0) return 1.0 - 0.5 * (1.0 - t) * (1.0 - t);
    return 1.0;
}

/* First moment of the unit tent: integral of s max(0, 1 - |s|) from -1 to t. */
static inline double eq_tent_moment(double t)
{
    if (t <= -1.0 || t >= 1.0) return 0.0;
    if (t <= 0.0) return t * t * (0.5 + t / 3.0) - 1.0 / 6.0;
    return t * t * (0.5 - t / 3.0) - 1.0 / 6.0;
}

/* atan on [0, 1]: Abramowitz & Stegun 4.4.49 (|error| <= 2e-8 rad, far below any pixel). */
static inline double eq_atan_unit(double x)
{
    double x2 = x * x;
    return x * (1.0 + x2 * (-0.3333314528 + x2 * (0.1999355085 + x2 * (-0.1420889944 +
           x2 * (0.1065626393 + x2 * (-0.0752896400 + x2 * (0.0429096138 +
           x2 * (-0.0161657367 + x2 * 0.0028662257))))))));
}

/* atan2 from eq_atan_unit, without branches (the selects compile to masks, not jumps). */
static inline double eq_atan2_branchless(double y, double x)
{
    double ax = fabs(x), ay = fabs(y);
    double mn = ax < ay ? ax : ay, mx = ax < ay ? ay : ax;
    double r = eq_atan_unit(mn / (mx > 0.0 ? mx : 1.0));
    double r_steep = IBL_HALF_PI - r;
    r = ay > ax ? r_steep : r;
    double r_back = IBL_PI - r;
    r = x < 0.0 ? r_back : r;
    double r_neg = -r;
    return y < 0.0 ? r_neg : r;
}

/* ---- between the files ---- */

/* area_windows.c: the mean of the reconstructed picture over the window [px0, px1] x
 * [py0, py1] (pixel units), given sin and cos of theta at the window's centre. */
void ibl__eq_window_mean(const eq_job *job, double px0, double px1, double py0, double py1,
                         double sin_t, double cos_t, float out[4]);
/* polar_texels.c: a texel near a pole, integrated directly; a texel of a polar face crossed by
 * many source columns, as one window per column (returns 0 if it is not such a texel). */
void ibl__eq_polar_texel(const eq_job *job, int face, int tx, int ty, float out[4]);
int ibl__eq_polar_columns(const eq_job *job, int face, int tx, int ty, eq_batch *bt, float *out);
/* to_cube.c: evaluates the batch's samples and adds them to their texels (out: the row). */
void ibl__eq_batch_flush(const eq_job *job, int face, eq_batch *bt, float *out);
/* batch_double.c: the means (and weights) of the windows the lanes left. */
void ibl__eq_double_windows(const eq_job *job, int face, eq_double_windows *dw);

#endif
