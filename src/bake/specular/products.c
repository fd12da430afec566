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
 * are in difference form (moment leaf minus uniform leaf, on a coarser grid). */
#include "bake/specular/fast_internal.h"

typedef struct product_job {
    ibl_specular_plan *p;
    const precomputed_piece *c;
    const ibl_cubemap *src;
    float *sums;  /* the numerators of the piece's grid */
    int face;     /* the face being summed (its padded source in p->padded_source) */
} product_job;

/* Row `row` of face j->face's padded source. */
static void padded_row_task(void *arg, int row)
{
    const product_job *j = arg;
    const precomputed_piece *c = j->c;
    int f = j->face, S = c->source_edge, shift = 0;
    while ((1 << shift) < S) shift++;
    size_t plane = (size_t)c->padded_edge * c->padded_edge;
    const int32_t *cells = c->cell_texel + (size_t)row * c->padded_edge;
    float *out = j->p->padded_source + (size_t)row * c->padded_edge;
    const source_level *s = &j->p->pyramid[c->source_level];
    /* level 0: the source texels; a coarse level: its texels as uniform light, those with a
     * centroid correction left out (their moment leaves are summed instead) */
    const float *face[6];
    const float *uniform = c->without_bright ? s->uniform_not_bright : s->uniform;
    for (int g = 0; g < 6; g++)
        face[g] = c->source_level == 0 ? ibl_cubemap_face(j->src, 0, g) : uniform + (size_t)g * S * S * 4;
    int corrected = c->source_level > 0 && c->correction_block_count > 0 && !c->correction_difference;
    /* inside the face itself the padded source is the face: copied by rows */
    int y = row - c->origin, inside = y >= 0 && y < S;
    if (inside) {
        const float *v = face[f] + (size_t)y * S * 4;
        float *o = out + c->origin;
        for (int x = 0; x < S; x++) o[x] = v[4 * x], o[plane + x] = v[4 * x + 1], o[2 * plane + x] = v[4 * x + 2];
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
        const float *v = face[g] + ((size_t)yy * S + x) * 4;
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
        const float *in = j->p->padded_source + ch * plane;
        float *out = j->p->padded_source + (3 + ch) * plane;
        for (int X = 0; X < P; X++)
            for (int Y = y0; Y < y1; Y++) out[(size_t)Y * P + X] = in[(size_t)X * P + Y];
    }
}

/* One row b of base texels into the images of face j->face. Image by image, so that the source
 * rows under the row's windows stay in L1 while the row's weights stream from L2 (base by base,
 * every base re-read its windows from L2: measured 1.6x slower). */
static void product_row_task(void *arg, int b)
{
    const product_job *j = arg;
    const precomputed_piece *c = j->c;
    size_t plane = (size_t)c->padded_edge * c->padded_edge;
    int n = c->grid_edge, nb = c->base_edge;
    for (int fy = 0; fy < 2; fy++) {
        int y = fy ? n - 1 - b : b;
        if (fy && y == b) continue;
        for (int fx = 0; fx < 2; fx++)
            for (int a = 0; a < nb; a++) {
                int x = fx ? n - 1 - a : a;
                if (fx && x == a) continue;
                /* below the diagonal: the mirror's weights on the transposed source */
                int mirror = a > b;
                size_t base = mirror ? (size_t)a * nb + b : (size_t)b * nb + a;
                const float *planes = j->p->padded_source + (mirror ? 3 * plane : 0);
                double s[3];
                j->p->kernels->product(c, base, planes, mirror ? fy : fx, mirror ? fx : fy, s);
                float *o = j->sums + (((size_t)j->face * n + y) * n + x) * 4;
                for (int ch = 0; ch < 3; ch++) o[ch] = (float)(o[ch] + s[ch]);
            }
    }
}

void ibl__fast_products(ibl_specular_plan *p, int level, const ibl_cubemap *src)
{
    level_plan *lv = &p->levels[level];
    for (int k = 0; k < lv->piece_count; k++) {
        const precomputed_piece *c = lv->pieces[k].precomputed;
        if (!c) continue;
        product_job job = {p, c, src, lv->grids[lv->pieces[k].grid].sums, 0};
        for (job.face = 0; job.face < 6; job.face++) {
            ibl_parallel_for(p->ctx, c->padded_edge, padded_row_task, &job);
            ibl_parallel_for(p->ctx, (c->padded_edge + TRANSPOSE_ROWS - 1) / TRANSPOSE_ROWS, transpose_task, &job);
            ibl_parallel_for(p->ctx, c->base_edge, product_row_task, &job);
        }
    }
}
