/* `ibl bake --target godot` rendered in Godot itself (Debian's godot3, 3.2.3, GLES3 on Mesa
 * llvmpipe under Xvfb): the bake's engine_environment.exr becomes a PanoramaSky, the only light
 * of a sphere grid (tests/godot/render.gd), and Godot's own pictures are checked here.
 *  - Orientation: an axes environment (one colour per axis direction and white dots beside
 *    +X, +Z and -Z that change side under a mirror: the environment of
 *    tests/viewer/engines_test.mjs, written again here in C). Every pixel of the background and
 *    of the mirror sphere is compared with the colour the picture has at the direction the ray
 *    sees (the camera ray, or its reflection), where README.txt says Godot shows it: the
 *    input's (x, y, z) at Godot's (x, y, z). The same pixels against the picture turned by 180
 *    degrees or mirrored must fail by far (the check can tell the frames apart).
 *  - Level: a constant environment E (a white furnace). Godot's linear tone mapper shows
 *    exposure x value, then the sRGB curve: the background and a mirror are
 *    E x background_energy, a white diffuse sphere E x background_energy x ambient_energy (x
 *    Godot's irradiance quadrature), rough white metals E x background_energy x Godot's
 *    split-sum approximation.
 * Godot is required: when godot3 or xvfb-run is missing the test fails (scripts/install-deps.sh
 * installs godot3, xvfb and xauth). `test_godot DIR` also writes docs/ENGINES.md's pictures. */
#include "test_support.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* ---- the scene of render.gd (kept equal to its constants) ------------------------------------ */

#define VIEW 256
#define FOV_DEGREES 35.0
#define CAMERA_Z 8.0
#define RADIUS 0.9
enum { MIRROR, METAL_HALF, METAL_ROUGH, DIFFUSE, SPHERES };
static const double centres[SPHERES][3] = {{-1, 1, 0}, {1, 1, 0}, {-1, -1, 0}, {1, -1, 0}};

/* The exposures of the views (render.gd's linear tone mapper multiplies by it): the axes'
 * brightest colour, 3.0, stays under 1 */
#define AXES_EXPOSURE 0.3
static const double furnace[3] = {0.6, 0.4, 0.25}; /* E, per channel */

/* What a pixel sees: the ray through its centre from the camera (Godot's Camera: vertical field
 * of view, square view), which sphere it meets (-1: none) and how close to a silhouette it
 * passes (in units of the radius: 0 at the centre, 1 at the rim). */
typedef struct pixel_ray {
    double dir[3];
    int sphere;
    double rim;    /* distance of the ray from the sphere's centre / radius: < 1 is a hit */
    double normal[3];
    double nearest_rim; /* min over all spheres: background pixels near a sphere are skipped */
} pixel_ray;

static void normalize(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; k++) v[k] /= l;
}

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static pixel_ray trace_pixel(int i, int j)
{
    pixel_ray p = {.sphere = -1, .rim = 2, .nearest_rim = 1e9};
    double t = tan(FOV_DEGREES * PI / 360.0);
    p.dir[0] = (2.0 * (i + 0.5) / VIEW - 1.0) * t;
    p.dir[1] = (1.0 - 2.0 * (j + 0.5) / VIEW) * t;
    p.dir[2] = -1.0;
    normalize(p.dir);
    const double eye[3] = {0, 0, CAMERA_Z};
    double best_t = 1e30;
    for (int s = 0; s < SPHERES; s++) {
        double oc[3] = {eye[0] - centres[s][0], eye[1] - centres[s][1], eye[2] - centres[s][2]};
        double b = dot3(oc, p.dir), closest2 = dot3(oc, oc) - b * b;
        double rim = sqrt(fmax(closest2, 0.0)) / RADIUS;
        p.nearest_rim = fmin(p.nearest_rim, rim);
        if (rim >= 1.0) continue;
        double hit_t = -b - sqrt(RADIUS * RADIUS - closest2);
        if (hit_t >= best_t) continue;
        best_t = hit_t;
        p.sphere = s;
        p.rim = rim;
        for (int k = 0; k < 3; k++) p.normal[k] = (eye[k] + hit_t * p.dir[k] - centres[s][k]) / RADIUS;
    }
    return p;
}

/* ---- the axes environment ------------------------------------------------------------------ */

