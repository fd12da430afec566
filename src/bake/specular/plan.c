/* The public plan object of the specular prefilter (ibl_specular_plan_create / _run / _info /
 * _destroy, include/ibl/specular.h) and the order in which the fast method's mechanisms run.
 *
 * A plan fixes everything that depends on the sizes and the lobes only: the geometry of the
 * moment pyramid, the pieces of every level and their grids, the precomputed weights and the
 * normalisers, and every buffer a run needs; a run allocates nothing. A one-shot plan, made by
 * ibl_specular_prefilter for its single run, instead makes the records of the coarse levels
 * only the pyramid reads during the run and frees them as the pyramid goes, and keeps its
 * precomputed weights only while their products run (fast_internal.h, one_shot). With
 * desc.dynamic the plan
 * is instead the per-frame plan of specular_dynamic/. The fast method itself is
 * described in fast_internal.h and docs/SPECULAR.md "The fast method".
 *
 * Plan:  face frames -> sub-texel split -> moments of every pyramid level (geometry.c) ->
 *        per level: pieces and grids (pieces.c), precomputed weights (precomputed.c) ->
 *        run buffers -> level 0's records if a leaf sum reads them -> per level: normalisers
 *        (leaf_sums.c) and the bars of the gathered texels (gathering.c).
 * Run:   radiance pyramid (pyramid.c), level by level with its bright texels and the
 *        centroid corrections of the precomputed pieces over it (gathering.c) -> per filtered
 *        level: leaf sums (leaf_sums.c) and products (products.c) into its grids -> per
 *        level: the mirror (mirror.c) or the combination of the grids (combine.c), then the
 *        edge fixup. The grids are all filled before the output is written, so that a
 *        one-shot run (ibl_specular_prefilter) can allocate the output after its largest
 *        buffers are gone. */
#include "bake/specular/fast_internal.h"
#include "core/context_internal.h"
#include "core/cpu.h"

#include <string.h>

void ibl_specular_plan_destroy(ibl_specular_plan *p)
{
    if (!p) return;
    ibl_context *ctx = p->ctx;
    ibl__dynamic_destroy(p->dynamic);
    ibl_free(ctx, p->level0_geometry);
    ibl_free(ctx, p->padded_source);
    ibl_free(ctx, p->correction_pool);
    for (int l = 0; l < IBL_MAX_LEVELS; l++) {
        source_level *s = &p->pyramid[l];
        ibl_free(ctx, s->records);
        ibl_free(ctx, s->geometry);
        ibl_free(ctx, s->cones);
        ibl_free(ctx, s->row_power);
        ibl_free(ctx, s->uniform);
        ibl_free(ctx, s->uniform_not_bright);
        ibl_free(ctx, s->bright_records);
        ibl_free(ctx, s->bright_keys);
        ibl_free(ctx, s->bright_cones);
        level_plan *lv = &p->levels[l];
        for (int k = 0; k < lv->piece_count; k++) {
            ibl_free(ctx, lv->pieces[k].table);
            ibl__fast_precomputed_destroy(ctx, lv->pieces[k].precomputed);
        }
        for (int g = 0; g < lv->grid_count; g++) {
            ibl_free(ctx, lv->grids[g].sums);
            ibl_free(ctx, lv->grids[g].normalisers);
            ibl_free(ctx, lv->grids[g].bordered);
        }
    }
    ibl_free(ctx, p);
}

const ibl_specular_info *ibl_specular_plan_info(const ibl_specular_plan *plan)
{
    return plan ? &plan->info : NULL;
}

#define FREE_AND_CLEAR(ctx, ptr) (ibl_free((ctx), (ptr)), (ptr) = NULL)

/* A lobe narrower than SUBTEXEL_BELOW_TEXELS source texels is summed over k x k sub-texels of
 * level 0 (each with its parent's radiance), as the reference splits such texels. */
static void choose_subtexel_split(ibl_specular_plan *p)
{
    int S = p->source_edge;
    p->subtexel_split = 1;
    for (int l = 0; l < p->output_levels; l++) {
        if (level_is_mirror(p, l)) continue;
        const ibl__lobe *lobe = &p->levels[l].lobe;
        while (p->subtexel_split < SUBTEXEL_MAX_SPLIT && (long)S * p->subtexel_split < SUBTEXEL_MAX_EDGE &&
               lobe->half_angle < SUBTEXEL_BELOW_TEXELS * texel_angle(S * p->subtexel_split))
            p->subtexel_split *= 2;
    }
}

