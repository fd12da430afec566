/* The pieces of a lobe: a smooth partition of unity in u = 1 - R.l, and where each piece is
 * summed.
 *
 * The lobe f(u) is cut into a core f psi(u / U0) and dyadic rings f (psi(u / Uj) -
 * psi(u / Uj-1)), Uj = 4^j U0, where psi is 1 for t <= 1, 0 for t >= 4 and the quintic
 * smootherstep 6s^5 - 15s^4 + 10s^3 between (Perlin 2002; C2, so the second-order leaves of
 * leaf_sums.c see a smooth g''). The pieces add up to f exactly. This is the splitting of
 * multilevel summation (Brandt & Lubrecht 1990; Skeel, Tezcan & Hardy 2002) on the sphere: a
 * ring whose inner radius is b varies on the scale of b, so it can be summed from a mip whose
 * texels are a fixed fraction of b wide and evaluated on a cube grid spaced a fixed fraction of
 * b, then interpolated. The cost per output texel is then set by those fractions, not by the
 * source size: GGX's long tail is summed from coarse mips on coarse grids. The core, where the
 * lobe is narrow, is summed at every output texel over the finest level it needs.
 *
 * Each piece is tabulated (g and g'' in u) for the portable kernels and for the bars of
 * gathering.c, and described in closed form (GGX's alpha, Phong's n, the two steps) for the
 * AVX2 kernels. The fractions are in tuning.h. */
#include "bake/specular/fast_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

/* psi(t) and its first two derivatives in u, where t = u / scale. */
static void psi_derivatives(double t, double scale, double out[3])
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
    double step = s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
    double step1 = 30.0 * s * s * (1.0 - s) * (1.0 - s);
    double step2 = 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s);
    double ds_du = 1.0 / (3.0 * scale);
    out[0] = 1.0 - step;
    out[1] = -step1 * ds_du;
    out[2] = -step2 * ds_du * ds_du;
}

/* g = f (psi(u / outer) - psi(u / inner)) and g'' in u (inner 0: the core; outer 0: no outer
 * step, the last ring). */
static void piece_value(const ibl__lobe *lobe, double inner, double outer, double u, double out[2])
{
    double f[3];
    ibl__lobe_f012(lobe, 1.0 - u, f);
    /* derivatives in u = 1 - x: f_u = -f_x, f_uu = f_xx */
    double f0 = f[0], f1 = -f[1], f2 = f[2];
    double psi_out[3] = {1, 0, 0}, psi_in[3] = {0, 0, 0};
    if (outer > 0) psi_derivatives(u / outer, outer, psi_out);
    if (inner > 0) psi_derivatives(u / inner, inner, psi_in);
    double p0 = psi_out[0] - psi_in[0], p1 = psi_out[1] - psi_in[1], p2 = psi_out[2] - psi_in[2];
    out[0] = f0 * p0;
    out[1] = f2 * p0 + 2.0 * f1 * p1 + f0 * p2;
}

/* Tabulates the piece over [u_lo, u_hi] and fills its closed-form description. */
static ibl_status piece_describe(ibl_context *ctx, const ibl__lobe *lobe, double inner,
                                 double outer, lobe_piece *pc)
{
    pc->table = ibl_alloc(ctx, (size_t)(PIECE_TABLE_STEPS + 2) * 2 * sizeof(float));
    if (!pc->table) return ibl_context_status(ctx);
    double step = (pc->u_hi - pc->u_lo) / PIECE_TABLE_STEPS;
    for (int i = 0; i <= PIECE_TABLE_STEPS; i++) {
        double g[2];
        piece_value(lobe, inner, outer, pc->u_lo + i * step, g);
        pc->table[2 * i] = (float)g[0];
        pc->table[2 * i + 1] = (float)g[1];
    }
    pc->table[2 * PIECE_TABLE_STEPS + 2] = pc->table[2 * PIECE_TABLE_STEPS + 3] = 0.0f;
    pc->table_u0 = (float)pc->u_lo;
    pc->table_scale = (float)(PIECE_TABLE_STEPS / (pc->u_hi - pc->u_lo));
    pc->is_ggx = lobe->kind == IBL__LOBE_GGX;
    pc->phong_n = (float)lobe->n;
    /* the series' first dropped terms, n u^7 / 7 in the exponent and u^7 in 1 / x, at the
     * piece's end */
    pc->phong_series = !pc->is_ggx && pc->u_hi <= PHONG_SERIES_MAX_U &&
                       lobe->n * pow(pc->u_hi, 7.0) / 7.0 <= PHONG_SERIES_MAX_ERROR;
    double alpha2 = lobe->alpha * lobe->alpha;
    pc->ggx_alpha2 = (float)alpha2;
    pc->ggx_slope = (float)(0.5 * (1.0 - alpha2));
    pc->ggx_alpha4 = (float)(alpha2 * alpha2);
    /* see psi_step for the encoding of an absent step */
    pc->outer.scale = outer > 0 ? (float)(1.0 / (3.0 * outer)) : 0.0f;
    pc->outer.offset = outer > 0 ? (float)(1.0 / 3.0) : 1.0f;
    pc->outer.slope = pc->outer.scale;
    pc->inner.scale = inner > 0 ? (float)(1.0 / (3.0 * inner)) : 0.0f;
    pc->inner.offset = inner > 0 ? (float)(1.0 / 3.0) : -2.0f;
    pc->inner.slope = pc->inner.scale;
    return IBL_OK;
}

