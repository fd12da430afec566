/* Leaf sums: a piece summed texel by texel over the blocks of its source level that can reach a
 * tile of grid points.
 *
 * A texel contributes the second-order Taylor expansion of the piece g about its centroid:
 *     int g(1 - R.l) dl ~ Omega (g(u0) + g''(u0) R^T C R / 2),  u0 = |R - m|^2 / 2 + e,
 * (u0 is 1 - R.m written so that it keeps float precision next to the lobe's axis, where u is
 * ~alpha^2). The numerator of a coarse level uses its luminance-weighted moments and power; the
 * normaliser always uses the geometric moments, so a constant environment stays constant. The
 * kernels (kernels_portable.c, kernels_avx2.c) evaluate eight texels at a time.
 *
 * Candidate blocks are found per tile of TILE_EDGE^2 grid points: for each face the exact
 * bounding box of the tile's reach (a spherical cap's range of longitudes on the face plane),
 * then 4 x 2-texel blocks tested against the cap (and the ring's hole) by their bounding cones,
 * then per grid point by the same test (candidate_record). Gathered texels (gathering.c) are
 * summed here too, at the grid points of the piece that left them out.
 *
 * The normalisers (plan time) depend only on a direction's (s, t) on its face: the signed
 * permutations that carry one face onto another carry the source texels onto source texels,
 * and the reflections x -> n-1-x, y -> n-1-y, x <-> y are symmetries too, so one eighth of
 * face 0 is summed and copied. Output is bit-identical at any thread count: tiles are
 * independent and each sums in a fixed order. */
#include "bake/specular/fast_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

typedef struct tile_points {
    int count, x[TILE_EDGE * TILE_EDGE], y[TILE_EDGE * TILE_EDGE];
    double dir[TILE_EDGE * TILE_EDGE][3];
    double sums[TILE_EDGE * TILE_EDGE][4];
    double axis[3]; /* the mean of the directions (unit)                  */
    double radius;  /* the largest angle between the axis and a direction */
} tile_points;

/* The reach of a tile for one piece: its axis, the piece's end plus the tile's radius (T), and
 * the piece's hole seen from the tile (its start minus the radius). */
typedef struct reach_test {
    const double *axis;
    double T, cos_T, sin_T;
    double hole, cos_hole, sin_hole;
    double angle_out, angle_in, cos_out, sin_out, cos_in, sin_in;
} reach_test;

typedef struct leaf_job {
    ibl_specular_plan *p;
    int level, mode; /* mode: LEAF_NORMALISER (face 0 only) or numerators (every face) */
} leaf_job;

/* [lo, hi] of tan(longitude) around `pole` of the cap (axis a, radius T), for a face whose axis
 * is `ax` and tangent `tg` (the coordinate is a.tg / a.ax). 0 if the cap misses the face's
 * front half-space in this coordinate. */