/* What a run needs besides the levels' own buffers: the padded faces and their transposes for
 * the precomputed pieces (products.c; a one-shot plan's products make them level by level), and
 * the uniform images of the coarse levels they read. */
static ibl_status run_buffers(ibl_specular_plan *p)
{
    ibl_context *ctx = p->ctx;
    size_t padded = 0;
    for (int l = 0; l < p->output_levels; l++) {
        size_t level_padded = ibl__fast_kept_padded_floats(p, l);
        if (!p->one_shot && level_padded > padded) padded = level_padded;
        for (int k = 0; k < p->levels[l].piece_count; k++) {
            const precomputed_piece *c = p->levels[l].pieces[k].precomputed;
            if (!c || c->source_level == 0) continue;
            source_level *s = &p->pyramid[c->source_level];
            float **image = c->without_bright ? &s->uniform_not_bright : &s->uniform;
            size_t floats = (size_t)6 * s->edge * s->edge * UNIFORM_CHANNELS;
            if (!*image && !(*image = ibl_alloc(ctx, floats * sizeof(float))))
                return ibl_context_status(ctx);
        }
    }
    if (padded && !(p->padded_source = ibl_alloc(ctx, padded * sizeof(float))))
        return ibl_context_status(ctx);
    return IBL_OK;
}

/* Level 0's records exist only for pieces that sum it leaf by leaf (sub-texels, or a level-0
 * piece that could not be precomputed). */
static int needs_level0_records(const ibl_specular_plan *p)
{
    if (p->subtexel_split > 1) return 1;
    for (int l = 0; l < p->output_levels; l++)
        for (int k = 0; k < p->levels[l].piece_count; k++)
            if (!level_is_mirror(p, l) && p->levels[l].pieces[k].source_level == 0 &&
                !p->levels[l].pieces[k].precomputed)
                return 1;
    return 0;
}

/* The finest coarse level a piece reads; pyramid_levels if none (a mirror level smaller than
 * the source takes its area means from a kept level or from the source, mirror.c). With
 * sub-texels every level is kept (level 1 comes from level 0's records). */
static int first_read_level(const ibl_specular_plan *p)
{
    if (p->subtexel_split > 1) return 1;
    int first = p->pyramid_levels;
    for (int l = 0; l < p->output_levels; l++) {
        if (level_is_mirror(p, l)) continue;
        for (int k = 0; k < p->levels[l].piece_count; k++) {
            int s = p->levels[l].pieces[k].source_level;
            if (s >= 1 && s < first) first = s;
        }
    }
    return first;
}

/* The lobes of every level, made in parallel (a GGX lobe's peak search is ~0.1 ms). */
static void plan_lobes(ibl_specular_plan *p)
{
    ibl__lobe lobes[IBL_MAX_LEVELS];
    ibl__lobes_for_levels(p->ctx, &p->info, p->output_levels, lobes);
    for (int l = 0; l < p->output_levels; l++) p->levels[l].lobe = lobes[l];
}

typedef struct pieces_job {
    ibl_specular_plan *p;
    ibl_status status[IBL_MAX_LEVELS];
} pieces_job;

static void pieces_task(void *arg, int level)
{
    pieces_job *j = arg;
    j->status[level] = level_is_mirror(j->p, level) ? IBL_OK : ibl__fast_plan_pieces(j->p, level);
}

/* The pieces and grids of every filtered level: a level's depend on its lobe and the pyramid's
 * edges only, so the levels are planned in parallel (their tables, piece_describe in pieces.c,
 * were ~1 ms of one thread at 256). The first failure in level order is the one returned. */
static ibl_status plan_pieces(ibl_specular_plan *p)
{
    pieces_job job = {.p = p};
    ibl_parallel_for(p->ctx, p->output_levels, pieces_task, &job);
    for (int l = 0; l < p->output_levels; l++)
        if (job.status[l] != IBL_OK) return job.status[l];
    return IBL_OK;
}

