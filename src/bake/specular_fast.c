/* The fast prefilter: a multilevel summation over a moment pyramid of the source.
 *
 * The lobe f(u), u = 1 - R.l, is split by a smooth partition of unity in u into a core
 * f phi_0 (u < 4 U0, U0 set by the lobe's half width) and dyadic rings f phi_j
 * (U0 4^(j-1) < u < U0 4^(j+1)): phi_0 = psi(u / U0), phi_j = psi(u / Uj) - psi(u / Uj-1),
 * psi a C2 step from 1 (t <= 1) to 0 (t >= 4), so that sum_j phi_j = 1 exactly. A ring is
 * smooth on the scale of its inner radius b, so it is summed over a source mip whose texels
 * are <= gamma b wide and evaluated on a cube grid whose spacing is <= beta b, then
 * bilinearly interpolated to the output texels. The core is summed over the finest source
 * level the lobe needs, directly at every output texel (edge-fixup directions included).
 * Cost per output texel is therefore a constant set by gamma and beta, not by the source
 * size: the far field of a heavy-tailed GGX lobe costs little because it is summed on coarse
 * grids from coarse mips.
 *
 * Every source texel carries its moments: solid angle, mean direction m (|m| < 1), the
 * covariance C of directions over it, and e = (1 - |m|^2) / 2; a coarse texel also carries
 * the same moments weighted by luminance and its power per channel. A texel contributes the
 * second-order Taylor expansion of the piece g about its centroid:
 *     int g(1 - R.l) dl ~ Omega (g(u0) + g''(u0) R^T C R / 2),  u0 = |R - m|^2 / 2 + e,
 * (u0 written so that it keeps float precision next to the lobe's axis). The numerator uses
 * the luminance-weighted moments (a point light lies exactly at its texel's centroid), the
 * normaliser the geometric ones (summed once per plan, on one eighth of a face: they depend
 * only on the cube's geometry), so that a constant environment stays constant. The AVX2 path
 * evaluates GGX and Phong in closed form; the portable path reads each piece (lobe times
 * partition) from a table in u with its second derivative. Phong texels whose spread reaches
 * the horizon, where x^n has a kink, take the closed-form mean of x^n over the spread.
 *
 * Most of the work is not leaf by leaf: a piece whose leaves use geometric moments only (the
 * core over the source texels, or a piece over a coarse level read as uniform texels) has
 * weights that depend on geometry alone; they are precomputed for one quadrant of face 0 and
 * carried to the rest by the cube's symmetries ("struct core"), and a run is a product of
 * weights and padded source rows. A coarse level read as uniform texels is then corrected
 * leaf by leaf where a texel's light is far from uniform (centroid corrections), and a ring on
 * a coarse grid leaves its bright texels to a direct sum at the output texels, where bilinear
 * interpolation would smear them (bright texels).
 * Deterministic: every output value is a sum in a fixed order, independent of the threads.
 * Design and measurements: docs/SPECULAR.md "The fast method". */
#include "specular_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "core/pixel_format.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

enum { BW = 4, BH = 2, BT = BW * BH }; /* a block: one 8-wide vector */
/* fields of a source block, BT floats each: the geometric moments, then level 0's radiance
 * or a coarse level's luminance-weighted moments and power */
enum { F_MX = 0, F_E = 3, F_C = 4, F_OM = 10, GEO_FIELDS = 11 };
enum { F_L = GEO_FIELDS, NF0 = GEO_FIELDS + 3 };
/* F_PD: the power of a texel that is not bright (0 for a bright one; see "bright texels") */
enum { F_WM = GEO_FIELDS, F_WE = F_WM + 3, F_WC = F_WM + 4, F_P = F_WM + 10, F_PD = F_P + 3, NFC = F_PD + 3 };
/* Bright texels: a split ring's grid may be spaced BETA_SPLIT of its inner radius because a
 * texel whose largest contribution to an output exceeds BRIGHT_TAU times the mean radiance is
 * summed at the output texels instead (at most BRIGHT_BLOCKS blocks of them per level). */
#define BETA_SPLIT 0.6
/* A ring summed by precomputed weights reads texels at most GAMMA_MAC of its inner radius (a
 * finer level than other rings: fewer centroid corrections; 0.3 and 0.6 were each slower at
 * one of 256 and 512, docs/SPECULAR.md) */
#define GAMMA_MAC 0.45
#define BRIGHT_TAU 0.02
/* ... at the output texels, or on a grid spaced at most BETA_BRIGHT of the ring's inner radius
 * when that is coarser (bilinear error ~(0.08 / 0.6)^2 of the 20-35% above) */
#define BETA_BRIGHT 0.08
enum { BRIGHT_BLOCKS = 256 };
/* A precomputed core over a coarse level treats its texels as uniform; a texel whose moment
 * leaf could differ from that by more than CORR_TAU times the mean radiance (relative to the
 * normaliser) is corrected at the output texels (at most CORR_BLOCKS blocks per level). */
#define CORR_TAU 1e-2
enum { CORR_BLOCKS = 2048 };
enum { BINFO = 6, TAB = 2048, TILE = 8, MAX_PIECES = 24, MAX_GRIDS = MAX_PIECES, CAND = 1024 };
/* gathered blocks (bright texels, corrections) are tested SUPER at a time first: a tile's
 * reach test against every gathered block was most of level 1's corrections at 512 */
enum { SUPER = 16 };
#define CONES(cap) ((size_t)(cap) + ((size_t)(cap) + SUPER - 1) / SUPER) /* blocks, then supers */

static const double LUM[3] = {0.2126, 0.7152, 0.0722}; /* Rec. 709 luminance */

typedef struct srclev {
    int M, nbx, nby, nf;
    float *rec;    /* 6 nby nbx blocks x nf fields x BT                     */
    float *block;  /* per block: centre direction (unit), angular radius r, cos r, sin r */
    /* run, coarse levels: the luminance power of each task's block row (6 nby), and their
     * sum in order (the bright and correction bars are relative to the mean radiance) */
    double *row_power, power;
    /* run, levels read by precomputed pieces: each texel as uniform light, its power over its
     * solid angle (rgb and a pad float, a cube face's layout), without its bright texels'
     * power for split rings (uni_dim); the padded sources gather from these */
    float *uni, *uni_dim;
    /* bright texels (levels read by split rings): their records gathered in blocks */
    double bright_c;     /* threshold on a texel's luminance power / mean radiance (0: unused) */
    int bright_cap, nbright; /* capacity and count of bright blocks                     */
    float *bright_rec, *bright_block;
    uint64_t *bright_order;  /* bright_cap BT: scratch of gather_texels                  */
} srclev;

typedef struct piece {
    int grid, src;
    double u_lo, u_hi, th_in, th_out;
    float t0, tscale;
    float *tab; /* (TAB + 2) x 2: g, g'' (the last entry zero) */
    /* GGX in closed form for the SIMD path: a2 = alpha^2, kap = (1 - alpha^2) / 2, a4 =
     * alpha^4; each psi as s = clamp(u sa - sb, 0, 1) with ds/du = sk */
    float a2, kap, a4, out_sa, out_sb, out_sk, in_sa, in_sb, in_sk;
    float n;  /* Phong exponent */
    int ggx;
    int split; /* a ring on a coarse grid without the bright texels, which go direct */
    int bright_grid; /* split: the grid its bright texels are summed on                */
    struct core *core; /* the core summed by precomputed weights (NULL: by leaves) */
} piece;

typedef struct grid {
    int n, direct; /* direct: the output level's own texels (edge-fixup directions) */
    int tiles;     /* tiles per face edge */
    float *acc;    /* 6 n n x 4: sum g P (rgb), sum g Omega */
    float *pad;    /* coarse grids: 6 (n + 2)^2 x 4, acc with a border of one texel taken across
                    * the edges (corner: the mean of its three texels), as the seamless
                    * bilinear sampler reads them */
} grid;

typedef struct level_plan {
    ibl__lobe lobe;
    int npieces, ngrids, tasks;
    piece pieces[MAX_PIECES];
    grid grids[MAX_GRIDS];
    int task_begin[MAX_GRIDS + 1];
} level_plan;

struct ibl_specular_plan {
    ibl_context *ctx;
    ibl_specular_desc desc;
    ibl_specular_info info;
    int S, K, SL, N, L; /* source edge, sub-texel split, pyramid levels (of S K) */
    srclev src[IBL_MAX_LEVELS];
    level_plan lv[IBL_MAX_LEVELS];
    float face_basis[6][3][3]; /* axis, s tangent, t tangent */
    ibl__dynamic *dyn; /* desc.dynamic: the precomputed operator instead of the pieces */
    /* level 0's geometric moments once, face-local (GEO_FIELDS floats per texel of face 0):
     * the other faces by the signed permutations. Level 0's records (src[0].rec) exist only
     * when some piece sums level 0 leaf by leaf (rec0). */
    float *geo0;
    int rec0;
    float *pad; /* run: the padded source of the precomputed piece being summed (6 x rgb x P P) */
    /* the gathered corrections of every core, one after the other: only the part a run uses
     * is touched (one buffer per core touched a fresh huge page each) */
    float *corr_pool;
    size_t corr_pool_blocks;
    int perm_ax[6][3]; /* face f's local (s, t, axis) -> world: world[i] = perm_sg[i] local[perm_ax[i]] */
    float perm_sg[6][3];
    int portable;      /* tests: the portable sums even where AVX2 is available          */
    const ibl_cubemap *run_src;
    ibl_cubemap *run_dst;
    int run_level;
};

static int is_pow2(int n) { return n > 0 && (n & (n - 1)) == 0; }

/* desc.accuracy relative to the default 0.35: scales every step and bar of the method */
static double accuracy_scale(const ibl_specular_plan *p)
{
    return p->desc.accuracy > 0 ? p->desc.accuracy / 0.35 : 1.0;
}

static size_t rec_index(const srclev *s, int face, int x, int y, int field)
{
    size_t b = ((size_t)face * s->nby + y / BH) * s->nbx + x / BW;
    return (b * s->nf + field) * BT + (y % BH) * BW + x % BW;
}

static size_t block_count(const srclev *s) { return (size_t)6 * s->nby * s->nbx; }

/* ---- pieces as precomputed weights ("core": first used for the cores over level 0) ---- */

/* When a piece's leaves use geometric moments only (the core over the source texels, K = 1, or
 * any piece over a coarse level read as uniform texels, corrected below), its weights depend
 * only on geometry, and the cube's symmetries carry them over: the weights of the points of one
 * quadrant of face 0 of its grid serve the four quadrants of all six faces (the maps x -> n-1-x, y -> n-1-y and the
 * signed permutations taking face 0 to face F are symmetries of the cube and of its texels).
 * They are stored as rows over the *padded* face: the face with a border W deep taken from its
 * four neighbours unfolded about the shared edges (the corner squares of the border are empty),
 * so that texels across an edge stay in rows. A run is then a plain product of those rows with
 * the padded source: no lobe evaluation, ~10x cheaper per texel than a leaf. */
struct core {
    int level;             /* the source level it sums (0: the source texels)                       */
    int direct, dim;       /* on the output texels (edge-fixup directions) / without bright texels   */
    int S, W, P, O, n, nb; /* source edge, border, padded edge, offset of cell 0, output edge, base edge */
    int32_t *map;          /* P P: face 0's source texel (f S S + y S + x) or -1                     */
    /* bases below the diagonal (a > b) have no weights of their own: base (a, b)'s weights
     * are (b, a)'s transposed (the cube's reflection x <-> y), applied to the transposed
     * padded source; so the plan computes and keeps half of them */
    int carry[6][6][7];    /* face F: where face 0's map entries on face g go (see carry_face)       */
    uint32_t *row0;        /* nb nb + 1: each base texel's first row                                 */
    size_t *w0;            /* nb nb + 1: each base texel's first weight                              */
    int32_t *rows;         /* per row: y, x (padded coordinates), len (a multiple of 8)              */
    /* per 8 weights: the padded cell (x + O, y + O) of the first; base i's are from w0[i] / 8.
     * One loop over a base's vectors has a steady trip count, where the rows' short loops
     * (3-5 vectors) mispredicted their exits */
    uint16_t *vec;
    uint16_t *w;           /* half floats, times wscale: the weights (half the memory of floats)     */
    float wscale;          /* an upper bound of the weights: stored values are at most ~1            */
    double *den;           /* nb nb: sum of the weights (as stored)                                  */
    /* centroid corrections (a coarse level's texels are summed as uniform): each texel whose
     * moment leaf may differ from its uniform one by more than CORR_TAU (bound a1 |dm| + a2 |de|
     * + a3 |dC| per unit of luminance power) is left out of the padded source and summed at
     * the grid points as a leaf at its luminance moments */
    double a1, a2, a3;
    int corr_cap, ncorr;
    float *corr_rec;       /* run: in p->corr_pool, after the cores gathered before this one       */
    float *corr_block;
    uint64_t *corr_order;  /* corr_cap BT: scratch of gather_texels                         */
    float *bound;          /* run: each texel's bound (block order)                                  */
    float corr_thr;        /* run: the texels over it are summed as leaves, left out of the padded source */
};

enum { CORE_GEO = 12 }; /* geometry fields of a padded cell: GEO_FIELDS, then |m| */

static void core_destroy(ibl_context *ctx, struct core *c)
{
    if (!c) return;
    ibl_free(ctx, c->map);
    ibl_free(ctx, c->row0);
    ibl_free(ctx, c->w0);
    ibl_free(ctx, c->rows);
    ibl_free(ctx, c->vec);
    ibl_free(ctx, c->w);
    ibl_free(ctx, c->den);
    ibl_free(ctx, c->corr_order);
    ibl_free(ctx, c->corr_block);
    ibl_free(ctx, c->bound);
    ibl_free(ctx, c);
}

/* The source texel under padded cell (X, Y) of face f (-1 in the border's corner squares): a
 * border cell k texels beyond an edge is the neighbour's texel k texels in from that edge. */
static int32_t core_cell_texel(const ibl_specular_plan *p, int S, int f, int X, int Y)
{
    int outx = X < 0 || X >= S, outy = Y < 0 || Y >= S;
    if (outx && outy) return -1;
    if (!outx && !outy) return (int32_t)(((size_t)f * S + Y) * S + X);
    /* local (u, v, w) of the point: the edge point, then depth delta along -axis */
    double u, v, depth;
    if (outx) {
        int k = X < 0 ? -1 - X : X - S;
        u = X < 0 ? -1.0 : 1.0, v = -1.0 + (2.0 * Y + 1.0) / S, depth = (2.0 * k + 1.0) / S;
    } else {
        int k = Y < 0 ? -1 - Y : Y - S;
        v = Y < 0 ? -1.0 : 1.0, u = -1.0 + (2.0 * X + 1.0) / S, depth = (2.0 * k + 1.0) / S;
    }
    if (depth >= 2.0) return -1;
    const float(*B)[3] = p->face_basis[f];
    double d[3], s, t;
    for (int i = 0; i < 3; i++) d[i] = B[0][i] * (1.0 - depth) + B[1][i] * u + B[2][i] * v;
    int g = ibl_cube_face_st_d(d, &s, &t);
    int x = (int)floor(s * S), y = (int)floor(t * S);
    x = x < 0 ? 0 : x >= S ? S - 1 : x;
    y = y < 0 ? 0 : y >= S ? S - 1 : y;
    return (int32_t)(((size_t)g * S + y) * S + x);
}


/* ---- the partition of unity and the tabulated pieces ---- */

/* psi(t): 1 for t <= 1, 0 for t >= 4, the quintic smootherstep between (C2). */
static void psi012(double t, double scale, double out[3])
{
    double s = (t - 1.0) / 3.0;
    if (s <= 0.0) {
        out[0] = 1.0, out[1] = out[2] = 0.0;
        return;
    }
    if (s >= 1.0) {
        out[0] = out[1] = out[2] = 0.0;
        return;
    }
    double S = s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
    double S1 = 30.0 * s * s * (1.0 - s) * (1.0 - s);
    double S2 = 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s);
    double k = 1.0 / (3.0 * scale); /* ds/du */
    out[0] = 1.0 - S;
    out[1] = -S1 * k;
    out[2] = -S2 * k * k;
}

/* g = f phi and g'' in u for piece (inner scale a, outer scale b; a = 0: core). */
static void piece_g(const ibl__lobe *lobe, double a, double b, double u, double out[2])
{
    double f[3];
    ibl__lobe_f012(lobe, 1.0 - u, f);
    /* derivatives in u = 1 - x: f_u = -f_x, f_uu = f_xx */
    double f0 = f[0], f1 = -f[1], f2 = f[2];
    double po[3] = {1, 0, 0}, pi[3] = {0, 0, 0};
    if (b > 0) psi012(u / b, b, po);
    if (a > 0) psi012(u / a, a, pi);
    double p0 = po[0] - pi[0], p1 = po[1] - pi[1], p2 = po[2] - pi[2];
    out[0] = f0 * p0;
    out[1] = f2 * p0 + 2.0 * f1 * p1 + f0 * p2;
}

static ibl_status make_table(ibl_context *ctx, const ibl__lobe *lobe, double a, double b,
                             piece *p)
{
    p->tab = ibl_alloc(ctx, (size_t)(TAB + 2) * 2 * sizeof(float));
    if (!p->tab) return ibl_context_status(ctx);
    double step = (p->u_hi - p->u_lo) / TAB;
    for (int i = 0; i <= TAB; i++) {
        double g[2];
        piece_g(lobe, a, b, p->u_lo + i * step, g);
        p->tab[2 * i] = (float)g[0];
        p->tab[2 * i + 1] = (float)g[1];
    }
    p->tab[2 * TAB + 2] = p->tab[2 * TAB + 3] = 0.0f;
    p->t0 = (float)p->u_lo;
    p->tscale = (float)(TAB / (p->u_hi - p->u_lo));
    p->ggx = lobe->kind == IBL__LOBE_GGX;
    p->n = (float)lobe->n;
    double al2 = lobe->alpha * lobe->alpha;
    p->a2 = (float)al2;
    p->kap = (float)(0.5 * (1.0 - al2));
    p->a4 = (float)(al2 * al2);
    /* an absent outer step is psi = 1 (s = 0), an absent inner one psi = 0 (s = 1) */
    p->out_sa = b > 0 ? (float)(1.0 / (3.0 * b)) : 0.0f;
    p->out_sb = b > 0 ? (float)(1.0 / 3.0) : 1.0f;
    p->out_sk = p->out_sa;
    p->in_sa = a > 0 ? (float)(1.0 / (3.0 * a)) : 0.0f;
    p->in_sb = a > 0 ? (float)(1.0 / 3.0) : -2.0f;
    p->in_sk = p->in_sa;
    return IBL_OK;
}

/* ---- geometry: moments of every texel of every source level ---- */

typedef struct geo {
    double m[3], e, c[6], om; /* c: xx yy zz xy xz yz */
} geo;

