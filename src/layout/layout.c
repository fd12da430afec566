/* Layout names, detection from the aspect ratio, the orientation (yaw / mirror / z-up) and the
 * dispatch of the conversions between flat pictures and cubemaps. Conventions: docs/CONVENTIONS.md. */
#include "layout_internal.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>


/* ---- names ---- */

static const struct {
    ibl_layout layout;
    const char *name;
} names[] = {
    {IBL_LAYOUT_AUTO, "auto"},         {IBL_LAYOUT_EQUIRECT, "equirect"},
    {IBL_LAYOUT_HCROSS, "hcross"},     {IBL_LAYOUT_VCROSS, "vcross"},
    {IBL_LAYOUT_HSTRIP, "hstrip"},     {IBL_LAYOUT_VSTRIP, "vstrip"},
    {IBL_LAYOUT_ANGULAR, "angular"},   {IBL_LAYOUT_OCTAHEDRAL, "octahedral"},
    {IBL_LAYOUT_FACES, "faces"},       {IBL_LAYOUT_CUBE, "cube"},
    /* aliases accepted by ibl_layout_from_name only */
    {IBL_LAYOUT_EQUIRECT, "latlong"},  {IBL_LAYOUT_EQUIRECT, "equirectangular"},
    {IBL_LAYOUT_ANGULAR, "probe"},     {IBL_LAYOUT_OCTAHEDRAL, "octahedron"},
};

const char *ibl_layout_name(ibl_layout layout)
{
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (names[i].layout == layout) return names[i].name;
    return "unknown";
}

static int same_name(const char *a, const char *b)
{
    for (; *a && *b; a++, b++) {
        char ca = (*a >= 'A' && *a <= 'Z') ? (char)(*a - 'A' + 'a') : *a;
        if (ca != *b) return 0;
    }
    return *a == *b;
}

int ibl_layout_from_name(const char *name, ibl_layout *out)
{
    for (size_t i = 0; name && i < sizeof names / sizeof names[0]; i++)
        if (same_name(name, names[i].name)) {
            *out = names[i].layout;
            return 1;
        }
    return 0;
}

ibl_layout ibl_layout_detect(int width, int height)
{
    if (width <= 0 || height <= 0) return IBL_LAYOUT_AUTO;
    long w = width, h = height;
    if (w == 2 * h) return IBL_LAYOUT_EQUIRECT;
    if (w % 4 == 0 && h % 3 == 0 && w / 4 == h / 3) return IBL_LAYOUT_HCROSS;
    if (w % 3 == 0 && h % 4 == 0 && w / 3 == h / 4) return IBL_LAYOUT_VCROSS;
    if (w == 6 * h) return IBL_LAYOUT_HSTRIP;
    if (h == 6 * w) return IBL_LAYOUT_VSTRIP;
    if (w == h) return IBL_LAYOUT_ANGULAR;
    return IBL_LAYOUT_AUTO;
}

/* Does a picture of this size hold this layout exactly? */
static int size_fits(ibl_layout layout, int w, int h)
{
    int cols, rows;
    switch (layout) {
    case IBL_LAYOUT_EQUIRECT: return (long)w == 2L * h;
    case IBL_LAYOUT_ANGULAR:
    case IBL_LAYOUT_OCTAHEDRAL: return w == h;
    case IBL_LAYOUT_HCROSS:
    case IBL_LAYOUT_VCROSS:
    case IBL_LAYOUT_HSTRIP:
    case IBL_LAYOUT_VSTRIP:
        ibl__cube_layout_grid(layout, &cols, &rows);
        return w % cols == 0 && h % rows == 0 && w / cols == h / rows;
    default: return 0;
    }
}

static int nearest_power_of_two(double x)
{
    if (!(x > 1.0)) return 1;
    int p = (int)floor(log2(x) + 0.5);
    if (p > 20) p = 20;
    return 1 << p;
}

