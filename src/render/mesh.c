/* The preview's optional mesh: a small OBJ reader (positions, optional vertex colours as AO,
 * polygons fanned into triangles, smooth normals from the faces), a bounding volume
 * hierarchy for ray casting, and per-vertex ambient occlusion by cosine-weighted ray casting
 * when the file has none (the AO tri-Ace's specular occlusion formulas take). */
#include "render_internal.h"
#include "core/context_internal.h"

#include <errno.h>
#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct bvh_node {
    float lo[3], hi[3];
    int first, count; /* leaf: triangles [first, first+count) of the order; inner: count 0 */
    int left, right;
} bvh_node;

typedef struct bvh {
    bvh_node *nodes;
    int node_count;
    int *order; /* triangle indices */
} bvh;

typedef struct growable {
    void *data;
    size_t count, capacity, elem;
} growable;

static int grow_push(ibl_context *ctx, growable *g, const void *item)
{
    if (g->count == g->capacity) {
        size_t cap = g->capacity ? g->capacity * 2 : 256;
        void *n = ibl_alloc(ctx, cap * g->elem);
        if (!n) return 0;
        if (g->data) memcpy(n, g->data, g->count * g->elem);
        ibl_free(ctx, g->data);
        g->data = n;
        g->capacity = cap;
    }
    memcpy((char *)g->data + g->count * g->elem, item, g->elem);
    g->count++;
    return 1;
}

static const float *tri_vertex(const ibl_mesh *m, int tri, int corner)
{
    return m->positions + 3 * m->indices[3 * tri + corner];
}

static void tri_bounds(const ibl_mesh *m, int tri, float lo[3], float hi[3], float c[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = FLT_MAX;
        hi[k] = -FLT_MAX;
    }
    for (int v = 0; v < 3; v++) {
        const float *p = tri_vertex(m, tri, v);
        for (int k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], p[k]);
            hi[k] = fmaxf(hi[k], p[k]);
        }
    }
    for (int k = 0; k < 3; k++) c[k] = 0.5f * (lo[k] + hi[k]);
}

static int build_node(const ibl_mesh *m, bvh *b, int first, int count)
{
    int index = b->node_count++;
    bvh_node *node = &b->nodes[index];
    float clo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, chi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    for (int k = 0; k < 3; k++) {
        node->lo[k] = FLT_MAX;
        node->hi[k] = -FLT_MAX;
    }
    for (int i = first; i < first + count; i++) {
        float lo[3], hi[3], c[3];
        tri_bounds(m, b->order[i], lo, hi, c);
        for (int k = 0; k < 3; k++) {
            node->lo[k] = fminf(node->lo[k], lo[k]);
            node->hi[k] = fmaxf(node->hi[k], hi[k]);
            clo[k] = fminf(clo[k], c[k]);
            chi[k] = fmaxf(chi[k], c[k]);
        }
    }
    if (count <= 4) {
        node->first = first;
        node->count = count;
        return index;
    }
    int axis = 0;
    for (int k = 1; k < 3; k++)
        if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
    float split = 0.5f * (clo[axis] + chi[axis]);
    /* partition by the centroid midpoint; fall back to halves when everything lands on one side */
    int i = first, j = first + count - 1;
    while (i <= j) {
        float lo[3], hi[3], c[3];
        tri_bounds(m, b->order[i], lo, hi, c);
        if (c[axis] < split)
            i++;
        else {
            int t = b->order[i];
            b->order[i] = b->order[j];
            b->order[j--] = t;
        }
    }
    int left_count = i - first;
    if (left_count == 0 || left_count == count) left_count = count / 2;
    node->count = 0;
    int l = build_node(m, b, first, left_count);
    int r = build_node(m, b, first + left_count, count - left_count);
    b->nodes[index].left = l;
    b->nodes[index].right = r;
    return index;
}

