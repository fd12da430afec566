/* Study 5: the cost of tri-Ace 2010's six "Implemented configurations" (ibl_specular_preset),
 * on one thread of this machine: a one-shot ibl_specular_prefilter of a 64² source (the talk
 * refilters dynamic probes from a 64x64x6 cube; its static 64² configuration needs no less), and
 * the per-frame path, a plan created once and ibl_specular_plan_run per frame (the dynamic
 * plan, desc.dynamic, for the dynamic configurations). Medians of several runs. */
#include "studies.h"

#include <stdlib.h>

enum { SOURCE = 64 };

typedef struct preset_time {
    double oneshot, levels, plan_create, plan_run; /* ms */
    ibl_specular_info info;
} preset_time;

static int time_preset(const study_env *env, const ibl_cubemap *src, const char *name, int runs,
                       preset_time *t)
{
    ibl_specular_desc d;
    if (!ibl_specular_preset(name, &d)) return 1;
    double *ms = malloc((size_t)runs * sizeof *ms);
    if (!ms) return 1;
    ibl_status st = IBL_OK;
    for (int r = 0; r < runs && st == IBL_OK; r++) {
        ibl_cubemap out;
        double t0 = study_now_ms();
        st = ibl_specular_prefilter(env->ctx, src, &d, &out, &t->info);
        ms[r] = study_now_ms() - t0;
        if (st == IBL_OK) ibl_cubemap_free(env->ctx, &out);
    }
    t->oneshot = study_median(ms, runs);
    /* of which: the level parameters alone (the mapping, no filtering) */
    for (int r = 0; r < runs && st == IBL_OK; r++) {
        ibl_specular_info info;
        double t0 = study_now_ms();
        st = ibl_specular_levels(env->ctx, &d, src->size, &info);
        ms[r] = study_now_ms() - t0;
    }
    t->levels = study_median(ms, runs);
    d.source_size = SOURCE;
    d.dynamic = name[0] == 'd'; /* the "dynamic-*" configurations */
    ibl_specular_plan *plan = NULL;
    double t0 = study_now_ms();
    if (st == IBL_OK) st = ibl_specular_plan_create(env->ctx, &d, &plan);
    t->plan_create = study_now_ms() - t0;
    ibl_cubemap dst = {0};
    if (st == IBL_OK) st = ibl_cubemap_alloc(env->ctx, d.size, ibl_specular_plan_info(plan)->levels, &dst);
    for (int r = 0; r < runs && st == IBL_OK; r++) {
        t0 = study_now_ms();
        st = ibl_specular_plan_run(plan, src, &dst);
        ms[r] = study_now_ms() - t0;
    }
    t->plan_run = study_median(ms, runs);
    ibl_cubemap_free(env->ctx, &dst);
    ibl_specular_plan_destroy(plan);
    free(ms);
    return st == IBL_OK ? 0 : study_fail(env, name, st);
}

int study_speed(const study_env *env)
{
    static const char *const presets[] = {"dynamic-box16",  "dynamic-gauss32", "dynamic-phong16",
                                          "dynamic-phong32", "static-phong32",  "static-phong64"};
    ibl_cubemap src;
    if (study_load_cube(env, "forest.exr", SOURCE, &src)) return 1;
    FILE *md = study_fragment(env, "speed");
    if (!md) {
        ibl_cubemap_free(env->ctx, &src);
        return 1;
    }
    int runs = env->quick ? 3 : 15, rc = 0;
    fprintf(md, "| preset | kernel | face | levels | shininess | edge fixup | one-shot prefilter | of which "
                "level parameters | plan created once | per frame (plan run) |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for (size_t i = 0; i < sizeof presets / sizeof presets[0] && !rc; i++) {
        preset_time t;
        ibl_specular_desc d;
        ibl_specular_preset(presets[i], &d);
        rc = time_preset(env, &src, presets[i], runs, &t);
        if (rc) break;
        fprintf(md, "| %s | %s | %d² | %d | %g–%g | %s | %.2f ms |", presets[i],
                ibl_specular_filter_name(t.info.filter), t.info.size, t.info.levels,
                (double)t.info.shininess_min, (double)t.info.shininess_max,
                ibl_edge_fixup_name(d.edge_fixup), t.oneshot);
        fprintf(md, " %.3f ms |", t.levels);
        fprintf(md, " %.1f ms | %.3f ms |\n", t.plan_create, t.plan_run);
    }
    fprintf(md, "\nOne thread (`ibl_context_desc.threads = 1`), 64² source, median of %d runs.\n", runs);
    ibl_cubemap_free(env->ctx, &src);
    if (rc) {
        fclose(md);
        return rc;
    }
    return study_fragment_close(env, md, "speed");
}
