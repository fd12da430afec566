/* Precomputed pieces, run time: the product of each base texel's weights (precomputed.c) with
 * the padded source, for every image of the base texel under the cube's symmetries.
 *
 * A run builds, face by face, the padded source (the face and a border unfolded from its four
 * neighbours, three planes r, g, b) and its transpose, which stay in cache (2 x 3 planes of
 * padded_edge^2), and applies every base texel's weights to the four flips of the face: face f's
 * padded cells are face 0's carried by the signed permutation between the faces (face_carry),
 * so one set of rows serves all six faces. A base below the quadrant's diagonal reads its
 * mirror's weights on the transposed source with its flips swapped. A level-0 piece reads the
 * source texels; a coarse one reads the level's texels as uniform light, with the texels that
 * get a centroid correction left out (gathering.c sums them as leaves), unless the corrections
 * are in difference form (moment leaf minus uniform leaf, on a coarser grid).
 *
 * A one-shot plan whose piece's weights would take more memory than the six padded faces makes
 * the six first and the weights a batch of base rows at a time (products_batched): a base row's
 * task applies its bases and their mirrors, so a batch needs only its own rows' weights. */
#include "bake/specular/fast_internal.h"
#include "core/context_internal.h"

#include <stdatomic.h>

typedef struct product_job {
    ibl_specular_plan *p;
    const precomputed_piece *c;
    const ibl_cubemap *src;
    float *sums;    /* the numerators of the piece's grid */
    int face;       /* the face being summed */
    /* the padded sources (and transposes) of faces 0-5, 6 padded_edge^2 floats apart, or of
     * j->face alone (p->padded_source, every face in turn) */
    float *padded;
    int all_faces;
    /* the weights and their vectors' cells at hand: from base weight_origin on */
    const uint16_t *weights, *cells;
    size_t weight_origin;
    int first_row, rows; /* the loop's base rows: first_row .. first_row + rows - 1 */
    /* whole-face tasks: face_slots padded buffers of 6 padded_edge^2 floats or more, and which
     * of them a running face holds (outside the job, which each face copies) */
    int face_slots;
    float *const *slot_padded;
    atomic_int *slot_busy;
} product_job;

/* Face f's padded source (3 planes), then its transpose (3 more). */
static float *face_padded(const product_job *j, int f)
{
    return j->all_faces ? j->padded + (size_t)f * 6 * j->c->padded_edge * j->c->padded_edge : j->padded;
}

/* Row `row` of face j->face's padded source. */
static void padded_row_task(void *arg, int row)
{
    const product_job *j = arg;
    const precomputed_piece *c = j->c;
    int f = j->face, S = c->source_edge, shift = 0;
    while ((1 << shift) < S) shift++;
    size_t plane = (size_t)c->padded_edge * c->padded_edge;
    const int32_t *cells = c->cell_texel + (size_t)row * c->padded_edge;
    float *out = face_padded(j, f) + (size_t)row * c->padded_edge;
    const source_level *s = &j->p->pyramid[c->source_level];
    /* level 0: the source texels; a coarse level: its texels as uniform light, those with a
     * centroid correction left out (their moment leaves are summed instead) */
    const float *face[6];
    const float *uniform = c->without_bright ? s->uniform_not_bright : s->uniform;
    int n = c->source_level == 0 ? 4 : UNIFORM_CHANNELS; /* floats a texel */
    for (int g = 0; g < 6; g++)
        face[g] = c->source_level == 0 ? ibl_cubemap_face(j->src, 0, g) : uniform + (size_t)g * S * S * n;
    int corrected = c->source_level > 0 && c->correction_block_count > 0 && !c->correction_difference;
    /* inside the face itself the padded source is the face: copied by rows */
    int y = row - c->origin, inside = y >= 0 && y < S;
    if (inside) {
        const float *v = face[f] + (size_t)y * S * n;
        float *o = out + c->origin;
        for (int x = 0; x < S; x++) o[x] = v[n * x], o[plane + x] = v[n * x + 1], o[2 * plane + x] = v[n * x + 2];
        for (int x = 0; corrected && x < S; x++)
            if (texel_corrected(c, s, f, x, y)) o[x] = o[plane + x] = o[2 * plane + x] = 0.0f;
    }
    for (int X = 0; X < c->padded_edge; X++) {
        if (inside && X == c->origin) X += S;
        if (X >= c->padded_edge) break;
        int32_t t0 = cells[X];
        if (t0 < 0) {
            out[X] = out[plane + X] = out[2 * plane + X] = 0.0f;
            continue;
        }
        /* face 0's texel carried to face f by the permutation between the faces (S is a power
         * of two: shifts) */
        int g0 = t0 >> (2 * shift), y0 = (t0 >> shift) & (S - 1), x0 = t0 & (S - 1);
        const int *m = c->face_carry[f][g0];
        int g = m[0], x = m[1] + m[2] * x0 + m[3] * y0, yy = m[4] + m[5] * x0 + m[6] * y0;
        if (corrected && texel_corrected(c, s, g, x, yy)) {
            out[X] = out[plane + X] = out[2 * plane + X] = 0.0f;
            continue;
        }
        const float *v = face[g] + ((size_t)yy * S + x) * n;
        out[X] = v[0], out[plane + X] = v[1], out[2 * plane + X] = v[2];
    }
}

