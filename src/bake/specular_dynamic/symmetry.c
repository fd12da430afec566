/* The 48 symmetries of the cube (the signed permutations of x, y, z) as maps between texels.
 *
 * A symmetry g carries the cube onto itself, faces onto faces and, because every face's texel
 * grid is symmetric under its own mirrors and its diagonal, texels onto texels of the same
 * size at every mip. The dynamic operator uses that twice: a lobe that is symmetric about its
 * axis (Phong, GGX) and an output direction that follows the symmetry (texel centres, and the
 * bent and warped directions of the edge fixups, which are odd in each face coordinate and
 * symmetric in the two) give g(texel)'s row of weights as the row of the texel with its
 * source texels moved by g. So the rows of one octant of face +X, texels (a, b) with
 * a <= b <= (n-1)/2, are all the plan computes (tri-Ace 2010 filters every texel by brute
 * force on the GPU; the symmetry is what makes the CPU plan cheap to build).
 *
 * Face frames follow cubemap.c: direction = major + sc s_axis + tc t_axis. For g and a face
 * f, g(major_f) is the major axis of the target face f'; g(s_axis_f) is +-s_axis_f' (no swap)
 * or +-t_axis_f' (swap), and likewise g(t_axis_f). */
#include "bake/specular_dynamic/dynamic_internal.h"

#include <math.h>
#include <string.h>

/* Major, s and t axes of a face, from the library's geometry. */
static void face_axes(int face, int axes[3][3])
{
    double c[3], s1[3], t1[3];
    ibl_cube_direction_d(face, 0.5, 0.5, c);
    ibl_cube_direction_d(face, 1.0, 0.5, s1);
    ibl_cube_direction_d(face, 0.5, 1.0, t1);
    for (int i = 0; i < 3; i++) {
        axes[0][i] = (int)lround(c[i]);
        axes[1][i] = (int)lround(s1[i] - c[i]);
        axes[2][i] = (int)lround(t1[i] - c[i]);
    }
}

/* g(v) for the signed permutation g: component i of the image is sign[i] v[perm[i]]. */
static void apply(const int perm[3], const int sign[3], const int v[3], int out[3])
{
    for (int i = 0; i < 3; i++) out[i] = sign[i] * v[perm[i]];
}

static int same(const int a[3], const int b[3], int s)
{
    return a[0] == s * b[0] && a[1] == s * b[1] && a[2] == s * b[2];
}

void ibl__dyn_symmetries(dyn_symmetries *out)
{
    static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    int axes[6][3][3];
    for (int f = 0; f < 6; f++) face_axes(f, axes[f]);
    memset(out, 0, sizeof *out);
    int g = 0;
    for (int p = 0; p < 6; p++)
        for (int signs = 0; signs < 8; signs++, g++) {
            int sign[3] = {(signs & 1) ? -1 : 1, (signs & 2) ? -1 : 1, (signs & 4) ? -1 : 1};
            for (int f = 0; f < 6; f++) {
                int m[3], s[3], t[3];
                apply(perms[p], sign, axes[f][0], m);
                apply(perms[p], sign, axes[f][1], s);
                apply(perms[p], sign, axes[f][2], t);
                dyn_face_map *map = &out->map[g][f];
                for (int k = 0; k < 6; k++)
                    if (same(m, axes[k][0], 1)) map->target = (uint8_t)k;
                const int(*to)[3] = axes[map->target];
                map->swap = !(same(s, to[1], 1) || same(s, to[1], -1));
                if (!map->swap) {
                    map->flip_x = same(s, to[1], -1);
                    map->flip_y = same(t, to[2], -1);
                } else {
                    map->flip_x = same(s, to[2], -1);
                    map->flip_y = same(t, to[1], -1);
                }
            }
        }
}

void ibl__dyn_face_frame(int face, dyn_face_frame *f)
{
    double c[3], s1[3], t1[3];
    ibl_cube_direction_d(face, 0.5, 0.5, c);
    ibl_cube_direction_d(face, 1.0, 0.5, s1);
    ibl_cube_direction_d(face, 0.5, 1.0, t1);
    for (int i = 0; i < 3; i++) f->m[i] = c[i], f->s[i] = s1[i] - c[i], f->t[i] = t1[i] - c[i];
}

void ibl__dyn_map_texel(const dyn_face_map *m, int M, int x, int y, int *mx, int *my)
{
    int fx = m->flip_x ? M - 1 - x : x, fy = m->flip_y ? M - 1 - y : y;
    *mx = m->swap ? fy : fx;
    *my = m->swap ? fx : fy;
}

void ibl__dyn_fold(const dyn_symmetries *sym, int n, int face, int x, int y, int *a, int *b,
                   int *symmetry)
{
    int u = x < n - 1 - x ? x : n - 1 - x, v = y < n - 1 - y ? y : n - 1 - y;
    *a = u < v ? u : v;
    *b = u < v ? v : u;
    *symmetry = 0;
    for (int g = 0; g < DYN_SYMMETRIES; g++) {
        const dyn_face_map *m = &sym->map[g][0];
        int mx, my;
        ibl__dyn_map_texel(m, n, *a, *b, &mx, &my);
        if (m->target == face && mx == x && my == y) {
            *symmetry = g;
            return;
        }
    }
}
