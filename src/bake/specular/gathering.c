/* Gathering: the texels that the cheap paths would get wrong, picked at every run and summed
 * leaf by leaf at the output texels.
 *
 * Bright texels. A ring summed from a coarse level on a coarse grid is interpolated bilinearly
 * to the output texels; a bright texel (a sun) next to such a grid would be smeared over a grid
 * cell. So a texel whose largest contribution to an output exceeds BRIGHT_BAR of the mean
 * radiance is left out of the ring's grid (its power without it is FIELD_POWER_NOT_BRIGHT) and
 * summed on a grid fine enough for it (pieces.c) -- the ring's grid may then be 3x coarser.
 *
 * Centroid corrections. A precomputed piece over a coarse level (precomputed.c) reads each
 * texel as uniform light over its area; a texel whose light is far from uniform (a sun in one
 * corner) has a moment leaf far from that. The difference is bounded per texel by the piece's
 * slopes (plan time) times how far the luminance moments are from the geometric ones (run
 * time); texels over CORRECTION_BAR of the mean radiance are left out of the padded source and
 * summed as leaves at their luminance moments instead.
 *
 * Both bars are raised until the texels fit a fixed number of blocks, so the direct sums stay
 * bounded. Picked texels are gathered eight to a block in Morton order (Morton 1966: face,
 * then interleaved x and y bits), so that a gathered block holds neighbours and its cone is
 * small; blocks are also grouped SUPER_CONE_BLOCKS at a time under one cone, tested first. */
#include "bake/specular/fast_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- plan time: the bars' constants ---- */

/* The piece's bound constants of a centroid correction, per unit of the level's mean normaliser
 * `den`: a leaf moves by at most |g'| sqrt(2u) |dm| + |g'| |de| + 3 |g''| |dC| / 2 (g' by
 * differences of the table). */
static void correction_bounds(const lobe_piece *pc, double den, precomputed_piece *c)
{
    double step = (pc->u_hi - pc->u_lo) / PIECE_TABLE_STEPS, d1 = 0, d1e = 0, d2 = 0;
    const float *tab = pc->table;
    for (int i = 0; i < PIECE_TABLE_STEPS; i++) {
        double u = pc->u_lo + (i + 0.5) * step;
        double g1 = fabs(tab[2 * i + 2] - tab[2 * i]) / step;
        double g2 = fabs(tab[2 * i + 1]) > fabs(tab[2 * i + 3]) ? fabs(tab[2 * i + 1])
                                                                : fabs(tab[2 * i + 3]);
        d1 = g1 * sqrt(2.0 * u) > d1 ? g1 * sqrt(2.0 * u) : d1;
        d1e = g1 > d1e ? g1 : d1e;
        d2 = 1.5 * g2 > d2 ? 1.5 * g2 : d2;
    }
    c->bound_mean = d1 / den, c->bound_spread = d1e / den, c->bound_covariance = d2 / den;
}

/* A texel of power P adds at most P peak / den to an output of a ring whose bright texels go
 * apart (peak: the piece's largest value, den: the level's mean normaliser), so the bright test
 * is P > BRIGHT_BAR mean_radiance den / peak; a source level keeps the strictest of its rings'
 * constants. Precomputed pieces over coarse levels get their correction bounds and buffers. */