/* TRANSPOSE_ROWS rows of the transposed padded source (after the padded source): T[y][x] =
 * padded[x][y], plane by plane. */
static void transpose_task(void *arg, int index)
{
    const product_job *j = arg;
    int P = j->c->padded_edge, y0 = index * TRANSPOSE_ROWS;
    int y1 = y0 + TRANSPOSE_ROWS < P ? y0 + TRANSPOSE_ROWS : P;
    size_t plane = (size_t)P * P;
    for (int ch = 0; ch < 3; ch++) {
        const float *in = face_padded(j, j->face) + ch * plane;
        float *out = face_padded(j, j->face) + (3 + ch) * plane;
        for (int X = 0; X < P; X++)
            for (int Y = y0; Y < y1; Y++) out[(size_t)Y * P + X] = in[(size_t)X * P + Y];
    }
}

/* One base's product with one image, added to the grid point it stands for: (x, y) of face
 * j->face, through the base's weights on the padded source flipped by flip_x / flip_y
 * (transposed: the source's transpose). */
static void product_at(const product_job *j, int face, size_t base, int transposed, int flip_x,
                       int flip_y, int x, int y)
{
    const precomputed_piece *c = j->c;
    size_t plane = (size_t)c->padded_edge * c->padded_edge, first = c->first_weight[base] - j->weight_origin;
    const float *planes = face_padded(j, face) + (transposed ? 3 * plane : 0);
    double s[3];
    j->p->kernels->product(c, base, j->weights + first, j->cells + 2 * (first / 8), planes, flip_x, flip_y, s);
    float *o = j->sums + (((size_t)face * c->grid_edge + y) * c->grid_edge + x) * 4;
    for (int ch = 0; ch < 3; ch++) o[ch] = (float)(o[ch] + s[ch]);
}

/* Row b of base texels (a, b), a <= b, into the images of face `face`: each base's own four
 * flips at (a, b), and for a < b its mirror's at (b, a) (the reflection x <-> y: the same
 * weights on the transposed source, flips swapped), so that a row needs the weights of its own
 * bases only. Row b holds 2b + 1 products, so the loop takes its rows from the last: the
 * longest go first and each thread ends on a short one. Image by image, so that the source rows
 * under the row's windows stay in L1 while the row's weights stream from L2 (base by base,
 * every base re-read its windows from L2: measured 1.6x slower). Every grid point gets one
 * product, as from any order. */
static void product_row(const product_job *j, int face, int b)
{
    int n = j->c->grid_edge, nb = j->c->base_edge;
    for (int fy = 0; fy < 2; fy++)
        for (int fx = 0; fx < 2; fx++) {
            int y = fy ? n - 1 - b : b;
            if (!(fy && y == b))
                for (int a = 0; a <= b; a++) {
                    int x = fx ? n - 1 - a : a;
                    if (!(fx && x == a)) product_at(j, face, (size_t)b * nb + a, 0, fx, fy, x, y);
                }
            /* the mirrors: base (b, a) below the diagonal, at x from b (flip fx), y from a (fy) */
            int x = fx ? n - 1 - b : b;
            if (!(fx && x == b))
                for (int a = 0; a < b; a++) {
                    int ym = fy ? n - 1 - a : a;
                    if (!(fy && ym == a)) product_at(j, face, (size_t)b * nb + a, 1, fy, fx, x, ym);
                }
        }
}

