/* A procedural clear sky: Preetham, Shirley & Smits 1999, "A Practical Analytic Model for
 * Daylight" (SIGGRAPH 99), with a sun disk and a Lambertian ground. Units and directions: see
 * include/ibl/sky.h and docs/CONVENTIONS.md. */
#include "ibl/sky.h"
#include "core/context_internal.h"
#include "core/numeric.h"

#include <math.h>
#include <string.h>


/* The sun: mean angular diameter 0.53 degrees; the extraterrestrial solar illuminance 127.5 klux
 * (the IESNA value used in daylighting; 133 klux in some later work). */
static const double SUN_RADIUS_DEG = 0.265;
static const double SUN_ILLUMINANCE_KLUX = 127.5;
/* Wavelengths (micrometres) standing for the Rec.709 R, G, B channels in the transmittance
 * (near the dominant wavelengths of the primaries). */
static const double CHANNEL_UM[3] = {0.612, 0.549, 0.465};

static void fill_defaults(const ibl_sky_desc *in, ibl_sky_desc *d)
{
    memset(d, 0, sizeof *d);
    if (in) *d = *in;
    if (d->sun_elevation_deg == 0.0f) d->sun_elevation_deg = 35.0f;
    if (d->turbidity == 0.0f) d->turbidity = 3.0f;
    if (d->width == 0) d->width = 1024;
    if (d->ground_albedo == 0.0f) d->ground_albedo = 0.3f;
    else if (d->ground_albedo < 0.0f) d->ground_albedo = 0.0f;
}

static ibl_vec3 sun_dir(const ibl_sky_desc *d)
{
    double e = d->sun_elevation_deg * IBL_PI / 180.0, a = d->sun_azimuth_deg * IBL_PI / 180.0;
    ibl_vec3 v = {(float)(cos(e) * sin(a)), (float)sin(e), (float)(-cos(e) * cos(a))};
    return v;
}

ibl_vec3 ibl_sky_sun_direction(const ibl_sky_desc *desc)
{
    ibl_sky_desc d;
    fill_defaults(desc, &d);
    return sun_dir(&d);
}

/* Perez et al. 1993 distribution, as used by Preetham 1999 eq. 3:
 * F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma). */
static double perez(const double c[5], double cos_theta, double gamma, double cos_gamma)
{
    double horizon = cos_theta > 1e-6 ? 1.0 + c[0] * exp(c[1] / cos_theta) : 1.0;
    return horizon * (1.0 + c[2] * exp(c[3] * gamma) + c[4] * cos_gamma * cos_gamma);
}

/* CIE xyY -> linear Rec.709 (sRGB primaries, D65), IEC 61966-2-1 matrix. Out-of-gamut
 * negatives are clipped to 0. */
static void xyY_to_rgb(double x, double y, double Y, float rgb[3])
{
    if (!(y > 1e-9)) {
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
        return;
    }
    double X = x / y * Y, Z = (1.0 - x - y) / y * Y;
    double r = 3.2404542 * X - 1.5371385 * Y - 0.4985314 * Z;
    double g = -0.9692660 * X + 1.8760108 * Y + 0.0415560 * Z;
    double b = 0.0556434 * X - 0.2040259 * Y + 1.0572252 * Z;
    rgb[0] = (float)(r > 0 ? r : 0);
    rgb[1] = (float)(g > 0 ? g : 0);
    rgb[2] = (float)(b > 0 ? b : 0);
}

static void sky_rgb(const ibl_sky_model *m, const double d[3], float rgb[3])
{
    double sx = m->sun.direction.x, sy = m->sun.direction.y, sz = m->sun.direction.z;
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double cos_theta = d[1] / len;
    double cos_gamma = (d[0] * sx + d[1] * sy + d[2] * sz) / len;
    if (cos_gamma > 1.0) cos_gamma = 1.0;
    if (cos_gamma < -1.0) cos_gamma = -1.0;
    double gamma = acos(cos_gamma), v[3];
    for (int i = 0; i < 3; i++)
        v[i] = m->zenith[i] * perez(m->perez[i], cos_theta, gamma, cos_gamma) * m->norm[i];
    xyY_to_rgb(v[1], v[2], v[0], rgb);
}

