/* Real spherical harmonics up to 5 bands: basis, projection (cube, equirect, samples, face
 * centres), clamped-cosine convolution, the R&H quadratic form and windowing.
 * References: Ramamoorthi & Hanrahan 2001, "An efficient representation for irradiance
 * environment maps"; Sloan 2008, "Stupid spherical harmonics (SH) tricks". Design notes and
 * measured errors: docs/DIFFUSE.md. */
#include "ibl/sh.h"
#include "core/context_internal.h"
#include "core/cpu.h"
#include "core/numeric.h"
#include "layout/layout_internal.h"

#include "ibl/cubemap.h"

#include <math.h>
#include <string.h>


/* ---- the basis as homogeneous polynomials -------------------------------------------------
 * Every Y_lm is a homogeneous harmonic polynomial of degree l in (x, y, z) (using
 * x^2 + y^2 + z^2 = 1 to make the lower-degree parts homogeneous). The same table serves
 * direct evaluation and the moment-based projection below. */

typedef struct sh_term {
    double k;
    unsigned char p, q, r; /* x^p y^q z^r */
} sh_term;

typedef struct sh_poly {
    int count;
    sh_term t[6];
} sh_poly;

#define K00 0.28209479177387814  /* 1/2 sqrt(1/pi)    */
#define K1 0.48860251190291992   /* sqrt(3/(4pi))     */
#define K2A 1.0925484305920792   /* 1/2 sqrt(15/pi)   */
#define K20 0.31539156525252005  /* 1/4 sqrt(5/pi)    */
#define K22 0.54627421529603959  /* 1/4 sqrt(15/pi)   */
#define K33 0.59004358992664352  /* 1/4 sqrt(35/2pi)  */
#define K32A 2.8906114426405538  /* 1/2 sqrt(105/pi)  */
#define K31 0.45704579946446577  /* 1/4 sqrt(21/2pi)  */
#define K30 0.3731763325901154   /* 1/4 sqrt(7/pi)    */
#define K32 1.4453057213202769   /* 1/4 sqrt(105/pi)  */
#define K44 2.5033429417967046   /* 3/4 sqrt(35/pi)   */
#define K43 1.7701307697799304   /* 3/4 sqrt(35/2pi)  */
#define K42 0.94617469575756008  /* 3/4 sqrt(5/pi)    */
#define K41 0.66904654355728921  /* 3/4 sqrt(5/2pi)   */
#define K40 0.10578554691520431  /* 3/16 sqrt(1/pi)   */
#define K42B 0.47308734787878004 /* 3/8 sqrt(5/pi)    */
#define K44B 0.62583573544917614 /* 3/16 sqrt(35/pi)  */

static const sh_poly basis_poly[IBL_SH_MAX_COEFFS] = {
    /* l = 0 */
    {1, {{K00, 0, 0, 0}}},
    /* l = 1: y, z, x */
    {1, {{K1, 0, 1, 0}}},
    {1, {{K1, 0, 0, 1}}},
    {1, {{K1, 1, 0, 0}}},
    /* l = 2: xy, yz, 2z^2 - x^2 - y^2, xz, x^2 - y^2 */
    {1, {{K2A, 1, 1, 0}}},
    {1, {{K2A, 0, 1, 1}}},
    {3, {{2 * K20, 0, 0, 2}, {-K20, 2, 0, 0}, {-K20, 0, 2, 0}}},
    {1, {{K2A, 1, 0, 1}}},
    {2, {{K22, 2, 0, 0}, {-K22, 0, 2, 0}}},
    /* l = 3 */
    {2, {{3 * K33, 2, 1, 0}, {-K33, 0, 3, 0}}},                      /* y(3x^2 - y^2)        */
    {1, {{K32A, 1, 1, 1}}},                                           /* xyz                  */
    {3, {{4 * K31, 0, 1, 2}, {-K31, 2, 1, 0}, {-K31, 0, 3, 0}}},      /* y(4z^2 - x^2 - y^2)  */
    {3, {{2 * K30, 0, 0, 3}, {-3 * K30, 2, 0, 1}, {-3 * K30, 0, 2, 1}}}, /* z(2z^2-3x^2-3y^2) */
    {3, {{4 * K31, 1, 0, 2}, {-K31, 3, 0, 0}, {-K31, 1, 2, 0}}},      /* x(4z^2 - x^2 - y^2)  */
    {2, {{K32, 2, 0, 1}, {-K32, 0, 2, 1}}},                           /* (x^2 - y^2) z        */
    {2, {{K33, 3, 0, 0}, {-3 * K33, 1, 2, 0}}},                       /* x(x^2 - 3y^2)        */
    /* l = 4 */
    {2, {{K44, 3, 1, 0}, {-K44, 1, 3, 0}}},                           /* xy(x^2 - y^2)        */
    {2, {{3 * K43, 2, 1, 1}, {-K43, 0, 3, 1}}},                       /* (3x^2 - y^2) yz      */
    {3, {{6 * K42, 1, 1, 2}, {-K42, 3, 1, 0}, {-K42, 1, 3, 0}}},      /* xy(7z^2 - 1)         */
    {3, {{4 * K41, 0, 1, 3}, {-3 * K41, 2, 1, 1}, {-3 * K41, 0, 3, 1}}}, /* yz(7z^2 - 3)      */
    {6,
     {{8 * K40, 0, 0, 4},
      {-24 * K40, 2, 0, 2},
      {-24 * K40, 0, 2, 2},
      {3 * K40, 4, 0, 0},
      {3 * K40, 0, 4, 0},
      {6 * K40, 2, 2, 0}}},                                           /* 35z^4 - 30z^2 + 3    */
    {3, {{4 * K41, 1, 0, 3}, {-3 * K41, 3, 0, 1}, {-3 * K41, 1, 2, 1}}}, /* xz(7z^2 - 3)      */
    {4, {{6 * K42B, 2, 0, 2}, {-6 * K42B, 0, 2, 2}, {-K42B, 4, 0, 0}, {K42B, 0, 4, 0}}},
    {2, {{K43, 3, 0, 1}, {-3 * K43, 1, 2, 1}}},                       /* (x^2 - 3y^2) xz      */
    {3, {{K44B, 4, 0, 0}, {-6 * K44B, 2, 2, 0}, {K44B, 0, 4, 0}}},    /* x^4 - 6x^2y^2 + y^4  */
};