double ibl__fast_piece_peak(const lobe_piece *pc)
{
    double peak = 0;
    for (int i = 0; i <= PIECE_TABLE_STEPS; i++)
        peak = fabs(pc->table[2 * i]) > peak ? fabs(pc->table[2 * i]) : peak;
    return peak;
}

/* The piece's integral over the sphere, 2 pi times the integral of g over u (dOmega = 2 pi du
 * about the lobe's axis), by the trapezoid rule on its table: what its normaliser is at any
 * direction, to the table's and the leaves' precision. */
double ibl__fast_piece_integral(const lobe_piece *pc)
{
    double sum = 0.5 * (pc->table[0] + pc->table[2 * PIECE_TABLE_STEPS]);
    for (int i = 1; i < PIECE_TABLE_STEPS; i++) sum += pc->table[2 * i];
    return 2.0 * IBL_PI * sum * (pc->u_hi - pc->u_lo) / PIECE_TABLE_STEPS;
}

/* The coarsest pyramid level whose texels are at most `width` wide (0 if none is) and whose
 * faces are at least MIN_SOURCE_EDGE texels. */
static int source_level_for(const ibl_specular_plan *p, double width)
{
    int best = 0;
    for (int l = 0; l < p->pyramid_levels; l++)
        if (texel_angle(p->pyramid[l].edge) <= width && p->pyramid[l].edge >= MIN_SOURCE_EDGE)
            best = l;
    return best;
}

/* The level's grid of `edge` points a face edge (at_output: the output texels; lagrange: read by
 * 6-point Lagrange interpolation, combine.c), added if new. */
static int grid_index(level_plan *lv, int edge, int at_output, int lagrange)
{
    for (int g = 0; g < lv->grid_count; g++)
        if (lv->grids[g].edge == edge && lv->grids[g].at_output == at_output &&
            lv->grids[g].lagrange == lagrange)
            return g;
    sum_grid *g = &lv->grids[lv->grid_count];
    g->edge = edge;
    g->at_output = at_output;
    g->lagrange = lagrange;
    g->tiles = (edge + TILE_EDGE - 1) / TILE_EDGE;
    return lv->grid_count++;
}

/* Where a ring of inner radius angle_in is summed: over texels a fixed fraction of its radius
 * wide, on a grid a fixed fraction of it apart; a ring from a coarse level on a coarse grid
 * sends its bright texels to a finer grid (gathering.c) so that its own grid may be coarser. */
