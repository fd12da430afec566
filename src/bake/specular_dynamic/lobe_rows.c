/* The lobe operator of one output level: every output texel a row of weights over the texels
 * of one box mip of the source, each weight the lobe integrated over the texel and the row
 * normalised to sum 1 (so a constant cube stays constant). tri-Ace 2010 "Spherical Phong
 * kernel" sums the lobe over every texel of the source; here the lobe is cut where its mean
 * over a texel falls below the plan's floor, and the rows are computed for the
 * representatives of the cube's symmetries only (symmetry.c).
 *
 * Storage. A representative's row is a list of chunks: eight consecutive texels of one row of
 * one source face, with eight weights (zero past the end of a run). A symmetry carries a face
 * row onto a face row, or, when it swaps the face's axes, onto a face column, and it may
 * reverse the direction. So the products read two images of the mip, the faces and the faces
 * transposed (a carried column is a row of the transposed face), and every chunk keeps its
 * weights also reversed: any carried chunk is then eight consecutive floats of one image read
 * forward. Each output texel keeps one code per chunk (where its first lane is, and whether
 * the reversed weights apply); the weights are shared by the 48 rows of a representative.
 *
 * Weights: the lobe f(R.l) times the solid-angle element dsc dtc / (1 + sc^2 + tc^2)^(3/2)
 * of the face plane, by 2 x 2 Gauss-Legendre over the texel (error O(h^4): ~1e-4 of a weight
 * for the texels of 0.4-0.8 of the lobe's half width the plan picks), 4 x 4 when the texel is
 * wider than the lobe's half width, and 8 x 8 midpoints when the texel straddles the lobe's
 * horizon, where a Phong lobe of exponent below 1 has a kink a polynomial rule cannot see. */
#include "bake/specular_dynamic/dynamic_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>

/* where f falls to a fraction of its peak (f decreases with the angle; pi/2 if never) */
static double angle_where(const ibl__lobe *lobe, double value)
{
    double lo = 0.0, hi = 0.5 * IBL_PI;
    for (int i = 0; i < 60; i++) {
        double mid = 0.5 * (lo + hi);
        if (ibl__lobe_f(lobe, cos(mid)) > value) lo = mid;
        else hi = mid;
    }
    return hi;
}

/* f(R.l) dOmega at face-plane point (sc, tc), per unit of face-plane area */
static double lobe_density(const ibl__lobe *lobe, const double R[3], const dyn_face_frame *fr,
                           double sc, double tc)
{
    double d[3];
    for (int i = 0; i < 3; i++) d[i] = fr->m[i] + sc * fr->s[i] + tc * fr->t[i];
    double r2 = 1.0 + sc * sc + tc * tc, r = sqrt(r2);
    double c = (R[0] * d[0] + R[1] * d[1] + R[2] * d[2]) / r;
    return c > 0 ? ibl__lobe_f(lobe, c) / (r2 * r) : 0.0;
}

static const double gl2_node[2] = {-0.57735026918962576, 0.57735026918962576};
static const double gl2_weight[2] = {1.0, 1.0};
static const double gl4_node[4] = {-0.86113631159405258, -0.33998104358485626, 0.33998104358485626,
                                   0.86113631159405258};
static const double gl4_weight[4] = {0.34785484513745386, 0.65214515486254614, 0.65214515486254614,
                                     0.34785484513745386};

/* The lobe integrated over texel (x, y) of a face of edge M. */
static double texel_weight(const ibl__lobe *lobe, const double R[3], const dyn_face_frame *fr, int M,
                           int x, int y)
{
    double h = 2.0 / M, u0 = -1.0 + x * h, v0 = -1.0 + y * h;
    /* the horizon R.l = 0 crosses the texel: the corners' signs differ */
    int positive = 0;
    for (int k = 0; k < 4; k++) {
        double sc = u0 + (k & 1) * h, tc = v0 + (k >> 1) * h, d[3];
        for (int i = 0; i < 3; i++) d[i] = fr->m[i] + sc * fr->s[i] + tc * fr->t[i];
        positive += R[0] * d[0] + R[1] * d[1] + R[2] * d[2] > 0;
    }
    if (positive == 0) return 0.0;
    double sum = 0.0;
    if (positive < 4) {
        enum { K = 8 };
        for (int j = 0; j < K; j++)
            for (int i = 0; i < K; i++)
                sum += lobe_density(lobe, R, fr, u0 + (i + 0.5) * h / K, v0 + (j + 0.5) * h / K);
        return sum * (h / K) * (h / K);
    }
    int wide = h > lobe->half_angle;
    int k = wide ? 4 : 2;
    const double *node = wide ? gl4_node : gl2_node, *weight = wide ? gl4_weight : gl2_weight;
    double uc = u0 + 0.5 * h, vc = v0 + 0.5 * h;
    for (int j = 0; j < k; j++)
        for (int i = 0; i < k; i++)
            sum += weight[i] * weight[j] *
                   lobe_density(lobe, R, fr, uc + 0.5 * h * node[i], vc + 0.5 * h * node[j]);
    return sum * 0.25 * h * h;
}

