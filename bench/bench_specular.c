/* Specular prefilter benchmark: the fast method's error against the reference on real HDRIs
 * (the accuracy bar's measurement, docs/SPECULAR.md "Accuracy": per level, solid-angle weighted relative RMS per channel
 * and the largest texel error relative to max(reference, level mean), on a deterministic
 * sample of texels), the fast method's filtering time, and the dynamic plan's refilter time.
 *
 *   bench_specular [--sizes 128,256] [--samples 2000] [--filters ggx,phong,blinn]
 *                  [--threads N] [--accuracy A] [--levels L] [--dynamic]
 *                  [--table V,V,...] [--ref-cache DIR] FILE.exr ...
 *
 * --table gives the Phong-family chains a mapping table (e.g. cmft's exponents 2049 ... 3);
 * their cached references are then keyed by the table too.
 *
 * --ref-cache keeps the reference values of the sampled texels in DIR (one file per file,
 * size, filter, level), so that re-measuring a changed fast method costs seconds.
 */
#include "ibl/ibl.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + t.tv_nsec * 1e-9;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The reference at a list of sampled texels of one level, in parallel, optionally cached in a
 * file (the reference is slow; the fast method changes more often than the yardstick). */
typedef struct ref_job {
    const ibl_specular_reference *ref;
    const ibl_specular_info *info;
    int level, n;
    const size_t *idx;
    double *out;
} ref_job;

static void ref_task(void *arg, int index)
{
    const ref_job *j = arg;
    size_t t = j->idx[index];
    int f = (int)(t / ((size_t)j->n * j->n)), y = (int)(t / j->n % j->n), x = (int)(t % j->n);
    ibl_specular_reference_eval(j->ref, j->info, j->level, ibl_cube_texel_direction(f, j->n, x, y),
                                j->out + 4 * (size_t)index);
}

static void reference_samples(ibl_context *ctx, const char *cache_dir, const char *base, int size,
                              const char *filter, int src_size, int level,
                              const ibl_specular_reference *ref, const ibl_specular_info *info,
                              int n, const size_t *idx, size_t count, double *out)
{
    char path[1024] = "";
    if (cache_dir) {
        snprintf(path, sizeof path, "%s/%s_%d_%s_src%d_l%d_n%zu.ref", cache_dir, base, size,
                 filter, src_size, level, count);
        FILE *fp = fopen(path, "rb");
        if (fp) {
            size_t got = fread(out, 4 * sizeof(double), count, fp);
            fclose(fp);
            if (got == count) return;
        }
    }
    ref_job job = {ref, info, level, n, idx, out};
    ibl_parallel_for(ctx, (int)count, ref_task, &job);
    if (cache_dir) {
        FILE *fp = fopen(path, "wb");
        if (fp) {
            fwrite(out, 4 * sizeof(double), count, fp);
            fclose(fp);
        }
    }
}

static void dynamic_bench(void)
{
    /* tri-Ace 2010's dynamic 32x32x6 Phong chain (1-1000) refiltered from a 64-face cube, one core */
    ibl_context_desc cd = {0};
    cd.threads = 1;
    ibl_context *ctx;
    ibl_context_create(&cd, &ctx);
    ibl_cubemap src;
    ibl_cubemap_alloc(ctx, 64, 1, &src);
    for (size_t i = 0; i < ibl_cubemap_floats(64, 1); i++) src.data[i] = (float)((i * 2654435761u) % 1000) / 100.0f;
    ibl_specular_desc d = {0};
    d.filter = IBL_FILTER_PHONG;
    d.size = 32;
    d.source_size = 64;
    d.dynamic = 1;
    double t0 = now();
    ibl_specular_plan *plan = NULL;
    if (ibl_specular_plan_create(ctx, &d, &plan) != IBL_OK) {
        fprintf(stderr, "plan: %s\n", ibl_context_message(ctx));
        exit(1);
    }
    double t_plan = now() - t0;
    int levels = ibl_specular_plan_info(plan)->levels;
    float *mem = malloc(ibl_cubemap_floats(32, levels) * sizeof(float));
    ibl_cubemap dst;
    ibl_cubemap_wrap(32, levels, mem, &dst);
    double times[51];
    for (int i = 0; i < 51; i++) {
        double a = now();
        ibl_specular_plan_run(plan, &src, &dst);
        times[i] = now() - a;
    }
    qsort(times, 51, sizeof(double), cmp_double);
    printf("dynamic phong 32x32x6 (%d levels) from 64: plan %.1f ms, refilter median %.3f ms "
           "(min %.3f) on 1 thread\n", levels, t_plan * 1e3, times[25] * 1e3, times[0] * 1e3);
    free(mem);
    ibl_specular_plan_destroy(plan);
    ibl_cubemap_free(ctx, &src);
    ibl_context_destroy(ctx);
}

/* The command line: --sizes A,B --samples N --threads N --accuracy X --levels N --ref-cache
 * DIR --dynamic --filters ggx,phong,blinn FILE... */
