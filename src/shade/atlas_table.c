/* The coordinate table of the 2D mip atlas (Daqi 2016, 6.1: "an array is declared to store
 * their relative coordinates") as text: what the bake manifest's "atlas" object and the KTX2
 * key "ibl.atlas" hold, so that an engine uploads the rectangles without recomputing the
 * arrangement (docs/ATLAS.md). Reading checks the table against ibl_atlas_plan: a table
 * that is not the arrangement this library makes for its level-0 size is refused, so every
 * table a shader receives addresses texels that exist. */
#include "shade/atlas_table.h"
#include "core/context_internal.h"

#include <string.h>

enum { IBL__ATLAS_MAX_EDGE = 65536 }; /* the largest image edge the readers accept */

json_t *ibl__atlas_layout_json(const ibl_atlas_layout *l)
{
    json_t *o = json_object();
    ibl__json_set(o, "width", ibl__json_number(l->width));
    ibl__json_set(o, "height", ibl__json_number(l->height));
    ibl__json_set(o, "levels", ibl__json_number(l->levels));
    ibl__json_set(o, "gutter", ibl__json_number(l->gutter));
    ibl__json_set(o, "face_order", ibl__json_string("3x2 per level: +X -X +Y / -Y +Z -Z"));
    json_t *rects = json_array();
    for (int k = 0; k < l->levels; k++) {
        json_t *r = json_array();
        ibl__json_append(r, ibl__json_number(l->x[k]));
        ibl__json_append(r, ibl__json_number(l->y[k]));
        ibl__json_append(r, ibl__json_number(l->face_size[k]));
        ibl__json_append(rects, r);
    }
    ibl__json_set(o, "rects", rects);
    return o;
}

static int same_layout(const ibl_atlas_layout *a, const ibl_atlas_layout *b)
{
    if (a->width != b->width || a->height != b->height || a->levels != b->levels ||
        a->gutter != b->gutter)
        return 0;
    for (int k = 0; k < a->levels; k++)
        if (a->x[k] != b->x[k] || a->y[k] != b->y[k] || a->face_size[k] != b->face_size[k]) return 0;
    return 1;
}

void ibl__atlas_layout_read(ibl__json_reader *r, json_t *o, const char *path, ibl_atlas_layout *out)
{
    memset(out, 0, sizeof *out);
    out->width = ibl__json_get_int(r, o, path, "width", 1, IBL__ATLAS_MAX_EDGE);
    out->height = ibl__json_get_int(r, o, path, "height", 1, IBL__ATLAS_MAX_EDGE);
    out->levels = ibl__json_get_int(r, o, path, "levels", 1, IBL_MAX_LEVELS);
    out->gutter = ibl__json_get_int(r, o, path, "gutter", 0, 64);
    json_t *rects = ibl__json_array(r, o, path, "rects");
    if (r->status != IBL_OK || !rects) return;
    if ((int)json_array_size(rects) != out->levels) {
        ibl__json_fail(r, path, "rects", "holds %d rectangles for %d levels",
                       (int)json_array_size(rects), out->levels);
        return;
    }
    for (int k = 0; k < out->levels; k++) {
        json_t *rect = json_array_get(rects, (size_t)k);
        int v[3] = {-1, -1, -1};
        for (int i = 0; i < 3 && json_is_array(rect) && json_array_size(rect) == 3; i++) {
            json_t *e = json_array_get(rect, (size_t)i);
            if (json_is_integer(e) && json_integer_value(e) >= 0 &&
                json_integer_value(e) <= IBL__ATLAS_MAX_EDGE)
                v[i] = (int)json_integer_value(e);
        }
        if (v[0] < 0 || v[1] < 0 || v[2] < 1) {
            ibl__json_fail(r, path, "rects", "rectangle %d is not [x, y, face_size] of "
                                             "non-negative integers", k);
            return;
        }
        out->x[k] = v[0];
        out->y[k] = v[1];
        out->face_size[k] = v[2];
    }
    ibl_atlas_layout plan;
    ibl_atlas_desc d = {.gutter = out->gutter ? out->gutter : -1};
    if (ibl_atlas_plan(out->face_size[0], out->levels, &d, &plan) != IBL_OK ||
        !same_layout(&plan, out))
        ibl__json_fail(r, path, "rects", "is not the atlas arrangement of a %d-level chain of "
                                         "size %d (docs/ATLAS.md)", out->levels, out->face_size[0]);
}

ibl_status ibl_atlas_layout_to_json(ibl_context *ctx, const ibl_atlas_layout *layout, char **text)
{
    if (!text) return IBL_ERR_INVALID_ARGUMENT;
    *text = NULL;
    if (!layout || layout->levels < 1 || layout->levels > IBL_MAX_LEVELS)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "atlas table: no layout");
    return ibl__json_text_compact(ctx, ibl__atlas_layout_json(layout), "atlas table", text);
}

ibl_status ibl_atlas_layout_from_json(ibl_context *ctx, const char *text, const char *name,
                                      ibl_atlas_layout *out)
{
    if (!name) name = "atlas table";
    memset(out, 0, sizeof *out);
    if (!text) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: no text", name);
    json_t *root = NULL;
    ibl_status st = ibl__json_parse(ctx, text, strlen(text), name, &root);
    if (st != IBL_OK) return st;
    ibl__json_reader r = {ctx, name, IBL_OK};
    if (!json_is_object(root)) ibl__json_fail(&r, "", "", "expected an object");
    else ibl__atlas_layout_read(&r, root, "", out);
    json_decref(root);
    if (r.status != IBL_OK) memset(out, 0, sizeof *out);
    return r.status;
}
