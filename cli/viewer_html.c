/* Assembling the page of `ibl view` (viewer_html.h): the template of viewer/viewer.html with
 * its @IBL_...@ slots filled, and the JSON block the page's script reads:
 *   {"format": "ibl-viewer", "version": 1, "title", "probe": base64 of ibl_shader_probe,
 *    "sh_bands", "exposure", "textures": {name: {target, width, height, depth, levels, channels, type,
 *    bytes, fnv, data}}, "spheres": [...], "manifest": {...}}
 * Texture bytes are little-endian half floats (f16) or floats (f32), cube faces level-major
 * in OpenGL's order as ibl stores them; `fnv` (FNV-1a, 32 bits) lets the page refuse a
 * corrupted texture with a message instead of drawing black. */
#include "viewer_html.h"

#include "core/pixel_format.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* viewer_assets.c, generated from viewer/ and shaders/ibl.glsl by viewer/embed.cmake */
extern const char ibl_viewer_template[], ibl_viewer_css[], ibl_viewer_js[],
    ibl_viewer_scene_frag[], ibl_viewer_ibl_glsl[];

enum { TONEMAP_LUT_SIZE = 4096 };

/* ---- a growing string ------------------------------------------------------------------ */

typedef struct sbuf {
    char *data;
    size_t len, cap;
    int failed;
} sbuf;

static void sb_reserve(sbuf *b, size_t extra)
{
    if (b->failed || b->cap - b->len > extra) return;
    size_t cap = b->cap ? b->cap : 1 << 16;
    while (cap - b->len <= extra) {
        if (cap > SIZE_MAX / 2) {
            b->failed = 1;
            return;
        }
        cap *= 2;
    }
    char *grown = realloc(b->data, cap);
    if (!grown) {
        b->failed = 1;
        return;
    }
    b->data = grown;
    b->cap = cap;
}

static void sb_put(sbuf *b, const char *s, size_t n)
{
    sb_reserve(b, n + 1);
    if (b->failed) return;
    memcpy(b->data + b->len, s, n);
    b->len += n;
    b->data[b->len] = 0;
}

static void sb_str(sbuf *b, const char *s) { sb_put(b, s, strlen(s)); }

static void sb_printf(sbuf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void sb_printf(sbuf *b, const char *fmt, ...)
{
    char tmp[512];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof tmp) {
        b->failed = 1;
        return;
    }
    sb_put(b, tmp, (size_t)n);
}

/* A JSON string; "</" is written "<\/" so that no text can close the page's script element. */
static void sb_json_string(sbuf *b, const char *s)
{
    sb_str(b, "\"");
    for (unsigned char prev = 0, c; (c = (unsigned char)*s) != 0; s++, prev = c) {
        if (c == '"' || c == '\\') sb_printf(b, "\\%c", c);
        else if (c < 0x20) sb_printf(b, "\\u%04x", c);
        else if (c == '/' && prev == '<') sb_str(b, "\\/");
        else sb_put(b, (const char *)&c, 1);
    }
    sb_str(b, "\"");
}