static void place_ring(const ibl_specular_plan *p, level_plan *lv, int output_edge, double acc,
                       lobe_piece *pc)
{
    const double ring_texel = RING_SOURCE_TEXEL * acc;
    const double spacing = RING_GRID_SPACING * acc;
    const double spacing_bright_apart = RING_GRID_SPACING_BRIGHT_APART * acc;
    double b = pc->angle_in;
    int finer = centred_directions(p) &&
                acos(1.0 - (pc->u_hi < 2.0 ? pc->u_hi : 2.0)) < RING_PRECOMPUTED_MAX_ANGLE;
    pc->source_level =
        source_level_for(p, (finer ? RING_SOURCE_TEXEL_PRECOMPUTED * acc : ring_texel) * b);
    int bright_apart = pc->source_level > 0;
    int edge = 1;
    while (texel_angle(edge) > (bright_apart ? spacing_bright_apart : spacing) * b) edge *= 2;
    if (edge < MIN_GRID_EDGE) edge = MIN_GRID_EDGE;
    if (edge >= output_edge) {
        pc->grid = grid_index(lv, output_edge, 1, 0);
        return;
    }
    pc->grid = grid_index(lv, edge, 0, 0);
    pc->bright_apart = bright_apart;
    int bright_edge = MIN_GRID_EDGE;
    while (bright_edge < output_edge && texel_angle(bright_edge) > BRIGHT_GRID_SPACING * acc * b)
        bright_edge *= 2;
    pc->bright_grid = bright_edge >= output_edge ? grid_index(lv, output_edge, 1, 0)
                                                 : grid_index(lv, bright_edge, 0, 0);
}

/* Where the core is summed: on the output texels, or, when they are finer than the lobe needs,
 * on a cube grid spaced by the lobe's half width, interpolated (the core of a wide lobe, whose
 * result varies on the scale of its half width, not of the output's texels). The centroid
 * corrections of its weights go to a coarser grid still when one is fine enough for them
 * (gathering.c, difference form).
 *
 * A Phong lobe that is nil long before the horizon is smooth on the scale of its half width
 * with every derivative (cos^n is close to a Gaussian): its grids are read by 6-point Lagrange
 * interpolation (combine.c), which lets the core's grid be four times as coarse as the bilinear
 * rule (tuning.h), its centroid corrections summed on the same grid. Such grids must divide the
 * output's edge (combine.c reads them row by row) and have at least MIN_LAGRANGE_GRID_EDGE
 * points a face edge. A lobe that reaches the horizon has a kink there and keeps the bilinear
 * rules. */
static void place_core(const ibl_specular_plan *p, level_plan *lv, int output_edge, double acc,
                       lobe_piece *pc)
{
    const ibl__lobe *lobe = &lv->lobe;
    double half = lobe->half_angle;
    int smooth = lobe->kind == IBL__LOBE_PHONG && lobe->horizon < PHONG_CULL;
    int core_edge = MIN_GRID_EDGE, correction_edge = MIN_GRID_EDGE;
    while (texel_angle(core_edge) > (smooth ? CORE_GRID_SPACING_LAGRANGE : CORE_GRID_SPACING) * acc * half)
        core_edge *= 2;
    while (texel_angle(correction_edge) > CORRECTION_GRID_SPACING * acc * half) correction_edge *= 2;
    if (!centred_directions(p)) {
        pc->grid = grid_index(lv, output_edge, 1, 0);
        return;
    }
    if (smooth && core_edge < MIN_LAGRANGE_GRID_EDGE) core_edge = MIN_LAGRANGE_GRID_EDGE;
    if (smooth && (core_edge >= output_edge || output_edge % core_edge != 0)) core_edge = output_edge;
    int at_output = core_edge >= output_edge, edge = at_output ? output_edge : core_edge;
    pc->grid = grid_index(lv, edge, at_output, smooth && !at_output);
    /* a smooth core on the output texels is where its Lagrange grid would not divide them or
     * would not be coarser: its corrections, in difference form, go on a Lagrange grid of half
     * the output's edge when that is at most CORRECTION_GRID_SPACING_LAGRANGE half widths apart */
    int half_edge = output_edge / 2;
    if (smooth && at_output && output_edge % 2 == 0 && half_edge >= MIN_LAGRANGE_GRID_EDGE &&
        texel_angle(half_edge) <= CORRECTION_GRID_SPACING_LAGRANGE * acc * lobe->half_angle) {
        pc->has_correction_grid = 1;
        pc->correction_grid = grid_index(lv, half_edge, 0, 1);
    } else if (correction_edge < edge) {
        pc->has_correction_grid = 1;
        pc->correction_grid = grid_index(lv, correction_edge, 0, 0);
    }
}

/* Whether the core's grid holds the core's normaliser alone and may get it at a one-shot run,
 * where the weights are made for the products anyway (precomputed.c, normalisers_at_run), so
 * that the level's bars take the pieces' integrals as their scale (gathering.c) in every plan:
 * a Lagrange grid (only the core is read by one), and the output texels of a smooth Phong core
 * (nil before the horizon) when no ring is summed there (a cmft exponent of 862 at 128 found
 * its 1.7 M weights twice, for the plan's normalisers and for the products). A single piece's
 * normaliser added at the run is the same bits as at the plan. */
