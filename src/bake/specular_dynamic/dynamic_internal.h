/* The per-frame (dynamic) prefilter, tri-Ace 2010's dynamic configurations ("Real-time
 * Physically Based Rendering - Implementation", "Implemented configurations": box 16x16x6,
 * Gaussian 32x32x6, Phong 16x16x6 and 32x32x6, refiltered every frame from a freshly rendered
 * cube). A plan fixes every table and buffer; a run allocates nothing and its time depends on
 * the sizes only. Two engines, chosen by the filter:
 *
 *   box and gauss  the tri-Ace chains themselves ("Generate PMREM (1)" and "(2)"), with every
 *                  weight and normaliser precomputed: the same operations in the same order as
 *                  specular_box.c, specular_gauss.c and cubemap.c, so the same bits
 *                  (box_chain.c, the inner loops in chain_kernels.c);
 *   phong, blinn,  one linear operator: each output texel is a row of weights over one
 *   ggx            area-weighted box mip of the source, the lobe integrated over each texel
 *                  ("Spherical Phong kernel"). The cube's 48 symmetries carry the rows of one
 *                  octant of face +X onto every other texel (symmetry.c), so weights are
 *                  computed and stored for 1/48 of the rows; a row is a list of chunks of eight
 *                  consecutive texels of one face row, read from the mip's planar image or its
 *                  transpose, forward or with the weights reversed (lobe_rows.c; the products
 *                  in lobe_kernels.c).
 *
 * Edge fixups are tables too (fixup_tables.c), and the plan keeps the weights of a 3..5-band
 * SH projection of the source's 8x8x6 box mip (the talk's "small cube" for the diffuse SH).
 * dynamic.c holds the plan object and the order of a run; the entry points are declared in
 * specular_internal.h (ibl__dynamic_*). docs/SPECULAR.md "Dynamic path". */
#ifndef IBL_BAKE_SPECULAR_DYNAMIC_INTERNAL_H
#define IBL_BAKE_SPECULAR_DYNAMIC_INTERNAL_H

#include "bake/specular_internal.h"
#include "core/cpu.h"

#include <stdint.h>

/* ---- the cube's symmetries (symmetry.c) ---- */

enum { DYN_SYMMETRIES = 48 };

/* What one symmetry does to the texels of one face: the face it goes to, and how texel
 * coordinates (x, y) of a face of edge M map. Without swap: x' = x or M-1-x (flip_x),
 * y' = y or M-1-y (flip_y). With swap: x' = y or M-1-y (flip_y), y' = x or M-1-x (flip_x):
 * flip_x always mirrors the coordinate that came from x. */
typedef struct dyn_face_map {
    uint8_t target, swap, flip_x, flip_y;
} dyn_face_map;

typedef struct dyn_symmetries {
    dyn_face_map map[DYN_SYMMETRIES][6];
} dyn_symmetries;

void ibl__dyn_symmetries(dyn_symmetries *out);
/* A face's frame: its centre direction m and the steps s, t from the centre to the middle
 * of its +x and +y edges (point = m + u s + v t for face coordinates u, v in [-1, 1]). */
typedef struct dyn_face_frame {
    double m[3], s[3], t[3];
} dyn_face_frame;
void ibl__dyn_face_frame(int face, dyn_face_frame *out);
/* Texel (x, y) of face `face` (edge M) carried by a face map. */
void ibl__dyn_map_texel(const dyn_face_map *m, int M, int x, int y, int *mx, int *my);
/* The representative of output texel (face, x, y) of edge n: texel (a, b) of face 0 with
 * a <= b <= (n-1)/2, and a symmetry carrying it there. */
void ibl__dyn_fold(const dyn_symmetries *sym, int n, int face, int x, int y, int *a, int *b,
                   int *symmetry);
/* The index of the representative (a, b), a <= b: rows of the octant in order. */
static inline int ibl__dyn_rep_index(int a, int b) { return b * (b + 1) / 2 + a; }
/* Representatives of an edge n: (h + 1)(h + 2) / 2 with h = (n - 1) / 2. */
static inline int ibl__dyn_rep_count(int n)
{
    int h = (n - 1) / 2;
    return (h + 1) * (h + 2) / 2;
}

/* ---- the lobe operator (lobe_rows.c) ---- */

enum { DYN_CHUNK = 8, DYN_GUARD = 16 /* floats before and after a mip's images */ };

/* A source mip as the products read it (dynamic.c builds it every run): DYN_GUARD zeros,
 * planes R, G, B of the six faces (row-major, face after face), the same three planes of
 * every face transposed, DYN_GUARD zeros; a plane holds 6 M^2 floats. One output level summed
 * by symmetric rows keeps, per chunk of each output texel, a code (offset << 1) | reversed:
 * the offset of the R sample of the chunk's first lane from the buffer's start, and whether
 * the reversed weights apply. */
typedef struct dyn_lobe_level {
    int edge, mip;
    int reps;
    uint32_t *rep_chunks; /* reps + 1: the first chunk of each representative            */
    float *weights;       /* 8 per chunk, normalised so that each row sums to 1           */
    float *reversed;      /* the same, each chunk's eight lanes reversed                  */
    float *weight_memory; /* the block holding both                                       */
    uint32_t *row_rep;    /* per output texel (face, y, x): its representative            */
    uint32_t *row_codes;  /* per output texel + 1: the first of its chunk codes           */
    uint32_t *codes;
} dyn_lobe_level;

