/* Half-vector quadrature for BRDF directional albedos; see brdf_common.h and docs/BRDF.md. */
#include "bake/brdf_common.h"
#include "core/numeric.h"

#include <math.h>


/* cos(phi) for phi in [0, pi] as sin(pi/2 - phi) by its Taylor series to t^17 (truncation
 * below 5e-14): cheaper than libm's cos in the innermost loop, and the same on every
 * platform, which keeps tables bit-identical across C libraries. */
static inline double cos_0_pi(double phi)
{
    double t = 0.5 * IBL_PI - phi, t2 = t * t;
    double q = -1.0 / 355687428096000.0;                /* -1/17! */
    q = q * t2 + 1.0 / 1307674368000.0;                 /* 1/15!  */
    q = q * t2 - 1.0 / 6227020800.0;                    /* -1/13! */
    q = q * t2 + 1.0 / 39916800.0;                      /* 1/11!  */
    q = q * t2 - 1.0 / 362880.0;                        /* -1/9!  */
    q = q * t2 + 1.0 / 5040.0;                          /* 1/7!   */
    q = q * t2 - 1.0 / 120.0;                           /* -1/5!  */
    q = q * t2 + 1.0 / 6.0;                             /* 1/3!   */
    return t - t * t2 * q;
}

void ibl__gauss_legendre(int n, ibl__rule *rule)
{
    if (n < 1) n = 1;
    if (n > IBL__GL_MAX) n = IBL__GL_MAX;
    rule->n = n;
    /* Roots of P_n by Newton from the Tricomi initial guess; symmetric pairs. */
    for (int i = 0; i < (n + 1) / 2; i++) {
        double z = cos(IBL_PI * (i + 0.75) / (n + 0.5)), dp = 1;
        for (int it = 0; it < 100; it++) {
            double p0 = 1, p1 = 0;
            for (int k = 1; k <= n; k++) {
                double p2 = p1;
                p1 = p0;
                p0 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p2) / k;
            }
            dp = n * (z * p0 - p1) / (z * z - 1.0);
            double dz = p0 / dp;
            z -= dz;
            if (fabs(dz) < 1e-16) break;
        }
        double w = 2.0 / ((1.0 - z * z) * dp * dp);
        /* map [-1, 1] -> [0, 1] */
        rule->x[i] = 0.5 * (1.0 - z);
        rule->x[n - 1 - i] = 0.5 * (1.0 + z);
        rule->w[i] = rule->w[n - 1 - i] = 0.5 * w;
    }
}

void ibl__quadrature_init(ibl__quadrature *q, int order)
{
    if (order <= 0) order = IBL__DEFAULT_ORDER;
    if (order < 4) order = 4;
    if (order > IBL__GL_MAX) order = IBL__GL_MAX;
    /* At the default order 24: 12 points per cut theta_h piece (20 at grazing n.v), 12 on
     * the whole-circle piece, 8 per phi interval and 8 on the half circle (docs/BRDF.md
     * "The quadrature" has the measured errors that fixed these ratios). */
    ibl__gauss_legendre(order / 2, &q->u_part);
    ibl__gauss_legendre(order * 5 / 6, &q->u_graze);
    ibl__gauss_legendre(order / 2, &q->u_full);
    ibl__gauss_legendre(order / 3, &q->phi);
    q->circle = order / 3;
    for (int j = 0; j < q->circle; j++) q->circle_cos[j] = cos_0_pi((j + 0.5) * IBL_PI / q->circle);
}

/* e = exp(l) and 1 - e (l <= 0) with one libm call, each to full relative precision: the
 * smaller of the two is computed directly, the larger (>= 1/2) by subtraction. */
static inline void complement_pair(double l, double *e, double *one_minus_e)
{
    if (l < -0.6931471805599453) {
        *e = exp(l);
        *one_minus_e = 1.0 - *e;
    } else {
        *one_minus_e = -expm1(l);
        *e = 1.0 - *one_minus_e;
    }
}

/* The lobe's weight measure in theta_h through its CDF u (the textbook importance map):
 * cos^2 and sin^2 of theta_h from u and 1 - u, each passed exactly so that both ends keep
 * their precision. */