static const double axis_dirs[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
static const double axis_colours[6][3] = {{3.0, 0.15, 0.1}, {0.1, 0.9, 1.2}, {0.2, 2.0, 0.2},
                                          {0.6, 0.1, 0.9}, {0.15, 0.3, 3.0}, {1.6, 1.4, 0.1}};
/* white dots 0.44 rad (25 degrees) to the right of +X, +Z and -Z seen from inside, 0.35 rad
 * up, of angular radius 0.16 rad: a mirrored picture has them on the left */
#define DOTS 4
static const double dot_azimuths[DOTS] = {-PI / 2 + 0.44, PI + 0.44, 0.44, 0.44 - PI};
#define DOT_ELEVATION 0.35
#define DOT_RADIUS 0.16
#define DOT_VALUE 8.0

static void dot_centre(int k, double d[3])
{
    double p = dot_azimuths[k];
    d[0] = cos(DOT_ELEVATION) * sin(p);
    d[1] = sin(DOT_ELEVATION);
    d[2] = -cos(DOT_ELEVATION) * cos(p);
}

/* The radiance of the axes environment in direction d (unit), and how far d is from an edge
 * of the picture (the smaller of the gap between the two nearest axes' cosines and the angle
 * to a dot's rim): pixels near an edge are left out of the comparison. */
static void axes_radiance(const double d[3], double c[3], double *edge_margin)
{
    int best = 0;
    double best_dot = -2, second_dot = -2;
    for (int a = 0; a < 6; a++) {
        double t = dot3(axis_dirs[a], d);
        if (t > best_dot) {
            second_dot = best_dot;
            best_dot = t;
            best = a;
        } else if (t > second_dot) second_dot = t;
    }
    for (int k = 0; k < 3; k++) c[k] = axis_colours[best][k] * (0.35 + 0.65 * best_dot);
    double margin = best_dot - second_dot;
    for (int k = 0; k < DOTS; k++) {
        double centre[3];
        dot_centre(k, centre);
        double angle = acos(fmax(-1.0, fmin(1.0, dot3(centre, d))));
        if (angle < DOT_RADIUS)
            for (int ch = 0; ch < 3; ch++) c[ch] = DOT_VALUE;
        margin = fmin(margin, fabs(angle - DOT_RADIUS));
    }
    if (edge_margin) *edge_margin = margin;
}

/* The picture in ibl's equirect layout (docs/CONVENTIONS.md: centre column -Z, right quarter
 * +X, top row +Y). */
static void write_axes_picture(ibl_context *ctx, const char *path, int width)
{
    ibl_image img;
    assert_int_equal(ibl_image_alloc(ctx, width, width / 2, &img), IBL_OK);
    for (int y = 0; y < img.height; y++)
        for (int x = 0; x < width; x++) {
            double phi = 2 * PI * ((x + 0.5) / width - 0.5), theta = PI * (y + 0.5) / img.height;
            double d[3] = {sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi)}, c[3];
            axes_radiance(d, c, NULL);
            float *p = img.pixels + ((size_t)y * width + x) * 4;
            for (int k = 0; k < 3; k++) p[k] = (float)c[k];
            p[3] = 1.0f;
        }
    assert_int_equal(ibl_write_image(ctx, path, &img, NULL), IBL_OK);
    ibl_image_free(ctx, &img);
}

static void write_constant_picture(ibl_context *ctx, const char *path)
{
    ibl_image img;
    assert_int_equal(ibl_image_alloc(ctx, 64, 32, &img), IBL_OK);
    for (size_t i = 0; i < (size_t)64 * 32; i++)
        for (int k = 0; k < 4; k++) img.pixels[i * 4 + k] = k < 3 ? (float)furnace[k] : 1.0f;
    assert_int_equal(ibl_write_image(ctx, path, &img, NULL), IBL_OK);
    ibl_image_free(ctx, &img);
}

/* ---- running Godot --------------------------------------------------------------------------- */

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    assert_int_equal(fclose(f), 0);
}

static void print_log_tail(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) return;
    static char text[8192];
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    fseek(f, size > (long)sizeof text - 1 ? size - (long)sizeof text + 1 : 0, SEEK_SET);
    size_t n = fread(text, 1, sizeof text - 1, f);
    text[n] = 0;
    fclose(f);
    print_message("%s\n", text);
}

/* The project: GLES3 (the renderer Godot 3 uses on desktops), and the sky's radiance filtered
 * with Godot's low-quality GGX (64 samples instead of 512; the mobile default): the high-quality
 * filter takes over a minute on llvmpipe. Views: axes (exposure 0.3), the furnace at energies
 * 1 and 1, and the furnace at background_energy 0.5 and ambient_energy 0.5. */
