/* The four inner loops of the fast prefilter with AVX2, FMA and F16C (see fast_kernels in
 * fast_internal.h), eight texels per vector; chosen per plan when the context's CPU features
 * allow them (core/cpu.h). Their portable twins are in kernels_portable.c.
 *
 * The leaf evaluates the piece in closed form rather than from its table: GGX's
 * D(h) (n.l) / D(n) in u = 1 - R.l (Walter et al. 2007, with v = n as in the split-sum
 * prefilter, Karis 2013), Phong's x^n (Phong 1975) through a vector log and exp, and the two
 * quintic steps of the partition. Phong texels whose spread reaches the horizon take the
 * closed-form mean of x^n over the spread. The products convert eight half-float weights at a
 * time (F16C) and keep two sets of accumulators, so that the loads bound them rather than the
 * FMA latency. The functions are named avx2_* and their twins portable_*: under one name, a
 * profile of a binary without debug information (perf report) cannot tell which one ran. */
#include "bake/specular/fast_internal.h"
#include "core/cpu.h"

#if IBL_HAVE_X86_KERNELS
#include <immintrin.h>

#define KERNEL_INLINE IBL_TARGET_AVX2 __attribute__((always_inline)) static inline

/* A piece's constants, broadcast once per call. */
typedef struct lobe_vectors {
    __m256 half, zero, one, two, c4, c6, cm15, c10, c30, c60;
    __m256 alpha2, slope, alpha4, slope6;            /* GGX: alpha^2, kappa, alpha^4, 6 kappa^2 */
    __m256 out_scale, out_offset, out_slope, in_scale, in_offset, in_slope;
    __m256 n, nn1, xmin;          /* Phong: n, n (n - 1), smallest x divided by */
    __m256 n1, three, amin, tiny; /* Phong's mean over the spread at the horizon */
    __m256 u_start, u_end; /* the inner step's start, the outer's end: g = g'' = 0 outside */
    int has_in, has_out;
    int phong_series;      /* Phong x^n through series in u (phong_series_leaf)              */
} lobe_vectors;

IBL_TARGET_AVX2 static void lobe_setup(const lobe_piece *pc, lobe_vectors *k)
{
    k->half = _mm256_set1_ps(0.5f), k->zero = _mm256_setzero_ps(), k->one = _mm256_set1_ps(1.0f);
    k->two = _mm256_set1_ps(2.0f), k->c4 = _mm256_set1_ps(4.0f), k->c6 = _mm256_set1_ps(6.0f);
    k->cm15 = _mm256_set1_ps(-15.0f), k->c10 = _mm256_set1_ps(10.0f);
    k->c30 = _mm256_set1_ps(30.0f), k->c60 = _mm256_set1_ps(60.0f);
    k->alpha2 = _mm256_set1_ps(pc->ggx_alpha2), k->slope = _mm256_set1_ps(pc->ggx_slope);
    k->alpha4 = _mm256_set1_ps(pc->ggx_alpha4);
    k->slope6 = _mm256_set1_ps(6.0f * pc->ggx_slope * pc->ggx_slope);
    k->out_scale = _mm256_set1_ps(pc->outer.scale), k->out_offset = _mm256_set1_ps(pc->outer.offset);
    k->out_slope = _mm256_set1_ps(pc->outer.slope), k->in_scale = _mm256_set1_ps(pc->inner.scale);
    k->in_offset = _mm256_set1_ps(pc->inner.offset), k->in_slope = _mm256_set1_ps(pc->inner.slope);
    k->n = _mm256_set1_ps(pc->phong_n), k->nn1 = _mm256_set1_ps(pc->phong_n * (pc->phong_n - 1.0f));
    k->xmin = _mm256_set1_ps(1e-3f);
    k->n1 = _mm256_set1_ps(pc->phong_n + 1.0f), k->three = _mm256_set1_ps(3.0f);
    k->amin = _mm256_set1_ps(1e-6f), k->tiny = _mm256_set1_ps(1e-30f);
    k->has_in = pc->inner.scale != 0.0f;
    k->has_out = pc->outer.scale != 0.0f;
    /* s = u scale - offset reaches 1 (psi_out = 0, clamped) at u = (1 + offset) / scale */
    k->u_end = _mm256_set1_ps(k->has_out ? (1.0f + pc->outer.offset) / pc->outer.scale : 4.0f);
    /* ... and psi_in = 1 = psi_out (p0 = p1 = p2 = 0) while s_in = u scale - offset <= 0 */
    k->u_start = _mm256_set1_ps(k->has_in ? pc->inner.offset / pc->inner.scale : -1.0f);
    k->phong_series = pc->phong_series;
}