static void lobe_angle(const ibl__lobe_params *p, double u, double omu, double *c2, double *s2)
{
    switch (p->lobe) {
    case IBL__LOBE_GGX_CORRELATED:
    case IBL__LOBE_GGX_SEPARABLE: {
        /* Walter et al. 2007: tan^2 theta = alpha^2 u / (1 - u) samples D(h)(n.h). */
        double a2 = p->alpha * p->alpha, den = omu + a2 * u;
        *c2 = omu / den;
        *s2 = a2 * u / den;
        break;
    }
    case IBL__LOBE_CHARLIE:
    case IBL__LOBE_CHARLIE_KHR: {
        /* Estevez-Kulla 2017: CDF of D(h)(n.h) in theta is sin^(2 + 1/alpha) theta. */
        if (!(u > 0)) {
            *s2 = 0;
            *c2 = 1;
            break;
        }
        double l = 2.0 / (2.0 + 1.0 / p->alpha) * log(u);
        complement_pair(l, s2, c2);
        break;
    }
    default: {
        /* (n.h)^s dw_h: 1 - CDF = cos^(s+1) theta. */
        if (!(omu > 0)) {
            *c2 = 0;
            *s2 = 1;
            break;
        }
        double l = 2.0 * log(omu) / (p->shininess + 1.0);
        complement_pair(l, c2, s2);
        break;
    }
    }
}

/* The CDF at theta (the inverse of lobe_angle): u and 1 - u. */
static void lobe_cdf(const ibl__lobe_params *p, double theta, double *u, double *omu)
{
    if (theta <= 0) {
        *u = 0;
        *omu = 1;
        return;
    }
    if (theta >= 0.5 * IBL_PI) {
        *u = 1;
        *omu = 0;
        return;
    }
    double s = sin(theta), c = cos(theta);
    switch (p->lobe) {
    case IBL__LOBE_GGX_CORRELATED:
    case IBL__LOBE_GGX_SEPARABLE: {
        double a2c2 = p->alpha * p->alpha * c * c, den = s * s + a2c2;
        *u = s * s / den;
        *omu = a2c2 / den;
        break;
    }
    case IBL__LOBE_CHARLIE:
    case IBL__LOBE_CHARLIE_KHR: {
        double l = (2.0 + 1.0 / p->alpha) * log(s);
        *u = exp(l);
        *omu = -expm1(l);
        break;
    }
    default: {
        double l = (p->shininess + 1.0) * log(c);
        *omu = exp(l);
        *u = -expm1(l);
        break;
    }
    }
}

/* Total mass of the weight measure (the integral the importance map normalises away). */
static double lobe_mass(const ibl__lobe_params *p)
{
    if (p->lobe == IBL__LOBE_BLINN) return 2.0 * IBL_PI / (p->shininess + 1.0);
    return 1.0;
}

typedef struct sink {
    double *out; /* 2 moments, or nf0 values */
    const double *f0;
    int nf0;
} sink;

enum { MAX_PHI = 2 * IBL__GL_MAX };

/* KHR_materials_sheen's "Charlie" visibility: Lambda(cos) of Conty Estevez & Kulla 2017
 * ("Production Friendly Microfacet Sheen BRDF"), their fitted curve l(x) interpolated in
 * (1 - alpha)^2, mirrored about x = 0.5 for cos >= 0.5 as the extension writes it. */
