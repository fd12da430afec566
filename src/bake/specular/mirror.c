/* Mirror levels: roughness 0 (or no shininess) has no lobe to filter with, so the level is the
 * source itself at the level's size -- the unfiltered level 0 of `--mirror`, or a mapping whose
 * first level has roughness 0 (docs/SPECULAR.md "Mirror"). This is the one place the fast
 * method writes such a level; level_is_mirror (fast_internal.h) is the one test, and a mirror
 * level has no pieces, grids or weights.
 *
 * At the source's size the level is a copy. Smaller, at a power of two, it is the exact area
 * mean of the source texels it covers: the pyramid level of that size holds each texel's power
 * and solid angle (pyramid.c), or, when the plan does not keep that level (no piece reads it),
 * the mean is summed here from the source texels and level 0's solid angles. Any other size is sampled bilinearly here;
 * ibl_specular_prefilter (specular.c) replaces a smaller one whose size does not divide the
 * source's by the exact area mean, which needs memory a plan's run does not allocate. */
#include "bake/specular/fast_internal.h"

#include <string.h>

typedef struct mirror_job {
    const ibl_specular_plan *p;
    const ibl_cubemap *src;
    ibl_cubemap *dst;
    int level;
} mirror_job;

static void mirror_row_task(void *arg, int index)
{
    const mirror_job *job = arg;
    const ibl_specular_plan *p = job->p;
    int n = ibl_level_size(p->output_edge, job->level), face = index / n, y = index % n;
    float *row = ibl_cubemap_face(job->dst, job->level, face) + (size_t)y * n * 4;
    if (n == p->source_edge) {
        memcpy(row, ibl_cubemap_face(job->src, 0, face) + (size_t)y * n * 4, (size_t)n * 4 * sizeof(float));
        return;
    }
    if (n < p->source_edge && is_power_of_two(n)) {
        int l = 0;
        while ((p->pyramid[0].edge >> l) > n) l++;
        const source_level *s = &p->pyramid[l];
        if (!s->records) { /* a level the plan does not keep: the same mean from the source */
            int K = p->source_edge / n, S = p->source_edge;
            const float *src = ibl_cubemap_face(job->src, 0, face);
            for (int x = 0; x < n; x++) {
                double P[3] = {0, 0, 0}, om = 0;
                for (int cy = K * y; cy < K * (y + 1); cy++)
                    for (int cx = K * x; cx < K * (x + 1); cx++) {
                        float g[GEOMETRY_FIELDS];
                        level0_face_moments(p, cx, cy, g);
                        const float *L = src + ((size_t)cy * S + cx) * 4;
                        for (int c = 0; c < 3; c++) P[c] += (double)g[FIELD_SOLID_ANGLE] * L[c];
                        om += g[FIELD_SOLID_ANGLE];
                    }
                for (int c = 0; c < 3; c++) row[x * 4 + c] = (float)(P[c] / om);
                row[x * 4 + 3] = 1.0f;
            }
            return;
        }
        for (int x = 0; x < n; x++) {
            float om = s->records[record_index(s, face, x, y, FIELD_SOLID_ANGLE)];
            for (int c = 0; c < 3; c++)
                row[x * 4 + c] = s->records[record_index(s, face, x, y, FIELD_POWER + c)] / om;
            row[x * 4 + 3] = 1.0f;
        }
        return;
    }
    for (int x = 0; x < n; x++) {
        double d[3];
        ibl_cube_direction_d(face, (x + 0.5) / n, (y + 0.5) / n, d);
        ibl_vec3 v = {(float)d[0], (float)d[1], (float)d[2]};
        ibl_cubemap_sample_bilinear(job->src, 0, v, row + x * 4);
    }
}

void ibl__fast_mirror_level(ibl_specular_plan *p, const ibl_cubemap *src, ibl_cubemap *dst,
                            int level)
{
    mirror_job job = {p, src, dst, level};
    ibl_parallel_for(p->ctx, 6 * ibl_level_size(p->output_edge, level), mirror_row_task, &job);
}
