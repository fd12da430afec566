/* Precomputed pieces, plan time: the weights of a piece whose leaves use geometric moments only,
 * found once and kept as rows over a padded face.
 *
 * Which pieces: the core over the source texels themselves (no sub-texels), and any piece over a
 * coarse level read as uniform texels (their non-uniform light is put back by the centroid
 * corrections of gathering.c). Their weights w(R, texel) depend on the cube's geometry alone,
 * and the cube's 48 symmetries carry them over: the weights of the grid points of one quadrant of
 * face 0 (the *base* texels) serve the four quadrants of all six faces (x -> n-1-x, y -> n-1-y and
 * the signed permutations between faces map texels onto texels). The quadrant's diagonal halves
 * them once more: base (a, b) below it (a > b) takes the weights of its mirror (b, a) -- the
 * reflection x <-> y maps the padded face onto itself -- applied to the transposed padded
 * source, so n(n + 2)/8 bases are computed and kept instead of n^2/4.
 *
 * The padded face is the face with a border of `border` texels unfolded from its four neighbours
 * about the shared edges (the border's corner squares are empty), so a window across an edge
 * stays in rows. The border is set by the piece's reach and the smallest texel (1 / (1.5 S)
 * radians, at a face corner); a piece reaching beyond PRECOMPUTED_MAX_REACH is summed by leaves.
 * A base texel's rows are found by a vector scan of a window sized by the local texel size (the
 * whole border when something reaches the window's edge), and its weights are stored as half
 * floats under a per-piece scale. The normaliser sums the same rounded weights, so a constant
 * environment stays constant. A run is then a product of these rows with the padded source
 * (products.c): no lobe evaluation, ~10x cheaper per texel than a leaf. */
#include "bake/specular/fast_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <stdatomic.h>
#include <string.h>

typedef struct weights_job {
    ibl_specular_plan *p;
    precomputed_piece *c;
    const lobe_piece *piece;
    const ibl__lobe *lobe;
    float *geometry;        /* GEOMETRY_FIELDS planes of padded_edge^2, face 0           */
    int32_t *found_rows;    /* base_edge^2 x (2 border + 1) x 3                           */
    int *found_count;       /* base_edge^2: rows found (-1: the border is too narrow)      */
    double cos_reach;       /* the window's reach (sizing)                                */
    double cos_end;         /* a cell counts when R.m >= cos_end: u < the piece's end     */
    /* weights_task: base `index + first_base` writes its weights at weights + its first
     * weight - weight_origin (the whole array, or a batch's scratch) */
    uint16_t *weights;
    size_t weight_origin;
    int first_base;
    /* a batch's: each vector's first cell (as vector_cells), from the batch's first vector */
    uint16_t *cells;
} weights_job;

void ibl__fast_precomputed_destroy(ibl_context *ctx, precomputed_piece *c)
{
    if (!c) return;
    ibl_free(ctx, c->cell_texel);
    ibl_free(ctx, c->first_row);
    ibl_free(ctx, c->first_weight);
    ibl_free(ctx, c->rows);
    ibl_free(ctx, c->vector_cells);
    ibl_free(ctx, c->weights);
    ibl_free(ctx, c->normaliser);
    ibl_free(ctx, c->correction_keys);
    ibl_free(ctx, c->correction_cones);
    ibl_free(ctx, c->texel_bound);
    ibl_free(ctx, c->kept_geometry);
    if (c->own_records) ibl_free(ctx, c->correction_records);
    ibl_free(ctx, c);
}

/* Row `row` of face 0's padded cells: the source texel under each. */
static void cell_texel_task(void *arg, int row)
{
    weights_job *j = arg;
    precomputed_piece *c = j->c;
    int y = row - c->origin;
    if (y < -c->border || y >= c->source_edge + c->border) return;
    for (int x = -c->border; x < c->source_edge + c->border; x++)
        c->cell_texel[(size_t)row * c->padded_edge + x + c->origin] =
            ibl__fast_unfolded_texel(j->p, c->source_edge, 0, x, y);
}

/* Where the signed permutation taking face 0 to face F carries the texels of face g: face
 * out[0] and x' = out[1] + out[2] x + out[3] y, y' = out[4] + out[5] x + out[6] y. */
