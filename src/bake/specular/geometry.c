/* The geometry of the source cube, computed once per plan: the faces' frames and the signed
 * permutations between them, the unfolded border around a face, and the geometric moments of
 * every texel of every level of the pyramid.
 *
 * A texel's moments describe the directions l it covers: its solid angle Omega, the mean
 * direction m (|m| < 1), the covariance C of l, and e = (1 - |m|^2) / 2 = E|l - m|^2 / 2. They
 * are what the second-order leaf (leaf_sums.c) needs. A source texel's are integrated by 4 x 4
 * Gauss-Legendre on the face plane (weight 1 / r^3, the solid angle of the plane element), for
 * one eighth of face 0 only: the reflections s -> -s, t -> -t and s <-> t carry it to the rest of
 * the face, and the signed permutations between faces to the other faces (the same moments,
 * moved and negated). A coarser texel's come from its four children by the parallel-axis rule
 * (the moments of a union), in double. Each block of 4 x 2 texels also gets a bounding cone,
 * which the leaf sums test against a tile's reach. */
#include "bake/specular/fast_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

/* The signed permutation taking face-local (s, t, axis) coordinates to world coordinates on face
 * f: world[i] = sign[i] local[axis[i]] (the face basis is made of signed unit vectors). */
static void face_permutation(const ibl_specular_plan *p, int f, int axis[3], double sign[3])
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

void ibl__fast_face_frames(ibl_specular_plan *p)
{
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
        double sign[3];
        face_permutation(p, f, p->face_axis[f], sign);
        for (int i = 0; i < 3; i++) p->face_sign[f][i] = (float)sign[i];
    }
}

/* A cell (x, y) k texels beyond an edge of face f is the neighbour's texel k texels in from that
 * edge (the neighbour unfolded about the shared edge); cells beyond two edges (the border's
 * corner squares) have none (-1). */
int32_t ibl__fast_unfolded_texel(const ibl_specular_plan *p, int edge, int f, int x, int y)
{
    int S = edge, out_x = x < 0 || x >= S, out_y = y < 0 || y >= S;
    if (out_x && out_y) return -1;
    if (!out_x && !out_y) return (int32_t)(((size_t)f * S + y) * S + x);
    /* local (u, v) of the edge point, then the depth along -axis into the neighbour */
    double u, v, depth;
    if (out_x) {
        int k = x < 0 ? -1 - x : x - S;
        u = x < 0 ? -1.0 : 1.0, v = -1.0 + (2.0 * y + 1.0) / S, depth = (2.0 * k + 1.0) / S;
    } else {
        int k = y < 0 ? -1 - y : y - S;
        v = y < 0 ? -1.0 : 1.0, u = -1.0 + (2.0 * x + 1.0) / S, depth = (2.0 * k + 1.0) / S;
    }
    if (depth >= 2.0) return -1;
    const float(*B)[3] = p->face_basis[f];
    double d[3], s, t;
    for (int i = 0; i < 3; i++) d[i] = B[0][i] * (1.0 - depth) + B[1][i] * u + B[2][i] * v;
    int g = ibl_cube_face_st_d(d, &s, &t);
    int gx = ibl__clampi((int)floor(s * S), 0, S - 1), gy = ibl__clampi((int)floor(t * S), 0, S - 1);
    return (int32_t)(((size_t)g * S + gy) * S + gx);
}

/* Face-local moments of source texel (x, y) of a face of edge n, by 4 x 4 Gauss-Legendre on
 * the face plane. */
static void source_texel_moments(int n, int x, int y, texel_moments *g)
{
    static const double node[4] = {-0.861136311594052575, -0.339981043584856265,
                                   0.339981043584856265, 0.861136311594052575};
    static const double weight[4] = {0.347854845137453857, 0.652145154862546143,
                                     0.652145154862546143, 0.347854845137453857};
    double h = 2.0 / n, u0 = -1.0 + x * h, v0 = -1.0 + y * h;
    double l[16][3], w[16], W = 0, m[3] = {0, 0, 0};
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            double u = u0 + 0.5 * h * (1.0 + node[i]), v = v0 + 0.5 * h * (1.0 + node[j]);
            double r2 = 1.0 + u * u + v * v, r = sqrt(r2);
            int k = j * 4 + i;
            w[k] = weight[i] * weight[j] / (r2 * r);
            l[k][0] = u / r, l[k][1] = v / r, l[k][2] = 1.0 / r;
            W += w[k];
            for (int c = 0; c < 3; c++) m[c] += w[k] * l[k][c];
        }
    for (int c = 0; c < 3; c++) g->mean[c] = m[c] / W;
    memset(g->covariance, 0, sizeof g->covariance);
    double e = 0;
    for (int k = 0; k < 16; k++) {
        double d[3] = {l[k][0] - g->mean[0], l[k][1] - g->mean[1], l[k][2] - g->mean[2]};
        double ww = w[k] / W;
        double *C = g->covariance;
        C[0] += ww * d[0] * d[0], C[1] += ww * d[1] * d[1], C[2] += ww * d[2] * d[2];
        C[3] += ww * d[0] * d[1], C[4] += ww * d[0] * d[2], C[5] += ww * d[1] * d[2];
        e += ww * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }
    g->spread = 0.5 * e; /* 1 - |m|^2 = E |l - m|^2 for unit l */
    g->solid_angle = ibl_cube_texel_solid_angle(n, x, y);
}

