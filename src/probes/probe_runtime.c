/* The run time of a probe bake on the CPU (docs/PROBES.md "Run time"): tiled culling of
 * influence volumes with per-tile depth bounds and the write-up's three per-tile sorts (JAGE
 * 2015, "Tiled Probe Culling"), and the per-pixel blend: influence weights, parallax
 * correction (Lagarde and Zanuttini 2012) and the alpha-aware front-to-back priority blend
 * with the global probe taking what is left. Every statement here is one a compute or pixel
 * shader can make; the shaders mirror them. */
#include "ibl/probes.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* ---- the camera ------------------------------------------------------------------------------ */

static ibl_vec3 cross3(ibl_vec3 a, ibl_vec3 b)
{
    ibl_vec3 c = {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
    return c;
}

void ibl_camera_basis(const ibl_camera *cam, ibl_vec3 *right, ibl_vec3 *up, ibl_vec3 *forward)
{
    ibl_vec3 f = ibl__norm(cam->forward);
    ibl_vec3 r = ibl__norm(cross3(f, cam->up));
    *forward = f;
    *right = r;
    *up = cross3(r, f);
}

static void half_tangents(const ibl_camera *cam, float *tx, float *ty)
{
    float fov = cam->fov_y_degrees > 0.0f ? cam->fov_y_degrees : 60.0f;
    *ty = tanf(fov * 0.5f * 3.14159265358979f / 180.0f);
    *tx = *ty * (float)cam->width / (float)cam->height;
}

ibl_vec3 ibl_camera_ray(const ibl_camera *cam, float px, float py)
{
    ibl_vec3 r, u, f;
    ibl_camera_basis(cam, &r, &u, &f);
    float tx, ty;
    half_tangents(cam, &tx, &ty);
    float sx = (2.0f * px / (float)cam->width - 1.0f) * tx;
    float sy = (1.0f - 2.0f * py / (float)cam->height) * ty;
    return ibl__add(f, ibl__add(ibl__scale(r, sx), ibl__scale(u, sy)));
}

/* ---- the three sorts ------------------------------------------------------------------------- */

static long long odd_even(int *a, int n)
{
    long long compares = 0;
    for (int pass = 0; pass < n; pass++)
        for (int i = 1 + (pass & 1); i < n; i += 2) {
            compares++;
            if (a[i] < a[i - 1]) {
                int t = a[i];
                a[i] = a[i - 1];
                a[i - 1] = t;
            }
        }
    return compares;
}

/* Each entry's rank is the number of smaller entries (distinct values): what one GPU thread per
 * entry computes; the ranks are written to scratch and copied back. */
static long long rank_sort(int *a, int n, int *scratch)
{
    long long compares = 0;
    for (int i = 0; i < n; i++) {
        int rank = 0;
        for (int j = 0; j < n; j++, compares++) rank += a[j] < a[i];
        scratch[rank] = a[i];
    }
    memcpy(a, scratch, sizeof *a * (size_t)n);
    return compares;
}

long long ibl_tile_sort_run(ibl_tile_sort sort, int *indices, int n, int *scratch)
{
    if (n < 2) return 0;
    if (sort == IBL_TILE_SORT_ODD_EVEN) return odd_even(indices, n);
    /* RANK and RANK_COPY make the same comparisons; on a GPU they differ in barriers only */
    return rank_sort(indices, n, scratch);
}

/* ---- tiled culling ----------------------------------------------------------------------------- */

typedef struct plane {
    float n[3], d; /* inside where n.p + d >= 0 */
} plane;

typedef struct cam_frame {
    ibl_vec3 pos, right, up, forward;
    float tx, ty;
} cam_frame;

static ibl_vec3 to_camera(const cam_frame *c, ibl_vec3 p)
{
    ibl_vec3 q = ibl__sub(p, c->pos);
    ibl_vec3 r = {ibl__dot(q, c->right), ibl__dot(q, c->up), ibl__dot(q, c->forward)};
    return r;
}

static plane make_plane(float a, float b, float c, float d)
{
    float len = sqrtf(a * a + b * b + c * c);
    plane p = {{a / len, b / len, c / len}, d / len};
    return p;
}

static int outside(const plane *pl, const ibl_vec3 *pts, int n, float radius)
{
    for (int i = 0; i < n; i++)
        if (pl->n[0] * pts[i].x + pl->n[1] * pts[i].y + pl->n[2] * pts[i].z + pl->d >= -radius)
            return 0;
    return 1;
}

/* Is the volume (in camera space: a sphere's centre or a box's 8 corners) wholly outside one
 * of the 6 planes? */
static int culled(const plane planes[6], const ibl_vec3 *pts, int n, float radius)
{
    for (int k = 0; k < 6; k++)
        if (outside(&planes[k], pts, n, radius)) return 1;
    return 0;
}

static int volume_points(const cam_frame *c, const ibl_volume *v, ibl_vec3 pts[8], float *radius)
{
    if (v->shape == IBL_VOLUME_SPHERE) {
        pts[0] = to_camera(c, v->center);
        *radius = v->radius;
        return 1;
    }
    for (int i = 0; i < 8; i++) {
        ibl_vec3 p = {v->center.x + ((i & 1) ? v->half_extent.x : -v->half_extent.x),
                      v->center.y + ((i & 2) ? v->half_extent.y : -v->half_extent.y),
                      v->center.z + ((i & 4) ? v->half_extent.z : -v->half_extent.z)};
        pts[i] = to_camera(c, p);
    }
    *radius = 0.0f;
    return 8;
}

typedef struct tile_job {
    const ibl_camera *cam;
    cam_frame frame;
    const float *depth;
    const ibl_volume *volumes;
    int count, tile_size, tiles_x, exact;
    ibl_tile_sort sort;
    int *lists;     /* count per tile */
    int *lengths;
    long long *tests, *compares;
} tile_job;

static int depth_valid(float d)
{
    return d > 0.0f && d < FLT_MAX;
}

static int some_pixel_inside(const tile_job *j, const ibl_volume *v, int x0, int y0, int x1, int y1)
{
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            float d = j->depth[(size_t)y * j->cam->width + x];
            if (!depth_valid(d)) continue;
            ibl_vec3 ray = ibl_camera_ray(j->cam, (float)x + 0.5f, (float)y + 0.5f);
            if (ibl_volume_weight(v, ibl__add(j->cam->position, ibl__scale(ray, d))) > 0.0f) return 1;
        }
    return 0;
}