void ibl_sky_model_radiance(const ibl_sky_model *m, ibl_vec3 dir, float rgb[3])
{
    if (dir.y < 0.0f) {
        memcpy(rgb, m->ground, 3 * sizeof(float));
        return;
    }
    double d[3] = {dir.x, dir.y, dir.z};
    sky_rgb(m, d, rgb);
}

ibl_status ibl_sky_model_init(ibl_context *ctx, const ibl_sky_desc *desc, ibl_sky_model *out)
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sky: no output model");
    memset(out, 0, sizeof *out);
    ibl_sky_desc d;
    fill_defaults(desc, &d);
    if (!(d.sun_elevation_deg > 0.0f && d.sun_elevation_deg <= 90.0f))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "sky: sun elevation %g is outside (0, 90] degrees (the model needs the "
                        "sun above the horizon)", d.sun_elevation_deg);
    if (!(d.turbidity >= 1.7f && d.turbidity <= 10.0f))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "sky: turbidity %g is outside [1.7, 10], the range of the model's fit",
                        d.turbidity);
    if (!isfinite(d.sun_azimuth_deg))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sky: sun azimuth is not finite");
    if (d.width < 8 || d.width % 2 || d.width > 65536)
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT,
                        "sky: width %d must be even and in [8, 65536]", d.width);
    if (!(d.ground_albedo <= 1.0f))
        return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sky: ground albedo %g is above 1",
                        d.ground_albedo);
    out->desc = d;

    double T = d.turbidity, ts = (90.0 - d.sun_elevation_deg) * IBL_PI / 180.0;
    /* Preetham 1999, Appendix A.2: Perez coefficients as linear functions of turbidity */
    static const double coef[3][5][2] = {
        {{0.1787, -1.4630}, {-0.3554, 0.4275}, {-0.0227, 5.3251}, {0.1206, -2.5771}, {-0.0670, 0.3703}},
        {{-0.0193, -0.2592}, {-0.0665, 0.0008}, {-0.0004, 0.2125}, {-0.0641, -0.8989}, {-0.0033, 0.0452}},
        {{-0.0167, -0.2608}, {-0.0950, 0.0092}, {-0.0079, 0.2102}, {-0.0441, -1.6537}, {-0.0109, 0.0529}},
    };
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 5; j++) out->perez[i][j] = coef[i][j][0] * T + coef[i][j][1];
    /* Appendix A.2: zenith luminance (kcd/m^2) and chromaticity */
    double chi = (4.0 / 9.0 - T / 120.0) * (IBL_PI - 2.0 * ts);
    out->zenith[0] = (4.0453 * T - 4.9710) * tan(chi) - 0.2155 * T + 2.4192;
    static const double zx[3][4] = {{0.00166, -0.00375, 0.00209, 0.0},
                                    {-0.02903, 0.06377, -0.03202, 0.00394},
                                    {0.11693, -0.21196, 0.06052, 0.25886}};
    static const double zy[3][4] = {{0.00275, -0.00610, 0.00317, 0.0},
                                    {-0.04214, 0.08970, -0.04153, 0.00516},
                                    {0.15346, -0.26756, 0.06670, 0.26688}};
    double tv[4] = {ts * ts * ts, ts * ts, ts, 1.0}, Tv[3] = {T * T, T, 1.0};
    out->zenith[1] = out->zenith[2] = 0.0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) {
            out->zenith[1] += Tv[r] * zx[r][c] * tv[c];
            out->zenith[2] += Tv[r] * zy[r][c] * tv[c];
        }
    for (int i = 0; i < 3; i++) out->norm[i] = 1.0 / perez(out->perez[i], 1.0, ts, cos(ts));

    /* The sun: Preetham 1999 Appendix A.1 (after Iqbal 1983): air mass (Kasten 1966) and
     * the Rayleigh and aerosol (Angstrom, alpha = 1.3) transmittances; ozone, water vapour
     * and mixed gases are left out (a few percent in the visible). */
    ibl_sky_sun *sun = &out->sun;
    sun->direction = sun_dir(&d);
    sun->angular_radius = SUN_RADIUS_DEG * IBL_PI / 180.0;
    sun->solid_angle = 2.0 * IBL_PI * (1.0 - cos(sun->angular_radius));
    double ts_deg = 90.0 - d.sun_elevation_deg;
    sun->air_mass = 1.0 / (cos(ts) + 0.15 * pow(93.885 - ts_deg, -1.253));
    double beta = 0.04608 * T - 0.04586;
    double l0 = SUN_ILLUMINANCE_KLUX / sun->solid_angle; /* extraterrestrial, taken as white */
    for (int c = 0; c < 3; c++) {
        double lam = CHANNEL_UM[c];
        double tau = 0.008735 * pow(lam, -4.08) + beta * pow(lam, -1.3);
        sun->radiance[c] = (float)(l0 * exp(-sun->air_mass * tau));
    }

    /* Horizontal illuminance of the sky: midpoint rule over the upper hemisphere, 0.5 degree
     * in theta by 1 degree in phi (the integrand is smooth; error well below 0.1%). */
    double acc[3] = {0, 0, 0};
    const int nt = 180, np = 360;
    for (int i = 0; i < nt; i++) {
        double th = (i + 0.5) * (IBL_PI / 2) / nt, st = sin(th), ct = cos(th);
        double w = st * ct * (IBL_PI / 2 / nt) * (2 * IBL_PI / np);
        for (int j = 0; j < np; j++) {
            double ph = (j + 0.5) * 2 * IBL_PI / np;
            double dd[3] = {st * sin(ph), ct, -st * cos(ph)};
            float rgb[3];
            sky_rgb(out, dd, rgb);
            for (int c = 0; c < 3; c++) acc[c] += w * rgb[c];
        }
    }
    double sin_e = sin(d.sun_elevation_deg * IBL_PI / 180.0);
    for (int c = 0; c < 3; c++) {
        out->sky_illuminance[c] = (float)acc[c];
        out->sun_illuminance[c] = (float)(sun->radiance[c] * sun->solid_angle * sin_e);
        out->ground[c] = (float)(d.ground_albedo / IBL_PI * (acc[c] + out->sun_illuminance[c]));
    }
    return IBL_OK;
}