/* ln x for x in (0, 1]: x = m 2^e with m in [sqrt(1/2), sqrt(2)), ln m = 2 atanh(r),
 * r = (m - 1) / (m + 1), |r| <= 0.172, its odd series to r^9 (error < 1e-9) */
KERNEL_INLINE __m256 vector_log(__m256 x)
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
KERNEL_INLINE __m256 vector_exp(__m256 y)
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

/* psi = 1 - S(s), s = clamp(u scale - offset, 0, 1), S the quintic smootherstep; v1, v2 are
 * -psi' and -psi'' */
KERNEL_INLINE void vector_psi(const lobe_vectors *k, __m256 u, __m256 scale, __m256 offset,
                              __m256 slope, __m256 *v0, __m256 *v1, __m256 *v2)
{
    __m256 s = _mm256_min_ps(_mm256_max_ps(_mm256_fmsub_ps(u, scale, offset), k->zero), k->one);
    __m256 t = _mm256_sub_ps(k->one, s), ss = _mm256_mul_ps(s, s);
    __m256 S = _mm256_mul_ps(_mm256_mul_ps(ss, s),
                             _mm256_fmadd_ps(s, _mm256_fmadd_ps(s, k->c6, k->cm15), k->c10));
    __m256 S1 = _mm256_mul_ps(_mm256_mul_ps(k->c30, ss), _mm256_mul_ps(t, t));
    __m256 S2 = _mm256_mul_ps(_mm256_mul_ps(k->c60, s), _mm256_mul_ps(t, _mm256_fnmadd_ps(k->two, s, k->one)));
    *v0 = _mm256_sub_ps(k->one, S);
    *v1 = _mm256_mul_ps(S1, slope);
    *v2 = _mm256_mul_ps(S2, _mm256_mul_ps(slope, slope));
}

/* Phong's x^n has a kink at the horizon (and for n < 2 an unbounded f''): a texel whose u
 * spread reaches it takes the mean of f over u0 +- a, a = sqrt(3 q), in closed form
 * ((x + a)^(n+1) - (x - a)^(n+1)) / (2 a (n + 1)) -- the same to second order where the Taylor
 * leaf is valid, exact at the kink for a uniform spread. w is the Taylor leaf, p0 the
 * partition, xraw = 1 - u. */
KERNEL_INLINE __m256 phong_horizon(const lobe_vectors *k, __m256 w, __m256 u, __m256 q,
                                   __m256 xraw, __m256 p0)
{
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
                              vector_exp(_mm256_mul_ps(k->n1, vector_log(_mm256_max_ps(xl, k->tiny)))));
    __m256 ph = _mm256_and_ps(_mm256_cmp_ps(xh, k->zero, _CMP_GT_OQ),
                              vector_exp(_mm256_mul_ps(k->n1, vector_log(_mm256_max_ps(xh, k->tiny)))));
    __m256 box = _mm256_div_ps(_mm256_sub_ps(pl, ph),
                               _mm256_mul_ps(_mm256_mul_ps(k->two, _mm256_max_ps(a, k->amin)), k->n1));
    return _mm256_blendv_ps(w, _mm256_mul_ps(box, p0), near);
}