/* Everything of the fast method's plan after the checks and the mapping. */
static ibl_status plan_fast(ibl_specular_plan *p)
{
    plan_lobes(p);
    choose_subtexel_split(p);
    p->pyramid_levels = ibl_full_mip_count(p->source_edge * p->subtexel_split);
    ibl__fast_pyramid_edges(p);
    ibl_status st = plan_pieces(p);
    p->first_stored = first_read_level(p);
    if (st == IBL_OK) st = ibl__fast_build_moments(p);
    for (int l = 0; st == IBL_OK && l < p->output_levels; l++)
        if (!level_is_mirror(p, l)) st = ibl__fast_precompute_level(p, l);
    if (st == IBL_OK) st = ibl__fast_kept_records(p);
    if (st == IBL_OK) st = run_buffers(p);
    if (st == IBL_OK && needs_level0_records(p)) st = ibl__fast_level0_records(p);
    for (int l = 0; st == IBL_OK && l < p->output_levels; l++) {
        if (level_is_mirror(p, l)) continue;
        if (p->one_shot) st = ibl__fast_grids_restore(p, l);
        if (st == IBL_OK) ibl__fast_normalisers(p, l);
        if (st == IBL_OK) st = ibl__fast_plan_bars(p, l);
        if (st == IBL_OK && p->one_shot) st = ibl__fast_grids_set_aside(p, l);
    }
    if (st == IBL_OK) st = ibl__fast_gathering_buffers(p);
    return st;
}

/* The source edge the chain needs (ibl_specular_source_size, include/ibl/specular.h). The
 * finest pyramid level any piece reads is the core's of the narrowest filtered lobe: the
 * coarsest level whose texels are at most core_source_width wide (pieces.c; rings read coarser
 * levels, from twice the half width on). SOURCE_LEVELS_BELOW_CORE levels finer than that are
 * kept (tuning.h: an area mean puts a texel's light at its centre, where the pyramid would have
 * kept its luminance centroid), and never less than the chain's own edge (a mirror level 0).
 * A source of at most this edge is used as it is. */
static int needed_source_edge(ibl_context *ctx, const ibl_specular_desc *desc,
                              const ibl_specular_info *info, int levels)
{
    double acc = desc->accuracy > 0 ? desc->accuracy / ACCURACY_DEFAULT : 1.0;
    int edge = 1;
    while (edge < desc->size) edge *= 2;
    ibl__lobe lobes[IBL_MAX_LEVELS];
    ibl__lobes_for_levels(ctx, info, levels, lobes);
    for (int l = 0; l < levels; l++) {
        if (lobes[l].kind == IBL__LOBE_MIRROR) continue;
        int core = MIN_SOURCE_EDGE;
        while (core < 16384 && texel_angle(core) > core_source_width(&lobes[l], acc)) core *= 2;
        if ((core << SOURCE_LEVELS_BELOW_CORE) > edge) edge = core << SOURCE_LEVELS_BELOW_CORE;
    }
    return edge < 16384 ? edge : 16384;
}

ibl_status ibl_specular_source_size(ibl_context *ctx, const ibl_specular_desc *desc,
                                    int source_size, int *out)
{
    if (!ctx || !desc || !out) return IBL_ERR_INVALID_ARGUMENT;
    *out = 0;
    ibl_specular_desc d = *desc;
    d.size = d.size > 0 ? d.size : source_size;
    if (d.size < 1 || d.size > 16384 || source_size < 1 || source_size > 16384)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "prefilter: size %d from %d out of range",
                         d.size, source_size);
    int full = ibl_full_mip_count(d.size);
    int levels = d.levels > 0 && d.levels < full ? d.levels : full;
    ibl_specular_info info;
    ibl_status st = ibl_specular_levels(ctx, &d, source_size, &info);
    if (st != IBL_OK) return st;
    if (info.levels < levels) levels = info.levels;
    int pow2 = 1;
    while (pow2 < source_size) pow2 *= 2;
    int needed = needed_source_edge(ctx, &d, &info, levels);
    *out = needed < pow2 ? needed : pow2;
    return IBL_OK;
}

ibl_status ibl_specular_plan_create(ibl_context *ctx, const ibl_specular_desc *desc,
                                    ibl_specular_plan **out)
{
    return ibl__specular_plan_create(ctx, desc, 0, out);
}