typedef struct sky_job {
    const ibl_sky_model *m;
    ibl_image *im;
} sky_job;

static void sky_row(void *arg, int j)
{
    const sky_job *job = arg;
    int W = job->im->width, H = job->im->height;
    double th0 = IBL_PI * j / H, th1 = IBL_PI * (j + 1) / H, th = 0.5 * (th0 + th1);
    double ground_w = 0.0, sky_w = 1.0;
    if (th0 >= IBL_PI / 2) {
        ground_w = 1.0;
        sky_w = 0.0;
    } else if (th1 > IBL_PI / 2) {
        /* the horizon crosses this row: blend by solid angle above and below */
        double above = cos(th0), below = -cos(th1);
        sky_w = above / (above + below);
        ground_w = 1.0 - sky_w;
        th = 0.5 * (th0 + IBL_PI / 2);
    }
    float *row = job->im->pixels + (size_t)j * W * 4;
    double st = sin(th), ct = cos(th);
    for (int i = 0; i < W; i++) {
        float sky[3] = {0, 0, 0};
        if (sky_w > 0.0) {
            double ph = 2.0 * IBL_PI * ((i + 0.5) / W - 0.5);
            double d[3] = {st * sin(ph), ct, -st * cos(ph)};
            sky_rgb(job->m, d, sky);
        }
        for (int c = 0; c < 3; c++)
            row[(size_t)i * 4 + c] = (float)(sky_w * sky[c] + ground_w * job->m->ground[c]);
        row[(size_t)i * 4 + 3] = 1.0f;
    }
}

