/* The radiance pyramid, rebuilt at every run: what the source's light adds to the geometric
 * moments of geometry.c.
 *
 * A source texel is uniform light, so its moments are the geometric ones and only its radiance
 * is new. A coarser texel carries its power per channel and the moments of its directions
 * weighted by the luminance of its children's power (the same parallel-axis rule as the
 * geometric moments): a sun inside a coarse texel then sits exactly at that texel's luminance
 * centroid, and the texel's spread is the spread of its light, not of its area. A texel without
 * light keeps its geometric moments. Levels read by precomputed pieces also get an image of
 * their texels as uniform light (power over solid angle), which the products copy into the
 * padded source. Each task takes whole block rows; the luminance power of each block row is
 * kept and summed in order, so the level's total does not depend on the threads. */
#include "bake/specular/fast_internal.h"

#include <string.h>

typedef struct pyramid_job {
    ibl_specular_plan *p;
    const ibl_cubemap *src;
    int level;
} pyramid_job;

/* Level 0's radiance (each sub-texel its source texel's), one block row of one face. */
static void level0_task(void *arg, int index)
{
    const pyramid_job *job = arg;
    source_level *s = &job->p->pyramid[0];
    int M = s->edge, K = job->p->subtexel_split;
    int f = index / s->blocks_y, block_row = index % s->blocks_y;
    for (int y = block_row * BLOCK_H; y < (block_row + 1) * BLOCK_H && y < M; y++) {
        const float *row = ibl_cubemap_face(job->src, 0, f) + (size_t)(y / K) * (M / K) * 4;
        for (int x = 0; x < M; x++)
            for (int c = 0; c < 3; c++)
                s->records[record_index(s, f, x, y, FIELD_RADIANCE + c)] = row[(x / K) * 4 + c];
    }
}

void ibl__fast_pyramid_level0(ibl_specular_plan *p, const ibl_cubemap *src)
{
    pyramid_job job = {p, src, 0};
    ibl_parallel_for(p->ctx, 6 * p->pyramid[0].blocks_y, level0_task, &job);
}

/* A source texel's power and luminance weight, its face-local moments g given. */
static double source_child_power(const ibl_specular_plan *p, const float *face, int cx, int cy,
                                 const float g[GEOMETRY_FIELDS], double power[3])
{
    const float *L = face + ((size_t)cy * p->pyramid[0].edge + cx) * 4;
    double om = g[FIELD_SOLID_ANGLE];
    for (int c = 0; c < 3; c++) power[c] = om * L[c];
    double lum = luminance(power[0], power[1], power[2]);
    return lum > 0 ? lum : 0;
}

/* Children whose face-local moments one texel of the first stored level keeps for its six faces
 * and two passes (K <= 8); beyond that each child is unfolded where it is read. */
enum { CACHED_CHILDREN = 64 };

/* Texel (x, y) of face f of the first stored level from its K x K source children (row by
 * row): their luminance-weighted moments by the parallel-axis rule, in face-local coordinates,
 * turned to face f's world coordinates once, into dst's records (the level's, or a view of
 * rows from row0 on). g holds the children's face-local moments (NULL: unfolded here). */