static void sb_base64(sbuf *b, const uint8_t *p, size_t n)
{
    static const char abc[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    sb_reserve(b, (n + 2) / 3 * 4 + 1);
    if (b->failed) return;
    char *o = b->data + b->len;
    size_t i = 0;
    for (; i + 3 <= n; i += 3) {
        uint32_t v = (uint32_t)p[i] << 16 | (uint32_t)p[i + 1] << 8 | p[i + 2];
        *o++ = abc[v >> 18];
        *o++ = abc[v >> 12 & 63];
        *o++ = abc[v >> 6 & 63];
        *o++ = abc[v & 63];
    }
    if (i < n) {
        uint32_t v = (uint32_t)p[i] << 16 | (i + 1 < n ? (uint32_t)p[i + 1] << 8 : 0);
        *o++ = abc[v >> 18];
        *o++ = abc[v >> 12 & 63];
        *o++ = i + 1 < n ? abc[v >> 6 & 63] : '=';
        *o++ = '=';
    }
    b->len = (size_t)(o - b->data);
    b->data[b->len] = 0;
}

static uint32_t fnv1a(const uint8_t *p, size_t n)
{
    uint32_t h = 2166136261u;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 16777619u;
    return h;
}

/* ---- textures ---------------------------------------------------------------------------- */

typedef struct tex_desc {
    const char *name, *target; /* "cube", "2d", "3d" */
    int width, height, depth, levels, channels, is_f32;
} tex_desc;

/* Writes "name": {...} with the bytes (already in their stored type). */
static void put_texture(sbuf *b, const tex_desc *t, const uint8_t *bytes, size_t n, int first)
{
    sb_printf(b, "%s\n\"%s\": {\"target\": \"%s\", \"width\": %d, \"height\": %d, \"depth\": %d, "
                 "\"levels\": %d, \"channels\": %d, \"type\": \"%s\", \"bytes\": %zu, "
                 "\"fnv\": %lu, \"data\": \"",
              first ? "" : ",", t->name, t->target, t->width, t->height, t->depth, t->levels,
              t->channels, t->is_f32 ? "f32" : "f16", n, (unsigned long)fnv1a(bytes, n));
    sb_base64(b, bytes, n);
    sb_str(b, "\"}");
}

/* Half floats of `count` samples of `stride` floats, keeping the first `channels`. */
static uint8_t *to_half(const float *src, size_t count, int stride, int channels, size_t *n)
{
    *n = count * (size_t)channels * 2;
    uint8_t *out = malloc(*n ? *n : 1);
    if (!out) return NULL;
    for (size_t i = 0; i < count; i++)
        for (int c = 0; c < channels; c++) {
            uint16_t h = ibl_float_to_half(src[i * (size_t)stride + (size_t)c]);
            size_t at = (i * (size_t)channels + (size_t)c) * 2;
            out[at] = (uint8_t)(h & 0xff);
            out[at + 1] = (uint8_t)(h >> 8);
        }
    return out;
}

/* A cube (every level, RGBA16F); a missing one is 1x1 black. */
static int put_cube(sbuf *b, const char *name, const ibl_cubemap *cube, int first)
{
    static float black[6 * 4];
    ibl_cubemap none = {.size = 1, .levels = 1, .data = black};
    if (!cube->data) cube = &none;
    size_t texels = 0;
    for (int k = 0; k < cube->levels; k++) {
        size_t s = (size_t)ibl_level_size(cube->size, k);
        texels += 6 * s * s;
    }
    /* levels are contiguous, faces level-major (ibl_cubemap_face) */
    size_t n;
    uint8_t *bytes = to_half(ibl_cubemap_face(cube, 0, 0), texels, 4, 4, &n);
    if (!bytes) return 0;
    tex_desc t = {name, "cube", cube->size, cube->size, 1, cube->levels, 4, 0};
    put_texture(b, &t, bytes, n, first);
    free(bytes);
    return 1;
}

static int put_table(sbuf *b, const char *name, const char *target, const float *data,
                     int stride, int channels, int w, int h, int d)
{
    static const float zero[4];
    if (!data) {
        data = zero;
        stride = 4;
        w = h = d = 1;
    }
    size_t n;
    uint8_t *bytes = to_half(data, (size_t)w * h * d, stride, channels, &n);
    if (!bytes) return 0;
    tex_desc t = {name, target, w, h, d, 1, channels, 0};
    put_texture(b, &t, bytes, n, 0);
    free(bytes);
    return 1;
}

/* IEC 61966-2-1 encoding, for the display table below. */
static double srgb_encode(double v)
{
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

/* The display transform of `ibl render`'s PNGs as a table the page interpolates: row 0 the
 * filmic curve (ibl_tonemap_apply), row 1 a plain clamp, both then sRGB-encoded; sample i
 * holds x = 8 (i / (N - 1))^2 (dense near black; the curve is 1 from x = 7.24 on). */
static int put_tonemap(sbuf *b)
{
    float *lut = malloc(sizeof(float) * TONEMAP_LUT_SIZE * 2);
    if (!lut) return 0;
    for (int row = 0; row < 2; row++)
        for (int i = 0; i < TONEMAP_LUT_SIZE; i++) {
            double u = (double)i / (TONEMAP_LUT_SIZE - 1);
            float y = ibl_tonemap_apply(row ? IBL_TONEMAP_NONE : IBL_TONEMAP_FILMIC, (float)(8.0 * u * u));
            lut[row * TONEMAP_LUT_SIZE + i] = (float)srgb_encode(y);
        }
    /* little-endian floats, as the page reads them */
    size_t n = sizeof(float) * TONEMAP_LUT_SIZE * 2;
    uint8_t *bytes = malloc(n);
    if (!bytes) {
        free(lut);
        return 0;
    }
    for (size_t i = 0; i < TONEMAP_LUT_SIZE * 2; i++) {
        uint32_t v;
        memcpy(&v, &lut[i], 4);
        for (int k = 0; k < 4; k++) bytes[i * 4 + (size_t)k] = (uint8_t)(v >> (8 * k));
    }
    tex_desc t = {"tonemap", "2d", TONEMAP_LUT_SIZE, 2, 1, 1, 1, 1};
    put_texture(b, &t, bytes, n, 0);
    free(bytes);
    free(lut);
    return 1;
}

static int put_textures(sbuf *b, const ibl_probe *p)
{
    sb_str(b, ",\n\"textures\": {");
    int ok = put_cube(b, "specular", &p->specular, 1) && put_cube(b, "mirror", &p->mirror, 0) &&
             put_cube(b, "irradiance", &p->irradiance, 0);
    const ibl_splitsum_view *ss = &p->splitsum;
    ok = ok && put_table(b, "splitsum", "2d", ss->data, ss->channels ? ss->channels : 2, 2,
                         ss->n_dot_v.count, ss->roughness.count, 1);
    const ibl_ambient_brdf_view *ab = &p->ambient_brdf;
    ok = ok && put_table(b, "ambient_brdf", "3d", ab->data, ab->channels ? ab->channels : 1, 1,
                         ab->n_dot_v.count, ab->shininess.count, ab->f0.count);
    ok = ok && put_tonemap(b);
    sb_str(b, "}");
    return ok;
}

/* ---- the rest of the data block ------------------------------------------------------------ */

/* The sphere grid of `ibl render` (ibl_render_scene_objects): its materials. */
static void put_spheres(sbuf *b)
{
    ibl_render_object objects[64];
    int n = ibl_render_scene_objects(objects, 64);
    sb_str(b, ",\n\"spheres\": [");
    for (int i = 0; i < n; i++) {
        const ibl_material *m = &objects[i].material;
        sb_printf(b, "%s\n{\"model\": %d, \"base\": [%.9g, %.9g, %.9g], \"metallic\": %.9g, "
                     "\"roughness\": %.9g, \"f0\": [%.9g, %.9g, %.9g], \"shininess\": %.9g, "
                     "\"label\": ",
                  i ? "," : "", (int)m->model, m->base_color[0], m->base_color[1],
                  m->base_color[2], m->metallic, m->roughness, m->f0[0], m->f0[1], m->f0[2],
                  m->shininess);
        sb_json_string(b, objects[i].label);
        sb_str(b, "}");
    }
    sb_str(b, "]");
}

/* The manifest as it is, made safe inside a script element ("</" only occurs in strings). */
static void put_manifest(sbuf *b, const char *json)
{
    sb_str(b, ",\n\"manifest\": ");
    for (const char *s = json; *s; s++) {
        if (s[0] == '/' && s > json && s[-1] == '<') sb_put(b, "\\", 1);
        sb_put(b, s, 1);
    }
}

static int build_data(sbuf *b, const viewer_input *in)
{
    sb_str(b, "{\"format\": \"ibl-viewer\", \"version\": 1, \"title\": ");
    sb_json_string(b, in->title);
    sb_printf(b, ", \"sh_bands\": %d, \"exposure\": %.9g, \"probe\": \"", in->sh_bands,
              (double)in->exposure);
    sb_base64(b, (const uint8_t *)in->block, sizeof *in->block);
    sb_str(b, "\"");
    if (!put_textures(b, in->probe)) return 0;
    put_spheres(b);
    put_manifest(b, in->manifest_json);
    sb_str(b, "}\n");
    return !b->failed;
}

/* ---- the template -------------------------------------------------------------------------- */

static const char *find_ci(const char *s, const char *needle)
{
    size_t n = strlen(needle);
    for (; *s; s++) {
        size_t i = 0;
        while (i < n && s[i] && (s[i] | 0x20) == (needle[i] | 0x20)) i++;
        if (i == n) return s;
    }
    return NULL;
}

/* HTML text of a title (the only slot that is not script or style). */
static void put_html_text(sbuf *b, const char *s)
{
    for (; *s; s++) {
        if (*s == '<') sb_str(b, "&lt;");
        else if (*s == '>') sb_str(b, "&gt;");
        else if (*s == '&') sb_str(b, "&amp;");
        else if (*s == '"') sb_str(b, "&quot;");
        else sb_put(b, s, 1);
    }
}

ibl_status viewer_html_build(const viewer_input *in, char **html, size_t *size, char *err,
                             size_t err_size)
{
    *html = NULL;
    *size = 0;
    const struct {
        const char *slot, *text, *closer;
    } inline_parts[] = {
        {"@IBL_CSS@", ibl_viewer_css, "</style"},
        {"@IBL_JS@", ibl_viewer_js, "</script"},
        {"@IBL_SCENE_FRAG@", ibl_viewer_scene_frag, "</script"},
        {"@IBL_GLSL@", ibl_viewer_ibl_glsl, "</script"},
    };
    enum { PARTS = sizeof inline_parts / sizeof inline_parts[0] };
    for (int i = 0; i < PARTS; i++)
        if (find_ci(inline_parts[i].text, inline_parts[i].closer)) {
            snprintf(err, err_size, "viewer: the text for %s contains %s", inline_parts[i].slot,
                     inline_parts[i].closer);
            return IBL_ERR_INVALID_ARGUMENT;
        }
    sbuf b = {0};
    for (const char *t = ibl_viewer_template; *t;) {
        const char *at = strstr(t, "@IBL_");
        const char *end = at ? strchr(at + 5, '@') : NULL;
        if (!at || !end) {
            sb_str(&b, t);
            break;
        }
        sb_put(&b, t, (size_t)(at - t));
        size_t len = (size_t)(end + 1 - at);
        int done = 0;
        for (int i = 0; i < PARTS && !done; i++)
            if (strlen(inline_parts[i].slot) == len && memcmp(at, inline_parts[i].slot, len) == 0) {
                sb_str(&b, inline_parts[i].text);
                done = 1;
            }
        if (!done && len == 11 && memcmp(at, "@IBL_TITLE@", len) == 0) {
            put_html_text(&b, in->title);
            done = 1;
        }
        if (!done && len == 10 && memcmp(at, "@IBL_DATA@", len) == 0) {
            if (!build_data(&b, in)) b.failed = 1;
            done = 1;
        }
        if (!done) sb_put(&b, at, len); /* not a slot: kept as it is */
        t = end + 1;
    }
    if (b.failed) {
        free(b.data);
        snprintf(err, err_size, "viewer: out of memory building the page");
        return IBL_ERR_OUT_OF_MEMORY;
    }
    *html = b.data;
    *size = b.len;
    return IBL_OK;
}