int ibl__natural_cube_size(ibl_layout layout, int width, int height)
{
    int cols, rows;
    (void)height;
    switch (layout) {
    /* equal texel density at the equator: 4 faces across 360 degrees */
    case IBL_LAYOUT_EQUIRECT: return nearest_power_of_two(width / 4.0);
    /* the angular map has about W/(2 pi) pixels per radian, a cube about 2N/pi */
    case IBL_LAYOUT_ANGULAR: return nearest_power_of_two(width / 4.0);
    /* centre-to-edge (W/2 pixels) spans 90 degrees, as a face does over N texels */
    case IBL_LAYOUT_OCTAHEDRAL: return nearest_power_of_two(width / 2.0);
    default:
        if (ibl__cube_layout_grid(layout, &cols, &rows)) return width / cols;
        return 0;
    }
}

/* ---- orientation ---- */

static void mat_mul(const double a[3][3], const double b[3][3], double out[3][3])
{
    double r[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) r[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
    memcpy(out, r, sizeof r);
}

void ibl__frame_from_matrix(const double m[3][3], ibl__frame *f)
{
    memcpy(f->m, m, sizeof f->m);
    f->identity = 1;
    f->permutation = 1;
    for (int i = 0; i < 3; i++) {
        int nonzero = 0;
        for (int j = 0; j < 3; j++) {
            double v = m[i][j];
            if (v != (i == j ? 1.0 : 0.0)) f->identity = 0;
            if (v != 0.0) {
                nonzero++;
                if (v != 1.0 && v != -1.0) f->permutation = 0;
            }
        }
        if (nonzero != 1) f->permutation = 0;
    }
}

/* An angle in degrees as cos/sin, exact at multiples of 90 so quarter turns stay permutations. */
static void cos_sin_degrees(double deg, double *c, double *s)
{
    double r = fmod(deg, 360.0);
    if (r < 0) r += 360.0;
    if (r == 0.0) { *c = 1; *s = 0; }
    else if (r == 90.0) { *c = 0; *s = 1; }
    else if (r == 180.0) { *c = -1; *s = 0; }
    else if (r == 270.0) { *c = 0; *s = -1; }
    else { *c = cos(r * IBL_PI / 180.0); *s = sin(r * IBL_PI / 180.0); }
}

/* world = Yaw * Mirror * Zup * picture: the picture's frame is first brought to +Y up, then
 * mirrored (x -> -x), then turned about +Y (right-handed: positive is counter-clockwise seen
 * from above, +X goes toward -Z). */
void ibl__frame_from_orientation(const ibl_orientation *o, ibl__frame *f)
{
    double m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    if (o) {
        if (o->z_up) {
            /* right-handed Z-up to right-handed Y-up: (x, y, z) -> (x, z, -y) */
            static const double zup[3][3] = {{1, 0, 0}, {0, 0, 1}, {0, -1, 0}};
            mat_mul(zup, m, m);
        }
        if (o->mirror) {
            static const double mir[3][3] = {{-1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
            mat_mul(mir, m, m);
        }
        if (o->yaw_degrees != 0.0f) {
            double c, s;
            cos_sin_degrees(o->yaw_degrees, &c, &s);
            double yaw[3][3] = {{c, 0, s}, {0, 1, 0}, {-s, 0, c}};
            mat_mul(yaw, m, m);
        }
    }
    ibl__frame_from_matrix(m, f);
}

void ibl__frame_transpose(const ibl__frame *f, ibl__frame *out)
{
    double t[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) t[i][j] = f->m[j][i];
    ibl__frame_from_matrix(t, out);
}

ibl_vec3 ibl_orientation_apply(const ibl_orientation *o, ibl_vec3 p)
{
    ibl__frame f;
    ibl__frame_from_orientation(o, &f);
    double in[3] = {p.x, p.y, p.z}, w[3];
    ibl__mul3(f.m, in, w);
    ibl_vec3 r = {(float)w[0], (float)w[1], (float)w[2]};
    return r;
}

ibl_vec3 ibl_orientation_invert(const ibl_orientation *o, ibl_vec3 w)
{
    ibl__frame f, t;
    ibl__frame_from_orientation(o, &f);
    ibl__frame_transpose(&f, &t);
    double in[3] = {w.x, w.y, w.z}, p[3];
    ibl__mul3(t.m, in, p);
    ibl_vec3 r = {(float)p[0], (float)p[1], (float)p[2]};
    return r;
}

/* ---- sphere layouts, public float entry points ---- */

int ibl_layout_direction(ibl_layout layout, float u, float v, ibl_vec3 *dir)
{
    double d[3] = {0, 0, 0};
    int ok;
    if (!(u >= 0.0f && u <= 1.0f && v >= 0.0f && v <= 1.0f)) return 0;
    switch (layout) {
    case IBL_LAYOUT_EQUIRECT: ok = ibl__equirect_dir(u, v, d); break;
    case IBL_LAYOUT_ANGULAR: ok = ibl__angular_dir(u, v, d); break;
    case IBL_LAYOUT_OCTAHEDRAL: ok = ibl__octahedral_dir(u, v, d); break;
    default: return 0;
    }
    if (ok && dir) {
        dir->x = (float)d[0];
        dir->y = (float)d[1];
        dir->z = (float)d[2];
    }
    return ok;
}

int ibl_layout_uv(ibl_layout layout, ibl_vec3 dir, float *u, float *v)
{
    double d[3] = {dir.x, dir.y, dir.z}, uu, vv;
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(len > 0.0)) return 0;
    for (int i = 0; i < 3; i++) d[i] /= len;
    switch (layout) {
    case IBL_LAYOUT_EQUIRECT: ibl__equirect_uv(d, &uu, &vv); break;
    case IBL_LAYOUT_ANGULAR: ibl__angular_uv(d, &uu, &vv); break;
    case IBL_LAYOUT_OCTAHEDRAL: ibl__octahedral_uv(d, &uu, &vv); break;
    default: return 0;
    }
    if (u) *u = (float)uu;
    if (v) *v = (float)vv;
    return 1;
}

/* ---- dispatch ---- */

enum { MAX_CUBE_SIZE = 32768 };

/* Turns the picture-frame cube into the requested world cube: moves it when nothing changes,
 * resamples for a new size, remaps through the orientation otherwise. Frees `picture`. */
static ibl_status finish_cube(ibl_context *ctx, ibl_cubemap *picture, const ibl__frame *frame,
                              int size, ibl_cubemap *out)
{
    ibl_status st;
    if (frame->identity && size == picture->size) {
        *out = *picture;
        memset(picture, 0, sizeof *picture);
        return IBL_OK;
    }
    st = ibl_cubemap_alloc(ctx, size, 1, out);
    if (st == IBL_OK) {
        if (frame->identity) {
            st = ibl_cubemap_resample(ctx, picture, out);
        } else {
            /* a world texel's direction d is seen in the picture at M^T d */
            ibl__frame inv;
            ibl__frame_transpose(frame, &inv);
            st = ibl__cube_remap(ctx, picture, 0, &inv, out);
        }
        if (st != IBL_OK) ibl_cubemap_free(ctx, out);
    }
    ibl_cubemap_free(ctx, picture);
    return st;
}

/* A one-level cube whose every texel the caller writes, left as the allocator gives it:
 * ibl_cubemap_alloc's zeroing would touch every page on this thread, serially (on a fresh
 * block: fault each one in and have the kernel clear it), before the workers write them all
 * again in parallel. */
static ibl_status cube_alloc_unzeroed(ibl_context *ctx, int size, ibl_cubemap *out)
{
    size_t n = ibl_cubemap_floats(size, 1);
    if (n == 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "invalid cubemap size %d", size);
    float *data = ibl_alloc(ctx, n * sizeof(float));
    if (!data) return ibl_context_status(ctx);
    ibl_cubemap_wrap(size, 1, data, out);
    out->owns_data = 1;
    return IBL_OK;
}

static ibl_status check_image(ibl_context *ctx, const char *what, const ibl_image *im)
{
    if (!im || !im->pixels || im->width <= 0 || im->height <= 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "%s: empty image (%dx%d)", what,
                        im ? im->width : 0, im ? im->height : 0);
    return IBL_OK;
}

int ibl_layout_cube_size(ibl_layout layout, int width, int height)
{
    if (layout == IBL_LAYOUT_AUTO) layout = ibl_layout_detect(width, height);
    if (layout == IBL_LAYOUT_AUTO || layout == IBL_LAYOUT_FACES || layout == IBL_LAYOUT_CUBE ||
        (int)layout < 0 || layout > IBL_LAYOUT_CUBE || width < 1 || height < 1 ||
        !size_fits(layout, width, height))
        return 0;
    int size = ibl__natural_cube_size(layout, width, height);
    return size >= 1 && size <= MAX_CUBE_SIZE ? size : 0;
}

ibl_status ibl_image_to_cubemap(ibl_context *ctx, const ibl_image *image,
                                const ibl_to_cube_desc *desc, ibl_cubemap *out)
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: no output cubemap");
    memset(out, 0, sizeof *out);
    ibl_status st = check_image(ctx, "layout", image);
    if (st != IBL_OK) return st;
    ibl_to_cube_desc d;
    memset(&d, 0, sizeof d);
    if (desc) d = *desc;
    int w = image->width, h = image->height;
    ibl_layout layout = d.layout;
    if (layout == IBL_LAYOUT_AUTO) {
        layout = ibl_layout_detect(w, h);
        if (layout == IBL_LAYOUT_AUTO)
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "layout: cannot tell the layout of a %dx%d image from its aspect "
                            "ratio; name it (equirect, hcross, vcross, hstrip, vstrip, angular, "
                            "octahedral)", w, h);
    }
    if (layout == IBL_LAYOUT_FACES || layout == IBL_LAYOUT_CUBE)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "layout: %s is not a single-picture layout (use ibl_faces_to_cubemap)",
                        ibl_layout_name(layout));
    if ((int)layout < 0 || layout > IBL_LAYOUT_CUBE)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: unknown layout %d", (int)layout);
    if (!size_fits(layout, w, h))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: a %dx%d image is not a %s image",
                        w, h, ibl_layout_name(layout));
    int size = d.size > 0 ? d.size : ibl__natural_cube_size(layout, w, h);
    if (d.size < 0 || size < 1 || size > MAX_CUBE_SIZE)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: cube size %d out of range", d.size);
    if (d.samples_per_axis < 0 || d.samples_per_axis > 64)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "layout: samples_per_axis %d out of range [0, 64]", d.samples_per_axis);
    ibl__frame frame;
    ibl__frame_from_orientation(&d.orientation, &frame);

    switch (layout) {
    case IBL_LAYOUT_EQUIRECT:
        st = cube_alloc_unzeroed(ctx, size, out);
        if (st != IBL_OK) return st;
        st = ibl__equirect_to_cube(ctx, image, &frame, d.samples_per_axis, out);
        break;
    case IBL_LAYOUT_ANGULAR:
    case IBL_LAYOUT_OCTAHEDRAL:
        st = ibl_cubemap_alloc(ctx, size, 1, out);
        if (st != IBL_OK) return st;
        st = ibl__sphere_to_cube(ctx, layout, image, &frame, d.samples_per_axis, out);
        break;
    default: {
        ibl_cubemap picture;
        int n = ibl__natural_cube_size(layout, w, h);
        st = ibl_cubemap_alloc(ctx, n, 1, &picture);
        if (st != IBL_OK) return st;
        ibl__cells_to_cube(layout, image, &picture);
        return finish_cube(ctx, &picture, &frame, size, out);
    }
    }
    if (st != IBL_OK) ibl_cubemap_free(ctx, out);
    return st;
}

