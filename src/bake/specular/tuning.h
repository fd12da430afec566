/* Every tuning constant of the fast prefilter, in one table: what each one decides and why it
 * has its value. The accuracy constants were chosen by measuring the six test HDRIs at 128
 * and 256 against the reference (docs/SPECULAR.md "Accuracy"): with them every level of ggx,
 * phong and blinn stays within 0.44% RMS and 3.2% max, and docs/SPECULAR.md lists the coarser
 * settings that failed that bar. The capacities and chunk sizes were chosen by timing the 256
 * and 512 chains (docs/SPECULAR.md "Known limits" has the alternatives that lost).
 *
 * Widths are angles in radians; "b" is a ring's inner radius. ibl_specular_desc.accuracy
 * scales every width and bar below by accuracy / ACCURACY_DEFAULT. */
#ifndef IBL_SPECULAR_TUNING_H
#define IBL_SPECULAR_TUNING_H

/* ---- the accuracy knob ---- */

/* desc.accuracy = 0 means this value; the widths and bars below are the ones it gives */
#define ACCURACY_DEFAULT 0.35

/* ---- where the lobe's pieces are summed (pieces.c) ---- */

/* The core is summed over the coarsest source level whose texels are at most 1/2.5 of the
 * lobe's half width: 1.4 texels per half width gave 0.89% RMS at level 1 of interior, 1.7 gave
 * 0.53% RMS; 2.5 keeps the worst level under 0.44%. */
#define CORE_TEXELS_PER_HALF_WIDTH 2.5
/* The core's step (the partition's first psi) starts at 2 half widths: ending it at 1.5 made
 * blinn level 0 of night 5.5% max. */
#define CORE_END_HALF_WIDTHS 2.0
/* ... and never inside 2 mean texels of the core's level: a core narrower than that would be
 * a handful of texels whose second-order leaves cannot follow the step. */
#define CORE_END_MIN_TEXELS 2.0
/* Neither a core nor a ring reads a level of fewer than 16 texels a face edge: coarse texels
 * that straddle the horizon, where the lobe has a kink, are what a Taylor leaf gets wrong
 * (cores from 8-texel faces: 8.6% max on night, blinn level 5). */
#define MIN_SOURCE_EDGE 16

/* A ring is smooth on the scale of b, so it is summed over texels at most 0.6 b wide ... */
#define RING_SOURCE_TEXEL 0.6
/* ... or 0.45 b when its weights are precomputed: a finer level has fewer centroid corrections
 * but more weights; 0.3 b made the 512 chain 1.2x slower, 0.6 b gave level 1 of 256 fifteen
 * times the corrections. */
#define RING_SOURCE_TEXEL_PRECOMPUTED 0.45
/* ... for rings whose outer edge is inside 1.1 radians (and centred output directions): a ring
 * reaching further may pass PRECOMPUTED_MAX_REACH once a texel is added and be summed by
 * leaves, which the finer level would only make slower. */
#define RING_PRECOMPUTED_MAX_ANGLE 1.1
/* A ring is evaluated on a cube grid spaced at most 0.2 b, then bilinearly interpolated: a grid
 * of 0.4 b with every texel in it gave 8.5% max at level 1 of night. */
#define RING_GRID_SPACING 0.2
/* ... or 0.6 b when its bright texels are summed apart (gathering.c): the smooth remainder
 * interpolates well; without the bright texels apart, 0.6 b gave 1.6% RMS and 23% max (night). */
#define RING_GRID_SPACING_BRIGHT_APART 0.6
/* The bright texels of such a ring are summed at the output texels, or on a grid spaced at most
 * 0.08 b when that is coarser: the bilinear error, ~(0.08 / 0.6)^2 of the 20-35% it removes. */
#define BRIGHT_GRID_SPACING 0.08
/* The core is summed on the output texels, or on a cube grid spaced at most 0.08 of the lobe's
 * half width when the output is finer than that, then interpolated: the core's result varies on
 * the scale of its half width, and a core at every output texel made a wide lobe's cost grow
 * with the output's texels (Phong level 0 of 1024: 94 M weights, where the same lobe at 512 has
 * 23 M). On the sun test cube a grid at 0.122 of the half width added 0.23% RMS and 0.9% max
 * to the core on the output texels (Phong 40 at 128: 0.06% / 1.06%); the error goes as the
 * spacing squared, so 0.08 keeps it near 0.1%. */