int ibl__fast_core_normalisers_later(const level_plan *lv)
{
    const sum_grid *core = &lv->grids[lv->pieces[0].grid];
    if (core->lagrange) return 1;
    if (lv->lobe.kind != IBL__LOBE_PHONG || !(lv->lobe.horizon < PHONG_CULL)) return 0;
    for (int k = 1; k < lv->piece_count; k++)
        if (lv->pieces[k].grid == lv->pieces[0].grid) return 0;
    return 1;
}

static size_t grid_bytes(const sum_grid *gr)
{
    return (size_t)6 * gr->edge * gr->edge * 4 * sizeof(float);
}

/* Every grid's leaf-sum tasks (6 faces of tiles) and its sums (a one-shot plan's: when its plan
 * finds the level's normalisers, ibl__fast_grids_restore). */
static ibl_status allocate_grids(ibl_specular_plan *p, level_plan *lv)
{
    lv->task_count = 0;
    for (int g = 0; g < lv->grid_count; g++) {
        sum_grid *gr = &lv->grids[g];
        lv->task_begin[g] = lv->task_count;
        lv->task_count += 6 * gr->tiles * gr->tiles;
        if (!p->one_shot && !(gr->sums = ibl_alloc(p->ctx, grid_bytes(gr)))) return ibl_context_status(p->ctx);
        if (!gr->at_output) {
            /* a Lagrange grid keeps two copies: the border unfolded, then resampled (combine.c);
             * a one-shot plan makes them for the level's combine only, after the run's buffers
             * are freed (the Phong 256 chain's peak held 4.8 MB of them, read only at the end) */
            size_t m = (size_t)gr->edge + 2 * grid_border(gr), copies = gr->lagrange ? 2 : 1;
            gr->bordered_floats = copies * 6 * m * m * 4;
            if (!p->one_shot && !(gr->bordered = ibl_alloc(p->ctx, gr->bordered_floats * sizeof(float))))
                return ibl_context_status(p->ctx);
        }
    }
    lv->task_begin[lv->grid_count] = lv->task_count;
    return IBL_OK;
}

/* A one-shot plan holds a level's sums only while its plan finds the level's normalisers and
 * while its run sums the level, each level in turn: the normalisers are all the plan writes in
 * them, and face 0's are every face's (leaf_sums.c copies them; a precomputed piece adds the
 * same to each face), so between the two a level keeps face 0's, a quarter of a face's sums.
 * The run makes a level's sums once its weights are made and the geometry they came from is
 * freed (plan.c): the Phong chain with cmft's exponents at 256 has 11 MB of grids, and its
 * peak, level 0's products, holds level 0's 8.3 MB of them only, where its weights (7.2 MB)
 * and their geometry (5.8 MB) would otherwise have met all 11. The floats are copied, so the
 * sums are the same bits. */
ibl_status ibl__fast_grids_set_aside(ibl_specular_plan *p, int level)
{
    level_plan *lv = &p->levels[level];
    for (int g = 0; g < lv->grid_count; g++) {
        sum_grid *gr = &lv->grids[g];
        size_t points = (size_t)gr->edge * gr->edge;
        if (!(gr->normalisers = ibl_alloc(p->ctx, points * sizeof(float)))) return ibl_context_status(p->ctx);
        for (size_t i = 0; i < points; i++) gr->normalisers[i] = gr->sums[i * 4 + 3];
        ibl_free(p->ctx, gr->sums);
        gr->sums = NULL;
    }
    return IBL_OK;
}

/* (at the plan a grid has no normalisers yet: ibl__fast_normalisers writes every point's next;
 * at the run every grid has the ones its plan set aside) */
ibl_status ibl__fast_grids_restore(ibl_specular_plan *p, int level)
{
    level_plan *lv = &p->levels[level];
    for (int g = 0; g < lv->grid_count; g++) {
        sum_grid *gr = &lv->grids[g];
        size_t points = (size_t)gr->edge * gr->edge;
        if (gr->sums) continue;
        if (!(gr->sums = ibl_alloc(p->ctx, grid_bytes(gr)))) return ibl_context_status(p->ctx);
        if (!gr->normalisers) continue;
        for (size_t f = 0; f < 6; f++)
            for (size_t i = 0; i < points; i++) gr->sums[(f * points + i) * 4 + 3] = gr->normalisers[i];
        ibl_free(p->ctx, gr->normalisers);
        gr->normalisers = NULL;
    }
    return IBL_OK;
}