/* Phong's f = x^n, -f' and f'' in u = 1 - x, for the pieces of a narrow lobe (u <= 0.1 where
 * they are not zero): ln x = -(u + u^2/2 + ... + u^6/6) and 1 / x = 1 + u + ... + u^6 by Horner,
 * whose first dropped terms are within PHONG_SERIES_MAX_ERROR of f (relative) and 1e-7 of 1 / x
 * at the piece's end (lobe_piece.phong_series, pieces.c). This is the closed form without vector_log's division and
 * 1 / x's, and from u itself: x = 1 - u rounded to a float moves n ln x by up to n 6e-8 (1.2e-4
 * at n = 2049) next to the axis, where u ~ 1e-4. Beyond the piece's end (its outer step, or
 * for the last piece, the lobe's 1e-9 cull, u >= 20.7 / n) the truncated series only keeps f
 * as small: every term is positive. Nor does the horizon's closed-form mean (phong_horizon)
 * apply: it takes texels with u >= 1/3, where such a lobe is below (2/3)^200. */
KERNEL_INLINE void phong_series_leaf(const lobe_vectors *k, __m256 u, __m256 *f0, __m256 *f1,
                                     __m256 *f2)
{
    __m256 s = _mm256_fmadd_ps(u, _mm256_set1_ps(1.0f / 6.0f), _mm256_set1_ps(1.0f / 5.0f));
    s = _mm256_fmadd_ps(u, s, _mm256_set1_ps(0.25f));
    s = _mm256_fmadd_ps(u, s, _mm256_set1_ps(1.0f / 3.0f));
    s = _mm256_fmadd_ps(u, s, k->half);
    s = _mm256_fmadd_ps(u, s, k->one);
    __m256 ix = _mm256_fmadd_ps(u, k->one, k->one);
    for (int i = 0; i < 5; i++) ix = _mm256_fmadd_ps(u, ix, k->one);
    *f0 = vector_exp(_mm256_mul_ps(_mm256_sub_ps(k->zero, k->n), _mm256_mul_ps(u, s)));
    __m256 fx = _mm256_mul_ps(*f0, ix);
    *f1 = _mm256_sub_ps(k->zero, _mm256_mul_ps(k->n, fx));
    *f2 = _mm256_mul_ps(k->nn1, _mm256_mul_ps(fx, ix));
}