static int ray_box(const float lo[3], const float hi[3], const float o[3], const float inv[3],
                   float tmax)
{
    float t0 = 0.0f, t1 = tmax;
    for (int k = 0; k < 3; k++) {
        float a = (lo[k] - o[k]) * inv[k], b = (hi[k] - o[k]) * inv[k];
        if (a > b) {
            float t = a;
            a = b;
            b = t;
        }
        t0 = a > t0 ? a : t0;
        t1 = b < t1 ? b : t1;
        if (t0 > t1) return 0;
    }
    return 1;
}

/* Moller & Trumbore 1997. */
static int ray_triangle(const ibl_mesh *m, int tri, const float o[3], const float d[3], float *t,
                        float *u, float *v)
{
    const float *a = tri_vertex(m, tri, 0), *b = tri_vertex(m, tri, 1), *c = tri_vertex(m, tri, 2);
    float e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    float e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    float p[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2],
                  d[0] * e2[1] - d[1] * e2[0]};
    float det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (fabsf(det) < 1e-12f) return 0;
    float inv = 1.0f / det;
    float s[3] = {o[0] - a[0], o[1] - a[1], o[2] - a[2]};
    float uu = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) * inv;
    if (uu < 0.0f || uu > 1.0f) return 0;
    float q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2],
                  s[0] * e1[1] - s[1] * e1[0]};
    float vv = (d[0] * q[0] + d[1] * q[1] + d[2] * q[2]) * inv;
    if (vv < 0.0f || uu + vv > 1.0f) return 0;
    float tt = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) * inv;
    if (tt <= 1e-5f) return 0;
    *t = tt;
    *u = uu;
    *v = vv;
    return 1;
}

/* Nearest hit: triangle index or -1. */
static int trace(const ibl_mesh *m, ibl_vec3 origin, ibl_vec3 dir, float tmax, float *t_out,
                 float *u_out, float *v_out, int any)
{
    const bvh *b = m->accel;
    float o[3] = {origin.x, origin.y, origin.z}, d[3] = {dir.x, dir.y, dir.z};
    float inv[3];
    for (int k = 0; k < 3; k++) inv[k] = 1.0f / (d[k] != 0.0f ? d[k] : 1e-30f);
    int stack[128], sp = 0, best = -1;
    float best_t = tmax;
    stack[sp++] = 0;
    while (sp > 0) {
        const bvh_node *n = &b->nodes[stack[--sp]];
        if (!ray_box(n->lo, n->hi, o, inv, best_t)) continue;
        if (n->count > 0) {
            for (int i = n->first; i < n->first + n->count; i++) {
                float t, u, v;
                if (ray_triangle(m, b->order[i], o, d, &t, &u, &v) && t < best_t) {
                    best_t = t;
                    best = b->order[i];
                    if (u_out) *u_out = u;
                    if (v_out) *v_out = v;
                    if (any) return best;
                }
            }
        } else if (sp < 126) {
            stack[sp++] = n->left;
            stack[sp++] = n->right;
        }
    }
    if (t_out) *t_out = best_t;
    return best;
}

int ibl__mesh_intersect(const ibl_mesh *m, ibl_vec3 o, ibl_vec3 d, float *t, ibl_vec3 *n, float *ao)
{
    float u = 0, v = 0;
    int tri = trace(m, o, d, FLT_MAX, t, &u, &v, 0);
    if (tri < 0) return 0;
    float w[3] = {1.0f - u - v, u, v};
    ibl_vec3 nn = {0, 0, 0};
    float a = 0.0f;
    for (int c = 0; c < 3; c++) {
        int vi = m->indices[3 * tri + c];
        nn.x += w[c] * m->normals[3 * vi];
        nn.y += w[c] * m->normals[3 * vi + 1];
        nn.z += w[c] * m->normals[3 * vi + 2];
        a += w[c] * m->ao[vi];
    }
    nn = ibl__norm(nn);
    /* two-sided: face the viewer */
    if (ibl__dot(nn, d) > 0.0f) nn = ibl__v3(-nn.x, -nn.y, -nn.z);
    *n = nn;
    *ao = a;
    return 1;
}

typedef struct ao_job {
    ibl_mesh *mesh;
    int rays;
} ao_job;

enum { AO_CHUNK = 64 };