static int clamp_bands(int bands)
{
    if (bands == 0) return 3;
    return bands;
}

static int valid_bands(int bands) { return bands >= 1 && bands <= IBL_SH_MAX_BANDS; }

void ibl_sh_eval_basis(int bands, const double dir[3], double *out)
{
    double xp[5], yp[5], zp[5];
    xp[0] = yp[0] = zp[0] = 1.0;
    for (int i = 1; i < 5; i++) {
        xp[i] = xp[i - 1] * dir[0];
        yp[i] = yp[i - 1] * dir[1];
        zp[i] = zp[i - 1] * dir[2];
    }
    int n = bands * bands;
    for (int i = 0; i < n; i++) {
        const sh_poly *poly = &basis_poly[i];
        double v = 0;
        for (int t = 0; t < poly->count; t++) {
            const sh_term *term = &poly->t[t];
            v += term->k * xp[term->p] * yp[term->q] * zp[term->r];
        }
        out[i] = v;
    }
}

void ibl_sh_eval(const ibl_sh *sh, const double dir[3], double rgb[3])
{
    double y[IBL_SH_MAX_COEFFS];
    ibl_sh_eval_basis(sh->bands, dir, y);
    rgb[0] = rgb[1] = rgb[2] = 0;
    for (int i = 0; i < sh->bands * sh->bands; i++)
        for (int c = 0; c < 3; c++) rgb[c] += sh->c[i][c] * y[i];
}

/* ---- moments ---------------------------------------------------------------------------------
 * Projection accumulates the monomial moments  W[p][q][r] = sum L * dOmega * x^p y^q z^r  for
 * p + q + r <= bands - 1 and turns them into coefficients with the table above at the end.
 * Monomials factor over rows of a cube face or an equirect image, so the per-texel work is a
 * handful of multiply-adds (6 for 3 bands) instead of a full basis evaluation. */

enum { MOM_DIM = 5, MOM_SIZE = MOM_DIM * MOM_DIM * MOM_DIM };

static inline int mom_index(int p, int q, int r) { return (p * MOM_DIM + q) * MOM_DIM + r; }

static void moments_to_sh(const double *mom /* MOM_SIZE x 4 */, int bands, ibl_sh *out)
{
    memset(out, 0, sizeof *out);
    out->bands = bands;
    for (int i = 0; i < bands * bands; i++) {
        const sh_poly *poly = &basis_poly[i];
        for (int t = 0; t < poly->count; t++) {
            const sh_term *term = &poly->t[t];
            const double *m = mom + (size_t)mom_index(term->p, term->q, term->r) * 4;
            for (int c = 0; c < 3; c++) out->c[i][c] += term->k * m[c];
        }
    }
}

/* Cube face frames (cubemap.h): direction = major + sc * s_axis + tc * t_axis. axis[0] is the
 * s axis, axis[1] the t axis, axis[2] the major axis; sign likewise. */
static const int face_axis[6][3] = {{2, 1, 0}, {2, 1, 0}, {0, 2, 1}, {0, 2, 1}, {0, 1, 2}, {0, 1, 2}};
static const int face_sign[6][3] = {{-1, -1, +1}, {+1, -1, -1}, {+1, +1, +1},
                                    {+1, -1, -1}, {+1, -1, +1}, {-1, -1, -1}};

enum { SEG = 128, MAX_WEIGHTS = 15, MAX_CANON = 35 /* monomials of degree <= 4 */ };

struct ibl_sh_plan {
    ibl_context *ctx;
    int n, bands, deg, nw;
    int tasks, rows_per_task;
    int simd; /* AVX2 + FMA row sums */
    double *omega;   /* n*n exact texel solid angles (identical on all faces) */
    double *partial; /* tasks * MOM_SIZE * 4 */
    const float *faces;
};

/* Row-sum weights of one texel: omega * sc^i / r^d for d = 0..deg, i = 0..d (canonical
 * a = sc/r, b = tc/r, c = 1/r; tc is constant along a row and factored out). */