/* Face-local moments of level-0 texels by 4x4 Gauss-Legendre on the face plane. */
static void texel_geo(int n, int x, int y, geo *g)
{
    static const double gx[4] = {-0.861136311594052575, -0.339981043584856265,
                                 0.339981043584856265, 0.861136311594052575};
    static const double gw[4] = {0.347854845137453857, 0.652145154862546143,
                                 0.652145154862546143, 0.347854845137453857};
    double h = 2.0 / n, u0 = -1.0 + x * h, v0 = -1.0 + y * h;
    double l[16][3], w[16], W = 0, m[3] = {0, 0, 0};
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            double u = u0 + 0.5 * h * (1.0 + gx[i]), v = v0 + 0.5 * h * (1.0 + gx[j]);
            double r2 = 1.0 + u * u + v * v, r = sqrt(r2);
            int k = j * 4 + i;
            w[k] = gw[i] * gw[j] / (r2 * r);
            l[k][0] = u / r, l[k][1] = v / r, l[k][2] = 1.0 / r;
            W += w[k];
            for (int c = 0; c < 3; c++) m[c] += w[k] * l[k][c];
        }
    for (int c = 0; c < 3; c++) g->m[c] = m[c] / W;
    memset(g->c, 0, sizeof g->c);
    double e = 0;
    for (int k = 0; k < 16; k++) {
        double d[3] = {l[k][0] - g->m[0], l[k][1] - g->m[1], l[k][2] - g->m[2]};
        double ww = w[k] / W;
        g->c[0] += ww * d[0] * d[0], g->c[1] += ww * d[1] * d[1], g->c[2] += ww * d[2] * d[2];
        g->c[3] += ww * d[0] * d[1], g->c[4] += ww * d[0] * d[2], g->c[5] += ww * d[1] * d[2];
        e += ww * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }
    g->e = 0.5 * e; /* 1 - |m|^2 = E |l - m|^2 for unit l */
    g->om = ibl_cube_texel_solid_angle(n, x, y);
}

/* Moments of a union from its parts (weights w): the parallel-axis rule. */
static void combine(const geo *const *parts, const double *w, int count, geo *out)
{
    double W = 0, m[3] = {0, 0, 0};
    for (int k = 0; k < count; k++) {
        W += w[k];
        for (int c = 0; c < 3; c++) m[c] += w[k] * parts[k]->m[c];
    }
    memset(out, 0, sizeof *out);
    if (!(W > 0)) return;
    for (int c = 0; c < 3; c++) out->m[c] = m[c] / W;
    for (int k = 0; k < count; k++) {
        const geo *p = parts[k];
        double a = w[k] / W, d[3] = {p->m[0] - out->m[0], p->m[1] - out->m[1], p->m[2] - out->m[2]};
        out->c[0] += a * (p->c[0] + d[0] * d[0]);
        out->c[1] += a * (p->c[1] + d[1] * d[1]);
        out->c[2] += a * (p->c[2] + d[2] * d[2]);
        out->c[3] += a * (p->c[3] + d[0] * d[1]);
        out->c[4] += a * (p->c[4] + d[0] * d[2]);
        out->c[5] += a * (p->c[5] + d[1] * d[2]);
        out->e += a * (p->e + 0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    }
}

/* The signed permutation taking face-local (s, t, axis) coordinates to world coordinates on
 * face f: world[i] = sign[i] local[axis[i]] (the face basis is made of signed unit vectors). */
static void face_perm(const ibl_specular_plan *p, int f, int axis[3], double sign[3])
{
    const float(*B)[3] = p->face_basis[f];
    for (int i = 0; i < 3; i++) {
        axis[i] = 0, sign[i] = 1.0;
        /* local columns: s tangent B[1], t tangent B[2], axis B[0] */
        const float col[3] = {B[1][i], B[2][i], B[0][i]};
        for (int k = 0; k < 3; k++)
            if (col[k] != 0.0f) axis[i] = k, sign[i] = col[k] > 0 ? 1.0 : -1.0;
    }
}

/* Writes the geometric fields of texel (x, y) of every face from face-local moments. */
static void store_geo(srclev *s, const int ax[6][3], const double sg[6][3], int x, int y, const geo *g)
{
    /* local covariance as a matrix (c: xx yy zz xy xz yz) */
    const double Cl[3][3] = {{g->c[0], g->c[3], g->c[4]}, {g->c[3], g->c[1], g->c[5]},
                             {g->c[4], g->c[5], g->c[2]}};
    static const int ci[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    for (int f = 0; f < 6; f++) {
        /* the fields of one texel are BT floats apart */
        float *r = s->rec + rec_index(s, f, x, y, 0);
        for (int c = 0; c < 3; c++) r[(F_MX + c) * BT] = (float)(sg[f][c] * g->m[ax[f][c]]);
        r[F_E * BT] = (float)g->e;
        for (int c = 0; c < 6; c++) {
            int i = ci[c][0], j = ci[c][1];
            r[(F_C + c) * BT] = (float)(sg[f][i] * sg[f][j] * Cl[ax[f][i]][ax[f][j]]);
        }
        r[F_OM * BT] = (float)g->om;
    }
}

typedef struct geo_job {
    ibl_specular_plan *p;
    srclev *s;
    geo *g;
    int n;
    const geo *fine; /* texel_combine_task: the level below */
} geo_job;

/* Row b of one eighth of the face: texels (a, b), a <= b < ceil(n / 2). */
static void texel_geo_task(void *arg, int b)
{
    const geo_job *j = arg;
    for (int a = 0; a <= b; a++) texel_geo(j->n, a, b, &j->g[(size_t)b * j->n + a]);
}

/* Row y of the face from its eighth: the reflections s -> -s, t -> -t and the swap s <-> t
 * are symmetries of the face, and they act on the moments by sign flips and swaps. */
static void texel_geo_fill_task(void *arg, int y)
{
    const geo_job *j = arg;
    int n = j->n;
    for (int x = 0; x < n; x++) {
        int fx = x > n - 1 - x, fy = y > n - 1 - y;
        int a = fx ? n - 1 - x : x, b = fy ? n - 1 - y : y, sw = a > b;
        if (sw) {
            int t = a;
            a = b, b = t;
        }
        if (!fx && !fy && !sw) continue;
        geo g = j->g[(size_t)b * n + a];
        if (sw) { /* back from the eighth: swap s and t first */
            double t = g.m[0];
            g.m[0] = g.m[1], g.m[1] = t;
            t = g.c[0], g.c[0] = g.c[1], g.c[1] = t;
            t = g.c[4], g.c[4] = g.c[5], g.c[5] = t;
        }
        if (fx) g.m[0] = -g.m[0], g.c[3] = -g.c[3], g.c[4] = -g.c[4];
        if (fy) g.m[1] = -g.m[1], g.c[3] = -g.c[3], g.c[5] = -g.c[5];
        j->g[(size_t)y * n + x] = g;
    }
}

/* Row y of a level's moments from its children (the parallel-axis rule). */
static void texel_combine_task(void *arg, int y)
{
    const geo_job *j = arg;
    int M = j->n;
    const geo *fine = j->fine;
    for (int x = 0; x < M; x++) {
        const geo *parts[4];
        double w[4];
        for (int k = 0; k < 4; k++) {
            parts[k] = &fine[(size_t)(2 * y + (k >> 1)) * (2 * M) + 2 * x + (k & 1)];
            w[k] = parts[k]->om;
        }
        combine(parts, w, 4, &j->g[(size_t)y * M + x]);
        j->g[(size_t)y * M + x].om = w[0] + w[1] + w[2] + w[3];
    }
}

static void store_geo_row(void *arg, int y)
{
    const geo_job *j = arg;
    int ax[6][3];
    double sg[6][3];
    for (int f = 0; f < 6; f++) face_perm(j->p, f, ax[f], sg[f]);
    for (int x = 0; x < j->n; x++)
        store_geo(j->s, (const int(*)[3])ax, (const double(*)[3])sg, x, y, &j->g[(size_t)y * j->n + x]);
}

/* The bounding cones of block row `by` on every face: computed on face 0 and carried to the
 * others by the signed permutation between the faces. */
static void block_cone_task(void *arg, int by)
{
    const geo_job *j = arg;
    srclev *s = j->s;
    int M = s->M, ax0[3], ax[3];
    double h = 2.0 / M, sg0[3], sg[3];
    face_perm(j->p, 0, ax0, sg0);
    for (int bx = 0; bx < s->nbx; bx++) {
        int x1 = (bx + 1) * BW < M ? (bx + 1) * BW : M;
        int y1 = (by + 1) * BH < M ? (by + 1) * BH : M;
        double c[3], local[3];
        double r = ibl__rect_radius(0, bx * BW * h - 1, by * BH * h - 1, x1 * h - 1, y1 * h - 1, c);
        for (int i = 0; i < 3; i++) local[ax0[i]] = sg0[i] * c[i];
        for (int f = 0; f < 6; f++) {
            face_perm(j->p, f, ax, sg);
            float *b = s->block + (((size_t)f * s->nby + by) * s->nbx + bx) * BINFO;
            for (int i = 0; i < 3; i++) b[i] = (float)(sg[i] * local[ax[i]]);
            b[3] = (float)(r + 1e-6);
            b[4] = (float)cos(r + 1e-6);
            b[5] = (float)sin(r + 1e-6);
        }
    }
}

/* Row y of level 0's face-local moments (floats, as the records would hold them). */
static void store_geo0_task(void *arg, int y)
{
    const geo_job *j = arg;
    for (int x = 0; x < j->n; x++) {
        const geo *g = &j->g[(size_t)y * j->n + x];
        float *o = j->p->geo0 + ((size_t)y * j->n + x) * GEO_FIELDS;
        for (int c = 0; c < 3; c++) o[F_MX + c] = (float)g->m[c];
        o[F_E] = (float)g->e;
        for (int c = 0; c < 6; c++) o[F_C + c] = (float)g->c[c];
        o[F_OM] = (float)g->om;
    }
}

/* The geometric fields of level-0 texel (f, x, y) in world coordinates (the same floats as
 * its records would hold: the permutation only moves and negates them). */
static void geo0_world(const ibl_specular_plan *p, int f, int x, int y, float out[GEO_FIELDS])
{
    static const int ci[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    const float *g = p->geo0 + ((size_t)y * p->src[0].M + x) * GEO_FIELDS;
    const int *ax = p->perm_ax[f];
    const float *sg = p->perm_sg[f];
    /* local covariance (xx yy zz xy xz yz) as a matrix */
    const float Cl[3][3] = {{g[F_C], g[F_C + 3], g[F_C + 4]}, {g[F_C + 3], g[F_C + 1], g[F_C + 5]},
                            {g[F_C + 4], g[F_C + 5], g[F_C + 2]}};
    for (int c = 0; c < 3; c++) out[F_MX + c] = sg[c] * g[F_MX + ax[c]];
    out[F_E] = g[F_E];
    for (int c = 0; c < 6; c++) {
        int i = ci[c][0], k = ci[c][1];
        out[F_C + c] = sg[i] * sg[k] * Cl[ax[i]][ax[k]];
    }
    out[F_OM] = g[F_OM];
}

static void store_rec0_row(void *arg, int y)
{
    const ibl_specular_plan *p = arg;
    const srclev *s = &p->src[0];
    for (int f = 0; f < 6; f++)
        for (int x = 0; x < s->M; x++) {
            float v[GEO_FIELDS];
            geo0_world(p, f, x, y, v);
            float *r = s->rec + rec_index(s, f, x, y, 0);
            for (int k = 0; k < GEO_FIELDS; k++) r[k * BT] = v[k];
        }
}

/* Records are stored in blocks of BH rows: a task takes a whole block row, so that two threads
 * never write the same cache lines (rows y and y + 1 share blocks). */
static void store_geo_task(void *arg, int yb)
{
    const geo_job *j = arg;
    for (int y = yb * BH; y < (yb + 1) * BH && y < j->n; y++) store_geo_row(arg, y);
}

static void store_rec0_task(void *arg, int yb)
{
    const ibl_specular_plan *p = arg;
    for (int y = yb * BH; y < (yb + 1) * BH && y < p->src[0].M; y++) store_rec0_row(arg, y);
}

/* Level 0's records, for the pieces that sum it leaf by leaf. */
static ibl_status level0_records(ibl_specular_plan *p)
{
    srclev *s = &p->src[0];
    ibl_context *ctx = p->ctx;
    s->rec = s->M % BW || s->M % BH ? ibl_calloc(ctx, block_count(s) * s->nf * BT, sizeof(float))
                                    : ibl_alloc(ctx, block_count(s) * s->nf * BT * sizeof(float));
    s->block = ibl_alloc(ctx, block_count(s) * BINFO * sizeof(float));
    if (!s->rec || !s->block) return ibl_context_status(ctx);
    ibl_parallel_for(ctx, s->nby, store_rec0_task, p);
    geo_job job = {p, s, NULL, s->M, NULL};
    ibl_parallel_for(ctx, s->nby, block_cone_task, &job);
    p->rec0 = 1;
    return IBL_OK;
}

static ibl_status build_geometry(ibl_specular_plan *p)
{
    ibl_context *ctx = p->ctx;
    int S = p->S * p->K;
    geo *cur = ibl_alloc(ctx, (size_t)S * S * sizeof(geo));
    geo *next = ibl_alloc(ctx, (size_t)(S > 1 ? S / 2 : 1) * (S > 1 ? S / 2 : 1) * sizeof(geo));
    if (!cur || !next) {
        ibl_free(ctx, cur);
        ibl_free(ctx, next);
        return ibl_context_status(ctx);
    }
    p->geo0 = ibl_alloc(ctx, (size_t)S * S * GEO_FIELDS * sizeof(float));
    if (!p->geo0) {
        ibl_free(ctx, cur);
        ibl_free(ctx, next);
        return ibl_context_status(ctx);
    }
    geo_job first = {p, NULL, cur, S, NULL};
    ibl_parallel_for(ctx, (S + 1) / 2, texel_geo_task, &first);
    ibl_parallel_for(ctx, S, texel_geo_fill_task, &first);
    for (int l = 0; l < p->SL; l++) {
        srclev *s = &p->src[l];
        int M = s->M;
        if (l > 0) {
            geo_job cj = {p, s, next, M, cur};
            ibl_parallel_for(ctx, M, texel_combine_task, &cj);
            geo *t = cur;
            cur = next;
            next = t;
        }
        geo_job job = {p, s, cur, M, NULL};
        if (l == 0) {
            ibl_parallel_for(ctx, M, store_geo0_task, &job);
            continue;
        }
        ibl_parallel_for(ctx, s->nby, store_geo_task, &job);
        ibl_parallel_for(ctx, s->nby, block_cone_task, &job);
    }
    ibl_free(ctx, cur);
    ibl_free(ctx, next);
    return IBL_OK;
}

/* ---- the plan: pieces, grids, tasks ---- */

/* the mean angular size of a texel of a face of edge n (sqrt(4 pi / 6) / n); the texels at a
 * face centre are 1.38 times wider, those at its corners 1.7 times narrower */
static double texel_angle(int n) { return 1.4472025 / n; }

/* The coarsest source level whose texels are at most `width` wide (0 if none is) and whose
 * faces are at least min_edge texels (wide lobes are cheap; coarse texels across the horizon,
 * where the lobe has a kink, are what a Taylor leaf gets wrong). */
static int source_level_for(const ibl_specular_plan *p, double width, int min_edge)
{
    int best = 0;
    for (int l = 0; l < p->SL; l++)
        if (texel_angle(p->src[l].M) <= width && p->src[l].M >= min_edge) best = l;
    return best;
}

static int grid_index(level_plan *lv, int n, int direct, int tile_edge)
{
    for (int g = 0; g < lv->ngrids; g++)
        if (lv->grids[g].n == n && lv->grids[g].direct == direct) return g;
    grid *g = &lv->grids[lv->ngrids];
    g->n = n;
    g->direct = direct;
    g->tiles = (n + tile_edge - 1) / tile_edge;
    return lv->ngrids++;
}

/* Whether the output directions are the texel centres (no edge fixup bends them). */
static int centred_directions(const ibl_specular_plan *p)
{
    return p->desc.edge_fixup != IBL_EDGE_FIXUP_BENT && p->desc.edge_fixup != IBL_EDGE_FIXUP_WARP;
}

static ibl_status plan_level(ibl_specular_plan *p, int level)
{
    level_plan *lv = &p->lv[level];
    const ibl__lobe *lobe = &lv->lobe;
    int n = ibl_level_size(p->N, level);
    double acc = accuracy_scale(p);
    /* measured on the six test HDRIs at 128 and 256 against the reference (docs/SPECULAR.md
     * "Accuracy"): these keep every level of ggx, phong and blinn within 0.44% RMS and 3.2%
     * max; accuracy 0.175 (half the default) brings the max to 2.0% at 2-5 times the cost */
    const double kappa = 2.5 / acc; /* core source texels per lobe half width      */
    const double c0 = 2.0;          /* the core ends (psi starts) at c0 half widths */
    const double gamma = 0.6 * acc; /* ring source texel / ring inner radius        */
    const double beta = 0.2 * acc;  /* ring grid spacing / ring inner radius        */
    const double beta_split = BETA_SPLIT * acc; /* the same without the bright texels */
    const double cull = lobe->kind == IBL__LOBE_PHONG ? 1e-9 : 0.0;

    int core_src = source_level_for(p, lobe->half_angle / kappa, 16);
    double b0 = c0 * lobe->half_angle;
    double min_b0 = 2.0 * texel_angle(p->src[core_src].M);
    if (b0 < min_b0) b0 = min_b0;
    double U = 1.0 - cos(b0 < IBL_PI ? b0 : IBL_PI);
    lv->ngrids = 0;
    lv->npieces = 0;
    double prevU = 0.0, inner[MAX_PIECES]; /* each piece's inner step scale (0: none) */
    for (int j = 0; j < MAX_PIECES; j++) {
        piece *pc = &lv->pieces[lv->npieces];
        memset(pc, 0, sizeof *pc);
        double outerU = U;            /* psi(u / U) ends at 4 U */
        int last = (outerU >= 1.0) || j == MAX_PIECES - 1;
        pc->u_lo = prevU;
        pc->u_hi = last ? 2.0 : 4.0 * outerU;
        if (pc->u_hi > 2.0) pc->u_hi = 2.0;
        pc->th_in = acos(1.0 - pc->u_lo);
        pc->th_out = acos(1.0 - (pc->u_hi < 2.0 ? pc->u_hi : 2.0));
        /* a Phong tail far below the peak is dropped (its weight is below `cull`) */
        if (cull > 0 && j > 0 && ibl__lobe_f(lobe, 1.0 - pc->u_lo) < cull) break;
        if (j == 0) {
            pc->src = core_src;
            pc->grid = grid_index(lv, n, 1, TILE);
        } else {
            double b = pc->th_in;
            int mac = centred_directions(p) && acos(1.0 - (pc->u_hi < 2.0 ? pc->u_hi : 2.0)) < 1.1;
            pc->src = source_level_for(p, (mac ? GAMMA_MAC * acc : gamma) * b, 16);
            /* a ring summed from a coarse level leaves its bright texels to a direct sum, so
             * that its grid may be coarser (see "bright texels") */
            int split = pc->src > 0;
            int gn = 1;
            while (texel_angle(gn) > (split ? beta_split : beta) * b) gn *= 2;
            if (gn < 8) gn = 8;
            if (gn >= n) {
                pc->grid = grid_index(lv, n, 1, TILE);
            } else {
                pc->grid = grid_index(lv, gn, 0, TILE);
                pc->split = split;
                int bn = 8;
                while (bn < n && texel_angle(bn) > BETA_BRIGHT * acc * b) bn *= 2;
                pc->bright_grid = bn >= n ? grid_index(lv, n, 1, TILE) : grid_index(lv, bn, 0, TILE);
            }
        }
        /* a ring over the same source level and grid as the ring before it (the far rings,
         * once both reach the coarsest level) joins it: their sum is one piece, the lobe
         * between the first one's inner step and this one's outer step, summed once */
        piece *prev = lv->npieces > 1 ? pc - 1 : NULL;
        if (prev && prev->src == pc->src && prev->grid == pc->grid && prev->split == pc->split) {
            prev->u_hi = pc->u_hi;
            prev->th_out = pc->th_out;
            ibl_free(p->ctx, prev->tab);
            prev->tab = NULL;
            ibl_status st = make_table(p->ctx, lobe, inner[lv->npieces - 1], last ? 0.0 : outerU, prev);
            if (st != IBL_OK) return st;
        } else {
            inner[lv->npieces] = j == 0 ? 0.0 : prevU;
            ibl_status st = make_table(p->ctx, lobe, inner[lv->npieces], last ? 0.0 : outerU, pc);
            if (st != IBL_OK) return st;
            lv->npieces++;
        }
        if (last) break;
        prevU = U;
        U *= 4.0;
    }
    lv->tasks = 0;
    for (int g = 0; g < lv->ngrids; g++) {
        grid *gr = &lv->grids[g];
        lv->task_begin[g] = lv->tasks;
        lv->tasks += 6 * gr->tiles * gr->tiles;
        gr->acc = ibl_alloc(p->ctx, (size_t)6 * gr->n * gr->n * 4 * sizeof(float));
        if (!gr->acc) return ibl_context_status(p->ctx);
        if (!gr->direct) {
            gr->pad = ibl_alloc(p->ctx, (size_t)6 * (gr->n + 2) * (gr->n + 2) * 4 * sizeof(float));
            if (!gr->pad) return ibl_context_status(p->ctx);
        }
    }
    lv->task_begin[lv->ngrids] = lv->tasks;
    return IBL_OK;
}

static void plan_denominators(ibl_specular_plan *p, int level);
static ibl_status core_create(ibl_specular_plan *p, int level);
static ibl_status plan_bright(ibl_specular_plan *p, int level);
static ibl_status core_build_weights(ibl_specular_plan *p, int level);

void ibl_specular_plan_destroy(ibl_specular_plan *p)
{
    if (!p) return;
    ibl_context *ctx = p->ctx;
    ibl__dynamic_destroy(p->dyn);
    ibl_free(ctx, p->geo0);
    ibl_free(ctx, p->pad);
    ibl_free(ctx, p->corr_pool);
    for (int l = 0; l < IBL_MAX_LEVELS; l++) {
        ibl_free(ctx, p->src[l].rec);
        ibl_free(ctx, p->src[l].block);
        ibl_free(ctx, p->src[l].row_power);
        ibl_free(ctx, p->src[l].uni);
        ibl_free(ctx, p->src[l].uni_dim);
        ibl_free(ctx, p->src[l].bright_rec);
        ibl_free(ctx, p->src[l].bright_order);
        ibl_free(ctx, p->src[l].bright_block);
        for (int k = 0; k < p->lv[l].npieces; k++) {
            ibl_free(ctx, p->lv[l].pieces[k].tab);
            core_destroy(ctx, p->lv[l].pieces[k].core);
        }
        for (int g = 0; g < p->lv[l].ngrids; g++) {
            ibl_free(ctx, p->lv[l].grids[g].acc);
            ibl_free(ctx, p->lv[l].grids[g].pad);
        }
    }
    ibl_free(ctx, p);
}

void ibl__specular_plan_set_portable(ibl_specular_plan *p, int portable)
{
    p->portable = portable;
    if (!p->dyn)
        for (int l = 0; l < p->L; l++)
            if (p->lv[l].lobe.kind != IBL__LOBE_MIRROR) {
                core_build_weights(p, l);
                plan_denominators(p, l);
            }
}

const ibl_specular_info *ibl_specular_plan_info(const ibl_specular_plan *plan)
{
    return plan ? &plan->info : NULL;
}

ibl_status ibl_specular_plan_create(ibl_context *ctx, const ibl_specular_desc *desc,
                                    ibl_specular_plan **out)
{
    if (!ctx || !desc || !out) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (desc->size < 1 || desc->size > 16384)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "specular plan: size %d out of range",
                        desc->size);
    if (desc->filter == IBL_FILTER_BOX || desc->filter == IBL_FILTER_GAUSS)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "specular plan: the %s filter has no plan (use ibl_specular_prefilter)",
                        ibl_specular_filter_name(desc->filter));
    int S = desc->source_size > 0 ? desc->source_size : desc->size;
    if (!is_pow2(S) || S > 16384)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "specular plan: source size %d is not a power of two", S);
    ibl_specular_plan *p = ibl_calloc(ctx, 1, sizeof *p);
    if (!p) return ibl_context_status(ctx);
    p->ctx = ctx;
    p->desc = *desc;
    p->S = S;
    p->N = desc->size;
    int full = ibl_full_mip_count(p->N);
    p->L = desc->levels > 0 && desc->levels < full ? desc->levels : full;
    p->desc.levels = p->L;
    ibl_status st = ibl__specular_mapping(ctx, &p->desc, p->N, p->L, &p->info);
    if (st != IBL_OK) goto fail;
    for (int f = 0; f < 6; f++) {
        double c[3], sx[3], ty[3];
        ibl_cube_direction_d(f, 0.5, 0.5, c);
        ibl_cube_direction_d(f, 1.0, 0.5, sx);
        ibl_cube_direction_d(f, 0.5, 1.0, ty);
        for (int i = 0; i < 3; i++) {
            p->face_basis[f][0][i] = (float)c[i];
            p->face_basis[f][1][i] = (float)(sx[i] - c[i]);
            p->face_basis[f][2][i] = (float)(ty[i] - c[i]);
        }
    }
    for (int f = 0; f < 6; f++) {
        double sg[3];
        face_perm(p, f, p->perm_ax[f], sg);
        for (int i = 0; i < 3; i++) p->perm_sg[f][i] = (float)sg[i];
    }
    if (desc->dynamic) {
        st = ibl__dynamic_create(ctx, &p->desc, &p->info, S, &p->dyn);
        if (st != IBL_OK) goto fail;
        *out = p;
        return IBL_OK;
    }
    /* a lobe narrower than ~1.5 source texels is summed over k x k sub-texels of level 0
     * (each with its parent's radiance), as the reference splits such texels */
    p->K = 1;
    for (int l = 0; l < p->L; l++) {
        ibl__lobe lobe = ibl__lobe_for_level(&p->info, l);
        if (lobe.kind == IBL__LOBE_MIRROR) continue;
        while (p->K < 8 && (long)S * p->K < 4096 && lobe.half_angle < 1.5 * texel_angle(S * p->K))
            p->K *= 2;
    }
    p->SL = ibl_full_mip_count(S * p->K);
    for (int l = 0; l < p->SL; l++) {
        srclev *s = &p->src[l];
        s->M = (S * p->K) >> l;
        s->nbx = (s->M + BW - 1) / BW;
        s->nby = (s->M + BH - 1) / BH;
        s->nf = l == 0 ? NF0 : NFC;
        if (l == 0) continue; /* level0_records, when some piece needs them */
        /* every field of every texel is written before it is read; only the lanes beyond a
         * face of fewer than one block's texels stay as they are (zero) */
        s->rec = s->M % BW || s->M % BH ? ibl_calloc(ctx, block_count(s) * s->nf * BT, sizeof(float))
                                        : ibl_alloc(ctx, block_count(s) * s->nf * BT * sizeof(float));
        s->block = ibl_alloc(ctx, block_count(s) * BINFO * sizeof(float));
        s->row_power = ibl_alloc(ctx, (size_t)6 * s->nby * sizeof(double));
        if (!s->rec || !s->block || !s->row_power) {
            st = ibl_context_status(ctx);
            goto fail;
        }
    }
    st = build_geometry(p);
    if (st != IBL_OK) goto fail;
    for (int l = 0; l < p->L; l++) {
        p->lv[l].lobe = ibl__lobe_for_level(&p->info, l);
        if (p->lv[l].lobe.kind == IBL__LOBE_MIRROR) continue;
        st = plan_level(p, l);
        if (st == IBL_OK) st = core_create(p, l);
        if (st != IBL_OK) goto fail;
    }
    /* one padded face and its transpose for the precomputed pieces, which run one after the
     * other, face by face */
    size_t pad = 0;
    for (int l = 0; l < p->L; l++)
        for (int k = 0; k < p->lv[l].npieces; k++) {
            const struct core *c = p->lv[l].pieces[k].core;
            if (c && (size_t)6 * c->P * c->P > pad) pad = (size_t)6 * c->P * c->P;
        }
    for (int l = 0; l < p->L; l++)
        for (int k = 0; k < p->lv[l].npieces; k++) {
            const struct core *c = p->lv[l].pieces[k].core;
            if (!c || c->level == 0) continue;
            srclev *s = &p->src[c->level];
            float **u = c->dim ? &s->uni_dim : &s->uni;
            if (!*u && !(*u = ibl_alloc(ctx, (size_t)6 * s->M * s->M * 4 * sizeof(float)))) {
                st = ibl_context_status(ctx);
                goto fail;
            }
        }
    if (pad) {
        p->pad = ibl_alloc(ctx, pad * sizeof(float));
        if (!p->pad) {
            st = ibl_context_status(ctx);
            goto fail;
        }
    }
    /* level 0's records only for pieces that sum it leaf by leaf */
    int need_rec0 = p->K > 1;
    for (int l = 0; l < p->L; l++)
        for (int k = 0; k < p->lv[l].npieces; k++)
            if (p->lv[l].lobe.kind != IBL__LOBE_MIRROR && p->lv[l].pieces[k].src == 0 && !p->lv[l].pieces[k].core)
                need_rec0 = 1;
    if (need_rec0) {
        st = level0_records(p);
        if (st != IBL_OK) goto fail;
    }
    for (int l = 0; l < p->L; l++) {
        if (p->lv[l].lobe.kind == IBL__LOBE_MIRROR) continue;
        plan_denominators(p, l);
        st = plan_bright(p, l);
        if (st != IBL_OK) goto fail;
    }
    if (p->corr_pool_blocks &&
        !(p->corr_pool = ibl_alloc(ctx, p->corr_pool_blocks * NFC * BT * sizeof(float)))) {
        st = ibl_context_status(ctx);
        goto fail;
    }
    for (int l = 0; l < p->SL; l++) {
        srclev *s = &p->src[l];
        if (s->bright_c == 0) continue;
        s->bright_cap = BRIGHT_BLOCKS;
        s->bright_rec = ibl_alloc(ctx, (size_t)s->bright_cap * NFC * BT * sizeof(float));
        s->bright_block = ibl_alloc(ctx, CONES(s->bright_cap) * BINFO * sizeof(float));
        s->bright_order = ibl_alloc(ctx, (size_t)s->bright_cap * BT * sizeof(uint64_t));
        if (!s->bright_rec || !s->bright_block || !s->bright_order) {
            st = ibl_context_status(ctx);
            goto fail;
        }
    }
    *out = p;
    return IBL_OK;
fail:
    ibl_specular_plan_destroy(p);
    return st;
}