static void ao_task(void *arg, int chunk)
{
    ao_job *job = arg;
    ibl_mesh *m = job->mesh;
    int end = (chunk + 1) * AO_CHUNK;
    if (end > m->vertex_count) end = m->vertex_count;
    for (int i = chunk * AO_CHUNK; i < end; i++) {
        ibl_vec3 n = ibl__v3(m->normals[3 * i], m->normals[3 * i + 1], m->normals[3 * i + 2]);
        ibl_vec3 p =
            ibl__v3(m->positions[3 * i] + 1e-3f * n.x, m->positions[3 * i + 1] + 1e-3f * n.y,
                    m->positions[3 * i + 2] + 1e-3f * n.z);
        ibl_vec3 t, b;
        ibl__frame(n, &t, &b);
        float r0 = (float)(ibl__hash((uint32_t)i) >> 8) * (1.0f / 16777216.0f);
        int open = 0;
        for (int k = 0; k < job->rays; k++) {
            float u0, u1;
            ibl__hammersley((uint32_t)k, (uint32_t)job->rays, r0, 0.0f, &u0, &u1);
            float rr = sqrtf(u1), phi = 6.2831853f * u0;
            float x = rr * cosf(phi), y = rr * sinf(phi), z = sqrtf(fmaxf(0.0f, 1.0f - u1));
            ibl_vec3 d = ibl__v3(t.x * x + b.x * y + n.x * z, t.y * x + b.y * y + n.y * z,
                                 t.z * x + b.z * y + n.z * z);
            if (trace(m, p, d, FLT_MAX, NULL, NULL, NULL, 1) < 0) open++;
        }
        m->ao[i] = (float)open / (float)job->rays;
    }
}

static int parse_index(const char *tok, int count)
{
    long v = strtol(tok, NULL, 10);
    if (v < 0)
        v = count + v; /* relative */
    else
        v -= 1;
    return (v < 0 || v >= count) ? -1 : (int)v;
}