static inline void texel_weights(double omega, double sc, double inv_r, int deg, double *w)
{
    double rp = omega;
    int k = 0;
    for (int d = 0; d <= deg; d++) {
        double v = rp;
        for (int i = 0; i <= d; i++) {
            w[k++] = v;
            v *= sc;
        }
        rp *= inv_r;
    }
}

/* Sums of weight * texel over one row segment; nw is a small constant at every call site so
 * the loop is unrolled and kept in registers. */
static inline void row_sums_c(const double *w, const float *px, int count, int nw, double (*s)[3])
{
    for (int k = 0; k < nw; k++) s[k][0] = s[k][1] = s[k][2] = 0;
    for (int x = 0; x < count; x++) {
        double r = px[4 * x], g = px[4 * x + 1], b = px[4 * x + 2];
        const double *wx = w + (size_t)x * nw;
        for (int k = 0; k < nw; k++) {
            s[k][0] += wx[k] * r;
            s[k][1] += wx[k] * g;
            s[k][2] += wx[k] * b;
        }
    }
}

#if defined(__GNUC__) && defined(__x86_64__)
/* The same sums with AVX2 + FMA when the CPU has them (checked at run time): one RGBA texel
 * widened to four doubles, one fused multiply-add per weight; still double accumulation.
 * Blocks of at most 6 weights keep every accumulator in a register. */
#include <immintrin.h>
#define IBL_SH_HAVE_AVX2 1
#define ROW_SUMS_AVX2(KB)                                                                      \
    __attribute__((target("avx2,fma"))) static void row_sums_avx2_##KB(                       \
        const double *w, const float *px, int count, int nw, int k0, double (*s)[3])          \
    {                                                                                          \
        /* two texels per step into two accumulator sets: hides the FMA latency */             \
        __m256d acc[KB], acc2[KB];                                                             \
        for (int k = 0; k < KB; k++) acc[k] = acc2[k] = _mm256_setzero_pd();                   \
        int x = 0;                                                                             \
        for (; x + 1 < count; x += 2) {                                                        \
            __m256d v = _mm256_cvtps_pd(_mm_loadu_ps(px + 4 * x));                             \
            __m256d v2 = _mm256_cvtps_pd(_mm_loadu_ps(px + 4 * x + 4));                        \
            const double *wx = w + (size_t)x * nw + k0;                                        \
            for (int k = 0; k < KB; k++) {                                                     \
                acc[k] = _mm256_fmadd_pd(_mm256_broadcast_sd(wx + k), v, acc[k]);              \
                acc2[k] = _mm256_fmadd_pd(_mm256_broadcast_sd(wx + nw + k), v2, acc2[k]);      \
            }                                                                                  \
        }                                                                                      \
        if (x < count) {                                                                       \
            __m256d v = _mm256_cvtps_pd(_mm_loadu_ps(px + 4 * x));                             \
            const double *wx = w + (size_t)x * nw + k0;                                        \
            for (int k = 0; k < KB; k++)                                                       \
                acc[k] = _mm256_fmadd_pd(_mm256_broadcast_sd(wx + k), v, acc[k]);              \
        }                                                                                      \
        for (int k = 0; k < KB; k++) {                                                         \
            double t[4];                                                                       \
            _mm256_storeu_pd(t, _mm256_add_pd(acc[k], acc2[k]));                               \
            s[k0 + k][0] = t[0];                                                               \
            s[k0 + k][1] = t[1];                                                               \
            s[k0 + k][2] = t[2];                                                               \
        }                                                                                      \
    }
ROW_SUMS_AVX2(1)
ROW_SUMS_AVX2(3)
ROW_SUMS_AVX2(5)
ROW_SUMS_AVX2(6)
#endif

static void row_sums(int simd, const double *w, const float *px, int count, int nw, double (*s)[3])
{
#ifdef IBL_SH_HAVE_AVX2
    if (simd) {
        switch (nw) {
        case 1: row_sums_avx2_1(w, px, count, 1, 0, s); return;
        case 3: row_sums_avx2_3(w, px, count, 3, 0, s); return;
        case 6: row_sums_avx2_6(w, px, count, 6, 0, s); return;
        case 10:
            row_sums_avx2_5(w, px, count, 10, 0, s);
            row_sums_avx2_5(w, px, count, 10, 5, s);
            return;
        default:
            row_sums_avx2_5(w, px, count, 15, 0, s);
            row_sums_avx2_5(w, px, count, 15, 5, s);
            row_sums_avx2_5(w, px, count, 15, 10, s);
            return;
        }
    }
#else
    (void)simd;
#endif
    switch (nw) {
    case 1: row_sums_c(w, px, count, 1, s); break;
    case 3: row_sums_c(w, px, count, 3, s); break;
    case 6: row_sums_c(w, px, count, 6, s); break;
    case 10: row_sums_c(w, px, count, 10, s); break;
    default: row_sums_c(w, px, count, 15, s); break;
    }
}