/* The loop's base rows from the last, on face j->face. */
static void product_row_task(void *arg, int index)
{
    const product_job *j = arg;
    product_row(j, j->face, j->first_row + j->rows - 1 - index);
}

/* The same on the six faces at once (their padded sources all at hand): the longest rows
 * first, each on its six faces. A batch of one to four rows made six loops of as many tasks,
 * one face each: on two threads a loop of one task ran alone and one of three ended on one
 * thread (18 ms of such loops in the 1024 chain, about half of it one thread's). Each face
 * writes its own sums, so the bits are those of the face-by-face loops. */
static void product_rows_all_faces_task(void *arg, int index)
{
    const product_job *j = arg;
    product_row(j, index % 6, j->first_row + j->rows - 1 - index / 6);
}

/* Face j->face's padded source and its transpose. */
static void padded_face(ibl_specular_plan *p, product_job *j)
{
    int P = j->c->padded_edge;
    ibl_parallel_for(p->ctx, P, padded_row_task, j);
    ibl_parallel_for(p->ctx, (P + TRANSPOSE_ROWS - 1) / TRANSPOSE_ROWS, transpose_task, j);
}

/* The floats of one padded face and its transpose for the level's pieces whose weights the plan
 * holds (a piece whose products make their own six padded faces needs none). */
static size_t face_floats(const ibl_specular_plan *p, int level)
{
    size_t floats = 0;
    for (int k = 0; k < p->levels[level].piece_count; k++) {
        const precomputed_piece *c = p->levels[level].pieces[k].precomputed;
        if (c && !ibl__fast_products_batched(c) && (size_t)6 * c->padded_edge * c->padded_edge > floats)
            floats = (size_t)6 * c->padded_edge * c->padded_edge;
    }
    return floats;
}

/* How many faces are summed at once, each in its own padded buffer: the threads when they
 * divide the six faces, else one. */
static int product_face_slots(const ibl_context *ctx)
{
    int threads = ibl_context_threads(ctx);
    return threads <= 6 && 6 % threads == 0 ? threads : 1;
}

/* Whether the level's kept pieces apply enough weights to each padded face for a buffer a
 * thread (FACE_TASK_WEIGHTS_PER_CELL). */
static int faces_worth_a_buffer_each(const ibl_specular_plan *p, int level)
{
    double weights = 0, cells = 0;
    for (int k = 0; k < p->levels[level].piece_count; k++) {
        const precomputed_piece *c = p->levels[level].pieces[k].precomputed;
        if (!c || ibl__fast_products_batched(c)) continue;
        weights += (double)c->first_weight[(size_t)c->base_edge * c->base_edge];
        if ((double)c->padded_edge * c->padded_edge > cells) cells = (double)c->padded_edge * c->padded_edge;
    }
    return weights >= FACE_TASK_WEIGHTS_PER_CELL * cells;
}

size_t ibl__fast_kept_padded_floats(const ibl_specular_plan *p, int level)
{
    return face_floats(p, level) * (size_t)product_face_slots(p->ctx);
}

/* One face of a piece whose weights the plan holds: its padded source and transpose in a free
 * buffer, then its base rows from the last. On the library's own pool the rows are a loop of
 * their own: the face's thread runs them all unless another thread, out of faces, helps with
 * the last ones. A buffer is always free in the end: a face holds one while it pads and while
 * its rows run, a row waits for nothing, and a thread waits for its rows' last indices only
 * while another thread runs one, which that thread took when no face was left to take (the
 * oldest loop first), so no thread starts a second face while it holds a buffer. A host's
 * parallel_for promises no such order (a work-stealing scheduler may start a face on a thread
 * whose face waits for its rows, and two such threads would wait for each other's buffers):
 * there a face runs its rows itself. */