/* The constant of a split ring's bright test on its source level: a texel of power P adds at
 * most P gmax / den to an output (gmax the piece's peak, den the level's normaliser), so the
 * test P > BRIGHT_TAU mean_radiance den / gmax; the level keeps the strictest of its rings. */
static ibl_status plan_bright(ibl_specular_plan *p, int level)
{
    level_plan *lv = &p->lv[level];
    const grid *dg = &lv->grids[lv->pieces[0].grid];
    size_t face = (size_t)dg->n * dg->n;
    double den = 0;
    for (size_t i = 0; i < face; i++) den += dg->acc[4 * i + 3];
    den /= (double)face;
    for (int k = 0; k < lv->npieces; k++) {
        const piece *core = &lv->pieces[k];
        if (!core->core || core->core->level == 0 || !(den > 0)) continue;
        /* largest |g'| sqrt(2u), |g'| and 3|g''|/2 over the piece (g' by differences) */
        double step = (core->u_hi - core->u_lo) / TAB, d1 = 0, d1e = 0, d2 = 0;
        for (int i = 0; i < TAB; i++) {
            double u = core->u_lo + (i + 0.5) * step;
            double g1 = fabs(core->tab[2 * i + 2] - core->tab[2 * i]) / step;
            double g2 = fabs(core->tab[2 * i + 1]) > fabs(core->tab[2 * i + 3]) ? fabs(core->tab[2 * i + 1])
                                                                                : fabs(core->tab[2 * i + 3]);
            d1 = g1 * sqrt(2.0 * u) > d1 ? g1 * sqrt(2.0 * u) : d1;
            d1e = g1 > d1e ? g1 : d1e;
            d2 = 1.5 * g2 > d2 ? 1.5 * g2 : d2;
        }
        struct core *c = core->core;
        c->a1 = d1 / den, c->a2 = d1e / den, c->a3 = d2 / den;
        c->corr_cap = CORR_BLOCKS;
        p->corr_pool_blocks += (size_t)c->corr_cap;
        c->corr_block = ibl_alloc(p->ctx, CONES(c->corr_cap) * BINFO * sizeof(float));
        c->corr_order = ibl_alloc(p->ctx, (size_t)c->corr_cap * BT * sizeof(uint64_t));
        c->bound = ibl_alloc(p->ctx, block_count(&p->src[c->level]) * BT * sizeof(float));
        if (!c->corr_block || !c->corr_order || !c->bound) return ibl_context_status(p->ctx);
    }
    for (int k = 0; k < lv->npieces; k++) {
        const piece *pc = &lv->pieces[k];
        if (!pc->split) continue;
        double gmax = 0;
        for (int i = 0; i <= TAB; i++) gmax = fabs(pc->tab[2 * i]) > gmax ? fabs(pc->tab[2 * i]) : gmax;
        if (!(gmax > 0)) continue;
        double c = den / gmax;
        srclev *s = &p->src[pc->src];
        if (s->bright_c == 0 || c < s->bright_c) s->bright_c = c;
    }
    return IBL_OK;
}

/* Picks the bright texels of source level l (largest luminance power first), gathers their
 * records into blocks and writes every texel's power without them (F_PD). */
static void gathered_cones(const float *recs, float *blocks, int count, double tr);
static void super_cones(const float *cones, int count, float *supers);
static uint64_t texel_key(const srclev *s, size_t b, int t);
static int gather_texels(const srclev *s, uint64_t *keys, int count, int pf, float *recs, float *cones);

static void select_bright(ibl_specular_plan *p, int l)
{
    srclev *s = &p->src[l];
    size_t blocks = block_count(s);
    double thr = BRIGHT_TAU * accuracy_scale(p) * s->power / (4.0 * IBL_PI) * s->bright_c;
    for (;;) { /* raise the bar until the brightest fit (a bounded direct sum) */
        int count = 0;
        for (size_t b = 0; b < blocks; b++) {
            const float *P = s->rec + (b * s->nf + F_P) * BT;
            for (int t = 0; t < BT; t++)
                count += LUM[0] * P[t] + LUM[1] * P[BT + t] + LUM[2] * P[2 * BT + t] > thr;
        }
        if (count <= s->bright_cap * BT) break;
        thr *= 2.0;
    }
    int k = 0;
    for (size_t b = 0; b < blocks; b++) {
        float *rec = s->rec + b * s->nf * BT;
        for (int t = 0; t < BT; t++) {
            const float *P = rec + F_P * BT;
            int is_bright = LUM[0] * P[t] + LUM[1] * P[BT + t] + LUM[2] * P[2 * BT + t] > thr;
            for (int c = 0; c < 3; c++) rec[(F_PD + c) * BT + t] = is_bright ? 0.0f : P[c * BT + t];
            if (is_bright) s->bright_order[k++] = texel_key(s, b, t);
        }
    }
    s->nbright = gather_texels(s, s->bright_order, k, F_P, s->bright_rec, s->bright_block);
    super_cones(s->bright_block, s->nbright, s->bright_block + (size_t)s->bright_cap * BINFO);
}

/* A texel's place in the order texels are gathered in: its face, then the Morton order of its
 * (x, y), so that the eight texels of a gathered block are neighbours and its cone is small.
 * (In block order a gathered block could span a face row, and every tile's reach test would
 * take it: at 512, level 1's corrections cost 3x more that way.) */
static uint64_t texel_key(const srclev *s, size_t b, int t)
{
    int f = (int)(b / ((size_t)s->nby * s->nbx)), r = (int)(b % ((size_t)s->nby * s->nbx));
    uint32_t x = (uint32_t)((r % s->nbx) * BW + t % BW), y = (uint32_t)((r / s->nbx) * BH + t / BW);
    uint64_t key = 0;
    for (int i = 0; i < 16; i++) key |= (uint64_t)((x >> i) & 1) << (2 * i) | (uint64_t)((y >> i) & 1) << (2 * i + 1);
    return (uint64_t)f << 32 | key;
}

/* The block and lane of a texel_key. */
static void texel_of_key(const srclev *s, uint64_t key, size_t *b, int *t)
{
    int f = (int)(key >> 32);
    uint32_t x = 0, y = 0;
    for (int i = 0; i < 16; i++) {
        x |= (uint32_t)((key >> (2 * i)) & 1) << i;
        y |= (uint32_t)((key >> (2 * i + 1)) & 1) << i;
    }
    *b = ((size_t)f * s->nby + y / BH) * s->nbx + x / BW;
    *t = (int)(y % BH) * BW + (int)(x % BW);
}