static int cap_range(const double a[3], double T, const double ax[3], const double tg[3],
                     const double pole[3], double *lo, double *hi)
{
    double pz = ibl__clampd(ibl__dot_d(a, pole), -1, 1);
    double beta = acos(pz);
    if (T >= beta || T >= IBL_PI - beta) {
        *lo = -1, *hi = 1;
        return 1;
    }
    double phi = atan2(ibl__dot_d(a, tg), ibl__dot_d(a, ax));
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

/* Whether a block's cone is out of the tile's reach or inside the piece's hole. */
static int cone_misses(const reach_test *t, const float *bc)
{
    const double centre[3] = {bc[0], bc[1], bc[2]};
    double c = ibl__dot_d(t->axis, centre), r = bc[3], cr = bc[4], sr = bc[5];
    /* angle(axis, centre) > T + r: out of reach; < hole - r: inside the hole */
    if (t->T + r < IBL_PI && c < t->cos_T * cr - t->sin_T * sr - 1e-7) return 1;
    return t->hole - r > 0 && c > t->cos_hole * cr + t->sin_hole * sr + 1e-7;
}

/* Appends block b (its cone in `cones`) to the batch if it can matter for the tile; 1 when the
 * batch is full. */
static int add_candidate(leaf_batch *batch, leaf_candidate *list, const reach_test *t,
                         const float *cones, uint32_t b)
{
    const float *bc = cones + (size_t)b * CONE_FLOATS;
    if (cone_misses(t, bc)) return 0;
    double r = bc[3], cr = bc[4], sr = bc[5];
    leaf_candidate *cd = &list[batch->count++];
    cd->block = b;
    cd->cos_out = t->angle_out + r >= IBL_PI ? -2.0f : (float)(t->cos_out * cr - t->sin_out * sr) - 1e-6f;
    cd->cos_in = t->angle_in - r <= 0 ? 2.0f : (float)(t->cos_in * cr + t->sin_in * sr) + 1e-6f;
    return batch->count == CANDIDATE_BATCH;
}

/* Sums the batch at every point of the tile and empties it. */
static void sum_batch(const ibl_specular_plan *p, leaf_batch *batch, tile_points *tp)
{
    float R[TILE_EDGE * TILE_EDGE][3], RR[TILE_EDGE * TILE_EDGE][6];
    for (int k = 0; k < tp->count; k++) {
        const double *d = tp->dir[k];
        float *r = R[k], *q = RR[k];
        r[0] = (float)d[0], r[1] = (float)d[1], r[2] = (float)d[2];
        q[0] = r[0] * r[0], q[1] = r[1] * r[1], q[2] = r[2] * r[2];
        q[3] = 2 * r[0] * r[1], q[4] = 2 * r[0] * r[2], q[5] = 2 * r[1] * r[2];
    }
    p->kernels->sum_leaves(batch, tp->count, (const float(*)[3])R, (const float(*)[6])RR, tp->sums);
    batch->count = 0;
}

/* The points of tile (tx, ty) of face `face` of the grid, their axis and radius. */
static void tile_points_of(const ibl_specular_plan *p, const level_plan *lv, const sum_grid *gr,
                           int face, int tx, int ty, tile_points *tp)
{
    int n = gr->edge;
    double *axis = tp->axis;
    tp->count = 0;
    axis[0] = axis[1] = axis[2] = 0;
    for (int y = ty * TILE_EDGE; y < (ty + 1) * TILE_EDGE && y < n; y++)
        for (int x = tx * TILE_EDGE; x < (tx + 1) * TILE_EDGE && x < n; x++) {
            int k = tp->count++;
            tp->x[k] = x, tp->y[k] = y;
            if (gr->at_output) {
                ibl__output_direction(&p->desc, &lv->lobe, face, n, x, y, tp->dir[k]);
            } else {
                ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, tp->dir[k]);
                ibl__normalize_d(tp->dir[k]);
            }
            for (int i = 0; i < 3; i++) axis[i] += tp->dir[k][i];
            memset(tp->sums[k], 0, sizeof tp->sums[k]);
        }
    ibl__normalize_d(axis);
    double min_cos = 1.0;
    for (int k = 0; k < tp->count; k++) {
        double c = ibl__dot_d(axis, tp->dir[k]);
        if (c < min_cos) min_cos = c;
    }
    tp->radius = acos(min_cos > 1 ? 1 : min_cos) + 1e-6;
}

/* Every block of the piece's source level within the tile's reach, face by face (the exact
 * bounding box of the reach on each face, then the blocks' cones). */
static void sum_level_blocks(const ibl_specular_plan *p, const reach_test *reach,
                             leaf_batch *batch, leaf_candidate *list, tile_points *tp)
{
    const source_level *s = batch->level;
    double T = reach->T;
    for (int f = 0; f < 6; f++) {
        double B[3][3], u0, u1, v0, v1;
        for (int r = 0; r < 3; r++)
            for (int i = 0; i < 3; i++) B[r][i] = p->face_basis[f][r][i];
        if (T >= 0.5 * IBL_PI - 1e-9) {
            u0 = v0 = -1, u1 = v1 = 1;
        } else {
            if (!cap_range(reach->axis, T, B[0], B[1], B[2], &u0, &u1)) continue;
            if (!cap_range(reach->axis, T, B[0], B[2], B[1], &v0, &v1)) continue;
        }
        int M = s->edge;
        int x0 = (int)floor((u0 + 1) * 0.5 * M) - 1, x1 = (int)ceil((u1 + 1) * 0.5 * M);
        int y0 = (int)floor((v0 + 1) * 0.5 * M) - 1, y1 = (int)ceil((v1 + 1) * 0.5 * M);
        x0 = x0 < 0 ? 0 : x0, y0 = y0 < 0 ? 0 : y0;
        x1 = x1 > M - 1 ? M - 1 : x1, y1 = y1 > M - 1 ? M - 1 : y1;
        for (int by = y0 / BLOCK_H; by <= y1 / BLOCK_H; by++)
            for (int bx = x0 / BLOCK_W; bx <= x1 / BLOCK_W; bx++) {
                uint32_t b = (uint32_t)(((size_t)f * s->blocks_y + by) * s->blocks_x + bx);
                if (add_candidate(batch, list, reach, s->cones, b)) sum_batch(p, batch, tp);
            }
    }
    if (batch->count) sum_batch(p, batch, tp);
}