static void run_godot(const char *project, const char *axes_exr, const char *furnace_exr,
                      const char *extra_views)
{
    char path[600], text[4096];
    snprintf(path, sizeof path, "%s/project.godot", project);
    write_text(path, "config_version=4\n\n[application]\nconfig/name=\"ibl godot test\"\n\n"
                     "[rendering]\nquality/driver/driver_name=\"GLES3\"\n"
                     "quality/reflections/high_quality_ggx=false\n");
    snprintf(text, sizeof text,
             "[axes]\npanorama=\"%s\"\noutput=\"%s/axes.png\"\nexposure=%.17g\n\n"
             "[furnace]\npanorama=\"%s\"\noutput=\"%s/furnace.png\"\n\n"
             "[furnace_half]\npanorama=\"%s\"\noutput=\"%s/furnace_half.png\"\n"
             "background_energy=0.5\nambient_energy=0.5\n\n%s",
             axes_exr, project, AXES_EXPOSURE, furnace_exr, project, furnace_exr, project, extra_views);
    snprintf(path, sizeof path, "%s/views.cfg", project);
    write_text(path, text);
    char log[600], cmd[3000];
    snprintf(log, sizeof log, "%s/godot.log", project);
    /* Godot's user data and caches stay in the project folder; xvfb-run -a takes a free display */
    snprintf(cmd, sizeof cmd,
             "cd '%s' && XDG_DATA_HOME='%s/data' XDG_CONFIG_HOME='%s/config' XDG_CACHE_HOME='%s/cache' "
             "LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe timeout 120 xvfb-run -a -s '-screen 0 64x64x24' "
             "godot3 --audio-driver Dummy --path '%s' -s '%s/render.gd' >'%s' 2>&1",
             project, project, project, project, project, IBL_GODOT_DIR, log);
    int rc = system(cmd);
    if (rc != 0) {
        print_log_tail(log);
        fail_msg("godot3 failed (status %d): its log is above", rc);
    }
}

static int have_godot(void)
{
    return system("command -v godot3 >/dev/null 2>&1 && command -v xvfb-run >/dev/null 2>&1") == 0;
}

/* ---- the checks ------------------------------------------------------------------------------ */

static double srgb_code(double linear)
{
    double v = fmin(1.0, fmax(0.0, linear));
    v = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
    return 255.0 * v;
}

/* Godot's picture, as 8-bit codes (0..255) */
static ibl_image read_codes(ibl_context *ctx, const char *path)
{
    ibl_read_desc rd = {.as_data = 1};
    ibl_image img;
    assert_int_equal(ibl_read_image(ctx, path, &rd, &img, NULL), IBL_OK);
    assert_int_equal(img.width, VIEW);
    assert_int_equal(img.height, VIEW);
    for (size_t i = 0; i < (size_t)VIEW * VIEW * 4; i++) img.pixels[i] *= 255.0f;
    return img;
}

enum { FRAME_GODOT, FRAME_TURNED, FRAME_MIRRORED, FRAMES };
static const char *const frame_names[FRAMES] = {"(x, y, z)", "turned 180 degrees", "mirrored"};

typedef struct frame_score {
    int compared;
    double mean_error;  /* mean over pixels of the largest channel error, in 8-bit codes */
    double within;      /* the fraction of pixels within ORIENTATION_CODES */
} frame_score;

/* The colour (8-bit codes) the axes view shows at a seen direction when Godot's (x, y, z) holds
 * the input's (x, y, z) (FRAME_GODOT), (-x, y, -z) or (-x, y, z); margin: see axes_radiance. */
static void expected_codes(const double seen[3], int frame, double code[3], double *margin)
{
    double d[3] = {seen[0], seen[1], seen[2]}, c[3];
    if (frame != FRAME_GODOT) d[0] = -d[0];
    if (frame == FRAME_TURNED) d[2] = -d[2];
    axes_radiance(d, c, margin);
    for (int k = 0; k < 3; k++) code[k] = srgb_code(AXES_EXPOSURE * c[k]);
}

/* Per pixel of the background and of the mirror sphere, the largest channel error against the
 * frame's expected colour. For the two wrong frames only the pixels where their expectation
 * differs from FRAME_GODOT's by more than 3 x ORIENTATION_CODES count (elsewhere no frame can be
 * told from another). */