typedef struct dyn_lobe_stats {
    size_t rep_chunks, row_chunks, taps;
} dyn_lobe_stats;

/* Builds the operator of one level: output edge n, lobe, source mip of edge M (source level
 * `mip`); texels where the lobe's mean stays under floor_value (of its peak) are left out. */
ibl_status ibl__dyn_lobe_level_create(ibl_context *ctx, const ibl_specular_desc *desc,
                                      const ibl__lobe *lobe, const dyn_symmetries *sym, int n,
                                      int mip, int M, double floor_value, dyn_lobe_level *out,
                                      dyn_lobe_stats *stats);
void ibl__dyn_lobe_level_destroy(ibl_context *ctx, dyn_lobe_level *level);

/* The row products (lobe_kernels.c): out[0..2] = the sum over the row's chunks of the chunk's
 * weights (from `weights` or `reversed`, the representative's first chunk) times eight floats
 * of each plane at buffer + (code >> 1). */
typedef void (*dyn_row_product_fn)(const float *buffer, size_t plane, const uint32_t *codes,
                                   int count, const float *weights, const float *reversed,
                                   float out[3]);
void ibl__dyn_row_product_portable(const float *buffer, size_t plane, const uint32_t *codes,
                                   int count, const float *weights, const float *reversed,
                                   float out[3]);
#if IBL_HAVE_X86_KERNELS
void ibl__dyn_row_product_avx2(const float *buffer, size_t plane, const uint32_t *codes, int count,
                               const float *weights, const float *reversed, float out[3]);
#endif

/* ---- the box chain and the Gaussian blur (box_chain.c) ---- */

/* A chain of `levels` levels of edge `edge` from sources of edge source_edge (a power-of-two
 * multiple of edge): level 0 the block means of ratio x ratio source texels (the source itself
 * when the ratio is 1), then 2 x 2 means; optionally every level blurred within its faces. */
typedef struct dyn_box_chain {
    int source_edge, edge, levels, ratio;
    double *block_weights;                /* ratio > 1: source texel solid angles (m^2)     */
    double *block_sums;                   /* ratio > 1: their sums per level-0 texel        */
    double *mip_weights[IBL_MAX_LEVELS];  /* level l >= 1: level l-1's texel solid angles   */
    double *mip_sums[IBL_MAX_LEVELS];     /* level l >= 1: their sums per texel             */
    ibl_cubemap chain;                    /* the box chain (level 0 unused at ratio 1)      */
    int radius[IBL_MAX_LEVELS];           /* Gaussian: 0 = the level is the box level       */
    double *kernel[IBL_MAX_LEVELS];       /* radius + 1 weights                             */
    double *line_sums[IBL_MAX_LEVELS];    /* edge: the kernel's sum at each position        */
    float *blur_scratch;                  /* one level's faces, between the two passes      */
} dyn_box_chain;

/* blur_phong_exponents: NULL for the box chain, else the Phong exponent of every level
 * (ibl__gauss_sigma gives the blur). */
ibl_status ibl__dyn_box_chain_create(ibl_context *ctx, int source_edge, int edge, int levels,
                                     const float *blur_phong_exponents, dyn_box_chain *chain);
void ibl__dyn_box_chain_destroy(ibl_context *ctx, dyn_box_chain *chain);
/* Levels 0 .. levels-1 of the box chain of src. */
void ibl__dyn_box_chain_build(dyn_box_chain *chain, ibl_context *ctx, const ibl_cubemap *src,
                              int levels);
/* A face of a built level (level 0 at ratio 1: src's). */
const float *ibl__dyn_box_chain_face(const dyn_box_chain *chain, const ibl_cubemap *src, int level,
                                     int face);
/* dst's level: the chain's level, blurred if it has a kernel. */
void ibl__dyn_box_chain_output(dyn_box_chain *chain, ibl_context *ctx, const ibl_cubemap *src,
                               ibl_cubemap *dst, int level);

/* ---- edge fixups as tables (fixup_tables.c) ---- */

enum { DYN_FIXUP_MEAN = 0 /* equal weights */, DYN_FIXUP_DEEP /* overlap2's second row */ };

/* Texels blended together: indices (face, y, x) into one level, in canonical order. */
typedef struct dyn_fixup_group {
    uint32_t texel[3];
    uint8_t count, kind;
} dyn_fixup_group;

typedef struct dyn_fixup {
    int edge, groups;
    ibl_edge_fixup method;
    dyn_fixup_group *group;
} dyn_fixup;

/* The groups of one level of edge n (none for NONE, BENT, WARP: those only average a 1x1
 * level). The same result as ibl_edge_fixup_apply, bit for bit. */
ibl_status ibl__dyn_fixup_create(ibl_context *ctx, ibl_edge_fixup fixup, int n, dyn_fixup *out);
void ibl__dyn_fixup_destroy(ibl_context *ctx, dyn_fixup *f);
/* level: the level's six faces of RGBA. */
void ibl__dyn_fixup_apply(const dyn_fixup *f, float *level);

#endif
