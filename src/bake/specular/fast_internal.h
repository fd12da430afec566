/* The shared types of the fast prefilter (src/bake/specular/): the plan and what it is made
 * of, the layout of texel records, and the functions one file of the method calls in another.
 *
 * The method in one paragraph (docs/SPECULAR.md "The fast method" has it in full): the lobe
 * f(u), u = 1 - R.l, is cut by a smooth partition of unity into a *core* and dyadic *rings*
 * (pieces.c). Each piece is summed over one level of a moment pyramid of the source
 * (geometry.c, pyramid.c), where a texel contributes the second-order Taylor expansion of the
 * piece about its centroid (the *leaf*, leaf_sums.c and the kernels). A piece whose leaves use
 * geometric moments only has weights fixed by the cube's geometry: they are computed once per
 * plan for one quadrant of face 0 (precomputed.c) and a run is a product of those weights with
 * the source (products.c). Texels whose light is far from uniform, and bright texels next to
 * coarse grids, are gathered and summed leaf by leaf (gathering.c). The pieces are evaluated
 * on cube grids, interpolated and divided by their normaliser into the output (combine.c).
 * Roughness-0 levels are the source itself (mirror.c). plan.c holds the public plan object and
 * the order of a run; tuning.h every tuning constant.
 *
 * Words used throughout: a *block* is 4 x 2 texels of one face (one 8-wide vector per field);
 * a *record* holds a texel's fields; a *cone* bounds a block's directions; *bright apart*
 * means a ring's bright texels are summed on a finer grid (or at the output texels) instead of
 * on its own; the *normaliser* is the sum of the same weights over geometry alone (the
 * denominator). */
#ifndef IBL_SPECULAR_FAST_INTERNAL_H
#define IBL_SPECULAR_FAST_INTERNAL_H

#include "bake/specular_internal.h"
#include "bake/specular/tuning.h"

#include <stddef.h>
#include <stdint.h>

/* ---- texel records ---- */

enum { BLOCK_W = 4, BLOCK_H = 2, BLOCK_TEXELS = BLOCK_W * BLOCK_H };

/* The fields of a texel record, each BLOCK_TEXELS floats from the next within its block. First
 * the geometric moments of the directions the texel covers: */
enum {
    FIELD_MEAN = 0,        /* 3: mean direction m (|m| < 1)                              */
    FIELD_SPREAD = 3,      /* e = (1 - |m|^2) / 2 = E|l - m|^2 / 2                        */
    FIELD_COVARIANCE = 4,  /* 6: C, as xx yy zz xy xz yz                                  */
    FIELD_SOLID_ANGLE = 10,
    GEOMETRY_FIELDS = 11
};
/* then, on level 0 (the source texels, or their sub-texels), the radiance: */
enum { FIELD_RADIANCE = GEOMETRY_FIELDS, LEVEL0_FIELDS = GEOMETRY_FIELDS + 3 };
/* and on coarser levels the same moments weighted by luminance (a sun inside the texel sits at
 * their centroid), the texel's power per channel, and its power when it is not bright (0 for
 * a bright texel, which is gathered and summed apart): */
enum {
    FIELD_LUM_MEAN = GEOMETRY_FIELDS,
    FIELD_LUM_SPREAD = FIELD_LUM_MEAN + 3,
    FIELD_LUM_COVARIANCE = FIELD_LUM_MEAN + 4,
    FIELD_POWER = FIELD_LUM_MEAN + 10,
    FIELD_POWER_NOT_BRIGHT = FIELD_POWER + 3,
    COARSE_FIELDS = FIELD_POWER_NOT_BRIGHT + 3
};
/* The bounding cone of a block: its centre direction (unit), angular radius r, cos r, sin r. */
enum { CONE_FLOATS = 6 };

/* Cone slots for `blocks` gathered blocks: one per block, then one per SUPER_CONE_BLOCKS. */
static inline size_t cone_slots(int blocks)
{
    return (size_t)blocks + ((size_t)blocks + SUPER_CONE_BLOCKS - 1) / SUPER_CONE_BLOCKS;
}

/* Rec. 709 luminance: the radiance centroids and the bright and correction bars weigh light by
 * it. */
