/* Internal contract of the specular prefilter: the lobe math shared by the reference and the
 * fast method, what the fast method's plan (src/bake/specular/, its own types in
 * specular/fast_internal.h) shows the rest of the library and the tests, and the box and
 * Gaussian kernels implemented in specular_box.c / specular_gauss.c. */
#ifndef IBL_SPECULAR_INTERNAL_H
#define IBL_SPECULAR_INTERNAL_H

#include "ibl/specular.h"
#include "bake/specular_kernels.h"

/* The box and Gaussian kernels and the box chain's fitted shininess live in specular_box.c /
 * specular_gauss.c and are declared once, in specular_kernels.h. */

/* A radially symmetric lobe f(x) of x = cos(angle between the lobe axis and l), normalised to
 * f(1) = 1; zero for x <= 0. */
typedef enum ibl__lobe_kind {
    IBL__LOBE_MIRROR = 0, /* a delta: the level is the source resampled */
    IBL__LOBE_PHONG,      /* x^n                                         */
    IBL__LOBE_GGX         /* x D(h) / D(n), n.h = sqrt((1 + x) / 2)      */
} ibl__lobe_kind;

typedef struct ibl__lobe {
    ibl__lobe_kind kind;
    double n;           /* Phong exponent                               */
    double alpha;       /* GGX alpha = roughness^2                      */
    double k;           /* GGX: (alpha^2 - 1) / 2                       */
    double a4;          /* GGX: alpha^4                                 */
    double cull_angle;  /* f < 1e-12 beyond this angle (radians)        */
    double peak_angle;  /* angle where |d log f / d angle| peaks (GGX)  */
    double half_angle;  /* angle where f = 1/2: the blur radius         */
    double floor_angle; /* angle where f = 0.02                         */
    double horizon;
} ibl__lobe;

/* The lobe of one level of the chain info describes (MIRROR for roughness 0 / no shininess). */
ibl__lobe ibl__lobe_for_level(const ibl_specular_info *info, int level);
/* The lobes of levels [0, levels), made in parallel: the same as ibl__lobe_for_level's (a GGX
 * lobe's peak search is a 4000-point scan of sin, cos and tan, ~0.1 ms a level). */
void ibl__lobes_for_levels(ibl_context *ctx, const ibl_specular_info *info, int levels, ibl__lobe *out);
/* Whether ibl__lobe_for_level(info, level) is a mirror, without making the lobe. */
int ibl__level_is_mirror(const ibl_specular_info *info, int level);
/* f, f', f'' at x (double). */
double ibl__lobe_f(const ibl__lobe *lobe, double x);
void ibl__lobe_f012(const ibl__lobe *lobe, double x, double out[3]);
/* |d log f / d theta| at angle theta (the lobe's local scale is its inverse). */
double ibl__lobe_log_slope(const ibl__lobe *lobe, double theta);
/* Upper bound of the log slope over [t0, t1]. */
double ibl__lobe_max_log_slope(const ibl__lobe *lobe, double t0, double t1);

/* Angular radius of the face-plane rectangle [u0,u1]x[v0,v1] seen from its centre direction. */
double ibl__rect_radius(int face, double u0, double v0, double u1, double v1, double centre[3]);

/* The reference's precomputed source geometry. */
struct ibl_specular_reference {
    ibl_context *ctx;
    const ibl_cubemap *src;
    int n, blocks;      /* source face edge; blocks per face edge           */
    double *dir;        /* 6 n n x 3: texel centre directions (unit)        */
    double *omega;      /* n n: texel solid angles (same on every face)     */
    double *radius;     /* n n: texel angular radii                         */
    double max_radius;  /* the largest of them                              */
    double *block;      /* 6 blocks^2 x 4: block centre direction, radius   */
};
void ibl__reference_eval_lobe(const ibl_specular_reference *ref, const ibl__lobe *lobe,
                              const double dir[3], double out[4]);