static void cube_task(void *arg, int task)
{
    ibl_sh_plan *p = arg;
    int n = p->n, deg = p->deg, nw = p->nw;
    double *mom = p->partial + (size_t)task * MOM_SIZE * 4;
    memset(mom, 0, sizeof(double) * MOM_SIZE * 4);
    int half = (n + 1) / 2; /* tasks cover the top half; each row brings its mirror */
    int y0 = task * p->rows_per_task, y1 = y0 + p->rows_per_task;
    if (y1 > half) y1 = half;
    double w[SEG * MAX_WEIGHTS];
    double s[MAX_WEIGHTS][3];
    double canon[6][MAX_CANON][3]; /* per face, canonical moments in (d, i, j) order */
    memset(canon, 0, sizeof canon);
    for (int y = y0; y < y1; y++) {
        double tc = (2.0 * y + 1.0) / n - 1.0;
        double tcp[MOM_DIM];
        tcp[0] = 1;
        for (int j = 1; j < MOM_DIM; j++) tcp[j] = tcp[j - 1] * tc;
        for (int x0 = 0; x0 < n; x0 += SEG) {
            int count = n - x0 < SEG ? n - x0 : SEG;
            const double *om = p->omega + (size_t)y * n + x0;
            if (deg == 2) {
                /* the default 3 bands, written out so the loop vectorises */
                for (int x = 0; x < count; x++) {
                    double sc = (2.0 * (x0 + x) + 1.0) / n - 1.0;
                    double inv_r = 1.0 / sqrt(1.0 + sc * sc + tc * tc);
                    double w1 = om[x] * inv_r, w2 = w1 * inv_r;
                    double *wx = w + (size_t)x * 6;
                    wx[0] = om[x];
                    wx[1] = w1;
                    wx[2] = w1 * sc;
                    wx[3] = w2;
                    wx[4] = w2 * sc;
                    wx[5] = w2 * sc * sc;
                }
            } else {
                for (int x = 0; x < count; x++) {
                    double sc = (2.0 * (x0 + x) + 1.0) / n - 1.0;
                    double inv_r = 1.0 / sqrt(1.0 + sc * sc + tc * tc);
                    texel_weights(om[x], sc, inv_r, deg, w + (size_t)x * nw);
                }
            }
            /* row y and its mirror n-1-y (tc -> -tc) share every weight */
            for (int mirror = 0; mirror < 2; mirror++) {
                int row = mirror ? n - 1 - y : y;
                if (mirror && row == y) break;
                for (int face = 0; face < 6; face++) {
                    const float *px = p->faces + (((size_t)face * n + row) * n + x0) * 4;
                    row_sums(p->simd, w, px, count, nw, s);
                    /* canonical moments of this face: a^i b^j c^(d-i-j) = sum (d, i) * tc^j */
                    double(*cm)[3] = canon[face];
                    int k = 0, q = 0;
                    for (int d = 0; d <= deg; d++)
                        for (int i = 0; i <= d; i++, k++)
                            for (int j = 0; j <= d - i; j++, q++) {
                                double t = (mirror && (j & 1)) ? -tcp[j] : tcp[j];
                                cm[q][0] += t * s[k][0];
                                cm[q][1] += t * s[k][1];
                                cm[q][2] += t * s[k][2];
                            }
                }
            }
        }
    }
    /* canonical -> world monomials, once per chunk: the face's axis permutation and signs */
    for (int face = 0; face < 6; face++) {
        const int *ax = face_axis[face], *sg = face_sign[face];
        int q = 0;
        for (int d = 0; d <= deg; d++)
            for (int i = 0; i <= d; i++)
                for (int j = 0; j <= d - i; j++, q++) {
                    int c = d - i - j, e[3] = {0, 0, 0};
                    e[ax[0]] += i;
                    e[ax[1]] += j;
                    e[ax[2]] += c;
                    int odd = (sg[0] < 0 && (i & 1)) ^ (sg[1] < 0 && (j & 1)) ^ (sg[2] < 0 && (c & 1));
                    double sign = odd ? -1.0 : 1.0;
                    double *m = mom + (size_t)mom_index(e[0], e[1], e[2]) * 4;
                    for (int ch = 0; ch < 3; ch++) m[ch] += sign * canon[face][q][ch];
                }
    }
}

static void reduce_partials(const double *partial, int tasks, double *mom)
{
    memset(mom, 0, sizeof(double) * MOM_SIZE * 4);
    for (int t = 0; t < tasks; t++)
        for (int i = 0; i < MOM_SIZE * 4; i++) mom[i] += partial[(size_t)t * MOM_SIZE * 4 + i];
}

/* Fills the n x n table of exact texel solid angles from the (n+1)^2 grid of the corner
 * function F(u, v) = atan(uv / sqrt(1 + u^2 + v^2)) (Driscoll 2012), using F(u, v) = F(v, u)
 * and F(-u, v) = -F(u, v) so only one octant of atan2 calls is made. */