#define LUMINANCE_R 0.2126
#define LUMINANCE_G 0.7152
#define LUMINANCE_B 0.0722
static inline double luminance(double r, double g, double b)
{
    return LUMINANCE_R * r + LUMINANCE_G * g + LUMINANCE_B * b;
}

static inline int is_power_of_two(int n) { return n > 0 && (n & (n - 1)) == 0; }

/* The mean angular size of a texel of a face of edge n, sqrt(4 pi / 6) / n (the texels at a face
 * centre are 1.38 times wider, those at its corners 1.7 times narrower). */
static inline double texel_angle(int n) { return 1.4472025 / n; }

/* The widest texels the core of a lobe may be summed over (pieces.c: the coarsest pyramid level
 * with texels at most this wide), acc being accuracy_scale. */
static inline double core_source_width(const ibl__lobe *lobe, double acc)
{
    return lobe->half_angle / (CORE_TEXELS_PER_HALF_WIDTH / acc);
}

/* ---- the moment pyramid (geometry.c, pyramid.c) ---- */

/* One level of the pyramid: the source (level 0) or a mip of it, as records in blocks. */
/* Floats a texel of a level's uniform images: r, g, b (no pad: the padded sources copy the
 * three planes, and the 512 level's image at the 1024 chain's peak is 6.3 MB smaller so). */
#define UNIFORM_CHANNELS 3

typedef struct source_level {
    int edge;              /* texels per face edge                                            */
    int blocks_x, blocks_y; /* blocks per face row and column                                 */
    int fields;            /* floats per texel record: LEVEL0_FIELDS or COARSE_FIELDS, less
                            * first_field                                                    */
    /* the first field the records hold: 0, or GEOMETRY_FIELDS for a level whose geometric
     * fields are in `geometry` only (levels only the run's pyramid reads) */
    int first_field;
    float *records;        /* 6 blocks_y blocks_x blocks x fields x BLOCK_TEXELS               */
    float *cones;          /* per block: its bounding cone                                     */
    /* coarse levels whose records only the run's pyramid reads (no leaf sum, no mirror level):
     * their geometric fields kept once, face-local (GEOMETRY_FIELDS floats per texel of one
     * face, row by row, as records would hold them before moments_to_world), the records
     * holding the other fields only (first_field); NULL for levels whose records hold all */
    float *geometry;
    /* run, coarse levels: the luminance power of each task's block row (6 blocks_y), and their
     * sum in order (the bright and correction bars are relative to the mean radiance) */
    double *row_power, power;
    /* run, levels read by precomputed pieces: each texel as uniform light, its power over its
     * solid angle (UNIFORM_CHANNELS floats, r g b, a cube face's layout), and the same without
     * the power of its bright texels; the padded sources are copied from these */
    float *uniform, *uniform_not_bright;
    /* bright texels (levels read by rings whose bright texels go apart), gathered in blocks */
    double bright_scale;   /* the bar's constant per unit of mean radiance (0: no bright texels) */
    int bright_capacity, bright_block_count;
    float *bright_records, *bright_cones;
    uint64_t *bright_keys; /* bright_capacity BLOCK_TEXELS: scratch of the gathering           */
} source_level;

static inline size_t source_block_count(const source_level *s)
{
    return (size_t)6 * s->blocks_y * s->blocks_x;
}

/* Where field `field` (at least s->first_field) of lane t of block b is in s->records. */
static inline size_t field_index(const source_level *s, size_t b, int field, int t)
{
    return (b * s->fields + (size_t)(field - s->first_field)) * BLOCK_TEXELS + (size_t)t;
}

/* Where field `field` (at least s->first_field) of texel (x, y) of face `face` is in
 * s->records. */
static inline size_t record_index(const source_level *s, int face, int x, int y, int field)
{
    size_t b = ((size_t)face * s->blocks_y + y / BLOCK_H) * s->blocks_x + x / BLOCK_W;
    return field_index(s, b, field, (y % BLOCK_H) * BLOCK_W + x % BLOCK_W);
}

