/* The float-lane kernels of the equirect -> cube batch engine (to_cube.c), written once for
 * LANES floats to a vector and compiled twice: four lanes (batch_lanes_portable.c: plain SSE
 * or any target) and eight (batch_lanes_avx2.c: one AVX2 register). Every lane goes through the
 * same float operations in the same order at either width, and nothing is fused into
 * multiply-adds, so both give the same bits.
 *
 * Float is enough here: a window's ends move by under 3e-4 pixel (float spacing at 2048
 * pixels, and the float polynomial atan2), against windows 1/16 pixel and wider; narrower
 * ones, and the wide ones, are left to batch_double.c. The windows are those of
 * area_windows.c (tent rows, or constant bands next to a pole) restricted to at most two
 * pixels each way, so that fixed 4 x 4 taps cover them and nothing branches per lane.
 *
 * The includer defines LANES (4 or 8), LANE_TARGET (the functions' attribute) and
 * LANE_KERNELS (the name of the eq_lane_kernels table this copy defines). */
#include "equirect_internal.h"

#include <math.h>

#if LANES == 8
typedef float v8f __attribute__((vector_size(32)));
typedef int v8i __attribute__((vector_size(32)));
#define VF v8f
#define VI v8i
#else
#define VF v4f
#define VI v4i
#endif

/* Samples per axis: this many per source row / column the texel spans (at least 1). */
static const double SAMPLES_PER_ROW = 0.6;
static const double SAMPLES_PER_COLUMN = 0.6;

/* Lane helpers for VF (mask type VI). Macros (statement expressions): GCC notes an ABI change
 * for every function taking a 32-byte vector, even an always inlined one. */
#define LLOAD(p) ({ VF l_; memcpy(&l_, (p), sizeof l_); l_; })
#define LSTORE(p, v) do { __typeof__(v) s_ = (v); memcpy((p), &s_, sizeof s_); } while (0)
#define LSEL(m, a, b) ({ VI m_ = (m); (VF)((m_ & (VI)(a)) | (~m_ & (VI)(b))); })
#define LABS(x) ((VF)((VI)(x) & 0x7fffffff))
#define LCLAMP1(t) LMIN(LMAX((t), (VF){} - 1.0f), (VF){} + 1.0f)
/* eq_tent_cdf and eq_tent_moment without branches, for t clamped to [-1, 1]:
 * T(t) = 1/2 + t - t |t| / 2, M(t) = t^2 (1/2 - |t| / 3) - 1/6 */
#define LTENT(t) ({ VF u_ = LCLAMP1(t); 0.5f + u_ - 0.5f * u_ * LABS(u_); })
#define LMOMENT(t) ({ VF u_ = LCLAMP1(t); \
                      u_ * u_ * (0.5f - LABS(u_) * (1.0f / 3.0f)) - 1.0f / 6.0f; })
/* atan2 from eq_atan_unit's polynomial (Abramowitz & Stegun 4.4.49) in float, without
 * branches */
#define LATAN2(y, x) ({ \
    VF y_ = (y), x_ = (x), ax_ = LABS(x_), ay_ = LABS(y_); \
    VI steep_ = ay_ > ax_; \
    VF mn_ = LMIN(ax_, ay_), mx_ = LMAX(ax_, ay_); \
    VF t_ = mn_ / LSEL(mx_ > 0.0f, mx_, (VF){} + 1.0f), t2_ = t_ * t_; \
    VF r_ = t_ * (1.0f + t2_ * (-0.3333314528f + t2_ * (0.1999355085f + \
            t2_ * (-0.1420889944f + t2_ * (0.1065626393f + t2_ * (-0.0752896400f + \
            t2_ * (0.0429096138f + t2_ * (-0.0161657367f + t2_ * 0.0028662257f)))))))); \
    r_ = LSEL(steep_, (float)IBL_HALF_PI - r_, r_); \
    r_ = LSEL(x_ < 0.0f, (float)IBL_PI - r_, r_); \
    LSEL(y_ < 0.0f, -r_, r_); })

/* The larger / smaller of finite a and b (as a select on a < b would give, in one
 * instruction), and sqrt */