static int key_order(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Gathers the `count` texels of `keys` (texel_key) in key order, eight to a block of recs with
 * their power from field pf, and their cones; the number of blocks. */
static int gather_texels(const srclev *s, uint64_t *keys, int count, int pf, float *recs, float *cones)
{
    qsort(keys, (size_t)count, sizeof *keys, key_order);
    for (int k = 0; k < count; k++) {
        size_t b;
        int t;
        texel_of_key(s, keys[k], &b, &t);
        const float *rec = s->rec + b * s->nf * BT;
        float *dst = recs + (size_t)(k / BT) * NFC * BT + k % BT;
        for (int fl = 0; fl < NFC; fl++) dst[fl * BT] = rec[fl * BT + t];
        for (int ch = 0; ch < 3; ch++) dst[(F_P + ch) * BT] = rec[(pf + ch) * BT + t];
    }
    for (int i = count; i < (count + BT - 1) / BT * BT; i++) { /* the rest of the last block: nothing */
        float *dst = recs + (size_t)(i / BT) * NFC * BT + i % BT;
        for (int fl = 0; fl < NFC; fl++) dst[fl * BT] = 0.0f;
        dst[F_WE * BT] = 0.5f;
    }
    gathered_cones(recs, cones, count, 1.5 / s->M);
    return (count + BT - 1) / BT;
}

/* The cones around each SUPER consecutive cones of `count` (gathered in Morton order, they are
 * neighbours): around the mean of their centres, out to the farthest one's edge. */
static void super_cones(const float *cones, int count, float *supers)
{
    for (int g = 0; g * SUPER < count; g++) {
        int n = count - g * SUPER < SUPER ? count - g * SUPER : SUPER;
        const float *bc = cones + (size_t)g * SUPER * BINFO;
        double c[3] = {0, 0, 0}, r = 0;
        for (int k = 0; k < n; k++)
            for (int i = 0; i < 3; i++) c[i] += bc[k * BINFO + i];
        double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        for (int i = 0; i < 3; i++) c[i] = len > 0 ? c[i] / len : (i == 0);
        for (int k = 0; k < n; k++) {
            double d = c[0] * bc[k * BINFO] + c[1] * bc[k * BINFO + 1] + c[2] * bc[k * BINFO + 2];
            double a = acos(d > 1 ? 1 : d < -1 ? -1 : d) + bc[k * BINFO + 3];
            r = a > r ? a : r;
        }
        r += 1e-6;
        float *o = supers + (size_t)g * BINFO;
        for (int i = 0; i < 3; i++) o[i] = (float)c[i];
        o[3] = (float)r, o[4] = (float)cos(r), o[5] = (float)sin(r);
    }
}

/* The cones of `count` texels gathered in blocks (recs): around the mean of each block's
 * texel directions, out to the farthest one plus tr (a texel's half diagonal). */
static void gathered_cones(const float *recs, float *blocks, int count, double tr)
{
    int k = count;
    for (int b = 0; b < (count + BT - 1) / BT; b++) {
        const float *rec = recs + (size_t)b * NFC * BT;
        int n = k - b * BT < BT ? k - b * BT : BT;
        double d[BT][3], c[3] = {0, 0, 0};
        for (int t = 0; t < n; t++) {
            double len = 0;
            for (int i = 0; i < 3; i++) d[t][i] = rec[(F_MX + i) * BT + t], len += d[t][i] * d[t][i];
            len = sqrt(len);
            for (int i = 0; i < 3; i++) d[t][i] /= len, c[i] += d[t][i];
        }
        double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), r = 0;
        for (int i = 0; i < 3; i++) c[i] /= len;
        for (int t = 0; t < n; t++) {
            double dd = c[0] * d[t][0] + c[1] * d[t][1] + c[2] * d[t][2];
            double a = acos(dd > 1 ? 1 : dd < -1 ? -1 : dd);
            r = a > r ? a : r;
        }
        r += tr + 1e-6;
        float *bc = blocks + (size_t)b * BINFO;
        for (int i = 0; i < 3; i++) bc[i] = (float)c[i];
        bc[3] = (float)r, bc[4] = (float)cos(r), bc[5] = (float)sin(r);
    }
}


/* Gathers each texel over the threshold with its luminance moments and its power from field
 * pf (F_P, or F_PD for split rings): summed as a leaf, while the padded source leaves it out
 * (core_pad_task), it turns the texel's uniform share into its moment leaf; the number of
 * blocks. */
static int gather_corrections(const struct core *c, const srclev *s, double thr, int pf, float *recs,
                              float *cones)
{
    size_t blocks = block_count(s);
    int k = 0;
    for (size_t b = 0; b < blocks; b++) {
        const float *rec = s->rec + b * s->nf * BT;
        for (int t = 0; t < BT; t++) {
            if (!(c->bound[b * BT + t] > thr)) continue;
            if (rec[pf * BT + t] == 0 && rec[(pf + 1) * BT + t] == 0 && rec[(pf + 2) * BT + t] == 0) continue;
            c->corr_order[k++] = texel_key(s, b, t);
        }
    }
    return gather_texels(s, c->corr_order, k, pf, recs, cones);
}

/* Picks the texels of the precomputed piece's level whose moment leaves differ most from
 * uniform texels (see struct core) and gathers them. */
typedef struct bound_job {
    const ibl_specular_plan *p;
    struct core *c;
} bound_job;

enum { BOUND_CHUNK = 256 }; /* blocks per task */

/* How far each texel's moment leaf can be from its uniform leaf, per unit of the normaliser
 * (see struct core): in float, lane by lane. */
static void bound_task(void *arg, int index)
{
    const bound_job *j = arg;
    const struct core *c = j->c;
    const srclev *s = &j->p->src[c->level];
    size_t b0 = (size_t)index * BOUND_CHUNK, b1 = b0 + BOUND_CHUNK, blocks = block_count(s);
    const float a1 = (float)c->a1, a2 = (float)c->a2, a3 = (float)c->a3;
    const float l0 = (float)LUM[0], l1 = (float)LUM[1], l2 = (float)LUM[2];
    for (size_t b = b0; b < b1 && b < blocks; b++) {
        const float *rec = s->rec + b * s->nf * BT;
        float *out = c->bound + b * BT;
        for (int t = 0; t < BT; t++) {
            float P = l0 * rec[F_P * BT + t] + l1 * rec[(F_P + 1) * BT + t] + l2 * rec[(F_P + 2) * BT + t];
            float dm = 0, dc = 0;
            for (int k = 0; k < 3; k++) {
                float d = rec[(F_WM + k) * BT + t] - rec[(F_MX + k) * BT + t];
                dm += d * d;
            }
            for (int k = 0; k < 6; k++) {
                float d = fabsf(rec[(F_WC + k) * BT + t] - rec[(F_C + k) * BT + t]);
                dc = d > dc ? d : dc;
            }
            float de = fabsf(rec[F_WE * BT + t] - rec[F_E * BT + t]);
            out[t] = P > 0 ? P * (a1 * sqrtf(dm) + a2 * de + a3 * dc) : 0.0f;
        }
    }
}

static void select_corrections(ibl_specular_plan *p, struct core *c)
{
    const srclev *s = &p->src[c->level];
    size_t blocks = block_count(s);
    int pf = c->dim ? F_PD : F_P;
    bound_job bj = {p, c};
    ibl_parallel_for(p->ctx, (int)((blocks + BOUND_CHUNK - 1) / BOUND_CHUNK), bound_task, &bj);
    double thr = CORR_TAU * accuracy_scale(p) * s->power / (4.0 * IBL_PI);
    int cap = c->corr_cap * BT;
    for (;;) {
        int count = 0;
        for (size_t i = 0; i < blocks * BT; i++) count += c->bound[i] > thr;
        if (count <= cap) break;
        thr *= 2.0;
    }
    c->corr_thr = (float)thr; /* the pad and the gathering compare the same floats */
    c->ncorr = gather_corrections(c, s, c->corr_thr, pf, c->corr_rec, c->corr_block);
    super_cones(c->corr_block, c->ncorr, c->corr_block + (size_t)c->corr_cap * BINFO);
}

/* ---- run: the radiance pyramid ---- */

typedef struct pyr_job {
    ibl_specular_plan *p;
    const ibl_cubemap *src;
    int level;
} pyr_job;


static void level0_row(void *arg, int index)
{
    const pyr_job *job = arg;
    srclev *s = &job->p->src[0];
    int M = s->M, K = job->p->K, f = index / M, y = index % M;
    const float *row = ibl_cubemap_face(job->src, 0, f) + (size_t)(y / K) * (M / K) * 4;
    for (int x = 0; x < M; x++)
        for (int c = 0; c < 3; c++) s->rec[rec_index(s, f, x, y, F_L + c)] = row[(x / K) * 4 + c];
}

/* Level 1 straight from the source texels (no sub-texels, no level-0 records): the four
 * children are uniform texels whose geometric moments are face 0's face-local ones (geo0, the
 * same on every face), so they are combined in face-local coordinates and the result is
 * turned to face f's world coordinates once (the generic path below turns every child). */