/* The face and texel of lane t of block b. */
static inline void block_texel(const source_level *s, size_t b, int t, int *face, int *x, int *y)
{
    size_t per_face = (size_t)s->blocks_y * s->blocks_x, r = b % per_face;
    *face = (int)(b / per_face);
    *x = (int)(r % s->blocks_x) * BLOCK_W + t % BLOCK_W;
    *y = (int)(r / s->blocks_x) * BLOCK_H + t / BLOCK_W;
}

/* Writes moments given in a face's local (s, t, axis) coordinates in world coordinates, through
 * the face's signed permutation (see ibl_specular_plan.face_axis), as floats `stride` apart:
 * the mean at out[0..2], the spread at out[3], the covariance (xx yy zz xy xz yz) at
 * out[4..9]. Moving and negating components is exact. */
static inline void moments_to_world(const int axis[3], const float sign[3], const double mean[3],
                                    double spread, const double covariance[6], float *out,
                                    size_t stride)
{
    static const int pair[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {0, 2}, {1, 2}};
    const double local[3][3] = {{covariance[0], covariance[3], covariance[4]},
                                {covariance[3], covariance[1], covariance[5]},
                                {covariance[4], covariance[5], covariance[2]}};
    for (int c = 0; c < 3; c++) out[c * stride] = (float)(sign[c] * mean[axis[c]]);
    out[3 * stride] = (float)spread;
    for (int c = 0; c < 6; c++) {
        int i = pair[c][0], k = pair[c][1];
        out[(4 + c) * stride] = (float)(sign[i] * sign[k] * local[axis[i]][axis[k]]);
    }
}

/* A texel's face-local geometric fields g (floats, GEOMETRY_FIELDS) in world coordinates, as
 * floats `stride` apart. */
static inline void face_local_to_world(const int axis[3], const float sign[3], const float *g,
                                       float *out, size_t stride)
{
    double mean[3] = {g[FIELD_MEAN], g[FIELD_MEAN + 1], g[FIELD_MEAN + 2]}, covariance[6];
    for (int k = 0; k < 6; k++) covariance[k] = g[FIELD_COVARIANCE + k];
    moments_to_world(axis, sign, mean, g[FIELD_SPREAD], covariance, out + FIELD_MEAN * stride,
                     stride);
    out[FIELD_SOLID_ANGLE * stride] = g[FIELD_SOLID_ANGLE];
}

/* The geometric fields (FIELD_MEAN .. FIELD_SOLID_ANGLE) of texel (x, y) of face f of level s:
 * from its records, or from the face-local store through face f's signed permutation. Moving
 * and negating floats is exact, so both give the same bits. */
static inline void level_texel_geometry(const int axis[3], const float sign[3],
                                        const source_level *s, int f, int x, int y,
                                        float out[GEOMETRY_FIELDS])
{
    if (s->records && s->first_field == 0) {
        const float *r = s->records + record_index(s, f, x, y, 0);
        for (int k = 0; k < GEOMETRY_FIELDS; k++) out[k] = r[k * BLOCK_TEXELS];
        return;
    }
    face_local_to_world(axis, sign, s->geometry + ((size_t)y * s->edge + x) * GEOMETRY_FIELDS,
                        out, 1);
}

/* The moments of a set of directions, in double (geometry.c). */
typedef struct texel_moments {
    double mean[3], spread, covariance[6], solid_angle; /* covariance: xx yy zz xy xz yz */
} texel_moments;

/* ---- the pieces of a lobe and the grids they are evaluated on (pieces.c) ---- */

/* One step of the partition in closed form: psi = 1 - smootherstep(s), s = clamp(u scale -
 * offset, 0, 1), ds/du = slope. Scale 0 encodes an absent step: offset 1 keeps s at 0 (psi = 1:
 * the last ring has no outer step), offset -2 keeps it at 1 (psi = 0: the core has no inner
 * step). */
typedef struct psi_step {
    float scale, offset, slope;
} psi_step;

typedef struct precomputed_piece precomputed_piece;