ibl_status ibl__specular_plan_create(ibl_context *ctx, const ibl_specular_desc *desc,
                                     int one_shot, ibl_specular_plan **out)
{
    if (!ctx || !desc || !out) return IBL_ERR_INVALID_ARGUMENT;
    *out = NULL;
    if (desc->size < 1 || desc->size > 16384)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "specular plan: size %d out of range",
                         desc->size);
    if ((desc->filter == IBL_FILTER_BOX || desc->filter == IBL_FILTER_GAUSS) && !desc->dynamic)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "specular plan: the %s filter has a dynamic plan only (set .dynamic)",
                         ibl_specular_filter_name(desc->filter));
    int S = desc->source_size > 0 ? desc->source_size : desc->size;
    if (!is_power_of_two(S) || S > 16384)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                         "specular plan: source size %d is not a power of two", S);
    ibl_specular_plan *p = ibl_calloc(ctx, 1, sizeof *p);
    if (!p) return ibl_context_status(ctx);
    p->ctx = ctx;
    p->one_shot = one_shot;
    p->desc = *desc;
    p->source_edge = S;
    p->output_edge = desc->size;
    int full = ibl_full_mip_count(p->output_edge);
    p->output_levels = desc->levels > 0 && desc->levels < full ? desc->levels : full;
    p->desc.levels = p->output_levels;
#if IBL_HAVE_X86_KERNELS
    p->kernels = ibl__cpu_has(ctx, IBL__CPU_AVX2_FMA | IBL__CPU_F16C) ? &ibl__fast_kernels_avx2
                                                                        : &ibl__fast_kernels_portable;
#else
    p->kernels = &ibl__fast_kernels_portable;
#endif
    ibl_status st = ibl__specular_mapping(ctx, &p->desc, p->output_edge, p->output_levels, &p->info);
    if (st == IBL_OK) ibl__fast_face_frames(p);
    if (st == IBL_OK && desc->dynamic) st = ibl__dynamic_create(ctx, &p->desc, &p->info, S, &p->dynamic);
    else if (st == IBL_OK) st = plan_fast(p);
    if (st != IBL_OK) {
        ibl_specular_plan_destroy(p);
        return st;
    }
    *out = p;
    return IBL_OK;
}

/* The per-frame path: the sparse operator over box mips. */
static ibl_status run_dynamic(ibl_specular_plan *p, const ibl_cubemap *src, ibl_cubemap *dst)
{
    ibl_status st = ibl__dynamic_run(p->dynamic, src, dst);
    return st == IBL_OK ? ibl__progress(p->ctx, "prefilter", 1.0) : st;
}

/* The precomputed pieces over pyramid level `level` gather their centroid corrections, one
 * after the other in the correction pool (pool_used: its blocks taken so far). */
static ibl_status gather_corrections(ibl_specular_plan *p, const ibl_cubemap *src, int level,
                                     size_t *pool_used)
{
    for (int l = 0; l < p->output_levels; l++)
        for (int k = 0; k < p->levels[l].piece_count; k++) {
            precomputed_piece *c = p->levels[l].pieces[k].precomputed;
            if (!c || c->correction_capacity == 0 || c->source_level != level) continue;
            c->own_records = !p->correction_pool;
            if (!c->own_records) c->correction_records = p->correction_pool + *pool_used * COARSE_FIELDS * BLOCK_TEXELS;
            ibl_status st = ibl__fast_select_corrections(p, c, src);
            if (st != IBL_OK) return st;
            /* the selection's scratch, and the texels' bounds unless the padded source leaves
             * the corrected texels out by them (products.c) */
            if (p->one_shot) FREE_AND_CLEAR(p->ctx, c->correction_keys);
            if (p->one_shot && (c->correction_block_count == 0 || c->correction_difference))
                FREE_AND_CLEAR(p->ctx, c->texel_bound);
            *pool_used += (size_t)c->correction_block_count;
        }
    return IBL_OK;
}

/* The radiance pyramid and what is gathered from it: level by level, the records (those only
 * the pyramid reads are made here), the bright texels, the uniform images and the centroid
 * corrections of the precomputed pieces over it. A one-shot plan frees a level's records
 * once the next level is made from them (ibl__fast_free_run_records: no-op for kept ones),
 * and makes its first stored level block row by block row with the next one, without its
 * records, where it can (ibl__fast_pyramid_streamed). */