/* One representative's row before packing: chunks (source face, face row, first texel) and
 * eight weights each. */
typedef struct rep_row {
    int chunks, capacity;
    int32_t *where; /* 3 per chunk: face, row, first texel */
    double *w;      /* 8 per chunk */
} rep_row;

typedef struct rows_job {
    ibl_context *ctx;
    const ibl_specular_desc *desc;
    const ibl__lobe *lobe;
    int n, M;
    double reach, reach_cos, floor_value;
    dyn_face_frame frames[6];
    double *centres; /* 6 M M x 3: texel centre directions of the mip (unit) */
    double *omega;   /* M M: texel solid angles */
    double *scratch; /* per task: M doubles of one face row's weights */
    rep_row *rows;
    ibl_status *status;
} rows_job;

static int grow(ibl_context *ctx, rep_row *r)
{
    int cap = r->capacity ? 2 * r->capacity : 64;
    int32_t *where = ibl_alloc(ctx, (size_t)cap * 3 * sizeof(int32_t));
    double *w = ibl_alloc(ctx, (size_t)cap * DYN_CHUNK * sizeof(double));
    if (!where || !w) {
        ibl_free(ctx, where);
        ibl_free(ctx, w);
        return 0;
    }
    if (r->chunks) {
        memcpy(where, r->where, (size_t)r->chunks * 3 * sizeof(int32_t));
        memcpy(w, r->w, (size_t)r->chunks * DYN_CHUNK * sizeof(double));
    }
    ibl_free(ctx, r->where);
    ibl_free(ctx, r->w);
    r->where = where, r->w = w, r->capacity = cap;
    return 1;
}

/* Appends the run [x0, x1) of face row (face, y) with its weights as chunks of eight. The
 * chunks start at multiples of eight (zero weights before the run): with the faces' edges
 * multiples of eight, every chunk any symmetry carries it to is then eight aligned floats
 * that never straddle a cache line (unaligned chunks were a third slower). */
static int add_run(ibl_context *ctx, rep_row *r, int face, int y, int x0, int x1, const double *w)
{
    for (int x = x0 - x0 % DYN_CHUNK; x < x1; x += DYN_CHUNK) {
        if (r->chunks == r->capacity && !grow(ctx, r)) return 0;
        int32_t *where = r->where + (size_t)r->chunks * 3;
        where[0] = face, where[1] = y, where[2] = x;
        double *cw = r->w + (size_t)r->chunks * DYN_CHUNK;
        for (int k = 0; k < DYN_CHUNK; k++) cw[k] = x + k >= x0 && x + k < x1 ? w[x + k] : 0.0;
        r->chunks++;
    }
    return 1;
}

static void rep_task(void *arg, int rep)
{
    rows_job *job = arg;
    int b = 0;
    while ((b + 1) * (b + 2) / 2 <= rep) b++;
    int a = rep - b * (b + 1) / 2, M = job->M;
    double R[3];
    ibl__output_direction(job->desc, job->lobe, 0, job->n, a, b, R);
    rep_row *row = &job->rows[rep];
    double *w = job->scratch + (size_t)rep * M;
    for (int f = 0; f < 6; f++) {
        /* faces beyond the reach: a face is within atan(sqrt(2)) of its centre */
        const double *m = job->frames[f].m;
        double cf = R[0] * m[0] + R[1] * m[1] + R[2] * m[2];
        if (acos(cf > 1 ? 1 : cf < -1 ? -1 : cf) > job->reach + atan(sqrt(2.0)) + 1e-6) continue;
        for (int y = 0; y < M; y++) {
            const double *c = job->centres + ((size_t)f * M + y) * M * 3;
            int run = -1;
            for (int x = 0; x <= M; x++) {
                int keep = 0;
                if (x < M && R[0] * c[3 * x] + R[1] * c[3 * x + 1] + R[2] * c[3 * x + 2] >= job->reach_cos) {
                    w[x] = texel_weight(job->lobe, R, &job->frames[f], M, x, y);
                    /* the lobe's mean over the texel above the floor */
                    keep = w[x] > job->floor_value * job->omega[(size_t)y * M + x];
                }
                if (keep && run < 0) run = x;
                if (!keep && run >= 0) {
                    if (!add_run(job->ctx, row, f, y, run, x, w)) {
                        job->status[rep] = IBL_ERR_OUT_OF_MEMORY;
                        return;
                    }
                    run = -1;
                }
            }
        }
    }
    double sum = 0;
    for (size_t i = 0; i < (size_t)row->chunks * DYN_CHUNK; i++) sum += row->w[i];
    for (size_t i = 0; i < (size_t)row->chunks * DYN_CHUNK; i++) row->w[i] = sum > 0 ? row->w[i] / sum : 0.0;
}