ibl_status ibl_mesh_load_obj(ibl_context *ctx, const char *path, int ao_rays, ibl_mesh *out)
{
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "r");
    if (!f) return ibl__fail(ctx, IBL_ERR_IO, "%s: cannot open (%s)", path, strerror(errno));
    growable pos = {0, 0, 0, sizeof(float) * 4}, idx = {0, 0, 0, sizeof(int) * 3};
    ibl_status st = IBL_OK;
    int have_colour = 1;
    char line[4096];
    int line_no = 0;
    while (fgets(line, sizeof line, f)) {
        line_no++;
        if (line[0] == 'v' && line[1] == ' ') {
            float p[4] = {0, 0, 0, 1}, rgb[3];
            int n = sscanf(line + 2, "%f %f %f %f %f %f", &p[0], &p[1], &p[2], &rgb[0], &rgb[1],
                           &rgb[2]);
            if (n < 3) {
                st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s:%d: bad vertex", path, line_no);
                break;
            }
            if (n >= 6)
                p[3] = rgb[0];
            else
                have_colour = 0;
            if (!grow_push(ctx, &pos, p)) {
                st = ibl_context_status(ctx);
                break;
            }
        } else if (line[0] == 'f' && line[1] == ' ') {
            int corners[64], nc = 0;
            char *save = NULL;
            for (char *tok = strtok_r(line + 2, " \t\r\n", &save); tok && nc < 64;
                 tok = strtok_r(NULL, " \t\r\n", &save)) {
                int vi = parse_index(tok, (int)pos.count);
                if (vi < 0) {
                    st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s:%d: bad face index", path, line_no);
                    break;
                }
                corners[nc++] = vi;
            }
            if (st != IBL_OK) break;
            for (int k = 2; k < nc; k++) {
                int tri[3] = {corners[0], corners[k - 1], corners[k]};
                if (!grow_push(ctx, &idx, tri)) {
                    st = ibl_context_status(ctx);
                    break;
                }
            }
            if (st != IBL_OK) break;
        }
    }
    fclose(f);
    if (st == IBL_OK && (pos.count == 0 || idx.count == 0))
        st = ibl__fail(ctx, IBL_ERR_FORMAT, "%s: no triangles", path);
    if (st != IBL_OK) {
        ibl_free(ctx, pos.data);
        ibl_free(ctx, idx.data);
        return st;
    }
    int nv = (int)pos.count, nt = (int)idx.count;
    out->vertex_count = nv;
    out->triangle_count = nt;
    out->positions = ibl_alloc(ctx, sizeof(float) * 3 * nv);
    out->normals = ibl_calloc(ctx, (size_t)3 * nv, sizeof(float));
    out->ao = ibl_alloc(ctx, sizeof(float) * nv);
    out->indices = idx.data;
    bvh *b = ibl_calloc(ctx, 1, sizeof *b);
    out->accel = b;
    if (b) {
        b->nodes = ibl_alloc(ctx, sizeof(bvh_node) * 2 * (size_t)nt);
        b->order = ibl_alloc(ctx, sizeof(int) * (size_t)nt);
    }
    if (!out->positions || !out->normals || !out->ao || !b || !b->nodes || !b->order) {
        ibl_free(ctx, pos.data);
        ibl_mesh_free(ctx, out);
        return ibl_context_status(ctx);
    }
    /* centre the mesh and scale it to the height the sphere grid takes in the preview */
    float lo[3] = {FLT_MAX, FLT_MAX, FLT_MAX}, hi[3] = {-FLT_MAX, -FLT_MAX, -FLT_MAX};
    const float *p4 = pos.data;
    for (int i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fminf(lo[k], p4[4 * i + k]);
            hi[k] = fmaxf(hi[k], p4[4 * i + k]);
        }
    float extent = fmaxf(hi[0] - lo[0], fmaxf(hi[1] - lo[1], hi[2] - lo[2]));
    float s = extent > 0.0f ? 3.2f / extent : 1.0f;
    for (int i = 0; i < nv; i++) {
        for (int k = 0; k < 3; k++)
            out->positions[3 * i + k] = (p4[4 * i + k] - 0.5f * (lo[k] + hi[k])) * s;
        out->ao[i] = fminf(1.0f, fmaxf(0.0f, p4[4 * i + 3]));
    }
    ibl_free(ctx, pos.data);
    /* area-weighted smooth normals: the cross product's length is twice the area */
    for (int t = 0; t < nt; t++) {
        const float *a = tri_vertex(out, t, 0), *bb = tri_vertex(out, t, 1),
                    *c = tri_vertex(out, t, 2);
        float e1[3] = {bb[0] - a[0], bb[1] - a[1], bb[2] - a[2]},
              e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        float n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                      e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++)
            for (int v = 0; v < 3; v++) out->normals[3 * out->indices[3 * t + k] + v] += n[v];
    }
    for (int i = 0; i < nv; i++) {
        ibl_vec3 n = ibl__norm(
            ibl__v3(out->normals[3 * i], out->normals[3 * i + 1], out->normals[3 * i + 2]));
        if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) n.y = 1.0f;
        out->normals[3 * i] = n.x;
        out->normals[3 * i + 1] = n.y;
        out->normals[3 * i + 2] = n.z;
    }
    for (int t = 0; t < nt; t++) b->order[t] = t;
    build_node(out, b, 0, nt);
    if (!have_colour) {
        ao_job job = {out, ao_rays > 0 ? ao_rays : 64};
        ibl_parallel_for(ctx, (nv + AO_CHUNK - 1) / AO_CHUNK, ao_task, &job);
    }
    return IBL_OK;
}

void ibl_mesh_free(ibl_context *ctx, ibl_mesh *m)
{
    if (!m) return;
    bvh *b = m->accel;
    if (b) {
        ibl_free(ctx, b->nodes);
        ibl_free(ctx, b->order);
        ibl_free(ctx, b);
    }
    ibl_free(ctx, m->positions);
    ibl_free(ctx, m->normals);
    ibl_free(ctx, m->ao);
    ibl_free(ctx, m->indices);
    memset(m, 0, sizeof *m);
}