/* g + g'' q / 2 of the piece at u, in closed form. */
KERNEL_INLINE __m256 vector_leaf(const lobe_vectors *k, int ggx, __m256 u, __m256 q)
{
    __m256 xraw = _mm256_sub_ps(k->one, u), x = _mm256_max_ps(xraw, k->zero);
    __m256 front = _mm256_cmp_ps(u, k->one, _CMP_LT_OQ);
    __m256 f0, f1, f2;
    if (ggx) {
        /* f = (1 - u) alpha4 / T^2, T = alpha2 + kappa u; f' and f'' in u; zero beyond the
         * horizon. 1 / T by a division, correctly rounded on every CPU: the reciprocal
         * estimate (vrcpps), even after a Newton step, gives other bits on Intel than on AMD,
         * and so did the chains */
        __m256 T = _mm256_fmadd_ps(k->slope, u, k->alpha2), it = _mm256_div_ps(k->one, T);
        __m256 A = _mm256_mul_ps(k->alpha4, _mm256_mul_ps(it, it));
        __m256 xi = _mm256_mul_ps(x, it);
        f0 = _mm256_mul_ps(x, A);
        f1 = _mm256_and_ps(front, _mm256_fnmsub_ps(A, _mm256_mul_ps(_mm256_add_ps(k->slope, k->slope), xi), A));
        f2 = _mm256_and_ps(front, _mm256_mul_ps(_mm256_mul_ps(A, it),
                                                _mm256_fmadd_ps(k->slope6, xi, _mm256_mul_ps(k->c4, k->slope))));
    } else if (k->phong_series) {
        phong_series_leaf(k, u, &f0, &f1, &f2);
    } else {
        /* Phong: f = x^n, f' = -n f / x, f'' = n (n - 1) f / x^2 (in u = 1 - x) */
        __m256 xs = _mm256_max_ps(x, k->xmin), ix = _mm256_div_ps(k->one, xs);
        f0 = _mm256_and_ps(front, vector_exp(_mm256_mul_ps(k->n, vector_log(xs))));
        __m256 fx = _mm256_mul_ps(f0, ix);
        f1 = _mm256_sub_ps(k->zero, _mm256_mul_ps(k->n, fx));
        f2 = _mm256_mul_ps(k->nn1, _mm256_mul_ps(fx, ix));
    }
    /* the core has no inner step and the last ring no outer one: psi_in = 0, psi_out = 1 */
    __m256 po0 = k->one, po1 = k->zero, po2 = k->zero, pi0 = k->zero, pi1 = k->zero, pi2 = k->zero;
    /* each step is flat (psi_out = 1 inside its start, psi_in = 0 beyond its end) over most
     * of a piece: skip it when all eight texels are there */
    if (k->has_out &&
        _mm256_movemask_ps(_mm256_cmp_ps(_mm256_fmsub_ps(u, k->out_scale, k->out_offset), k->zero, _CMP_GT_OQ)))
        vector_psi(k, u, k->out_scale, k->out_offset, k->out_slope, &po0, &po1, &po2);
    if (k->has_in &&
        _mm256_movemask_ps(_mm256_cmp_ps(_mm256_fmsub_ps(u, k->in_scale, k->in_offset), k->one, _CMP_LT_OQ)))
        vector_psi(k, u, k->in_scale, k->in_offset, k->in_slope, &pi0, &pi1, &pi2);
    __m256 p0 = _mm256_sub_ps(po0, pi0), p1 = _mm256_sub_ps(pi1, po1), p2 = _mm256_sub_ps(pi2, po2);
    __m256 g = _mm256_mul_ps(f0, p0);
    __m256 g2 = _mm256_fmadd_ps(f2, p0, _mm256_fmadd_ps(_mm256_add_ps(f1, f1), p1, _mm256_mul_ps(f0, p2)));
    __m256 w = _mm256_fmadd_ps(_mm256_mul_ps(k->half, g2), q, g);
    return ggx || k->phong_series ? w : phong_horizon(k, w, u, q, xraw, p0);
}

IBL_TARGET_AVX2 static double horizontal_sum(__m256 v)
{
    float l[8];
    _mm256_storeu_ps(l, v);
    double s = 0;
    for (int i = 0; i < 8; i++) s += l[i];
    return s;
}