static void pyramid_row_level1(const pyr_job *job, int f, int y)
{
    static const int ci[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    const ibl_specular_plan *p = job->p;
    srclev *s = &job->p->src[1];
    int M = s->M, S = p->src[0].M;
    const float *face = ibl_cubemap_face(job->src, 0, f);
    const int *ax = p->perm_ax[f];
    const float *sg = p->perm_sg[f];
    for (int x = 0; x < M; x++) {
        const float *g[4];
        double w[4], W = 0, m[3] = {0, 0, 0}, P[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++) {
            int cx = 2 * x + (k & 1), cy = 2 * y + (k >> 1);
            g[k] = p->geo0 + ((size_t)cy * S + cx) * GEO_FIELDS;
            const float *L = face + ((size_t)cy * S + cx) * 4;
            double om = g[k][F_OM], pw[3] = {om * L[0], om * L[1], om * L[2]};
            for (int c = 0; c < 3; c++) P[c] += pw[c];
            double lum = LUM[0] * pw[0] + LUM[1] * pw[1] + LUM[2] * pw[2];
            w[k] = lum > 0 ? lum : 0;
            W += w[k];
            for (int c = 0; c < 3; c++) m[c] += w[k] * g[k][F_MX + c];
        }
        float *o = s->rec + rec_index(s, f, x, y, 0);
        if (W > 0) {
            double C[6] = {0, 0, 0, 0, 0, 0}, e = 0;
            for (int c = 0; c < 3; c++) m[c] /= W;
            for (int k = 0; k < 4; k++) {
                const float *q = g[k];
                double a = w[k] / W, d[3] = {q[F_MX] - m[0], q[F_MX + 1] - m[1], q[F_MX + 2] - m[2]};
                for (int c = 0; c < 6; c++) C[c] += a * (q[F_C + c] + d[ci[c][0]] * d[ci[c][1]]);
                e += a * (q[F_E] + 0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
            }
            const double Cl[3][3] = {{C[0], C[3], C[4]}, {C[3], C[1], C[5]}, {C[4], C[5], C[2]}};
            for (int c = 0; c < 3; c++) o[(F_WM + c) * BT] = (float)(sg[c] * m[ax[c]]);
            o[F_WE * BT] = (float)e;
            for (int c = 0; c < 6; c++) {
                int i = ci[c][0], k = ci[c][1];
                o[(F_WC + c) * BT] = (float)(sg[i] * sg[k] * Cl[ax[i]][ax[k]]);
            }
        } else { /* no light: the geometric moments */
            for (int c = 0; c < 3; c++) o[(F_WM + c) * BT] = o[(F_MX + c) * BT];
            o[F_WE * BT] = o[F_E * BT];
            for (int c = 0; c < 6; c++) o[(F_WC + c) * BT] = o[(F_C + c) * BT];
        }
        for (int c = 0; c < 3; c++) o[(F_P + c) * BT] = (float)P[c];
    }
}

static void pyramid_row(void *arg, int index)
{
    const pyr_job *job = arg;
    const srclev *lo = &job->p->src[job->level - 1];
    srclev *s = &job->p->src[job->level];
    int M = s->M, f = index / M, y = index % M;
    if (job->level == 1 && !job->p->rec0) {
        pyramid_row_level1(job, f, y);
        return;
    }
    const float *r0 = lo->rec;
    float *r = s->rec;
    for (int x = 0; x < M; x++) {
        geo parts[4], out;
        const geo *pp[4];
        double w[4], P[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++) {
            int cx = 2 * x + (k & 1), cy = 2 * y + (k >> 1);
            geo *g = &parts[k];
            double pw[3];
            if (job->level == 1 && !job->p->rec0) {
                /* the source texel (K = 1 here) and level 0's moments */
                float v[GEO_FIELDS];
                geo0_world(job->p, f, cx, cy, v);
                const float *L = ibl_cubemap_face(job->src, 0, f) + ((size_t)cy * lo->M + cx) * 4;
                for (int c = 0; c < 3; c++) pw[c] = (double)v[F_OM] * L[c];
                for (int c = 0; c < 3; c++) g->m[c] = v[F_MX + c];
                g->e = v[F_E];
                for (int c = 0; c < 6; c++) g->c[c] = v[F_C + c];
            } else {
                /* the child's fields, BT floats apart */
                const float *q = r0 + rec_index(lo, f, cx, cy, 0);
                if (job->level == 1) {
                    double om = q[F_OM * BT];
                    for (int c = 0; c < 3; c++) pw[c] = om * q[(F_L + c) * BT];
                    for (int c = 0; c < 3; c++) g->m[c] = q[(F_MX + c) * BT];
                    g->e = q[F_E * BT];
                    for (int c = 0; c < 6; c++) g->c[c] = q[(F_C + c) * BT];
                } else {
                    for (int c = 0; c < 3; c++) pw[c] = q[(F_P + c) * BT];
                    for (int c = 0; c < 3; c++) g->m[c] = q[(F_WM + c) * BT];
                    g->e = q[F_WE * BT];
                    for (int c = 0; c < 6; c++) g->c[c] = q[(F_WC + c) * BT];
                }
            }
            w[k] = LUM[0] * pw[0] + LUM[1] * pw[1] + LUM[2] * pw[2];
            if (!(w[k] > 0)) w[k] = 0;
            for (int c = 0; c < 3; c++) P[c] += pw[c];
            pp[k] = g;
        }
        float *o = r + rec_index(s, f, x, y, 0);
        if (w[0] + w[1] + w[2] + w[3] > 0) {
            combine(pp, w, 4, &out);
        } else { /* no light: the geometric moments */
            for (int c = 0; c < 3; c++) out.m[c] = o[(F_MX + c) * BT];
            out.e = o[F_E * BT];
            for (int c = 0; c < 6; c++) out.c[c] = o[(F_C + c) * BT];
        }
        for (int c = 0; c < 3; c++) o[(F_WM + c) * BT] = (float)out.m[c];
        o[F_WE * BT] = (float)out.e;
        for (int c = 0; c < 6; c++) o[(F_WC + c) * BT] = (float)out.c[c];
        for (int c = 0; c < 3; c++) o[(F_P + c) * BT] = (float)P[c];
    }
}

/* Row `index` (face M + y) of the level's uniform texels (srclev.uni, uni_dim). */
static void uniform_task(void *arg, int index)
{
    const pyr_job *job = arg;
    const srclev *s = &job->p->src[job->level];
    int M = s->M, f = index / M, y = index % M;
    for (int x = 0; x < M; x++) {
        const float *rec = s->rec + rec_index(s, f, x, y, 0);
        float om = rec[F_OM * BT], inv = om > 0 ? 1.0f / om : 0.0f;
        size_t o = (((size_t)f * M + y) * M + x) * 4;
        if (s->uni) {
            for (int c = 0; c < 3; c++) s->uni[o + c] = rec[(F_P + c) * BT] * inv;
            s->uni[o + 3] = 0.0f;
        }
        if (s->uni_dim) {
            for (int c = 0; c < 3; c++) s->uni_dim[o + c] = rec[(F_PD + c) * BT] * inv;
            s->uni_dim[o + 3] = 0.0f;
        }
    }
}

/* Whole block rows per task (see store_geo_task): index = face nby + block row. */
static void level0_task(void *arg, int index)
{
    const pyr_job *job = arg;
    const srclev *s = &job->p->src[0];
    int f = index / s->nby, yb = index % s->nby;
    for (int y = yb * BH; y < (yb + 1) * BH && y < s->M; y++) level0_row(arg, f * s->M + y);
}

static void pyramid_task(void *arg, int index)
{
    const pyr_job *job = arg;
    const srclev *s = &job->p->src[job->level];
    int f = index / s->nby, yb = index % s->nby;
    for (int y = yb * BH; y < (yb + 1) * BH && y < s->M; y++) pyramid_row(arg, f * s->M + y);
    double power = 0;
    for (int bx = 0; bx < s->nbx; bx++) {
        const float *P = s->rec + (((size_t)f * s->nby + yb) * s->nbx + bx) * s->nf * BT + F_P * BT;
        for (int t = 0; t < BT; t++) power += LUM[0] * P[t] + LUM[1] * P[BT + t] + LUM[2] * P[2 * BT + t];
    }
    s->row_power[index] = power;
}

/* ---- run: summing pieces over blocks ---- */

/* ---- the sums over source blocks ---- */

/* What a sum accumulates: the normaliser (geometric moments, plan time), or the numerator
 * from level 0 (texel radiance, geometric moments) or from a coarse level (luminance-weighted
 * moments and power). */
enum { EVAL_DEN = 0, EVAL_NUM0, EVAL_NUMC };

typedef struct cand {
    uint32_t block;
    float cos_out, cos_in; /* the block can matter only where cos_out <= R.centre <= cos_in */
} cand;

typedef struct sum_args {
    int mode, avx2;
    const srclev *s;
    const piece *pc;
    const cand *cands;
    int ncand;
    int dim; /* a split ring's grid: the power of the texels that are not bright */
} sum_args;

/* psi_out - psi_in of the piece at u (the partition of unity alone) */
static float piece_phi(const piece *pc, float u)
{
    float v[2];
    const float sa[2] = {pc->out_sa, pc->in_sa}, sb[2] = {pc->out_sb, pc->in_sb};
    for (int i = 0; i < 2; i++) {
        float s = u * sa[i] - sb[i];
        s = s < 0 ? 0 : s > 1 ? 1 : s;
        v[i] = 1.0f - s * s * s * (10.0f + s * (-15.0f + 6.0f * s));
    }
    return v[0] - v[1];
}

static float table_weight(const piece *pc, float u, float q)
{
    if (!pc->ggx && q > 0) {
        /* Phong near the horizon: the closed-form mean over u0 +- a (see avx2_lobe) */
        float a = sqrtf(3.0f * q);
        if (u + 2.0f * a >= 1.0f && a > 1e-6f && a <= u) {
            float xl = 1.0f - u + a, xh = 1.0f - u - a, n1 = pc->n + 1.0f;
            float pl = xl > 0 ? powf(xl, n1) : 0.0f, ph = xh > 0 ? powf(xh, n1) : 0.0f;
            return (pl - ph) / (2.0f * a * n1) * piece_phi(pc, u);
        }
    }
    float ti = (u - pc->t0) * pc->tscale;
    ti = ti < 0.0f ? 0.0f : ti > (float)(TAB + 1) ? (float)(TAB + 1) : ti;
    int i = (int)ti;
    i = i > TAB ? TAB : i;
    float fr = ti - (float)i;
    const float *tab = pc->tab;
    float g = tab[2 * i] + fr * (tab[2 * i + 2] - tab[2 * i]);
    float g2 = tab[2 * i + 1] + fr * (tab[2 * i + 3] - tab[2 * i + 1]);
    return g + 0.5f * g2 * q;
}

/* The record of candidate ci if it can matter for direction R (NULL if it is culled). */
static inline const float *candidate_record(const sum_args *sa, int ci, const float R[3])
{
    const cand *cd = &sa->cands[ci];
    const float *bc = sa->s->block + (size_t)cd->block * BINFO;
    float dd = R[0] * bc[0] + R[1] * bc[1] + R[2] * bc[2];
    if (dd < cd->cos_out || dd > cd->cos_in) return NULL;
    return sa->s->rec + (size_t)cd->block * sa->s->nf * BT;
}

/* The portable sum: one texel at a time through the piece's table. */
static void sum_blocks_generic(const sum_args *sa, const float R[3], const float RR[6], double out[4])
{
    int base = sa->mode == EVAL_NUMC ? F_WM : F_MX;
    float acc[4] = {0, 0, 0, 0};
    for (int ci = 0; ci < sa->ncand; ci++) {
        const float *rec = candidate_record(sa, ci, R);
        if (!rec) continue;
        const float *m = rec + base * BT, *e = m + 3 * BT, *c = m + 4 * BT;
        const float *om = rec + F_OM * BT, *L = rec + (sa->mode == EVAL_NUMC ? (sa->dim ? F_PD : F_P) : F_L) * BT;
        for (int t = 0; t < BT; t++) {
            float dx = R[0] - m[t], dy = R[1] - m[BT + t], dz = R[2] - m[2 * BT + t];
            float u = 0.5f * (dx * dx + dy * dy + dz * dz) + e[t];
            float q = RR[0] * c[t] + RR[1] * c[BT + t] + RR[2] * c[2 * BT + t] +
                      RR[3] * c[3 * BT + t] + RR[4] * c[4 * BT + t] + RR[5] * c[5 * BT + t];
            float w = table_weight(sa->pc, u, q);
            if (sa->mode == EVAL_DEN) {
                acc[3] += w * om[t];
                continue;
            }
            if (sa->mode == EVAL_NUM0) w *= om[t];
            acc[0] += w * L[t], acc[1] += w * L[BT + t], acc[2] += w * L[2 * BT + t];
        }
    }
    for (int k = 0; k < 4; k++) out[k] += acc[k];
}

#if (defined(__x86_64__) || defined(__i386__)) && defined(__GNUC__)
#include <cpuid.h>
#include <immintrin.h>

#define AVX2 __attribute__((target("avx2,fma,f16c")))
#define AVX2_INLINE __attribute__((target("avx2,fma,f16c"), always_inline))

typedef struct avx2_consts {
    __m256 half, zero, one, two, c4, c6, cm15, c10, c30, c60;
    __m256 t0, ts, tmax;
    __m256i imax;
    __m256 a2, kap, a4, kap6, osa, osb, osk, isa, isb, isk;
    __m256 n, nn1, xmin; /* Phong: n, n (n - 1), smallest x divided by */
    __m256 n1, three, amin, tiny; /* Phong's box mean at the horizon */
    int has_in, has_out;
} avx2_consts;

AVX2 static void avx2_setup(const piece *pc, avx2_consts *k)
{
    k->half = _mm256_set1_ps(0.5f), k->zero = _mm256_setzero_ps(), k->one = _mm256_set1_ps(1.0f);
    k->two = _mm256_set1_ps(2.0f), k->c4 = _mm256_set1_ps(4.0f), k->c6 = _mm256_set1_ps(6.0f);
    k->cm15 = _mm256_set1_ps(-15.0f), k->c10 = _mm256_set1_ps(10.0f);
    k->c30 = _mm256_set1_ps(30.0f), k->c60 = _mm256_set1_ps(60.0f);
    k->t0 = _mm256_set1_ps(pc->t0), k->ts = _mm256_set1_ps(pc->tscale);
    k->tmax = _mm256_set1_ps((float)(TAB + 1)), k->imax = _mm256_set1_epi32(TAB);
    k->a2 = _mm256_set1_ps(pc->a2), k->kap = _mm256_set1_ps(pc->kap), k->a4 = _mm256_set1_ps(pc->a4);
    k->kap6 = _mm256_set1_ps(6.0f * pc->kap * pc->kap);
    k->osa = _mm256_set1_ps(pc->out_sa), k->osb = _mm256_set1_ps(pc->out_sb);
    k->osk = _mm256_set1_ps(pc->out_sk), k->isa = _mm256_set1_ps(pc->in_sa);
    k->isb = _mm256_set1_ps(pc->in_sb), k->isk = _mm256_set1_ps(pc->in_sk);
    k->n = _mm256_set1_ps(pc->n), k->nn1 = _mm256_set1_ps(pc->n * (pc->n - 1.0f));
    k->xmin = _mm256_set1_ps(1e-3f);
    k->n1 = _mm256_set1_ps(pc->n + 1.0f), k->three = _mm256_set1_ps(3.0f);
    k->amin = _mm256_set1_ps(1e-6f), k->tiny = _mm256_set1_ps(1e-30f);
    k->has_in = pc->in_sa != 0.0f;
    k->has_out = pc->out_sa != 0.0f;
}

/* ln x for x in (0, 1]: x = m 2^e with m in [sqrt(1/2), sqrt(2)), ln m = 2 atanh(r),
 * r = (m - 1) / (m + 1), |r| <= 0.172, its odd series to r^9 (error < 1e-9) */
AVX2_INLINE static inline __m256 avx2_log(__m256 x)
{
    __m256i bits = _mm256_castps_si256(x);
    __m256i e = _mm256_sub_epi32(_mm256_srli_epi32(bits, 23), _mm256_set1_epi32(127));
    __m256 m = _mm256_castsi256_ps(_mm256_or_si256(_mm256_and_si256(bits, _mm256_set1_epi32(0x007fffff)),
                                                   _mm256_set1_epi32(0x3f800000)));
    __m256 big = _mm256_cmp_ps(m, _mm256_set1_ps(1.41421356f), _CMP_GT_OQ);
    m = _mm256_blendv_ps(m, _mm256_mul_ps(m, _mm256_set1_ps(0.5f)), big);
    e = _mm256_add_epi32(e, _mm256_and_si256(_mm256_castps_si256(big), _mm256_set1_epi32(1)));
    __m256 r = _mm256_div_ps(_mm256_sub_ps(m, _mm256_set1_ps(1.0f)), _mm256_add_ps(m, _mm256_set1_ps(1.0f)));
    __m256 r2 = _mm256_mul_ps(r, r);
    __m256 p = _mm256_fmadd_ps(r2, _mm256_set1_ps(1.0f / 9.0f), _mm256_set1_ps(1.0f / 7.0f));
    p = _mm256_fmadd_ps(r2, p, _mm256_set1_ps(1.0f / 5.0f));
    p = _mm256_fmadd_ps(r2, p, _mm256_set1_ps(1.0f / 3.0f));
    p = _mm256_fmadd_ps(r2, p, _mm256_set1_ps(1.0f));
    __m256 lnm = _mm256_mul_ps(_mm256_add_ps(r, r), p);
    return _mm256_fmadd_ps(_mm256_cvtepi32_ps(e), _mm256_set1_ps(0.693147180559945f), lnm);
}

/* e^y for y <= 0: 2^(y log2 e) = 2^k 2^f, f in [-1/2, 1/2] by a degree-6 Taylor polynomial of
 * e^(f ln 2) (relative error < 3e-8); 0 below 2^-126 */
AVX2_INLINE static inline __m256 avx2_exp(__m256 y)
{
    __m256 t = _mm256_mul_ps(y, _mm256_set1_ps(1.44269504088896f));
    t = _mm256_max_ps(t, _mm256_set1_ps(-126.0f));
    __m256 kf = _mm256_round_ps(t, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
    __m256 z = _mm256_mul_ps(_mm256_sub_ps(t, kf), _mm256_set1_ps(0.693147180559945f));
    __m256 p = _mm256_fmadd_ps(z, _mm256_set1_ps(1.0f / 720.0f), _mm256_set1_ps(1.0f / 120.0f));
    p = _mm256_fmadd_ps(z, p, _mm256_set1_ps(1.0f / 24.0f));
    p = _mm256_fmadd_ps(z, p, _mm256_set1_ps(1.0f / 6.0f));
    p = _mm256_fmadd_ps(z, p, _mm256_set1_ps(0.5f));
    p = _mm256_fmadd_ps(z, p, _mm256_set1_ps(1.0f));
    p = _mm256_fmadd_ps(z, p, _mm256_set1_ps(1.0f));
    __m256i k = _mm256_cvtps_epi32(kf);
    __m256 scale = _mm256_castsi256_ps(_mm256_slli_epi32(_mm256_add_epi32(k, _mm256_set1_epi32(127)), 23));
    __m256 under = _mm256_cmp_ps(t, _mm256_set1_ps(-125.5f), _CMP_GT_OQ);
    return _mm256_and_ps(under, _mm256_mul_ps(p, scale));
}

/* psi = 1 - S(s), s = clamp(u sa - sb, 0, 1), S the quintic smootherstep; v1, v2 are
 * -psi' and -psi'' */
AVX2_INLINE static inline void avx2_psi(const avx2_consts *k, __m256 u, __m256 sa, __m256 sb, __m256 sk,
                                 __m256 *v0, __m256 *v1, __m256 *v2)
{
    __m256 s = _mm256_min_ps(_mm256_max_ps(_mm256_fmsub_ps(u, sa, sb), k->zero), k->one);
    __m256 t = _mm256_sub_ps(k->one, s), ss = _mm256_mul_ps(s, s);
    __m256 S = _mm256_mul_ps(_mm256_mul_ps(ss, s),
                             _mm256_fmadd_ps(s, _mm256_fmadd_ps(s, k->c6, k->cm15), k->c10));
    __m256 S1 = _mm256_mul_ps(_mm256_mul_ps(k->c30, ss), _mm256_mul_ps(t, t));
    __m256 S2 = _mm256_mul_ps(_mm256_mul_ps(k->c60, s), _mm256_mul_ps(t, _mm256_fnmadd_ps(k->two, s, k->one)));
    *v0 = _mm256_sub_ps(k->one, S);
    *v1 = _mm256_mul_ps(S1, sk);
    *v2 = _mm256_mul_ps(S2, _mm256_mul_ps(sk, sk));
}

/* g + g'' q / 2 of the GGX piece at u, in closed form */
AVX2_INLINE static inline __m256 avx2_lobe(const avx2_consts *k, int ggx, __m256 u, __m256 q)
{
    __m256 xraw = _mm256_sub_ps(k->one, u), x = _mm256_max_ps(xraw, k->zero);
    __m256 front = _mm256_cmp_ps(u, k->one, _CMP_LT_OQ);
    __m256 f0, f1, f2;
    if (ggx) {
        /* f = (1 - u) a4 / T^2, T = a2 + kap u; f' and f'' in u; zero beyond the horizon */
        /* 1 / T by the reciprocal estimate and one Newton step (relative error ~1e-7) */
        __m256 T = _mm256_fmadd_ps(k->kap, u, k->a2), it = _mm256_rcp_ps(T);
        it = _mm256_mul_ps(it, _mm256_fnmadd_ps(T, it, k->two));
        __m256 A = _mm256_mul_ps(k->a4, _mm256_mul_ps(it, it));
        __m256 xi = _mm256_mul_ps(x, it);
        f0 = _mm256_mul_ps(x, A);
        f1 = _mm256_and_ps(front, _mm256_fnmsub_ps(A, _mm256_mul_ps(_mm256_add_ps(k->kap, k->kap), xi), A));
        f2 = _mm256_and_ps(front, _mm256_mul_ps(_mm256_mul_ps(A, it),
                                                _mm256_fmadd_ps(k->kap6, xi, _mm256_mul_ps(k->c4, k->kap))));
    } else {
        /* Phong: f = x^n, f' = -n f / x, f'' = n (n - 1) f / x^2 (in u = 1 - x) */
        __m256 xs = _mm256_max_ps(x, k->xmin), ix = _mm256_div_ps(k->one, xs);
        f0 = _mm256_and_ps(front, avx2_exp(_mm256_mul_ps(k->n, avx2_log(xs))));
        __m256 fx = _mm256_mul_ps(f0, ix);
        f1 = _mm256_sub_ps(k->zero, _mm256_mul_ps(k->n, fx));
        f2 = _mm256_mul_ps(k->nn1, _mm256_mul_ps(fx, ix));
    }
    /* the core has no inner step and the last ring no outer one: psi_in = 0, psi_out = 1 */
    __m256 po0 = k->one, po1 = k->zero, po2 = k->zero, pi0 = k->zero, pi1 = k->zero, pi2 = k->zero;
    /* each step is flat (psi_out = 1 inside its start, psi_in = 0 beyond its end) over most
     * of a piece: skip it when all eight texels are there */
    if (k->has_out &&
        _mm256_movemask_ps(_mm256_cmp_ps(_mm256_fmsub_ps(u, k->osa, k->osb), k->zero, _CMP_GT_OQ)))
        avx2_psi(k, u, k->osa, k->osb, k->osk, &po0, &po1, &po2);
    if (k->has_in &&
        _mm256_movemask_ps(_mm256_cmp_ps(_mm256_fmsub_ps(u, k->isa, k->isb), k->one, _CMP_LT_OQ)))
        avx2_psi(k, u, k->isa, k->isb, k->isk, &pi0, &pi1, &pi2);
    __m256 p0 = _mm256_sub_ps(po0, pi0), p1 = _mm256_sub_ps(pi1, po1), p2 = _mm256_sub_ps(pi2, po2);
    __m256 g = _mm256_mul_ps(f0, p0);
    __m256 g2 = _mm256_fmadd_ps(f2, p0, _mm256_fmadd_ps(_mm256_add_ps(f1, f1), p1, _mm256_mul_ps(f0, p2)));
    __m256 w = _mm256_fmadd_ps(_mm256_mul_ps(k->half, g2), q, g);
    if (ggx) return w;
    /* Phong's x^n has a kink at the horizon (and for n < 2 an unbounded f''): a texel whose
     * u spread reaches it takes the mean of f over u0 +- a, a = sqrt(3 q), in closed form
     * ((x + a)^(n+1) - (x - a)^(n+1)) / (2 a (n + 1)) -- the same to second order where the
     * Taylor leaf is valid, exact at the kink for a uniform spread */
    __m256 a = _mm256_sqrt_ps(_mm256_mul_ps(_mm256_max_ps(q, k->zero), k->three));
    /* (and whose spread does not reach u < 0: only the coarsest texels of tiny sources, where
     * (1 + a - u)^(n+1) could overflow; the Taylor leaf is fine there, the lobe being smooth) */
    __m256 near = _mm256_and_ps(_mm256_cmp_ps(_mm256_fmadd_ps(k->two, a, u), k->one, _CMP_GE_OQ),
                                _mm256_cmp_ps(a, k->amin, _CMP_GT_OQ));
    near = _mm256_and_ps(near, _mm256_cmp_ps(a, u, _CMP_LE_OQ));
    if (_mm256_movemask_ps(near) == 0) return w;
    __m256 xl = _mm256_max_ps(_mm256_add_ps(xraw, a), k->zero);
    __m256 xh = _mm256_max_ps(_mm256_sub_ps(xraw, a), k->zero);
    __m256 pl = _mm256_and_ps(_mm256_cmp_ps(xl, k->zero, _CMP_GT_OQ),
                              avx2_exp(_mm256_mul_ps(k->n1, avx2_log(_mm256_max_ps(xl, k->tiny)))));
    __m256 ph = _mm256_and_ps(_mm256_cmp_ps(xh, k->zero, _CMP_GT_OQ),
                              avx2_exp(_mm256_mul_ps(k->n1, avx2_log(_mm256_max_ps(xh, k->tiny)))));
    __m256 box = _mm256_div_ps(_mm256_sub_ps(pl, ph),
                               _mm256_mul_ps(_mm256_mul_ps(k->two, _mm256_max_ps(a, k->amin)), k->n1));
    return _mm256_blendv_ps(w, _mm256_mul_ps(box, p0), near);
}

AVX2 static double avx2_hsum(__m256 v)
{
    float l[8];
    _mm256_storeu_ps(l, v);
    double s = 0;
    for (int i = 0; i < 8; i++) s += l[i];
    return s;
}

AVX2 static void sum_blocks_avx2(const sum_args *sa, const float R[3], const float RR[6], double out[4])
{
    avx2_consts k;
    avx2_setup(sa->pc, &k);
    const __m256 r0 = _mm256_set1_ps(R[0]), r1 = _mm256_set1_ps(R[1]), r2 = _mm256_set1_ps(R[2]);
    const __m256 q0 = _mm256_set1_ps(RR[0]), q1 = _mm256_set1_ps(RR[1]), q2 = _mm256_set1_ps(RR[2]);
    const __m256 q3 = _mm256_set1_ps(RR[3]), q4 = _mm256_set1_ps(RR[4]), q5 = _mm256_set1_ps(RR[5]);
    int base = sa->mode == EVAL_NUMC ? F_WM : F_MX;
    int lfield = sa->mode == EVAL_NUMC ? (sa->dim ? F_PD : F_P) : F_L;
    int ggx = sa->pc->ggx;
    __m256 ar = k.zero, ag = k.zero, ab = k.zero, aw = k.zero;
    for (int ci = 0; ci < sa->ncand; ci++) {
        const float *rec = candidate_record(sa, ci, R);
        if (!rec) continue;
        const float *m = rec + base * BT;
        __m256 dx = _mm256_sub_ps(r0, _mm256_loadu_ps(m));
        __m256 dy = _mm256_sub_ps(r1, _mm256_loadu_ps(m + BT));
        __m256 dz = _mm256_sub_ps(r2, _mm256_loadu_ps(m + 2 * BT));
        __m256 d2 = _mm256_fmadd_ps(dx, dx, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dz, dz)));
        __m256 u = _mm256_fmadd_ps(k.half, d2, _mm256_loadu_ps(m + 3 * BT));
        const float *c = m + 4 * BT;
        __m256 q = _mm256_mul_ps(q0, _mm256_loadu_ps(c));
        q = _mm256_fmadd_ps(q1, _mm256_loadu_ps(c + BT), q);
        q = _mm256_fmadd_ps(q2, _mm256_loadu_ps(c + 2 * BT), q);
        q = _mm256_fmadd_ps(q3, _mm256_loadu_ps(c + 3 * BT), q);
        q = _mm256_fmadd_ps(q4, _mm256_loadu_ps(c + 4 * BT), q);
        q = _mm256_fmadd_ps(q5, _mm256_loadu_ps(c + 5 * BT), q);
        __m256 w = avx2_lobe(&k, ggx, u, q);
        if (sa->mode == EVAL_DEN) {
            aw = _mm256_fmadd_ps(w, _mm256_loadu_ps(rec + F_OM * BT), aw);
            continue;
        }
        if (sa->mode == EVAL_NUM0) w = _mm256_mul_ps(w, _mm256_loadu_ps(rec + F_OM * BT));
        const float *L = rec + lfield * BT;
        ar = _mm256_fmadd_ps(w, _mm256_loadu_ps(L), ar);
        ag = _mm256_fmadd_ps(w, _mm256_loadu_ps(L + BT), ag);
        ab = _mm256_fmadd_ps(w, _mm256_loadu_ps(L + 2 * BT), ab);
    }
    out[0] += avx2_hsum(ar), out[1] += avx2_hsum(ag), out[2] += avx2_hsum(ab), out[3] += avx2_hsum(aw);
}


/* A base texel's weights over its rows (cells in padded face 0's geometry `geo`, rows in
 * padded coordinates minus O), times `inv`, stored as halves; the stored halves summed per
 * lane into `lanes` (the normaliser sums exactly what the products will use). One setup for
 * the whole base: per row it cost as much as a row's weights. */
AVX2 static void avx2_base_weights(const piece *pc, const float R[3], const float RR[6], const float *geo,
                                   size_t plane, int P, int O, const int32_t *rows, int nrows, float inv,
                                   uint16_t *w, float lanes[8])
{
    avx2_consts k;
    avx2_setup(pc, &k);
    const __m256 r0 = _mm256_set1_ps(R[0]), r1 = _mm256_set1_ps(R[1]), r2 = _mm256_set1_ps(R[2]);
    const __m256 vinv = _mm256_set1_ps(inv);
    __m256 qk[6];
    for (int i = 0; i < 6; i++) qk[i] = _mm256_set1_ps(RR[i]);
    __m256 acc = _mm256_loadu_ps(lanes);
    for (int r = 0; r < nrows; r++) {
        const int32_t *row = rows + 3 * r;
        const float *g = geo + (size_t)(row[0] + O) * P + row[1] + O;
        for (int i = 0; i < row[2]; i += 8) {
            __m256 dx = _mm256_sub_ps(r0, _mm256_loadu_ps(g + i));
            __m256 dy = _mm256_sub_ps(r1, _mm256_loadu_ps(g + plane + i));
            __m256 dz = _mm256_sub_ps(r2, _mm256_loadu_ps(g + 2 * plane + i));
            __m256 d2 = _mm256_fmadd_ps(dx, dx, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dz, dz)));
            __m256 u = _mm256_fmadd_ps(k.half, d2, _mm256_loadu_ps(g + F_E * plane + i));
            __m256 q = _mm256_mul_ps(qk[0], _mm256_loadu_ps(g + F_C * plane + i));
            for (int c = 1; c < 6; c++) q = _mm256_fmadd_ps(qk[c], _mm256_loadu_ps(g + (F_C + c) * plane + i), q);
            __m256 v = _mm256_mul_ps(avx2_lobe(&k, pc->ggx, u, q), _mm256_loadu_ps(g + F_OM * plane + i));
            __m128i h = _mm256_cvtps_ph(_mm256_mul_ps(v, vinv), _MM_FROUND_TO_NEAREST_INT);
            _mm_storeu_si128((__m128i *)(w + i), h);
            acc = _mm256_add_ps(acc, _mm256_cvtph_ps(h));
        }
        w += row[2];
    }
    _mm256_storeu_ps(lanes, acc);
}