static ibl_status run_pyramid(ibl_specular_plan *p, const ibl_cubemap *src)
{
    if (p->has_level0_records) ibl__fast_pyramid_level0(p, src);
    size_t pool_used = 0;
    int made = -1; /* the level made with the streamed one */
    for (int l = p->first_stored; l < p->pyramid_levels; l++) {
        ibl_status st = IBL_OK;
        if (l != made && ibl__fast_pyramid_streams(p, l)) {
            st = ibl__fast_run_records(p, l + 1);
            if (st == IBL_OK) st = ibl__fast_pyramid_streamed(p, src, l);
            made = l + 1;
        } else if (l != made) {
            st = ibl__fast_run_records(p, l);
            if (st == IBL_OK) ibl__fast_pyramid_level(p, src, l);
        }
        if (st != IBL_OK) return st;
        if (p->pyramid[l].bright_scale > 0) ibl__fast_select_bright(p, l);
        if (p->one_shot) FREE_AND_CLEAR(p->ctx, p->pyramid[l].bright_keys);
        if (l != made - 1) ibl__fast_uniform_level(p, l); /* (a streamed level's: made with it) */
        st = gather_corrections(p, src, l, &pool_used);
        if (st != IBL_OK) return st;
        if (p->one_shot && l > p->first_stored) ibl__fast_free_run_records(p, l - 1);
    }
    if (p->one_shot && p->pyramid_levels > p->first_stored)
        ibl__fast_free_run_records(p, p->pyramid_levels - 1);
    return IBL_OK;
}

static ibl_status check_run(const ibl_specular_plan *p, const ibl_cubemap *src,
                            const ibl_cubemap *dst)
{
    if (!p || !src || !src->data || (dst && !dst->data)) return IBL_ERR_INVALID_ARGUMENT;
    int out_edge = dst ? dst->size : p->output_edge, out_levels = dst ? dst->levels : p->output_levels;
    if (src->size != p->source_edge || out_edge != p->output_edge || out_levels != p->output_levels)
        return ibl__fail(p->ctx, IBL_ERR_INVALID_ARGUMENT,
                         "specular run: planned source %d -> %d x %d levels, got %d -> %d x %d",
                         p->source_edge, p->output_edge, p->output_levels, src->size, out_edge,
                         out_levels);
    return IBL_OK;
}

/* A filtered level's grids: leaf sums, then products (a one-shot plan's weights made for them
 * and freed after: whole, or batch by batch by the products where that takes less memory). A
 * one-shot plan makes the level's sums after the weights, once the geometry they were made
 * from is freed (pieces.c, ibl__fast_grids_restore), then adds the normalisers its plan left
 * to the run. */
static ibl_status level_sums(ibl_specular_plan *p, const ibl_cubemap *src, int l)
{
    level_plan *lv = &p->levels[l];
    for (int k = 0; k < lv->piece_count; k++) {
        const precomputed_piece *c = lv->pieces[k].precomputed;
        ibl_status st = c && !ibl__fast_products_batched(c) ? ibl__fast_precomputed_refill(p, l, k) : IBL_OK;
        if (st != IBL_OK) return st;
    }
    ibl_status st = p->one_shot ? ibl__fast_grids_restore(p, l) : IBL_OK;
    if (st != IBL_OK) return st;
    for (int k = 0; k < lv->piece_count; k++) {
        const precomputed_piece *c = lv->pieces[k].precomputed;
        if (c && c->normalisers_at_run) ibl__fast_precomputed_run_normalisers(p, l, k);
    }
    ibl__fast_leaf_sums(p, l);
    st = ibl__fast_products(p, l, src);
    if (st != IBL_OK) return st;
    for (int k = 0; p->one_shot && k < lv->piece_count; k++)
        if (lv->pieces[k].precomputed) ibl__fast_precomputed_release(p->ctx, lv->pieces[k].precomputed);
    return IBL_OK;
}

/* Whether a mirror level is made from the pyramid or level 0's geometry (mirror.c: a level
 * smaller than the source) rather than copied or sampled from the source. */
static int mirror_reads_pyramid(const ibl_specular_plan *p)
{
    for (int l = 0; l < p->output_levels; l++) {
        int n = ibl_level_size(p->output_edge, l);
        if (level_is_mirror(p, l) && n < p->source_edge && is_power_of_two(n)) return 1;
    }
    return 0;
}

/* Once a one-shot plan's grids are summed, the output levels need the grids only (combine.c),
 * and mirror levels smaller than the source the pyramid (mirror.c): the rest of what the run
 * used is freed, so that the output chain can take its memory (in one piece: even small
 * blocks left between freed ones would split it). */
