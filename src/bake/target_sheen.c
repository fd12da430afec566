/* The sheen side of the glTF target (KHR_materials_sheen, Khronos): the prefiltered Charlie
 * chain and the sheen albedo table.
 *
 * The chain: level l holds, for each direction n, the radiance weighted by the Charlie
 * distribution (Conty Estevez & Kulla 2017, "Production Friendly Microfacet Sheen BRDF")
 * under the split-sum assumption v = n (Karis 2013):
 *     P(n) = sum L(w) D(h) (n.w) dw / sum D(h) (n.w) dw,   h = normalize(n + w), n.w > 0,
 * with D(h) = (2 + 1/a) sin(theta_h)^(1/a) / (2 pi) and a = sheenRoughness of the level,
 * l / (levels - 1) as the Khronos glTF-IBL-Sampler spaces its "charlie" mips (a is held at
 * 1/64 or more: the lobe of a = 0 has no weight inside the hemisphere). With v = n,
 * theta_h = theta_w / 2, so the weight is a function of c = n.w alone: it is tabulated per
 * level and the sum runs over every texel of the source, weighted by its exact solid angle.
 * The source is the environment at 32 texels (its area-correct mean), the chain at most 64
 * texels (the bake makes it with the GGX chain's number of levels): sheen lobes are wide. */
#include "bake_internal.h"
#include "target_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"
#include "ibl/cubemap.h"

#include <math.h>
#include <string.h>

enum { WEIGHT_TABLE = 2048, SOURCE_SIZE = 32 };

typedef struct charlie_job {
    const ibl_cubemap *src;   /* one level, SOURCE_SIZE or smaller */
    const float *dirs;        /* per source texel: x y z solid-angle */
    int src_texels;
    ibl_cubemap *out;
    int level, size;
    double table[WEIGHT_TABLE + 1]; /* D(theta_w / 2) c over c = n.w in [0, 1] */
} charlie_job;

static double charlie_d(double sin_h, double alpha)
{
    return (2.0 + 1.0 / alpha) * pow(sin_h, 1.0 / alpha) / (2.0 * IBL_PI);
}

static void fill_table(charlie_job *job, double alpha)
{
    for (int i = 0; i <= WEIGHT_TABLE; i++) {
        double c = (double)i / WEIGHT_TABLE;
        /* theta_h = theta_w / 2: sin^2(theta_h) = (1 - c) / 2 */
        job->table[i] = charlie_d(sqrt(0.5 * (1.0 - c)), alpha) * c;
    }
}

/* one face row of one level per task: the sums run in a fixed order (bit-identical at any
 * thread count) */
static void charlie_row(void *arg, int task)
{
    charlie_job *job = arg;
    int face = task / job->size, y = task % job->size;
    float *row = ibl_cubemap_face(job->out, job->level, face) + (size_t)y * (size_t)job->size * 4;
    const float *src = ibl_cubemap_face(job->src, 0, 0);
    for (int x = 0; x < job->size; x++) {
        ibl_vec3 n = ibl_cube_texel_direction(face, job->size, x, y);
        double acc[3] = {0, 0, 0}, wsum = 0;
        for (int k = 0; k < job->src_texels; k++) {
            const float *d = job->dirs + (size_t)k * 4;
            double c = n.x * d[0] + n.y * d[1] + n.z * d[2];
            if (c <= 0) continue;
            double t = c * WEIGHT_TABLE;
            int i = (int)t;
            if (i >= WEIGHT_TABLE) i = WEIGHT_TABLE - 1;
            double f = t - i, w = (job->table[i] + f * (job->table[i + 1] - job->table[i])) * d[3];
            const float *l = src + (size_t)k * 4;
            acc[0] += w * l[0], acc[1] += w * l[1], acc[2] += w * l[2];
            wsum += w;
        }
        float *o = row + (size_t)x * 4;
        for (int ch = 0; ch < 3; ch++) o[ch] = wsum > 0 ? (float)(acc[ch] / wsum) : 0.0f;
        o[3] = 1.0f;
    }
}

float ibl_charlie_level_roughness(int level, int levels)
{
    float r = levels > 1 ? (float)level / (float)(levels - 1) : 1.0f;
    return r < 1.0f / 64.0f ? 1.0f / 64.0f : r;
}