#define ORIENTATION_CODES 8.0
static frame_score score_frame(const ibl_image *shot, int frame)
{
    frame_score s = {0};
    int within = 0;
    for (int j = 0; j < VIEW; j++)
        for (int i = 0; i < VIEW; i++) {
            pixel_ray p = trace_pixel(i, j);
            double seen[3];
            if (p.sphere < 0) {
                if (p.nearest_rim < 1.05) continue; /* the mesh's silhouette, antialiasing */
                memcpy(seen, p.dir, sizeof seen);
            } else if (p.sphere == MIRROR && p.rim < 0.9) {
                double dn = dot3(p.dir, p.normal);
                for (int k = 0; k < 3; k++) seen[k] = p.dir[k] - 2 * dn * p.normal[k];
            } else continue;
            double want[3], right[3], margin, right_margin, apart = 0, worst = 0;
            expected_codes(seen, frame, want, &margin);
            expected_codes(seen, FRAME_GODOT, right, &right_margin);
            if (fmin(margin, right_margin) < 0.08) continue;
            const float *got = shot->pixels + ((size_t)j * VIEW + i) * 4;
            for (int k = 0; k < 3; k++) {
                apart = fmax(apart, fabs(want[k] - right[k]));
                worst = fmax(worst, fabs(got[k] - want[k]));
            }
            if (frame != FRAME_GODOT && apart <= 3 * ORIENTATION_CODES) continue;
            s.mean_error += worst;
            within += worst <= ORIENTATION_CODES;
            s.compared++;
        }
    if (s.compared) {
        s.mean_error /= s.compared;
        s.within = (double)within / s.compared;
    }
    return s;
}

/* The mean code per channel over one region of a furnace view: the background (away from the
 * spheres) or a sphere's pixels whose ray passes within 0.8 of the radius of its centre (away
 * from grazing angles, where Godot's Fresnel and horizon terms act). */
static void region_mean(const ibl_image *shot, int sphere, double mean[3])
{
    int n = 0;
    mean[0] = mean[1] = mean[2] = 0;
    for (int j = 0; j < VIEW; j++)
        for (int i = 0; i < VIEW; i++) {
            pixel_ray p = trace_pixel(i, j);
            int in = sphere < 0 ? p.sphere < 0 && p.nearest_rim > 1.05 : p.sphere == sphere && p.rim < 0.8;
            if (!in) continue;
            for (int k = 0; k < 3; k++) mean[k] += shot->pixels[((size_t)j * VIEW + i) * 4 + k];
            n++;
        }
    assert_true(n > 100);
    for (int k = 0; k < 3; k++) mean[k] /= n;
}

/* The mean code per channel over a small disc (radius 0.2 of the sphere's, on screen) around
 * (centre + offset x radius) of one sphere. */
static void disc_mean(const ibl_image *shot, int sphere, double dx, double dy, double mean[3])
{
    int n = 0;
    mean[0] = mean[1] = mean[2] = 0;
    double t = tan(FOV_DEGREES * PI / 360.0), scale = VIEW / (2 * t * CAMERA_Z);
    double cx = (VIEW / 2.0) + (centres[sphere][0] + dx * RADIUS) * scale;
    double cy = (VIEW / 2.0) - (centres[sphere][1] + dy * RADIUS) * scale, r = 0.2 * RADIUS * scale;
    for (int j = 0; j < VIEW; j++)
        for (int i = 0; i < VIEW; i++) {
            if ((i + 0.5 - cx) * (i + 0.5 - cx) + (j + 0.5 - cy) * (j + 0.5 - cy) > r * r) continue;
            for (int k = 0; k < 3; k++) mean[k] += shot->pixels[((size_t)j * VIEW + i) * 4 + k];
            n++;
        }
    assert_true(n > 20);
    for (int k = 0; k < 3; k++) mean[k] /= n;
}

/* With a folder argument (`test_godot docs/images`), the pictures of docs/ENGINES.md go there too:
 * the axes view and the grid lit by tests/data/forest.exr (baked at --working-size 256). */
static const char *screenshot_dir;

static void copy_file(const char *from, const char *to)
{
    char cmd[1400];
    snprintf(cmd, sizeof cmd, "cp '%s' '%s'", from, to);
    assert_int_equal(system(cmd), 0);
}

typedef struct godot_run {
    ibl_context *ctx;
    ibl_image axes, furnace, furnace_half;
} godot_run;