/* First and last of n cells (geometry planes `plane` apart from g) within reach of R:
 * m.R >= cr (the piece's end, u = 1 - R.m < u_hi) and a texel there; -1 if none. */
AVX2 static void avx2_row_extent(const float *g, size_t plane, int n, const float R[3], float cr,
                                 int *first, int *last)
{
    const __m256 r0 = _mm256_set1_ps(R[0]), r1 = _mm256_set1_ps(R[1]), r2 = _mm256_set1_ps(R[2]);
    const __m256 c = _mm256_set1_ps(cr), zero = _mm256_setzero_ps();
    *first = *last = -1;
    for (int i = 0; i < n; i += 8) {
        __m256 d = _mm256_fmadd_ps(r0, _mm256_loadu_ps(g + i),
                                   _mm256_fmadd_ps(r1, _mm256_loadu_ps(g + plane + i),
                                                   _mm256_mul_ps(r2, _mm256_loadu_ps(g + 2 * plane + i))));
        __m256 in = _mm256_and_ps(_mm256_cmp_ps(d, c, _CMP_GE_OQ),
                                  _mm256_cmp_ps(_mm256_loadu_ps(g + F_OM * plane + i), zero, _CMP_GT_OQ));
        unsigned mask = (unsigned)_mm256_movemask_ps(in);
        if (i + 8 > n) mask &= (1u << (n - i)) - 1u;
        if (!mask) continue;
        if (*first < 0) *first = i + __builtin_ctz(mask);
        *last = i + 31 - __builtin_clz(mask);
    }
}

/* Eight half-float weights as floats, reversed for a flipped image (cells X.. of the base's
 * row are columns S-1-X.. of the flipped face). */
AVX2_INLINE static inline __m256 avx2_weights8(const uint16_t *w, int reversed)
{
    __m256 v = _mm256_cvtph_ps(_mm_loadu_si128((const __m128i *)w));
    return reversed ? _mm256_permutevar8x32_ps(v, _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0)) : v;
}

/* r, g, b += w times the 8 cells at q of the three planes */
AVX2_INLINE static inline void avx2_mac3(__m256 w, const float *q, size_t plane, __m256 *r, __m256 *g, __m256 *b)
{
    *r = _mm256_fmadd_ps(w, _mm256_loadu_ps(q), *r);
    *g = _mm256_fmadd_ps(w, _mm256_loadu_ps(q + plane), *g);
    *b = _mm256_fmadd_ps(w, _mm256_loadu_ps(q + 2 * plane), *b);
}

/* The core's product for one image of a base texel (see core_mac_generic). */
AVX2 static void avx2_core_mac(const struct core *c, const uint16_t *w, const uint16_t *vec, int nvec,
                               const float *planes, int fx, int fy, double out[3])
{
    size_t plane = (size_t)c->P * c->P;
    /* the first cell of vector k in the flipped image: y' = fy ? S - 1 + 2 O - y : y, and
     * x' = fx ? S - 1 + 2 O - x - 7 (read reversed) : x, in padded coordinates */
    ptrdiff_t P = c->P, E = c->S - 1 + 2 * c->O;
    ptrdiff_t c0 = (fy ? E * P : 0) + (fx ? E - 7 : 0), cy = fy ? -P : P, cx = fx ? -1 : 1;
    /* two sets of accumulators, for even and odd vectors: one set is a chain of dependent
     * FMAs whose latency (4 cycles), not the loads, would bound the loop */
    __m256 ar = _mm256_setzero_ps(), ag = ar, ab = ar, br = ar, bg = ar, bb = ar;
    int k = 0;
    /* two loops, so that neither the reversal nor x's sign is decided per vector */
    if (!fx) {
        for (; k + 2 <= nvec; k += 2) {
            const float *qa = planes + c0 + cy * vec[2 * k + 1] + vec[2 * k];
            avx2_mac3(avx2_weights8(w + 8 * k, 0), qa, plane, &ar, &ag, &ab);
            const float *qb = planes + c0 + cy * vec[2 * k + 3] + vec[2 * k + 2];
            avx2_mac3(avx2_weights8(w + 8 * k + 8, 0), qb, plane, &br, &bg, &bb);
        }
    } else {
        for (; k + 2 <= nvec; k += 2) {
            const float *qa = planes + c0 + cy * vec[2 * k + 1] - vec[2 * k];
            avx2_mac3(avx2_weights8(w + 8 * k, 1), qa, plane, &ar, &ag, &ab);
            const float *qb = planes + c0 + cy * vec[2 * k + 3] - vec[2 * k + 2];
            avx2_mac3(avx2_weights8(w + 8 * k + 8, 1), qb, plane, &br, &bg, &bb);
        }
    }
    if (k < nvec)
        avx2_mac3(avx2_weights8(w + 8 * k, fx), planes + c0 + cy * vec[2 * k + 1] + cx * vec[2 * k], plane, &ar,
                  &ag, &ab);
    ar = _mm256_add_ps(ar, br), ag = _mm256_add_ps(ag, bg), ab = _mm256_add_ps(ab, bb);
    out[0] = avx2_hsum(ar) * c->wscale, out[1] = avx2_hsum(ag) * c->wscale, out[2] = avx2_hsum(ab) * c->wscale;
}

static int cpu_has_avx2(void)
{
    /* F16C read from CPUID leaf 1 (ECX bit 29): clang's __builtin_cpu_supports has no "f16c" */
    unsigned a, b, c, d;
    int f16c = __get_cpuid(1, &a, &b, &c, &d) && (c & (1u << 29));
    return f16c && __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}
#else
#define sum_blocks_avx2 sum_blocks_generic
#define avx2_row_extent row_extent_generic
static void avx2_core_mac(const struct core *c, const uint16_t *w, const uint16_t *vec, int nvec,
                          const float *planes, int fx, int fy, double out[3])
{
    (void)c, (void)w, (void)vec, (void)nvec, (void)planes, (void)fx, (void)fy, (void)out;
}
static void avx2_base_weights(const piece *pc, const float R[3], const float RR[6], const float *geo,
                              size_t plane, int P, int O, const int32_t *rows, int nrows, float inv,
                              uint16_t *w, float lanes[8])
{
    (void)pc, (void)R, (void)RR, (void)geo, (void)plane, (void)P, (void)O, (void)rows, (void)nrows,
        (void)inv, (void)w, (void)lanes;
}
static int cpu_has_avx2(void) { return 0; }
#endif

static double dot3(const double *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* [lo, hi] of tan(longitude) around `pole` of the cap (axis a, radius T), for a face whose
 * axis is `ax` and tangent `tg` (the coordinate is a.tg / a.ax). 0 if the cap misses the
 * face's front half-space in this coordinate. */
static int cap_range(const double a[3], double T, const float ax[3], const float tg[3],
                     const float pole[3], double *lo, double *hi)
{
    double pz = dot3(a, pole);
    if (pz > 1) pz = 1;
    if (pz < -1) pz = -1;
    double beta = acos(pz);
    if (T >= beta || T >= IBL_PI - beta) {
        *lo = -1, *hi = 1;
        return 1;
    }
    double phi = atan2(dot3(a, tg), dot3(a, ax));
    double d = asin(sin(T) / sin(beta));
    double p0 = phi - d, p1 = phi + d;
    const double H = 0.5 * IBL_PI;
    if (p1 <= -H || p0 >= H) return 0;
    *lo = p0 <= -0.25 * IBL_PI ? -1.0 : tan(p0);
    *hi = p1 >= 0.25 * IBL_PI ? 1.0 : tan(p1);
    if (*lo < -1) *lo = -1;
    if (*hi > 1) *hi = 1;
    return *lo <= *hi;
}

typedef struct tile_pts {
    int count, x[TILE * TILE], y[TILE * TILE];
    double dir[TILE * TILE][3];
    double acc[TILE * TILE][4];
} tile_pts;

/* Whether the grid's directions are symmetric under the square's eight symmetries on a face
 * (edge fixups that bend directions are not assumed to be). */
static int grid_symmetric(const ibl_specular_plan *p, const grid *gr)
{
    return !gr->direct || centred_directions(p);
}

typedef struct grid_job {
    ibl_specular_plan *p;
    int level, mode; /* mode: EVAL_DEN (face 0 only) or numerators (every face) */
} grid_job;

static void sum_candidates(const sum_args *sa, tile_pts *tp)
{
    for (int k = 0; k < tp->count; k++) {
        const double *d = tp->dir[k];
        float R[3] = {(float)d[0], (float)d[1], (float)d[2]};
        float RR[6] = {R[0] * R[0], R[1] * R[1], R[2] * R[2],
                       2 * R[0] * R[1], 2 * R[0] * R[2], 2 * R[1] * R[2]};
        if (sa->avx2) sum_blocks_avx2(sa, R, RR, tp->acc[k]);
        else sum_blocks_generic(sa, R, RR, tp->acc[k]);
    }
}

typedef struct reach_test {
    const double *axis;     /* the tile's axis                                             */
    double T, cT, sT;       /* the tile's reach (the piece's end + the tile's radius)       */
    double hole, cH, sH;    /* the piece's hole seen from the tile (its start - the radius) */
    double th_out, th_in, cO, sO, cI, sI;
} reach_test;

/* Appends block b (cone info in `blocks`) to the candidates if it can matter for the tile;
 * 1 when the list is full. */
static int cone_misses(const reach_test *t, const float *bc)
{
    double c = dot3(t->axis, bc), r = bc[3], cr = bc[4], sr = bc[5];
    /* angle(axis, centre) > T + r: out of reach; < hole - r: inside the hole */
    if (t->T + r < IBL_PI && c < t->cT * cr - t->sT * sr - 1e-7) return 1;
    return t->hole - r > 0 && c > t->cH * cr + t->sH * sr + 1e-7;
}

static int add_candidate(sum_args *sa, const reach_test *t, const float *blocks, uint32_t b)
{
    const float *bc = blocks + (size_t)b * BINFO;
    if (cone_misses(t, bc)) return 0;
    double r = bc[3], cr = bc[4], sr = bc[5];
    cand *cd = (cand *)&sa->cands[sa->ncand++];
    cd->block = b;
    cd->cos_out = t->th_out + r >= IBL_PI ? -2.0f : (float)(t->cO * cr - t->sO * sr) - 1e-6f;
    cd->cos_in = t->th_in - r <= 0 ? 2.0f : (float)(t->cI * cr + t->sI * sr) + 1e-6f;
    return sa->ncand == CAND;
}

static void grid_task(void *arg, int index)
{
    const grid_job *job = arg;
    ibl_specular_plan *p = job->p;
    level_plan *lv = &p->lv[job->level];
    int faces = job->mode == EVAL_DEN ? 1 : 6;
    int g = 0, begin = 0;
    while (index >= begin + faces * lv->grids[g].tiles * lv->grids[g].tiles) {
        begin += faces * lv->grids[g].tiles * lv->grids[g].tiles;
        g++;
    }
    grid *gr = &lv->grids[g];
    int t = index - begin, face = t / (gr->tiles * gr->tiles);
    int ty = (t / gr->tiles) % gr->tiles, tx = t % gr->tiles, n = gr->n;
    if (job->mode == EVAL_DEN && grid_symmetric(p, gr)) {
        /* one eighth of the face: the tiles covering x <= y < ceil(n / 2) */
        int half = ((n + 1) / 2 + TILE - 1) / TILE;
        if (tx >= half || ty >= half || tx > ty) return;
    }
    tile_pts tp;
    tp.count = 0;
    double axis[3] = {0, 0, 0};
    for (int y = ty * TILE; y < (ty + 1) * TILE && y < n; y++)
        for (int x = tx * TILE; x < (tx + 1) * TILE && x < n; x++) {
            int k = tp.count++;
            tp.x[k] = x, tp.y[k] = y;
            if (gr->direct) {
                ibl__output_direction(&p->desc, &lv->lobe, face, n, x, y, tp.dir[k]);
            } else {
                double *d = tp.dir[k];
                ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, d);
                double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                for (int i = 0; i < 3; i++) d[i] /= len;
            }
            for (int i = 0; i < 3; i++) axis[i] += tp.dir[k][i];
            memset(tp.acc[k], 0, sizeof tp.acc[k]);
        }
    double alen = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    for (int i = 0; i < 3; i++) axis[i] /= alen;
    double mincos = 1.0;
    for (int k = 0; k < tp.count; k++) {
        double c = axis[0] * tp.dir[k][0] + axis[1] * tp.dir[k][1] + axis[2] * tp.dir[k][2];
        if (c < mincos) mincos = c;
    }
    double rho = acos(mincos > 1 ? 1 : mincos) + 1e-6;

    cand cands[CAND];
    int avx2 = cpu_has_avx2() && !p->portable;
    for (int pi = 0; pi < lv->npieces; pi++) {
        const piece *pc = &lv->pieces[pi];
        const srclev *s = &p->src[pc->src];
        int main_sum = pc->grid == g && !pc->core;
        /* a split ring's bright texels are summed at the output texels (the direct grid), and
         * so are the corrections of a precomputed core over a coarse level */
        int bright = pc->split && g == pc->bright_grid && job->mode != EVAL_DEN && s->nbright > 0;
        int corr = pc->core && pc->grid == g && job->mode != EVAL_DEN && pc->core->ncorr > 0;
        if (!main_sum && !bright && !corr) continue;
        sum_args sa = {job->mode == EVAL_DEN ? EVAL_DEN : pc->src == 0 ? EVAL_NUM0 : EVAL_NUMC,
                       avx2, s, pc, cands, 0, pc->split && !gr->direct};
        double T = pc->th_out + rho;
        reach_test reach = {axis, T, cos(T), sin(T), pc->th_in - rho, cos(pc->th_in - rho),
                            sin(pc->th_in - rho), pc->th_out, pc->th_in, cos(pc->th_out),
                            sin(pc->th_out), cos(pc->th_in), sin(pc->th_in)};
        for (int f = 0; main_sum && f < 6; f++) {
            const float(*B)[3] = p->face_basis[f];
            double u0, u1, v0, v1;
            if (T >= 0.5 * IBL_PI - 1e-9) {
                u0 = v0 = -1, u1 = v1 = 1;
            } else {
                if (!cap_range(axis, T, B[0], B[1], B[2], &u0, &u1)) continue;
                if (!cap_range(axis, T, B[0], B[2], B[1], &v0, &v1)) continue;
            }
            int M = s->M;
            int x0 = (int)floor((u0 + 1) * 0.5 * M) - 1, x1 = (int)ceil((u1 + 1) * 0.5 * M);
            int y0 = (int)floor((v0 + 1) * 0.5 * M) - 1, y1 = (int)ceil((v1 + 1) * 0.5 * M);
            x0 = x0 < 0 ? 0 : x0, y0 = y0 < 0 ? 0 : y0;
            x1 = x1 > M - 1 ? M - 1 : x1, y1 = y1 > M - 1 ? M - 1 : y1;
            for (int by = y0 / BH; by <= y1 / BH; by++)
                for (int bx = x0 / BW; bx <= x1 / BW; bx++) {
                    uint32_t b = (uint32_t)(((size_t)f * s->nby + by) * s->nbx + bx);
                    if (add_candidate(&sa, &reach, s->block, b)) {
                        sum_candidates(&sa, &tp);
                        sa.ncand = 0;
                    }
                }
        }
        if (sa.ncand) sum_candidates(&sa, &tp);
        if (bright || corr) {
            srclev bs = *s;
            bs.rec = bright ? s->bright_rec : pc->core->corr_rec;
            bs.block = bright ? s->bright_block : pc->core->corr_block;
            bs.nf = NFC;
            int nblocks = bright ? s->nbright : pc->core->ncorr;
            const float *supers = bs.block + (size_t)(bright ? s->bright_cap : pc->core->corr_cap) * BINFO;
            sa.s = &bs, sa.dim = 0, sa.ncand = 0;
            for (int g = 0; g * SUPER < nblocks; g++) {
                if (cone_misses(&reach, supers + (size_t)g * BINFO)) continue;
                for (int k = g * SUPER; k < (g + 1) * SUPER && k < nblocks; k++)
                    if (add_candidate(&sa, &reach, bs.block, (uint32_t)k)) {
                        sum_candidates(&sa, &tp);
                        sa.ncand = 0;
                    }
            }
            if (sa.ncand) sum_candidates(&sa, &tp);
        }
    }
    for (int k = 0; k < tp.count; k++) {
        float *o = gr->acc + (((size_t)face * n + tp.y[k]) * n + tp.x[k]) * 4;
        if (job->mode == EVAL_DEN) {
            o[3] = (float)tp.acc[k][3];
        } else {
            for (int c = 0; c < 3; c++) o[c] = (float)tp.acc[k][c];
        }
    }
}

typedef struct core_job {
    ibl_specular_plan *p;
    struct core *c;
    const piece *pc;
    const ibl__lobe *lobe;
    const float *geo;    /* CORE_GEO x P P, face 0 */
    int32_t *tmp_rows;   /* nb nb x (2 W + 1) x 3 */
    int *tmp_count;      /* nb nb: rows found (-1: the border is too narrow) */
    double cos_reach;       /* the window's reach (sizing)                          */
    double dot_min;         /* a cell counts when R.m >= dot_min: u < the piece's end */
    int avx2;
    const ibl_cubemap *src; /* run */
    float *acc;             /* run: the direct grid */
    int face;               /* run: the face being summed (its padded source in p->pad) */
} core_job;

/* Row Y of face 0's padded map. */
static void core_map_task(void *arg, int row)
{
    core_job *j = arg;
    struct core *c = j->c;
    int Y = row - c->O;
    if (Y < -c->W || Y >= c->S + c->W) return;
    for (int X = -c->W; X < c->S + c->W; X++)
        c->map[(size_t)row * c->P + X + c->O] = core_cell_texel(j->p, c->S, 0, X, Y);
}

/* Where the signed permutation taking face 0 to face F carries the texels of face g: face
 * out[0] and x' = out[1] + out[2] x + out[3] y, y' = out[4] + out[5] x + out[6] y. */
