/* JSON through jansson with the library's conventions (json.h says which and why). */
#include "io/json.h"
#include "core/context_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Set in an object whose field could not be allocated: ibl__json_text refuses such a tree
 * instead of writing a document with a field silently missing. */
static const char ALLOCATION_FAILED[] = "ibl:allocation-failed";

/* ---- writing ---------------------------------------------------------------------------- */

/* Length of the valid UTF-8 sequence at s (1..4), or 0 if the bytes there are not one
 * (overlong forms, surrogates and code points past U+10FFFF are invalid, as RFC 3629 says). */
static size_t utf8_sequence(const unsigned char *s)
{
    unsigned c = s[0];
    if (c < 0x80) return 1;
    size_t n;
    unsigned cp;
    if (c >= 0xC2 && c <= 0xDF) n = 2, cp = c & 0x1F;
    else if (c >= 0xE0 && c <= 0xEF) n = 3, cp = c & 0x0F;
    else if (c >= 0xF0 && c <= 0xF4) n = 4, cp = c & 0x07;
    else return 0;
    for (size_t i = 1; i < n; i++) {
        if ((s[i] & 0xC0) != 0x80) return 0;
        cp = (cp << 6) | (s[i] & 0x3F);
    }
    if ((n == 3 && (cp < 0x800 || (cp >= 0xD800 && cp <= 0xDFFF))) || (n == 4 && (cp < 0x10000 || cp > 0x10FFFF)))
        return 0;
    return n;
}

json_t *ibl__json_string(const char *s)
{
    if (!s) return json_null();
    size_t len = strlen(s), bad = 0;
    for (size_t i = 0; i < len;) {
        size_t n = utf8_sequence((const unsigned char *)s + i);
        if (n == 0) bad++, n = 1;
        i += n;
    }
    if (bad == 0) return json_stringn(s, len);
    /* each bad byte becomes U+FFFD (3 bytes) */
    char *clean = malloc(len + 2 * bad + 1);
    if (!clean) return NULL;
    size_t o = 0;
    for (size_t i = 0; i < len;) {
        size_t n = utf8_sequence((const unsigned char *)s + i);
        if (n == 0) {
            memcpy(clean + o, "\xEF\xBF\xBD", 3);
            o += 3;
            i++;
        } else {
            memcpy(clean + o, s + i, n);
            o += n;
            i += n;
        }
    }
    json_t *v = json_stringn(clean, o);
    free(clean);
    return v;
}

json_t *ibl__json_number(double x)
{
    if (!isfinite(x)) return json_null();
    if (x == floor(x) && fabs(x) < 9.0e15) return json_integer((json_int_t)x);
    return json_real(x);
}

json_t *ibl__json_float(float x)
{
    if (!isfinite(x)) return json_null();
    /* the shortest decimal that reads back as the same float (0.3f is "0.3", not the
     * 0.300000012 its double prints as) */
    char buf[32];
    for (int digits = 6; digits <= 9; digits++) {
        snprintf(buf, sizeof buf, "%.*g", digits, (double)x);
        if ((float)strtod(buf, NULL) == x) break;
    }
    return ibl__json_number(strtod(buf, NULL));
}

json_t *ibl__json_bool(int b) { return json_boolean(b); }

json_t *ibl__json_vec3(ibl_vec3 v)
{
    json_t *a = json_array();
    ibl__json_append(a, ibl__json_float(v.x));
    ibl__json_append(a, ibl__json_float(v.y));
    ibl__json_append(a, ibl__json_float(v.z));
    return a;
}

void ibl__json_set(json_t *object, const char *key, json_t *value)
{
    if (!object) return;
    if (!value || json_object_set_new(object, key, value) != 0)
        json_object_set_new(object, ALLOCATION_FAILED, json_true());
}

void ibl__json_append(json_t *array, json_t *value)
{
    if (!array) return;
    if (!value || json_array_append_new(array, value) != 0) {
        /* an array cannot carry the marker: replace its last slot by a marked object */
        json_t *mark = json_object();
        if (mark) json_object_set_new(mark, ALLOCATION_FAILED, json_true());
        if (mark) json_array_append_new(array, mark);
    }
}

static int tree_complete(const json_t *v)
{
    if (json_is_object(v)) {
        if (json_object_get(v, ALLOCATION_FAILED)) return 0;
        const char *key;
        json_t *child;
        json_object_foreach((json_t *)v, key, child) if (!tree_complete(child)) return 0;
    } else if (json_is_array(v)) {
        size_t i;
        json_t *child;
        json_array_foreach(v, i, child) if (!tree_complete(child)) return 0;
    }
    return 1;
}

static ibl_status json_text(ibl_context *ctx, json_t *root, const char *name, size_t flags,
                           char **text)
{
    *text = NULL;
    if (!root || !tree_complete(root)) {
        json_decref(root);
        return ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory building the JSON", name);
    }
    char *s = json_dumps(root, flags | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(9));
    json_decref(root);
    if (!s) return ibl__fail(ctx, IBL_ERR_OUT_OF_MEMORY, "%s: out of memory writing the JSON", name);
    size_t n = strlen(s);
    char *out = ibl_alloc(ctx, n + 2);
    if (!out) {
        free(s);
        return ibl__fail(ctx, ibl_context_status(ctx), "%s: out of memory writing the JSON", name);
    }
    memcpy(out, s, n);
    out[n] = '\n';
    out[n + 1] = 0;
    free(s);
    *text = out;
    return IBL_OK;
}