static void omega_table(int n, double *grid /* (n+1)^2 */, double *omega)
{
    int g = n + 1;
    /* canonical grid points: u >= 0, v >= 0 and u >= v */
    for (int j = (n + 1) / 2; j < g; j++) {
        for (int i = j; i < g; i++) {
            double u = 2.0 * i / n - 1.0, v = 2.0 * j / n - 1.0;
            grid[(size_t)j * g + i] = atan2(u * v, sqrt(u * u + v * v + 1.0));
        }
    }
    for (int j = 0; j < g; j++) {
        for (int i = 0; i < g; i++) {
            int ii = 2 * i < n ? n - i : i, jj = 2 * j < n ? n - j : j;
            double sgn = ((2 * i < n) ^ (2 * j < n)) ? -1.0 : 1.0;
            if (ii < jj) {
                int t = ii;
                ii = jj;
                jj = t;
            }
            if (ii != i || jj != j) grid[(size_t)j * g + i] = sgn * grid[(size_t)jj * g + ii];
        }
    }
    for (int y = 0; y < n; y++)
        for (int x = 0; x < n; x++)
            omega[(size_t)y * n + x] = grid[(size_t)(y + 1) * g + x + 1] - grid[(size_t)(y + 1) * g + x] -
                                       grid[(size_t)y * g + x + 1] + grid[(size_t)y * g + x];
}

ibl_status ibl_sh_plan_create(ibl_context *ctx, const ibl_sh_plan_desc *desc, ibl_sh_plan **out)
{
    if (!out || !desc) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    int face_size = desc->face_size, bands = clamp_bands(desc->bands);
    if (!ctx || face_size < 1 || face_size > 65536 || !valid_bands(bands))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sh: face size %d / bands %d out of range",
                        face_size, bands);
    ibl_sh_plan *p = ibl_calloc(ctx, 1, sizeof *p);
    if (!p) return ibl_context_status(ctx);
    p->ctx = ctx;
    p->n = face_size;
    p->bands = bands;
    p->deg = bands - 1;
    p->nw = bands * (bands + 1) / 2;
    p->simd = ibl__cpu_has(ctx, IBL__CPU_AVX2_FMA);
    /* chunking depends on the size only, never on the thread count */
    int half = (face_size + 1) / 2;
    p->tasks = half < 32 ? half : 32;
    p->rows_per_task = (half + p->tasks - 1) / p->tasks;
    p->tasks = (half + p->rows_per_task - 1) / p->rows_per_task;
    size_t n = (size_t)face_size;
    p->omega = ibl_alloc(ctx, n * n * sizeof(double));
    p->partial = ibl_alloc(ctx, (size_t)p->tasks * MOM_SIZE * 4 * sizeof(double));
    double *grid = ibl_alloc(ctx, (n + 1) * (n + 1) * sizeof(double));
    if (!p->omega || !p->partial || !grid) {
        ibl_free(ctx, grid);
        ibl_sh_plan_destroy(p);
        return ibl_context_status(ctx);
    }
    omega_table(face_size, grid, p->omega);
    ibl_free(ctx, grid);
    *out = p;
    return IBL_OK;
}

void ibl_sh_plan_destroy(ibl_sh_plan *p)
{
    if (!p) return;
    ibl_free(p->ctx, p->omega);
    ibl_free(p->ctx, p->partial);
    ibl_free(p->ctx, p);
}

/* Projects the six faces of edge p->n stored one after another (a cube's level). */
static void project_faces(ibl_sh_plan *p, const float *faces, ibl_sh *out)
{
    p->faces = faces;
    ibl_parallel_for(p->ctx, p->tasks, cube_task, p);
    p->faces = NULL;
    double mom[MOM_SIZE * 4];
    reduce_partials(p->partial, p->tasks, mom);
    moments_to_sh(mom, p->bands, out);
}

ibl_status ibl_sh_plan_run(ibl_sh_plan *p, const ibl_cubemap *cube, ibl_sh *out)
{
    if (!p || !cube || !cube->data || !out) return IBL_ERR_INVALID_ARGUMENT;
    if (cube->size != p->n)
        return ibl__fail(p->ctx, IBL_ERR_INVALID_ARGUMENT,
                         "sh: the plan is for faces of %d texels, not %d", p->n, cube->size);
    project_faces(p, cube->data, out);
    return IBL_OK;
}

ibl_status ibl_sh_project_cubemap(ibl_context *ctx, const ibl_cubemap *cube, int level, int bands,
                                  ibl_sh *out)
{
    if (!cube || !cube->data || !out || level < 0 || level >= cube->levels)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sh: no cubemap or level %d absent", level);
    ibl_sh_plan *p;
    ibl_sh_plan_desc pd = {.face_size = ibl_level_size(cube->size, level), .bands = bands};
    ibl_status st = ibl_sh_plan_create(ctx, &pd, &p);
    if (st != IBL_OK) return st;
    project_faces(p, ibl_cubemap_face(cube, level, 0), out);
    ibl_sh_plan_destroy(p);
    return IBL_OK;
}

/* ---- equirect ------------------------------------------------------------------------------ */

typedef struct equirect_job {
    const ibl_image *image;
    int deg, nw, rows_per_task, simd;
    const double *colw; /* per column: sin(a)^p (-cos(a))^r for p + r <= deg */
    double *partial;
} equirect_job;