void ibl__fast_combine_moments(const texel_moments *const *parts, const double *weights,
                               int count, texel_moments *out)
{
    double W = 0, m[3] = {0, 0, 0};
    for (int k = 0; k < count; k++) {
        W += weights[k];
        for (int c = 0; c < 3; c++) m[c] += weights[k] * parts[k]->mean[c];
    }
    memset(out, 0, sizeof *out);
    if (!(W > 0)) return;
    for (int c = 0; c < 3; c++) out->mean[c] = m[c] / W;
    for (int k = 0; k < count; k++) {
        const texel_moments *q = parts[k];
        double a = weights[k] / W;
        double d[3] = {q->mean[0] - out->mean[0], q->mean[1] - out->mean[1],
                       q->mean[2] - out->mean[2]};
        out->covariance[0] += a * (q->covariance[0] + d[0] * d[0]);
        out->covariance[1] += a * (q->covariance[1] + d[1] * d[1]);
        out->covariance[2] += a * (q->covariance[2] + d[2] * d[2]);
        out->covariance[3] += a * (q->covariance[3] + d[0] * d[1]);
        out->covariance[4] += a * (q->covariance[4] + d[0] * d[2]);
        out->covariance[5] += a * (q->covariance[5] + d[1] * d[2]);
        out->spread += a * (q->spread + 0.5 * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    }
}

void ibl__fast_level0_moments(const ibl_specular_plan *p, int f, int x, int y,
                              float out[GEOMETRY_FIELDS])
{
    float g[GEOMETRY_FIELDS];
    level0_face_moments(p, x, y, g);
    double mean[3], covariance[6];
    for (int c = 0; c < 3; c++) mean[c] = g[FIELD_MEAN + c];
    for (int c = 0; c < 6; c++) covariance[c] = g[FIELD_COVARIANCE + c];
    moments_to_world(p->face_axis[f], p->face_sign[f], mean, g[FIELD_SPREAD], covariance,
                     out + FIELD_MEAN, 1);
    out[FIELD_SOLID_ANGLE] = g[FIELD_SOLID_ANGLE];
}

/* ---- parallel tasks over one level ---- */

typedef struct moments_job {
    ibl_specular_plan *p;
    source_level *level;
    texel_moments *moments; /* the level's face-local moments, edge^2              */
    int edge;
    const texel_moments *finer; /* combine_task: the level below                   */
} moments_job;

/* Row b of one eighth of the face: texels (a, b), a <= b < ceil(n / 2). */
static void eighth_task(void *arg, int b)
{
    const moments_job *j = arg;
    for (int a = 0; a <= b; a++) source_texel_moments(j->edge, a, b, &j->moments[(size_t)b * j->edge + a]);
}

/* Row y of the face from its eighth: the reflections s -> -s, t -> -t and the swap s <-> t act
 * on the moments by sign flips and swaps. */
static void unfold_eighth_task(void *arg, int y)
{
    const moments_job *j = arg;
    int n = j->edge;
    for (int x = 0; x < n; x++) {
        int fx = x > n - 1 - x, fy = y > n - 1 - y;
        int a = fx ? n - 1 - x : x, b = fy ? n - 1 - y : y, swap = a > b;
        if (swap) {
            int t = a;
            a = b, b = t;
        }
        if (!fx && !fy && !swap) continue;
        texel_moments g = j->moments[(size_t)b * n + a];
        double *C = g.covariance, t;
        if (swap) { /* back from the eighth: swap s and t first */
            t = g.mean[0], g.mean[0] = g.mean[1], g.mean[1] = t;
            t = C[0], C[0] = C[1], C[1] = t;
            t = C[4], C[4] = C[5], C[5] = t;
        }
        if (fx) g.mean[0] = -g.mean[0], C[3] = -C[3], C[4] = -C[4];
        if (fy) g.mean[1] = -g.mean[1], C[3] = -C[3], C[5] = -C[5];
        j->moments[(size_t)y * n + x] = g;
    }
}

/* Row y of a level's moments from its children. */
static void combine_task(void *arg, int y)
{
    const moments_job *j = arg;
    int M = j->edge;
    for (int x = 0; x < M; x++) {
        const texel_moments *parts[4];
        double w[4];
        for (int k = 0; k < 4; k++) {
            parts[k] = &j->finer[(size_t)(2 * y + (k >> 1)) * (2 * M) + 2 * x + (k & 1)];
            w[k] = parts[k]->solid_angle;
        }
        texel_moments *out = &j->moments[(size_t)y * M + x];
        ibl__fast_combine_moments(parts, w, 4, out);
        out->solid_angle = w[0] + w[1] + w[2] + w[3];
    }
}

/* Row y of a coarse level's face-local geometric fields, as floats (the same on every face up
 * to the signed permutation, which level_texel_geometry applies). */
static void store_geometry_task(void *arg, int y)
{
    const moments_job *j = arg;
    for (int x = 0; x < j->edge; x++) {
        const texel_moments *g = &j->moments[(size_t)y * j->edge + x];
        float *o = j->level->geometry + ((size_t)y * j->edge + x) * GEOMETRY_FIELDS;
        for (int c = 0; c < 3; c++) o[FIELD_MEAN + c] = (float)g->mean[c];
        o[FIELD_SPREAD] = (float)g->spread;
        for (int c = 0; c < 6; c++) o[FIELD_COVARIANCE + c] = (float)g->covariance[c];
        o[FIELD_SOLID_ANGLE] = (float)g->solid_angle;
    }
}

/* Records are stored in blocks of BLOCK_H rows: a task takes a whole block row, so that two
 * threads never write the same cache lines. This one writes the geometric fields of every
 * face from the level's face-local floats (level_texel_geometry). */
static void store_records_task(void *arg, int block_row)
{
    const moments_job *j = arg;
    const ibl_specular_plan *p = j->p;
    source_level *s = j->level;
    for (int y = block_row * BLOCK_H; y < (block_row + 1) * BLOCK_H && y < s->edge; y++)
        for (int f = 0; f < 6; f++)
            for (int x = 0; x < s->edge; x++)
                face_local_to_world(p->face_axis[f], p->face_sign[f],
                                    s->geometry + ((size_t)y * s->edge + x) * GEOMETRY_FIELDS,
                                    s->records + record_index(s, f, x, y, 0), BLOCK_TEXELS);
}

/* Row b of the stored eighth of level 0's face-local moments (a <= b), as floats (what
 * records would hold; level0_face_moments reads them). */
static void store_level0_geometry_task(void *arg, int b)
{
    const moments_job *j = arg;
    for (int a = 0; a <= b; a++) {
        const texel_moments *g = &j->moments[(size_t)b * j->edge + a];
        float *o = j->p->level0_geometry + ((size_t)b * (b + 1) / 2 + a) * GEOMETRY_FIELDS;
        for (int c = 0; c < 3; c++) o[FIELD_MEAN + c] = (float)g->mean[c];
        o[FIELD_SPREAD] = (float)g->spread;
        for (int c = 0; c < 6; c++) o[FIELD_COVARIANCE + c] = (float)g->covariance[c];
        o[FIELD_SOLID_ANGLE] = (float)g->solid_angle;
    }
}

/* The bounding cones of block row `block_row` of every face: computed on face 0 and carried to
 * the others by the signed permutation between the faces. */
static void block_cones_task(void *arg, int block_row)
{
    const moments_job *j = arg;
    const ibl_specular_plan *p = j->p;
    source_level *s = j->level;
    int M = s->edge, by = block_row;
    double h = 2.0 / M;
    for (int bx = 0; bx < s->blocks_x; bx++) {
        int x1 = (bx + 1) * BLOCK_W < M ? (bx + 1) * BLOCK_W : M;
        int y1 = (by + 1) * BLOCK_H < M ? (by + 1) * BLOCK_H : M;
        double c[3], local[3];
        double r = ibl__rect_radius(0, bx * BLOCK_W * h - 1, by * BLOCK_H * h - 1, x1 * h - 1,
                                    y1 * h - 1, c);
        for (int i = 0; i < 3; i++) local[p->face_axis[0][i]] = p->face_sign[0][i] * c[i];
        for (int f = 0; f < 6; f++) {
            float *b = s->cones + (((size_t)f * s->blocks_y + by) * s->blocks_x + bx) * CONE_FLOATS;
            for (int i = 0; i < 3; i++) b[i] = (float)(p->face_sign[f][i] * local[p->face_axis[f][i]]);
            b[3] = (float)(r + 1e-6);
            b[4] = (float)cos(r + 1e-6);
            b[5] = (float)sin(r + 1e-6);
        }
    }
}

/* Level 0's geometric fields of one block row, from level0_geometry. */
static void store_level0_records_task(void *arg, int block_row)
{
    const ibl_specular_plan *p = arg;
    const source_level *s = &p->pyramid[0];
    for (int y = block_row * BLOCK_H; y < (block_row + 1) * BLOCK_H && y < s->edge; y++)
        for (int f = 0; f < 6; f++)
            for (int x = 0; x < s->edge; x++) {
                float v[GEOMETRY_FIELDS];
                ibl__fast_level0_moments(p, f, x, y, v);
                float *r = s->records + record_index(s, f, x, y, 0);
                for (int k = 0; k < GEOMETRY_FIELDS; k++) r[k * BLOCK_TEXELS] = v[k];
            }
}

/* Records of a level: zeroed when a face has fewer texels than a block (the lanes beyond the
 * face are never written); every other field of every texel is written before it is read. */
static float *allocate_records(ibl_context *ctx, const source_level *s)
{
    size_t floats = source_block_count(s) * s->fields * BLOCK_TEXELS;
    return s->edge % BLOCK_W || s->edge % BLOCK_H ? ibl_calloc(ctx, floats, sizeof(float))
                                                  : ibl_alloc(ctx, floats * sizeof(float));
}

ibl_status ibl__fast_level0_records(ibl_specular_plan *p)
{
    source_level *s = &p->pyramid[0];
    ibl_context *ctx = p->ctx;
    s->records = allocate_records(ctx, s);
    s->cones = ibl_alloc(ctx, source_block_count(s) * CONE_FLOATS * sizeof(float));
    if (!s->records || !s->cones) return ibl_context_status(ctx);
    ibl_parallel_for(ctx, s->blocks_y, store_level0_records_task, p);
    moments_job job = {p, s, NULL, s->edge, NULL};
    ibl_parallel_for(ctx, s->blocks_y, block_cones_task, &job);
    p->has_level0_records = 1;
    return IBL_OK;
}

/* Every level's edge and record layout (the pieces are placed by the edges alone). */
void ibl__fast_pyramid_edges(ibl_specular_plan *p)
{
    for (int l = 0; l < p->pyramid_levels; l++) {
        source_level *s = &p->pyramid[l];
        s->edge = (p->source_edge * p->subtexel_split) >> l;
        s->blocks_x = (s->edge + BLOCK_W - 1) / BLOCK_W;
        s->blocks_y = (s->edge + BLOCK_H - 1) / BLOCK_H;
        s->fields = l == 0 ? LEVEL0_FIELDS : COARSE_FIELDS;
    }
}

/* The face-local geometry of the stored coarse levels (their records come later, from
 * ibl__fast_kept_records, or for a one-shot plan's levels only the pyramid reads from
 * ibl__fast_run_records; level 0's from ibl__fast_level0_records, when some piece needs
 * them). */
static ibl_status allocate_pyramid(ibl_specular_plan *p)
{
    ibl_context *ctx = p->ctx;
    for (int l = p->first_stored; l < p->pyramid_levels; l++) {
        source_level *s = &p->pyramid[l];
        s->geometry = ibl_alloc(ctx, (size_t)s->edge * s->edge * GEOMETRY_FIELDS * sizeof(float));
        s->row_power = ibl_alloc(ctx, (size_t)6 * s->blocks_y * sizeof(double));
        if (!s->geometry || !s->row_power) return ibl_context_status(ctx);
    }
    return IBL_OK;
}

/* Whether a coarse level's records are read after the run's pyramid: by a piece summed leaf by
 * leaf (its normalisers too, at plan time) or by a mirror level of its edge (mirror.c). */
static int records_read_after_pyramid(const ibl_specular_plan *p, int level)
{
    for (int l = 0; l < p->output_levels; l++) {
        if (level_is_mirror(p, l)) {
            int n = ibl_level_size(p->output_edge, l);
            if (n < p->source_edge && is_power_of_two(n) && (p->pyramid[0].edge >> level) == n)
                return 1;
            continue;
        }
        for (int k = 0; k < p->levels[l].piece_count; k++)
            if (p->levels[l].pieces[k].source_level == level && !p->levels[l].pieces[k].precomputed)
                return 1;
    }
    return 0;
}

/* The records of a level, with their geometric fields from its face-local geometry unless
 * the level keeps those apart (first_field). */
static ibl_status materialise_records(ibl_specular_plan *p, int level)
{
    source_level *s = &p->pyramid[level];
    s->records = allocate_records(p->ctx, s);
    if (!s->records) return ibl_context_status(p->ctx);
    moments_job job = {p, s, NULL, s->edge, NULL};
    if (s->first_field == 0) ibl_parallel_for(p->ctx, s->blocks_y, store_records_task, &job);
    return IBL_OK;
}

ibl_status ibl__fast_kept_records(ibl_specular_plan *p)
{
    ibl_context *ctx = p->ctx;
    for (int l = p->first_stored; l < p->pyramid_levels; l++) {
        source_level *s = &p->pyramid[l];
        if (!records_read_after_pyramid(p, l)) {
            /* the pyramid reads the geometric fields from `geometry`: records without them,
             * made here for a reusable plan (a run allocates nothing), by the run for a
             * one-shot one */
            s->first_field = GEOMETRY_FIELDS;
            s->fields = COARSE_FIELDS - GEOMETRY_FIELDS;
            ibl_status st = p->one_shot ? IBL_OK : materialise_records(p, l);
            if (st != IBL_OK) return st;
            continue;
        }
        ibl_status st = materialise_records(p, l);
        if (st != IBL_OK) return st;
        s->cones = ibl_alloc(ctx, source_block_count(s) * CONE_FLOATS * sizeof(float));
        if (!s->cones) return ibl_context_status(ctx);
        moments_job job = {p, s, NULL, s->edge, NULL};
        ibl_parallel_for(ctx, s->blocks_y, block_cones_task, &job);
        ibl_free(ctx, s->geometry); /* the records hold it now */
        s->geometry = NULL;
    }
    return IBL_OK;
}

ibl_status ibl__fast_run_records(ibl_specular_plan *p, int level)
{
    return p->pyramid[level].records ? IBL_OK : materialise_records(p, level);
}

void ibl__fast_free_run_records(ibl_specular_plan *p, int level)
{
    source_level *s = &p->pyramid[level];
    if (!s->geometry) return; /* records the plan keeps */
    ibl_free(p->ctx, s->records);
    s->records = NULL;
}

ibl_status ibl__fast_build_moments(ibl_specular_plan *p)
{
    ibl_context *ctx = p->ctx;
    ibl_status st = allocate_pyramid(p);
    if (st != IBL_OK) return st;
    int S = p->source_edge * p->subtexel_split, half = S > 1 ? S / 2 : 1;
    /* what the plan keeps before the scratch it frees, so that the scratch leaves one hole
     * (an allocator that reuses freed blocks, as the CLI's, then fits larger buffers in it) */
    size_t eighth_rows = (size_t)(S + 1) / 2, eighth = eighth_rows * (eighth_rows + 1) / 2;
    p->level0_geometry = ibl_alloc(ctx, eighth * GEOMETRY_FIELDS * sizeof(float));
    texel_moments *cur = ibl_alloc(ctx, (size_t)S * S * sizeof(texel_moments));
    texel_moments *next = ibl_alloc(ctx, (size_t)half * half * sizeof(texel_moments));
    if (!cur || !next || !p->level0_geometry) {
        ibl_free(ctx, cur);
        ibl_free(ctx, next);
        return ibl_context_status(ctx);
    }
    moments_job first = {p, NULL, cur, S, NULL};
    ibl_parallel_for(ctx, (S + 1) / 2, eighth_task, &first);
    ibl_parallel_for(ctx, S, unfold_eighth_task, &first);
    for (int l = 0; l < p->pyramid_levels; l++) {
        source_level *s = &p->pyramid[l];
        if (l > 0) {
            moments_job cj = {p, s, next, s->edge, cur};
            ibl_parallel_for(ctx, s->edge, combine_task, &cj);
            texel_moments *t = cur;
            cur = next;
            next = t;
        }
        moments_job job = {p, s, cur, s->edge, NULL};
        if (l == 0) {
            ibl_parallel_for(ctx, (s->edge + 1) / 2, store_level0_geometry_task, &job);
            continue;
        }
        if (l < p->first_stored) continue; /* combined through, not kept */
        ibl_parallel_for(ctx, s->edge, store_geometry_task, &job);
    }
    ibl_free(ctx, cur);
    ibl_free(ctx, next);
    return IBL_OK;
}