ibl_status ibl_faces_to_cubemap(ibl_context *ctx, const ibl_image faces[6],
                                const ibl_to_cube_desc *desc, ibl_cubemap *out)
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: no output cubemap");
    memset(out, 0, sizeof *out);
    if (!faces) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "faces: no face images");
    static const char *face_names[6] = {"+X", "-X", "+Y", "-Y", "+Z", "-Z"};
    int n = faces[0].width;
    for (int f = 0; f < 6; f++) {
        ibl_status st = check_image(ctx, "faces", &faces[f]);
        if (st != IBL_OK) return st;
        if (faces[f].width != faces[f].height || faces[f].width != n)
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "faces: face %s is %dx%d; every face must be square and %dx%d",
                            face_names[f], faces[f].width, faces[f].height, n, n);
    }
    ibl_to_cube_desc d;
    memset(&d, 0, sizeof d);
    if (desc) d = *desc;
    int size = d.size > 0 ? d.size : n;
    if (d.size < 0 || size > MAX_CUBE_SIZE)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "faces: cube size %d out of range", d.size);
    ibl__frame frame;
    ibl__frame_from_orientation(&d.orientation, &frame);
    ibl_cubemap picture;
    ibl_status st = ibl_cubemap_alloc(ctx, n, 1, &picture);
    if (st != IBL_OK) return st;
    for (int f = 0; f < 6; f++)
        memcpy(ibl_cubemap_face(&picture, 0, f), faces[f].pixels, (size_t)n * n * 4 * sizeof(float));
    return finish_cube(ctx, &picture, &frame, size, out);
}

