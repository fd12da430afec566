/* Internal: JSON through jansson (Debian libjansson-dev) with the library's conventions:
 * strings that are not valid UTF-8 are written with U+FFFD in place of the bad bytes (a path
 * can hold any bytes; the JSON must stay valid), numbers that are not finite become null,
 * reals carry 9 significant digits (every float exactly), output is indented and ends with a
 * newline. Reading reports the position of a syntax error and the path of a bad field
 * ("specular.levels[3].roughness"). */
#ifndef IBL_IO_JSON_H
#define IBL_IO_JSON_H

#include "ibl/core.h"
#include "ibl/cubemap.h"

#include <jansson.h>

/* ---- writing ---- */

json_t *ibl__json_string(const char *s);  /* NULL s: JSON null */
json_t *ibl__json_number(double x);       /* integers stay integers; NaN/Inf: null */
json_t *ibl__json_float(float x);         /* the shortest text that reads back as x  */
json_t *ibl__json_bool(int b);
json_t *ibl__json_vec3(ibl_vec3 v);      /* [x, y, z] as floats                     */
/* Sets key to value (stealing the reference); a NULL value (allocation failure) is recorded
 * in the object as a failure that ibl__json_text reports. */
void ibl__json_set(json_t *object, const char *key, json_t *value);
void ibl__json_append(json_t *array, json_t *value);
/* The text of root (NUL-terminated, from ibl_alloc, freed with ibl_free); consumes root. */
ibl_status ibl__json_text(ibl_context *ctx, json_t *root, const char *name, char **text);
/* The same on one line without spaces or a final newline (key/value metadata). */
ibl_status ibl__json_text_compact(ibl_context *ctx, json_t *root, const char *name, char **text);

/* ---- reading ---- */

/* Parses bytes (refuses more than 16 MiB); the error names `name`, line and column. */
ibl_status ibl__json_parse(ibl_context *ctx, const void *bytes, size_t size, const char *name,
                           json_t **out);

/* A cursor for reading fields with their path in messages. */
typedef struct ibl__json_reader {
    ibl_context *ctx;
    const char *name; /* the file, first in every message */
    ibl_status status;
} ibl__json_reader;

/* Each getter fails (records "name: path: problem", sets r->status) and returns a fallback
 * when the field is missing or of the wrong type; "optional" ones return the fallback
 * silently when the field is absent or null. path is the object's own path ("" for root). */
json_t *ibl__json_object(ibl__json_reader *r, json_t *parent, const char *path, const char *key);
json_t *ibl__json_array(ibl__json_reader *r, json_t *parent, const char *path, const char *key);
double ibl__json_get_number(ibl__json_reader *r, json_t *parent, const char *path,
                            const char *key);
double ibl__json_opt_number(ibl__json_reader *r, json_t *parent, const char *path,
                            const char *key, double fallback);
int ibl__json_get_int(ibl__json_reader *r, json_t *parent, const char *path, const char *key,
                      int min, int max);
const char *ibl__json_get_string(ibl__json_reader *r, json_t *parent, const char *path,
                                 const char *key);
const char *ibl__json_opt_string(ibl__json_reader *r, json_t *parent, const char *path,
                                 const char *key, const char *fallback);
int ibl__json_opt_bool(ibl__json_reader *r, json_t *parent, const char *path, const char *key,
                       int fallback);
/* Records a failure about a field: "name: path.key: message". */
void ibl__json_fail(ibl__json_reader *r, const char *path, const char *key, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#endif
