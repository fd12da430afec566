/* The specular sources' shared types (specular_sources.c makes them, specular_sources_apply.c
 * adds their refinement to a chain): see specular_sources.c for the method. */
#ifndef IBL_SPECULAR_SOURCES_INTERNAL_H
#define IBL_SPECULAR_SOURCES_INTERNAL_H

#include "specular_internal.h"

#include <stddef.h>

/* The region's texels (one group each) at most; see BRIGHT_PEAK_SHARE in specular_sources.c. */
#define MAX_REGION_TEXELS 256
/* A Phong near field is summed NEAR_LANES cells at a time (independent lanes the compiler
 * vectorizes). */
#define NEAR_LANES 8

typedef struct source_group {
    double centre[3]; /* unit mean direction of its cells       */
    double radius;    /* largest angle of a cell from centre    */
    double energy[3]; /* sum of the cells' weights per channel  */
    double moment[3][3]; /* [channel][axis]: sum w (l - centre) */
    double *cell;     /* 6 per cell: unit direction, weight (solid angle x radiance) RGB */
    size_t count;
    /* the cells again as six float planes of `padded` (a multiple of NEAR_LANES, the rest zero):
     * the offset d - centre (x, y, z) and the weight (r, g, b), for the Phong near field */
    float *lanes;
    size_t padded;
} source_group;

struct ibl_specular_sources {
    ibl_context *ctx;
    ibl_specular_info info;
    int working_size;
    int groups;
    source_group *group;
    /* per level: its lobe, and whether it is refined (made once, each level on its own task:
     * a GGX lobe's set-up scans its slope at 4000 angles) */
    ibl__lobe lobe[IBL_MAX_LEVELS];
    int refined[IBL_MAX_LEVELS];
};

/* int f dl over the sphere, in closed form (specular_sources.c). */
double ibl__sources_lobe_normaliser(const ibl__lobe *lobe);

#endif