static int setup(void **state)
{
    if (!have_godot()) {
        print_error("godot3 and xvfb-run are needed (Debian packages godot3, xvfb, xauth: "
                    "scripts/install-deps.sh installs them)\n");
        return -1;
    }
    godot_run *run = calloc(1, sizeof *run);
    run->ctx = test_context(0);
    write_axes_picture(run->ctx, test_path("axes.exr"), 1024);
    write_constant_picture(run->ctx, test_path("constant.exr"));
    /* --working-size 64: the EXR is 256 x 128 (4 pixels per cube texel around the horizon) */
    const char *fast = "--size 16 --working-size 64 --lut-size 8 --irradiance-size 4 --preview-width 0";
    const char *out;
    if (test_run_cli(&out, "bake -q '%s' -o '%s' --target godot %s", test_path("axes.exr"),
                     test_path("axes_bake"), fast) != 0 ||
        test_run_cli(&out, "bake -q '%s' -o '%s' --target godot %s", test_path("constant.exr"),
                     test_path("furnace_bake"), fast) != 0) {
        print_error("ibl bake failed: %s\n", out);
        return -1;
    }
    const char *project = test_path("project");
    char cmd[700];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s'", project);
    assert_int_equal(system(cmd), 0);
    char extra[1400] = "";
    if (screenshot_dir) {
        if (test_run_cli(&out, "bake -q '%s' -o '%s' --target godot --size 64 --working-size 256 "
                         "--lut-size 8 --irradiance-size 4 --preview-width 0", test_data("forest.exr"),
                         test_path("forest_bake")) != 0) {
            print_error("ibl bake failed: %s\n", out);
            return -1;
        }
        snprintf(extra, sizeof extra, "[forest]\npanorama=\"%s\"\noutput=\"%s/forest.png\"\n",
                 test_path("forest_bake/engine_environment.exr"), project);
    }
    run_godot(project, test_path("axes_bake/engine_environment.exr"),
              test_path("furnace_bake/engine_environment.exr"), extra);
    if (screenshot_dir) {
        char to[700];
        snprintf(to, sizeof to, "%s/godot_axes.png", screenshot_dir);
        copy_file(test_path("project/axes.png"), to);
        snprintf(to, sizeof to, "%s/godot_forest.png", screenshot_dir);
        copy_file(test_path("project/forest.png"), to);
    }
    run->axes = read_codes(run->ctx, test_path("project/axes.png"));
    run->furnace = read_codes(run->ctx, test_path("project/furnace.png"));
    run->furnace_half = read_codes(run->ctx, test_path("project/furnace_half.png"));
    *state = run;
    return 0;
}

static int teardown(void **state)
{
    godot_run *run = *state;
    if (!run) return 0;
    ibl_image_free(run->ctx, &run->axes);
    ibl_image_free(run->ctx, &run->furnace);
    ibl_image_free(run->ctx, &run->furnace_half);
    ibl_context_destroy(run->ctx);
    free(run);
    return 0;
}

/* The background and the mirror sphere show the input's direction d at Godot's d. Bound: 99% of
 * the compared pixels within 8 codes (the picture's colour changes by at most 0.65 x 3.0 per
 * radian, x 0.3 exposure: under 0.6 per radian, a few codes per 0.02 rad, the size of a texel
 * of Godot's 256-texel radiance map and of the 256-pixel-wide EXR), pixels within 0.08 of an
 * edge of the picture left out. Controls: on the pixels where the picture turned by 180 degrees
 * or mirrored (the dots and the X faces) predicts another colour, fewer than 10% within. The
 * diffuse sphere (Godot's ambient light) shows the same frame: its right side is lit by the red
 * +X, its left by the cyan -X, its top by the green +Y. */
static void orientation_in_godot(void **state)
{
    godot_run *run = *state;
    for (int f = 0; f < FRAMES; f++) {
        frame_score s = score_frame(&run->axes, f);
        print_message("axes: against the picture %s: %d pixels, mean error %.2f codes, %.2f%% within %g\n",
                      frame_names[f], s.compared, s.mean_error, 100 * s.within, ORIENTATION_CODES);
        if (f == FRAME_GODOT) {
            assert_true(s.compared > 20000);
            assert_true(s.within >= 0.99);
        } else {
            assert_true(s.compared > 1000);
            assert_true(s.within < 0.1);
        }
    }
    double right[3], left[3], top[3], bottom[3];
    disc_mean(&run->axes, DIFFUSE, 0.5, 0, right);
    disc_mean(&run->axes, DIFFUSE, -0.5, 0, left);
    disc_mean(&run->axes, DIFFUSE, 0, 0.5, top);
    disc_mean(&run->axes, DIFFUSE, 0, -0.5, bottom);
    print_message("axes: diffuse sphere: right %.0f %.0f %.0f, left %.0f %.0f %.0f, top %.0f %.0f %.0f, "
                  "bottom %.0f %.0f %.0f\n", right[0], right[1], right[2], left[0], left[1], left[2],
                  top[0], top[1], top[2], bottom[0], bottom[1], bottom[2]);
    assert_true(right[0] - left[0] > 20 && left[1] - right[1] > 10);
    assert_true(top[1] - bottom[1] > 20);
}