static void face_carry(const ibl_specular_plan *p, int S, int F, int g, int out[7])
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

/* The direction of base texel (a, b) of face 0 of the piece's grid. */
static void base_direction(const weights_job *j, int a, int b, double R[3])
{
    const precomputed_piece *c = j->c;
    if (c->at_output) {
        ibl__output_direction(&j->p->desc, j->lobe, 0, c->grid_edge, a, b, R);
        return;
    }
    ibl_cube_direction_d(0, (a + 0.5) / c->grid_edge, (b + 0.5) / c->grid_edge, R);
    ibl__normalize_d(R);
}

/* The rows within reach of base texel `index`, scanning a window of half width w; 0 when a row
 * reaches the window's edge (the window is too small). */
static int rows_in_window(weights_job *j, int index, const float R[3], int xc, int yc, int w)
{
    const precomputed_piece *c = j->c;
    int S = c->source_edge, W = c->border;
    int lo = xc - w > -W ? xc - w : -W, hi = xc + w < S + W - 1 ? xc + w : S + W - 1;
    int ylo = yc - w > -W ? yc - w : -W, yhi = yc + w < S + W - 1 ? yc + w : S + W - 1;
    size_t plane = (size_t)c->padded_edge * c->padded_edge;
    int32_t *out = j->found_rows + (size_t)index * (2 * W + 1) * 3;
    int count = 0;
    for (int y = ylo; y <= yhi; y++) {
        int first, last;
        const float *g = j->geometry + (size_t)(y + c->origin) * c->padded_edge + c->origin + lo;
        j->p->kernels->row_extent(g, plane, hi - lo + 1, R, (float)j->cos_end, &first, &last);
        if (first < 0) continue;
        first += lo, last += lo;
        if (first == lo || last == hi || y == ylo || y == yhi) return 0;
        int32_t *r = out + 3 * count++;
        r[0] = y, r[1] = first, r[2] = (last - first + 8) & ~7;
    }
    j->found_count[index] = count;
    return 1;
}

static void rows_task(void *arg, int index)
{
    weights_job *j = arg;
    const precomputed_piece *c = j->c;
    int a = index % c->base_edge, b = index / c->base_edge, S = c->source_edge, W = c->border;
    if (a > b) { /* (b, a)'s, transposed */
        j->found_count[index] = 0;
        return;
    }
    double Rd[3];
    base_direction(j, a, b, Rd);
    float R[3] = {(float)Rd[0], (float)Rd[1], (float)Rd[2]};
    int xc = (int)floor((a + 0.5) * S / c->grid_edge), yc = (int)floor((b + 0.5) * S / c->grid_edge);
    /* first a window sized by the texels around the base texel (radial size (2 / S) / (1 +
     * u^2 + v^2) on the face plane), then, if something lies on its edge, the whole border */
    double u = (xc + 0.5) * 2.0 / S - 1.0, v = (yc + 0.5) * 2.0 / S - 1.0;
    double cells = acos(j->cos_reach) * S * 0.5 * (1.0 + u * u + v * v);
    int w = (int)ceil(PRECOMPUTED_WINDOW_MARGIN * cells) + 2;
    if (w < W && rows_in_window(j, index, R, xc, yc, w)) return;
    if (!rows_in_window(j, index, R, xc, yc, W)) j->found_count[index] = -1; /* W too small */
}