/* The batch's leaves for direction R, added to out (k: the piece's constants). */
KERNEL_INLINE void leaves_at(const leaf_batch *batch, const lobe_vectors *k, const float R[3],
                             const float RR[6], double out[4])
{
    const int B = BLOCK_TEXELS;
    const __m256 r0 = _mm256_set1_ps(R[0]), r1 = _mm256_set1_ps(R[1]), r2 = _mm256_set1_ps(R[2]);
    const __m256 q0 = _mm256_set1_ps(RR[0]), q1 = _mm256_set1_ps(RR[1]), q2 = _mm256_set1_ps(RR[2]);
    const __m256 q3 = _mm256_set1_ps(RR[3]), q4 = _mm256_set1_ps(RR[4]), q5 = _mm256_set1_ps(RR[5]);
    int moments = batch->mode == LEAF_COARSE || batch->mode == LEAF_DIFFERENCE ? FIELD_LUM_MEAN : FIELD_MEAN;
    int light = batch->mode == LEAF_COARSE || batch->mode == LEAF_DIFFERENCE
                    ? (batch->without_bright ? FIELD_POWER_NOT_BRIGHT : FIELD_POWER)
                    : FIELD_RADIANCE;
    int ggx = batch->piece->is_ggx, difference = batch->mode == LEAF_DIFFERENCE;
    __m256 ar = k->zero, ag = k->zero, ab = k->zero, aw = k->zero;
    for (int ci = 0; ci < batch->count; ci++) {
        const float *rec = candidate_record(batch, ci, R);
        if (!rec) continue;
        __m256 w = k->zero;
        /* the difference form: the moment leaf, then minus the leaf at the geometric moments */
        for (int pass = 0; pass <= difference; pass++) {
            const float *m = rec + (pass ? FIELD_MEAN : moments) * B;
            __m256 dx = _mm256_sub_ps(r0, _mm256_loadu_ps(m));
            __m256 dy = _mm256_sub_ps(r1, _mm256_loadu_ps(m + B));
            __m256 dz = _mm256_sub_ps(r2, _mm256_loadu_ps(m + 2 * B));
            __m256 d2 = _mm256_fmadd_ps(dx, dx, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dz, dz)));
            __m256 u = _mm256_fmadd_ps(k->half, d2, _mm256_loadu_ps(m + 3 * B));
            const float *c = m + 4 * B;
            __m256 q = _mm256_mul_ps(q0, _mm256_loadu_ps(c));
            q = _mm256_fmadd_ps(q1, _mm256_loadu_ps(c + B), q);
            q = _mm256_fmadd_ps(q2, _mm256_loadu_ps(c + 2 * B), q);
            q = _mm256_fmadd_ps(q3, _mm256_loadu_ps(c + 3 * B), q);
            q = _mm256_fmadd_ps(q4, _mm256_loadu_ps(c + 4 * B), q);
            q = _mm256_fmadd_ps(q5, _mm256_loadu_ps(c + 5 * B), q);
            /* eight texels past the outer step or inside the inner one (blocks of scattered
             * gathered texels, whose cones are wide, often are) add exactly zero */
            __m256 live = _mm256_and_ps(_mm256_cmp_ps(u, k->u_end, _CMP_LT_OQ),
                                        _mm256_cmp_ps(u, k->u_start, _CMP_GT_OQ));
            __m256 v = _mm256_movemask_ps(live) ? vector_leaf(k, ggx, u, q) : k->zero;
            w = pass ? _mm256_sub_ps(w, v) : v;
        }
        if (batch->mode == LEAF_NORMALISER) {
            aw = _mm256_fmadd_ps(w, _mm256_loadu_ps(rec + FIELD_SOLID_ANGLE * B), aw);
            continue;
        }
        if (batch->mode == LEAF_LEVEL0) w = _mm256_mul_ps(w, _mm256_loadu_ps(rec + FIELD_SOLID_ANGLE * B));
        const float *L = rec + light * B;
        ar = _mm256_fmadd_ps(w, _mm256_loadu_ps(L), ar);
        ag = _mm256_fmadd_ps(w, _mm256_loadu_ps(L + B), ag);
        ab = _mm256_fmadd_ps(w, _mm256_loadu_ps(L + 2 * B), ab);
    }
    out[0] += horizontal_sum(ar), out[1] += horizontal_sum(ag), out[2] += horizontal_sum(ab);
    out[3] += horizontal_sum(aw);
}

/* One setup of the piece's constants for all the points: per point it cost as much as the
 * leaves of a point with few candidates (the centroid corrections at the output texels). */
IBL_TARGET_AVX2 static void avx2_sum_leaves(const leaf_batch *batch, int points, const float (*R)[3],
                                            const float (*RR)[6], double (*out)[4])
{
    lobe_vectors k;
    lobe_setup(batch->piece, &k);
    for (int i = 0; i < points; i++) leaves_at(batch, &k, R[i], RR[i], out[i]);
}