#if LANES == 8
#include <immintrin.h>
#define LMAX(a, b) LAVX(_mm256_max_ps, (a), (b))
#define LMIN(a, b) LAVX(_mm256_min_ps, (a), (b))
#define LAVX(op, a, b) ({ __m256 p_, q_; VF a_ = (a), b_ = (b); memcpy(&p_, &a_, sizeof p_); \
                          memcpy(&q_, &b_, sizeof q_); p_ = op(p_, q_); \
                          memcpy(&a_, &p_, sizeof a_); a_; })
#define LSQRT(x) ({ __m256 q_; VF r_ = (x); memcpy(&q_, &r_, sizeof q_); \
                    q_ = _mm256_sqrt_ps(q_); memcpy(&r_, &q_, sizeof r_); r_; })
/* two v4f side by side */
#define LJOIN(lo, hi) __builtin_shufflevector((lo), (hi), 0, 1, 2, 3, 4, 5, 6, 7)
#elif defined(__SSE__)
#include <xmmintrin.h>
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

/* The 4 x 4 tap weights of LANES tent windows, normalised: longitude tap k weighs
 * T(e - k) - T(da - k) (over their sum), latitude row k (T(ey - k) - T(dy - k)) (s_c + s_d (k -
 * dy - h / 2)) + s_d (M(ey - k) - M(dy - k)) (over their sum), with T(da - k) = T(da), da^2 / 2,
 * 0, 0 for da in [0, 1) (the same for M). batch_double.c uses the four-lane copy. */
LANE_TARGET static void lane_tent_weights(VF da, VF e, VF dy, VF ey, VF h, VF s_c, VF s_d,
                                          VF wy[4], VF wx[4])
{
    VF lo_t[2] = {0.5f + da - 0.5f * da * da, 0.5f * da * da};
    VF dm = dy - 1.0f;
    VF ly_t[2] = {0.5f + dy - 0.5f * dy * dy, 0.5f * dy * dy};
    VF ly_m[2] = {dy * dy * (0.5f - dy * (1.0f / 3.0f)) - 1.0f / 6.0f,
                  dm * dm * (0.5f + dm * (1.0f / 3.0f)) - 1.0f / 6.0f};
    VF sum = {0}, wsum = {0};
    for (int k = 0; k < 4; k++) {
        float fk = (float)k;
        wx[k] = LTENT(e - fk);
        if (k < 2) wx[k] -= lo_t[k];
        wsum += wx[k];
        VF t = LTENT(ey - fk), mom = LMOMENT(ey - fk);
        if (k < 2) {
            t -= ly_t[k];
            mom -= ly_m[k];
        }
        wy[k] = t * (s_c + s_d * (fk - dy - 0.5f * h)) + s_d * mom;
        sum += wy[k];
    }
    /* lanes of other kinds: any finite value (unused) */
    sum = LSEL(sum > 0.0f, sum, (VF){} + 1.0f);
    wsum = LSEL(wsum > 0.0f, wsum, (VF){} + 1.0f);
    VF inv = 1.0f / sum, inv_w = 1.0f / wsum;
    for (int k = 0; k < 4; k++) wy[k] *= inv, wx[k] *= inv_w;
}

/* For lanes [0, n) of a batch (n a multiple of LANES): each sample's direction, weight dA / |d|^3
 * and window (as batch_double.c computes them), then, for the tent windows, the first row and
 * column, the row count and the 4 x 4 tap weights; fast[i] says whether sample i took it.
 * Returns how many of the first n_real samples did. */