static double sheen_l(double x, double alpha)
{
    double t = (1.0 - alpha) * (1.0 - alpha);
    double a = 21.5473 + (25.3245 - 21.5473) * t, b = 3.82987 + (3.32435 - 3.82987) * t;
    double c = 0.19823 + (0.16801 - 0.19823) * t, d = -1.97760 + (-1.27393 + 1.97760) * t;
    double e = -4.32054 + (-4.85967 + 4.32054) * t;
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

static double sheen_lambda(double cos_theta, double alpha)
{
    double x = fabs(cos_theta);
    return x < 0.5 ? exp(sheen_l(x, alpha)) : exp(2.0 * sheen_l(0.5, alpha) - sheen_l(1.0 - x, alpha));
}

/* Integrand per unit weight measure at the n phi nodes of one theta_h node, times the node
 * weights wgt[]; writes g * w into wgt[] and the Schlick factor (1 - v.h)^5 into fc[]. One
 * branch-free loop per lobe so the compiler can vectorise it. */
static void evaluate(const ibl__lobe_params *p, double mu, double sv, double ch, double sh,
                     const double *cphi, double *wgt, double *fc, int n)
{
    double a2 = p->alpha * p->alpha, b2 = 1.0 - a2, inv_ch = 1.0 / ch, svsh = sv * sh;
    double lv = sqrt(mu * mu * b2 + a2);
    double k = 0.5 * p->alpha, g1v = mu / (mu * (1.0 - k) + k);
    double nlv[MAX_PHI], vhv[MAX_PHI];
    for (int j = 0; j < n; j++) {
        double vh = svsh * cphi[j] + mu * ch;
        double nl = 2.0 * vh * ch - mu;
        nlv[j] = nl > 0 ? nl : 0; /* round-off at the exact cut */
        vhv[j] = vh;
        double t = 1.0 - vh, t2 = t * t;
        fc[j] = t2 * t2 * t;
    }
    switch (p->lobe) {
    case IBL__LOBE_GGX_CORRELATED:
        /* Heitz 2014 height-correlated Smith as Vis = G2 / (4 nl nv); with D (n.h) dh the
         * measure, f (n.l) dl = D Vis F nl 4 (v.h) dh, so g = 4 Vis nl (v.h) / (n.h). */
        for (int j = 0; j < n; j++) {
            double nl = nlv[j];
            wgt[j] *= 2.0 * nl * vhv[j] * inv_ch / (nl * lv + mu * sqrt(nl * nl * b2 + a2));
        }
        break;
    case IBL__LOBE_GGX_SEPARABLE:
        /* Karis 2013: Schlick-GGX G1(l) G1(v), k = alpha / 2 for image-based lighting. */
        for (int j = 0; j < n; j++) {
            double nl = nlv[j];
            wgt[j] *= g1v * nl * vhv[j] * inv_ch / (mu * (nl * (1.0 - k) + k));
        }
        break;
    case IBL__LOBE_CHARLIE:
        /* Neubelt & Pettineo 2013 visibility 1 / (4 (nl + nv - nl nv)). */
        for (int j = 0; j < n; j++) {
            double nl = nlv[j];
            wgt[j] *= nl * vhv[j] * inv_ch / (nl + mu - nl * mu);
        }
        break;
    case IBL__LOBE_CHARLIE_KHR: {
        /* V = 1 / ((1 + Lambda(nv) + Lambda(nl)) 4 nv nl), so g = 4 V nl (v.h) / (n.h) =
         * (v.h) / ((n.h) nv (1 + Lambda(nv) + Lambda(nl))) */
        double lambda_v = sheen_lambda(mu, p->alpha);
        for (int j = 0; j < n; j++) {
            double nl = nlv[j];
            double g = nl > 0 ? vhv[j] * inv_ch / (mu * (1.0 + lambda_v + sheen_lambda(nl, p->alpha))) : 0.0;
            wgt[j] *= g;
        }
        break;
    }
    default:
        /* tri-Ace 2010: norm (n.h)^s F / max(n.l, n.v), with (n.h)^s dh the measure. */
        for (int j = 0; j < n; j++) {
            double nl = nlv[j], m = nl > mu ? nl : mu;
            wgt[j] *= 4.0 * p->norm * nl * vhv[j] / m;
        }
        break;
    }
}

static void sort_small(double *v, int n)
{
    for (int i = 1; i < n; i++)
        for (int j = i; j > 0 && v[j] < v[j - 1]; j--) {
            double t = v[j];
            v[j] = v[j - 1];
            v[j - 1] = t;
        }
}

/* The level n.l = c where a lobe's integrand has a kink inside the hemisphere: tri-Ace's
 * max(n.l, n.v) switches at c = n.v; KHR_materials_sheen's Lambda is mirrored at cos = 0.5.
 * 0 when the lobe has none. */
static int lobe_kink(const ibl__lobe_params *p, double mu, double *level)
{
    if (p->lobe == IBL__LOBE_BLINN) {
        *level = mu;
        return 1;
    }
    if (p->lobe == IBL__LOBE_CHARLIE_KHR) {
        *level = 0.5;
        return 1;
    }
    return 0;
}

/* How x in [0, 1] maps to the CDF u on one theta_h piece. zeta = sqrt(1 - u) removes the
 * 1/sqrt(1 - u) end point that the 1/(n.h) factors of GGX and Charlie have at the horizon.
 * GGX's map tan^2 theta = alpha^2 u / (1 - u) has poles at zeta = +-i c, c = alpha /
 * sqrt(1 - alpha^2), a distance c from the real axis (the lobe's long tail): zeta = c sinh(w)
 * moves them to w = +-i pi/2 whatever alpha is, so Gauss-Legendre in w converges at a rate
 * that no longer degrades as alpha -> 0. Charlie's sin^2 theta = u^(2 / (2 + 1/alpha)) has a
 * fractional power at u = 0 (theta_h = 0); u = u1 x^3 on the piece that starts there makes it
 * x^(6 / (2 + 1/alpha)) with the x^2 weight, a far milder end point. */
typedef enum piece_map { MAP_ZETA, MAP_ZETA_SINH, MAP_U_CUBE } piece_map;

typedef struct piece {
    piece_map map;
    double za, zb;    /* zeta at the piece's ends, za <= zb */
    double c, wa, wb; /* MAP_ZETA_SINH: zeta = c sinh(w), w in [wa, wb] */
    double u1;        /* MAP_U_CUBE: u at the piece's upper theta_h end */
} piece;

static piece make_piece(const ibl__lobe_params *p, double theta_a, double theta_b)
{
    piece pc = {MAP_ZETA, 0, 0, 0, 0, 0, 0};
    double ua, oa, ub, ob;
    lobe_cdf(p, theta_a, &ua, &oa);
    lobe_cdf(p, theta_b, &ub, &ob);
    pc.za = sqrt(ob);
    pc.zb = sqrt(oa);
    double a2 = p->alpha * p->alpha;
    if ((p->lobe == IBL__LOBE_GGX_CORRELATED || p->lobe == IBL__LOBE_GGX_SEPARABLE) &&
        a2 < 1.0 - 1e-6) {
        pc.map = MAP_ZETA_SINH;
        pc.c = p->alpha / sqrt(1.0 - a2);
        pc.wa = asinh(pc.za / pc.c);
        pc.wb = asinh(pc.zb / pc.c);
    } else if ((p->lobe == IBL__LOBE_CHARLIE || p->lobe == IBL__LOBE_CHARLIE_KHR) && theta_a <= 0) {
        pc.map = MAP_U_CUBE;
        pc.u1 = ub;
    }
    return pc;
}

/* u, 1 - u and du/dx at x (orientation-free: du > 0). */
static void piece_node(const piece *pc, double x, double *u, double *omu, double *du)
{
    double z, dz;
    switch (pc->map) {
    case MAP_U_CUBE:
        *u = pc->u1 * x * x * x;
        *omu = 1.0 - *u;
        *du = 3.0 * pc->u1 * x * x;
        return;
    case MAP_ZETA_SINH: {
        /* sinh and cosh from one expm1 (w >= 0): sinh w = (e - 1/e) / 2 = m (1 + 1/e) / 2
         * with m = e - 1 keeps full precision at small w. */
        double w = pc->wa + (pc->wb - pc->wa) * x;
        double m = expm1(w), inv_e = 1.0 / (1.0 + m);
        z = pc->c * 0.5 * m * (1.0 + inv_e);
        dz = pc->c * 0.5 * (1.0 + m + inv_e) * (pc->wb - pc->wa);
        break;
    }
    default:
        z = pc->za + (pc->zb - pc->za) * x;
        dz = pc->zb - pc->za;
        break;
    }
    *omu = z * z;
    *u = (1.0 - z) * (1.0 + z);
    *du = 2.0 * z * dz;
}

/* Below this n.v the cut theta_h piece spans almost the whole quarter circle and its kinks
 * at th1 ~ n.v / 2 and th2 ~ pi/2 - n.v / 2 sit n.v from their mirror images: it gets the
 * larger rule u_graze. */
#define GRAZING_MU 0.25

/* One theta_h node: its weight (per unit phi, both sides of the circle) and angles. */
typedef struct theta_node {
    double wu, c2, s2, ch, sh;
} theta_node;

/* The nodes of one piece, computed before any phi loop so that their independent chains of
 * libm calls, divisions and square roots overlap in the processor. Returns the count. */
static int theta_nodes(const ibl__lobe_params *p, const piece *pc, const ibl__rule *ru,
                       int partial, double mass, theta_node *out)
{
    int n = 0;
    for (int i = 0; i < ru->n; i++) {
        double x = ru->x[i], wx = ru->w[i];
        if (partial) {
            wx *= 6.0 * x * (1.0 - x);
            x = x * x * (3.0 - 2.0 * x);
        }
        double u, omu, du;
        piece_node(pc, x, &u, &omu, &du);
        if (!(du > 0)) continue;
        theta_node *t = &out[n++];
        lobe_angle(p, u, omu, &t->c2, &t->s2);
        t->ch = sqrt(t->c2);
        t->sh = sqrt(t->s2);
        t->wu = du * wx * mass / IBL_PI; /* (1/2pi) * 2 sides of phi */
    }
    return n;
}

/* The phi nodes of one theta_h node: cos(phi) into cphi[], weights into wgt[]; 0 when no
 * phi gives n.l > 0. */
static int phi_nodes(const theta_node *t, double mu, double sv, int kink, double level,
                     const ibl__quadrature *q, double *cphi, double *wgt)
{
    /* n.l = 2 (v.h) ch - mu > 0  <=>  cos phi > -cot(tv) cot(2 th) */
    double num = -mu * (t->c2 - t->s2), den = sv * 2.0 * t->sh * t->ch;
    double cmax = den > 0 ? num / den : (num > 0 ? 2.0 : -2.0);
    if (cmax >= 1.0) return 0;
    double phimax = cmax <= -1.0 ? IBL_PI : acos(cmax);
    double cuts[3] = {0, phimax, phimax};
    int ncut = 2, n = 0;
    if (kink) {
        /* n.l = c  <=>  v.h = (c + mu) / (2 ch)  <=>  cos phi = (c + mu - 2 mu ch^2) / (2 ch sv sh) */
        double ceq = den > 0 ? (level + mu - 2.0 * mu * t->c2) / den : 2.0;
        if (ceq < 1.0) {
            double pe = ceq <= -1.0 ? IBL_PI : acos(ceq);
            if (pe > 0 && pe < phimax) {
                cuts[1] = pe;
                ncut = 3;
            }
        }
    }
    if (ncut == 2 && phimax >= IBL_PI) {
        /* The whole circle: the integrand is smooth, even and 2 pi periodic, where the
         * midpoint rule converges geometrically (exact for cos(k phi), k < 2m). */
        int m = q->circle;
        double wc = t->wu * IBL_PI / m;
        for (int j = 0; j < m; j++) {
            cphi[n] = q->circle_cos[j];
            wgt[n++] = wc;
        }
        return n;
    }
    const ibl__rule *rphi = &q->phi;
    for (int c = 0; c + 1 < ncut; c++) {
        double pa = cuts[c], dp = cuts[c + 1] - pa;
        if (!(dp > 0)) continue;
        /* Towards the n.l = 0 cut the GGX visibility has poles at n.l ~ +-i alpha (Charlie's
         * at n.l ~ -mu): x (2 - x) grades the nodes towards phimax, which turns a pole at
         * relative distance d from the end into one at ~sqrt(d). */
        int graded = c + 2 == ncut && phimax < IBL_PI;
        for (int j = 0; j < rphi->n; j++) {
            double x = rphi->x[j], wx = rphi->w[j];
            if (graded) {
                wx *= 2.0 * (1.0 - x);
                x *= 2.0 - x;
            }
            cphi[n] = cos_0_pi(pa + dp * x);
            wgt[n++] = t->wu * dp * wx;
        }
    }
    return n;
}

static void integrate(const ibl__lobe_params *p, double mu, const ibl__quadrature *q, sink *s)
{
    if (mu > 1.0) mu = 1.0;
    double sv = sqrt((1.0 - mu) * (1.0 + mu)), tv = acos(mu);
    /* Kinks in theta_h: below th1 every phi gives n.l > 0, above th2 none does (the
     * reflected direction's polar angle spans |2 th - tv| .. 2 th + tv); a level n.l = c
     * (polar angle tc) is crossed for some phi only while |tc - tv| / 2 < th < (tc + tv) / 2. */
    double th[6];
    int nth = 0;
    th[nth++] = 0;
    double th1 = 0.5 * (0.5 * IBL_PI - tv);
    th[nth++] = th1;
    double th2 = 0.5 * (0.5 * IBL_PI + tv);
    th[nth++] = th2;
    double level = 0, kink_lo = 0, kink_hi = 0;
    int kink = lobe_kink(p, mu, &level);
    if (kink) {
        double tc = acos(level);
        kink_lo = 0.5 * fabs(tc - tv);
        kink_hi = 0.5 * (tc + tv);
        if (kink_lo > 0 && kink_lo < th2) th[nth++] = kink_lo;
        if (kink_hi > 0 && kink_hi < th2) th[nth++] = kink_hi;
    }
    sort_small(th, nth);
    double mass = lobe_mass(p);
    double cphi[MAX_PHI], wgt[MAX_PHI], fc[MAX_PHI];
    theta_node nodes[IBL__GL_MAX];
    for (int seg = 0; seg + 1 < nth; seg++) {
        if (th[seg] >= th2) break;
        if (!(th[seg + 1] > th[seg])) continue;
        piece pc = make_piece(p, th[seg], th[seg + 1]);
        /* Where the phi circle is cut (n.l = 0, or the kink level) the phi-integrated
         * function has (t - t0)^(3/2)-type end points; the cubic smoothstep
         * t = x^2 (3 - 2x) makes them O(x^3) so Gauss-Legendre keeps converging fast. */
        int whole = th[seg + 1] <= th1 + 1e-15 &&
                    (!kink || th[seg + 1] <= kink_lo + 1e-15 || th[seg] >= kink_hi - 1e-15);
        const ibl__rule *ru = whole ? &q->u_full : mu < GRAZING_MU ? &q->u_graze : &q->u_part;
        int nn = theta_nodes(p, &pc, ru, !whole, mass, nodes);
        for (int i = 0; i < nn; i++) {
            int n = phi_nodes(&nodes[i], mu, sv, kink, level, q, cphi, wgt);
            if (!n) continue;
            evaluate(p, mu, sv, nodes[i].ch, nodes[i].sh, cphi, wgt, fc, n);
            if (!s->nf0) {
                double a = 0, b = 0;
                for (int j = 0; j < n; j++) {
                    a += wgt[j] * (1.0 - fc[j]);
                    b += wgt[j] * fc[j];
                }
                s->out[0] += a;
                s->out[1] += b;
            } else {
                for (int k = 0; k < s->nf0; k++) {
                    double f0 = s->f0[k], a = 0;
                    for (int j = 0; j < n; j++) a += wgt[j] * (f0 + (1.0 - f0) * fc[j]);
                    s->out[k] += a;
                }
            }
        }
    }
}

void ibl__albedo_moments(const ibl__lobe_params *p, double mu, const ibl__quadrature *q,
                         double out[2])
{
    out[0] = out[1] = 0;
    sink s = {out, NULL, 0};
    integrate(p, mu, q, &s);
}

void ibl__albedo_f0(const ibl__lobe_params *p, double mu, const ibl__quadrature *q,
                    const double *f0, int nf0, double *out)
{
    for (int k = 0; k < nf0; k++) out[k] = 0;
    sink s = {out, f0, nf0};
    integrate(p, mu, q, &s);
}