ibl_status ibl_cubemap_to_image(ibl_context *ctx, const ibl_cubemap *cube,
                                const ibl_from_cube_desc *desc, ibl_image *out)
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: no output image");
    memset(out, 0, sizeof *out);
    if (!cube || !cube->data || cube->size <= 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: empty cubemap");
    if (!desc) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: no descriptor (the layout is required)");
    ibl_from_cube_desc d = *desc;
    if (d.level < 0 || d.level >= cube->levels)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: level %d out of range [0, %d]",
                        d.level, cube->levels - 1);
    if (d.width < 0 || d.width > 8 * MAX_CUBE_SIZE)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "layout: width %d out of range", d.width);
    if (d.samples_per_axis < 0 || d.samples_per_axis > 64)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "layout: samples_per_axis %d out of range [0, 64]", d.samples_per_axis);
    int n = ibl_level_size(cube->size, d.level);
    ibl__frame frame;
    ibl__frame_from_orientation(&d.orientation, &frame);
    ibl_cubemap level_view;
    ibl_status st = ibl_cubemap_wrap(n, 1, ibl_cubemap_face(cube, d.level, 0), &level_view);
    if (st != IBL_OK) return ibl__fail(ctx, st, "layout: bad cubemap");
    int cols, rows;
    switch (d.layout) {
    case IBL_LAYOUT_EQUIRECT:
    case IBL_LAYOUT_ANGULAR:
    case IBL_LAYOUT_OCTAHEDRAL: {
        int width = d.width;
        if (width == 0) width = d.layout == IBL_LAYOUT_EQUIRECT ? 4 * n
                                : d.layout == IBL_LAYOUT_ANGULAR ? 4 * n : 2 * n;
        int height = d.layout == IBL_LAYOUT_EQUIRECT ? width / 2 : width;
        if (d.layout == IBL_LAYOUT_EQUIRECT && (width < 2 || width % 2))
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "layout: an equirect image needs an even width (got %d)", width);
        st = ibl_image_alloc(ctx, width, height, out);
        if (st != IBL_OK) return st;
        st = ibl__cube_to_sphere(ctx, &level_view, 0, d.layout, &frame, d.samples_per_axis, out);
        if (st != IBL_OK) ibl_image_free(ctx, out);
        return st;
    }
    case IBL_LAYOUT_HCROSS:
    case IBL_LAYOUT_VCROSS:
    case IBL_LAYOUT_HSTRIP:
    case IBL_LAYOUT_VSTRIP: {
        ibl__cube_layout_grid(d.layout, &cols, &rows);
        if (d.width % cols)
            return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                            "layout: a %s image's width must be a multiple of %d (got %d)",
                            ibl_layout_name(d.layout), cols, d.width);
        int m = d.width ? d.width / cols : n;
        st = ibl_image_alloc(ctx, m * cols, m * rows, out);
        if (st != IBL_OK) return st;
        if (frame.identity && m == n) {
            ibl__cube_to_cells(d.layout, &level_view, 0, out);
            return IBL_OK;
        }
        ibl_cubemap tmp;
        st = ibl_cubemap_alloc(ctx, m, 1, &tmp);
        if (st == IBL_OK) {
            /* a picture texel's direction p is the world direction M p */
            st = frame.identity ? ibl_cubemap_resample(ctx, &level_view, &tmp)
                                : ibl__cube_remap(ctx, &level_view, 0, &frame, &tmp);
            if (st == IBL_OK) ibl__cube_to_cells(d.layout, &tmp, 0, out);
            ibl_cubemap_free(ctx, &tmp);
        }
        if (st != IBL_OK) ibl_image_free(ctx, out);
        return st;
    }
    default:
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "layout: cannot write a cube as layout '%s' (use ibl_cubemap_to_faces "
                        "for six images)", ibl_layout_name(d.layout));
    }
}