static void product_face_task(void *arg, int face)
{
    const product_job *shared = arg;
    int slot = face % shared->face_slots;
    for (;;) {
        int expected = 0;
        if (atomic_compare_exchange_strong(&shared->slot_busy[slot], &expected, 1)) break;
        slot = (slot + 1) % shared->face_slots;
    }
    product_job j = *shared;
    size_t P = (size_t)j.c->padded_edge;
    j.face = face, j.all_faces = 0, j.padded = shared->slot_padded[slot];
    for (int row = 0; row < (int)P; row++) padded_row_task(&j, row);
    for (int t = 0; t < ((int)P + TRANSPOSE_ROWS - 1) / TRANSPOSE_ROWS; t++) transpose_task(&j, t);
    j.first_row = 0, j.rows = j.c->base_edge;
    if (ibl__parallel_on_own_pool(j.p->ctx)) ibl_parallel_for(j.p->ctx, j.rows, product_row_task, &j);
    else
        for (int i = 0; i < j.rows; i++) product_row_task(&j, i);
    atomic_store(&shared->slot_busy[slot], 0);
}

/* A piece whose weights the plan holds: every base row of the six faces. When the threads
 * divide the six faces, a face is a task (product_face_slots): its thread pads the face and
 * applies the weights to it, so the padded source it reads a few hundred times is in its own
 * core's cache (the 256 chain's level 1 on two threads: the padded rows one thread wrote were
 * read by both, and its ~60 loops of pads ended on one thread). Otherwise face by face, each
 * padded by rows and summed row by row over all threads. The same products either way. */
static void products_kept(ibl_specular_plan *p, product_job *job, float *const *padded, int face_slots)
{
    const precomputed_piece *c = job->c;
    job->padded = padded[0], job->all_faces = 0;
    job->weights = c->weights, job->cells = c->vector_cells, job->weight_origin = 0;
    job->face_slots = face_slots, job->slot_padded = padded;
    if (job->face_slots > 1) {
        atomic_int busy[6];
        for (int s = 0; s < 6; s++) atomic_init(&busy[s], 0);
        job->slot_busy = busy;
        ibl_parallel_for(p->ctx, 6, product_face_task, job);
        job->slot_busy = NULL;
        return;
    }
    for (job->face = 0; job->face < 6; job->face++) {
        padded_face(p, job);
        job->first_row = 0, job->rows = c->base_edge;
        ibl_parallel_for(p->ctx, job->rows, product_row_task, job);
    }
}

/* About this many batches of a one-shot plan's weights are made, one after the other. */
enum { WEIGHT_BATCHES = 16 };

int ibl__fast_products_batched(const precomputed_piece *c)
{
    /* the weights (2 bytes) and their cells (4 bytes a vector of 8) against the six faces'
     * padded sources and transposes, beyond the one face's the plan holds */
    size_t bases = (size_t)c->base_edge * c->base_edge, P = (size_t)c->padded_edge;
    return !c->weights && !c->normalisers_at_run &&
           (double)c->first_weight[bases] * 2.5 > 30.0 * P * P * sizeof(float);
}

/* Whether a one-shot plan still reads the uniform image (with or without bright texels, as
 * piece k of `level` reads) of that piece's source level after the piece: a later piece of any
 * level over the same image. */
static int uniform_read_later(const ibl_specular_plan *p, int level, int k)
{
    const precomputed_piece *c = p->levels[level].pieces[k].precomputed;
    for (int l = level; l < p->output_levels; l++)
        for (int i = l == level ? k + 1 : 0; i < p->levels[l].piece_count; i++) {
            const precomputed_piece *o = p->levels[l].pieces[i].precomputed;
            if (o && o->source_level == c->source_level && o->without_bright == c->without_bright) return 1;
        }
    return 0;
}

/* A one-shot plan's piece whose weights take more memory than the six faces' padded sources
 * (ibl__fast_products_batched): the padded sources first, then the weights batch by batch of
 * base rows, each batch's products with the six faces. Where the 44 M weights of the 1024
 * chain's level 1 took 110 MB with their cells, a batch takes a sixteenth and the six padded
 * faces 55 MB; at 256 the weights are the smaller, and are made whole (plan.c). */