/* Gathered blocks (bright texels or corrections): groups of SUPER_CONE_BLOCKS first, by the
 * cones after the blocks' own. */
static void sum_gathered_blocks(const ibl_specular_plan *p, const reach_test *reach,
                                leaf_batch *batch, leaf_candidate *list, tile_points *tp,
                                int blocks, int capacity)
{
    const float *cones = batch->level->cones, *groups = cones + (size_t)capacity * CONE_FLOATS;
    for (int group = 0; group * SUPER_CONE_BLOCKS < blocks; group++) {
        if (cone_misses(reach, groups + (size_t)group * CONE_FLOATS)) continue;
        for (int k = group * SUPER_CONE_BLOCKS; k < (group + 1) * SUPER_CONE_BLOCKS && k < blocks; k++)
            if (add_candidate(batch, list, reach, cones, (uint32_t)k)) sum_batch(p, batch, tp);
    }
    if (batch->count) sum_batch(p, batch, tp);
}

/* Piece pc at the points of a tile of grid g: its own leaf sum when it is summed by leaves on
 * this grid, then the texels gathered for it on this grid (its bright texels, or the
 * corrections of its precomputed weights). */
static void sum_piece(const ibl_specular_plan *p, int mode, int g, const sum_grid *gr,
                      const lobe_piece *pc, tile_points *tp, leaf_candidate *list)
{
    const source_level *s = &p->pyramid[pc->source_level];
    const precomputed_piece *c = pc->precomputed;
    int leaves = pc->grid == g && !c;
    int bright = pc->bright_apart && g == pc->bright_grid && mode != LEAF_NORMALISER &&
                 s->bright_block_count > 0;
    int corrections = c && g == (c->correction_difference ? pc->correction_grid : pc->grid) &&
                      mode != LEAF_NORMALISER && c->correction_block_count > 0;
    if (!leaves && !bright && !corrections) return;
    leaf_batch batch = {mode == LEAF_NORMALISER ? LEAF_NORMALISER
                        : pc->source_level == 0 ? LEAF_LEVEL0 : LEAF_COARSE,
                        s, pc, list, 0, pc->bright_apart && !gr->at_output};
    if (corrections && c->correction_difference) batch.mode = LEAF_DIFFERENCE;
    double rho = tp->radius, T = pc->angle_out + rho;
    reach_test reach = {tp->axis, T, cos(T), sin(T), pc->angle_in - rho, cos(pc->angle_in - rho),
                        sin(pc->angle_in - rho), pc->angle_out, pc->angle_in, cos(pc->angle_out),
                        sin(pc->angle_out), cos(pc->angle_in), sin(pc->angle_in)};
    if (leaves) sum_level_blocks(p, &reach, &batch, list, tp);
    if (bright || corrections) {
        source_level gathered = *s;
        gathered.records = bright ? s->bright_records : c->correction_records;
        gathered.cones = bright ? s->bright_cones : c->correction_cones;
        gathered.fields = COARSE_FIELDS, gathered.first_field = 0;
        batch.level = &gathered, batch.without_bright = 0;
        sum_gathered_blocks(p, &reach, &batch, list, tp,
                            bright ? s->bright_block_count : c->correction_block_count,
                            bright ? s->bright_capacity : c->correction_capacity);
    }
}

/* The texels gathered for piece pc on grid g, as sum_piece reads them (its bright texels
 * first), or 0 blocks when it has none there. */