/* One setup for the whole base texel: per row it cost as much as a row's weights. */
IBL_TARGET_AVX2 static void avx2_base_weights(const lobe_piece *pc, const float R[3],
                                              const float RR[6], const float *geometry,
                                              size_t plane, int padded_edge, int origin,
                                              const int32_t *rows, int row_count, float inv_scale,
                                              uint16_t *w, float lanes[8])
{
    lobe_vectors k;
    lobe_setup(pc, &k);
    const __m256 r0 = _mm256_set1_ps(R[0]), r1 = _mm256_set1_ps(R[1]), r2 = _mm256_set1_ps(R[2]);
    const __m256 vinv = _mm256_set1_ps(inv_scale);
    __m256 qk[6];
    for (int i = 0; i < 6; i++) qk[i] = _mm256_set1_ps(RR[i]);
    __m256 acc = _mm256_loadu_ps(lanes);
    for (int r = 0; r < row_count; r++) {
        const int32_t *row = rows + 3 * r;
        const float *g = geometry + (size_t)(row[0] + origin) * padded_edge + row[1] + origin;
        for (int i = 0; i < row[2]; i += 8) {
            __m256 dx = _mm256_sub_ps(r0, _mm256_loadu_ps(g + i));
            __m256 dy = _mm256_sub_ps(r1, _mm256_loadu_ps(g + plane + i));
            __m256 dz = _mm256_sub_ps(r2, _mm256_loadu_ps(g + 2 * plane + i));
            __m256 d2 = _mm256_fmadd_ps(dx, dx, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dz, dz)));
            __m256 u = _mm256_fmadd_ps(k.half, d2, _mm256_loadu_ps(g + FIELD_SPREAD * plane + i));
            __m256 q = _mm256_mul_ps(qk[0], _mm256_loadu_ps(g + FIELD_COVARIANCE * plane + i));
            for (int c = 1; c < 6; c++)
                q = _mm256_fmadd_ps(qk[c], _mm256_loadu_ps(g + (FIELD_COVARIANCE + c) * plane + i), q);
            __m256 v = _mm256_mul_ps(vector_leaf(&k, pc->is_ggx, u, q),
                                     _mm256_loadu_ps(g + FIELD_SOLID_ANGLE * plane + i));
            __m128i h = _mm256_cvtps_ph(_mm256_mul_ps(v, vinv), _MM_FROUND_TO_NEAREST_INT);
            _mm_storeu_si128((__m128i *)(w + i), h);
            acc = _mm256_add_ps(acc, _mm256_cvtph_ps(h));
        }
        w += row[2];
    }
    _mm256_storeu_ps(lanes, acc);
}

IBL_TARGET_AVX2 static void avx2_row_extent(const float *g, size_t plane, int n, const float R[3],
                                            float cos_reach, int *first, int *last)
{
    const __m256 r0 = _mm256_set1_ps(R[0]), r1 = _mm256_set1_ps(R[1]), r2 = _mm256_set1_ps(R[2]);
    const __m256 c = _mm256_set1_ps(cos_reach), zero = _mm256_setzero_ps();
    *first = *last = -1;
    for (int i = 0; i < n; i += 8) {
        __m256 d = _mm256_fmadd_ps(r0, _mm256_loadu_ps(g + i),
                                   _mm256_fmadd_ps(r1, _mm256_loadu_ps(g + plane + i),
                                                   _mm256_mul_ps(r2, _mm256_loadu_ps(g + 2 * plane + i))));
        __m256 in = _mm256_and_ps(_mm256_cmp_ps(d, c, _CMP_GE_OQ),
                                  _mm256_cmp_ps(_mm256_loadu_ps(g + FIELD_SOLID_ANGLE * plane + i), zero, _CMP_GT_OQ));
        unsigned mask = (unsigned)_mm256_movemask_ps(in);
        if (i + 8 > n) mask &= (1u << (n - i)) - 1u;
        if (!mask) continue;
        if (*first < 0) *first = i + __builtin_ctz(mask);
        *last = i + 31 - __builtin_clz(mask);
    }
}