/* The lobe times one function of the partition of unity: the core (no inner step) or a ring. */
typedef struct lobe_piece {
    int grid;              /* the grid it is evaluated on (index into level_plan.grids)        */
    int source_level;      /* the pyramid level it is summed over                              */
    double u_lo, u_hi;     /* its support in u = 1 - R.l                                       */
    double angle_in, angle_out; /* the same as angles from the lobe's axis                     */
    /* g and g'' tabulated in u (PIECE_TABLE_STEPS + 2 pairs, the last zero) */
    float table_u0, table_scale;
    float *table;
    /* in closed form for the AVX2 kernels: GGX f = (1 - u) alpha4 / T^2, T = alpha2 + slope u */
    float ggx_alpha2, ggx_slope, ggx_alpha4;
    float phong_n;         /* Phong exponent                                                   */
    int phong_series;      /* the AVX2 kernels may take x^n by series in u (kernels_avx2.c)     */
    int is_ggx;
    psi_step outer, inner;
    int bright_apart;      /* a ring on a coarse grid whose bright texels are summed apart      */
    int bright_grid;       /* ... on this grid                                                 */
    /* a core on the output texels, many of them a half width: the centroid corrections of its
     * weights (if precomputed over a coarse level) go on this coarser grid, in difference form
     * (gathering.c) */
    int has_correction_grid, correction_grid;
    precomputed_piece *precomputed; /* its weights, when precomputed (NULL: summed by leaves) */
} lobe_piece;

/* The points one or more pieces are evaluated at: the output level's own texels (at_output,
 * where edge fixups may bend the directions) or a coarser cube grid, interpolated. */
typedef struct sum_grid {
    int edge, at_output;
    int lagrange;          /* read by 6-point Lagrange interpolation (a Phong core), not bilinear */
    int tiles;             /* TILE_EDGE tiles per face edge                                    */
    float *sums;           /* 6 edge^2 x 4: sum g P (rgb), sum g Omega (the normaliser)         */
    /* a one-shot plan holds a level's sums for its plan's normalisers and its run only; between
     * them it keeps face 0's normalisers here (edge^2: every face's are face 0's, leaf_sums.c)
     * and the sums are NULL (pieces.c, ibl__fast_grids_set_aside / ibl__fast_grids_restore) */
    float *normalisers;
    float *bordered;       /* coarse grids: 6 (edge + 2 border)^2 x 4, the sums with a border
                            * (grid_border) across the face edges (corner: the mean of its
                            * three texels), as the seamless bilinear sampler reads them      */
    size_t bordered_floats; /* its size (two copies for a Lagrange grid): a one-shot plan makes
                             * it only for the level's combine (combine.c)                     */
} sum_grid;

/* Texels of a coarse grid's border: the 6-point reads of a Lagrange grid take three beyond a
 * face edge (combine.c), bilinear ones one. */
static inline int grid_border(const sum_grid *g) { return g->lagrange ? 3 : 1; }

typedef struct level_plan {
    ibl__lobe lobe;
    int piece_count, grid_count, task_count;
    lobe_piece pieces[MAX_PIECES];
    sum_grid grids[MAX_PIECES];
    int task_begin[MAX_PIECES + 1]; /* the first leaf-sum task of each grid                    */
} level_plan;

/* ---- precomputed weights (precomputed.c, products.c) ---- */

/* A piece whose weights depend on geometry alone, stored for the base texels of one quadrant of
 * face 0 as rows over the padded face (the face with a `border` of texels unfolded from its four
 * neighbours). See precomputed.c. */
