/* Test data for the skin bakes (skin_data.h). */
#include "skin_data.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static const double PI = 3.14159265358979323846;

/* The blob's radius factor: a head stretched along Y with a nose (+Z) and brows. */
static double blob_radius(double theta, double phi, double blob)
{
    double x = sin(theta) * cos(phi), y = cos(theta), z = -sin(theta) * sin(phi);
    double nose = exp(-((x * x) + (y + 0.05) * (y + 0.05)) / 0.02) * (z > 0 ? z : 0);
    double brows = exp(-(y - 0.3) * (y - 0.3) / 0.01) * (z > 0 ? z * z : 0);
    double ears = exp(-((z * z) + (y * y)) / 0.03) * fabs(x);
    return 1.0 + blob * (1.5 * nose + 0.4 * brows + 0.6 * ears) - 0.15 * (blob > 0) * y * y;
}

int skin_write_sphere_obj(const char *path, double r, int seg_u, int seg_v, double blob)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    for (int j = 0; j <= seg_v; j++)
        for (int i = 0; i <= seg_u; i++) {
            double u = (double)i / seg_u, v = (double)j / seg_v;
            double theta = PI * v, phi = 2 * PI * u;
            double k = blob > 0 ? blob_radius(theta, phi, blob) : 1.0;
            double x = sin(theta) * cos(phi), y = cos(theta), z = -sin(theta) * sin(phi);
            fprintf(f, "v %.9g %.9g %.9g\n", r * k * x, r * k * y * (blob > 0 ? 1.2 : 1.0), r * k * z);
            fprintf(f, "vt %.9g %.9g\n", u, 1.0 - v); /* OBJ: v = 0 at the image's bottom */
            fprintf(f, "vn %.9g %.9g %.9g\n", x, y, z);
        }
    for (int j = 0; j < seg_v; j++)
        for (int i = 0; i < seg_u; i++) {
            int a = j * (seg_u + 1) + i + 1, b = a + 1, c = a + seg_u + 1, d = c + 1;
            /* counter-clockwise seen from outside: a (top left), c (below), d, b */
            if (blob > 0) {
                fprintf(f, "f %d/%d %d/%d %d/%d\n", a, a, c, c, d, d);
                fprintf(f, "f %d/%d %d/%d %d/%d\n", a, a, d, d, b, b);
            } else {
                fprintf(f, "f %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, c, c, c, d, d, d);
                fprintf(f, "f %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, d, d, d, b, b, b);
            }
        }
    return fclose(f) == 0 ? 0 : -1;
}

int skin_write_ellipsoid_obj(const char *path, double rx, double ry, double rz, int seg_u, int seg_v)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    for (int j = 0; j <= seg_v; j++)
        for (int i = 0; i <= seg_u; i++) {
            double u = (double)i / seg_u, v = (double)j / seg_v;
            double theta = PI * v, phi = 2 * PI * u;
            double x = sin(theta) * cos(phi), y = cos(theta), z = -sin(theta) * sin(phi);
            double n[3] = {x / rx, y / ry, z / rz}, len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            fprintf(f, "v %.9g %.9g %.9g\nvt %.9g %.9g\nvn %.9g %.9g %.9g\n", rx * x, ry * y, rz * z,
                    u, 1.0 - v, n[0] / len, n[1] / len, n[2] / len);
        }
    for (int j = 0; j < seg_v; j++)
        for (int i = 0; i < seg_u; i++) {
            int a = j * (seg_u + 1) + i + 1, b = a + 1, c = a + seg_u + 1, d = c + 1;
            fprintf(f, "f %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, c, c, c, d, d, d);
            fprintf(f, "f %d/%d/%d %d/%d/%d %d/%d/%d\n", a, a, a, d, d, d, b, b, b);
        }
    return fclose(f) == 0 ? 0 : -1;
}

int skin_write_slab_obj(const char *path, double sx, double sz, double depth)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    double x0 = -sx / 2, x1 = sx / 2, z0 = -sz / 2, z1 = sz / 2, y0 = -depth, y1 = 0;
    /* 8 corners: bit 0 x, bit 1 y, bit 2 z */
    for (int k = 0; k < 8; k++)
        fprintf(f, "v %.9g %.9g %.9g\n", k & 1 ? x1 : x0, k & 2 ? y1 : y0, k & 4 ? z1 : z0);
    fprintf(f, "vt 0 1\nvt 1 1\nvt 0 0\nvt 1 0\nvt 0.5 0.5\nvn 0 1 0\nvn 0 -1 0\n");
    /* top (y = 0, +Y): image v along +z, so z0 is the image's top row (OBJ v = 1); its own
       normal, so that no smoothing bends it toward the sides */
    fprintf(f, "f 3/1/1 7/3/1 8/4/1\nf 3/1/1 8/4/1 4/2/1\n");
    static const int quads[5][4] = {{1, 2, 6, 5}, {1, 5, 7, 3}, {2, 4, 8, 6}, {1, 3, 4, 2}, {5, 6, 8, 7}};
    for (int q = 0; q < 5; q++) /* the other faces: every corner at one UV (no area) */
        fprintf(f, "f %d/5/2 %d/5/2 %d/5/2\nf %d/5/2 %d/5/2 %d/5/2\n", quads[q][0], quads[q][1], quads[q][2],
                quads[q][0], quads[q][2], quads[q][3]);
    return fclose(f) == 0 ? 0 : -1;
}

static double hash01(unsigned x)
{
    x ^= x >> 16, x *= 0x7feb352dU, x ^= x >> 15, x *= 0x846ca68bU, x ^= x >> 16;
    return (x & 0xFFFFFF) / 16777216.0;
}

/* Height of the pore field at texel coordinates (x, y) of a w x h map. */
static double pore_height(double x, double y, int w, int pores, double depth)
{
    double cell = (double)w / pores, h = 0;
    int cx = (int)floor(x / cell), cy = (int)floor(y / cell);
    for (int j = cy - 1; j <= cy + 1; j++)
        for (int i = cx - 1; i <= cx + 1; i++) {
            unsigned id = (unsigned)(j * 7919 + i * 104729);
            double px = (i + 0.2 + 0.6 * hash01(id)) * cell, py = (j + 0.2 + 0.6 * hash01(id + 1)) * cell;
            double rad = cell * (0.12 + 0.1 * hash01(id + 2));
            double d2 = ((x - px) * (x - px) + (y - py) * (y - py)) / (rad * rad);
            h -= depth * exp(-d2);
        }
    h += 0.15 * depth * sin(x * 0.21 + 2 * sin(y * 0.05)) * sin(y * 0.13);
    return h;
}

void skin_pores_normal_map(ibl_image *im, int pores, double depth)
{
    for (int y = 0; y < im->height; y++)
        for (int x = 0; x < im->width; x++) {
            double dx = pore_height(x + 0.5, y, im->width, pores, depth) -
                        pore_height(x - 0.5, y, im->width, pores, depth);
            double dy = pore_height(x, y + 0.5, im->width, pores, depth) -
                        pore_height(x, y - 0.5, im->width, pores, depth);
            /* tangent space: +x along u, +y along -v (up in the image), +z out */
            double n[3] = {-dx, dy, 1.0}, len = sqrt(n[0] * n[0] + n[1] * n[1] + 1.0);
            float *p = ibl_image_texel(im, x, y);
            for (int c = 0; c < 3; c++) p[c] = (float)(0.5 * n[c] / len + 0.5);
            p[3] = 1.0f;
        }
}