static void release_after_grids(ibl_specular_plan *p)
{
    ibl_context *ctx = p->ctx;
    int keep_pyramid = mirror_reads_pyramid(p);
    FREE_AND_CLEAR(ctx, p->padded_source);
    FREE_AND_CLEAR(ctx, p->correction_pool);
    if (!keep_pyramid) FREE_AND_CLEAR(ctx, p->level0_geometry);
    for (int l = 0; l < p->pyramid_levels; l++) {
        source_level *s = &p->pyramid[l];
        FREE_AND_CLEAR(ctx, s->uniform);
        FREE_AND_CLEAR(ctx, s->uniform_not_bright);
        FREE_AND_CLEAR(ctx, s->bright_records);
        FREE_AND_CLEAR(ctx, s->bright_cones);
        FREE_AND_CLEAR(ctx, s->bright_keys);
        FREE_AND_CLEAR(ctx, s->geometry);
        if (keep_pyramid) continue;
        FREE_AND_CLEAR(ctx, s->records);
        FREE_AND_CLEAR(ctx, s->cones);
    }
    for (int l = 0; l < p->output_levels; l++)
        for (int k = 0; k < p->levels[l].piece_count; k++) {
            ibl__fast_precomputed_destroy(ctx, p->levels[l].pieces[k].precomputed);
            p->levels[l].pieces[k].precomputed = NULL;
        }
}

ibl_status ibl__specular_plan_run_grids(ibl_specular_plan *p, const ibl_cubemap *src)
{
    ibl_status st = check_run(p, src, NULL);
    if (st != IBL_OK || p->dynamic) return st;
    st = run_pyramid(p, src);
    /* every level's grids before any output: they need no output memory */
    for (int l = 0; st == IBL_OK && l < p->output_levels; l++) {
        if (!level_is_mirror(p, l)) st = level_sums(p, src, l);
        if (st == IBL_OK) st = ibl__progress(p->ctx, "prefilter", (l + 1.0) / p->output_levels);
    }
    if (st == IBL_OK && p->one_shot) release_after_grids(p);
    return st;
}

ibl_status ibl__specular_plan_run_output(ibl_specular_plan *p, const ibl_cubemap *src,
                                         ibl_cubemap *dst)
{
    ibl_status st = check_run(p, src, dst);
    if (st != IBL_OK) return st;
    if (p->dynamic) return run_dynamic(p, src, dst);
    for (int l = 0; st == IBL_OK && l < p->output_levels; l++) {
        if (level_is_mirror(p, l)) ibl__fast_mirror_level(p, src, dst, l);
        else st = ibl__fast_combine(p, dst, l);
        if (st == IBL_OK) st = ibl_edge_fixup_apply(p->ctx, p->desc.edge_fixup, dst, l);
    }
    return st;
}

ibl_status ibl_specular_plan_run(ibl_specular_plan *p, const ibl_cubemap *src, ibl_cubemap *dst)
{
    if (!p || !src || !dst || !src->data || !dst->data) return IBL_ERR_INVALID_ARGUMENT;
    ibl_status st = check_run(p, src, dst); /* before any work */
    if (st == IBL_OK) st = ibl__specular_plan_run_grids(p, src);
    return st == IBL_OK ? ibl__specular_plan_run_output(p, src, dst) : st;
}

void ibl__specular_plan_stats(const ibl_specular_plan *p, ibl__specular_stats *out)
{
    memset(out, 0, sizeof *out);
    for (int l = 0; l < p->output_levels; l++)
        for (int k = 0; k < p->levels[l].piece_count; k++) {
            const lobe_piece *pc = &p->levels[l].pieces[k];
            out->pieces++;
            out->split += pc->bright_apart;
            out->coarse_cores += k == 0 && !p->levels[l].grids[pc->grid].at_output;
            if (!pc->precomputed) continue;
            out->precomputed++;
            out->precomputed_coarse += pc->precomputed->source_level > 0;
            out->correction_blocks += pc->precomputed->correction_block_count;
            out->difference_corrections +=
                pc->precomputed->correction_difference && pc->precomputed->correction_block_count > 0;
        }
    for (int l = 0; l < p->pyramid_levels; l++) out->bright_blocks += p->pyramid[l].bright_block_count;
}