/* Eight half-float weights as floats, reversed for a flipped image (cells x.. of the base's
 * row are columns S-1-x.. of the flipped face). */
KERNEL_INLINE __m256 weights8(const uint16_t *w, int reversed)
{
    __m256 v = _mm256_cvtph_ps(_mm_loadu_si128((const __m128i *)w));
    return reversed ? _mm256_permutevar8x32_ps(v, _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0)) : v;
}

/* r, g, b += w times the 8 cells at q of the three planes */
KERNEL_INLINE void mac3(__m256 w, const float *q, size_t plane, __m256 *r, __m256 *g, __m256 *b)
{
    *r = _mm256_fmadd_ps(w, _mm256_loadu_ps(q), *r);
    *g = _mm256_fmadd_ps(w, _mm256_loadu_ps(q + plane), *g);
    *b = _mm256_fmadd_ps(w, _mm256_loadu_ps(q + 2 * plane), *b);
}

IBL_TARGET_AVX2 static void avx2_product(const precomputed_piece *c, size_t base, const uint16_t *w,
                                         const uint16_t *vec, const float *planes, int flip_x,
                                         int flip_y, double out[3])
{
    int nvec = (int)((c->first_weight[base + 1] - c->first_weight[base]) / 8);
    size_t plane = (size_t)c->padded_edge * c->padded_edge;
    /* the first cell of vector k in the flipped image: y' = flip_y ? S - 1 + 2 origin - y : y,
     * and x' = flip_x ? S - 1 + 2 origin - x - 7 (read reversed) : x, in padded coordinates */
    ptrdiff_t P = c->padded_edge, E = c->source_edge - 1 + 2 * c->origin;
    ptrdiff_t c0 = (flip_y ? E * P : 0) + (flip_x ? E - 7 : 0), cy = flip_y ? -P : P, cx = flip_x ? -1 : 1;
    /* two sets of accumulators, for even and odd vectors: one set is a chain of dependent
     * FMAs whose latency (4 cycles), not the loads, would bound the loop */
    __m256 ar = _mm256_setzero_ps(), ag = ar, ab = ar, br = ar, bg = ar, bb = ar;
    int k = 0;
    /* two loops, so that neither the reversal nor x's sign is decided per vector */
    if (!flip_x) {
        for (; k + 2 <= nvec; k += 2) {
            const float *qa = planes + c0 + cy * vec[2 * k + 1] + vec[2 * k];
            mac3(weights8(w + 8 * k, 0), qa, plane, &ar, &ag, &ab);
            const float *qb = planes + c0 + cy * vec[2 * k + 3] + vec[2 * k + 2];
            mac3(weights8(w + 8 * k + 8, 0), qb, plane, &br, &bg, &bb);
        }
    } else {
        for (; k + 2 <= nvec; k += 2) {
            const float *qa = planes + c0 + cy * vec[2 * k + 1] - vec[2 * k];
            mac3(weights8(w + 8 * k, 1), qa, plane, &ar, &ag, &ab);
            const float *qb = planes + c0 + cy * vec[2 * k + 3] - vec[2 * k + 2];
            mac3(weights8(w + 8 * k + 8, 1), qb, plane, &br, &bg, &bb);
        }
    }
    if (k < nvec)
        mac3(weights8(w + 8 * k, flip_x), planes + c0 + cy * vec[2 * k + 1] + cx * vec[2 * k], plane,
             &ar, &ag, &ab);
    ar = _mm256_add_ps(ar, br), ag = _mm256_add_ps(ag, bg), ab = _mm256_add_ps(ab, bb);
    out[0] = horizontal_sum(ar) * c->weight_scale, out[1] = horizontal_sum(ag) * c->weight_scale;
    out[2] = horizontal_sum(ab) * c->weight_scale;
}

const fast_kernels ibl__fast_kernels_avx2 = {avx2_sum_leaves, avx2_base_weights, avx2_row_extent,
                                             avx2_product};

#endif