/* Adds the disk by integrating it: the cap is cut into rings of equal solid angle and each
 * ring into equal sectors; every piece deposits radiance x its solid angle into the pixel
 * holding its centre, divided by that pixel's exact solid angle. The total is radiance x the
 * disk's solid angle at any width; the pieces are much smaller than a pixel so the edge is
 * anti-aliased. */
static void splat_sun(const ibl_sky_model *m, ibl_image *im)
{
    const ibl_sky_sun *sun = &m->sun;
    int W = im->width, H = im->height;
    double s[3] = {sun->direction.x, sun->direction.y, sun->direction.z};
    double len = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    for (int i = 0; i < 3; i++) s[i] /= len;
    /* tangent frame around the sun */
    double t1[3], t2[3];
    if (fabs(s[1]) < 0.9) {
        t1[0] = s[2]; t1[1] = 0; t1[2] = -s[0]; /* up x s */
    } else {
        t1[0] = 0; t1[1] = -s[2]; t1[2] = s[1]; /* x x s */
    }
    double l1 = sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
    for (int i = 0; i < 3; i++) t1[i] /= l1;
    t2[0] = s[1] * t1[2] - s[2] * t1[1];
    t2[1] = s[2] * t1[0] - s[0] * t1[2];
    t2[2] = s[0] * t1[1] - s[1] * t1[0];
    /* pieces: about 8 per pixel across the disk's diameter, more where pixels are narrow */
    double r = sun->angular_radius, theta_s = acos(s[1]);
    double sin_lo = fmax(sin(fmax(theta_s - r, 0.0)), sin(IBL_PI / (2.0 * H)));
    double px_per_rad = fmax(W / (2.0 * IBL_PI * sin_lo), H / IBL_PI);
    int rings = (int)ceil(8.0 * 2.0 * r * px_per_rad);
    if (rings < 32) rings = 32;
    if (rings > 512) rings = 512;
    int sectors = 4 * rings;
    double piece = sun->solid_angle / ((double)rings * sectors), cos_r = cos(r);
    for (int a = 0; a < rings; a++) {
        double ca = 1.0 - (1.0 - cos_r) * (a + 0.5) / rings, sa = sqrt(1.0 - ca * ca);
        for (int b = 0; b < sectors; b++) {
            double beta = 2.0 * IBL_PI * (b + 0.5) / sectors, cb = cos(beta), sb = sin(beta);
            double d[3];
            for (int i = 0; i < 3; i++) d[i] = ca * s[i] + sa * (cb * t1[i] + sb * t2[i]);
            if (d[1] < 0.0) continue; /* below the horizon: hidden by the ground */
            double rho = sqrt(d[0] * d[0] + d[2] * d[2]);
            double u = atan2(d[0], -d[2]) / (2.0 * IBL_PI) + 0.5, v = atan2(rho, d[1]) / IBL_PI;
            int x = (int)(u * W), y = (int)(v * H);
            if (x >= W) x -= W;
            if (x < 0) x += W;
            if (y >= H) y = H - 1;
            if (y < 0) y = 0;
            double omega = 2.0 * IBL_PI / W * (cos(IBL_PI * y / H) - cos(IBL_PI * (y + 1) / H));
            float *p = im->pixels + ((size_t)y * W + x) * 4;
            for (int c = 0; c < 3; c++) p[c] += (float)(sun->radiance[c] * piece / omega);
        }
    }
}

ibl_status ibl_sky_render(ibl_context *ctx, const ibl_sky_desc *desc, ibl_image *out)
{
    if (!out) return ibl__fail(ctx, IBL_ERR_INVALID_ARGUMENT, "sky: no output image");
    memset(out, 0, sizeof *out);
    ibl_sky_model m;
    ibl_status st = ibl_sky_model_init(ctx, desc, &m);
    if (st != IBL_OK) return st;
    st = ibl_image_alloc(ctx, m.desc.width, m.desc.width / 2, out);
    if (st != IBL_OK) return st;
    sky_job job = {&m, out};
    ibl_parallel_for(ctx, out->height, sky_row, &job);
    if (!m.desc.no_sun_disk) splat_sun(&m, out);
    return IBL_OK;
}