LANE_TARGET static int lane_windows(const eq_lane_face *ff, eq_batch *bt, int n, int n_real)
{
    VI lane, fast_count = {0};
    for (int l = 0; l < LANES; l++) lane[l] = l;
    const float *m = ff->m, *a = ff->a, *b = ff->b;
    const int Wi = ff->W;
    const float W = (float)ff->W, H = (float)ff->H;
    const float px_per_rad_u = (float)(ff->W / IBL_TWO_PI), px_per_rad_v = (float)(ff->H / IBL_PI);
    const float k_rad = (float)(IBL_PI / ff->H), row_lo = (float)ff->R + 1.0f;
    const float row_hi = (float)(ff->H - ff->R - 1);
    const VI narrow_ok = (VI){} - (ff->narrow_ok != 0);
    const VI polar_ok = (VI){} - (ff->narrow_ok && ff->H >= 64);
    const float R = (float)ff->R;
    for (int i = 0; i < n; i += LANES) {
        VF sc = LLOAD(bt->fsc + i), tc = LLOAD(bt->ftc + i), sub = LLOAD(bt->fsub + i);
        VF x = m[0] + tc * b[0] + sc * a[0];
        VF y = m[1] + tc * b[1] + sc * a[1];
        VF z = m[2] + tc * b[2] + sc * a[2];
        VF rho2 = x * x + z * z, len2 = rho2 + y * y;
        VF rho = LSQRT(rho2), len = LSQRT(len2);
        VF inv_len = 1.0f / len, inv_len2 = inv_len * inv_len;
        VF wt = inv_len2 * inv_len;
        VF px = (LATAN2(x, -z) * (float)(0.5 / IBL_PI) + 0.5f) * W;
        VF py = LATAN2(rho, y) * (float)(ff->H / IBL_PI);
        VF g1 = LABS(y * (x * a[0] + z * a[2]) - rho2 * a[1]);
        VF g2 = LABS(y * (x * b[0] + z * b[2]) - rho2 * b[1]);
        VF ga = LABS(x * a[2] - z * a[0]), gb = LABS(x * b[2] - z * b[0]);
        VI off_axis = rho2 > 1e-30f;
        VF inv_rho2 = 1.0f / LSEL(off_axis, rho2, (VF){} + 1.0f);
        VF wpx = (ga + gb) * inv_rho2 * sub * px_per_rad_u;
        wpx = LMIN(wpx, (VF){} + W);
        wpx = LSEL(off_axis, wpx, (VF){} + W);
        VF hpx = LSEL(off_axis, (g1 + g2) * rho * inv_rho2 * inv_len2 * sub * px_per_rad_v,
                        2.0f * inv_len * sub * px_per_rad_v);
        VF st = rho * inv_len, ct = y * inv_len;
        /* windows given by polar_columns (where sub is 0) */
        VI pre = sub == 0.0f, none = {0};
        if (memcmp(&pre, &none, sizeof pre) != 0) {
            wt = LSEL(pre, LLOAD(bt->gwt + i), wt);
            px = LSEL(pre, LLOAD(bt->gpx + i), px);
            py = LSEL(pre, LLOAD(bt->gpy + i), py);
            wpx = LSEL(pre, LLOAD(bt->gwpx + i), wpx);
            hpx = LSEL(pre, LLOAD(bt->ghpx + i), hpx);
            st = LSEL(pre, LLOAD(bt->gst + i), st);
            ct = LSEL(pre, LLOAD(bt->gct + i), ct);
        }
        /* the window, cut at the poles */
        VF hw = 0.5f * wpx, hh = 0.5f * hpx;
        VF px0 = px - hw, w = wpx, c = py;
        VF py0 = c - hh, py1 = c + hh;
        py0 = LMAX(py0, (VF){});
        py1 = LMIN(py1, (VF){} + H);
        py1 = LMAX(py1, py0);
        VF h = py1 - py0, s_d = k_rad * ct;
        VF s_c = st + s_d * (0.5f * (py0 + py1) - c);
        /* tent rows, or constant bands next to a pole (as batch_double.c; windows under 1/16
         * pixel wide, or tall in tent rows, are left to it) */
        VI ok = (h >= 1e-6f) & (h <= 2.0f) & (w >= 1.0f / 16) & (w <= 2.0f);
        VI fast = narrow_ok & ok & (h >= 1.0f / 16) & (py0 - 0.5f >= row_lo) &
                   (py1 + 0.5f <= row_hi);
        VI polar = polar_ok & ok & ((py1 <= R) | (py0 >= H - R)) & (hpx <= 2.0f);
        fast |= polar;
        int any_polar = memcmp(&polar, &none, sizeof polar) != 0;
        /* other lanes: any finite window (unused) */
        px0 = LSEL(fast, px0, (VF){});
        py0 = LSEL(fast, py0, (VF){} + row_lo);
        w = LSEL(fast, w, (VF){} + 1.0f);
        h = LSEL(fast, h, (VF){} + 1.0f);
        /* longitude: the first column whose tent reaches the window, then four */
        VF wa = LSEL(px0 < 0.0f, px0 + W, LSEL(px0 >= W, px0 - W, px0));
        VI i0 = __builtin_convertvector(wa + 0.5f, VI) - 1; /* floor(wa - 1/2) */
        VF da = wa - (__builtin_convertvector(i0, VF) + 0.5f); /* in [0, 1) */
        VF e = da + w;
        LSTORE(bt->fcol + i, i0); /* (columns i0 to i0 + 3, wrapped by lane_accumulate) */
        /* latitude: row jt + k has centre py0 - dy + k */
        VI jt = __builtin_convertvector(py0 + 0.5f, VI) - 1; /* floor(py0 - 1/2) */
        VF dy = py0 - (__builtin_convertvector(jt, VF) + 0.5f), ey = dy + h;
        VI rows = 2 - (ey > 1.0f) - (ey > 2.0f);
        LSTORE(bt->fast + i, fast);
        fast_count -= fast & (lane + i < n_real);
        LSTORE(bt->fwt + i, wt);
        VF share[4], wx[4];
        lane_tent_weights(da, e, dy, ey, h, s_c, s_d, share, wx);
        if (any_polar) {
            /* polar bands: row jp + k covers [jp + k, jp + k + 1]; the solid angle between
             * two latitudes from the centre's by the angle-sum formula and Taylor series (as
             * batch_double.c) */
            VI jp = __builtin_convertvector(py0, VI);
            VF fjp = __builtin_convertvector(jp, VF);
            VF cut[4] = {py0, LSEL(py1 < fjp + 1.0f, py1, fjp + 1.0f),
                          LSEL(py1 < fjp + 2.0f, py1, fjp + 2.0f), py1};
            VF band[3], bsum = {0};
            for (int k = 0; k < 3; k++) {
                VF mm = (0.5f * (cut[k] + cut[k + 1]) - c) * k_rad, m2 = mm * mm;
                VF hd = 0.5f * (cut[k + 1] - cut[k]) * k_rad, hd2 = hd * hd;
                VF cm = 1.0f - m2 * (0.5f - m2 * (1.0f / 24 - m2 * (1.0f / 720)));
                VF sm = mm * (1.0f - m2 * (1.0f / 6 - m2 * (1.0f / 120 - m2 * (1.0f / 5040))));
                VF shd = hd * (1.0f - hd2 * (1.0f / 6 - hd2 * (1.0f / 120 - hd2 * (1.0f / 5040))));
                band[k] = 2.0f * (st * cm + ct * sm) * shd;
                band[k] = LSEL(band[k] > 0.0f, band[k], (VF){});
                bsum += band[k];
            }
            bsum = LSEL(bsum > 0.0f, bsum, (VF){} + 1.0f);
            VF binv = 1.0f / bsum;
            for (int k = 0; k < 3; k++) share[k] = LSEL(polar, band[k] * binv, share[k]);
            share[3] = LSEL(polar, (VF){}, share[3]);
            jt = (jp & polar) | (jt & ~polar);
            rows = ((1 - (cut[1] < py1) - (cut[2] < py1)) & polar) | (rows & ~polar);
        }
        LSTORE(bt->frow + i, jt);
        /* (8: a window across the seam, whose columns are not side by side in the row) */
        LSTORE(bt->frows + i, rows | (((i0 < 0) | (i0 + 3 >= Wi)) & 8));
        for (int k = 0; k < 4; k++) {
            LSTORE(bt->fwy[k] + i, share[k]);
            LSTORE(bt->fwx[k] + i, wx[k]);
        }
    }
    int count = 0;
    for (int l = 0; l < LANES; l++) count += fast_count[l];
    return count;
}