typedef struct bench_options {
    int sizes[8], nsizes, samples, threads, dynamic, max_levels;
    float accuracy;
    float table[32];       /* --table: the Phong-family chains' mapping table */
    int table_count;
    unsigned table_key;    /* FNV-1a of the table's text, for the cache's file names */
    ibl_specular_filter filters[3];
    int nfilters;
    const char *files[64], *cache_dir;
    int nfiles;
} bench_options;

static void parse_options(int argc, char **argv, bench_options *o)
{
    *o = (bench_options){.sizes = {128, 256}, .nsizes = 2, .samples = 2000,
                         .filters = {IBL_FILTER_GGX, IBL_FILTER_PHONG, IBL_FILTER_BLINN}, .nfilters = 3};
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--sizes") == 0 && i + 1 < argc) {
            o->nsizes = 0;
            for (char *p = strtok(argv[++i], ","); p && o->nsizes < 8; p = strtok(NULL, ","))
                o->sizes[o->nsizes++] = atoi(p);
        } else if (strcmp(argv[i], "--samples") == 0 && i + 1 < argc) {
            o->samples = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
            o->threads = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--accuracy") == 0 && i + 1 < argc) {
            o->accuracy = (float)atof(argv[++i]);
        } else if (strcmp(argv[i], "--levels") == 0 && i + 1 < argc) {
            o->max_levels = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--ref-cache") == 0 && i + 1 < argc) {
            o->cache_dir = argv[++i];
        } else if (strcmp(argv[i], "--table") == 0 && i + 1 < argc) {
            o->table_key = 2166136261u;
            for (const char *c = argv[i + 1]; *c; c++) o->table_key = (o->table_key ^ (unsigned char)*c) * 16777619u;
            o->table_count = 0;
            for (char *p = strtok(argv[++i], ","); p && o->table_count < 32; p = strtok(NULL, ","))
                o->table[o->table_count++] = (float)atof(p);
        } else if (strcmp(argv[i], "--dynamic") == 0) {
            o->dynamic = 1;
        } else if (strcmp(argv[i], "--filters") == 0 && i + 1 < argc) {
            o->nfilters = 0;
            for (char *p = strtok(argv[++i], ","); p && o->nfilters < 3; p = strtok(NULL, ","))
                if (ibl_specular_filter_from_name(p, &o->filters[o->nfilters])) o->nfilters++;
        } else if (o->nfiles < 64) {
            o->files[o->nfiles++] = argv[i];
        }
    }
}