/* Reference for whole levels. */
ibl_status ibl__specular_reference(ibl_context *ctx, const ibl_cubemap *src,
                                   const ibl_specular_desc *desc, const ibl_specular_info *info,
                                   ibl_cubemap *dst);

/* The direction the kernel of texel (x, y) is centred on (edge fixups bend it). */
void ibl__output_direction(const ibl_specular_desc *desc, const ibl__lobe *lobe, int face, int n,
                           int x, int y, double dir[3]);

/* What a static plan does (tests: which paths a configuration exercises); the block counts are
 * those of the last run. */
typedef struct ibl__specular_stats {
    int pieces;             /* core and rings of every level                           */
    int precomputed;        /* summed by precomputed weights                           */
    int precomputed_coarse; /* ... over a coarse level (with centroid corrections)      */
    int split;              /* rings on coarse grids whose bright texels go direct      */
    int bright_blocks, correction_blocks;
    int coarse_cores;       /* cores on a grid coarser than the output, interpolated    */
    int difference_corrections; /* precomputed pieces whose corrections ran in difference
                                 * form on a coarser grid (last run)                   */
} ibl__specular_stats;
void ibl__specular_plan_stats(const ibl_specular_plan *plan, ibl__specular_stats *out);

/* A plan for a single run (one_shot, ibl_specular_prefilter): it keeps less between its steps
 * and makes the rest when the run needs it, so that its largest buffers never coexist
 * (src/bake/specular/fast_internal.h, ibl_specular_plan.one_shot). Its run in two steps: the
 * pyramid and every level's grids (no output needed yet), then the output levels from the
 * grids; ibl_specular_plan_run is both. */
ibl_status ibl__specular_plan_create(ibl_context *ctx, const ibl_specular_desc *desc,
                                     int one_shot, ibl_specular_plan **out);
ibl_status ibl__specular_plan_run_grids(ibl_specular_plan *plan, const ibl_cubemap *src);
ibl_status ibl__specular_plan_run_output(ibl_specular_plan *plan, const ibl_cubemap *src,
                                         ibl_cubemap *dst);
/* The one-shot plan a prepared chain holds (NULL for the methods without one) and the edge of
 * the working source it wants: for bench/bench_stages.c, which runs it step by step. The
 * prepared chain keeps it (ibl_specular_prepared_destroy frees both). */
ibl_specular_plan *ibl__specular_prepared_plan(const ibl_specular_prepared *prepared, int *edge);

/* The dynamic path (specular_dynamic/): every filter as a plan whose run allocates nothing
 * (box and gauss chains with precomputed tables, the lobes as symmetric sparse operators over
 * box mips; edge fixups included). */
typedef struct ibl__dynamic ibl__dynamic;
ibl_status ibl__dynamic_create(ibl_context *ctx, const ibl_specular_desc *desc,
                               const ibl_specular_info *info, int source_size, ibl__dynamic **out);
/* Every level of dst, edge fixups applied. */
ibl_status ibl__dynamic_run(ibl__dynamic *d, const ibl_cubemap *src, ibl_cubemap *dst);
/* Non-zero weights and 8-wide chunks the lobe operator holds (0 for box and gauss). */
void ibl__dynamic_stats(const ibl__dynamic *d, size_t *taps, size_t *row_chunks);
void ibl__dynamic_destroy(ibl__dynamic *d);

/* The most levels desc's mapping can make distinct (IBL_MAX_LEVELS when unbounded). */
int ibl__mapping_distinct_levels(const ibl_specular_desc *desc);
/* ibl_specular_level_phong_exponent in double, the exponent the Phong-family lobes filter with */
double ibl__level_phong_exponent(const ibl_specular_info *info, int level);
/* Fills info from desc for a chain of the given output size and levels. */
ibl_status ibl__specular_mapping(ibl_context *ctx, const ibl_specular_desc *desc, int size,
                                 int levels, ibl_specular_info *info);

#endif