static ibl_status products_batched(ibl_specular_plan *p, int level, int k, product_job *job)
{
    const precomputed_piece *c = job->c;
    ibl_context *ctx = p->ctx;
    size_t P = (size_t)c->padded_edge, nb = (size_t)c->base_edge, total = c->first_weight[nb * nb];
    size_t cap = total / WEIGHT_BATCHES + 1;
    for (size_t b = 0; b < nb; b++) /* at least one base row a batch */
        if (c->first_weight[(b + 1) * nb] - c->first_weight[b * nb] > cap)
            cap = c->first_weight[(b + 1) * nb] - c->first_weight[b * nb];
    float *geometry = NULL, *padded = ibl_alloc(ctx, 36 * P * P * sizeof(float));
    uint16_t *weights = NULL, *cells = NULL;
    ibl_status st = padded ? IBL_OK : ibl_context_status(ctx);
    if (st == IBL_OK) {
        job->padded = padded, job->all_faces = 1;
        for (job->face = 0; job->face < 6; job->face++) padded_face(p, job);
        /* the level's uniform image is in the padded faces now: if nothing reads it after this
         * piece, its memory (19 MB at the 1024 chain's level 1) goes to the weights */
        source_level *s = &p->pyramid[c->source_level];
        if (c->source_level > 0 && p->one_shot && !uniform_read_later(p, level, k)) {
            float **image = c->without_bright ? &s->uniform_not_bright : &s->uniform;
            ibl_free(ctx, *image);
            *image = NULL;
        }
        geometry = ibl__fast_precomputed_geometry(p, level, k);
        weights = ibl_alloc(ctx, cap * sizeof(uint16_t));
        cells = ibl_alloc(ctx, (cap / 8 + 1) * 2 * sizeof(uint16_t));
        if (!geometry || !weights || !cells) st = ibl_context_status(ctx);
        job->weights = weights, job->cells = cells;
    }
    if (st == IBL_OK) {
        for (size_t r0 = 0, r1; r0 < nb; r0 = r1) {
            for (r1 = r0 + 1; r1 < nb && c->first_weight[(r1 + 1) * nb] - c->first_weight[r0 * nb] <= cap;) r1++;
            ibl__fast_precomputed_weights(p, level, k, geometry, r0 * nb, r1 * nb, weights, cells);
            job->weight_origin = c->first_weight[r0 * nb];
            job->first_row = (int)r0, job->rows = (int)(r1 - r0);
            ibl_parallel_for(ctx, 6 * job->rows, product_rows_all_faces_task, job);
        }
    }
    ibl_free(ctx, cells);
    ibl_free(ctx, weights);
    ibl_free(ctx, padded);
    ibl_free(ctx, geometry);
    return st;
}

/* A reusable plan holds the padded buffers from its making, one block (a run allocates nothing
 * more); a one-shot plan's are made here for the level, after its weights were made and the
 * geometry they came from freed (precomputed.c), so that the two are never held at once: the
 * 256 GGX chain's peak is the level 1 refill's. One block a buffer, so that the first fits in
 * the freed geometry's pages (11 floats a texel against a buffer's 6: two in one block did not,
 * and took fresh pages: the 256 chain's RSS 40 -> 46 MB). It makes one a thread only where that
 * keeps under the context's peak so far and the faces are read enough to pay for it
 * (faces_worth_a_buffer_each), and else one (the faces in turn over all threads), so that a
 * buffer a thread never raises the context's peak. */
ibl_status ibl__fast_products(ibl_specular_plan *p, int level, const ibl_cubemap *src)
{
    level_plan *lv = &p->levels[level];
    ibl_context *ctx = p->ctx;
    float *padded[6] = {NULL};
    int slots = product_face_slots(ctx), made = 0;
    size_t face = face_floats(p, level);
    if (p->padded_source) {
        for (int s = 0; s < slots; s++) padded[s] = p->padded_source + (size_t)s * face;
    } else if (face) {
        if (slots > 1 && (!faces_worth_a_buffer_each(p, level) ||
                          ibl_context_current_bytes(ctx) + (uint64_t)slots * face * sizeof(float) >
                              ibl_context_peak_bytes(ctx)))
            slots = 1;
        for (; made < slots; made++)
            if (!(padded[made] = ibl_alloc(ctx, face * sizeof(float)))) {
                while (made > 0) ibl_free(ctx, padded[--made]);
                return ibl_context_status(ctx);
            }
    }
    ibl_status st = IBL_OK;
    for (int k = 0; st == IBL_OK && k < lv->piece_count; k++) {
        const precomputed_piece *c = lv->pieces[k].precomputed;
        if (!c) continue;
        product_job job = {.p = p, .c = c, .src = src, .sums = lv->grids[lv->pieces[k].grid].sums};
        if (c->weights) products_kept(p, &job, padded, slots);
        else st = products_batched(p, level, k, &job);
    }
    while (made > 0) ibl_free(ctx, padded[--made]);
    return st;
}