static int gathered_for(const ibl_specular_plan *p, int mode, int g, const lobe_piece *pc,
                        const float **cones, int *capacity)
{
    const source_level *s = &p->pyramid[pc->source_level];
    const precomputed_piece *c = pc->precomputed;
    int bright = pc->bright_apart && g == pc->bright_grid && mode != LEAF_NORMALISER &&
                 s->bright_block_count > 0;
    int corrections = c && g == (c->correction_difference ? pc->correction_grid : pc->grid) &&
                      mode != LEAF_NORMALISER && c->correction_block_count > 0;
    if (!bright && !corrections) return 0;
    *cones = bright ? s->bright_cones : c->correction_cones;
    *capacity = bright ? s->bright_capacity : c->correction_capacity;
    return bright ? s->bright_block_count : c->correction_block_count;
}

/* Whether tile (tx, ty) of face `face` of grid g (centred directions) can have anything to sum:
 * a piece summed by leaves on the grid, or a group of blocks gathered for a piece on it within
 * the piece's reach. The tile's cone here is its centre and the angle to its farthest corner
 * point (over a convex region of the face plane the angle from a direction is largest at a
 * vertex), so a tile it rules out sums nothing: its sums are zero. Most tiles of a grid that
 * only gathers (a ring's bright texels at the output texels, corrections) are such. */
static int tile_has_work(const ibl_specular_plan *p, const level_plan *lv, int mode, int g,
                         const sum_grid *gr, int face, int tx, int ty)
{
    for (int k = 0; k < lv->piece_count; k++)
        if (lv->pieces[k].grid == g && !lv->pieces[k].precomputed) return 1;
    int n = gr->edge, x0 = tx * TILE_EDGE, y0 = ty * TILE_EDGE;
    int x1 = (x0 + TILE_EDGE < n ? x0 + TILE_EDGE : n) - 1, y1 = (y0 + TILE_EDGE < n ? y0 + TILE_EDGE : n) - 1;
    double axis[3], radius = 0;
    ibl_cube_direction_d(face, 0.5 * (x0 + x1 + 1) / n, 0.5 * (y0 + y1 + 1) / n, axis);
    ibl__normalize_d(axis);
    for (int corner = 0; corner < 4; corner++) {
        double d[3];
        ibl_cube_direction_d(face, ((corner & 1 ? x1 : x0) + 0.5) / n, ((corner & 2 ? y1 : y0) + 0.5) / n, d);
        ibl__normalize_d(d);
        double a = acos(ibl__clampd(ibl__dot_d(axis, d), -1, 1));
        if (a > radius) radius = a;
    }
    radius += 1e-6;
    for (int k = 0; k < lv->piece_count; k++) {
        const lobe_piece *pc = &lv->pieces[k];
        const float *cones;
        int capacity, blocks = gathered_for(p, mode, g, pc, &cones, &capacity);
        if (!blocks) continue;
        double T = pc->angle_out + radius, hole = pc->angle_in - radius;
        reach_test reach = {axis, T, cos(T), sin(T), hole, cos(hole), sin(hole), pc->angle_out,
                            pc->angle_in, cos(pc->angle_out), sin(pc->angle_out), cos(pc->angle_in),
                            sin(pc->angle_in)};
        const float *groups = cones + (size_t)capacity * CONE_FLOATS;
        for (int group = 0; group * SUPER_CONE_BLOCKS < blocks; group++)
            if (!cone_misses(&reach, groups + (size_t)group * CONE_FLOATS)) return 1;
    }
    return 0;
}

/* One tile of one grid of a level: tasks run over the grids in order, then faces, then tiles
 * (the normalisers: face 0 only, and one eighth of it where the grid is symmetric). */