ibl_status ibl__fast_plan_bars(ibl_specular_plan *p, int level)
{
    level_plan *lv = &p->levels[level];
    const sum_grid *core_grid = &lv->grids[lv->pieces[0].grid];
    size_t face = (size_t)core_grid->edge * core_grid->edge;
    double den = 0;
    if (ibl__fast_core_normalisers_later(lv)) {
        /* the core grid's normalisers may be found only at the run (pieces.c, precomputed.c
         * normalisers_at_run): its pieces' integrals, the same whether they are or not */
        for (int k = 0; k < lv->piece_count; k++)
            if (lv->pieces[k].grid == lv->pieces[0].grid) den += ibl__fast_piece_integral(&lv->pieces[k]);
    } else {
        for (size_t i = 0; i < face; i++) den += core_grid->sums[4 * i + 3];
        den /= (double)face;
    }
    for (int k = 0; k < lv->piece_count; k++) {
        const lobe_piece *pc = &lv->pieces[k];
        precomputed_piece *c = pc->precomputed;
        if (!c || c->source_level == 0 || !(den > 0)) continue;
        correction_bounds(pc, den, c);
        /* no more blocks than the level has: a capacity it cannot fill would only take memory */
        size_t blocks = source_block_count(&p->pyramid[c->source_level]);
        c->correction_capacity = blocks < CORRECTION_BLOCKS ? (int)blocks : CORRECTION_BLOCKS;
        p->correction_pool_blocks += (size_t)c->correction_capacity;
        c->correction_cones =
            ibl_alloc(p->ctx, cone_slots(c->correction_capacity) * CONE_FLOATS * sizeof(float));
        c->correction_keys =
            ibl_alloc(p->ctx, (size_t)c->correction_capacity * BLOCK_TEXELS * sizeof(uint64_t));
        c->texel_bound = ibl_alloc(p->ctx, source_block_count(&p->pyramid[c->source_level]) *
                                               BLOCK_TEXELS * sizeof(float));
        if (!c->correction_cones || !c->correction_keys || !c->texel_bound)
            return ibl_context_status(p->ctx);
    }
    for (int k = 0; k < lv->piece_count; k++) {
        const lobe_piece *pc = &lv->pieces[k];
        if (!pc->bright_apart) continue;
        double peak = ibl__fast_piece_peak(pc);
        if (!(peak > 0)) continue;
        double scale = den / peak;
        source_level *s = &p->pyramid[pc->source_level];
        if (s->bright_scale == 0 || scale < s->bright_scale) s->bright_scale = scale;
    }
    return IBL_OK;
}

ibl_status ibl__fast_gathering_buffers(ibl_specular_plan *p)
{
    ibl_context *ctx = p->ctx;
    size_t record_bytes = (size_t)COARSE_FIELDS * BLOCK_TEXELS * sizeof(float);
    /* (a one-shot plan's pieces make their corrections' records as they gather them) */
    if (p->correction_pool_blocks && !p->one_shot &&
        !(p->correction_pool = ibl_alloc(ctx, p->correction_pool_blocks * record_bytes)))
        return ibl_context_status(ctx);
    for (int l = 0; l < p->pyramid_levels; l++) {
        source_level *s = &p->pyramid[l];
        if (s->bright_scale == 0) continue;
        s->bright_capacity = BRIGHT_BLOCKS;
        s->bright_records = ibl_alloc(ctx, (size_t)s->bright_capacity * record_bytes);
        s->bright_cones = ibl_alloc(ctx, cone_slots(s->bright_capacity) * CONE_FLOATS * sizeof(float));
        s->bright_keys = ibl_alloc(ctx, (size_t)s->bright_capacity * BLOCK_TEXELS * sizeof(uint64_t));
        if (!s->bright_records || !s->bright_cones || !s->bright_keys) return ibl_context_status(ctx);
    }
    return IBL_OK;
}

/* ---- gathering texels in Morton order ---- */

/* A texel's place in the order texels are gathered in: its face, then the Morton order of its
 * (x, y). (In block order a gathered block could span a face row, and every tile's reach test
 * would take it: at 512, level 1's corrections cost 3x more that way.) */
static uint64_t texel_key(const source_level *s, size_t b, int t)
{
    size_t per_face = (size_t)s->blocks_y * s->blocks_x;
    int f = (int)(b / per_face), r = (int)(b % per_face);
    uint32_t x = (uint32_t)((r % s->blocks_x) * BLOCK_W + t % BLOCK_W);
    uint32_t y = (uint32_t)((r / s->blocks_x) * BLOCK_H + t / BLOCK_W);
    uint64_t key = 0;
    for (int i = 0; i < 16; i++)
        key |= (uint64_t)((x >> i) & 1) << (2 * i) | (uint64_t)((y >> i) & 1) << (2 * i + 1);
    return (uint64_t)f << 32 | key;
}