void ibl__dyn_lobe_level_destroy(ibl_context *ctx, dyn_lobe_level *l)
{
    ibl_free(ctx, l->rep_chunks);
    ibl_free(ctx, l->weight_memory);
    ibl_free(ctx, l->row_rep);
    ibl_free(ctx, l->row_codes);
    ibl_free(ctx, l->codes);
    memset(l, 0, sizeof *l);
}

/* Mip geometry the rows need: unit texel centres and texel solid angles. */
static ibl_status mip_geometry(ibl_context *ctx, rows_job *job)
{
    int M = job->M;
    job->centres = ibl_alloc(ctx, (size_t)6 * M * M * 3 * sizeof(double));
    job->omega = ibl_alloc(ctx, (size_t)M * M * sizeof(double));
    if (!job->centres || !job->omega) return ibl_context_status(ctx);
    for (int f = 0; f < 6; f++) {
        ibl__dyn_face_frame(f, &job->frames[f]);
        for (int y = 0; y < M; y++)
            for (int x = 0; x < M; x++) {
                double *c = job->centres + (((size_t)f * M + y) * M + x) * 3;
                ibl_cube_direction_d(f, (x + 0.5) / M, (y + 0.5) / M, c);
                double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
                for (int i = 0; i < 3; i++) c[i] /= len;
            }
    }
    for (int y = 0; y < M; y++)
        for (int x = 0; x < M; x++) job->omega[(size_t)y * M + x] = ibl_cube_texel_solid_angle(M, x, y);
    return IBL_OK;
}

/* The packed representatives: chunk offsets and the weights forward and reversed. */
static ibl_status pack_reps(ibl_context *ctx, const rep_row *rows, dyn_lobe_level *l)
{
    l->rep_chunks = ibl_alloc(ctx, ((size_t)l->reps + 1) * sizeof(uint32_t));
    if (!l->rep_chunks) return ibl_context_status(ctx);
    size_t total = 0;
    for (int r = 0; r < l->reps; r++) {
        l->rep_chunks[r] = (uint32_t)total;
        total += (size_t)rows[r].chunks;
    }
    l->rep_chunks[l->reps] = (uint32_t)total;
    size_t floats = (total ? total : 1) * DYN_CHUNK;
    /* both tables in one block, 32-byte aligned: a chunk's weights are one aligned vector */
    l->weight_memory = ibl_alloc(ctx, (2 * floats + 8) * sizeof(float));
    if (!l->weight_memory) return ibl_context_status(ctx);
    uintptr_t a = (uintptr_t)l->weight_memory;
    l->weights = l->weight_memory + ((32 - a % 32) % 32) / sizeof(float);
    l->reversed = l->weights + floats;
    for (int r = 0; r < l->reps; r++)
        for (int c = 0; c < rows[r].chunks; c++) {
            float *fw = l->weights + ((size_t)l->rep_chunks[r] + c) * DYN_CHUNK;
            float *rw = l->reversed + ((size_t)l->rep_chunks[r] + c) * DYN_CHUNK;
            for (int k = 0; k < DYN_CHUNK; k++) {
                fw[k] = (float)rows[r].w[(size_t)c * DYN_CHUNK + k];
                rw[DYN_CHUNK - 1 - k] = fw[k];
            }
        }
    return IBL_OK;
}