struct precomputed_piece {
    int source_level;      /* the pyramid level it sums (0: the source texels)                  */
    int at_output;         /* on the output texels                                            */
    int without_bright;    /* over the texels' power without their bright texels               */
    int source_edge;       /* texels per face edge of that level                               */
    int border;            /* texels unfolded beyond each face edge                            */
    int padded_edge;       /* source_edge + 2 border + 16: a vector of slack on either side     */
    int origin;            /* padded cell of face texel (0, 0): border + 8                      */
    int grid_edge;         /* points per face edge of the grid                                 */
    int base_edge;         /* base texels per quadrant edge, (grid_edge + 1) / 2               */
    int32_t *cell_texel;   /* padded_edge^2: face 0's source texel under each cell, or -1       */
    int face_carry[6][6][7]; /* face F: where face 0's cell texels on face g go (products.c)    */
    /* base texels below the diagonal (a > b) have no weights of their own: base (a, b) takes
     * (b, a)'s, applied to the transposed padded source (the reflection x <-> y) */
    uint32_t *first_row;   /* base_edge^2 + 1: each base texel's first row                      */
    size_t *first_weight;  /* base_edge^2 + 1: each base texel's first weight                   */
    int32_t *rows;         /* per row: y, x (padded coordinates minus origin), length (x 8)     */
    /* per 8 weights: the padded cell (x, y) of the first; one loop over a base's vectors has a
     * steady trip count, where the rows' short loops (3-5 vectors) mispredicted their exits */
    uint16_t *vector_cells;
    uint16_t *weights;     /* half floats, divided by weight_scale                              */
    float weight_scale;
    double *normaliser;    /* base_edge^2: sum of the weights as stored                         */
    /* centroid corrections (a coarse level's texels are summed as uniform light): a texel's
     * moment leaf differs from its uniform leaf by at most P (mean |dm| + spread |de| +
     * covariance |dC|) per unit of the normaliser (gathering.c) */
    double bound_mean, bound_spread, bound_covariance;
    int correction_difference; /* the corrections are summed as moment leaf minus uniform leaf on
                                * the piece's correction grid; the corrected texels stay in the
                                * padded source */
    /* a one-shot plan's piece on a Lagrange grid computes its weights once, at the run: its
     * normalisers are found with them (ibl__fast_precomputed_refill) and added to the grid's
     * then (ibl__fast_precomputed_run_normalisers), and the level's bars take the piece's
     * integral instead (gathering.c) */
    int normalisers_at_run;
    /* ... and keeps the padded geometry its rows were found on for those weights when it is
     * small (KEPT_GEOMETRY_BYTES), instead of making it again; NULL otherwise */
    float *kept_geometry;
    /* a block of corrections spans at most this many texels of its first (0: no limit; the
     * Phong pieces', gathering.c) */
    int gather_span;
    int correction_capacity, correction_block_count;
    /* run: in the plan's correction pool, or (a one-shot plan: own_records) a block of the
     * piece's own, made as the corrections are gathered and freed after the level's sums */
    float *correction_records;
    int own_records;
    float *correction_cones;
    uint64_t *correction_keys; /* correction_capacity BLOCK_TEXELS: scratch of the gathering    */
    float *texel_bound;    /* run: each texel's bound (block order)                             */
    /* (a one-shot plan frees the keys once its corrections are gathered, and the bounds too
     * unless its padded source leaves the corrected texels out by them: plan.c) */
    float correction_threshold; /* run: texels over it are left out of the padded source and
                                 * summed as leaves                                            */
};

/* ---- the kernels (kernels_portable.c, kernels_avx2.c) ---- */

/* What a leaf sum accumulates: the normaliser (geometric moments, at plan time), or the
 * numerator from level 0 (texel radiance, geometric moments) or from a coarse level
 * (luminance-weighted moments and power), or a coarse texel's centroid correction in
 * difference form (its moment leaf minus its uniform leaf, the power at the geometric moments:
 * what the precomputed product already counted). */
enum leaf_mode { LEAF_NORMALISER = 0, LEAF_LEVEL0, LEAF_COARSE, LEAF_DIFFERENCE };

/* A block that may matter for a tile: only where cos_out <= R.centre <= cos_in. */
typedef struct leaf_candidate {
    uint32_t block;
    float cos_out, cos_in;
} leaf_candidate;

/* A batch of candidate blocks of one piece over one set of records. */
typedef struct leaf_batch {
    int mode;
    const source_level *level; /* records and cones (gathered texels: a view of them)          */
    const lobe_piece *piece;
    const leaf_candidate *candidates;
    int count;
    int without_bright;    /* read the power without the bright texels                         */
} leaf_batch;

/* The record of candidate `index` if it can matter for direction R (NULL if it is culled). */
static inline const float *candidate_record(const leaf_batch *batch, int index, const float R[3])
{
    const leaf_candidate *cd = &batch->candidates[index];
    const float *bc = batch->level->cones + (size_t)cd->block * CONE_FLOATS;
    float dd = R[0] * bc[0] + R[1] * bc[1] + R[2] * bc[2];
    if (dd < cd->cos_out || dd > cd->cos_in) return NULL;
    return batch->level->records + (size_t)cd->block * batch->level->fields * BLOCK_TEXELS;
}

