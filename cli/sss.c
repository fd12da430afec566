/* ibl sss: skin under image-based lighting, the offline half (skin.h): the stretch map of a
 * mesh, its normal map scattered by the skin's diffusion profile (one map per colour channel)
 * and the transmittance map for translucency. A thin client of skin.h. */
#include "cli.h"
#include "input.h"

#include "ibl/skin.h"

#include <stdio.h>
#include <string.h>

static const char usage[] =
    "usage: ibl sss --mesh MESH --normal NORMAL -o OUT [options]\n"
    "\n"
    "Scatters a tangent-space normal map by the skin's diffusion profile (d'Eon and Luebke's\n"
    "six Gaussians, GPU Gems 3 ch. 14, 2007), per colour channel, in texture space corrected\n"
    "by the mesh's stretch map, and writes one normal map per channel: OUT_r, OUT_g, OUT_b\n"
    "with OUT's extension (.png: 16-bit; .exr: float). The run time lights each colour channel\n"
    "along its own normal (docs/SKIN.md).\n"
    "\n"
    "  --mesh FILE            glTF 2.0 (.gltf/.glb) or Wavefront OBJ with texture coordinates\n"
    "  --normal FILE          the tangent-space normal map (.png, read as data, or .exr);\n"
    "                         its size is the size of every map written\n"
    "  -o, --output OUT       base name of the three scattered maps (.png or .exr)\n"
    "  --mm-per-unit S        millimetres per mesh unit (default 1000: glTF meshes are in metres)\n"
    "  --profile FILE         another profile, a JSON table of Gaussians:\n"
    "                         {\"gaussians\": [{\"variance_mm2\": V, \"weights\": [R, G, B]}, ...]}\n"
    "  --max-radius N         taps each side of a Gaussian at its working resolution (default 48)\n"
    "  --stretch FILE         also write the stretch map (.exr: R = |dP/du|, G = |dP/dv| in mesh\n"
    "                         units per texture, A = coverage)\n"
    "  --transmittance FILE   also bake the thickness (rays cast inward through the mesh) and\n"
    "                         write the grey transmittance map t = 1 - thickness / range, for\n"
    "                         the alpha of the packed material map (.png 16-bit or .exr)\n"
    "  --range MM             the thickness t = 0 stands for (default 8 mm)\n"
    "  --rays N               thickness rays per texel (default 16)\n"
    "  --cone DEG             their cone's half-angle about the inward normal (default 30)\n"
    "  --dilate N             texels filled past the UV charts' edges (default 16)\n"
    "  -q, -j N, --max-memory MiB: see 'ibl --help'\n";

typedef struct sss_options {
    const char *mesh, *normal, *output, *profile, *stretch, *transmittance;
    ibl_skin_scatter_desc scatter;
    ibl_skin_thickness_desc thickness;
    float range_mm;
} sss_options;

static void parse(cli_args *a, sss_options *o)
{
    const char *arg;
    while ((arg = cli_next(a))) {
        if (cli_common_option(a, arg)) continue;
        if (cli_is(a, arg, "--mesh", NULL)) o->mesh = cli_value(a, arg);
        else if (cli_is(a, arg, "--normal", NULL)) o->normal = cli_value(a, arg);
        else if (cli_is(a, arg, "--output", "-o")) o->output = cli_value(a, arg);
        else if (cli_is(a, arg, "--profile", NULL)) o->profile = cli_value(a, arg);
        else if (cli_is(a, arg, "--stretch", NULL)) o->stretch = cli_value(a, arg);
        else if (cli_is(a, arg, "--transmittance", NULL)) o->transmittance = cli_value(a, arg);
        else if (cli_is(a, arg, "--mm-per-unit", NULL))
            o->scatter.mm_per_unit = (float)cli_double(a, arg, 1e-6, 1e9);
        else if (cli_is(a, arg, "--max-radius", NULL)) o->scatter.max_radius = cli_int(a, arg, 1, 1024);
        else if (cli_is(a, arg, "--range", NULL)) o->range_mm = (float)cli_double(a, arg, 1e-3, 1e6);
        else if (cli_is(a, arg, "--rays", NULL)) o->thickness.rays = cli_int(a, arg, 1, 4096);
        else if (cli_is(a, arg, "--cone", NULL)) o->thickness.cone_degrees = (float)cli_double(a, arg, 0.01, 89);
        else if (cli_is(a, arg, "--dilate", NULL)) {
            int n = cli_int(a, arg, 0, 4096);
            o->thickness.map.dilate = n ? n : -1;
        } else cli_positional_or_unknown(a, arg);
    }
    if (a->positional_count) cli_usage_error(a, "takes no positional argument (--mesh, --normal)");
    if (!o->mesh || !o->normal) cli_usage_error(a, "needs --mesh MESH and --normal NORMAL");
    if (!o->output) cli_usage_error(a, "needs -o OUT");
    const char *outs[3] = {o->output, o->stretch, o->transmittance};
    for (int i = 0; i < 3; i++) {
        if (!outs[i]) continue;
        ibl_file_type t = cli_check_output(a, outs[i]);
        if (t != IBL_FILE_PNG && t != IBL_FILE_EXR)
            cli_usage_error(a, "%s: the maps are written as .png or .exr", outs[i]);
        cli_check_distinct(a, o->mesh, outs[i]);
        cli_check_distinct(a, o->normal, outs[i]);
    }
    if (ibl_file_type_from_path(o->normal) == IBL_FILE_JPEG)
        cli_usage_error(a, "%s: a normal map is data; JPEG's lossy sRGB is not taken (PNG or EXR)",
                        o->normal);
}