ibl_status ibl__fast_plan_pieces(ibl_specular_plan *p, int level)
{
    level_plan *lv = &p->levels[level];
    const ibl__lobe *lobe = &lv->lobe;
    int n = ibl_level_size(p->output_edge, level);
    double acc = accuracy_scale(p);
    const double cull = lobe->kind == IBL__LOBE_PHONG ? PHONG_CULL : 0.0;

    int core_level = source_level_for(p, core_source_width(lobe, acc));
    double core_end = CORE_END_HALF_WIDTHS * lobe->half_angle;
    double min_core_end = CORE_END_MIN_TEXELS * texel_angle(p->pyramid[core_level].edge);
    if (core_end < min_core_end) core_end = min_core_end;
    /* the scale of psi's step: psi(u / U) starts at u = U and ends at 4 U */
    double U = 1.0 - cos(core_end < IBL_PI ? core_end : IBL_PI);
    lv->grid_count = 0;
    lv->piece_count = 0;
    /* A Phong lobe ends where it falls below `cull` of its peak, u = 1 - cull^(1/n): cos^n dies
     * like exp(-n theta^2 / 2), so the partition's 4x steps in u would carry a piece far past
     * it (the ring after a core of exponent 62.5 reached 1.27 radians, the lobe being under
     * 1e-9 from 0.77 on: summed by leaves instead of precomputed weights). The piece that
     * reaches that end is the last one, without an outer step: the pieces still add up to the
     * lobe exactly, up to the cull. */
    const double u_cull = cull > 0 ? 1.0 - pow(cull, 1.0 / lobe->n) : 2.0;
    double previous_U = 0.0, inner[MAX_PIECES]; /* each piece's inner step scale (0: none) */
    for (int j = 0; j < MAX_PIECES; j++) {
        lobe_piece *pc = &lv->pieces[lv->piece_count];
        memset(pc, 0, sizeof *pc);
        double outer_U = U;
        int last = (outer_U >= 1.0) || j == MAX_PIECES - 1;
        pc->u_lo = previous_U;
        pc->u_hi = last ? 2.0 : 4.0 * outer_U;
        if (pc->u_hi > 2.0) pc->u_hi = 2.0;
        if (pc->u_hi > u_cull) pc->u_hi = u_cull, last = 1;
        pc->angle_in = acos(1.0 - pc->u_lo);
        pc->angle_out = acos(1.0 - (pc->u_hi < 2.0 ? pc->u_hi : 2.0));
        /* a Phong tail far below the peak is dropped (its weight is below `cull`) */
        if (cull > 0 && j > 0 && ibl__lobe_f(lobe, 1.0 - pc->u_lo) < cull) break;
        if (j == 0) {
            pc->source_level = core_level;
            place_core(p, lv, n, acc, pc);
        } else {
            place_ring(p, lv, n, acc, pc);
        }
        /* a ring over the same source level and grid as the ring before it (the far rings,
         * once both reach the coarsest level) joins it: their sum is one piece, the lobe
         * between the first one's inner step and this one's outer step, summed once */
        lobe_piece *prev = lv->piece_count > 1 ? pc - 1 : NULL;
        if (prev && prev->source_level == pc->source_level && prev->grid == pc->grid &&
            prev->bright_apart == pc->bright_apart) {
            prev->u_hi = pc->u_hi;
            prev->angle_out = pc->angle_out;
            ibl_free(p->ctx, prev->table);
            prev->table = NULL;
            ibl_status st = piece_describe(p->ctx, lobe, inner[lv->piece_count - 1],
                                           last ? 0.0 : outer_U, prev);
            if (st != IBL_OK) return st;
        } else {
            inner[lv->piece_count] = j == 0 ? 0.0 : previous_U;
            ibl_status st =
                piece_describe(p->ctx, lobe, inner[lv->piece_count], last ? 0.0 : outer_U, pc);
            if (st != IBL_OK) return st;
            lv->piece_count++;
        }
        if (last) break;
        previous_U = U;
        U *= 4.0;
    }
    return allocate_grids(p, lv);
}