/* How many samples ahead lane_accumulate asks for a window's taps: 8 took 5% off the
 * conversion's CPU time at 1024 from a 4096 x 2048 picture, 24 7% (bench/bench_stages.c). */
enum { PREFETCH_AHEAD = 24 };

/* The windows' values (the fast ones from their 4 x 4 taps, two columns to a vector) summed per
 * texel in the samples' order, in double; a texel is written when the next one starts. */
LANE_TARGET static void lane_accumulate(const eq_job *job, eq_batch *bt, float *out)
{
    const eq_double_windows *sl = bt->slow;
    const float *pix = job->im->pixels;
    const size_t stride = (size_t)job->im->width * 4;
    int cur = bt->cur;
    v4d acc = bt->acc;
    double wsum = bt->wsum;
    for (int i = 0, j = 0, n = bt->n; i < n; i++) {
        /* the taps of a sample PREFETCH_AHEAD on, asked of the cache now: a face's texel row
         * crosses the picture's rows, so its taps are mostly out of cache, and their latency
         * bounded this loop (a window across the seam, whose columns wrap, is not asked for) */
        int ia = i + PREFETCH_AHEAD;
        if (ia < n && bt->fast[ia] && !(bt->frows[ia] & 8)) {
            const float *tap = pix + (size_t)bt->frow[ia] * stride + (size_t)bt->fcol[ia] * 4;
            for (int k = 0; k < (bt->frows[ia] & 7); k++) {
                __builtin_prefetch(tap + (size_t)k * stride);
                __builtin_prefetch(tap + (size_t)k * stride + 15); /* the taps' last float */
            }
        }
        if (bt->texel[i] != cur) {
            if (cur >= 0) {
                v4f mean = __builtin_convertvector(acc * (1.0 / wsum), v4f);
                memcpy(out + (size_t)cur * 4, &mean, sizeof mean);
            }
            cur = bt->texel[i];
            acc = (v4d){0, 0, 0, 0};
            wsum = 0.0;
        }
        v4f val;
        double wt;
        if (bt->fast[i]) {
            const float *rowp = pix + (size_t)bt->frow[i] * stride;
            int i0 = bt->fcol[i], rows = bt->frows[i];
            const float *c0 = rowp + (size_t)i0 * 4, *c1 = c0 + 4, *c2 = c0 + 8, *c3 = c0 + 12;
            if (rows & 8) {
                /* across the seam: the columns wrap */
                int W = job->im->width, col[4];
                for (int k = 0; k < 4; k++) {
                    col[k] = i0 + k;
                    col[k] += col[k] < 0 ? W : 0;
                    col[k] -= col[k] >= W ? W : 0;
                }
                c0 = rowp + (size_t)col[0] * 4;
                c1 = rowp + (size_t)col[1] * 4;
                c2 = rowp + (size_t)col[2] * 4;
                c3 = rowp + (size_t)col[3] * 4;
            }
            float w[4] = {bt->fwx[0][i], bt->fwx[1][i], bt->fwx[2][i], bt->fwx[3][i]};
#if LANES == 8
            /* columns 0 and 1 in one vector, 2 and 3 in another */
            VF w01 = {w[0], w[0], w[0], w[0], w[1], w[1], w[1], w[1]};
            VF w23 = {w[2], w[2], w[2], w[2], w[3], w[3], w[3], w[3]};
            VF sum = {0};
            if (!(rows & 8)) {
                /* (not across the seam: the four columns side by side in the row) */
                for (int k = 0; k < rows; k++) {
                    size_t o = (size_t)k * stride;
                    sum += bt->fwy[k][i] * (w01 * LLOAD(c0 + o) + w23 * LLOAD(c2 + o));
                }
            } else {
                for (int k = 0; k < (rows & 7); k++) {
                    size_t o = (size_t)k * stride;
                    VF p01 = LJOIN(vload(c0 + o), vload(c1 + o));
                    VF p23 = LJOIN(vload(c2 + o), vload(c3 + o));
                    sum += bt->fwy[k][i] * (w01 * p01 + w23 * p23);
                }
            }
            v4f hi;
            memcpy(&val, &sum, sizeof val);
            memcpy(&hi, (const float *)&sum + 4, sizeof hi);
            val += hi;
#else
            /* the same sums as the eight-lane code, each half in its own vector */
            v4f w0 = vsplat(w[0]), w1 = vsplat(w[1]), w2 = vsplat(w[2]), w3 = vsplat(w[3]);
            v4f lo = vsplat(0.0f), hi = vsplat(0.0f);
            for (int k = 0; k < (rows & 7); k++) {
                size_t o = (size_t)k * stride;
                float wy = bt->fwy[k][i];
                lo += wy * (w0 * vload(c0 + o) + w2 * vload(c2 + o));
                hi += wy * (w1 * vload(c1 + o) + w3 * vload(c3 + o));
            }
            val = lo + hi;
#endif
            wt = bt->fwt[i];
        } else {
            val = vload(sl->val[j]);
            wt = sl->wt[j];
            j++;
        }
        acc += wt * __builtin_convertvector(val, v4d);
        wsum += wt;
    }
    bt->cur = cur;
    bt->acc = acc;
    bt->wsum = wsum;
}