static void equirect_task(void *arg, int task)
{
    const equirect_job *job = arg;
    int w = job->image->width, h = job->image->height, deg = job->deg, nw = job->nw;
    double *mom = job->partial + (size_t)task * MOM_SIZE * 4;
    memset(mom, 0, sizeof(double) * MOM_SIZE * 4);
    int y0 = task * job->rows_per_task, y1 = y0 + job->rows_per_task;
    if (y1 > h) y1 = h;
    double s[MAX_WEIGHTS][3];
    for (int y = y0; y < y1; y++) {
        /* exact solid angle of a pixel of this row: (2 pi / W) (cos theta0 - cos theta1) */
        double omega = ibl__equirect_row_solid_angle(w, h, y);
        double theta = IBL_PI * (y + 0.5) / h, st = sin(theta), ct = cos(theta);
        const float *px = ibl_image_texel(job->image, 0, y);
        row_sums(job->simd, job->colw, px, w, nw, s);
        /* x^p y^q z^r = (st sin a)^p ct^q (-st cos a)^r */
        int k = 0;
        for (int d = 0; d <= deg; d++) {
            for (int p = 0; p <= d; p++, k++) {
                int r = d - p;
                for (int q = 0; p + q + r <= deg; q++) {
                    double f = omega * pow(st, p + r) * pow(ct, q);
                    double *m = mom + (size_t)mom_index(p, q, r) * 4;
                    m[0] += f * s[k][0];
                    m[1] += f * s[k][1];
                    m[2] += f * s[k][2];
                }
            }
        }
    }
}

ibl_status ibl_sh_project_equirect(ibl_context *ctx, const ibl_image *image, int bands,
                                   ibl_sh *out)
{
    bands = clamp_bands(bands);
    if (!image || !image->pixels || image->width < 1 || image->height < 1 || !out ||
        !valid_bands(bands))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sh: bad equirect image or bands %d", bands);
    equirect_job job;
    job.image = image;
    job.deg = bands - 1;
    job.nw = bands * (bands + 1) / 2;
    job.simd = ibl__cpu_has(ctx, IBL__CPU_AVX2_FMA);
    int h = image->height, w = image->width;
    int tasks = h < 32 ? h : 32;
    job.rows_per_task = (h + tasks - 1) / tasks;
    tasks = (h + job.rows_per_task - 1) / job.rows_per_task;
    double *colw = ibl_alloc(ctx, (size_t)w * job.nw * sizeof(double));
    double *partial = ibl_alloc(ctx, (size_t)tasks * MOM_SIZE * 4 * sizeof(double));
    if (!colw || !partial) {
        ibl_free(ctx, colw);
        ibl_free(ctx, partial);
        return ibl_context_status(ctx);
    }
    for (int x = 0; x < w; x++) {
        /* library layout: u = 0.5 looks toward -Z, u = 0.75 toward +X */
        double a = 2.0 * IBL_PI * ((x + 0.5) / w - 0.5), sa = sin(a), nca = -cos(a);
        double *cw = colw + (size_t)x * job.nw;
        int k = 0;
        for (int d = 0; d <= job.deg; d++)
            for (int p = 0; p <= d; p++) cw[k++] = pow(sa, p) * pow(nca, d - p);
    }
    job.colw = colw;
    job.partial = partial;
    ibl_parallel_for(ctx, tasks, equirect_task, &job);
    double mom[MOM_SIZE * 4];
    reduce_partials(partial, tasks, mom);
    moments_to_sh(mom, bands, out);
    ibl_free(ctx, colw);
    ibl_free(ctx, partial);
    return IBL_OK;
}

/* ---- samples and face centres ---------------------------------------------------------------- */

ibl_status ibl_sh_project_samples(int bands, size_t count, const double *dirs,
                                  const double *weights, const float *rgb, size_t stride,
                                  ibl_sh *out)
{
    bands = clamp_bands(bands);
    if (!out || !valid_bands(bands) || (count && (!dirs || !weights || !rgb)) || stride < 3)
        return IBL_ERR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    out->bands = bands;
    double y[IBL_SH_MAX_COEFFS];
    for (size_t i = 0; i < count; i++) {
        ibl_sh_eval_basis(bands, dirs + 3 * i, y);
        const float *v = rgb + i * stride;
        for (int k = 0; k < bands * bands; k++)
            for (int c = 0; c < 3; c++) out->c[k][c] += weights[i] * y[k] * v[c];
    }
    return IBL_OK;
}

/* The six values determine bands 0 and 1 and the two band-2 functions that are even in every
 * axis (Y20, Y22); xy, yz, xz average to zero over every face and are lost. A plain 6-point
 * rule (weight 4 pi / 6 at each axis) is exact for bands 0 and 1 of point values but
 * overestimates band 2 by 2.5x; for face means it underestimates band 1 (x averages 0.8312
 * over its face) and overestimates band 2 by 1.378x. Dividing each band by that factor makes
 * the estimate exact for any radiance in span{Y00, Y1m, Y20, Y22} (docs/DIFFUSE.md). The
 * factors come from the face integrals J(p,q,n) = int u^p v^q (1+u^2+v^2)^(-(n+3)/2) du dv over
 * [-1,1]^2 (two-dimensional Gauss-Legendre, 120 nodes, converged to 1e-14). */
#define FACE_J000 2.0943951023931953 /* 2 pi / 3: a face's solid angle */
#define FACE_J001 1.7408395027342032 /* integral of the major-axis coordinate */
#define FACE_J002 1.4679320597172241 /* ... of its square                   */