/* The four inner loops of the method, chosen once per plan: AVX2 + FMA + F16C where the
 * context allows them, the portable C versions otherwise. R is a unit direction, RR its
 * quadratic terms (xx, yy, zz, 2xy, 2xz, 2yz) that turn a covariance into R^T C R. */
typedef struct fast_kernels {
    /* for each of `points` directions R[i] (RR[i] its quadratic terms), the sum over the
     * batch's leaves, added to out[i] (rgb, normaliser) */
    void (*sum_leaves)(const leaf_batch *batch, int points, const float (*R)[3],
                       const float (*RR)[6], double (*out)[4]);
    /* a base texel's weights over its rows of the padded geometry (GEOMETRY_FIELDS planes
     * `plane` apart), divided by the weight scale (inv_scale), stored as halves; the stored
     * halves summed per lane into lanes */
    void (*base_weights)(const lobe_piece *piece, const float R[3], const float RR[6],
                         const float *geometry, size_t plane, int padded_edge, int origin,
                         const int32_t *rows, int row_count, float inv_scale, uint16_t *weights,
                         float lanes[8]);
    /* first and last of n cells within reach of R (m.R >= cos_reach, a texel there); -1 none */
    void (*row_extent)(const float *geometry, size_t plane, int n, const float R[3],
                       float cos_reach, int *first, int *last);
    /* base texel `base`'s weights (from w on, their vectors' first cells from cells on) times an
     * image of the padded source (rgb planes), flipped by flip_x / flip_y */
    void (*product)(const precomputed_piece *c, size_t base, const uint16_t *w,
                    const uint16_t *cells, const float *planes, int flip_x, int flip_y,
                    double out[3]);
} fast_kernels;

extern const fast_kernels ibl__fast_kernels_portable;
extern const fast_kernels ibl__fast_kernels_avx2; /* only where IBL_HAVE_X86_KERNELS */

/* ---- the plan ---- */

struct ibl_specular_plan {
    ibl_context *ctx;
    ibl_specular_desc desc;
    ibl_specular_info info;
    const fast_kernels *kernels;
    int source_edge;       /* face edge of the cubes a run gets                                 */
    int subtexel_split;    /* level 0 of the pyramid splits each source texel k x k             */
    int pyramid_levels;    /* from source_edge subtexel_split texels down to 1                  */
    /* the first coarse level with records: levels 1 .. first_stored - 1 are read by no piece
     * and no mirror level, so they are skipped and level first_stored is summed straight from
     * the source texels (pyramid.c); 1 when the source is split into sub-texels */
    int first_stored;
    int output_edge, output_levels;
    source_level pyramid[IBL_MAX_LEVELS];
    level_plan levels[IBL_MAX_LEVELS];
    float face_basis[6][3][3]; /* per face: axis, s tangent, t tangent                         */
    /* the signed permutation from face f's local (s, t, axis) coordinates to world ones:
     * world[i] = face_sign[f][i] local[face_axis[f][i]] */
    int face_axis[6][3];
    float face_sign[6][3];
    ibl__dynamic *dynamic; /* desc.dynamic: the precomputed operator instead of the pieces      */
    /* level 0's geometric moments, once, face-local (GEOMETRY_FIELDS floats per texel of one
     * eighth of face 0, level0_face_moments): the rest of the face by its reflections, the
     * other faces by the signed permutations. Level 0's records exist only when some
     * piece sums level 0 leaf by leaf (has_level0_records). */
    float *level0_geometry;
    int has_level0_records;
    /* run: the padded sources and transposes of the precomputed pieces whose weights the plan
     * holds (ibl__fast_kept_padded_floats); a one-shot plan has none: its products make them
     * level by level */
    float *padded_source;
    /* run: the gathered corrections of every precomputed piece, one after the other (only the
     * part a run uses is touched) */
    float *correction_pool; /* (a reusable plan's: a one-shot plan's pieces make their own) */
    size_t correction_pool_blocks;
    /* a plan made for one run (ibl_specular_prefilter), whose largest buffers are never held
     * at once: the records only the pyramid reads are made by the run and freed as soon as the
     * pyramid is done with them; the precomputed pieces find their normalisers batch by batch
     * and keep their rows only, their weights made again just before their products and freed
     * after them; once the grids are summed, everything else is freed (plan.c) */
    int one_shot;
};