/* OUT.ext -> OUT_r.ext */
static void channel_path(const char *out, char suffix, char *path, size_t size)
{
    const char *dot = strrchr(out, '.'), *slash = strrchr(out, '/');
    if (!dot || (slash && dot < slash)) dot = out + strlen(out);
    snprintf(path, size, "%.*s_%c%s", (int)(dot - out), out, suffix, dot);
}

static ibl_write_desc map_write_desc(const char *path)
{
    ibl_write_desc wd;
    memset(&wd, 0, sizeof wd);
    /* 16-bit linear PNG; float EXR with alpha */
    wd.format = ibl_file_type_from_path(path) == IBL_FILE_PNG ? IBL_FORMAT_RGBA16_UNORM : IBL_FORMAT_RGBA32F;
    wd.tonemap = IBL_TONEMAP_NONE;
    return wd;
}

/* Bakes every map into the output set (nothing is written until the commit). */
static ibl_status bake(ibl_context *ctx, const cli_args *a, sss_options *o, ibl_output_set *set)
{
    ibl_scene *mesh = NULL;
    ibl_image normal = {0}, stretch = {0}, scattered[3] = {{0}}, thick = {0};
    ibl_skin_profile profile;
    const char *failed = o->mesh;
    ibl_status st = ibl_scene_load(ctx, o->mesh, &mesh);
    if (st == IBL_OK && o->profile) {
        failed = o->profile;
        st = ibl_skin_profile_load(ctx, o->profile, &profile);
        o->scatter.profile = &profile;
    }
    if (st == IBL_OK) {
        failed = o->normal;
        st = ibl_read_image(ctx, o->normal, &(ibl_read_desc){.as_data = 1}, &normal, NULL);
    }
    ibl_skin_map_desc md = {normal.width, normal.height, o->thickness.map.dilate};
    double t0 = cli_seconds();
    if (st == IBL_OK) {
        failed = o->mesh;
        st = ibl_skin_stretch_map(ctx, mesh, &md, &stretch);
    }
    if (st == IBL_OK) {
        cli_info(&a->common, "stretch map %dx%d in %.2f s\n", md.width, md.height, cli_seconds() - t0);
        failed = o->normal;
        t0 = cli_seconds();
        st = ibl_skin_scatter_normals(ctx, &normal, &stretch, &o->scatter, scattered);
    }
    if (st == IBL_OK) cli_info(&a->common, "scattered in %.2f s\n", cli_seconds() - t0);
    for (int c = 0; c < 3 && st == IBL_OK; c++) {
        char path[4096];
        channel_path(o->output, "rgb"[c], path, sizeof path);
        failed = path;
        ibl_write_desc wd = map_write_desc(path);
        st = ibl_output_set_add_image(set, path, &scattered[c], &wd);
    }
    if (st == IBL_OK && o->stretch) {
        failed = o->stretch;
        ibl_write_desc wd = map_write_desc(o->stretch);
        st = ibl_output_set_add_image(set, o->stretch, &stretch, &wd);
    }
    if (st == IBL_OK && o->transmittance) {
        failed = o->mesh;
        o->thickness.map = md;
        t0 = cli_seconds();
        st = ibl_skin_thickness_map(ctx, mesh, &o->thickness, &thick);
        if (st == IBL_OK) {
            cli_info(&a->common, "thickness in %.2f s\n", cli_seconds() - t0);
            ibl_skin_transmittance_from_thickness(&thick, o->scatter.mm_per_unit, o->range_mm);
            for (size_t i = 0; i < (size_t)thick.width * thick.height; i++) thick.pixels[4 * i + 3] = 1.0f;
            failed = o->transmittance;
            ibl_write_desc wd = map_write_desc(o->transmittance);
            st = ibl_output_set_add_image(set, o->transmittance, &thick, &wd);
        }
    }
    if (st != IBL_OK) cli_report_failure(ctx, failed, st);
    ibl_image_free(ctx, &thick);
    for (int c = 0; c < 3; c++) ibl_image_free(ctx, &scattered[c]);
    ibl_image_free(ctx, &stretch);
    ibl_image_free(ctx, &normal);
    ibl_scene_destroy(mesh);
    return st;
}

int cli_cmd_sss(int argc, char **argv)
{
    cli_args a = {argc, argv, 0, "sss", usage, {0}, {0}, 0};
    sss_options o;
    memset(&o, 0, sizeof o);
    parse(&a, &o);
    ibl_context *ctx = cli_context(&a.common);
    ibl_output_set *set = NULL;
    ibl_status st = ibl_output_set_create(ctx, &set);
    if (st == IBL_OK) st = ibl_output_set_protect(set, o.mesh);
    if (st == IBL_OK) st = ibl_output_set_protect(set, o.normal);
    if (st != IBL_OK) cli_report_failure(ctx, o.output, st);
    else st = bake(ctx, &a, &o, set);
    if (st == IBL_OK) {
        st = ibl_output_set_commit(set);
        if (st != IBL_OK) cli_report_failure(ctx, o.output, st);
        else cli_info(&a.common, "wrote the scattered normal maps of %s\n", o.output);
    }
    ibl_output_set_destroy(set);
    ibl_context_destroy(ctx);
    return st == IBL_OK ? CLI_EXIT_OK : cli_exit_code(st);
}