static void carry_face(const ibl_specular_plan *p, int S, int F, int g, int out[7])
{
    const float(*B0)[3] = p->face_basis[0], (*BF)[3] = p->face_basis[F];
    int xs[3], ys[3];
    for (int k = 0; k < 3; k++) {
        int x = k == 1, y = k == 2;
        double d[3], w[3], s, t;
        ibl_cube_direction_d(g, (x + 0.5) / S, (y + 0.5) / S, d);
        double l[3] = {0, 0, 0};
        for (int i = 0; i < 3; i++) l[0] += d[i] * B0[1][i], l[1] += d[i] * B0[2][i], l[2] += d[i] * B0[0][i];
        for (int i = 0; i < 3; i++) w[i] = l[0] * BF[1][i] + l[1] * BF[2][i] + l[2] * BF[0][i];
        out[0] = ibl_cube_face_st_d(w, &s, &t);
        xs[k] = (int)floor(s * S), ys[k] = (int)floor(t * S);
    }
    out[1] = xs[0], out[2] = xs[1] - xs[0], out[3] = xs[2] - xs[0];
    out[4] = ys[0], out[5] = ys[1] - ys[0], out[6] = ys[2] - ys[0];
}


/* The direction of base texel (a, b) of face 0 of the core's grid. */
static void core_direction(const core_job *j, int a, int b, double R[3])
{
    const struct core *c = j->c;
    if (c->direct) {
        ibl__output_direction(&j->p->desc, j->lobe, 0, c->n, a, b, R);
        return;
    }
    ibl_cube_direction_d(0, (a + 0.5) / c->n, (b + 0.5) / c->n, R);
    double len = sqrt(R[0] * R[0] + R[1] * R[1] + R[2] * R[2]);
    for (int i = 0; i < 3; i++) R[i] /= len;
}

/* The portable avx2_row_extent. */
static void row_extent_generic(const float *g, size_t plane, int n, const float R[3], float cr,
                               int *first, int *last)
{
    *first = *last = -1;
    for (int i = 0; i < n; i++) {
        float d = R[0] * g[i] + R[1] * g[plane + i] + R[2] * g[2 * plane + i];
        if (!(g[F_OM * plane + i] > 0) || !(d >= cr)) continue;
        if (*first < 0) *first = i;
        *last = i;
    }
}

/* The rows of the window around base texel `index` that hold cells within reach. */
/* The rows within reach of base texel `index`, scanning a window of half width w; 0 when a
 * row reaches the window's edge (the window is too small). */
static int core_rows_window(core_job *j, int index, const float R[3], int XC, int YC, int w)
{
    const struct core *c = j->c;
    int S = c->S, W = c->W;
    int lo = XC - w > -W ? XC - w : -W, hi = XC + w < S + W - 1 ? XC + w : S + W - 1;
    int ylo = YC - w > -W ? YC - w : -W, yhi = YC + w < S + W - 1 ? YC + w : S + W - 1;
    size_t plane = (size_t)c->P * c->P;
    int32_t *out = j->tmp_rows + (size_t)index * (2 * W + 1) * 3;
    int count = 0;
    for (int Y = ylo; Y <= yhi; Y++) {
        int first, last;
        const float *g = j->geo + (size_t)(Y + c->O) * c->P + c->O + lo;
        if (j->avx2) avx2_row_extent(g, plane, hi - lo + 1, R, (float)j->dot_min, &first, &last);
        else row_extent_generic(g, plane, hi - lo + 1, R, (float)j->dot_min, &first, &last);
        if (first < 0) continue;
        first += lo, last += lo;
        if (first == lo || last == hi || Y == ylo || Y == yhi) return 0;
        int32_t *r = out + 3 * count++;
        r[0] = Y, r[1] = first, r[2] = (last - first + 8) & ~7;
    }
    j->tmp_count[index] = count;
    return 1;
}

static void core_rows_task(void *arg, int index)
{
    core_job *j = arg;
    const struct core *c = j->c;
    int a = index % c->nb, b = index / c->nb, S = c->S, W = c->W;
    if (a > b) { /* (b, a)'s, transposed */
        j->tmp_count[index] = 0;
        return;
    }
    double Rd[3];
    core_direction(j, a, b, Rd);
    float R[3] = {(float)Rd[0], (float)Rd[1], (float)Rd[2]};
    int XC = (int)floor((a + 0.5) * S / c->n), YC = (int)floor((b + 0.5) * S / c->n);
    /* first a window sized by the texels around the base texel (radial size (2 / S) / (1 +
     * u^2 + v^2) on the face plane), then, if something lies on its edge, the whole border */
    double u = (XC + 0.5) * 2.0 / S - 1.0, v = (YC + 0.5) * 2.0 / S - 1.0;
    double cells = acos(j->cos_reach) * S * 0.5 * (1.0 + u * u + v * v);
    int w = (int)ceil(1.3 * cells) + 2;
    if (w < W && core_rows_window(j, index, R, XC, YC, w)) return;
    if (!core_rows_window(j, index, R, XC, YC, W)) j->tmp_count[index] = -1; /* W too small */
}