/* Roughness 0 (or no shininess): the level is the source itself (mirror.c), with no pieces,
 * grids or weights. Every loop over the filtered levels asks this. */
static inline int level_is_mirror(const ibl_specular_plan *p, int level)
{
    return p->levels[level].lobe.kind == IBL__LOBE_MIRROR;
}

/* desc.accuracy relative to the default: scales every width and bar of the method */
static inline double accuracy_scale(const ibl_specular_plan *p)
{
    return p->desc.accuracy > 0 ? p->desc.accuracy / ACCURACY_DEFAULT : 1.0;
}

/* Texel (x, y) of level 0's face-local geometric moments, from the eighth of the face that is
 * stored (a <= b < ceil(n / 2), row b from b (b + 1) / 2): the reflections s -> -s, t -> -t and
 * the swap s <-> t act on the moments by sign flips and swaps, exactly in float, so this is
 * the same as a whole face stored (geometry.c's unfold_eighth_task, which builds the doubles
 * the same way) at an eighth of its memory. */
static inline void level0_face_moments(const ibl_specular_plan *p, int x, int y,
                                       float out[GEOMETRY_FIELDS])
{
    int n = p->pyramid[0].edge;
    int fx = x > n - 1 - x, fy = y > n - 1 - y;
    int a = fx ? n - 1 - x : x, b = fy ? n - 1 - y : y, swap = a > b;
    if (swap) {
        int t = a;
        a = b, b = t;
    }
    const float *g = p->level0_geometry + ((size_t)b * (b + 1) / 2 + a) * GEOMETRY_FIELDS;
    for (int k = 0; k < GEOMETRY_FIELDS; k++) out[k] = g[k];
    float *m = out + FIELD_MEAN, *C = out + FIELD_COVARIANCE, t;
    if (swap) { /* C: xx yy zz xy xz yz */
        t = m[0], m[0] = m[1], m[1] = t;
        t = C[0], C[0] = C[1], C[1] = t;
        t = C[4], C[4] = C[5], C[5] = t;
    }
    if (fx) m[0] = -m[0], C[3] = -C[3], C[4] = -C[4];
    if (fy) m[1] = -m[1], C[3] = -C[3], C[5] = -C[5];
}

/* Whether the output directions are the texel centres (no edge fixup bends them). */
static inline int centred_directions(const ibl_specular_plan *p)
{
    return p->desc.edge_fixup != IBL_EDGE_FIXUP_BENT && p->desc.edge_fixup != IBL_EDGE_FIXUP_WARP;
}

/* Whether a grid's directions are symmetric under the square's eight symmetries on a face
 * (edge fixups that bend directions are not assumed to be). */
static inline int grid_symmetric(const ibl_specular_plan *p, const sum_grid *g)
{
    return !g->at_output || centred_directions(p);
}

/* Whether texel (x, y) of face f of the piece's level gets a centroid correction. */
static inline int texel_corrected(const precomputed_piece *c, const source_level *s, int f, int x,
                                  int y)
{
    size_t b = ((size_t)f * s->blocks_y + y / BLOCK_H) * s->blocks_x + x / BLOCK_W;
    return c->texel_bound[b * BLOCK_TEXELS + (y % BLOCK_H) * BLOCK_W + x % BLOCK_W] >
           c->correction_threshold;
}

/* ---- geometry.c ---- */
void ibl__fast_face_frames(ibl_specular_plan *p);
int32_t ibl__fast_unfolded_texel(const ibl_specular_plan *p, int edge, int face, int x, int y);
void ibl__fast_combine_moments(const texel_moments *const *parts, const double *weights,
                               int count, texel_moments *out);
void ibl__fast_level0_moments(const ibl_specular_plan *p, int face, int x, int y,
                              float out[GEOMETRY_FIELDS]);
void ibl__fast_pyramid_edges(ibl_specular_plan *p);
ibl_status ibl__fast_build_moments(ibl_specular_plan *p);
ibl_status ibl__fast_level0_records(ibl_specular_plan *p);
ibl_status ibl__fast_kept_records(ibl_specular_plan *p);
ibl_status ibl__fast_run_records(ibl_specular_plan *p, int level);
void ibl__fast_free_run_records(ibl_specular_plan *p, int level);