static double srgb_decode(double code)
{
    double v = code / 255.0;
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

/* The split-sum environment BRDF of Godot 3's scene shader for a white metal (F0 = 1): the
 * approximation of Lazarov ("Getting More Physical in Call of Duty: Black Ops II", SIGGRAPH
 * 2013) in Karis's form ("Physically Based Shading on Mobile", 2014) gives A + B = c.z + c.w =
 * 1 - 0.55 roughness whatever the angle: a rough metal in a white furnace reflects less than E. */
static double godot_metal_env_brdf(double roughness) { return 1.0 - 0.55 * roughness; }

/* Godot 3.2's irradiance map (cubemap_filter.glsl, COMPUTE_IRRADIANCE, read in the shader text of
 * Debian's godot3 binary) is a Riemann sum over a grid of (phi, theta) steps of 0.1 rad (the
 * low-quality filter; 0.03 in high quality), theta from 0 while under pi/2: pi x the mean of
 * L cos(theta) sin(theta). For a constant L that is L x this factor (0.9805 at 0.1), Godot's own
 * shortfall on a diffuse surface. */
static double godot_irradiance_quadrature(double step)
{
    double sum = 0;
    int n = 0;
    for (double theta = 0; theta < 0.5 * PI; theta += step, n++) sum += cos(theta) * sin(theta);
    return PI * sum / n;
}

/* White furnace, as 8-bit codes of the mean of a flat region: the background and the mirror show
 * E x background_energy, the rough metals E x background_energy x (1 - 0.55 roughness), the
 * diffuse sphere E x background_energy x ambient_energy x 0.9805 (the quadrature above), all
 * within 1.5 codes (Godot's pictures come out up to 1 code under the rounded value: its 8-bit
 * conversion; the half-float panorama and radiance maps add under 0.1%; one code is 1 to 2% of
 * the values here). Control: the diffuse sphere at energies 0.5 and 0.5 against
 * E x background_energy (ambient_energy left out) fails the same bound by far. */
static void furnace_level_in_godot(void **state)
{
    godot_run *run = *state;
    static const char *const names[SPHERES] = {"mirror", "metal roughness 0.5", "metal roughness 1",
                                               "diffuse white"};
    static const double roughness[SPHERES] = {0.0, 0.5, 1.0, 1.0};
    for (int view = 0; view < 2; view++) {
        const ibl_image *shot = view ? &run->furnace_half : &run->furnace;
        double background_energy = view ? 0.5 : 1.0, ambient_energy = view ? 0.5 : 1.0, mean[3];
        for (int s = -1; s < SPHERES; s++) {
            region_mean(shot, s, mean);
            double scale = background_energy;
            if (s == DIFFUSE) scale *= ambient_energy * godot_irradiance_quadrature(0.1);
            else if (s > MIRROR) scale *= godot_metal_env_brdf(roughness[s]);
            double ratio[3], codes_off[3];
            for (int k = 0; k < 3; k++) {
                ratio[k] = srgb_decode(mean[k]) / (furnace[k] * scale);
                codes_off[k] = mean[k] - srgb_code(furnace[k] * scale);
            }
            print_message("furnace, energies %.1f %.1f: %s: %.4f %.4f %.4f of the expected value "
                          "(%+.2f %+.2f %+.2f codes)\n", background_energy, ambient_energy,
                          s < 0 ? "background" : names[s], ratio[0], ratio[1], ratio[2], codes_off[0],
                          codes_off[1], codes_off[2]);
            for (int k = 0; k < 3; k++) assert_true(fabs(codes_off[k]) <= 1.5);
            if (s == DIFFUSE && view == 1) /* control: without ambient_energy */
                for (int k = 0; k < 3; k++) assert_true(fabs(mean[k] - srgb_code(furnace[k] * background_energy)) > 10);
        }
    }
}

int main(int argc, char **argv)
{
    if (argc > 1) screenshot_dir = argv[1];
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(orientation_in_godot),
        cmocka_unit_test(furnace_level_in_godot),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