ibl_status ibl__json_text(ibl_context *ctx, json_t *root, const char *name, char **text)
{
    return json_text(ctx, root, name, JSON_INDENT(2), text);
}

ibl_status ibl__json_text_compact(ibl_context *ctx, json_t *root, const char *name, char **text)
{
    ibl_status st = json_text(ctx, root, name, JSON_COMPACT, text);
    if (st == IBL_OK) (*text)[strlen(*text) - 1] = 0; /* one line, no newline */
    return st;
}

/* ---- reading ---------------------------------------------------------------------------- */

enum { MAX_JSON_BYTES = 16 << 20 };

ibl_status ibl__json_parse(ibl_context *ctx, const void *bytes, size_t size, const char *name,
                           json_t **out)
{
    *out = NULL;
    if (size > MAX_JSON_BYTES)
        return ibl__fail(ctx, IBL_ERR_TOO_LARGE, "%s: %zu bytes is too large for a manifest", name,
                         size);
    json_error_t err;
    json_t *root = json_loadb(bytes, size, JSON_REJECT_DUPLICATES, &err);
    if (!root)
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: line %d, column %d: %s", name, err.line,
                         err.column, err.text);
    if (!json_is_object(root)) {
        json_decref(root);
        return ibl__fail(ctx, IBL_ERR_FORMAT, "%s: not a JSON object", name);
    }
    *out = root;
    return IBL_OK;
}

/* "path.key" (or "key" at the root) into buf */
static const char *field_path(char *buf, size_t cap, const char *path, const char *key)
{
    if (path && path[0] && key) snprintf(buf, cap, "%s.%s", path, key);
    else snprintf(buf, cap, "%s", key ? key : (path ? path : ""));
    return buf;
}

void ibl__json_fail(ibl__json_reader *r, const char *path, const char *key, const char *fmt, ...)
{
    if (r->status != IBL_OK) return; /* the first problem is the one reported */
    char where[256], what[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    r->status = ibl__fail(r->ctx, IBL_ERR_FORMAT, "%s: %s: %s", r->name,
                          field_path(where, sizeof where, path, key), what);
}

static json_t *field(ibl__json_reader *r, json_t *parent, const char *path, const char *key,
                     int required)
{
    json_t *v = json_is_object(parent) ? json_object_get(parent, key) : NULL;
    if ((!v || json_is_null(v)) && required) ibl__json_fail(r, path, key, "missing");
    return v && !json_is_null(v) ? v : NULL;
}

json_t *ibl__json_object(ibl__json_reader *r, json_t *parent, const char *path, const char *key)
{
    json_t *v = field(r, parent, path, key, 1);
    if (v && !json_is_object(v)) {
        ibl__json_fail(r, path, key, "expected an object");
        return NULL;
    }
    return v;
}

json_t *ibl__json_array(ibl__json_reader *r, json_t *parent, const char *path, const char *key)
{
    json_t *v = field(r, parent, path, key, 1);
    if (v && !json_is_array(v)) {
        ibl__json_fail(r, path, key, "expected an array");
        return NULL;
    }
    return v;
}

static double number_of(ibl__json_reader *r, json_t *v, const char *path, const char *key,
                        double fallback)
{
    if (!v) return fallback;
    if (!json_is_number(v)) {
        ibl__json_fail(r, path, key, "expected a number");
        return fallback;
    }
    return json_number_value(v);
}

double ibl__json_get_number(ibl__json_reader *r, json_t *parent, const char *path,
                            const char *key)
{
    return number_of(r, field(r, parent, path, key, 1), path, key, 0.0);
}

double ibl__json_opt_number(ibl__json_reader *r, json_t *parent, const char *path,
                            const char *key, double fallback)
{
    return number_of(r, field(r, parent, path, key, 0), path, key, fallback);
}

int ibl__json_get_int(ibl__json_reader *r, json_t *parent, const char *path, const char *key,
                      int min, int max)
{
    json_t *v = field(r, parent, path, key, 1);
    if (!v) return min;
    if (!json_is_integer(v) || json_integer_value(v) < min || json_integer_value(v) > max) {
        ibl__json_fail(r, path, key, "expected a whole number from %d to %d", min, max);
        return min;
    }
    return (int)json_integer_value(v);
}

const char *ibl__json_get_string(ibl__json_reader *r, json_t *parent, const char *path,
                                 const char *key)
{
    json_t *v = field(r, parent, path, key, 1);
    if (v && !json_is_string(v)) {
        ibl__json_fail(r, path, key, "expected a string");
        return "";
    }
    return v ? json_string_value(v) : "";
}

const char *ibl__json_opt_string(ibl__json_reader *r, json_t *parent, const char *path,
                                 const char *key, const char *fallback)
{
    json_t *v = field(r, parent, path, key, 0);
    if (!v) return fallback;
    if (!json_is_string(v)) {
        ibl__json_fail(r, path, key, "expected a string");
        return fallback;
    }
    return json_string_value(v);
}

int ibl__json_opt_bool(ibl__json_reader *r, json_t *parent, const char *path, const char *key,
                       int fallback)
{
    json_t *v = field(r, parent, path, key, 0);
    if (!v) return fallback;
    if (!json_is_boolean(v)) {
        ibl__json_fail(r, path, key, "expected true or false");
        return fallback;
    }
    return json_is_true(v);
}