ibl_status ibl_charlie_prefilter(ibl_context *ctx, const ibl_cubemap *env, int size, int levels,
                                 ibl_cubemap *out)
{
    memset(out, 0, sizeof *out);
    if (!env || !env->data || size < 1 || levels < 1 || ibl_level_size(size, levels - 1) < 1 ||
        levels > IBL_MAX_LEVELS)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "charlie chain: bad size %d or levels %d",
                         size, levels);
    /* the source: the environment's area-correct mean at 32 texels (or its own size) */
    int ss = env->size < SOURCE_SIZE ? env->size : SOURCE_SIZE;
    ibl_cubemap src = {0};
    ibl_status st = ibl_cubemap_alloc(ctx, ss, 1, &src);
    if (st == IBL_OK) st = ibl_cubemap_resample(ctx, env, &src);
    int texels = 6 * ss * ss;
    float *dirs = st == IBL_OK ? ibl_alloc(ctx, (size_t)texels * 4 * sizeof *dirs) : NULL;
    charlie_job *job = st == IBL_OK && dirs ? ibl_calloc(ctx, 1, sizeof *job) : NULL;
    if (st == IBL_OK && (!dirs || !job)) st = ibl__fail(ctx, ibl_context_status(ctx), "charlie chain: out of memory");
    if (st == IBL_OK) st = ibl_cubemap_alloc(ctx, size, levels, out);
    if (st == IBL_OK) {
        for (int f = 0, k = 0; f < 6; f++)
            for (int y = 0; y < ss; y++)
                for (int x = 0; x < ss; x++, k++) {
                    ibl_vec3 d = ibl_cube_texel_direction(f, ss, x, y);
                    dirs[k * 4 + 0] = d.x, dirs[k * 4 + 1] = d.y, dirs[k * 4 + 2] = d.z;
                    dirs[k * 4 + 3] = (float)ibl_cube_texel_solid_angle(ss, x, y);
                }
        job->src = &src;
        job->dirs = dirs;
        job->src_texels = texels;
        job->out = out;
        for (int l = 0; l < levels && st == IBL_OK; l++) {
            job->level = l;
            job->size = ibl_level_size(size, l);
            fill_table(job, ibl_charlie_level_roughness(l, levels));
            ibl_parallel_for(ctx, 6 * job->size, charlie_row, job);
            st = ibl__progress(ctx, "charlie chain", (double)(l + 1) / levels);
        }
    }
    if (st != IBL_OK) ibl_cubemap_free(ctx, out);
    ibl_free(ctx, job);
    ibl_free(ctx, dirs);
    ibl_cubemap_free(ctx, &src);
    return st;
}

/* ---- the glTF target's sheen files --------------------------------------------------------- */

static ibl_status stage_ktx2(ibl_context *ctx, const char *dir, const char *name, ibl_texture *tex,
                             ibl_format format)
{
    ibl_write_desc wd = {.format = format};
    void *bytes = NULL;
    size_t size = 0;
    ibl_status st = ibl_encode_texture(ctx, IBL_FILE_KTX2, tex, &wd, &bytes, &size);
    if (st == IBL_OK) st = ibl__bake_write_staged(ctx, dir, name, bytes, size);
    else st = ibl__fail(ctx, st, "%s: %s", name, ibl_context_message(ctx));
    ibl_free(ctx, bytes);
    return st;
}

ibl_status ibl__stage_gltf_sheen(ibl_context *ctx, const char *dir, const ibl_bake_data *b)
{
    if (!b->sheen.data) return IBL_OK;
    ibl_texture tex = ibl_texture_from_cubemap(&b->sheen);
    ibl_status st = ibl_texture_set_metadata(ctx, &tex, "ibl.sheen",
                                  "prefiltered Charlie sheen radiance, v = n; level l: "
                                  "sheenRoughness = l / (levels - 1) (at least 1/64)");
    if (st == IBL_OK) st = stage_ktx2(ctx, dir, "engine_gltf_charlie.ktx2", &tex, IBL_FORMAT_RGBA16F);
    ibl_texture_free(ctx, &tex); /* the metadata; the texels stay with the bake */
    if (st != IBL_OK) return st;
    /* the table: E and E_avg of KHR_materials_sheen's BRDF over (n.v, sheenRoughness) */
    ibl_brdf_lut_desc d = {.size = b->lut_size > 0 ? b->lut_size : 128,
                           .channels = {IBL_BRDF_SHEEN_KHR, IBL_BRDF_SHEEN_KHR_AVG}};
    ibl_image lut;
    st = ibl_brdf_lut(ctx, &d, &lut);
    if (st != IBL_OK) return st;
    ibl_texture t2 = {.kind = IBL_TEXTURE_2D, .width = lut.width, .height = lut.height, .depth = 1,
                      .levels = 1, .data = lut.pixels};
    st = ibl_texture_set_metadata(ctx, &t2, "ibl.brdf",
                                  "KHR_materials_sheen albedo: R = E(n.v), G = its average; x = "
                                  "n.v, y = sheenRoughness (alpha = y), Charlie visibility");
    if (st == IBL_OK) st = stage_ktx2(ctx, dir, "engine_gltf_sheen_lut.ktx2", &t2, IBL_FORMAT_RG16F);
    ibl_texture_free(ctx, &t2);
    ibl_image_free(ctx, &lut);
    return st;
}