#define CORE_GRID_SPACING 0.08
/* A Phong core nil before the horizon is read by 6-point Lagrange interpolation per axis
 * (combine.c) from a grid spaced at most 0.45 of its half width: cos^n is close to a Gaussian of
 * sigma = 0.85 half widths, and a Gaussian sampled 0.73 sigma apart (0.45 half widths where the
 * grid is widest, a face centre: 1.38 times the mean) is interpolated within 6.5e-3 of its peak
 * per axis (9e-4 at 0.31 half widths; bilinear at 0.08 left 2e-3, Catmull-Rom at 0.31 4e-3, which
 * cost up to 0.25% RMS on level 0 of the 256 chain). The 256 chain's level 0 (exponent 1000) is
 * summed on 128 points a face edge instead of 256, and so, since 0.45 rather than 0.31, is cmft's
 * exponent 2049 at 256 (4.6 output texels a half width: 0.435 half widths; with its core's
 * weights at every output texel the chain cost 2.4x GGX's). Measured on the six test HDRIs at 256
 * (docs/SPECULAR.md "Accuracy"): that level went from 0.28% to 0.39% RMS at worst (interior)
 * and from 3.0% to 3.7% max (night); the other chains' grids are the same at 0.31 and 0.45. */
#define CORE_GRID_SPACING_LAGRANGE 0.45
/* The centroid corrections of a smooth Phong core on the output texels (its grid would not be
 * coarser) are summed in difference form on a Lagrange grid of half the output's edge when it is
 * at most this many half widths apart: the difference varies on the lobe's scale. cmft's
 * exponent 862 at 128 (0.56 half widths on 64 points): on the six test HDRIs at most 0.263% RMS
 * and 2.09% max (interior, night), against 0.234% and 2.13% with its 318 blocks (city.exr) at
 * the output texels, for 38 M fewer leaf instructions. */
#define CORRECTION_GRID_SPACING_LAGRANGE 0.6
/* Lagrange grids have at least 32 points a face edge: on 16 the face's own curvature (texels
 * 1.38 times the mean at its centre, 0.6 at its corners) cost phong level 3 of the 256 chain
 * (exponent 15.6) 0.2% RMS and up to 2.8% max. */
#define MIN_LAGRANGE_GRID_EDGE 32
/* The centroid corrections of a core on the output texels are summed, as the difference of a
 * texel's moment and uniform leaves, on a grid spaced at most 0.2 of the lobe's half width when
 * that is coarser than the output, then interpolated: the difference varies on the lobe's scale,
 * not the output's, and a corrected texel summed at every output texel in a core's reach cost
 * in proportion to the output's texels (Phong, level 0 of 512: 913 blocks, 0.93 of 1.6 CPU s). */
#define CORRECTION_GRID_SPACING 0.2
/* No grid is coarser than 8 texels a face edge (a coarser one would not see a face's curve). */
#define MIN_GRID_EDGE 8
/* Phong rings stop where the lobe falls below 1e-9 of its peak (x^n dies fast; GGX's long tail
 * goes to the horizon). */
#define PHONG_CULL 1e-9
/* The AVX2 kernels evaluate the Phong pieces that end before u = 0.1 by series in u (ln x to
 * u^6 / 6, kernels_avx2.c), when the first dropped term moves f by at most 1e-6 of itself at
 * the piece's end: the pieces of lobes from n ~ 200 on, whose leaves are most of the narrow
 * levels' work (cmft's exponents 2049, 862 and 363 at 256). */
#define PHONG_SERIES_MAX_U 0.1
#define PHONG_SERIES_MAX_ERROR 1e-6
/* Steps of the tabulated piece (portable kernels and the bars): the portable and AVX2 sums then
 * differ by ~1e-4 of a value. */
#define PIECE_TABLE_STEPS 2048
/* At most one core and 23 rings per level: dyadic rings (4x in u) from the narrowest core reach
 * the horizon in fewer. */
#define MAX_PIECES 24

/* ---- the working source (plan.c, ibl_specular_source_size) ---- */

/* A source finer than the chain needs is reduced by area means to 2^3 times the edge of the
 * finest level a core reads: the reduced texel puts its light at its centre where the pyramid
 * built from the full source keeps its luminance centroid, an error that falls ~8x per level
 * of margin. GGX 8 chains from 256, 512 and 1024 cubes of night.exr (point lights), level 1
 * against the plan at the full source: 1 level finer, 4.5% RMS and 59% max; 2 levels, 0.71% /
 * 10%; 3 levels, 0.069% / 0.96%; 4 levels, 0.012% / 0.18% (city, sunset: 5-15x less). Three
 * keeps the reduction's error a sixth of the method's own RMS bar above. */
#define SOURCE_LEVELS_BELOW_CORE 3

/* ---- sub-texels (plan.c) ---- */

/* A lobe narrower than 1.5 source texels is summed over k x k sub-texels of the source (each with
 * its parent's radiance), as the reference splits such texels; k at most 8, and the split
 * source at most 4096 texels a face edge. */
#define SUBTEXEL_BELOW_TEXELS 1.5
#define SUBTEXEL_MAX_SPLIT 8
#define SUBTEXEL_MAX_EDGE 4096

/* ---- leaf sums (leaf_sums.c) ---- */

/* Output points are summed in tiles of 8 x 8: one reach test per tile and block. */
#define TILE_EDGE 8
/* Candidate blocks gathered per tile before they are summed (a stack array). */
#define CANDIDATE_BATCH 1024