static void cull_tile(void *arg, int t)
{
    const tile_job *j = arg;
    int ts = j->tile_size, W = j->cam->width, H = j->cam->height;
    int x0 = (t % j->tiles_x) * ts, y0 = (t / j->tiles_x) * ts;
    int x1 = x0 + ts < W ? x0 + ts : W, y1 = y0 + ts < H ? y0 + ts : H;
    float dmin = FLT_MAX, dmax = 0.0f;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            float d = j->depth[(size_t)y * W + x];
            if (!depth_valid(d)) continue;
            dmin = d < dmin ? d : dmin;
            dmax = d > dmax ? d : dmax;
        }
    int *list = j->lists + (size_t)t * j->count, n = 0;
    j->tests[t] = j->compares[t] = 0;
    if (dmax > 0.0f) {
        const cam_frame *c = &j->frame;
        float sx0 = (2.0f * x0 / W - 1.0f) * c->tx, sx1 = (2.0f * x1 / W - 1.0f) * c->tx;
        float syt = (1.0f - 2.0f * y0 / H) * c->ty, syb = (1.0f - 2.0f * y1 / H) * c->ty;
        plane planes[6] = {make_plane(1, 0, -sx0, 0), make_plane(-1, 0, sx1, 0),
                           make_plane(0, 1, -syb, 0), make_plane(0, -1, syt, 0),
                           make_plane(0, 0, 1, -dmin * (1.0f - 1e-5f)),
                           make_plane(0, 0, -1, dmax * (1.0f + 1e-5f))};
        /* a GPU's atomic appends come in no set order: start at a tile-dependent probe */
        for (int s = 0; s < j->count; s++) {
            int i = (t + j->count - 1 - s) % j->count;
            ibl_vec3 pts[8];
            float radius;
            int np = volume_points(c, &j->volumes[i], pts, &radius);
            j->tests[t]++;
            if (culled(planes, pts, np, radius)) continue;
            if (j->exact && !some_pixel_inside(j, &j->volumes[i], x0, y0, x1, y1)) continue;
            list[n++] = i;
        }
        int scratch[1024]; /* count <= 1024 */
        j->compares[t] = ibl_tile_sort_run(j->sort, list, n, scratch);
    }
    j->lengths[t] = n;
}

