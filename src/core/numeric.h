/* Internal: the constants and small numeric helpers every module uses, defined once.
 *
 * Vectors: ibl_vec3 (float, the public type of directions and of the runtime), double[3]
 * (the bake's float64 geometry, as the public ibl_cube_direction_d takes it) and ibl__dvec3
 * (float64 by value, for geometry written as expressions). Nothing else in src/ defines its
 * own dot product, clamp or pi. */
#ifndef IBL_CORE_NUMERIC_H
#define IBL_CORE_NUMERIC_H

#include "ibl/cubemap.h"

#include <math.h>

#define IBL_PI 3.14159265358979323846
#define IBL_TWO_PI 6.28318530717958647692
#define IBL_HALF_PI 1.57079632679489661923
#define IBL_INV_PI 0.31830988618379067154
#define IBL_PI_F 3.14159265358979f

/* ---- scalars ---- */

static inline float ibl__saturate(float x)
{
    return x < 0.0f ? 0.0f : (x > 1.0f ? 1.0f : x);
}
static inline double ibl__saturate_d(double x)
{
    return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
}
static inline float ibl__clampf(float x, float lo, float hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}
static inline double ibl__clampd(double x, double lo, double hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}
static inline int ibl__clampi(int x, int lo, int hi)
{
    return x < lo ? lo : (x > hi ? hi : x);
}
static inline float ibl__lerpf(float a, float b, float t)
{
    return a + (b - a) * t;
}

/* ---- ibl_vec3 (float) ---- */

static inline ibl_vec3 ibl__v3(float x, float y, float z)
{
    ibl_vec3 v = {x, y, z};
    return v;
}
static inline float ibl__dot(ibl_vec3 a, ibl_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline ibl_vec3 ibl__add(ibl_vec3 a, ibl_vec3 b)
{
    return ibl__v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline ibl_vec3 ibl__sub(ibl_vec3 a, ibl_vec3 b)
{
    return ibl__v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline ibl_vec3 ibl__scale(ibl_vec3 a, float s)
{
    return ibl__v3(a.x * s, a.y * s, a.z * s);
}
static inline ibl_vec3 ibl__cross(ibl_vec3 a, ibl_vec3 b)
{
    return ibl__v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
/* a / |a|; a zero vector is returned unchanged */
static inline ibl_vec3 ibl__norm(ibl_vec3 a)
{
    float l = sqrtf(ibl__dot(a, a));
    return l > 0.0f ? ibl__v3(a.x / l, a.y / l, a.z / l) : a;
}

/* ---- double[3] ---- */

static inline double ibl__dot_d(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static inline void ibl__cross_d(const double a[3], const double b[3], double out[3])
{
    double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2],
           z = a[0] * b[1] - a[1] * b[0];
    out[0] = x, out[1] = y, out[2] = z;
}
/* in place; returns the length it had (a zero vector is left unchanged) */
static inline double ibl__normalize_d(double a[3])
{
    double l = sqrt(ibl__dot_d(a, a));
    if (l > 0.0) a[0] /= l, a[1] /= l, a[2] /= l;
    return l;
}

/* ---- a double vector by value (geometry that reads better as expressions) ---- */

typedef struct ibl__dvec3 {
    double x, y, z;
} ibl__dvec3;

static inline ibl__dvec3 ibl__dv(double x, double y, double z)
{
    ibl__dvec3 r = {x, y, z};
    return r;
}
static inline ibl__dvec3 ibl__dadd(ibl__dvec3 a, ibl__dvec3 b)
{
    return ibl__dv(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline ibl__dvec3 ibl__dscale(ibl__dvec3 a, double s)
{
    return ibl__dv(a.x * s, a.y * s, a.z * s);
}
static inline double ibl__ddot(ibl__dvec3 a, ibl__dvec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline ibl__dvec3 ibl__dnorm(ibl__dvec3 a)
{
    double l = sqrt(ibl__ddot(a, a));
    return l > 0 ? ibl__dscale(a, 1.0 / l) : a;
}

#endif