/* The weights of base texel `index` and their sum, from the padded geometry. */
static void weights_task(void *arg, int index)
{
    weights_job *j = arg;
    precomputed_piece *c = j->c;
    index += j->first_base;
    if (j->cells) {
        /* every row's count is a multiple of 8 (rows_in_window): the base's vectors start at
         * its first weight / 8, counted from the batch's */
        size_t v = (c->first_weight[index] - j->weight_origin) / 8;
        for (uint32_t r = c->first_row[index]; r < c->first_row[index + 1]; r++)
            for (int i = 0; i < c->rows[3 * r + 2]; i += 8, v++) {
                j->cells[2 * v] = (uint16_t)(c->rows[3 * r + 1] + i + c->origin);
                j->cells[2 * v + 1] = (uint16_t)(c->rows[3 * r] + c->origin);
            }
    }
    int a = index % c->base_edge, b = index / c->base_edge;
    if (a > b) return; /* (b, a)'s, transposed */
    double Rd[3];
    base_direction(j, a, b, Rd);
    float R[3] = {(float)Rd[0], (float)Rd[1], (float)Rd[2]};
    float RR[6] = {R[0] * R[0], R[1] * R[1], R[2] * R[2], 2 * R[0] * R[1], 2 * R[0] * R[2], 2 * R[1] * R[2]};
    float lanes[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    j->p->kernels->base_weights(j->piece, R, RR, j->geometry, (size_t)c->padded_edge * c->padded_edge,
                                c->padded_edge, c->origin, c->rows + 3 * (size_t)c->first_row[index],
                                (int)(c->first_row[index + 1] - c->first_row[index]), 1.0f / c->weight_scale,
                                j->weights + (c->first_weight[index] - j->weight_origin), lanes);
    double den = 0;
    for (int l = 0; l < 8; l++) den += lanes[l];
    c->normaliser[index] = den * c->weight_scale;
}

typedef struct normaliser_job {
    const precomputed_piece *c;
    float *sums;
} normaliser_job;

/* Base row b's normalisers added to the grid: each base stands for its own output texels, so
 * the rows are independent (each output texel gets one addition, as in order). */
static void normaliser_row_task(void *arg, int b)
{
    const normaliser_job *j = arg;
    const precomputed_piece *c = j->c;
    int n = c->grid_edge;
    for (int a = 0; a < c->base_edge; a++) {
        double den = c->normaliser[b * c->base_edge + a];
        /* the distinct output texels base (a, b) stands for: faces, then flips */
        for (int face = 0; face < 6; face++)
            for (int fy = 0; fy < 2; fy++)
                for (int fx = 0; fx < 2; fx++) {
                    int x = fx ? n - 1 - a : a, y = fy ? n - 1 - b : b;
                    if ((fx && x == a) || (fy && y == b)) continue;
                    float *o = j->sums + (((size_t)face * n + y) * n + x) * 4;
                    o[3] = (float)(o[3] + den);
                }
    }
}

/* A loop over the base rows: on one thread it was 1.3 ms of the 512 chain's plan and 5 ms of
 * the 1024 chain's, with the other thread waiting. */
void ibl__fast_precomputed_normalisers(ibl_context *ctx, const precomputed_piece *c, float *sums)
{
    normaliser_job job = {c, sums};
    ibl_parallel_for(ctx, c->base_edge, normaliser_row_task, &job);
}

/* Row `row` of face 0's padded geometry: each cell's texel's geometric moments (a cell without
 * a texel: no solid angle, and u > 2, beyond every lobe). */
static void geometry_task(void *arg, int row)
{
    const weights_job *j = arg;
    const precomputed_piece *c = j->c;
    size_t plane = (size_t)c->padded_edge * c->padded_edge, face = (size_t)c->source_edge * c->source_edge;
    const source_level *s = &j->p->pyramid[c->source_level];
    float *geo = j->geometry;
    for (size_t i = (size_t)row * c->padded_edge; i < (size_t)(row + 1) * c->padded_edge; i++) {
        int32_t t = c->cell_texel[i];
        if (t < 0) {
            for (int f = 0; f < GEOMETRY_FIELDS; f++) geo[f * plane + i] = 0.0f;
            geo[FIELD_SPREAD * plane + i] = 4.0f;
            continue;
        }
        int f = (int)(t / face), y = (int)(t % face) / c->source_edge, x = (int)(t % face) % c->source_edge;
        if (c->source_level == 0 && !j->p->has_level0_records) {
            float v[GEOMETRY_FIELDS];
            ibl__fast_level0_moments(j->p, f, x, y, v);
            for (int k = 0; k < GEOMETRY_FIELDS; k++) geo[k * plane + i] = v[k];
        } else {
            float v[GEOMETRY_FIELDS];
            level_texel_geometry(j->p->face_axis[f], j->p->face_sign[f], s, f, x, y, v);
            for (int k = 0; k < GEOMETRY_FIELDS; k++) geo[k * plane + i] = v[k];
        }
    }
}

/* A new precomputed piece: its sizes, arrays, padded map and face carries (NULL: no memory). */
static precomputed_piece *precomputed_new(ibl_specular_plan *p, const lobe_piece *pc,
                                          const sum_grid *gr, int S, int W)
{
    ibl_context *ctx = p->ctx;
    precomputed_piece *c = ibl_calloc(ctx, 1, sizeof *c);
    if (!c) return NULL;
    c->source_level = pc->source_level;
    c->at_output = gr->at_output;
    c->without_bright = pc->bright_apart;
    c->correction_difference = pc->has_correction_grid && pc->source_level > 0 && !pc->bright_apart;
    c->source_edge = S, c->border = W, c->origin = W + 8, c->padded_edge = S + 2 * W + 16;
    c->grid_edge = gr->edge, c->base_edge = (gr->edge + 1) / 2;
    size_t plane = (size_t)c->padded_edge * c->padded_edge, bases = (size_t)c->base_edge * c->base_edge;
    c->cell_texel = ibl_alloc(ctx, plane * sizeof(int32_t));
    c->first_row = ibl_alloc(ctx, (bases + 1) * sizeof(uint32_t));
    c->first_weight = ibl_alloc(ctx, (bases + 1) * sizeof(size_t));
    c->normaliser = ibl_alloc(ctx, bases * sizeof(double));
    if (!c->cell_texel || !c->first_row || !c->first_weight || !c->normaliser) {
        ibl__fast_precomputed_destroy(ctx, c);
        return NULL;
    }
    for (size_t i = 0; i < plane; i++) c->cell_texel[i] = -1;
    for (int f = 0; f < 6; f++)
        for (int g = 0; g < 6; g++) face_carry(p, S, f, g, c->face_carry[f][g]);
    return c;
}

/* The arrays a piece's weights take (the weights and their vectors' cells), freed between the
 * plan and the products of a one-shot plan. */
static ibl_status allocate_weights(ibl_context *ctx, precomputed_piece *c)
{
    size_t weights = c->first_weight[(size_t)c->base_edge * c->base_edge];
    c->weights = ibl_alloc(ctx, (weights ? weights : 1) * sizeof(uint16_t));
    c->vector_cells = ibl_alloc(ctx, (weights / 8 + 1) * 2 * sizeof(uint16_t));
    return c->weights && c->vector_cells ? IBL_OK : ibl_context_status(ctx);
}

/* The rows of PACK_BASES bases a task (pack_task): laid end to end (from the rows found), and
 * their vectors' first cells. Run through ibl_parallel_for: copying them on the calling thread
 * was a serial stretch of ~1.5 ms in the 256 GGX chain (into fresh pages), between loops. */
enum { PACK_BASES = 64 };

typedef struct pack_job {
    precomputed_piece *c;
    const int32_t *found_rows; /* NULL: the rows are in place already */
    const int *found_count;
    int cells;                 /* also the vectors' first cells */
} pack_job;

static void pack_task(void *arg, int index)
{
    const pack_job *pj = arg;
    precomputed_piece *c = pj->c;
    size_t bases = (size_t)c->base_edge * c->base_edge, stride = (size_t)(2 * c->border + 1) * 3;
    size_t b0 = (size_t)index * PACK_BASES, b1 = b0 + PACK_BASES < bases ? b0 + PACK_BASES : bases;
    if (pj->found_rows)
        for (size_t i = b0; i < b1; i++)
            memcpy(c->rows + 3 * (size_t)c->first_row[i], pj->found_rows + i * stride,
                   (size_t)pj->found_count[i] * 3 * sizeof(int32_t));
    if (!pj->cells) return;
    /* every row's count is a multiple of 8 (rows_in_window), so base i's vectors start at its
     * first weight / 8, as counting them from the first row gives */
    size_t v = c->first_weight[b0] / 8;
    for (size_t r = c->first_row[b0]; r < c->first_row[b1]; r++) /* padded cells are below 3 S + 16 <= 49168 */
        for (int i = 0; i < c->rows[3 * r + 2]; i += 8, v++) {
            c->vector_cells[2 * v] = (uint16_t)(c->rows[3 * r + 1] + i + c->origin);
            c->vector_cells[2 * v + 1] = (uint16_t)(c->rows[3 * r] + c->origin);
        }
}

static void pack(ibl_context *ctx, precomputed_piece *c, const int32_t *found_rows,
                 const int *found_count, int cells)
{
    size_t bases = (size_t)c->base_edge * c->base_edge;
    pack_job pj = {c, found_rows, found_count, cells};
    ibl_parallel_for(ctx, (int)((bases + PACK_BASES - 1) / PACK_BASES), pack_task, &pj);
}

/* What a one-shot plan's piece frees once its level's grids are summed: the weights made for
 * the products and the records of its corrections. */
void ibl__fast_precomputed_release(ibl_context *ctx, precomputed_piece *c)
{
    ibl_free(ctx, c->weights);
    ibl_free(ctx, c->vector_cells);
    c->weights = NULL;
    c->vector_cells = NULL;
    if (c->own_records) {
        ibl_free(ctx, c->correction_records);
        c->correction_records = NULL;
        c->own_records = 0;
    }
}

/* Where each base's rows and weights start: the bases' counts summed PACK_BASES at a time by a
 * loop, those sums' running totals on the calling thread, then each run of bases laid from its
 * total by a loop (integers: the same offsets as one pass; that pass was 2-5 ms of the 512 and
 * 1024 chains' plans with the other thread waiting). */
typedef struct offsets_job {
    precomputed_piece *c;
    const weights_job *j;
    size_t *rows, *weights; /* per run of PACK_BASES bases: its sums, then where it starts */
    atomic_int too_narrow;  /* some base's border was too narrow */
} offsets_job;

static void run_sums_task(void *arg, int index)
{
    offsets_job *o = arg;
    const weights_job *j = o->j;
    size_t bases = (size_t)o->c->base_edge * o->c->base_edge, stride = (size_t)(2 * o->c->border + 1) * 3;
    size_t b0 = (size_t)index * PACK_BASES, b1 = b0 + PACK_BASES < bases ? b0 + PACK_BASES : bases;
    size_t rows = 0, weights = 0;
    for (size_t i = b0; i < b1; i++) {
        if (j->found_count[i] < 0) {
            atomic_store(&o->too_narrow, 1);
            return;
        }
        for (int r = 0; r < j->found_count[i]; r++) weights += (size_t)j->found_rows[i * stride + r * 3 + 2];
        rows += (size_t)j->found_count[i];
    }
    o->rows[index] = rows, o->weights[index] = weights;
}

static void run_offsets_task(void *arg, int index)
{
    offsets_job *o = arg;
    const weights_job *j = o->j;
    precomputed_piece *c = o->c;
    size_t bases = (size_t)c->base_edge * c->base_edge, stride = (size_t)(2 * c->border + 1) * 3;
    size_t b0 = (size_t)index * PACK_BASES, b1 = b0 + PACK_BASES < bases ? b0 + PACK_BASES : bases;
    size_t rows = o->rows[index], weights = o->weights[index];
    for (size_t i = b0; i < b1; i++) {
        c->first_row[i] = (uint32_t)rows;
        c->first_weight[i] = weights;
        for (int r = 0; r < j->found_count[i]; r++) weights += (size_t)j->found_rows[i * stride + r * 3 + 2];
        rows += (size_t)j->found_count[i];
    }
}

/* Lays the rows found per base texel end to end, with their vectors' first cells; 0 when the
 * border was too narrow for some base or the weights would crowd the memory budget (sum by
 * leaves), -1 when memory ran out. */
static int pack_rows(ibl_context *ctx, precomputed_piece *c, const weights_job *j)
{
    size_t bases = (size_t)c->base_edge * c->base_edge, runs = (bases + PACK_BASES - 1) / PACK_BASES;
    offsets_job o = {c, j, ibl_alloc(ctx, runs * sizeof(size_t)), ibl_alloc(ctx, runs * sizeof(size_t)), 0};
    if (!o.rows || !o.weights) {
        ibl_free(ctx, o.rows);
        ibl_free(ctx, o.weights);
        return -1;
    }
    ibl_parallel_for(ctx, (int)runs, run_sums_task, &o);
    size_t rows = 0, weights = 0;
    for (size_t r = 0; r < runs && !atomic_load(&o.too_narrow); r++) {
        size_t run_rows = o.rows[r], run_weights = o.weights[r];
        o.rows[r] = rows, o.weights[r] = weights;
        rows += run_rows, weights += run_weights;
    }
    if (!atomic_load(&o.too_narrow)) ibl_parallel_for(ctx, (int)runs, run_offsets_task, &o);
    ibl_free(ctx, o.rows);
    ibl_free(ctx, o.weights);
    if (atomic_load(&o.too_narrow)) return 0;
    c->first_row[bases] = (uint32_t)rows;
    c->first_weight[bases] = weights;
    /* half floats, a 4-byte cell per 8 of them, 12 bytes a row */
    double bytes = weights * (sizeof(uint16_t) + 0.5) + (double)rows * 3 * sizeof(int32_t);
    uint64_t max = ibl_context_max_bytes(ctx), now = ibl_context_current_bytes(ctx);
    if (now >= max || bytes > PRECOMPUTED_BUDGET_SHARE * (double)(max - now)) return 0;
    c->rows = ibl_alloc(ctx, (rows ? rows : 1) * 3 * sizeof(int32_t));
    /* a one-shot plan finds the normalisers batch by batch (one_shot_normalisers) */
    if (!c->rows || (!j->p->one_shot && allocate_weights(ctx, c) != IBL_OK)) return -1;
    pack(ctx, c, j->found_rows, j->found_count, c->weights != NULL);
    return 1;
}

/* A one-shot plan's normalisers without keeping the weights: the bases in batches of about
 * ONE_SHOT_WEIGHT_BATCHES-th of the weights, each batch's weights in one scratch array (the
 * same halves, summed the same way, as weights_task stores). */
enum { ONE_SHOT_WEIGHT_BATCHES = 16 };
static ibl_status one_shot_normalisers(ibl_context *ctx, weights_job *job)
{
    const precomputed_piece *c = job->c;
    size_t bases = (size_t)c->base_edge * c->base_edge, total = c->first_weight[bases];
    size_t cap = total / ONE_SHOT_WEIGHT_BATCHES + 1;
    for (size_t i = 0; i < bases; i++)
        if (c->first_weight[i + 1] - c->first_weight[i] > cap) cap = c->first_weight[i + 1] - c->first_weight[i];
    job->weights = ibl_alloc(ctx, cap * sizeof(uint16_t));
    if (!job->weights) return ibl_context_status(ctx);
    for (size_t first = 0, end; first < bases; first = end) {
        for (end = first + 1; end < bases && c->first_weight[end + 1] - c->first_weight[first] <= cap;) end++;
        job->first_base = (int)first;
        job->weight_origin = c->first_weight[first];
        ibl_parallel_for(ctx, (int)(end - first), weights_task, job);
    }
    ibl_free(ctx, job->weights);
    job->weights = NULL, job->first_base = 0, job->weight_origin = 0;
    return IBL_OK;
}

/* Whether a level before `level` keeps its core's padded geometry for the run (KEPT_GEOMETRY_BYTES
 * in tuning.h: the first one only). */
static int geometry_kept_before(const ibl_specular_plan *p, int level)
{
    for (int l = 0; l < level; l++)
        if (p->levels[l].piece_count > 0 && p->levels[l].pieces[0].precomputed &&
            p->levels[l].pieces[0].precomputed->kept_geometry)
            return 1;
    return 0;
}

/* Sets up piece k of a level as precomputed weights when it can be (a symmetric grid, level 0
 * only without sub-texels, a reach the padded face holds); leaves it to the leaf sums when the
 * border would be too deep or the weights too many. */
static ibl_status precompute_piece(ibl_specular_plan *p, int level, int k)
{
    level_plan *lv = &p->levels[level];
    lobe_piece *pc = &lv->pieces[k];
    const sum_grid *gr = &lv->grids[pc->grid];
    if ((pc->source_level == 0 && p->subtexel_split != 1) || !grid_symmetric(p, gr)) return IBL_OK;
    int S = p->pyramid[pc->source_level].edge;
    /* reach: the piece's end plus a texel's angular radius; a cell subtends at least 1 / (1.5 S)
     * radians (radially, at a face corner), so W cells of border hold everything in reach (the
     * border is at most a whole neighbouring face) */
    double reach = pc->angle_out + 2.0 / S;
    if (reach > PRECOMPUTED_MAX_REACH) return IBL_OK;
    int W = (int)ceil(1.5 * S * reach) + 2;
    if (W > S) W = S;
    ibl_context *ctx = p->ctx;
    precomputed_piece *c = precomputed_new(p, pc, gr, S, W);
    if (!c) return ibl_context_status(ctx);
    /* a Phong piece's corrections in blocks spanning at most a fraction of its reach (gathering.c;
     * GGX's are packed as they come, its output unchanged) */
    if (lv->lobe.kind == IBL__LOBE_PHONG) {
        int span = (int)(GATHER_SPAN_OF_REACH * pc->angle_out / texel_angle(S));
        c->gather_span = span > 1 ? span : 1;
    }
    size_t plane = (size_t)c->padded_edge * c->padded_edge, bases = (size_t)c->base_edge * c->base_edge;
    /* u0 = 1 - R.m for a leaf at centroid m: the piece is zero from u_hi on, exactly */
    double cos_end = 1.0 - (pc->u_hi < 2.0 ? pc->u_hi : 2.0) - 1e-6;
    float *geometry = ibl_alloc(ctx, GEOMETRY_FIELDS * plane * sizeof(float));
    int32_t *found_rows = ibl_alloc(ctx, bases * (2 * W + 1) * 3 * sizeof(int32_t));
    int *found_count = ibl_alloc(ctx, bases * sizeof(int));
    weights_job job = {p, c, pc, &lv->lobe, geometry, found_rows, found_count, cos(reach), cos_end,
                       NULL, 0, 0, NULL};
    int packed = -1;
    if (geometry && found_rows && found_count) {
        ibl_parallel_for(ctx, c->padded_edge, cell_texel_task, &job);
        ibl_parallel_for(ctx, c->padded_edge, geometry_task, &job);
        ibl_parallel_for(ctx, (int)bases, rows_task, &job);
        packed = pack_rows(ctx, c, &job);
    }
    ibl_free(ctx, found_rows);
    ibl_free(ctx, found_count);
    if (packed == 1) {
        /* the weights' bound: the largest texel (a face centre) times the piece's peak */
        c->weight_scale = (float)(WEIGHT_BOUND_FACTOR * ibl__fast_piece_peak(pc) *
                                  ibl_cube_texel_solid_angle(S, S / 2, S / 2));
        if (!(c->weight_scale > 0)) c->weight_scale = 1.0f;
        /* a one-shot plan keeps the rows and the normalisers only: its weights are made again
         * for the products (ibl__fast_precomputed_refill); a core whose grid holds no other
         * piece's normaliser (a narrow Phong lobe's, with the most weights a point of any
         * piece: pieces.c, ibl__fast_core_normalisers_later) makes them there only, and its
         * normalisers with them (the same bits: no other piece adds to them) */
        c->normalisers_at_run = p->one_shot && k == 0 && ibl__fast_core_normalisers_later(lv);
        job.weights = c->weights;
        if (c->weights) ibl_parallel_for(ctx, (int)bases, weights_task, &job);
        else if (!c->normalisers_at_run && one_shot_normalisers(ctx, &job) != IBL_OK) packed = -1;
        /* the normalisers of the bases below the diagonal: their mirrors' (the same weights) */
        for (int b = 0; b < c->base_edge; b++)
            for (int a = b + 1; a < c->base_edge; a++)
                c->normaliser[b * c->base_edge + a] = c->normaliser[a * c->base_edge + b];
        if (packed == 1) pc->precomputed = c;
        if (packed == 1 && c->normalisers_at_run && !geometry_kept_before(p, level) &&
            GEOMETRY_FIELDS * plane * sizeof(float) <= KEPT_GEOMETRY_BYTES)
            c->kept_geometry = geometry, geometry = NULL;
    }
    ibl_free(ctx, geometry);
    if (packed != 1) ibl__fast_precomputed_destroy(ctx, c);
    return packed < 0 ? ibl_context_status(ctx) : IBL_OK;
}

ibl_status ibl__fast_precompute_level(ibl_specular_plan *p, int level)
{
    for (int k = 0; k < p->levels[level].piece_count; k++) {
        ibl_status st = precompute_piece(p, level, k);
        if (st != IBL_OK) return st;
    }
    return IBL_OK;
}

/* A one-shot plan's piece k of a level, batch by batch (products.c): its padded geometry, made
 * once (NULL: no memory; ibl_free it after), then the weights of bases [first, end) written
 * from `weights` on and their vectors' first cells from `cells` on: the same halves as
 * weights_task stores for the whole piece (ibl__fast_precomputed_refill). */
float *ibl__fast_precomputed_geometry(ibl_specular_plan *p, int level, int k)
{
    const precomputed_piece *c = p->levels[level].pieces[k].precomputed;
    float *geometry = ibl_alloc(p->ctx, GEOMETRY_FIELDS * (size_t)c->padded_edge * c->padded_edge * sizeof(float));
    if (!geometry) return NULL;
    weights_job job = {p, p->levels[level].pieces[k].precomputed, &p->levels[level].pieces[k],
                       &p->levels[level].lobe, geometry, NULL, NULL, 0.0, 0.0, NULL, 0, 0, NULL};
    ibl_parallel_for(p->ctx, c->padded_edge, geometry_task, &job);
    return geometry;
}

void ibl__fast_precomputed_weights(ibl_specular_plan *p, int level, int k, const float *geometry,
                                   size_t first, size_t end, uint16_t *weights, uint16_t *cells)
{
    lobe_piece *pc = &p->levels[level].pieces[k];
    precomputed_piece *c = pc->precomputed;
    size_t origin = c->first_weight[first];
    /* each vector's first cell too, base by base in the same tasks (after the loop, on the
     * calling thread, they were 6.5 ms of the 1024 chain with the other thread waiting) */
    weights_job job = {p, c, pc, &p->levels[level].lobe, (float *)geometry, NULL, NULL, 0.0, 0.0,
                       weights, origin, (int)first, cells};
    ibl_parallel_for(p->ctx, (int)(end - first), weights_task, &job);
}

/* The weights of a one-shot plan's piece k of a level again, from its rows: the same geometry,
 * rows and scale, so the same halves (and normalisers) as the plan found. */
ibl_status ibl__fast_precomputed_refill(ibl_specular_plan *p, int level, int k)
{
    level_plan *lv = &p->levels[level];
    lobe_piece *pc = &lv->pieces[k];
    precomputed_piece *c = pc->precomputed;
    if (!c || c->weights) return IBL_OK;
    ibl_context *ctx = p->ctx;
    size_t plane = (size_t)c->padded_edge * c->padded_edge, bases = (size_t)c->base_edge * c->base_edge;
    double cos_end = 1.0 - (pc->u_hi < 2.0 ? pc->u_hi : 2.0) - 1e-6;
    /* the plan's geometry when it kept it (the same floats), else made again */
    float *geometry = c->kept_geometry ? c->kept_geometry
                                       : ibl_alloc(ctx, GEOMETRY_FIELDS * plane * sizeof(float));
    ibl_status st = geometry ? allocate_weights(ctx, c) : ibl_context_status(ctx);
    if (st == IBL_OK) {
        weights_job job = {p, c, pc, &lv->lobe, geometry, NULL, NULL, 0.0, cos_end, c->weights, 0, 0,
                           NULL};
        pack(ctx, c, NULL, NULL, 1);
        if (!c->kept_geometry) ibl_parallel_for(ctx, c->padded_edge, geometry_task, &job);
        ibl_parallel_for(ctx, (int)bases, weights_task, &job);
    }
    ibl_free(ctx, geometry);
    c->kept_geometry = NULL;
    return st;
}

/* The normalisers the plan left to the run (normalisers_at_run), found by the refill: the bases
 * below the diagonal take their mirrors', as precompute_piece does, and all are added to the
 * grid's sums. */
void ibl__fast_precomputed_run_normalisers(ibl_specular_plan *p, int level, int k)
{
    const lobe_piece *pc = &p->levels[level].pieces[k];
    precomputed_piece *c = pc->precomputed;
    for (int b = 0; b < c->base_edge; b++)
        for (int a = b + 1; a < c->base_edge; a++)
            c->normaliser[b * c->base_edge + a] = c->normaliser[a * c->base_edge + b];
    ibl__fast_precomputed_normalisers(p->ctx, c, p->levels[level].grids[pc->grid].sums);
}