ibl_status ibl_cull_probes(ibl_context *ctx, const ibl_camera *cam, const float *depth,
                           const ibl_volume *influences, int count, const ibl_cull_desc *desc,
                           ibl_tile_lists *out, ibl_cull_stats *stats)
{
    if (out) memset(out, 0, sizeof *out);
    if (stats) memset(stats, 0, sizeof *stats);
    if (!ctx || !cam || !depth || !out || count < 0 || count > 1024 || (count && !influences) ||
        cam->width < 1 || cam->height < 1)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "cull probes: bad arguments (at most 1024 probes)");
    tile_job j;
    memset(&j, 0, sizeof j);
    j.cam = cam;
    j.depth = depth;
    j.volumes = influences;
    j.count = count;
    j.tile_size = desc && desc->tile_size > 0 ? desc->tile_size : 16;
    j.exact = desc ? desc->exact : 0;
    j.sort = desc ? desc->sort : IBL_TILE_SORT_ODD_EVEN;
    j.frame.pos = cam->position;
    ibl_camera_basis(cam, &j.frame.right, &j.frame.up, &j.frame.forward);
    half_tangents(cam, &j.frame.tx, &j.frame.ty);
    j.tiles_x = (cam->width + j.tile_size - 1) / j.tile_size;
    int tiles_y = (cam->height + j.tile_size - 1) / j.tile_size;
    int tiles = j.tiles_x * tiles_y;
    j.lists = ibl_alloc(ctx, sizeof(int) * (size_t)tiles * (size_t)(count > 0 ? count : 1));
    j.lengths = ibl_alloc(ctx, sizeof(int) * (size_t)tiles);
    j.tests = ibl_alloc(ctx, sizeof(long long) * (size_t)tiles);
    j.compares = ibl_alloc(ctx, sizeof(long long) * (size_t)tiles);
    out->offsets = ibl_alloc(ctx, sizeof(int) * (size_t)(tiles + 1));
    ibl_status st = j.lists && j.lengths && j.tests && j.compares && out->offsets ? IBL_OK : ibl_context_status(ctx);
    if (st == IBL_OK) {
        ibl_parallel_for(ctx, tiles, cull_tile, &j);
        out->offsets[0] = 0;
        for (int t = 0; t < tiles; t++) out->offsets[t + 1] = out->offsets[t] + j.lengths[t];
        out->indices = ibl_alloc(ctx, sizeof(int) * (size_t)(out->offsets[tiles] > 0 ? out->offsets[tiles] : 1));
        if (!out->indices) st = ibl_context_status(ctx);
    }
    if (st == IBL_OK) {
        for (int t = 0; t < tiles; t++) {
            memcpy(out->indices + out->offsets[t], j.lists + (size_t)t * count, sizeof(int) * (size_t)j.lengths[t]);
            if (stats) stats->tests += j.tests[t], stats->compares += j.compares[t];
        }
        if (stats) stats->entries = out->offsets[tiles];
        out->tiles_x = j.tiles_x;
        out->tiles_y = tiles_y;
        out->tile_size = j.tile_size;
    } else {
        ibl_tile_lists_free(ctx, out);
    }
    ibl_free(ctx, j.lists);
    ibl_free(ctx, j.lengths);
    ibl_free(ctx, j.tests);
    ibl_free(ctx, j.compares);
    return st;
}

/* ---- the per-pixel blend ------------------------------------------------------------------------ */