/* Every output texel's representative and chunk codes. */
static ibl_status pack_output_rows(ibl_context *ctx, const dyn_symmetries *sym, const rep_row *rows,
                                   int M, dyn_lobe_level *l, dyn_lobe_stats *stats)
{
    int n = l->edge;
    size_t count = (size_t)6 * n * n, plane = (size_t)6 * M * M, codes = 0;
    l->row_rep = ibl_alloc(ctx, count * sizeof(uint32_t));
    l->row_codes = ibl_alloc(ctx, (count + 1) * sizeof(uint32_t));
    if (!l->row_rep || !l->row_codes) return ibl_context_status(ctx);
    int *symmetry = ibl_alloc(ctx, count * sizeof(int));
    if (!symmetry) return ibl_context_status(ctx);
    for (int f = 0; f < 6; f++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                size_t i = ((size_t)f * n + y) * n + x;
                int a, b;
                ibl__dyn_fold(sym, n, f, x, y, &a, &b, &symmetry[i]);
                l->row_rep[i] = (uint32_t)ibl__dyn_rep_index(a, b);
                l->row_codes[i] = (uint32_t)codes;
                codes += (size_t)rows[l->row_rep[i]].chunks;
            }
    l->row_codes[count] = (uint32_t)codes;
    /* offsets are kept in 31 bits */
    if (codes > ((size_t)1 << 28) || 6 * plane + 2 * DYN_GUARD > ((size_t)1 << 30)) {
        ibl_free(ctx, symmetry);
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "specular plan: a dynamic level of %d from a mip of %d needs %zu chunk "
                         "codes; use the static plan for sizes this large", n, M, codes);
    }
    l->codes = ibl_alloc(ctx, (codes ? codes : 1) * sizeof(uint32_t));
    if (!l->codes) {
        ibl_free(ctx, symmetry);
        return ibl_context_status(ctx);
    }
    for (size_t i = 0; i < count; i++) {
        const rep_row *r = &rows[l->row_rep[i]];
        const dyn_face_map *maps = sym->map[symmetry[i]];
        uint32_t *out = l->codes + l->row_codes[i];
        for (int c = 0; c < r->chunks; c++) {
            const int32_t *where = r->where + (size_t)c * 3;
            const dyn_face_map *m = &maps[where[0]];
            int y = m->flip_y ? M - 1 - where[1] : where[1];
            int start = m->flip_x ? M - where[2] - DYN_CHUNK : where[2];
            size_t image = m->swap ? 3 * plane : 0;
            long offset = (long)DYN_GUARD + (long)image + ((long)m->target * M + y) * M + start;
            out[c] = (uint32_t)offset << 1 | m->flip_x;
        }
    }
    ibl_free(ctx, symmetry);
    if (stats) {
        stats->rep_chunks += l->rep_chunks[l->reps];
        stats->row_chunks += codes;
    }
    return IBL_OK;
}

ibl_status ibl__dyn_lobe_level_create(ibl_context *ctx, const ibl_specular_desc *desc,
                                      const ibl__lobe *lobe, const dyn_symmetries *sym, int n,
                                      int mip, int M, double floor_value, dyn_lobe_level *out,
                                      dyn_lobe_stats *stats)
{
    memset(out, 0, sizeof *out);
    out->edge = n;
    out->mip = mip;
    out->reps = ibl__dyn_rep_count(n);
    rows_job job;
    memset(&job, 0, sizeof job);
    job.ctx = ctx, job.desc = desc, job.lobe = lobe, job.n = n, job.M = M;
    job.floor_value = floor_value;
    /* texels whose centre is within the floor's angle plus a texel's half diagonal (at most
     * atan(sqrt(2) / M) at the face centre) */
    double reach = angle_where(lobe, floor_value) + atan(sqrt(2.0) / M) * 1.01;
    job.reach = reach;
    job.reach_cos = reach < IBL_PI ? cos(reach) : -1.0;
    ibl_status st = mip_geometry(ctx, &job);
    job.rows = ibl_calloc(ctx, (size_t)out->reps, sizeof(rep_row));
    job.status = ibl_calloc(ctx, (size_t)out->reps, sizeof(ibl_status));
    job.scratch = ibl_alloc(ctx, (size_t)out->reps * M * sizeof(double));
    if (st == IBL_OK && (!job.rows || !job.status || !job.scratch)) st = ibl_context_status(ctx);
    if (st == IBL_OK) ibl_parallel_for(ctx, out->reps, rep_task, &job);
    for (int r = 0; st == IBL_OK && r < out->reps; r++)
        if (job.status[r] != IBL_OK) st = ibl__fail(ctx, job.status[r], "specular plan: out of memory");
    if (st == IBL_OK) st = pack_reps(ctx, job.rows, out);
    if (st == IBL_OK) st = pack_output_rows(ctx, sym, job.rows, M, out, stats);
    if (st == IBL_OK && stats)
        for (int r = 0; r < out->reps; r++)
            for (size_t i = 0; i < (size_t)job.rows[r].chunks * DYN_CHUNK; i++)
                stats->taps += job.rows[r].w[i] > 0;
    for (int r = 0; job.rows && r < out->reps; r++) {
        ibl_free(ctx, job.rows[r].where);
        ibl_free(ctx, job.rows[r].w);
    }
    ibl_free(ctx, job.rows);
    ibl_free(ctx, job.status);
    ibl_free(ctx, job.scratch);
    ibl_free(ctx, job.centres);
    ibl_free(ctx, job.omega);
    if (st != IBL_OK) ibl__dyn_lobe_level_destroy(ctx, out);
    return st;
}