/* SH from six per-face values (+X -X +Y -Y +Z -Z; RGBA, 4 floats apart). */
static ibl_status six_value_sh(const float *values, int means, int bands, ibl_sh *out)
{
    double dirs[18] = {0};
    double weights[6];
    for (int f = 0; f < 6; f++) {
        dirs[3 * f + face_axis[f][2]] = face_sign[f][2];
        weights[f] = 4.0 * IBL_PI / 6.0;
    }
    ibl_status st = ibl_sh_project_samples(bands < 3 ? bands : 3, 6, dirs, weights, values, 4, out);
    if (st != IBL_OK) return st;
    double band1, band2;
    if (means) {
        /* face mean of x on the +X face: J001 / J000; of Y20 on the z and side faces */
        double mx = FACE_J001 / FACE_J000, mz2 = FACE_J002 / FACE_J000, ms2 = (1.0 - mz2) / 2.0;
        band1 = 1.0 / mx;
        double y20_axis = 3.0 * mz2 - 1.0, y20_side = 3.0 * ms2 - 1.0;
        /* estimate / exact for Y20 = (2pi/3) K20^2 (2 * 2 * y20_axis + 4 * (-1) * y20_side) */
        band2 = 1.0 / (FACE_J000 * K20 * K20 * (4.0 * y20_axis - 4.0 * y20_side));
    } else {
        band1 = 1.0;
        band2 = 1.0 / 2.5; /* (2pi/3) K20^2 (2*2*2 + 4*1) = 2.5 */
    }
    for (int m = -1; m <= 1; m++)
        for (int c = 0; c < 3; c++) out->c[ibl_sh_index(1, m)][c] *= band1;
    for (int m = -2; m <= 2; m++)
        for (int c = 0; c < 3; c++) out->c[ibl_sh_index(2, m)][c] *= band2;
    out->bands = bands;
    return IBL_OK;
}

ibl_status ibl_sh_project_face_centres(const ibl_cubemap *cube, int level, int bands, ibl_sh *out)
{
    bands = clamp_bands(bands);
    if (!cube || !cube->data || level < 0 || level >= cube->levels || !out || !valid_bands(bands))
        return IBL_ERR_INVALID_ARGUMENT;
    float values[24];
    for (int f = 0; f < 6; f++) {
        float d[3] = {0, 0, 0};
        d[face_axis[f][2]] = (float)face_sign[f][2];
        ibl_vec3 v = {d[0], d[1], d[2]};
        ibl_cubemap_sample_bilinear(cube, level, v, values + 4 * f);
    }
    return six_value_sh(values, ibl_level_size(cube->size, level) == 1, bands, out);
}

ibl_status ibl_sh_project_face_means(const ibl_cubemap *cube, int level, int bands, ibl_sh *out)
{
    bands = clamp_bands(bands);
    if (!cube || !cube->data || level < 0 || level >= cube->levels || !out || !valid_bands(bands))
        return IBL_ERR_INVALID_ARGUMENT;
    int n = ibl_level_size(cube->size, level);
    float values[24];
    for (int f = 0; f < 6; f++) {
        const float *p = ibl_cubemap_face(cube, level, f);
        double acc[3] = {0, 0, 0}, wsum = 0;
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++, p += 4) {
                double w = ibl_cube_texel_solid_angle(n, x, y);
                for (int c = 0; c < 3; c++) acc[c] += w * p[c];
                wsum += w;
            }
        for (int c = 0; c < 3; c++) values[4 * f + c] = (float)(acc[c] / wsum);
        values[4 * f + 3] = 1.0f;
    }
    return six_value_sh(values, 1, bands, out);
}

/* ---- convolution and forms ---------------------------------------------------------------------- */

double ibl_sh_cosine_factor(int l)
{
    /* R&H 2001 eq. 8: A_1 = 2pi/3, odd l > 1 vanish, even l:
     * 2pi (-1)^(l/2 - 1) / ((l + 2)(l - 1)) * l! / (2^l ((l/2)!)^2) */
    if (l < 0) return 0;
    if (l == 0) return IBL_PI;
    if (l == 1) return 2.0 * IBL_PI / 3.0;
    if (l & 1) return 0;
    double fact_l = 1, fact_h = 1;
    for (int i = 2; i <= l; i++) fact_l *= i;
    for (int i = 2; i <= l / 2; i++) fact_h *= i;
    double sign = ((l / 2 - 1) & 1) ? -1.0 : 1.0;
    return 2.0 * IBL_PI * sign / ((l + 2.0) * (l - 1.0)) * fact_l / (ldexp(1.0, l) * fact_h * fact_h);
}

void ibl_sh_radiance_to_irradiance(const ibl_sh *radiance, ibl_sh *irradiance)
{
    ibl_sh r = *radiance;
    for (int l = 0; l < r.bands; l++) {
        double a = ibl_sh_cosine_factor(l);
        for (int m = -l; m <= l; m++)
            for (int c = 0; c < 3; c++) r.c[ibl_sh_index(l, m)][c] *= a;
    }
    *irradiance = r;
}