ibl_status ibl_probe_bake_locals(ibl_context *ctx, const ibl_probe_bake_data *bake,
                                 const ibl_probe *global, ibl_probe *locals)
{
    for (int i = 0; i < bake->count; i++) {
        ibl_probe *p = &locals[i];
        memset(p, 0, sizeof *p);
        p->specular = bake->chains[i];
        p->specular.owns_data = 0;
        p->mapping = bake->mapping;
        p->sh_kind = IBL_SH_KIND_RADIANCE;
        for (int k = 0; k < 9; k++)
            for (int c = 0; c < 3; c++) p->sh[k][c] = bake->records[i].sh[k][c];
        p->splitsum = global->splitsum;
        p->ambient_brdf = global->ambient_brdf;
        ibl_status st = ibl_probe_validate(ctx, p);
        if (st != IBL_OK) return st;
    }
    return IBL_OK;
}

static float clamp01(float x)
{
    return x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x;
}

/* cosine-convolved coverage: E_a(n) / pi of the coverage's SH */
static float diffuse_alpha(const ibl_probe_record *r, ibl_vec3 n)
{
    float sh[9][3], e[3];
    for (int k = 0; k < 9; k++) sh[k][0] = sh[k][1] = sh[k][2] = r->sh[k][3];
    ibl_sh9_eval_irradiance(sh, IBL_SH_KIND_RADIANCE, n, e);
    return clamp01(e[0] / 3.14159265358979f);
}

void ibl_probes_shade(const ibl_probe_bake_data *bake, const ibl_probe *global,
                      const ibl_probe *locals, const int *list, int list_count,
                      const ibl_probe_blend_desc *blend, const ibl_shade_desc *desc,
                      const ibl_material *m, ibl_vec3 p, const ibl_surface *s,
                      ibl_shade_result *out, ibl_probe_blend_info *info)
{
    ibl_probe_blend_desc b;
    memset(&b, 0, sizeof b);
    if (blend) b = *blend;
    ibl_vec3 dir = ibl_shade_lookup_direction(desc, m, s);
    float S[3] = {0, 0, 0}, D[3] = {0, 0, 0}, rs = 1.0f, rd = 1.0f, best = 0.0f;
    int heaviest = -1;
    for (int i = 0; i < list_count && (rs > 0.0f || rd > 0.0f); i++) {
        int k = list[i];
        const ibl_probe_record *r = &bake->records[k];
        float w = ibl_volume_weight(&r->influence, p);
        if (!(w > 0.0f)) continue;
        if (b.no_blend) w = 1.0f;
        ibl_vec3 d = b.no_parallax ? dir : ibl_parallax_correct(&r->proxy, r->position, p, dir);
        ibl_shade_result lk;
        ibl_shade_dir(&locals[k], desc, m, s, d, &lk);
        float rgba[4];
        ibl_cubemap_sample_trilinear(&bake->chains[k], lk.lod, d, rgba);
        float as = b.no_alpha ? 1.0f : clamp01(rgba[3]);
        float ad = b.no_alpha ? 1.0f : diffuse_alpha(r, s->n);
        float cs = w * rs, cd = w * rd;
        for (int c = 0; c < 3; c++) S[c] += cs * lk.specular[c], D[c] += cd * lk.diffuse[c];
        if (cs * as > best) best = cs * as, heaviest = k;
        rs -= cs * as;
        rd -= cd * ad;
        rs = rs < 0.0f ? 0.0f : rs;
        rd = rd < 0.0f ? 0.0f : rd;
    }
    ibl_shade_result g;
    ibl_shade_dir(global, desc, m, s, dir, &g);
    for (int c = 0; c < 3; c++) {
        S[c] += rs * g.specular[c];
        D[c] += rd * g.diffuse[c];
        out->specular[c] = S[c];
        out->diffuse[c] = D[c];
        out->color[c] = D[c] * m->ao + S[c] * g.so;
    }
    out->so = g.so;
    out->lod = g.lod;
    out->r = dir;
    if (info) {
        info->specular_global = rs;
        info->diffuse_global = rd;
        info->heaviest = rs > best ? -1 : heaviest;
    }
}