ibl_status ibl_cubemap_to_faces(ibl_context *ctx, const ibl_cubemap *cube, int level,
                                ibl_image faces[6])
{
    if (!faces) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "faces: no output images");
    memset(faces, 0, 6 * sizeof faces[0]);
    if (!cube || !cube->data || cube->size <= 0)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "faces: empty cubemap");
    if (level < 0 || level >= cube->levels)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "faces: level %d out of range [0, %d]",
                        level, cube->levels - 1);
    int n = ibl_level_size(cube->size, level);
    for (int f = 0; f < 6; f++) {
        ibl_status st = ibl_image_alloc(ctx, n, n, &faces[f]);
        if (st != IBL_OK) {
            for (int g = 0; g < f; g++) ibl_image_free(ctx, &faces[g]);
            return st;
        }
        memcpy(faces[f].pixels, ibl_cubemap_face(cube, level, f), (size_t)n * n * 4 * sizeof(float));
    }
    return IBL_OK;
}

ibl_status ibl_image_mean(ibl_context *ctx, const ibl_image *image, ibl_layout layout,
                          double out[4])
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "mean: no output");
    ibl_status st = check_image(ctx, "mean", image);
    if (st != IBL_OK) return st;
    if (layout == IBL_LAYOUT_AUTO) layout = ibl_layout_detect(image->width, image->height);
    if (layout == IBL_LAYOUT_EQUIRECT && size_fits(layout, image->width, image->height)) {
        ibl__equirect_mean(image, out);
        return IBL_OK;
    }
    /* anything else (and every refusal: an unknown aspect, a size that does not fit, faces)
     * goes through the conversion, which explains itself */
    ibl_to_cube_desc d;
    memset(&d, 0, sizeof d);
    d.layout = layout;
    ibl_cubemap cube;
    st = ibl_image_to_cubemap(ctx, image, &d, &cube);
    if (st != IBL_OK) return st;
    ibl_cubemap_mean(&cube, 0, out);
    ibl_cubemap_free(ctx, &cube);
    return IBL_OK;
}