/* ---- precomputed weights (precomputed.c, products.c) ---- */

/* A piece reaching beyond 1.2 radians is summed by leaves: the opposite face could be in reach,
 * and the padded face holds only the four neighbours. */
#define PRECOMPUTED_MAX_REACH 1.2
/* ... and so is one whose weights (with their cells and rows) would take more than half of
 * what the context's memory budget has left. Nothing else caps them: a base texel's weights
 * are bounded by the source level's rule (cores: 2.5-5 texels a half width; rings: 0.45 b), so
 * they grow with the grid's points, and a leaf costs ~10x a weight and serves one point where a
 * weight serves 24 (the 1024 chain's level 1 has 44 M weights: as leaves, 5.5 CPU s; as
 * weights, 0.6). */
#define PRECOMPUTED_BUDGET_SHARE 0.5
/* The window scanned for a base texel's rows: 1.1 times its reach in local texels, plus 2 (the
 * whole border when something lies on the window's edge: the rows found are the same whatever
 * the margin). 1.3 scanned 1.4 times the cells: at 256, 12.6 M more instructions for cmft's
 * exponents, 7 M for GGX. */
#define PRECOMPUTED_WINDOW_MARGIN 1.1
/* Weights are stored as half floats divided by twice the piece's peak times the largest texel
 * (the second-order term can add a little to the peak): stored values are then at most ~1,
 * where half floats keep 11 bits. */
#define WEIGHT_BOUND_FACTOR 2.0
/* A one-shot plan's core that finds its weights at the run (normalisers_at_run) keeps the padded
 * geometry its rows were found on until then when it takes at most 8 MiB (11 floats a padded
 * cell: 5.8 MB for cmft's exponent 2049, whose core reads 256 texels a face edge at any output
 * size), instead of making it again: 3 ms of one thread for that core at 256. Only the first
 * such level keeps it (precomputed.c): a later level's would sit beside the first level's
 * products, where cmft's chain at 256 peaks (4.1 MB of levels 1-4's, for ~2 ms of one thread). */
#define KEPT_GEOMETRY_BYTES (8u << 20)
/* Rows of the padded source transposed per task (the transposed copy serves the mirror bases). */
#define TRANSPOSE_ROWS 16
/* A one-shot plan's level sums a face a task, each in a padded buffer of its thread's, only when
 * its pieces' weights (each applied to every face) number at least this many a cell of its
 * largest padded face: the products then read the face enough for its staying in one core's
 * cache to pay for the second buffer. The 256 GGX chain's level 1 has 14.6 a cell (-1.4 ms on
 * two threads, 61 paired runs); the 128 chain's level 1 has 5.5 and gained nothing (-0.1 ms,
 * 95% interval -0.8 to +1.2) while the buffer's pages took its peak RSS from 32 to 36 MB. */
#define FACE_TASK_WEIGHTS_PER_CELL 8.0

/* ---- bright texels and centroid corrections (gathering.c) ---- */

/* A texel is bright for a ring whose bright texels go apart when its largest contribution to an
 * output exceeds 2% of the mean radiance. */
#define BRIGHT_BAR 0.02
/* At most 256 blocks of 8 bright texels per level: the bar is raised until they fit, so the
 * direct sum stays bounded. */
#define BRIGHT_BLOCKS 256
/* A precomputed piece over a coarse level reads its texels as uniform; a texel whose moment leaf
 * may differ from that by more than 1e-2 of the mean radiance is corrected leaf by leaf (5e-2
 * gave 0.61% RMS on interior's phong level 2; no corrections, 5.1% RMS on night). */
#define CORRECTION_BAR 1e-2
/* At most 2048 blocks of corrected texels per precomputed piece (the bar is raised to fit). */
#define CORRECTION_BLOCKS 2048
/* A Phong piece's corrected texels are gathered in blocks that span at most its reach (in
 * texels of its level, either axis, from the block's first texel): a block's cone covers its
 * texels' spread, and the block is summed at every grid point its cone reaches. Eight texels in
 * Morton order had cones of 13 texels on average on the 128 level of cmft's exponent 862 (reach
 * 14 texels). Spans of 0.25, 0.5, 0.75, 1 and 1.5 reaches took that level's corrections (the
 * 256 chain of city.exr, one thread) from 15.4 ms to 14.6, 12.2, 12.1, 11.9 and 12.1: more and
 * emptier blocks against narrower cones; at 1, levels 0 and 2 from 5.5 and 8.0 ms to 3.2 and
 * 7.3. */
#define GATHER_SPAN_OF_REACH 1.0
/* Gathered blocks are tested 16 at a time first, by a cone around the 16: one reach test per
 * tile against every gathered block was most of level 1's corrections at 512. */
#define SUPER_CONE_BLOCKS 16
/* Blocks per task of the correction bounds. */
#define BOUND_BLOCKS_PER_TASK 256

#endif