int main(int argc, char **argv)
{
    bench_options o;
    parse_options(argc, argv, &o);
    int *sizes = o.sizes, nsizes = o.nsizes, samples = o.samples, threads = o.threads;
    int dynamic = o.dynamic, max_levels = o.max_levels, nfilters = o.nfilters, nfiles = o.nfiles;
    float accuracy = o.accuracy;
    const ibl_specular_filter *filters = o.filters;
    const char *const *files = o.files;
    const char *cache_dir = o.cache_dir;
    if (dynamic) dynamic_bench();
    ibl_context_desc cd = {0};
    cd.threads = threads;
    ibl_context *ctx;
    ibl_context_create(&cd, &ctx);
    printf("%-12s %5s %-6s %5s %10s %9s %9s %7s\n", "file", "size", "filter", "level", "param",
           "rms%", "max%", "texels");
    double worst_rms = 0, worst_max = 0;
    for (int fi = 0; fi < nfiles; fi++) {
        ibl_image img;
        if (ibl_read_image(ctx, files[fi], NULL, &img, NULL) != IBL_OK) {
            fprintf(stderr, "%s\n", ibl_context_message(ctx));
            return 1;
        }
        ibl_cubemap cube;
        ibl_to_cube_desc td = {0};
        if (ibl_image_to_cubemap(ctx, &img, &td, &cube) != IBL_OK) {
            fprintf(stderr, "%s\n", ibl_context_message(ctx));
            return 1;
        }
        ibl_image_free(ctx, &img);
        /* the prefilter works on a power-of-two source; give the reference the same one */
        int p = 1;
        while (p < cube.size) p *= 2;
        if (p != cube.size) {
            ibl_cubemap c2;
            ibl_cubemap_alloc(ctx, p, 1, &c2);
            ibl_cubemap_resample(ctx, &cube, &c2);
            ibl_cubemap_free(ctx, &cube);
            cube = c2;
        }
        ibl_specular_reference *ref = NULL;
        ibl_specular_reference_create(ctx, &cube, &ref);
        const char *base = strrchr(files[fi], '/');
        base = base ? base + 1 : files[fi];
        for (int si = 0; si < nsizes; si++) {
            for (int k = 0; k < nfilters; k++) {
                ibl_specular_desc d = {0};
                d.filter = filters[k];
                d.size = sizes[si];
                d.accuracy = accuracy;
                char filter_key[64];
                snprintf(filter_key, sizeof filter_key, "%s", ibl_specular_filter_name(filters[k]));
                if (o.table_count && filters[k] != IBL_FILTER_GGX) {
                    d.mapping = IBL_MAPPING_TABLE, d.table = o.table, d.table_count = o.table_count;
                    snprintf(filter_key, sizeof filter_key, "%s-table%08x",
                             ibl_specular_filter_name(filters[k]), o.table_key);
                }
                ibl_cubemap out;
                ibl_specular_info info;
                double t0 = now();
                if (ibl_specular_prefilter(ctx, &cube, &d, &out, &info) != IBL_OK) {
                    fprintf(stderr, "%s\n", ibl_context_message(ctx));
                    return 1;
                }
                double t_fast = now() - t0;
                printf("# %s %d %s: fast prefilter %.3f s (source %d)\n", base, sizes[si],
                       ibl_specular_filter_name(filters[k]), t_fast, cube.size);
                for (int l = 0; l < out.levels && (!max_levels || l < max_levels); l++) {
                    int n = ibl_level_size(out.size, l);
                    int mirror = filters[k] == IBL_FILTER_GGX ? !(info.roughness[l] > 1e-3f)
                                                              : !(info.shininess[l] > 0);
                    if (mirror) {
                        /* roughness 0: the source's exact area mean, no kernel to compare */
                        printf("%-12s %5d %-6s %5d %10s %9s %9s %7s\n", base, sizes[si],
                               ibl_specular_filter_name(filters[k]), l, "mirror", "-", "-", "-");
                        continue;
                    }
                    size_t total = (size_t)6 * n * n;
                    size_t count = total < (size_t)samples ? total : (size_t)samples;
                    double mean[4];
                    ibl_cubemap_mean(&out, l, mean);
                    double se[3] = {0}, sr[3] = {0}, mx = 0;
                    /* the sample depends on the level and the size only (log2(size) - 7:
                     * 0 for 128, 1 for 256), so that cached references stay valid whatever
                     * --sizes lists */
                    int size_key = 0;
                    while ((256 << size_key) <= sizes[si]) size_key++;
                    uint64_t state = 0x9E3779B97F4A7C15ull ^ (uint64_t)(l * 7919 + size_key * 104729);
                    size_t *idxs = malloc(count * sizeof *idxs);
                    double *refs = malloc(count * 4 * sizeof *refs);
                    for (size_t s = 0; s < count; s++) {
                        idxs[s] = s;
                        if (count < total) {
                            state = state * 6364136223846793005ull + 1442695040888963407ull;
                            idxs[s] = (size_t)((state >> 33) % total);
                        }
                    }
                    reference_samples(ctx, cache_dir, base, sizes[si], filter_key, cube.size, l,
                                      ref, &info, n, idxs, count, refs);
                    for (size_t s = 0; s < count; s++) {
                        size_t idx = idxs[s];
                        int f = (int)(idx / ((size_t)n * n)), y = (int)(idx / n % n), x = (int)(idx % n);
                        const double *r = refs + 4 * s;
                        const float *v = ibl_cubemap_face(&out, l, f) + ((size_t)y * n + x) * 4;
                        double w = ibl_cube_texel_solid_angle(n, x, y);
                        for (int c = 0; c < 3; c++) {
                            double e = v[c] - r[c];
                            se[c] += w * e * e;
                            sr[c] += w * r[c] * r[c];
                            double scale = fmax(r[c], mean[c]);
                            if (scale > 0 && fabs(e) / scale > mx) {
                                mx = fabs(e) / scale;
                                if (getenv("IBL_BENCH_WORST"))
                                    fprintf(stderr, "worst l%d f%d (%d,%d) c%d fast %g ref %g mean %g\n", l, f, x, y, c, v[c], r[c], mean[c]);
                            }
                        }
                    }
                    free(idxs);
                    free(refs);
                    double rms = 0;
                    for (int c = 0; c < 3; c++)
                        if (sr[c] > 0) rms = fmax(rms, sqrt(se[c] / sr[c]));
                    double param = filters[k] == IBL_FILTER_GGX ? info.roughness[l] : info.shininess[l];
                    printf("%-12s %5d %-6s %5d %10.4g %9.4f %9.3f %7zu\n", base, sizes[si],
                           ibl_specular_filter_name(filters[k]), l, param, 100 * rms, 100 * mx, count);
                    fflush(stdout);
                    if (rms > worst_rms) worst_rms = rms;
                    if (mx > worst_max) worst_max = mx;
                }
                ibl_cubemap_free(ctx, &out);
            }
        }
        ibl_specular_reference_destroy(ref);
        ibl_cubemap_free(ctx, &cube);
    }
    if (nfiles)
        printf("worst over all: rms %.4f%% (bar 0.5%%), max %.3f%% (bar 5%%)\n", 100 * worst_rms,
               100 * worst_max);
    ibl_context_destroy(ctx);
    return 0;
}