static void tile_task(void *arg, int index)
{
    const leaf_job *job = arg;
    ibl_specular_plan *p = job->p;
    level_plan *lv = &p->levels[job->level];
    int faces = job->mode == LEAF_NORMALISER ? 1 : 6;
    int g = 0, begin = 0;
    while (index >= begin + faces * lv->grids[g].tiles * lv->grids[g].tiles) {
        begin += faces * lv->grids[g].tiles * lv->grids[g].tiles;
        g++;
    }
    sum_grid *gr = &lv->grids[g];
    int t = index - begin, face = t / (gr->tiles * gr->tiles);
    int ty = (t / gr->tiles) % gr->tiles, tx = t % gr->tiles, n = gr->edge;
    if (job->mode == LEAF_NORMALISER && grid_symmetric(p, gr)) {
        /* one eighth of the face: the tiles covering x <= y < ceil(n / 2) */
        int half = ((n + 1) / 2 + TILE_EDGE - 1) / TILE_EDGE;
        if (tx >= half || ty >= half || tx > ty) return;
    }
    if (grid_symmetric(p, gr) && !tile_has_work(p, lv, job->mode, g, gr, face, tx, ty)) {
        for (int y = ty * TILE_EDGE; y < (ty + 1) * TILE_EDGE && y < n; y++)
            for (int x = tx * TILE_EDGE; x < (tx + 1) * TILE_EDGE && x < n; x++) {
                float *o = gr->sums + (((size_t)face * n + y) * n + x) * 4;
                if (job->mode == LEAF_NORMALISER) o[3] = 0.0f;
                else o[0] = o[1] = o[2] = 0.0f;
            }
        return;
    }
    tile_points tp;
    tile_points_of(p, lv, gr, face, tx, ty, &tp);
    leaf_candidate list[CANDIDATE_BATCH];
    for (int k = 0; k < lv->piece_count; k++) sum_piece(p, job->mode, g, gr, &lv->pieces[k], &tp, list);
    for (int k = 0; k < tp.count; k++) {
        float *o = gr->sums + (((size_t)face * n + tp.y[k]) * n + tp.x[k]) * 4;
        if (job->mode == LEAF_NORMALISER) {
            o[3] = (float)tp.sums[k][3];
        } else {
            for (int c = 0; c < 3; c++) o[c] = (float)tp.sums[k][c];
        }
    }
}

void ibl__fast_leaf_sums(ibl_specular_plan *p, int level)
{
    leaf_job job = {p, level, LEAF_LEVEL0};
    ibl_parallel_for(p->ctx, p->levels[level].task_count, tile_task, &job);
}

typedef struct symmetry_job {
    const ibl_specular_plan *p;
    level_plan *lv;
    int first_row[MAX_PIECES + 1]; /* grid g's rows are tasks [first_row[g], first_row[g + 1]) */
} symmetry_job;

/* Row y of grid g: face 0's normalisers from the texel of the symmetric grid's eighth that
 * holds it (which no task writes: it is its own), then the other faces' from face 0's row. */
static void symmetric_row_task(void *arg, int index)
{
    const symmetry_job *j = arg;
    int g = 0;
    while (index >= j->first_row[g + 1]) g++;
    sum_grid *gr = &j->lv->grids[g];
    int n = gr->edge, y = index - j->first_row[g];
    if (grid_symmetric(j->p, gr))
        for (int x = 0; x < n; x++) {
            int a = x < n - 1 - x ? x : n - 1 - x, b = y < n - 1 - y ? y : n - 1 - y;
            if (a > b) {
                int t = a;
                a = b, b = t;
            }
            if (a != x || b != y) gr->sums[((size_t)y * n + x) * 4 + 3] = gr->sums[((size_t)b * n + a) * 4 + 3];
        }
    size_t face = (size_t)n * n * 4, row = (size_t)y * n * 4;
    for (int f = 1; f < 6; f++)
        for (size_t i = row + 3; i < row + (size_t)n * 4; i += 4) gr->sums[f * face + i] = gr->sums[i];
}

void ibl__fast_normalisers(ibl_specular_plan *p, int level)
{
    level_plan *lv = &p->levels[level];
    int tasks = 0;
    for (int g = 0; g < lv->grid_count; g++) tasks += lv->grids[g].tiles * lv->grids[g].tiles;
    leaf_job job = {p, level, LEAF_NORMALISER};
    ibl_parallel_for(p->ctx, tasks, tile_task, &job);
    /* the mirrored texels and faces row by row, then the precomputed pieces' normalisers: as
     * loops (on one thread they were 0.5 + 1.3 ms of the 512 chain's plan, 2.8 + 5 ms of the
     * 1024 chain's, with the other thread waiting) */
    symmetry_job mj = {p, lv, {0}};
    for (int g = 0; g < lv->grid_count; g++) mj.first_row[g + 1] = mj.first_row[g] + lv->grids[g].edge;
    ibl_parallel_for(p->ctx, mj.first_row[lv->grid_count], symmetric_row_task, &mj);
    for (int k = 0; k < lv->piece_count; k++)
        if (lv->pieces[k].precomputed && !lv->pieces[k].precomputed->normalisers_at_run)
            ibl__fast_precomputed_normalisers(p->ctx, lv->pieces[k].precomputed,
                                              lv->grids[lv->pieces[k].grid].sums);
}