static void texel_from_source(const pyramid_job *job, const source_level *dst, int row0, int f,
                              int x, int y, const float (*g)[GEOMETRY_FIELDS])
{
    static const int pair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    const ibl_specular_plan *p = job->p;
    source_level *s = &job->p->pyramid[job->level];
    int K = 1 << job->level;
    const float *face = ibl_cubemap_face(job->src, 0, f);
    float own[GEOMETRY_FIELDS];
    double weight[CACHED_CHILDREN];
    double W = 0, m[3] = {0, 0, 0}, P[3] = {0, 0, 0}, pw[3];
    int child = 0;
    for (int cy = K * y; cy < K * (y + 1); cy++)
        for (int cx = K * x; cx < K * (x + 1); cx++, child++) {
            const float *gc = g ? g[child] : own;
            if (!g) level0_face_moments(p, cx, cy, own);
            double w = source_child_power(p, face, cx, cy, gc, pw);
            if (g) weight[child] = w;
            for (int c = 0; c < 3; c++) P[c] += pw[c];
            W += w;
            for (int c = 0; c < 3; c++) m[c] += w * gc[FIELD_MEAN + c];
        }
    float *o = dst->records + record_index(dst, f, x, y - row0, FIELD_LUM_MEAN); /* fields from it */
    if (W > 0) {
        double C[6] = {0, 0, 0, 0, 0, 0}, e = 0;
        for (int c = 0; c < 3; c++) m[c] /= W;
        child = 0;
        for (int cy = K * y; cy < K * (y + 1); cy++)
            for (int cx = K * x; cx < K * (x + 1); cx++, child++) {
                const float *gc = g ? g[child] : own;
                double a;
                if (g) {
                    a = weight[child] / W;
                } else {
                    level0_face_moments(p, cx, cy, own);
                    a = source_child_power(p, face, cx, cy, own, pw) / W;
                }
                double d[3] = {gc[FIELD_MEAN] - m[0], gc[FIELD_MEAN + 1] - m[1], gc[FIELD_MEAN + 2] - m[2]};
                for (int c = 0; c < 6; c++)
                    C[c] += a * (gc[FIELD_COVARIANCE + c] + d[pair[c][0]] * d[pair[c][1]]);
                e += a * (gc[FIELD_SPREAD] + 0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
            }
        moments_to_world(p->face_axis[f], p->face_sign[f], m, e, C, o, BLOCK_TEXELS);
    } else { /* no light: the geometric moments */
        level_texel_geometry(p->face_axis[f], p->face_sign[f], s, f, x, y, own);
        for (int k = 0; k < 10; k++) o[k * BLOCK_TEXELS] = own[FIELD_MEAN + k];
    }
    for (int c = 0; c < 3; c++) o[(FIELD_POWER - FIELD_LUM_MEAN + c) * BLOCK_TEXELS] = (float)P[c];
}

/* Row y of the first stored level, on all six faces, straight from the source texels (no
 * sub-texels): the K x K children of a texel are uniform texels whose geometric moments are
 * face 0's face-local ones, the same on every face (the levels between are read by nothing and
 * not kept). So each texel's children are unfolded from level 0's stored eighth once, for the
 * six faces and both passes: the unfolding's reads, scattered across the eighth where a child
 * lies beyond its diagonal, were most of the level's cost when each face made its own. */
static void level_row_from_source(const pyramid_job *job, const source_level *dst, int row0, int y)
{
    const ibl_specular_plan *p = job->p;
    int M = job->p->pyramid[job->level].edge, K = 1 << job->level;
    int cached = K * K <= CACHED_CHILDREN;
    float g[CACHED_CHILDREN][GEOMETRY_FIELDS];
    for (int x = 0; x < M; x++) {
        if (cached) {
            int child = 0;
            for (int cy = K * y; cy < K * (y + 1); cy++)
                for (int cx = K * x; cx < K * (x + 1); cx++) level0_face_moments(p, cx, cy, g[child++]);
        }
        for (int f = 0; f < 6; f++)
            texel_from_source(job, dst, row0, f, x, y, cached ? (const float(*)[GEOMETRY_FIELDS])g : NULL);
    }
}

/* The moments and power of one child texel (level 1 from level 0's records, else from the
 * level below's luminance moments). */
static void child_moments(const source_level *lo, int level, int f, int x, int y, texel_moments *g,
                          double power[3])
{
    const int B = BLOCK_TEXELS;
    if (level == 1) {
        const float *q = lo->records + record_index(lo, f, x, y, 0);
        double om = q[FIELD_SOLID_ANGLE * B];
        for (int c = 0; c < 3; c++) power[c] = om * q[(FIELD_RADIANCE + c) * B];
        for (int c = 0; c < 3; c++) g->mean[c] = q[(FIELD_MEAN + c) * B];
        g->spread = q[FIELD_SPREAD * B];
        for (int c = 0; c < 6; c++) g->covariance[c] = q[(FIELD_COVARIANCE + c) * B];
    } else { /* fields from FIELD_LUM_MEAN on (a level may keep its geometry apart) */
        const float *q = lo->records + record_index(lo, f, x, y, FIELD_LUM_MEAN);
        for (int c = 0; c < 3; c++) power[c] = q[(FIELD_POWER - FIELD_LUM_MEAN + c) * B];
        for (int c = 0; c < 3; c++) g->mean[c] = q[c * B];
        g->spread = q[(FIELD_LUM_SPREAD - FIELD_LUM_MEAN) * B];
        for (int c = 0; c < 6; c++) g->covariance[c] = q[(FIELD_LUM_COVARIANCE - FIELD_LUM_MEAN + c) * B];
    }
}

/* Row y of face f of a coarse level from the records of the level below, lo (that level's, or a
 * view of its rows from lo_row0 on). */
static void level_row(const pyramid_job *job, const source_level *lo, int lo_row0, int f, int y)
{
    const ibl_specular_plan *p = job->p;
    source_level *s = &job->p->pyramid[job->level];
    const int B = BLOCK_TEXELS;
    for (int x = 0; x < s->edge; x++) {
        texel_moments parts[4], out;
        const texel_moments *pp[4];
        double w[4], P[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++) {
            double pw[3];
            child_moments(lo, job->level, f, 2 * x + (k & 1), 2 * y + (k >> 1) - lo_row0, &parts[k], pw);
            w[k] = luminance(pw[0], pw[1], pw[2]);
            if (!(w[k] > 0)) w[k] = 0;
            for (int c = 0; c < 3; c++) P[c] += pw[c];
            pp[k] = &parts[k];
        }
        float *o = s->records + record_index(s, f, x, y, FIELD_LUM_MEAN); /* fields from it */
        if (w[0] + w[1] + w[2] + w[3] > 0) {
            ibl__fast_combine_moments(pp, w, 4, &out);
        } else { /* no light: the geometric moments */
            float g[GEOMETRY_FIELDS];
            level_texel_geometry(p->face_axis[f], p->face_sign[f], s, f, x, y, g);
            for (int c = 0; c < 3; c++) out.mean[c] = g[FIELD_MEAN + c];
            out.spread = g[FIELD_SPREAD];
            for (int c = 0; c < 6; c++) out.covariance[c] = g[FIELD_COVARIANCE + c];
        }
        for (int c = 0; c < 3; c++) o[c * B] = (float)out.mean[c];
        o[(FIELD_LUM_SPREAD - FIELD_LUM_MEAN) * B] = (float)out.spread;
        for (int c = 0; c < 6; c++)
            o[(FIELD_LUM_COVARIANCE - FIELD_LUM_MEAN + c) * B] = (float)out.covariance[c];
        for (int c = 0; c < 3; c++) o[(FIELD_POWER - FIELD_LUM_MEAN + c) * B] = (float)P[c];
    }
}

/* The luminance power of block row `block_row` of face f of a coarse level. */
static double block_row_power(const source_level *s, int f, int block_row)
{
    double power = 0;
    for (int bx = 0; bx < s->blocks_x; bx++) {
        const float *P = s->records +
                         field_index(s, ((size_t)f * s->blocks_y + block_row) * s->blocks_x + bx, FIELD_POWER, 0);
        for (int t = 0; t < BLOCK_TEXELS; t++)
            power += luminance(P[t], P[BLOCK_TEXELS + t], P[2 * BLOCK_TEXELS + t]);
    }
    return power;
}

/* One block row of one face of a coarse level, and its luminance power. */
static void level_task(void *arg, int index)
{
    const pyramid_job *job = arg;
    source_level *s = &job->p->pyramid[job->level];
    int f = index / s->blocks_y, block_row = index % s->blocks_y;
    const source_level *lo = &job->p->pyramid[job->level - 1];
    for (int y = block_row * BLOCK_H; y < (block_row + 1) * BLOCK_H && y < s->edge; y++)
        level_row(job, lo, 0, f, y);
    s->row_power[index] = block_row_power(s, f, block_row);
}

/* One block row of the first stored level made from the source, on all six faces, and the
 * luminance power of each face's. */
static void level_from_source_task(void *arg, int block_row)
{
    const pyramid_job *job = arg;
    source_level *s = &job->p->pyramid[job->level];
    for (int y = block_row * BLOCK_H; y < (block_row + 1) * BLOCK_H && y < s->edge; y++)
        level_row_from_source(job, s, 0, y);
    for (int f = 0; f < 6; f++) s->row_power[f * s->blocks_y + block_row] = block_row_power(s, f, block_row);
}

void ibl__fast_pyramid_level(ibl_specular_plan *p, const ibl_cubemap *src, int level)
{
    source_level *s = &p->pyramid[level];
    pyramid_job job = {p, src, level};
    /* the first stored level: from the source, unless it is level 1 over level 0's records */
    if (level == p->first_stored && (level > 1 || !p->has_level0_records))
        ibl_parallel_for(p->ctx, s->blocks_y, level_from_source_task, &job);
    else
        ibl_parallel_for(p->ctx, 6 * s->blocks_y, level_task, &job);
    s->power = 0;
    for (int i = 0; i < 6 * s->blocks_y; i++) s->power += s->row_power[i];
}

/* Row y of face f of level s's uniform images, from the records of `recs` (s's, or a view of
 * its rows from row0 on). */
static void uniform_row(const source_level *s, const source_level *recs, int row0, int f, int y)
{
    int M = s->edge;
    for (int x = 0; x < M; x++) {
        /* fields from FIELD_POWER on */
        const float *rec = recs->records + record_index(recs, f, x, y - row0, FIELD_POWER);
        float om = s->first_field ? s->geometry[((size_t)y * M + x) * GEOMETRY_FIELDS + FIELD_SOLID_ANGLE]
                                  : s->records[record_index(s, f, x, y, FIELD_SOLID_ANGLE)];
        float inv = om > 0 ? 1.0f / om : 0.0f;
        size_t o = (((size_t)f * M + y) * M + x) * UNIFORM_CHANNELS;
        if (s->uniform)
            for (int c = 0; c < 3; c++) s->uniform[o + c] = rec[c * BLOCK_TEXELS] * inv;
        if (s->uniform_not_bright)
            for (int c = 0; c < 3; c++)
                s->uniform_not_bright[o + c] = rec[(FIELD_POWER_NOT_BRIGHT - FIELD_POWER + c) * BLOCK_TEXELS] * inv;
    }
}

/* Row `index` (face edge + y) of the level's uniform images. */
static void uniform_task(void *arg, int index)
{
    const pyramid_job *job = arg;
    const source_level *s = &job->p->pyramid[job->level];
    uniform_row(s, s, 0, index / s->edge, index % s->edge);
}

void ibl__fast_uniform_level(ibl_specular_plan *p, int level)
{
    const source_level *s = &p->pyramid[level];
    if (!s->uniform && !s->uniform_not_bright) return;
    pyramid_job job = {p, NULL, level};
    ibl_parallel_for(p->ctx, 6 * s->edge, uniform_task, &job);
}

/* ---- the first stored level, streamed ---- */

/* A one-shot plan's first stored level, when only the pyramid reads its records, made a block
 * row at a time into scratch: each block row gives the level's uniform rows, its luminance
 * power, the centroid-correction bounds of the precomputed pieces over it and the next level's
 * row of texels (whose four children are that block row's), so the level's records are never
 * held whole (100 MB at the 512 level of a 1024 source, the largest block of the 1024 chain's
 * peak). The centroid corrections then make their few gathered texels again from the source
 * (ibl__fast_streamed_texel). Every texel goes through the same operations as in the level's
 * records, so the results are the same bits. Not for a level with bright texels (their
 * selection reads the whole level) or an image without them. */
int ibl__fast_pyramid_streams(const ibl_specular_plan *p, int level)
{
    const source_level *s = &p->pyramid[level];
    if (!p->one_shot || level != p->first_stored || level + 1 >= p->pyramid_levels) return 0;
    if (level == 1 && p->has_level0_records) return 0; /* made from level 0's records */
    if (s->records || !s->geometry || s->first_field != GEOMETRY_FIELDS) return 0;
    if (s->bright_scale > 0 || s->uniform_not_bright || s->edge % BLOCK_W || s->edge % BLOCK_H) return 0;
    for (int l = 0; l < p->output_levels; l++)
        for (int k = 0; k < p->levels[l].piece_count; k++) {
            const precomputed_piece *c = p->levels[l].pieces[k].precomputed;
            if (c && c->source_level == level && c->without_bright) return 0;
        }
    return 1;
}

/* Block rows made per parallel-for, each into its own scratch. */
enum { STREAM_BLOCK_ROWS = 16 };

typedef struct stream_job {
    pyramid_job level, next; /* the streamed level and the one made from it */
    float *scratch;          /* STREAM_BLOCK_ROWS block rows of six faces' records */
    int first_block_row;
    int bounded_count;       /* the precomputed pieces with correction bounds over the level */
    precomputed_piece *bounded[IBL_MAX_LEVELS * MAX_PIECES];
} stream_job;

/* A view of `row`, one block row of six faces' records of level s, as records of rows from
 * 2 block_row on; its geometric fields stay in s->geometry, read with the level's own rows. */
static source_level block_row_view(const source_level *s, float *row)
{
    source_level v = *s;
    v.records = row;
    v.blocks_y = 1;
    return v;
}

static void streamed_task(void *arg, int index)
{
    const stream_job *j = arg;
    const ibl_specular_plan *p = j->level.p;
    source_level *s = &j->level.p->pyramid[j->level.level];
    int block_row = j->first_block_row + index, row0 = block_row * BLOCK_H;
    size_t row_floats = (size_t)6 * s->blocks_x * s->fields * BLOCK_TEXELS;
    source_level v = block_row_view(s, j->scratch + (size_t)index * row_floats);
    for (int y = row0; y < row0 + BLOCK_H; y++) level_row_from_source(&j->level, &v, row0, y);
    for (int f = 0; f < 6; f++) s->row_power[f * s->blocks_y + block_row] = block_row_power(&v, f, 0);
    for (int f = 0; s->uniform && f < 6; f++)
        for (int y = row0; y < row0 + BLOCK_H; y++) uniform_row(s, &v, row0, f, y);
    for (int k = 0; k < j->bounded_count; k++)
        for (int f = 0; f < 6; f++)
            for (int bx = 0; bx < s->blocks_x; bx++) {
                size_t b = ((size_t)f * s->blocks_y + block_row) * s->blocks_x + bx;
                const float *lum = v.records + field_index(&v, (size_t)f * s->blocks_x + bx, FIELD_LUM_MEAN, 0);
                ibl__fast_block_bounds(p, j->bounded[k], s, b, lum);
            }
    for (int f = 0; f < 6; f++) level_row(&j->next, &v, row0, f, block_row);
}

ibl_status ibl__fast_pyramid_streamed(ibl_specular_plan *p, const ibl_cubemap *src, int level)
{
    source_level *s = &p->pyramid[level], *n = &p->pyramid[level + 1];
    stream_job job = {{p, src, level}, {p, src, level + 1}, NULL, 0, 0, {NULL}};
    for (int l = 0; l < p->output_levels; l++)
        for (int k = 0; k < p->levels[l].piece_count; k++) {
            precomputed_piece *c = p->levels[l].pieces[k].precomputed;
            if (c && c->source_level == level && c->correction_capacity > 0)
                job.bounded[job.bounded_count++] = c;
        }
    size_t row_floats = (size_t)6 * s->blocks_x * s->fields * BLOCK_TEXELS;
    job.scratch = ibl_alloc(p->ctx, STREAM_BLOCK_ROWS * row_floats * sizeof(float));
    if (!job.scratch) return ibl_context_status(p->ctx);
    for (int first = 0; first < s->blocks_y; first += STREAM_BLOCK_ROWS) {
        job.first_block_row = first;
        int rows = s->blocks_y - first < STREAM_BLOCK_ROWS ? s->blocks_y - first : STREAM_BLOCK_ROWS;
        ibl_parallel_for(p->ctx, rows, streamed_task, &job);
    }
    ibl_free(p->ctx, job.scratch);
    s->power = 0;
    for (int i = 0; i < 6 * s->blocks_y; i++) s->power += s->row_power[i];
    /* each block row of the next level is made by two streamed ones: its power once all are */
    for (int i = 0; i < 6 * n->blocks_y; i++)
        n->row_power[i] = block_row_power(n, i / n->blocks_y, i % n->blocks_y);
    n->power = 0;
    for (int i = 0; i < 6 * n->blocks_y; i++) n->power += n->row_power[i];
    return IBL_OK;
}

const float *ibl__fast_streamed_texel(const ibl_specular_plan *p, const ibl_cubemap *src, int level,
                                      int f, int x, int y, float *row)
{
    const source_level *s = &p->pyramid[level];
    pyramid_job job = {(ibl_specular_plan *)p, src, level};
    source_level v = block_row_view(s, row);
    int row0 = y - y % BLOCK_H;
    texel_from_source(&job, &v, row0, f, x, y, NULL);
    return v.records + record_index(&v, f, x, y - row0, GEOMETRY_FIELDS);
}