/* How many samples per axis each texel of a run takes (0: near a pole), from the texel's
 * extent in source rows and columns: SAMPLES_PER_ROW / _COLUMN per pixel it spans. LANES
 * texels at a time in float (n rounded up to 8; ks holds EQ_TEXEL_RUN). */
LANE_TARGET static void lane_sample_counts(const eq_lane_face *ff, int ty, int tx0, int n, int *ks)
{
    /* the axes in locals: stores to ks could otherwise alias them and force reloads */
    const float m[3] = {ff->m[0], ff->m[1], ff->m[2]}, a[3] = {ff->a[0], ff->a[1], ff->a[2]},
                b[3] = {ff->b[0], ff->b[1], ff->b[2]}, pole_radius2 = ff->pole_radius2;
    const double cell = 2.0 / ff->N;
    const float rows_per = (float)(SAMPLES_PER_ROW * cell * ff->H / IBL_PI);
    const float cols_per = (float)(SAMPLES_PER_COLUMN * cell * ff->W / IBL_TWO_PI);
    const float fcell = (float)cell, tc = (float)(-1.0 + (ty + 0.5) * cell);
    for (int i = 0; i < n; i += LANES) {
        VF sc;
        for (int l = 0; l < LANES; l++) sc[l] = (float)(-1.0 + (tx0 + i + l + 0.5) * cell);
        VF x = m[0] + sc * a[0] + tc * b[0], y = m[1] + sc * a[1] + tc * b[1],
            z = m[2] + sc * a[2] + tc * b[2];
        VF rho2 = x * x + z * z, r2 = rho2 + y * y;
        VF rho = LSQRT(rho2), len = LSQRT(r2);
        /* latitude extent of the texel in source rows, from the gradient of theta; at a pole
         * theta is a cone: its change is bound by the full gradient 1/|d| */
        VF inv_rr = 1.0f / (LSEL(rho > 0.0f, rho, (VF){} + 1.0f) * r2);
        VF g0 = y * x * inv_rr, g1 = -rho2 * inv_rr, g2 = y * z * inv_rr;
        VF ext = LABS(g0 * a[0] + g1 * a[1] + g2 * a[2]) + LABS(g0 * b[0] + g1 * b[1] + g2 * b[2]);
        ext = LSEL(rho < 2.0f * fcell * len, 2.0f / len, ext);
        VF want = ext * rows_per;
        /* and its longitude extent in source columns */
        VF want_c = (LABS(x * a[2] - z * a[0]) + LABS(x * b[2] - z * b[0])) /
                     LSEL(rho2 > 0.0f, rho2, (VF){} + 1.0f) * cols_per;
        want = LSEL(want_c > want, want_c, want);
        want = LSEL(want < 64.0f, want, (VF){} + 64.0f);
        want = LSEL(want > 1.0f, want, (VF){} + 1.0f); /* (and no NaN) */
        VI k = __builtin_convertvector(want, VI);
        k -= __builtin_convertvector(k, VF) < want; /* ceil */
        k &= ~(rho2 < pole_radius2 * r2);
        LSTORE(ks + i, k);
    }
}

const eq_lane_kernels LANE_KERNELS = {lane_windows, lane_accumulate, lane_sample_counts};