/* ---- pyramid.c ---- */
void ibl__fast_pyramid_level0(ibl_specular_plan *p, const ibl_cubemap *src);
void ibl__fast_pyramid_level(ibl_specular_plan *p, const ibl_cubemap *src, int level);
void ibl__fast_uniform_level(ibl_specular_plan *p, int level);
int ibl__fast_pyramid_streams(const ibl_specular_plan *p, int level);
ibl_status ibl__fast_pyramid_streamed(ibl_specular_plan *p, const ibl_cubemap *src, int level);
const float *ibl__fast_streamed_texel(const ibl_specular_plan *p, const ibl_cubemap *src, int level,
                                      int f, int x, int y, float *row);

/* ---- pieces.c ---- */
ibl_status ibl__fast_plan_pieces(ibl_specular_plan *p, int level);
/* A one-shot plan's grids of a level: their sums made (with the normalisers set aside, if any),
 * and the normalisers set aside with the sums freed. */
ibl_status ibl__fast_grids_restore(ibl_specular_plan *p, int level);
ibl_status ibl__fast_grids_set_aside(ibl_specular_plan *p, int level);
double ibl__fast_piece_peak(const lobe_piece *piece);
double ibl__fast_piece_integral(const lobe_piece *piece);
int ibl__fast_core_normalisers_later(const level_plan *lv);

/* ---- leaf_sums.c ---- */
void ibl__fast_normalisers(ibl_specular_plan *p, int level);
void ibl__fast_leaf_sums(ibl_specular_plan *p, int level);

/* ---- precomputed.c ---- */
ibl_status ibl__fast_precompute_level(ibl_specular_plan *p, int level);
void ibl__fast_precomputed_normalisers(ibl_context *ctx, const precomputed_piece *c, float *sums);
void ibl__fast_precomputed_destroy(ibl_context *ctx, precomputed_piece *c);
void ibl__fast_precomputed_release(ibl_context *ctx, precomputed_piece *c);
ibl_status ibl__fast_precomputed_refill(ibl_specular_plan *p, int level, int k);
void ibl__fast_precomputed_run_normalisers(ibl_specular_plan *p, int level, int k);
float *ibl__fast_precomputed_geometry(ibl_specular_plan *p, int level, int k);
void ibl__fast_precomputed_weights(ibl_specular_plan *p, int level, int k, const float *geometry,
                                   size_t first, size_t end, uint16_t *weights, uint16_t *cells);

/* ---- products.c ---- */
ibl_status ibl__fast_products(ibl_specular_plan *p, int level, const ibl_cubemap *src);
/* whether a one-shot plan's piece makes its weights batch by batch in the products (else whole,
 * ibl__fast_precomputed_refill) */
int ibl__fast_products_batched(const precomputed_piece *c);
/* the floats of padded sources and transposes that a level's pieces whose weights the plan holds
 * use: 2 x 3 planes of padded_edge^2 for each face summed at once (the threads when they divide
 * the six faces, else one) */
size_t ibl__fast_kept_padded_floats(const ibl_specular_plan *p, int level);

/* ---- gathering.c ---- */
ibl_status ibl__fast_plan_bars(ibl_specular_plan *p, int level);
ibl_status ibl__fast_gathering_buffers(ibl_specular_plan *p);
void ibl__fast_select_bright(ibl_specular_plan *p, int level);
/* (src: the run's source, from which a streamed level's gathered texels are made again) */
ibl_status ibl__fast_select_corrections(ibl_specular_plan *p, precomputed_piece *c,
                                        const ibl_cubemap *src);
void ibl__fast_block_bounds(const ibl_specular_plan *p, const precomputed_piece *c,
                            const source_level *s, size_t b, const float *lum);

/* ---- combine.c ---- */
ibl_status ibl__fast_combine(ibl_specular_plan *p, ibl_cubemap *dst, int level);

/* ---- mirror.c ---- */
void ibl__fast_mirror_level(ibl_specular_plan *p, const ibl_cubemap *src, ibl_cubemap *dst,
                            int level);

#endif