/* The weights of base texel `index` (and their sum), from the padded geometry. */
static void core_weights_task(void *arg, int index)
{
    core_job *j = arg;
    struct core *c = j->c;
    int a = index % c->nb, b = index / c->nb, P = c->P, O = c->O;
    if (a > b) return; /* (b, a)'s, transposed */
    double Rd[3];
    core_direction(j, a, b, Rd);
    float R[3] = {(float)Rd[0], (float)Rd[1], (float)Rd[2]};
    float RR[6] = {R[0] * R[0], R[1] * R[1], R[2] * R[2], 2 * R[0] * R[1], 2 * R[0] * R[2], 2 * R[1] * R[2]};
    size_t plane = (size_t)P * P;
    uint16_t *w = c->w + c->w0[index];
    double den = 0;
    float lanes[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    float inv = 1.0f / c->wscale;
    if (j->avx2) {
        avx2_base_weights(j->pc, R, RR, j->geo, plane, P, O, c->rows + 3 * (size_t)c->row0[index],
                          (int)(c->row0[index + 1] - c->row0[index]), inv, w, lanes);
        for (int l = 0; l < 8; l++) den += lanes[l];
        c->den[index] = den * c->wscale;
        return;
    }
    for (uint32_t r = c->row0[index]; r < c->row0[index + 1]; r++) {
        const int32_t *row = c->rows + 3 * (size_t)r;
        const float *g0 = j->geo + (size_t)(row[0] + O) * P + row[1] + O;
        /* weights, scaled, stored as halves (the portable avx2_base_weights) */
        for (int i = 0; i < row[2]; i++) {
            const float *g = g0 + i;
            float dx = R[0] - g[0], dy = R[1] - g[plane], dz = R[2] - g[2 * plane];
            float u = 0.5f * (dx * dx + dy * dy + dz * dz) + g[F_E * plane];
            float q = 0;
            for (int k = 0; k < 6; k++) q += RR[k] * g[(F_C + k) * plane];
            float v = table_weight(j->pc, u, q) * g[F_OM * plane] * inv;
            w[i] = ibl_float_to_half(v);
            lanes[i % 8] += ibl_half_to_float(w[i]);
        }
        w += row[2];
    }
    for (int l = 0; l < 8; l++) den += lanes[l];
    den *= c->wscale;
    c->den[index] = den;
}

/* The normalisers of the bases below the diagonal: their mirrors' (the same weights). */
static void core_mirror_den(struct core *c)
{
    for (int b = 0; b < c->nb; b++)
        for (int a = b + 1; a < c->nb; a++) c->den[b * c->nb + a] = c->den[a * c->nb + b];
}

/* Visits the distinct output texels that base texel (a, b) stands for: face, flips, (x, y). */
#define CORE_IMAGES(c, a, b, BODY)                                                            \
    for (int face_ = 0; face_ < 6; face_++)                                                   \
        for (int fy_ = 0; fy_ < 2; fy_++)                                                     \
            for (int fx_ = 0; fx_ < 2; fx_++) {                                               \
                int x_ = fx_ ? (c)->n - 1 - (a) : (a), y_ = fy_ ? (c)->n - 1 - (b) : (b);      \
                if ((fx_ && x_ == (a)) || (fy_ && y_ == (b))) continue;                       \
                BODY                                                                          \
            }

static void core_add_normalisers(const struct core *c, float *acc)
{
    for (int b = 0; b < c->nb; b++)
        for (int a = 0; a < c->nb; a++) {
            double den = c->den[b * c->nb + a];
            CORE_IMAGES(c, a, b, {
                float *o = acc + (((size_t)face_ * c->n + y_) * c->n + x_) * 4;
                o[3] = (float)(o[3] + den);
            })
        }
}

/* Whether texel (x, y) of face f of the core's level gets a centroid correction. */
static int texel_corrected(const struct core *c, const srclev *s, int f, int x, int y)
{
    size_t b = ((size_t)f * s->nby + y / BH) * s->nbx + x / BW;
    return c->bound[b * BT + (y % BH) * BW + x % BW] > c->corr_thr;
}

static void core_pad_task(void *arg, int index)
{
    core_job *j = arg;
    const struct core *c = j->c;
    int f = j->face, row = index, S = c->S, sh = 0;
    while ((1 << sh) < S) sh++;
    size_t plane = (size_t)c->P * c->P;
    const int32_t *map = c->map + (size_t)row * c->P;
    float *out = j->p->pad + (size_t)row * c->P;
    const srclev *s = &j->p->src[c->level];
    /* level 0: the source texels; a coarse level: its texels as uniform light, those with a
     * centroid correction left out (their moment leaves are summed instead) */
    const float *face[6];
    const float *uni = c->dim ? s->uni_dim : s->uni;
    for (int g = 0; g < 6; g++)
        face[g] = c->level == 0 ? ibl_cubemap_face(j->src, 0, g) : uni + (size_t)g * S * S * 4;
    int corr = c->level > 0 && c->ncorr > 0;
    /* inside the face itself the padded source is the face: copied by rows */
    int Y = row - c->O, inside = Y >= 0 && Y < S;
    if (inside) {
        const float *v = face[f] + (size_t)Y * S * 4;
        float *o = out + c->O;
        for (int x = 0; x < S; x++) o[x] = v[4 * x], o[plane + x] = v[4 * x + 1], o[2 * plane + x] = v[4 * x + 2];
        for (int x = 0; corr && x < S; x++)
            if (texel_corrected(c, s, f, x, Y)) o[x] = o[plane + x] = o[2 * plane + x] = 0.0f;
    }
    for (int X = 0; X < c->P; X++) {
        if (inside && X == c->O) X += S;
        if (X >= c->P) break;
        int32_t t0 = map[X];
        if (t0 < 0) {
            out[X] = out[plane + X] = out[2 * plane + X] = 0.0f;
            continue;
        }
        /* face 0's texel carried to face f by the permutation between the faces (S is a
         * power of two: shifts) */
        int g0 = t0 >> (2 * sh), y0 = (t0 >> sh) & (S - 1), x0 = t0 & (S - 1);
        const int *m = c->carry[f][g0];
        int g = m[0], x = m[1] + m[2] * x0 + m[3] * y0, y = m[4] + m[5] * x0 + m[6] * y0;
        if (corr && texel_corrected(c, s, g, x, y)) {
            out[X] = out[plane + X] = out[2 * plane + X] = 0.0f;
            continue;
        }
        const float *v = face[g] + ((size_t)y * S + x) * 4;
        out[X] = v[0], out[plane + X] = v[1], out[2 * plane + X] = v[2];
    }
}

/* sum over the rows of weights x source texels of padded face `planes` (r, g, b), the source
 * flipped by fx / fy */
static void core_mac_generic(const struct core *c, const uint16_t *w, const int32_t *rows, int nrows,
                             const float *planes, int fx, int fy, double out[3])
{
    size_t plane = (size_t)c->P * c->P;
    float acc[3][8] = {{0}};
    for (int r = 0; r < nrows; r++) {
        const int32_t *row = rows + 3 * r;
        int Y = fy ? c->S - 1 - row[0] : row[0];
        const float *base = planes + (size_t)(Y + c->O) * c->P + c->O;
        for (int i = 0; i < row[2]; i += 8)
            for (int l = 0; l < 8; l++) {
                int X = fx ? c->S - 1 - (row[1] + i + l) : row[1] + i + l;
                float wl = ibl_half_to_float(w[i + l]);
                for (int ch = 0; ch < 3; ch++) acc[ch][l] += wl * base[ch * plane + X];
            }
        w += row[2];
    }
    for (int ch = 0; ch < 3; ch++) {
        double s = 0;
        for (int l = 0; l < 8; l++) s += acc[ch][l];
        out[ch] = s * c->wscale;
    }
}

/* Rows TRANSPOSE_ROWS at a time of the transposed padded source (after the padded source in
 * p->pad): padT[Y][X] = pad[X][Y], plane by plane. */
enum { TRANSPOSE_ROWS = 16 };

static void core_transpose_task(void *arg, int index)
{
    core_job *j = arg;
    int P = j->c->P, y0 = index * TRANSPOSE_ROWS, y1 = y0 + TRANSPOSE_ROWS < P ? y0 + TRANSPOSE_ROWS : P;
    size_t plane = (size_t)P * P;
    for (int ch = 0; ch < 3; ch++) {
        const float *in = j->p->pad + ch * plane;
        float *out = j->p->pad + (3 + ch) * plane;
        for (int X = 0; X < P; X++)
            for (int Y = y0; Y < y1; Y++) out[(size_t)Y * P + X] = in[(size_t)X * P + Y];
    }
}

/* One row of base texels into the images of face j->face. Image by image, so that the source
 * rows under the row's windows stay in L1 while the row's weights stream from L2 (base by
 * base, every base re-read its windows from L2: measured 1.6x slower). A base below the
 * diagonal takes its mirror's weights on the transposed source, its flips swapped. */
static void core_mac_task(void *arg, int b)
{
    core_job *j = arg;
    const struct core *c = j->c;
    size_t plane = (size_t)c->P * c->P;
    int face = j->face;
    for (int fy = 0; fy < 2; fy++) {
        int y = fy ? c->n - 1 - b : b;
        if (fy && y == b) continue;
        for (int fx = 0; fx < 2; fx++)
            for (int a = 0; a < c->nb; a++) {
                int x = fx ? c->n - 1 - a : a;
                if (fx && x == a) continue;
                int mirror = a > b, index = mirror ? a * c->nb + b : b * c->nb + a;
                const uint16_t *w = c->w + c->w0[index];
                const int32_t *rows = c->rows + 3 * (size_t)c->row0[index];
                int nrows = (int)(c->row0[index + 1] - c->row0[index]);
                double s[3];
                const float *planes = j->p->pad + (mirror ? 3 * plane : 0);
                int gx = mirror ? fy : fx, gy = mirror ? fx : fy;
                if (j->avx2)
                    avx2_core_mac(c, w, c->vec + 2 * (c->w0[index] / 8), (int)((c->w0[index + 1] - c->w0[index]) / 8),
                                  planes, gx, gy, s);
                else core_mac_generic(c, w, rows, nrows, planes, gx, gy, s);
                float *o = j->acc + (((size_t)face * c->n + y) * c->n + x) * 4;
                for (int ch = 0; ch < 3; ch++) o[ch] = (float)(o[ch] + s[ch]);
            }
    }
}


typedef struct core_geo_job {
    const ibl_specular_plan *p;
    const struct core *c;
    float *geo;
} core_geo_job;

static void core_geometry_task(void *arg, int row)
{
    const core_geo_job *j = arg;
    const struct core *c = j->c;
    size_t plane = (size_t)c->P * c->P, S2 = (size_t)c->S * c->S;
    const srclev *s = &j->p->src[c->level];
    float *geo = j->geo;
    for (size_t i = (size_t)row * c->P; i < (size_t)(row + 1) * c->P; i++) {
        int32_t t = c->map[i];
        if (t < 0) {
            for (int f = 0; f < CORE_GEO; f++) geo[f * plane + i] = 0.0f;
            geo[F_E * plane + i] = 4.0f; /* u > 2: beyond every lobe */
            geo[GEO_FIELDS * plane + i] = 1.0f;
            continue;
        }
        int f = (int)(t / S2), y = (int)(t % S2) / c->S, x = (int)(t % S2) % c->S;
        if (c->level == 0 && !j->p->rec0) {
            float v[GEO_FIELDS];
            geo0_world(j->p, f, x, y, v);
            for (int k = 0; k < GEO_FIELDS; k++) geo[k * plane + i] = v[k];
        } else {
            const float *rec = s->rec + rec_index(s, f, x, y, 0);
            for (int k = 0; k < GEO_FIELDS; k++) geo[k * plane + i] = rec[k * BT];
        }
        double m0 = geo[i], m1 = geo[plane + i], m2 = geo[2 * plane + i];
        geo[GEO_FIELDS * plane + i] = (float)sqrt(m0 * m0 + m1 * m1 + m2 * m2);
    }
}

/* The padded geometry of face 0 (CORE_GEO planes of P P; cells without a texel: no weight). */
static float *core_geometry(ibl_specular_plan *p, const struct core *c)
{
    float *geo = ibl_alloc(p->ctx, CORE_GEO * (size_t)c->P * c->P * sizeof(float));
    if (!geo) return NULL;
    core_geo_job job = {p, c, geo};
    ibl_parallel_for(p->ctx, c->P, core_geometry_task, &job);
    return geo;
}

static ibl_status core_build_weights(ibl_specular_plan *p, int level)
{
    level_plan *lv = &p->lv[level];
    for (int k = 0; k < lv->npieces; k++) {
        struct core *c = lv->pieces[k].core;
        if (!c) continue;
        float *geo = core_geometry(p, c);
        if (!geo) return ibl_context_status(p->ctx);
        core_job job = {p, c, &lv->pieces[k], &lv->lobe, geo, NULL, NULL, 0, 0, cpu_has_avx2() && !p->portable,
                        NULL, NULL, 0};
        ibl_parallel_for(p->ctx, c->nb * c->nb, core_weights_task, &job);
        core_mirror_den(c);
        ibl_free(p->ctx, geo);
    }
    return IBL_OK;
}

/* Sets up piece k of a level as precomputed weights when it can be (a symmetric grid, level 0
 * only without sub-texels, a reach the padded face holds); leaves it to the leaf sums when
 * the border would be too deep or the weights too many. */
static ibl_status core_create_piece(ibl_specular_plan *p, int level, int k)
{
    level_plan *lv = &p->lv[level];
    piece *pc = &lv->pieces[k];
    grid *gr = &lv->grids[pc->grid];
    if ((pc->src == 0 && p->K != 1) || !grid_symmetric(p, gr)) return IBL_OK;
    int S = p->src[pc->src].M;
    /* reach: the core's end plus a texel's angular radius; a cell subtends at least 1 / (1.5 S)
     * radians (radially, at a face corner), so W cells of border hold everything in reach (the
     * border is at most a whole neighbouring face) */
    double reach = pc->th_out + 2.0 / S;
    if (reach > 1.2) return IBL_OK;
    int W = (int)ceil(1.5 * S * reach) + 2;
    if (W > S) W = S;
    ibl_context *ctx = p->ctx;
    struct core *c = ibl_calloc(ctx, 1, sizeof *c);
    if (!c) return ibl_context_status(ctx);
    c->level = pc->src;
    c->direct = gr->direct;
    c->dim = pc->split;
    c->S = S, c->W = W, c->O = W + 8, c->P = S + 2 * W + 16, c->n = gr->n, c->nb = (gr->n + 1) / 2;
    size_t plane = (size_t)c->P * c->P, nbase = (size_t)c->nb * c->nb;
    ibl_status st = IBL_OK;
    float *geo = NULL;
    int32_t *tmp_rows = NULL;
    int *tmp_count = NULL;
    c->map = ibl_alloc(ctx, plane * sizeof(int32_t));
    c->row0 = ibl_alloc(ctx, (nbase + 1) * sizeof(uint32_t));
    c->w0 = ibl_alloc(ctx, (nbase + 1) * sizeof(size_t));
    c->den = ibl_alloc(ctx, nbase * sizeof(double));
    tmp_rows = ibl_alloc(ctx, nbase * (2 * W + 1) * 3 * sizeof(int32_t));
    tmp_count = ibl_alloc(ctx, nbase * sizeof(int));
    if (!c->map || !c->row0 || !c->w0 || !c->den || !tmp_rows || !tmp_count) goto fail;
    for (size_t i = 0; i < plane; i++) c->map[i] = -1;
    for (int f = 0; f < 6; f++)
        for (int g = 0; g < 6; g++) carry_face(p, S, f, g, c->carry[f][g]);
    /* u0 = 1 - R.m for a leaf at centroid m: the piece is zero from u_hi on, exactly */
    double dot_min = 1.0 - (pc->u_hi < 2.0 ? pc->u_hi : 2.0) - 1e-6;
    core_job job = {p, c, pc, &lv->lobe, NULL, tmp_rows, tmp_count, cos(reach), dot_min, cpu_has_avx2() && !p->portable,
                    NULL, NULL, 0};
    ibl_parallel_for(ctx, c->P, core_map_task, &job);
    job.geo = geo = core_geometry(p, c);
    if (!geo) goto fail;
    ibl_parallel_for(ctx, (int)nbase, core_rows_task, &job);
    size_t rows = 0, weights = 0;
    for (size_t i = 0; i < nbase; i++) {
        if (tmp_count[i] < 0) goto give_up;
        c->row0[i] = (uint32_t)rows;
        c->w0[i] = weights;
        for (int r = 0; r < tmp_count[i]; r++) weights += (size_t)tmp_rows[(i * (2 * W + 1) + r) * 3 + 2];
        rows += (size_t)tmp_count[i];
    }
    c->row0[nbase] = (uint32_t)rows;
    c->w0[nbase] = weights;
    if (weights > ((size_t)1 << 25)) goto give_up; /* 128 MiB of weights: sum by leaves instead */
    c->rows = ibl_alloc(ctx, (rows ? rows : 1) * 3 * sizeof(int32_t));
    c->w = ibl_alloc(ctx, (weights ? weights : 1) * sizeof(uint16_t));
    c->vec = ibl_alloc(ctx, (weights / 8 + 1) * 2 * sizeof(uint16_t));
    /* the weights' bound: the largest texel (a face centre) times twice the piece's peak
     * (the second-order term can add a little); stored weights are then at most ~1, where
     * half floats keep 11 bits */
    double gmax = 0;
    for (int i = 0; i <= TAB; i++) gmax = fabs(pc->tab[2 * i]) > gmax ? fabs(pc->tab[2 * i]) : gmax;
    c->wscale = (float)(2.0 * gmax * ibl_cube_texel_solid_angle(S, S / 2, S / 2));
    if (!(c->wscale > 0)) c->wscale = 1.0f;
    if (!c->rows || !c->w || !c->vec) goto fail;
    for (size_t i = 0; i < nbase; i++)
        memcpy(c->rows + 3 * (size_t)c->row0[i], tmp_rows + i * (2 * W + 1) * 3,
               (size_t)tmp_count[i] * 3 * sizeof(int32_t));
    for (size_t r = 0, v = 0; r < rows; r++) /* padded cells are below 3 S + 16 <= 49168 */
        for (int i = 0; i < c->rows[3 * r + 2]; i += 8, v++) {
            c->vec[2 * v] = (uint16_t)(c->rows[3 * r + 1] + i + c->O);
            c->vec[2 * v + 1] = (uint16_t)(c->rows[3 * r] + c->O);
        }
    ibl_free(ctx, tmp_rows);
    ibl_free(ctx, tmp_count);
    job.avx2 = cpu_has_avx2() && !p->portable;
    ibl_parallel_for(ctx, (int)nbase, core_weights_task, &job);
    core_mirror_den(c);
    ibl_free(ctx, geo);
    pc->core = c;
    return IBL_OK;
fail:
    st = ibl_context_status(ctx);
give_up:
    ibl_free(ctx, geo);
    ibl_free(ctx, tmp_rows);
    ibl_free(ctx, tmp_count);
    core_destroy(ctx, c);
    return st;
}

/* Precomputes every piece of the level that can be (see core_create_piece). */
static ibl_status core_create(ibl_specular_plan *p, int level)
{
    for (int k = 0; k < p->lv[level].npieces; k++) {
        ibl_status st = core_create_piece(p, level, k);
        if (st != IBL_OK) return st;
    }
    return IBL_OK;
}

/* Adds the level's precomputed pieces to the numerators of their grids. */
static void core_run(ibl_specular_plan *p, int level, const ibl_cubemap *src)
{
    level_plan *lv = &p->lv[level];
    for (int k = 0; k < lv->npieces; k++) {
        struct core *c = lv->pieces[k].core;
        if (!c) continue;
        core_job job = {p, c, &lv->pieces[k], &lv->lobe, NULL, NULL, NULL, 0, 0, cpu_has_avx2() && !p->portable,
                        src, lv->grids[lv->pieces[k].grid].acc, 0};
        /* face by face: the padded source and its transpose (2 x 3 planes of P^2) stay in cache */
        for (job.face = 0; job.face < 6; job.face++) {
            ibl_parallel_for(p->ctx, c->P, core_pad_task, &job);
            ibl_parallel_for(p->ctx, (c->P + TRANSPOSE_ROWS - 1) / TRANSPOSE_ROWS, core_transpose_task, &job);
            ibl_parallel_for(p->ctx, c->nb, core_mac_task, &job);
        }
    }
}

/* The normalisers: the geometric sums depend only on the direction's (s, t) on its face (the
 * cube's texels are carried onto themselves by the signed permutations that swap faces), so
 * they are summed for face 0 and copied; within the face, the reflections x -> n-1-x,
 * y -> n-1-y and x <-> y are symmetries of the cube too, so one eighth of it is summed. */
static void plan_denominators(ibl_specular_plan *p, int level)
{
    level_plan *lv = &p->lv[level];
    int tasks = 0;
    for (int g = 0; g < lv->ngrids; g++) tasks += lv->grids[g].tiles * lv->grids[g].tiles;
    grid_job job = {p, level, EVAL_DEN};
    ibl_parallel_for(p->ctx, tasks, grid_task, &job);
    for (int g = 0; g < lv->ngrids; g++) {
        grid *gr = &lv->grids[g];
        int n = gr->n;
        if (grid_symmetric(p, gr))
            for (int y = 0; y < n; y++)
                for (int x = 0; x < n; x++) {
                    int a = x < n - 1 - x ? x : n - 1 - x, b = y < n - 1 - y ? y : n - 1 - y;
                    if (a > b) {
                        int t = a;
                        a = b, b = t;
                    }
                    gr->acc[((size_t)y * n + x) * 4 + 3] = gr->acc[((size_t)b * n + a) * 4 + 3];
                }
        size_t face = (size_t)gr->n * gr->n * 4;
        for (int f = 1; f < 6; f++)
            for (size_t i = 3; i < face; i += 4) gr->acc[f * face + i] = gr->acc[i];
    }
    for (int k = 0; k < lv->npieces; k++)
        if (lv->pieces[k].core) core_add_normalisers(lv->pieces[k].core, lv->grids[lv->pieces[k].grid].acc);
}

/* ---- run: combining the grids into the output level ---- */

typedef struct grid_pad_job {
    const ibl_specular_plan *p;
    grid *gr;
} grid_pad_job;

/* Face f of a coarse grid's bordered copy (grid.pad). */
static void grid_pad_task(void *arg, int f)
{
    const grid_pad_job *j = arg;
    grid *gr = j->gr;
    int n = gr->n, m = n + 2;
    float *out = gr->pad + (size_t)f * m * m * 4;
    for (int Y = -1; Y <= n; Y++)
        for (int X = -1; X <= n; X++) {
            float *o = out + ((size_t)(Y + 1) * m + X + 1) * 4;
            int ox = X < 0 || X >= n, oy = Y < 0 || Y >= n;
            if (ox && oy) { /* a cube corner: the mean of the three texels around it */
                int cx = X < 0 ? 0 : n - 1, cy = Y < 0 ? 0 : n - 1;
                int32_t t[3] = {core_cell_texel(j->p, n, f, cx, cy), core_cell_texel(j->p, n, f, X, cy),
                                core_cell_texel(j->p, n, f, cx, Y)};
                for (int c = 0; c < 4; c++) {
                    float v = 0;
                    for (int k = 0; k < 3; k++) v += gr->acc[(size_t)t[k] * 4 + c] * (1.0f / 3.0f);
                    o[c] = v;
                }
                continue;
            }
            int32_t t = core_cell_texel(j->p, n, f, X, Y);
            for (int c = 0; c < 4; c++) o[c] = gr->acc[(size_t)t * 4 + c];
        }
}

static void combine_task(void *arg, int index)
{
    ibl_specular_plan *p = arg;
    level_plan *lv = &p->lv[p->run_level];
    int n = ibl_level_size(p->N, p->run_level), face = index / n, y = index % n;
    float *row = ibl_cubemap_face(p->run_dst, p->run_level, face) + (size_t)y * n * 4;
    const grid *direct = NULL;
    /* the coarse grids this row reads: by the texel centre's bilinear footprint on the
     * bordered grid (it never leaves it: gx is in [-1/2, gn - 1/2]) when the output directions
     * are the texel centres and the grid divides the level; otherwise by direction */
    const float *rows[MAX_GRIDS][2];
    float fy[MAX_GRIDS], scale[MAX_GRIDS];
    int sampled[MAX_GRIDS], nrows = 0, nsampled = 0;
    int centred = centred_directions(p);
    for (int g = 0; g < lv->ngrids; g++) {
        const grid *gr = &lv->grids[g];
        int gn = gr->n;
        if (gr->direct) {
            direct = gr;
        } else if (centred && n % gn == 0) {
            float gy = (y + 0.5f) * gn / n - 0.5f;
            int iy = (int)floorf(gy);
            rows[nrows][0] = gr->pad + (((size_t)face * (gn + 2) + iy + 1) * (gn + 2) + 1) * 4;
            rows[nrows][1] = rows[nrows][0] + (size_t)(gn + 2) * 4;
            fy[nrows] = gy - iy;
            scale[nrows++] = (float)gn / n;
        } else {
            sampled[nsampled++] = g;
        }
    }
    for (int x = 0; x < n; x++) {
        float v[4] = {0, 0, 0, 0};
        if (direct) {
            const float *a = direct->acc + (((size_t)face * n + y) * n + x) * 4;
            for (int c = 0; c < 4; c++) v[c] = a[c];
        }
#if defined(__SSE2__)
        __m128 acc = _mm_loadu_ps(v);
        for (int k = 0; k < nrows; k++) {
            float gx = (x + 0.5f) * scale[k] - 0.5f;
            int ix = (int)floorf(gx);
            const float *a = rows[k][0] + (ptrdiff_t)ix * 4, *b = rows[k][1] + (ptrdiff_t)ix * 4;
            __m128 fx = _mm_set1_ps(gx - ix), a0 = _mm_loadu_ps(a), b0 = _mm_loadu_ps(b);
            __m128 top = _mm_add_ps(a0, _mm_mul_ps(fx, _mm_sub_ps(_mm_loadu_ps(a + 4), a0)));
            __m128 bot = _mm_add_ps(b0, _mm_mul_ps(fx, _mm_sub_ps(_mm_loadu_ps(b + 4), b0)));
            acc = _mm_add_ps(acc, _mm_add_ps(top, _mm_mul_ps(_mm_set1_ps(fy[k]), _mm_sub_ps(bot, top))));
        }
        _mm_storeu_ps(v, acc);
#else
        for (int k = 0; k < nrows; k++) {
            float gx = (x + 0.5f) * scale[k] - 0.5f;
            int ix = (int)floorf(gx);
            float fx = gx - ix;
            const float *a = rows[k][0] + (ptrdiff_t)ix * 4, *b = rows[k][1] + (ptrdiff_t)ix * 4;
            for (int c = 0; c < 4; c++) {
                float top = a[c] + fx * (a[4 + c] - a[c]);
                float bot = b[c] + fx * (b[4 + c] - b[c]);
                v[c] += top + fy[k] * (bot - top);
            }
        }
#endif
        if (nsampled) {
            double d[3];
            ibl__output_direction(&p->desc, &lv->lobe, face, n, x, y, d);
            ibl_vec3 dv = {(float)d[0], (float)d[1], (float)d[2]};
            for (int k = 0; k < nsampled; k++) {
                const grid *gr = &lv->grids[sampled[k]];
                ibl_cubemap cube = {gr->n, 1, gr->acc, 0};
                float s4[4];
                ibl_cubemap_sample_bilinear(&cube, 0, dv, s4);
                for (int c = 0; c < 4; c++) v[c] += s4[c];
            }
        }
        float *o = row + x * 4;
        float inv = v[3] > 0 ? 1.0f / v[3] : 0.0f;
        for (int c = 0; c < 3; c++) {
            float r = v[c] * inv;
            o[c] = r > 0 ? r : 0.0f;
        }
        o[3] = 1.0f;
    }
}

/* ---- run: mirror levels ---- */

typedef struct mirror_job {
    const ibl_specular_plan *p;
    const ibl_cubemap *src;
    ibl_cubemap *dst;
    int level;
} mirror_job;

static void mirror_row_task(void *arg, int index)
{
    const mirror_job *job = arg;
    const ibl_specular_plan *p = job->p;
    int n = ibl_level_size(p->N, job->level), face = index / n, y = index % n;
    float *row = ibl_cubemap_face(job->dst, job->level, face) + (size_t)y * n * 4;
    if (n == p->S) {
        memcpy(row, ibl_cubemap_face(job->src, 0, face) + (size_t)y * n * 4,
               (size_t)n * 4 * sizeof(float));
        return;
    }
    if (n < p->S && is_pow2(n)) {
        int sl = 0;
        while ((p->src[0].M >> sl) > n) sl++;
        const srclev *s = &p->src[sl];
        for (int x = 0; x < n; x++) {
            float om = s->rec[rec_index(s, face, x, y, F_OM)];
            for (int c = 0; c < 3; c++) row[x * 4 + c] = s->rec[rec_index(s, face, x, y, F_P + c)] / om;
            row[x * 4 + 3] = 1.0f;
        }
        return;
    }
    for (int x = 0; x < n; x++) {
        double d[3];
        ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, d);
        ibl_vec3 v = {(float)d[0], (float)d[1], (float)d[2]};
        ibl_cubemap_sample_bilinear(job->src, 0, v, row + x * 4);
    }
}

ibl_status ibl_specular_plan_run(ibl_specular_plan *p, const ibl_cubemap *src, ibl_cubemap *dst)
{
    if (!p || !src || !dst || !src->data || !dst->data) return IBL_ERR_INVALID_ARGUMENT;
    ibl_context *ctx = p->ctx;
    if (src->size != p->S || dst->size != p->N || dst->levels != p->L)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "specular run: planned source %d -> %d x %d levels, got %d -> %d x %d",
                        p->S, p->N, p->L, src->size, dst->size, dst->levels);
    if (p->dyn) {
        ibl__dynamic_mips(p->dyn, src);
        for (int l = 0; l < p->L; l++) {
            ibl__dynamic_level(p->dyn, dst, l);
            ibl_status st = ibl_edge_fixup_apply(ctx, p->desc.edge_fixup, dst, l);
            if (st != IBL_OK) return st;
        }
        return ibl__progress(ctx, "prefilter", 1.0);
    }
    pyr_job pj = {p, src, 0};
    if (p->rec0) ibl_parallel_for(ctx, 6 * p->src[0].nby, level0_task, &pj);
    for (int l = 1; l < p->SL; l++) {
        pyr_job job = {p, src, l};
        ibl_parallel_for(ctx, 6 * p->src[l].nby, pyramid_task, &job);
        p->src[l].power = 0;
        for (int i = 0; i < 6 * p->src[l].nby; i++) p->src[l].power += p->src[l].row_power[i];
        if (p->src[l].bright_c > 0) select_bright(p, l);
        if (p->src[l].uni || p->src[l].uni_dim) ibl_parallel_for(ctx, 6 * p->src[l].M, uniform_task, &job);
    }
    size_t pool_used = 0; /* blocks of p->corr_pool taken */
    for (int l = 0; l < p->L; l++)
        for (int k = 0; k < p->lv[l].npieces; k++) {
            struct core *c = p->lv[l].pieces[k].core;
            if (c && c->corr_cap > 0) {
                c->corr_rec = p->corr_pool + pool_used * NFC * BT;
                select_corrections(p, c);
                pool_used += (size_t)c->ncorr;
            }
        }
    p->run_src = src;
    p->run_dst = dst;
    for (int l = 0; l < p->L; l++) {
        if (p->lv[l].lobe.kind == IBL__LOBE_MIRROR) {
            mirror_job job = {p, src, dst, l};
            ibl_parallel_for(ctx, 6 * ibl_level_size(p->N, l), mirror_row_task, &job);
        } else {
            p->run_level = l;
            grid_job job = {p, l, EVAL_NUM0};
            ibl_parallel_for(ctx, p->lv[l].tasks, grid_task, &job);
            core_run(p, l, src);
            for (int g = 0; g < p->lv[l].ngrids; g++) {
                if (!p->lv[l].grids[g].pad) continue;
                grid_pad_job gj = {p, &p->lv[l].grids[g]};
                ibl_parallel_for(ctx, 6, grid_pad_task, &gj);
            }
            ibl_parallel_for(ctx, 6 * ibl_level_size(p->N, l), combine_task, p);
        }
        ibl_status st = ibl_edge_fixup_apply(ctx, p->desc.edge_fixup, dst, l);
        if (st != IBL_OK) return st;
        st = ibl__progress(ctx, "prefilter", (l + 1.0) / p->L);
        if (st != IBL_OK) return st;
    }
    return IBL_OK;
}

void ibl__specular_plan_stats(const ibl_specular_plan *p, ibl__specular_stats *out)
{
    memset(out, 0, sizeof *out);
    for (int l = 0; l < p->L; l++)
        for (int k = 0; k < p->lv[l].npieces; k++) {
            const piece *pc = &p->lv[l].pieces[k];
            out->pieces++;
            out->split += pc->split;
            if (!pc->core) continue;
            out->precomputed++;
            out->precomputed_coarse += pc->core->level > 0;
            out->correction_blocks += pc->core->ncorr;
        }
    for (int l = 0; l < p->SL; l++) out->bright_blocks += p->src[l].nbright;
}