/* The block and lane of a texel_key. */
static void texel_of_key(const source_level *s, uint64_t key, size_t *b, int *t)
{
    int f = (int)(key >> 32);
    uint32_t x = 0, y = 0;
    for (int i = 0; i < 16; i++) {
        x |= (uint32_t)((key >> (2 * i)) & 1) << i;
        y |= (uint32_t)((key >> (2 * i + 1)) & 1) << i;
    }
    *b = ((size_t)f * s->blocks_y + y / BLOCK_H) * s->blocks_x + x / BLOCK_W;
    *t = (int)(y % BLOCK_H) * BLOCK_W + (int)(x % BLOCK_W);
}

static int key_order(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* The cones of `blocks` blocks of gathered texels (records; a block's texels fill its first
 * lanes, an empty lane has no solid angle): around the mean of each block's texel directions,
 * out to the farthest one plus `texel_radius`. */
static void gathered_cones(const float *records, float *cones, int blocks, double texel_radius)
{
    for (int b = 0; b < blocks; b++) {
        const float *rec = records + (size_t)b * COARSE_FIELDS * BLOCK_TEXELS;
        int n = 0;
        while (n < BLOCK_TEXELS && rec[FIELD_SOLID_ANGLE * BLOCK_TEXELS + n] > 0) n++;
        double d[BLOCK_TEXELS][3], c[3] = {0, 0, 0}, r = 0;
        for (int t = 0; t < n; t++) {
            for (int i = 0; i < 3; i++) d[t][i] = rec[(FIELD_MEAN + i) * BLOCK_TEXELS + t];
            ibl__normalize_d(d[t]);
            for (int i = 0; i < 3; i++) c[i] += d[t][i];
        }
        ibl__normalize_d(c);
        for (int t = 0; t < n; t++) {
            double a = acos(ibl__clampd(ibl__dot_d(c, d[t]), -1, 1));
            r = a > r ? a : r;
        }
        r += texel_radius + 1e-6;
        float *bc = cones + (size_t)b * CONE_FLOATS;
        for (int i = 0; i < 3; i++) bc[i] = (float)c[i];
        bc[3] = (float)r, bc[4] = (float)cos(r), bc[5] = (float)sin(r);
    }
}

/* The cones around each SUPER_CONE_BLOCKS consecutive cones of `count` (gathered in Morton
 * order, they are neighbours): around the mean of their centres, out to the farthest one's
 * edge. */
static void super_cones(const float *cones, int count, float *supers)
{
    for (int g = 0; g * SUPER_CONE_BLOCKS < count; g++) {
        int n = count - g * SUPER_CONE_BLOCKS < SUPER_CONE_BLOCKS ? count - g * SUPER_CONE_BLOCKS
                                                                  : SUPER_CONE_BLOCKS;
        const float *bc = cones + (size_t)g * SUPER_CONE_BLOCKS * CONE_FLOATS;
        double c[3] = {0, 0, 0}, r = 0;
        for (int k = 0; k < n; k++)
            for (int i = 0; i < 3; i++) c[i] += bc[k * CONE_FLOATS + i];
        double len = sqrt(ibl__dot_d(c, c));
        for (int i = 0; i < 3; i++) c[i] = len > 0 ? c[i] / len : (i == 0);
        for (int k = 0; k < n; k++) {
            const float *q = bc + k * CONE_FLOATS;
            double d = c[0] * q[0] + c[1] * q[1] + c[2] * q[2];
            double a = acos(ibl__clampd(d, -1, 1)) + q[3];
            r = a > r ? a : r;
        }
        r += 1e-6;
        float *o = supers + (size_t)g * CONE_FLOATS;
        for (int i = 0; i < 3; i++) o[i] = (float)c[i];
        o[3] = (float)r, o[4] = (float)cos(r), o[5] = (float)sin(r);
    }
}

/* Where the records of level s come from when the level has none (a streamed level,
 * ibl__fast_pyramid_streamed): each gathered texel is made again from the source, in the same
 * operations, into a block row of scratch; REMAKE_ROWS of them, one per task that remakes. */
enum { REMAKE_ROWS = 4 };
typedef struct texel_remake {
    const ibl_cubemap *src;
    int level;
    float *rows; /* REMAKE_ROWS rows of row_floats */
    size_t row_floats;
} texel_remake;

/* Fills lane dst (of a block of records, B floats a field) with the texel of key: its geometry,
 * its fields from s's records (or made again from the source: remake, into scratch row `row`)
 * and its power from field power_field. */
static void fill_texel(const ibl_specular_plan *p, const source_level *s, uint64_t key,
                       const texel_remake *remake, int row, int power_field, float *dst)
{
    const int B = BLOCK_TEXELS;
    size_t b;
    int t, f, x, y;
    float g[GEOMETRY_FIELDS];
    texel_of_key(s, key, &b, &t);
    block_texel(s, b, t, &f, &x, &y);
    level_texel_geometry(p->face_axis[f], p->face_sign[f], s, f, x, y, g);
    /* the texel's fields from GEOMETRY_FIELDS on, B floats apart */
    const float *rec = remake ? ibl__fast_streamed_texel(p, remake->src, remake->level, f, x, y,
                                                         remake->rows + (size_t)row * remake->row_floats)
                              : s->records + field_index(s, b, GEOMETRY_FIELDS, t);
    for (int field = 0; field < GEOMETRY_FIELDS; field++) dst[field * B] = g[field];
    for (int field = GEOMETRY_FIELDS; field < COARSE_FIELDS; field++)
        dst[field * B] = rec[(field - GEOMETRY_FIELDS) * B];
    for (int c = 0; c < 3; c++) dst[(FIELD_POWER + c) * B] = rec[(power_field + c - GEOMETRY_FIELDS) * B];
}

/* Lane by lane in key order (texel k in lane k), GATHER_KEYS a task (whole blocks) through
 * ibl_parallel_for: each key fills its own slot. Filled on the calling thread they were, at
 * 512, ~7 ms between loops, most of it faulting in the fresh pages of the correction pool.
 * Texels made again from the source are gathered in REMAKE_ROWS tasks, each with its own
 * scratch row (in one task they were 2 ms of the 1024 chain with the other thread waiting). */
enum { GATHER_KEYS = 64 * BLOCK_TEXELS };

typedef struct gather_job {
    const ibl_specular_plan *p;
    const source_level *s;
    const uint64_t *keys;
    int count, power_field, per_task;
    float *records;
    const texel_remake *remake;
} gather_job;

static void gather_task(void *arg, int index)
{
    const gather_job *j = arg;
    const int B = BLOCK_TEXELS;
    int k0 = index * j->per_task, k1 = j->count - k0 < j->per_task ? j->count : k0 + j->per_task;
    for (int k = k0; k < k1; k++)
        fill_texel(j->p, j->s, j->keys[k], j->remake, index % REMAKE_ROWS, j->power_field,
                   j->records + (size_t)(k / B) * COARSE_FIELDS * B + k % B);
}

/* Where the texels of `keys` (sorted) go, in key order, eight to a block; with span > 0 a texel
 * also starts a new block when it is on another face or more than `span` texels (either axis)
 * from its block's first texel, so that a block's cone stays small: a block of texels scattered
 * along the Morton curve has a cone as wide as their spread and is summed at every grid point
 * its cone reaches (the 128 level's corrections of cmft's exponent 862 had cones of 13 texels
 * on average, against a reach of 14). */
typedef struct lane_cursor {
    int span, blocks, fill, face, x, y; /* fill: texels in the last block; face, x, y: its first's */
} lane_cursor;

/* The lane (block x BLOCK_TEXELS + lane) of the next texel, the one of `key` in level s. */
static int next_lane(lane_cursor *c, const source_level *s, uint64_t key)
{
    size_t b;
    int t, f, x, y;
    texel_of_key(s, key, &b, &t);
    block_texel(s, b, t, &f, &x, &y);
    int open = c->blocks > 0 && c->fill < BLOCK_TEXELS;
    if (open && c->span > 0 && (f != c->face || abs(x - c->x) > c->span || abs(y - c->y) > c->span))
        open = 0;
    if (!open) c->blocks++, c->fill = 0, c->face = f, c->x = x, c->y = y;
    return (c->blocks - 1) * BLOCK_TEXELS + c->fill++;
}

/* The blocks that next_lane's spans give the sorted keys (on the calling thread: a lane depends
 * on every texel before it); a new block's lanes are emptied before they are filled. */
static int gather_spans(const ibl_specular_plan *p, const source_level *s, const uint64_t *keys,
                        int count, int span, int power_field, float *records,
                        const texel_remake *remake)
{
    const int B = BLOCK_TEXELS;
    lane_cursor cursor = {span, 0, 0, 0, 0, 0};
    for (int k = 0; k < count; k++) {
        int blocks_before = cursor.blocks, lane = next_lane(&cursor, s, keys[k]);
        float *block = records + (size_t)(lane / B) * COARSE_FIELDS * B;
        for (int i = cursor.blocks > blocks_before ? 0 : B; i < B; i++) { /* a new block: empty */
            for (int field = 0; field < COARSE_FIELDS; field++) block[field * B + i] = 0.0f;
            block[FIELD_LUM_SPREAD * B + i] = 0.5f;
        }
        fill_texel(p, s, keys[k], remake, 0, power_field, block + lane % B);
    }
    return cursor.blocks;
}

/* Gathers the `count` texels of `keys` in key order, eight to a block of records (a new block
 * also past `span` texels of a block's first, next_lane, unless that takes more than `capacity`
 * blocks; 0: no limit) with their power from field power_field, then their cones (one per
 * block, then one per SUPER_CONE_BLOCKS blocks after `capacity` cones); the number of blocks.
 * Unfilled lanes hold nothing: no power, no solid angle, beyond every piece. The records are
 * s's, or made again (remake, when s has none). */
static int gather_texels(const ibl_specular_plan *p, const source_level *s, uint64_t *keys,
                         int count, int span, int power_field, float **made_records, float *cones,
                         int capacity, const texel_remake *remake)
{
    const int B = BLOCK_TEXELS;
    qsort(keys, (size_t)count, sizeof *keys, key_order);
    int blocks = (count + B - 1) / B;
    if (span > 0) {
        lane_cursor trial = {span, 0, 0, 0, 0, 0};
        for (int k = 0; k < count; k++) next_lane(&trial, s, keys[k]);
        if (trial.blocks > capacity) span = 0;
        else blocks = trial.blocks;
    }
    /* NULL: a one-shot plan's corrections, made here as many as they are (a pool of every
     * piece's capacity, mostly never written, sat on pages other blocks had written and set
     * the 256 chain's peak RSS 6.5 MB higher in some runs) */
    if (!*made_records &&
        !(*made_records = ibl_alloc(p->ctx, ((size_t)blocks > 0 ? (size_t)blocks : 1) * COARSE_FIELDS * B * sizeof(float))))
        return -1;
    float *records = *made_records;
    if (span > 0) {
        blocks = gather_spans(p, s, keys, count, span, power_field, records, remake);
    } else {
        /* remade: one task a scratch row */
        int per_task = remake && count > 0 ? (count + REMAKE_ROWS - 1) / REMAKE_ROWS : GATHER_KEYS;
        gather_job job = {p, s, keys, count, power_field, per_task, records, remake};
        ibl_parallel_for(p->ctx, (count + per_task - 1) / per_task, gather_task, &job);
        for (int i = count; i < blocks * B; i++) { /* the rest of the last block: nothing */
            float *dst = records + (size_t)(i / B) * COARSE_FIELDS * B + i % B;
            for (int field = 0; field < COARSE_FIELDS; field++) dst[field * B] = 0.0f;
            dst[FIELD_LUM_SPREAD * B] = 0.5f;
        }
    }
    gathered_cones(records, cones, blocks, 1.5 / s->edge);
    super_cones(cones, blocks, cones + (size_t)capacity * CONE_FLOATS);
    return blocks;
}

/* ---- run time: picking the texels ---- */

/* select_bright's passes over a level's blocks, through ibl_parallel_for in at most
 * SCAN_TASKS tasks of whole blocks (on the calling thread they were ~1 ms of the 256 GGX
 * chain, between loops): counting the texels over the bar (integers, summed in task order),
 * then marking them, each task writing its keys after those of the tasks before it, so the
 * keys come in block order as one pass gives them. */
enum { SCAN_TASKS = 128, SCAN_MIN_BLOCKS = 256 /* ~2 us of counting: small levels run inline */ };

typedef struct bright_scan {
    source_level *s;
    double bar;
    size_t blocks, per_task;
    int count[SCAN_TASKS], first[SCAN_TASKS];
} bright_scan;

static void bright_count_task(void *arg, int index)
{
    bright_scan *j = arg;
    const source_level *s = j->s;
    const int B = BLOCK_TEXELS;
    size_t b0 = (size_t)index * j->per_task, b1 = b0 + j->per_task < j->blocks ? b0 + j->per_task : j->blocks;
    int count = 0;
    for (size_t b = b0; b < b1; b++) {
        const float *P = s->records + field_index(s, b, FIELD_POWER, 0);
        for (int t = 0; t < B; t++) count += luminance(P[t], P[B + t], P[2 * B + t]) > j->bar;
    }
    j->count[index] = count;
}

static void bright_mark_task(void *arg, int index)
{
    bright_scan *j = arg;
    source_level *s = j->s;
    const int B = BLOCK_TEXELS;
    size_t b0 = (size_t)index * j->per_task, b1 = b0 + j->per_task < j->blocks ? b0 + j->per_task : j->blocks;
    int k = j->first[index];
    for (size_t b = b0; b < b1; b++) {
        float *P = s->records + field_index(s, b, FIELD_POWER, 0); /* fields from it */
        for (int t = 0; t < B; t++) {
            int is_bright = luminance(P[t], P[B + t], P[2 * B + t]) > j->bar;
            for (int c = 0; c < 3; c++)
                P[(FIELD_POWER_NOT_BRIGHT - FIELD_POWER + c) * B + t] = is_bright ? 0.0f : P[c * B + t];
            if (is_bright) s->bright_keys[k++] = texel_key(s, b, t);
        }
    }
}

void ibl__fast_select_bright(ibl_specular_plan *p, int level)
{
    source_level *s = &p->pyramid[level];
    bright_scan j;
    j.s = s;
    j.blocks = source_block_count(s);
    j.per_task = (j.blocks + SCAN_TASKS - 1) / SCAN_TASKS;
    if (j.per_task < SCAN_MIN_BLOCKS) j.per_task = SCAN_MIN_BLOCKS;
    int tasks = (int)((j.blocks + j.per_task - 1) / j.per_task);
    j.bar = BRIGHT_BAR * accuracy_scale(p) * s->power / (4.0 * IBL_PI) * s->bright_scale;
    int count;
    for (;;) { /* raise the bar until the brightest fit (a bounded direct sum) */
        ibl_parallel_for(p->ctx, tasks, bright_count_task, &j);
        count = 0;
        for (int i = 0; i < tasks; i++) j.first[i] = count, count += j.count[i];
        if (count <= s->bright_capacity * BLOCK_TEXELS) break;
        j.bar *= 2.0;
    }
    ibl_parallel_for(p->ctx, tasks, bright_mark_task, &j);
    s->bright_block_count = gather_texels(p, s, s->bright_keys, count, 0, FIELD_POWER, &s->bright_records,
                                          s->bright_cones, s->bright_capacity, NULL);
}

typedef struct bound_job {
    const ibl_specular_plan *p;
    precomputed_piece *c;
} bound_job;

/* How far each texel of block b of level s can be from its uniform leaf, per unit of the
 * normaliser, in float, lane by lane, into c->texel_bound; lum: the block's fields from
 * FIELD_LUM_MEAN on (BLOCK_TEXELS floats apart), the geometric ones apart (a level may keep
 * them apart: level_texel_geometry). */
void ibl__fast_block_bounds(const ibl_specular_plan *p, const precomputed_piece *c,
                            const source_level *s, size_t b, const float *lum)
{
    const int B = BLOCK_TEXELS;
    const float a1 = (float)c->bound_mean, a2 = (float)c->bound_spread, a3 = (float)c->bound_covariance;
    const float l0 = (float)LUMINANCE_R, l1 = (float)LUMINANCE_G, l2 = (float)LUMINANCE_B;
    const float *pw = lum + (FIELD_POWER - FIELD_LUM_MEAN) * B;
    float *out = c->texel_bound + b * B;
    for (int t = 0; t < B; t++) {
        int f, x, y;
        float geo[GEOMETRY_FIELDS];
        block_texel(s, b, t, &f, &x, &y);
        level_texel_geometry(p->face_axis[f], p->face_sign[f], s, f, x, y, geo);
        float P = l0 * pw[t] + l1 * pw[B + t] + l2 * pw[2 * B + t];
        float dm = 0, dc = 0;
        for (int k = 0; k < 3; k++) {
            float d = lum[k * B + t] - geo[FIELD_MEAN + k];
            dm += d * d;
        }
        for (int k = 0; k < 6; k++) {
            float d = fabsf(lum[(FIELD_LUM_COVARIANCE - FIELD_LUM_MEAN + k) * B + t] -
                            geo[FIELD_COVARIANCE + k]);
            dc = d > dc ? d : dc;
        }
        float de = fabsf(lum[(FIELD_LUM_SPREAD - FIELD_LUM_MEAN) * B + t] - geo[FIELD_SPREAD]);
        out[t] = P > 0 ? P * (a1 * sqrtf(dm) + a2 * de + a3 * dc) : 0.0f;
    }
}

/* The bounds of BOUND_BLOCKS_PER_TASK blocks. */
static void bound_task(void *arg, int index)
{
    const bound_job *j = arg;
    const source_level *s = &j->p->pyramid[j->c->source_level];
    size_t b0 = (size_t)index * BOUND_BLOCKS_PER_TASK, b1 = b0 + BOUND_BLOCKS_PER_TASK;
    size_t blocks = source_block_count(s);
    for (size_t b = b0; b < b1 && b < blocks; b++)
        ibl__fast_block_bounds(j->p, j->c, s, b, s->records + field_index(s, b, FIELD_LUM_MEAN, 0));
}

/* select_corrections' passes over a level's texel bounds, in at most SCAN_TASKS tasks of
 * whole blocks (as select_bright's; on the calling thread they were ~3 ms of the 1024 chain,
 * between loops): counting the texels over BAR_STEPS bars at once (the bar and its doublings:
 * integers, summed in task order), then listing those over the threshold, each task writing
 * its keys after those of the tasks before it, so the keys come in block order as one pass
 * gives them. */
enum { BAR_STEPS = 8 };

typedef struct bound_scan {
    precomputed_piece *c;
    const source_level *s;
    size_t blocks, per_task;
    double bars[BAR_STEPS]; /* counting: each twice the one before */
    double threshold;       /* listing */
    int power_field, remade;
    uint64_t *keys;
    int count[SCAN_TASKS][BAR_STEPS], first[SCAN_TASKS];
} bound_scan;

static void bound_count_task(void *arg, int index)
{
    bound_scan *j = arg;
    size_t i0 = (size_t)index * j->per_task * BLOCK_TEXELS;
    size_t i1 = (index + 1) * j->per_task < j->blocks ? (index + 1) * j->per_task * BLOCK_TEXELS : j->blocks * BLOCK_TEXELS;
    int count[BAR_STEPS] = {0};
    for (size_t i = i0; i < i1; i++)
        for (int k = 0; k < BAR_STEPS && j->c->texel_bound[i] > j->bars[k]; k++) count[k]++;
    memcpy(j->count[index], count, sizeof count);
}

/* Whether texel t of block b is a correction: over the threshold, and (a level with records)
 * with some power in power_field. A streamed level's texels over the threshold have a positive
 * luminance power (P > 0 in bound_task), so never all three channels 0; it has no bright
 * texels, so power_field is FIELD_POWER. */
static int is_correction(const bound_scan *j, size_t b, int t)
{
    const int B = BLOCK_TEXELS;
    if (!(j->c->texel_bound[b * B + t] > j->threshold)) return 0;
    if (j->remade) return 1;
    const float *P = j->s->records + field_index(j->s, b, j->power_field, 0);
    return !(P[t] == 0 && P[B + t] == 0 && P[2 * B + t] == 0);
}

static void correction_count_task(void *arg, int index)
{
    bound_scan *j = arg;
    size_t b0 = (size_t)index * j->per_task, b1 = b0 + j->per_task < j->blocks ? b0 + j->per_task : j->blocks;
    int count = 0;
    for (size_t b = b0; b < b1; b++)
        for (int t = 0; t < BLOCK_TEXELS; t++) count += is_correction(j, b, t);
    j->count[index][0] = count;
}

static void correction_list_task(void *arg, int index)
{
    bound_scan *j = arg;
    size_t b0 = (size_t)index * j->per_task, b1 = b0 + j->per_task < j->blocks ? b0 + j->per_task : j->blocks;
    int k = j->first[index];
    for (size_t b = b0; b < b1; b++)
        for (int t = 0; t < BLOCK_TEXELS; t++)
            if (is_correction(j, b, t)) j->keys[k++] = texel_key(j->s, b, t);
}

/* Gathers each texel over the threshold with its luminance moments and its power from
 * power_field (FIELD_POWER, or FIELD_POWER_NOT_BRIGHT for a piece without bright texels):
 * summed as a leaf while the padded source leaves it out (products.c), it turns the texel's
 * uniform share into its moment leaf. */
static int gather_corrections(const ibl_specular_plan *p, bound_scan *j, int tasks,
                              const texel_remake *remake)
{
    precomputed_piece *c = j->c;
    ibl_parallel_for(p->ctx, tasks, correction_count_task, j);
    int k = 0;
    for (int i = 0; i < tasks; i++) j->first[i] = k, k += j->count[i][0];
    j->keys = c->correction_keys;
    ibl_parallel_for(p->ctx, tasks, correction_list_task, j);
    return gather_texels(p, j->s, c->correction_keys, k, c->gather_span, j->power_field, &c->correction_records,
                         c->correction_cones, c->correction_capacity, remake);
}

ibl_status ibl__fast_select_corrections(ibl_specular_plan *p, precomputed_piece *c,
                                        const ibl_cubemap *src)
{
    const source_level *s = &p->pyramid[c->source_level];
    size_t blocks = source_block_count(s);
    int power_field = c->without_bright ? FIELD_POWER_NOT_BRIGHT : FIELD_POWER;
    /* a streamed level's bounds were found as it was made */
    texel_remake remake = {src, c->source_level, NULL, 0};
    if (!s->records) {
        remake.row_floats = (size_t)6 * s->blocks_x * s->fields * BLOCK_TEXELS;
        remake.rows = ibl_calloc(p->ctx, REMAKE_ROWS * remake.row_floats, sizeof(float));
        if (!remake.rows) return ibl_context_status(p->ctx);
    } else {
        bound_job job = {p, c};
        ibl_parallel_for(p->ctx, (int)((blocks + BOUND_BLOCKS_PER_TASK - 1) / BOUND_BLOCKS_PER_TASK),
                         bound_task, &job);
    }
    bound_scan j;
    memset(&j, 0, sizeof j);
    j.c = c, j.s = s, j.blocks = blocks, j.power_field = power_field, j.remade = remake.rows != NULL;
    j.per_task = (blocks + SCAN_TASKS - 1) / SCAN_TASKS;
    if (j.per_task < SCAN_MIN_BLOCKS) j.per_task = SCAN_MIN_BLOCKS;
    int tasks = (int)((blocks + j.per_task - 1) / j.per_task);
    /* the first of the bar's doublings that at most `capacity` texels pass */
    double bar = CORRECTION_BAR * accuracy_scale(p) * s->power / (4.0 * IBL_PI);
    int capacity = c->correction_capacity * BLOCK_TEXELS, found = 0;
    while (!found) {
        for (int k = 0; k < BAR_STEPS; k++) j.bars[k] = k ? j.bars[k - 1] * 2.0 : bar;
        ibl_parallel_for(p->ctx, tasks, bound_count_task, &j);
        for (int k = 0; k < BAR_STEPS && !found; k++) {
            int count = 0;
            for (int i = 0; i < tasks; i++) count += j.count[i][k];
            if (count <= capacity) bar = j.bars[k], found = 1;
        }
        if (!found) bar = j.bars[BAR_STEPS - 1] * 2.0;
    }
    /* the padded source and the gathering compare the same floats */
    c->correction_threshold = (float)bar;
    j.threshold = c->correction_threshold;
    int gathered = gather_corrections(p, &j, tasks, remake.rows ? &remake : NULL);
    ibl_free(p->ctx, remake.rows);
    if (gathered < 0) return ibl_context_status(p->ctx);
    c->correction_block_count = gathered;
    return IBL_OK;
}