void ibl_sh_scale(ibl_sh *sh, double s)
{
    for (int i = 0; i < IBL_SH_MAX_COEFFS; i++)
        for (int c = 0; c < 3; c++) sh->c[i][c] *= s;
}

void ibl_sh_polynomial(const ibl_sh *radiance, double m[3][4][4])
{
    const double c1 = IBL_SH_RH_C1, c2 = IBL_SH_RH_C2, c3 = IBL_SH_RH_C3, c4 = IBL_SH_RH_C4,
                 c5 = IBL_SH_RH_C5;
    for (int ch = 0; ch < 3; ch++) {
        double L[9];
        for (int i = 0; i < 9; i++) L[i] = radiance->bands * radiance->bands > i ? radiance->c[i][ch] : 0;
        /* R&H 2001 eq. 12; indices: 0 L00, 1 L1-1, 2 L10, 3 L11, 4 L2-2, 5 L2-1, 6 L20, 7 L21, 8 L22 */
        double M[4][4] = {{c1 * L[8], c1 * L[4], c1 * L[7], c2 * L[3]},
                          {c1 * L[4], -c1 * L[8], c1 * L[5], c2 * L[1]},
                          {c1 * L[7], c1 * L[5], c3 * L[6], c2 * L[2]},
                          {c2 * L[3], c2 * L[1], c2 * L[2], c4 * L[0] - c5 * L[6]}};
        memcpy(m[ch], M, sizeof M);
    }
}

/* ---- windowing -------------------------------------------------------------------------------- */

enum { WINDOW_DIRECTIONS = 4096 };

/* Deterministic, nearly uniform direction set (Fibonacci sphere). */
static void fibonacci_direction(int i, int n, double d[3])
{
    const double golden = IBL_PI * (3.0 - sqrt(5.0));
    double z = 1.0 - (2.0 * i + 1.0) / n, r = sqrt(1.0 - z * z), phi = golden * i;
    d[0] = r * cos(phi);
    d[1] = r * sin(phi);
    d[2] = z;
}

double ibl_sh_min_irradiance(const ibl_sh *radiance)
{
    ibl_sh e;
    ibl_sh_radiance_to_irradiance(radiance, &e);
    double lo = INFINITY;
    for (int i = 0; i < WINDOW_DIRECTIONS; i++) {
        double d[3], v[3];
        fibonacci_direction(i, WINDOW_DIRECTIONS, d);
        ibl_sh_eval(&e, d, v);
        for (int c = 0; c < 3; c++)
            if (v[c] < lo) lo = v[c];
    }
    return lo;
}

static double hanning(int l, double width)
{
    if (l == 0) return 1.0;
    if (!(l < width)) return 0.0;
    return 0.5 * (1.0 + cos(IBL_PI * l / width));
}

static void windowed(const ibl_sh *in, double width, ibl_sh *out)
{
    *out = *in;
    for (int l = 1; l < in->bands; l++) {
        double h = hanning(l, width);
        for (int m = -l; m <= l; m++)
            for (int c = 0; c < 3; c++) out->c[ibl_sh_index(l, m)][c] *= h;
    }
}

ibl_status ibl_sh_apply_window(ibl_sh *radiance, ibl_sh_window window, double width,
                               ibl_sh_window_report *report)
{
    if (!radiance || !valid_bands(radiance->bands)) return IBL_ERR_INVALID_ARGUMENT;
    if (window == IBL_SH_WINDOW_HANNING && !(width > 0)) return IBL_ERR_INVALID_ARGUMENT;
    ibl_sh_window_report rep;
    memset(&rep, 0, sizeof rep);
    rep.min_irradiance_before = ibl_sh_min_irradiance(radiance);
    if (window == IBL_SH_WINDOW_AUTO) {
        if (rep.min_irradiance_before >= 0 || radiance->bands == 1) {
            window = IBL_SH_WINDOW_NONE;
        } else {
            /* bisection on s = 1/W: s = 1 keeps band 0 only (non-negative whenever L00 >= 0),
             * s -> 0 is no window; keep the feasible end so the result always passes the check */
            double s_bad = 0.0, s_ok = 1.0;
            for (int it = 0; it < 40; it++) {
                double s = 0.5 * (s_bad + s_ok);
                ibl_sh t;
                windowed(radiance, 1.0 / s, &t);
                if (ibl_sh_min_irradiance(&t) >= 0) s_ok = s;
                else s_bad = s;
            }
            window = IBL_SH_WINDOW_HANNING;
            width = 1.0 / s_ok;
        }
    }
    rep.applied = window;
    for (int l = 0; l < IBL_SH_MAX_BANDS; l++) rep.factors[l] = 1.0;
    if (window == IBL_SH_WINDOW_HANNING) {
        rep.width = width;
        for (int l = 0; l < IBL_SH_MAX_BANDS; l++) rep.factors[l] = hanning(l, width);
        ibl_sh t;
        windowed(radiance, width, &t);
        *radiance = t;
        rep.min_irradiance_after = ibl_sh_min_irradiance(radiance);
    } else {
        rep.min_irradiance_after = rep.min_irradiance_before;
    }
    if (report) *report = rep;
    return IBL_OK;
}
